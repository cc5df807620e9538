"""The robots and scenes urdf2links ships (package data, installed as ``urdf2links.robots``).

Nothing to import: :func:`urdf2links.locations.shipped_robots_dir` finds this folder.
"""

"""How far the engines agree: terms at identical states, trajectories, energies, divergence (compare_scene).

May import :mod:`urdf2links.compare.mujoco_side` and everything below it.
"""

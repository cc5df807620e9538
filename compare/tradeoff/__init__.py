"""Accuracy against wall time: the work-precision study of a scene for both engines, its crossover and its report.

May import :mod:`urdf2links.compare.agreement`, :mod:`~urdf2links.compare.mujoco_side` and everything below them.
"""

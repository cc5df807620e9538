"""Reports: one scene's report.html, summary.json and .md, plots, the motion section, the index, baselines.

May import :mod:`urdf2links.compare.tradeoff` (its report section), agreement, mujoco_side and everything below.
"""

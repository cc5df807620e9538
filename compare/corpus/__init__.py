"""A fleet: every robot file of a corpus in its default scene against MuJoCo, in processes or on Dask; its report.

May import :mod:`urdf2links.compare.reports` and everything below it.
"""

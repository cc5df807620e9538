"""Scenes: a scene TOML (or a robot's default scene) -> the plan of the terms it calls for -> a compiled right-hand side.

May import the base modules, :mod:`urdf2links.dynamics` and :mod:`urdf2links.parsers`; never integration, view
or compare.
"""

from .. import numba_cache as _numba_cache

_numba_cache.install()     # before any compiled function is defined (idempotent)

from .plan import Plan, as_plan, compile_plan
from .default_scenes import default_scene
from .scene import Scene
from .scene_read import load_scene

__all__ = ["Scene", "load_scene", "default_scene", "Plan", "compile_plan", "as_plan"]

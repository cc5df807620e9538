"""Dynamics: the tree of links (frames, coordinates, H) and Lagrange's equations in trace form, compiled -> Model.

May import only the base modules (errors, ranges); nothing that reads files, scenes, integration, view or compare.
"""

from .. import numba_cache as _numba_cache

_numba_cache.install()     # before any compiled function is defined: numba caches into the user's folder

from .loads import Wrench  # noqa: E402
from .model import Model  # noqa: E402
from .transforms import BaseState, base_transforms  # noqa: E402
from .tree import LinkSpec, LinkTree, build_tree, pseudo_inertia_from

__all__ = ["Model", "LinkSpec", "LinkTree", "build_tree", "pseudo_inertia_from", "Wrench", "BaseState",
           "base_transforms"]

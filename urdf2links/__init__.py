"""urdf2links: URDF robots as trees of links of the trace method, simulated and checked against MuJoCo.

This package never imports MuJoCo; the comparison lives in the ``compare`` package.
"""

from . import numba_cache as _numba_cache

_numba_cache.install()     # before any compiled function is defined: numba caches into the user's folder

from .dynamics.loads import Wrench
from .dynamics.model import Model
from .dynamics.transforms import BaseState, base_transforms
from .dynamics.tree import LinkSpec, LinkTree, build_tree, pseudo_inertia_from
from .errors import (
    DescriptionError,
    DynamicsError,
    InertiaError,
    MeshError,
    URDFError,
    URDFStructureError,
    URDFSyntaxError,
    URDFValueError,
)
from .parsers.importer import AuditRecord, load_urdf, load_urdf_string, urdf_link_poses

__all__ = [
    "DescriptionError",
    "load_urdf",
    "load_urdf_string",
    "urdf_link_poses",
    "AuditRecord",
    "Model",
    "LinkSpec",
    "LinkTree",
    "build_tree",
    "pseudo_inertia_from",
    "Wrench",
    "BaseState",
    "base_transforms",
    "URDFError",
    "URDFSyntaxError",
    "URDFStructureError",
    "URDFValueError",
    "InertiaError",
    "MeshError",
    "DynamicsError",
]

__version__ = "0.1.0"

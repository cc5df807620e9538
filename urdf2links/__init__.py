"""urdf2links: URDF and MJCF robots as trees of links of the trace method, simulated and checked against MuJoCo.

This package never imports MuJoCo; the comparison lives in the ``compare`` package.
"""

from .dynamics.loads import Wrench
from .dynamics.model import Model
from .dynamics.transforms import BaseState, base_transforms
from .dynamics.tree import LinkSpec, LinkTree, build_tree, pseudo_inertia_from
from .errors import (
    DynamicsError,
    DescriptionError,
    InertiaError,
    MeshError,
    MJCFError,
    URDFError,
    URDFStructureError,
    URDFSyntaxError,
    URDFValueError,
)
from .parsers.importer import AuditRecord, load_urdf, load_urdf_string, urdf_link_poses
from .parsers.mjcf import load_mjcf, load_mjcf_string
from .parsers.robot_file import load_robot

__all__ = [
    "load_urdf",
    "load_mjcf",
    "load_mjcf_string",
    "load_robot",
    "DescriptionError",
    "MJCFError",
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

"""urdf2links: URDF and MJCF robots as trees of links of the trace method, simulated and checked against MuJoCo.

This package never imports MuJoCo; the comparison lives in the ``compare`` package.
"""

import os as _os

# numba's parallel calls (batched Model calls, sweeps) run on its OpenMP threading layer, GNU libgomp
# here. By default libgomp's worker threads wait actively after every parallel region: each spins
# ~6 ms of a core (GOMP_SPINCOUNT 300000) before sleeping, CPU taken from whatever the process runs
# next -- MuJoCo's own threads right after a batched call took up to 2.5x longer on a 2-core machine
# (docs/speed.md). Passive waiting puts them to sleep at once. libgomp reads this when numba first
# loads it (the first parallel call), so setting it here, before any, is enough; a user's own
# setting of either variable is kept.
if "OMP_WAIT_POLICY" not in _os.environ and "GOMP_SPINCOUNT" not in _os.environ:
    _os.environ["OMP_WAIT_POLICY"] = "PASSIVE"

from . import numba_cache as _numba_cache  # noqa: E402

_numba_cache.install()     # before any compiled function is defined: numba caches into the user's folder

from .dynamics.loads import Wrench
from .dynamics.model import Model
from .dynamics.transforms import BaseState, base_transforms
from .dynamics.tree import LinkSpec, LinkTree, build_tree, pseudo_inertia_from
from .errors import (
    DescriptionError,
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
    "DescriptionError",
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

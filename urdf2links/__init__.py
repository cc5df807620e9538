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

# The public API is loaded on first use (PEP 562): ``import urdf2links`` (and ``urdf2links --help``) imports
# neither numba nor scipy, so it takes a few tens of milliseconds; ``urdf2links.Model`` (or ``from urdf2links
# import Model``) imports what it needs then. numba's cache folder is set up by the first compiled
# subpackage imported (urdf2links.dynamics, before any compiled function is defined).
_PUBLIC = {
    "Wrench": "dynamics.loads", "Model": "dynamics.model", "BaseState": "dynamics.transforms",
    "base_transforms": "dynamics.transforms", "LinkSpec": "dynamics.tree", "LinkTree": "dynamics.tree",
    "build_tree": "dynamics.tree", "pseudo_inertia_from": "dynamics.tree",
    "AuditRecord": "parsers.importer", "load_urdf": "parsers.importer", "load_urdf_string": "parsers.importer",
    "urdf_link_poses": "parsers.importer", "load_mjcf": "parsers.mjcf", "load_mjcf_string": "parsers.mjcf",
    "load_robot": "parsers.robot_file",
}

from . import errors as _errors  # noqa: E402  (light: the error classes alone)
from .errors import (  # noqa: E402
    DescriptionError,
    DynamicsError,
    InertiaError,
    MeshError,
    MJCFError,
    URDFError,
    URDFStructureError,
    URDFSyntaxError,
    URDFValueError,
)


def __getattr__(name: str):
    """A public name (or a subpackage) imported at its first use."""
    import importlib

    if name in _PUBLIC:
        value = getattr(importlib.import_module(f".{_PUBLIC[name]}", __name__), name)
        globals()[name] = value
        return value
    try:
        return importlib.import_module(f".{name}", __name__)
    except ModuleNotFoundError as exc:
        if exc.name != f"{__name__}.{name}":
            raise
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_PUBLIC))


#: The public API: the names loaded at first use, and the error classes imported above (a robot's loading and its
#: dynamics; a scene's and a run's errors are in :mod:`urdf2links.errors`), each listed once.
__all__ = [*_PUBLIC, *(name for name in _errors.__all__ if name in globals())]

__version__ = "0.1.0"

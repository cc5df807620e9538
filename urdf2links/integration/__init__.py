"""Integration: a compiled right-hand side -> a trajectory (compiled loops, scipy's solvers, charts, batches).

May import the base modules, dynamics, parsers and scenes; never view or compare.
"""

from .. import numba_cache as _numba_cache

_numba_cache.install()     # before any compiled function is defined (idempotent)

from .batch import BatchResult, simulate_batch
from .integrators import integrate
from .simulate import Trajectory, simulate

__all__ = ["integrate", "simulate", "Trajectory", "simulate_batch", "BatchResult"]

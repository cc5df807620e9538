"""Integration: a compiled right-hand side -> a trajectory (compiled loops, scipy's solvers, charts, batches).

May import the base modules, dynamics, parsers and scenes; never view or compare.
"""

from .batch import BatchResult, simulate_batch
from .integrators import integrate
from .simulate import Trajectory, simulate

__all__ = ["integrate", "simulate", "Trajectory", "simulate_batch", "BatchResult"]

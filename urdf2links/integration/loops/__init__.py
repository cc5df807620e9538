"""The integration loops: RK45, DOP853, RK4, the implicit midpoint rule and Radau5, compiled with numba,
and ``auto``, which switches between DOP853 and Radau5.

``common`` (the evaluation of a compiled scene, the angle guard), ``erk`` (scipy's explicit pairs,
step for step, with auto's stiffness test), ``fixed`` (RK4, the implicit midpoint), ``radau`` (Radau IIA
of order 5 for stiff scenes, E59, E60) with ``lu`` (its factorisations), ``stiffness`` (auto's tests,
E58), ``auto`` (the stretches), ``driver`` (:func:`run`: chunks, storage, results; compiled around a
compiled scene, interpreted around a Python callable).
"""

from .common import AngleGuard, evaluate
from .driver import CHUNK, Outcome, run, wall_message
from .erk import TABLEAUX, Tableau, erk_chunk, initial_step
from .fixed import MAX_HALVINGS, NEWTON_MAXITER, midpoint_chunk, rk4_chunk

__all__ = ["AngleGuard", "evaluate", "run", "wall_message", "Outcome", "CHUNK", "Tableau", "TABLEAUX", "erk_chunk", "initial_step",
           "rk4_chunk", "midpoint_chunk", "NEWTON_MAXITER", "MAX_HALVINGS"]

"""Time integration of first-order systems ``y' = F(t, y)`` with a user-chosen method.

The simulator writes ``q'' = f(t, q, q')`` as ``y = (q, q')``; this module knows nothing
about robots and only takes the callable ``rhs(t, y) -> (dim,)`` (it must not modify ``y``).

Methods (:data:`METHODS`):

* ``auto`` (the default of scenes): DOP853 while the system is not stiff, Radau5 while it is, with
  Hairer's stiffness test in DOP853 and a cost comparison back (:mod:`urdf2links.integration.loops.auto`);
  the stretches are in ``result.stretches``.
* ``Radau5``: Radau IIA of order 5 with Hairer & Wanner's RADAU5 strategies, compiled
  (:mod:`urdf2links.integration.loops.radau`): L-stable, for stiff scenes; a finite-difference
  Jacobian kept over steps (or the user's ``jac``), and the structure ``y = (q, q', W)`` of a
  compiled scene used to solve ``n x n`` systems. ``rtol`` means about the global error DOP853
  gives at the same ``rtol`` (RADAU5's map ``0.1 rtol^(2/3)`` of its error estimate's tolerance).
  ``auto`` and ``Radau5`` run interpreted (the same loops) on a Python right-hand side.
* ``RK45``, ``DOP853``, ``Radau``, ``BDF``, ``LSODA``: scipy's adaptive ``OdeSolver`` classes,
  stepped one accepted step at a time (for ``callback`` and counting) with ``rtol``/``atol``;
  ``dt``, if given, is the maximum step; ``jac`` goes to the implicit ones. For a compiled
  scene (:class:`~urdf2links.scenes.scene_kernels.CompiledScene`) RK45 and DOP853 run in compiled loops
  that take scipy's steps (:mod:`urdf2links.integration.loops`).
* ``RK4``: classic fourth-order Runge-Kutta, fixed step ``dt`` (last step shortened to land
  on ``t_end``).
* ``midpoint``: implicit midpoint rule ``y1 = y0 + h F(t0 + h/2, (y0 + y1)/2)``, fixed step
  ``dt``. Symmetric, and symplectic in canonical variables: quadratic invariants (harmonic
  oscillator energy) are conserved up to the Newton tolerance and rounding. Applied to
  ``(q, q')`` with a configuration-dependent ``A`` it is not symplectic, but it stays symmetric
  (time-reversible), which for reversible mechanical systems also gives a bounded energy error
  without secular drift in practice (measured over 1000 s of the chaotic double pendulum:
  docs/hard-cases.md, case 8). It damps nothing: on stiff springs prefer Radau or BDF. The stage slope
  ``k = F(t0 + h/2, y0 + h/2 k)`` is found by simplified Newton iterations on
  ``(I - h/2 J) dk = F - k``, ``J`` a forward-difference (or the user's ``jac``) Jacobian
  kept over steps and refreshed, in the middle of a step, when the contraction rate
  predicts no convergence within :data:`~urdf2links.integration.loops.NEWTON_MAXITER` iterations. The iteration stops
  when the estimated remaining error ``rate / (1 - rate) |h dk|`` is below
  ``max(10 eps / rtol, min(0.03, sqrt(rtol)))`` in units of ``atol + rtol |y|`` (as scipy's
  Radau), or when ``h dk`` is at the rounding level of ``y``. If it fails with a fresh
  Jacobian the step is halved (``nrejected`` counts these attempts), at most
  :data:`~urdf2links.integration.loops.MAX_HALVINGS` times, then :class:`IntegrationError` is raised.

Dispatch, explicit: a compiled scene's right-hand side runs in the compiled loops of
:mod:`urdf2links.integration.loops` (auto, RK45, DOP853, Radau5, RK4, midpoint; with no ``jac`` and
``stop`` None or an :class:`AngleGuard`); any other callable runs in scipy's solvers, or for RK4,
the midpoint rule, Radau5 and auto in the same loops interpreted.

Shapes are time first: ``result.y`` is ``(m, dim)``; ``result.sol(t)`` is ``(dim,)`` for a
scalar ``t`` and ``(k, dim)`` for ``k`` times. Fixed-step methods get a cubic Hermite
interpolant from the states and slopes at the steps (RK4: the ``F`` values the method
evaluates anyway; midpoint: the exact ``F`` at both ends, inside the second-order weighted
mean of the two adjacent stage slopes), without extra evaluations but one ``F(t_end)``.

Argument errors raise ``ValueError``/``TypeError`` naming the argument and the value. A
scipy solver that fails (step size underflow) returns ``success=False`` with its message; so
does reaching ``max_steps``. A fixed-step method meeting a non-finite state or a Newton
failure raises :class:`IntegrationError`.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from .. import compilation
from ..errors import IntegrationError
from ..ranges import MAX_STEPS, METHODS, MIN_ATOL, RTOL_FLOOR
from ..scenes.scene_kernels import CompiledScene
from . import loops
from .dense import DenseOutput
from .loops import AngleGuard

__all__ = ["METHODS", "IntegrationError", "IntegrationResult", "DenseOutput", "AngleGuard", "integrate"]

_SCIPY = ("RK45", "DOP853", "Radau", "BDF", "LSODA")     # scipy's solvers, imported when one runs (a slow import)
_USES_JAC = ("Radau", "BDF", "LSODA", "midpoint", "Radau5")
#: The methods of the compiled loops (interpreted around a Python right-hand side).
_LOOPS = ("RK4", "midpoint", "Radau5", "auto")
_FIXED = ("RK4", "midpoint")


@dataclass(frozen=True, eq=False)
class IntegrationResult:
    """Outcome of :func:`integrate` (time-first shapes).

    ``t`` (m,), ``y`` (m, dim): the solver's steps (including ``t0``) or ``t_eval``.
    ``stretches`` (``auto``): one dict per stretch run by one method (``method``, ``t0``, ``t1``,
    ``steps``, ``nfev``, ``njev``, ``rejected``, ``started``/``ended`` and their figures).
    ``nfev`` counts every call of ``rhs`` (Jacobian finite differences and the initial
    shape check included), ``njev`` Jacobian evaluations (finite-difference or user's),
    ``nsteps`` accepted steps, ``nrejected`` rejected attempts (``None`` where unknown:
    Radau, BDF, LSODA). ``sol`` is a :class:`DenseOutput` when ``dense=True`` else ``None``.
    ``wall_time`` (s): the integration, from the first evaluation of ``rhs`` to the last step
    (with the dense output's coefficients when ``dense`` or ``t_eval`` asks for them); the
    argument checks and the sampling at ``t_eval`` are not in it, nor numba's compilation (or loading
    from its cache) of anything the run calls (:func:`urdf2links.compilation.clock`).
    """

    t: np.ndarray
    y: np.ndarray
    method: str
    rtol: float
    atol: Any
    dt: float | None
    nfev: int
    njev: int
    nsteps: int
    nrejected: int | None
    wall_time: float
    sol: "DenseOutput | None"
    success: bool
    message: str
    stopped: bool = False
    stretches: tuple = ()


class _Counted:
    """``rhs`` with a call counter, returning a fresh float array: an ``rhs`` that returns
    its own reused output buffer would otherwise corrupt the stored stages (scipy's too)."""

    __slots__ = ("fun", "n")

    def __init__(self, fun):
        self.fun, self.n = fun, 0

    def __call__(self, t, y):
        self.n += 1
        return np.array(self.fun(t, y), dtype=float)


def _validate(rhs, t_span, y0, method, rtol, atol, dt, t_eval, callback, max_steps, jac, max_wall=None):
    if not isinstance(method, str) or method not in METHODS:
        raise ValueError(f"unknown method={method!r}; expected one of {', '.join(METHODS)}")
    if not callable(rhs):
        raise TypeError(f"rhs must be callable rhs(t, y), got {rhs!r}")
    if callback is not None and not callable(callback):
        raise TypeError(f"callback must be callable callback(t, y) or None, got {callback!r}")
    try:
        t0, t1 = (float(v) for v in t_span)
    except (TypeError, ValueError):
        raise ValueError(f"t_span must be a pair (t0, t_end) of numbers, got {t_span!r}") from None
    if not (math.isfinite(t0) and math.isfinite(t1) and t1 > t0):
        raise ValueError(f"t_span must be finite and increasing (t0 < t_end), got {t_span!r}")
    y = np.array(y0, dtype=float)
    if y.ndim != 1 or y.size == 0:
        raise ValueError(f"y0 must be a non-empty 1-D array, got shape {y.shape}")
    if not np.all(np.isfinite(y)):
        raise ValueError(f"y0 must be finite, got {y0!r}")
    if not (isinstance(rtol, (int, float, np.floating)) and math.isfinite(rtol) and rtol > 0):
        raise ValueError(f"rtol must be a finite number > 0, got {rtol!r}")
    if rtol < RTOL_FLOOR:   # as scipy's solvers do: float64 cannot deliver less
        warnings.warn(f"rtol={rtol!r} is below what float64 can deliver; raised to {RTOL_FLOOR:.3g} (100 eps)",
                      RuntimeWarning, stacklevel=3)
        rtol = RTOL_FLOOR
    if max_wall is not None and not (isinstance(max_wall, (int, float, np.floating)) and not isinstance(
            max_wall, bool) and max_wall > 0 and not math.isnan(max_wall)):
        raise ValueError(f"max_wall must be a number of seconds > 0 or None, got {max_wall!r}")
    a = np.asarray(atol, dtype=float)
    if a.shape not in ((), y.shape) or not np.all(np.isfinite(a)) or np.any(a < MIN_ATOL):
        # atol = 0 leaves a state component that starts at 0 (the work W always does) without a scale
        raise ValueError(f"atol must be finite, >= {MIN_ATOL:g}, a scalar or of shape {y.shape}, got {atol!r}")
    if dt is not None:
        if not (isinstance(dt, (int, float, np.floating)) and math.isfinite(dt) and dt > 0):
            raise ValueError(f"dt must be a finite number > 0, got dt={dt!r}")
        dt = float(dt)
        if method in _FIXED and (t1 - t0) / dt > MAX_STEPS:
            raise IntegrationError(f"{method}: dt={dt!r} over t_span={t_span!r} makes {(t1 - t0) / dt:.3g} steps, "
                                   f"more than the {MAX_STEPS:g} a run may take (urdf2links.ranges.MAX_STEPS): "
                                   "take a longer step or a shorter span")
    elif method in _FIXED:
        raise ValueError(f"method {method!r} is fixed-step and requires dt > 0, got dt=None")
    if t_eval is not None:
        te = np.array(t_eval, dtype=float)
        slack = 1e-12 * max(1.0, abs(t0), abs(t1))
        if (te.ndim != 1 or not np.all(np.isfinite(te)) or np.any(np.diff(te) < 0)
                or (te.size and (te[0] < t0 - slack or te[-1] > t1 + slack))):
            raise ValueError(f"t_eval must be a sorted 1-D array of finite times within "
                             f"t_span={t_span!r}, got {t_eval!r}")
        t_eval = np.clip(te, t0, t1)
    if max_steps is not None and (isinstance(max_steps, bool) or not isinstance(
            max_steps, (int, np.integer)) or max_steps < 1):
        raise ValueError(f"max_steps must be an integer >= 1 or None, got {max_steps!r}")
    if jac is not None and method not in _USES_JAC:
        raise ValueError(f"jac is used only by {', '.join(_USES_JAC)}; got jac={jac!r} "
                         f"with method={method!r}")
    return t0, t1, y, a if a.ndim else float(a), dt, t_eval, float(rtol)


def integrate(rhs: Callable, t_span, y0, *, method: str = "DOP853", rtol: float = 1e-9,
              atol=1e-12, dt: float | None = None, t_eval=None, dense: bool = False,
              callback: Callable | None = None, max_steps: int | None = None,
              jac=None, stop: Callable | None = None, max_wall: float | None = None) -> IntegrationResult:
    """Integrate ``y' = rhs(t, y)`` over ``t_span = (t0, t_end)`` from ``y0`` (dim,).

    ``method`` one of :data:`METHODS`; ``rtol``/``atol`` the adaptive methods' tolerances
    and the midpoint Newton tolerance; ``dt`` the fixed step (``RK4``, ``midpoint``;
    required) or the maximum step (adaptive methods); ``t_eval`` sorted times at which ``y``
    is sampled from the dense interpolant (otherwise at the steps); ``dense`` returns the
    interpolant as ``sol``; ``callback(t, y)`` is called after each accepted step (do not
    modify ``y``); ``max_steps`` stops with ``success=False`` after that many accepted steps;
    ``jac`` (callable ``jac(t, y)`` or constant matrix) for Radau, BDF, LSODA and midpoint;
    ``stop(t, y) -> bool`` is asked after each accepted step (after ``callback``): True ends the
    integration there with ``success=True`` and ``stopped=True`` (an :class:`AngleGuard` is such a
    test); ``max_wall`` (seconds) ends it with ``success=False`` once that much wall time has passed
    (checked after each step, or each chunk of steps of a compiled loop). An ``rtol`` below 100 eps
    is raised to it with a RuntimeWarning (scipy's solvers do the same); a fixed step that would take
    more than :data:`~urdf2links.ranges.MAX_STEPS` steps raises :class:`IntegrationError`.
    """
    t0, t1, y0, atol, dt, t_eval, rtol = _validate(rhs, t_span, y0, method, rtol, atol, dt, t_eval,
                                                   callback, max_steps, jac, max_wall)
    if stop is not None and not callable(stop):
        raise TypeError(f"stop must be callable stop(t, y) -> bool or None, got {stop!r}")
    need_dense = dense or t_eval is not None
    if isinstance(rhs, CompiledScene):
        rhs.prepare(t0, y0)          # compiled (or loaded from the cache) before the clock starts
    timed = compilation.clock()         # one clock for the budget and the reported time: compilation left out
    wall = None if max_wall is None else (timed + float(max_wall), float(max_wall))
    fun = _Counted(rhs)
    f0 = fun(t0, y0)
    if f0.shape != y0.shape:
        raise ValueError(f"rhs(t, y) must return an array of shape {y0.shape}, got shape "
                         f"{f0.shape} at t0={t0!r}")
    if not np.all(np.isfinite(f0)):
        raise ValueError(f"rhs(t0, y0) is not finite at t0={t0!r}: {f0!r}")
    compiled = isinstance(rhs, CompiledScene) and jac is None and (stop is None or isinstance(stop, AngleGuard))
    if method in _LOOPS or (compiled and method in loops.TABLEAUX):
        if method == "Radau5" and jac is not None and not callable(jac):
            jac = (lambda J: (lambda t, y: J))(np.array(jac, dtype=float))
        out = loops.run(method, rhs if compiled else fun.fun, f0, t0, t1, y0, rtol=float(rtol), atol=atol, dt=dt,
                        grid=_grid(t0, t1, dt) if method in _FIXED else None, callback=callback,
                        max_steps=max_steps, need_dense=need_dense, stop=stop, jac=jac, wall=wall)
        nfev = fun.n + out.nfev
    else:
        out = _run_scipy(method, fun, t0, t1, y0, rtol, atol, dt, jac, callback, stop, max_steps,
                         need_dense, wall)
        nfev = fun.n
    wall = compilation.clock() - timed    # the integration, without compilation; sampling at t_eval is not timed
    ts, ys = out.t, out.y
    nsteps = ts.size - 1
    if t_eval is not None:
        te = t_eval[t_eval <= ts[-1]]
        ts, ys = te, (out.sol(te) if out.sol is not None else np.tile(y0, (te.size, 1)))
    return IntegrationResult(t=ts, y=ys, method=method, rtol=float(rtol), atol=atol, dt=dt, nfev=nfev,
                             njev=int(out.njev), nsteps=nsteps, nrejected=out.nrejected,
                             wall_time=wall, sol=out.sol if dense else None,
                             success=out.success, message=out.message, stopped=out.stopped,
                             stretches=tuple(out.stretches))


def _run_scipy(method, fun, t0, t1, y0, rtol, atol, dt, jac, callback, stop, max_steps, need_dense,
               wall=None) -> loops.Outcome:
    """scipy's solver ``method`` stepped one accepted step at a time (callback, stop, counters)."""
    import scipy.integrate

    cls = getattr(scipy.integrate, method)
    kw = {"rtol": rtol, "atol": atol}
    if dt is not None:
        kw["max_step"] = dt
    if jac is not None:
        kw["jac"] = jac
    solver = cls(fun, t0, y0, t1, **kw)
    n_stages = getattr(solver, "n_stages", None) if method in ("RK45", "DOP853") else None
    nrejected = 0 if n_stages else None
    ts, ys, interps = [t0], [y0.copy()], []
    success, message, stopped = True, "reached t_end", False
    while solver.status == "running":
        before = fun.n
        msg = solver.step()
        if solver.status == "failed":
            success, message = False, f"{cls.__name__} failed at t={float(solver.t)!r}: {msg}"
            break
        if n_stages:
            nrejected += (fun.n - before) // n_stages - 1
        y = solver.y.copy()
        ts.append(solver.t)
        ys.append(y)
        if need_dense:
            interps.append(solver.dense_output())
        if callback is not None:
            callback(solver.t, y)
        if stop is not None and stop(solver.t, y):
            stopped, message = True, f"stopped by stop(t, y) at t={float(solver.t)!r}"
            break
        if max_steps is not None and len(ts) > max_steps and solver.status == "running":
            success, message = False, f"max_steps={max_steps} reached at t={float(solver.t)!r}"
            break
        if wall is not None and solver.status == "running" and compilation.clock() > wall[0]:
            success, message = False, loops.wall_message(wall[1], float(solver.t), len(ts) - 1)
            break
    ts, ys = np.array(ts), np.array(ys)
    sol = DenseOutput(ts, ode=scipy.integrate.OdeSolution(ts, interps)) if need_dense and interps else None
    return loops.Outcome(ts, ys, sol, 0, solver.njev, nrejected, success, message, stopped)


def _grid(t0: float, t1: float, dt: float) -> np.ndarray:
    """Step times ``t0 + i dt``, the last one ``t_end`` (a final step shorter than ``dt``;
    a remainder below 1e-9 dt is absorbed in the previous step)."""
    n = max(1, math.ceil((t1 - t0) / dt - 1e-9))
    g = t0 + dt * np.arange(n + 1, dtype=float)
    g[-1] = t1
    return g

"""Time integration of first-order systems ``y' = F(t, y)`` with a user-chosen method.

The simulator writes ``q'' = f(t, q, q')`` as ``y = (q, q')``; this module knows nothing
about robots and only takes the callable ``rhs(t, y) -> (dim,)`` (it must not modify ``y``).

Methods (:data:`METHODS`):

* ``RK45``, ``DOP853``, ``Radau``, ``BDF``, ``LSODA``: scipy's adaptive ``OdeSolver`` classes,
  stepped one accepted step at a time (for ``callback`` and counting) with ``rtol``/``atol``;
  ``dt``, if given, is the maximum step; ``jac`` goes to the implicit ones.
* ``RK4``: classic fourth-order Runge-Kutta, fixed step ``dt`` (last step shortened to land
  on ``t_end``).
* ``midpoint``: implicit midpoint rule ``y1 = y0 + h F(t0 + h/2, (y0 + y1)/2)``, fixed step
  ``dt``. Symmetric, and symplectic in canonical variables: quadratic invariants (harmonic
  oscillator energy) are conserved up to the Newton tolerance and rounding. Applied to
  ``(q, q')`` with a configuration-dependent ``A`` it is not symplectic, but it stays symmetric
  (time-reversible), which for reversible mechanical systems also gives a bounded energy error
  without secular drift in practice (measured over 1000 s of the chaotic double pendulum:
  README, hard case 8). It damps nothing: on stiff springs prefer Radau or BDF. The stage slope
  ``k = F(t0 + h/2, y0 + h/2 k)`` is found by simplified Newton iterations on
  ``(I - h/2 J) dk = F - k``, ``J`` a forward-difference (or the user's ``jac``) Jacobian
  kept over steps and refreshed, in the middle of a step, when the contraction rate
  predicts no convergence within :data:`NEWTON_MAXITER` iterations. The iteration stops
  when the estimated remaining error ``rate / (1 - rate) |h dk|`` is below
  ``max(10 eps / rtol, min(0.03, sqrt(rtol)))`` in units of ``atol + rtol |y|`` (as scipy's
  Radau), or when ``h dk`` is at the rounding level of ``y``. If it fails with a fresh
  Jacobian the step is halved (``nrejected`` counts these attempts), at most
  :data:`MAX_HALVINGS` times, then :class:`IntegrationError` is raised.

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
import time
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np
from scipy.integrate import BDF, DOP853, LSODA, RK45, OdeSolution, Radau

__all__ = ["METHODS", "IntegrationError", "IntegrationResult", "DenseOutput", "AngleGuard", "integrate"]

METHODS = ("RK45", "DOP853", "Radau", "BDF", "LSODA", "RK4", "midpoint")
_SCIPY = {"RK45": RK45, "DOP853": DOP853, "Radau": Radau, "BDF": BDF, "LSODA": LSODA}
_USES_JAC = ("Radau", "BDF", "LSODA", "midpoint")
_FIXED = ("RK4", "midpoint")
_COMPILED = ("RK45", "DOP853", "RK4", "midpoint")   # compiled loops for a compiled scene
EPS = np.finfo(float).eps
MAX_HALVINGS = 4          # midpoint: step halvings before giving up
NEWTON_MAXITER = 8        # midpoint: simplified Newton iterations per attempt


class IntegrationError(RuntimeError):
    """The integration cannot continue (Newton failure, non-finite state)."""


@dataclass(frozen=True, eq=False)
class IntegrationResult:
    """Outcome of :func:`integrate` (time-first shapes).

    ``t`` (m,), ``y`` (m, dim): the solver's steps (including ``t0``) or ``t_eval``.
    ``nfev`` counts every call of ``rhs`` (Jacobian finite differences and the initial
    shape check included), ``njev`` Jacobian evaluations (finite-difference or user's),
    ``nsteps`` accepted steps, ``nrejected`` rejected attempts (``None`` where unknown:
    Radau, BDF, LSODA). ``sol`` is a :class:`DenseOutput` when ``dense=True`` else ``None``.
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


class DenseOutput:
    """Continuous solution ``t -> y`` on ``[t_min, t_max]``: scalar ``t`` -> ``(dim,)``,
    times of shape ``(k,)`` -> ``(k, dim)``. Cubic Hermite from ``(ts, ys, fs)``, or a
    wrapped scipy ``OdeSolution``."""

    __slots__ = ("t_min", "t_max", "_ts", "_ys", "_fs", "_ode", "_poly")

    def __init__(self, ts, ys=None, fs=None, ode: OdeSolution | None = None, poly=None):
        self._ts, self._ys, self._fs, self._ode, self._poly = ts, ys, fs, ode, poly
        self.t_min, self.t_max = float(ts[0]), float(ts[-1])

    def __call__(self, t):
        tt = np.asarray(t, dtype=float)
        scalar = tt.ndim == 0
        tt = np.atleast_1d(tt)
        if tt.ndim != 1:
            raise ValueError(f"t must be a scalar or a 1-D array, got shape {tt.shape}")
        slack = 1e-12 * max(1.0, abs(self.t_min), abs(self.t_max))
        if tt.size and (not np.all(np.isfinite(tt)) or tt.min() < self.t_min - slack
                        or tt.max() > self.t_max + slack):
            raise ValueError(f"t={t!r} outside the interpolated interval "
                             f"[{self.t_min!r}, {self.t_max!r}]")
        tt = np.clip(tt, self.t_min, self.t_max)
        if self._ode is not None:
            out = self._ode(tt).T
        elif self._poly is not None:
            out = self._poly_eval(tt)
        else:
            ts = self._ts
            i = np.clip(np.searchsorted(ts, tt, side="right") - 1, 0, ts.size - 2)
            h = ts[i + 1] - ts[i]
            s = ((tt - ts[i]) / h)[:, None]
            s2, r = s * s, 1.0 - s
            r2 = r * r
            out = ((1.0 + 2.0 * s) * r2 * self._ys[i] + s2 * (3.0 - 2.0 * s) * self._ys[i + 1]
                   + h[:, None] * (s * r2 * self._fs[i] - s2 * r * self._fs[i + 1]))
        return out[0] if scalar else out

    def _poly_eval(self, tt):
        """Compiled loops' dense output: ``poly = (method, coefficients (m, r, dim))``, row ``i + 1``
        for the step from ``ts[i]``: DOP853's seventh-degree form or RK45's quartic (scipy's)."""
        method, C = self._poly
        ts, ys = self._ts, self._ys
        i = np.clip(np.searchsorted(ts, tt, side="right") - 1, 0, ts.size - 2)
        h = (ts[i + 1] - ts[i])[:, None]
        x = (tt - ts[i])[:, None] / h
        rows = C[i + 1]                                   # (k, r, dim)
        if method == "DOP853":
            y = np.zeros((tt.size, ys.shape[1]))
            for j, r in enumerate(range(rows.shape[1] - 1, -1, -1)):
                y += rows[:, r]
                y *= x if j % 2 == 0 else (1.0 - x)
            return y + ys[i]
        y = np.zeros((tt.size, ys.shape[1]))
        p = np.ones_like(x)
        for r in range(rows.shape[1]):
            p = p * x
            y += rows[:, r] * p
        return ys[i] + h * y


class AngleGuard:
    """A ``stop`` test: True once ``|cos(y[j])| < cos_min`` for any ``j`` in ``indices``, i.e. an
    angle (a ZYX ``phi_y``) came within ``arccos(cos_min)`` of ``+-pi/2``, where its chart is
    singular. Compiled integration loops recognise it and test it without calling Python."""

    __slots__ = ("indices", "cos_min")

    def __init__(self, indices, cos_min: float):
        self.indices = np.asarray(indices, dtype=np.int64).ravel()
        if not 0.0 < float(cos_min) < 1.0:
            raise ValueError(f"cos_min must be in (0, 1), got {cos_min!r}")
        self.cos_min = float(cos_min)

    def __call__(self, t, y) -> bool:
        return bool(self.indices.size) and bool(np.any(np.abs(np.cos(y[self.indices])) < self.cos_min))


class _Counted:
    """``rhs`` with a call counter, returning a fresh float array: an ``rhs`` that returns
    its own reused output buffer would otherwise corrupt the stored stages (scipy's too)."""

    __slots__ = ("fun", "n")

    def __init__(self, fun):
        self.fun, self.n = fun, 0

    def __call__(self, t, y):
        self.n += 1
        return np.array(self.fun(t, y), dtype=float)


def _validate(rhs, t_span, y0, method, rtol, atol, dt, t_eval, callback, max_steps, jac):
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
    a = np.asarray(atol, dtype=float)
    if a.shape not in ((), y.shape) or not np.all(np.isfinite(a)) or np.any(a < 0):
        raise ValueError(f"atol must be finite, >= 0, a scalar or of shape {y.shape}, got {atol!r}")
    if dt is not None:
        if not (isinstance(dt, (int, float, np.floating)) and math.isfinite(dt) and dt > 0):
            raise ValueError(f"dt must be a finite number > 0, got dt={dt!r}")
        dt = float(dt)
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
    return t0, t1, y, a if a.ndim else float(a), dt, t_eval


def integrate(rhs: Callable, t_span, y0, *, method: str = "DOP853", rtol: float = 1e-9,
              atol=1e-12, dt: float | None = None, t_eval=None, dense: bool = False,
              callback: Callable | None = None, max_steps: int | None = None,
              jac=None, stop: Callable | None = None) -> IntegrationResult:
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
    test).
    """
    t0, t1, y0, atol, dt, t_eval = _validate(rhs, t_span, y0, method, rtol, atol, dt, t_eval,
                                             callback, max_steps, jac)
    if stop is not None and not callable(stop):
        raise TypeError(f"stop must be callable stop(t, y) -> bool or None, got {stop!r}")
    need_dense = dense or t_eval is not None
    start = time.perf_counter()
    fun = _Counted(rhs)
    f0 = fun(t0, y0)
    if f0.shape != y0.shape:
        raise ValueError(f"rhs(t, y) must return an array of shape {y0.shape}, got shape "
                         f"{f0.shape} at t0={t0!r}")
    if not np.all(np.isfinite(f0)):
        raise ValueError(f"rhs(t0, y0) is not finite at t0={t0!r}: {f0!r}")
    compiled = (getattr(rhs, "args", None) is not None and method in _COMPILED and jac is None
                and (stop is None or isinstance(stop, AngleGuard)))
    if compiled:
        from .compiled_integrators import run as run_compiled

        grid = _grid(t0, t1, dt) if method in _FIXED else None
        ts, ys, sol, nfev, njev, nrejected, success, message, stopped = run_compiled(
            method, rhs, f0, t0, t1, y0, float(rtol), atol, dt, callback, max_steps, need_dense, stop, grid)
        nsteps = ts.size - 1
        if t_eval is not None:
            te = t_eval[t_eval <= ts[-1]]
            ts, ys = te, (sol(te) if sol is not None else np.tile(y0, (te.size, 1)))
        return IntegrationResult(t=ts, y=ys, method=method, rtol=float(rtol), atol=atol, dt=dt,
                                 nfev=fun.n + nfev, njev=njev, nsteps=nsteps,
                                 nrejected=nrejected, wall_time=time.perf_counter() - start,
                                 sol=sol if dense else None, success=success, message=message, stopped=stopped)
    halted = []
    if callback is not None or stop is not None:
        user_callback = callback

        def callback(t, y):
            if user_callback is not None:
                user_callback(t, y)
            if stop is not None and stop(t, y):
                halted.append(float(t))
                return True
            return False
    if method in _SCIPY:
        out = _run_scipy(_SCIPY[method], fun, t0, t1, y0, rtol, atol, dt, jac, callback,
                         max_steps, need_dense)
    elif method == "RK4":
        out = _run_rk4(fun, f0, t0, t1, y0, dt, callback, max_steps, need_dense)
    else:
        out = _run_midpoint(fun, f0, t0, t1, y0, dt, float(rtol), atol, jac, callback,
                            max_steps, need_dense)
    ts, ys, sol, njev, nrejected, success, message = out
    if halted:
        message = f"stopped by stop(t, y) at t={halted[0]!r}"
    nsteps = ts.size - 1
    if t_eval is not None:
        te = t_eval[t_eval <= ts[-1]]
        ts, ys = te, (sol(te) if sol is not None else np.tile(y0, (te.size, 1)))
    wall = time.perf_counter() - start
    return IntegrationResult(t=ts, y=ys, method=method, rtol=float(rtol), atol=atol, dt=dt,
                             nfev=fun.n, njev=int(njev), nsteps=nsteps, nrejected=nrejected,
                             wall_time=wall, sol=sol if dense else None, success=success, message=message,
                             stopped=bool(halted))


def _run_scipy(cls, fun, t0, t1, y0, rtol, atol, dt, jac, callback, max_steps, need_dense):
    kw = {"rtol": rtol, "atol": atol}
    if dt is not None:
        kw["max_step"] = dt
    if jac is not None:
        kw["jac"] = jac
    solver = cls(fun, t0, y0, t1, **kw)
    n_stages = getattr(solver, "n_stages", None) if cls in (RK45, DOP853) else None
    nrejected = 0 if n_stages else None
    ts, ys, interps = [t0], [y0.copy()], []
    success, message = True, "reached t_end"
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
        if callback is not None and callback(solver.t, y):
            break
        if max_steps is not None and len(ts) > max_steps and solver.status == "running":
            success, message = False, f"max_steps={max_steps} reached at t={float(solver.t)!r}"
            break
    ts, ys = np.array(ts), np.array(ys)
    sol = DenseOutput(ts, ode=OdeSolution(ts, interps)) if need_dense and interps else None
    return ts, ys, sol, solver.njev, nrejected, success, message


def _grid(t0: float, t1: float, dt: float) -> np.ndarray:
    """Step times ``t0 + i dt``, the last one ``t_end`` (a final step shorter than ``dt``;
    a remainder below 1e-9 dt is absorbed in the previous step)."""
    n = max(1, math.ceil((t1 - t0) / dt - 1e-9))
    g = t0 + dt * np.arange(n + 1, dtype=float)
    g[-1] = t1
    return g


def _stopped(n, max_steps, t, t1):
    return max_steps is not None and n >= max_steps and t < t1


def _run_rk4(fun, f0, t0, t1, y0, dt, callback, max_steps, need_dense):
    ts = _grid(t0, t1, dt)
    m, d = ts.size, y0.size
    ys, fs = np.empty((m, d)), np.empty((m, d))
    ys[0], fs[0] = y0, f0
    k2, k3, k4 = np.empty(d), np.empty(d), np.empty(d)
    success, message, n = True, "reached t_end", m - 1
    for i in range(m - 1):
        t, h, y, k1 = ts[i], ts[i + 1] - ts[i], ys[i], fs[i]
        hh = 0.5 * h
        k2[:] = fun(t + hh, y + hh * k1)
        k3[:] = fun(t + hh, y + hh * k2)
        k4[:] = fun(t + h, y + h * k3)
        y1 = ys[i + 1]
        np.add(y, (h / 6.0) * (k1 + 2.0 * (k2 + k3) + k4), out=y1)
        f1 = fun(ts[i + 1], y1)
        if not (np.all(np.isfinite(y1)) and np.all(np.isfinite(f1))):
            raise IntegrationError(f"RK4: non-finite state or rhs at t={float(ts[i + 1])!r} "
                                   f"(step {i + 1}, dt={dt!r})")
        fs[i + 1] = f1
        if callback is not None and callback(ts[i + 1], y1):
            n = i + 1
            break
        if _stopped(i + 1, max_steps, ts[i + 1], t1):
            n = i + 1
            success, message = False, f"max_steps={max_steps} reached at t={float(ts[n])!r}"
            break
    ts, ys, fs = ts[:n + 1], ys[:n + 1], fs[:n + 1]
    sol = DenseOutput(ts, ys, fs) if need_dense else None
    return ts, ys, sol, 0, 0, success, message


def _run_midpoint(fun, f0, t0, t1, y0, dt, rtol, atol, jac, callback, max_steps, need_dense):
    grid = _grid(t0, t1, dt)
    d, cap = y0.size, grid.size
    ts, ys, ks = np.empty(cap), np.empty((cap, d)), np.empty((cap, d))  # ks[i]: slope on step i
    ts[0], ys[0] = t0, y0
    eye = np.eye(d)
    jac_const = jac is not None and not callable(jac)
    J = np.array(jac, dtype=float) if jac_const else None
    if J is not None and J.shape != (d, d):
        raise ValueError(f"jac must be callable or of shape {(d, d)}, got shape {J.shape}")
    need_jac, jac_fresh, minv, inv_h, njev, nrej = J is None, jac_const, None, None, 0, 0
    tol = max(10 * EPS / rtol, min(0.03, rtol ** 0.5))
    atol_zero = not np.any(atol)
    hist: list = []                          # (h, k) of the last accepted steps, newest first
    n, t, y = 0, t0, ys[0]
    success, message = True, "reached t_end"
    for target in grid[1:]:
        h_try, halvings = target - t, 0
        while t < target:
            last = h_try >= target - t
            h = target - t if last else h_try
            # predictor: extrapolation of the previous stage slopes at constant step
            if len(hist) == 3 and h == hist[0][0] == hist[1][0] == hist[2][0]:
                k_pred = 3.0 * (hist[0][1] - hist[1][1]) + hist[2][1]
            elif len(hist) >= 2 and h == hist[0][0] == hist[1][0]:
                k_pred = 2.0 * hist[0][1] - hist[1][1]
            else:
                k_pred = hist[0][1] if hist else f0
            k = k_pred.copy()
            scale = atol + rtol * np.abs(y)
            if atol_zero:
                np.maximum(scale, rtol * 1e-8 * np.max(np.abs(y)) + 1e-300, out=scale)
            tm, hh, w = t + 0.5 * h, 0.5 * h, h / scale
            # a correction at the rounding level of y + h k ends the iteration
            noise = 8 * EPS * math.sqrt(np.mean(np.square((np.abs(y) + np.abs(h * k)) / scale)))
            ok, dy_old, rate, it = False, None, None, 0
            while True:
                ym = y + hh * k
                f = fun(tm, ym)
                if need_jac:
                    jac_fresh, it, dy_old = True, 0, None
                    if not np.all(np.isfinite(f)):
                        break
                    J = _jacobian(fun, jac, tm, ym, f)
                    njev, need_jac, minv = njev + 1, False, None
                    if not np.all(np.isfinite(J)):
                        need_jac = True
                        break
                if minv is None or inv_h != h:
                    # the inverse only steers the iteration: the residual is exact
                    try:
                        minv, inv_h = np.linalg.inv(eye - hh * J), h
                    except np.linalg.LinAlgError:
                        break
                dk = minv @ (f - k)
                k += dk
                it += 1
                dk *= w
                dy = math.sqrt(np.dot(dk, dk) / d)
                if dy <= noise:
                    ok = True
                    break
                slow = not math.isfinite(dy) or it >= NEWTON_MAXITER
                if not slow and dy_old is not None:
                    rate = dy / dy_old
                    if rate < 1 and rate / (1 - rate) * dy < tol:
                        ok = True
                        break
                    # simplified Newton (stale J) converges linearly: predict failure
                    slow = not jac_fresh and (rate >= 1 or rate ** (NEWTON_MAXITER - it)
                                              / (1 - rate) * dy > tol)
                if slow:                  # refresh a stale Jacobian and go on, else give up
                    if jac_fresh:
                        break
                    need_jac = True
                    if not (math.isfinite(dy) and (rate is None or rate < 1)):
                        k = k_pred.copy()
                dy_old = dy
            if not ok:
                nrej += 1
                halvings += 1
                if halvings > MAX_HALVINGS:
                    raise IntegrationError(
                        f"implicit midpoint: Newton iteration did not converge at "
                        f"t={float(t)!r} (step {n + 1}, h={float(h)!r} after {MAX_HALVINGS} "
                        f"halvings of dt={dt!r}; rtol={rtol!r})")
                h_try *= 0.5
                continue
            if n + 1 >= ts.size:                     # halved steps: grow the storage
                grow = max(16, ts.size // 2)
                ts = np.concatenate([ts, np.empty(grow)])
                ys, ks = (np.concatenate([a, np.empty((grow, d))]) for a in (ys, ks))
            n += 1
            t = target if last else t + h
            ts[n], ks[n - 1] = t, k
            y = ys[n]
            np.add(ys[n - 1], h * k, out=y)
            hist = [(h, k)] + hist[:2]
            if not jac_fresh:               # slow convergence: fresh Jacobian next step
                need_jac = rate is not None and rate > 0.2
            jac_fresh = jac_const
            if callback is not None and callback(t, y):
                success = None
                break
            if _stopped(n, max_steps, t, t1):
                success, message = False, f"max_steps={max_steps} reached at t={float(t)!r}"
                break
        if not success:
            break
    success = True if success is None else success
    ts, ys, ks = ts[:n + 1], ys[:n + 1], ks[:n]
    sol = midpoint_dense(ts, ys, ks, f0, fun(ts[n], ys[n])) if need_dense else None
    return ts, ys, sol, njev, nrej, success, message


def midpoint_dense(ts, ys, ks, f0, f_end) -> DenseOutput:
    """The midpoint rule's interpolant: cubic Hermite on the steps ``ts`` (n + 1,), ``ys``, with
    the exact slopes ``f0``, ``f_end`` at the ends and, inside, the second-order weighted mean of
    the two adjacent stage slopes ``ks`` (n, dim)."""
    n = ts.size - 1
    fs = np.empty_like(ys)
    fs[0] = f0
    fs[n] = f_end
    if n > 1:
        h = np.diff(ts)[:, None]
        fs[1:n] = (h[1:] * ks[:-1] + h[:-1] * ks[1:]) / (h[1:] + h[:-1])
    return DenseOutput(ts, ys, fs)


def _jacobian(fun, jac, t, y, f):
    """User's ``jac(t, y)`` or forward differences of ``fun`` around ``(t, y)``."""
    if jac is not None:
        return np.array(jac(t, y), dtype=float)
    f = f.copy()
    d = y.size
    J = np.empty((d, d))
    yp = y.copy()
    steps = np.sqrt(EPS) * np.maximum(np.abs(y), 1.0)
    for j in range(d):
        yp[j] = y[j] + steps[j]
        J[:, j] = (fun(t, yp) - f) / (yp[j] - y[j])
        yp[j] = y[j]
    return J

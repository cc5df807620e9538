"""Drivers of the integration loops: storage, chunks, progress, results; compiled or interpreted.

:func:`run` integrates with a compiled loop when the right-hand side is a
:class:`~urdf2links.scenes.scene_kernels.CompiledScene`, else with the same loop interpreted
(:func:`_interpreted`) around any Python callable. Loops run in chunks: they return after
``chunk`` steps (or when their storage is full) so that the driver shows progress, grows the
storage and asks a Python ``stop``, then resume from the state they left. Status codes: 0 running,
1 reached ``t_end``, 2 stopped by the angle guard, 3 storage full, 4 stiff (DOP853 in ``auto``),
5 non-stiff (Radau5 in ``auto``), -1 step size too small, -2 the right-hand side failed
(non-finite, or A not positive definite), -3 Newton failed, -4 Radau5's iteration matrix singular.
``auto`` alternates the explicit and the implicit loop in stretches (:mod:`.auto`).
"""

from __future__ import annotations

import types
from collections import namedtuple

import numpy as np

from ... import compilation
from ...errors import IntegrationError
from ...scenes.scene_kernels import CompiledScene
from ..dense import DenseOutput, midpoint_dense
from . import erk, fixed
from .common import AngleGuard
from .auto import drive_auto
from .erk import TABLEAUX
from .fixed import MAX_HALVINGS
from .stretches import grow, run_erk, run_radau

__all__ = ["Outcome", "run", "CHUNK", "wall_message", "structure_of"]

CHUNK = 2000              # steps per call of a compiled loop between two returns to Python

# -- the interpreter's copy -------------------------------------------------------------------------
def _python_evaluate(t, y, out, args, counters):
    """:func:`evaluate` for a Python right-hand side ``args[0](t, y)``."""
    cnt, fail = counters
    cnt[0] += 1
    out[:] = args[0](t, y)
    if np.all(np.isfinite(out)):
        return True
    fail[0] = t
    fail[1:] = y
    return False


def _python_no_rows(args):
    """:func:`~.common.has_rows` for a Python right-hand side: none."""
    return False


def _python_jacobian(t, y, f, J, args, counters):
    """The user's ``jac(t, y)`` (``args[1]``) in place of finite differences."""
    J[:, :] = args[1](t, y)
    return bool(np.all(np.isfinite(J)))


def _python_radau_jacobian(t, y, f, Jl, nq, nv, yp, fp, args, counters):
    """The user's ``jac(t, y)`` (d, d) in place of Radau5's differences: its rows of ``v'`` and
    ``w'``, columns of ``q`` and ``v``."""
    J = np.asarray(args[1](t, y), dtype=float)
    Jl[:, :] = J[nq:, :nq + nv]
    return bool(np.all(np.isfinite(Jl)))


def _rebound(module, ns: dict) -> dict:
    """Every numba function defined in ``module``, its source (``py_func``) rebound to ``ns``."""
    for name, obj in vars(module).items():
        py = getattr(obj, "py_func", None)
        if py is not None and py.__module__ == module.__name__:
            ns[name] = types.FunctionType(py.__code__, ns, py.__name__, py.__defaults__, py.__closure__)
    return ns


def _interpreted(*, user_jac: bool) -> dict:
    """The loops as plain Python functions: each compiled function's source rebound to a copy of its
    module's namespace in which ``evaluate`` calls a Python right-hand side (``args = (rhs, jac)``).
    The same code as the compiled loops, so the two cannot drift."""
    from . import radau

    loops = {}
    for module in (fixed, erk, radau):
        ns = dict(vars(module))
        ns["evaluate"] = _python_evaluate
        ns["settle"] = _python_evaluate           # issue 45: a Python right-hand side carries no constraint rows
        ns["has_rows"] = _python_no_rows
        _rebound(module, ns)
        if user_jac and module is fixed:
            ns["_jacobian"] = _python_jacobian
        if user_jac and module is radau:
            ns["radau_jacobian"] = _python_radau_jacobian
        loops.update({k: v for k, v in ns.items() if k.endswith("_chunk") or k == "initial_step"})
    return loops


class _CompiledLoops(dict):
    """The compiled loops by name; Radau5's module (and scipy's coefficients it reads) is imported
    at its first use: a run that never turns stiff does not load it."""

    def __missing__(self, name):
        if name != "radau_chunk":
            raise KeyError(name)
        from .radau import radau_chunk

        self[name] = radau_chunk
        return radau_chunk


def _compiled() -> dict:
    return _CompiledLoops(rk4_chunk=fixed.rk4_chunk, midpoint_chunk=fixed.midpoint_chunk, erk_chunk=erk.erk_chunk,
                          initial_step=erk.initial_step)


# -- drivers (Python): chunks, storage, progress, results -------------------------------------------
Outcome = namedtuple("Outcome", ["t", "y", "sol", "nfev", "njev", "nrejected", "success", "message", "stopped",
                                 "stretches"], defaults=((),))
"""What :func:`run` returns: steps ``t`` (m,), ``y`` (m, d), the dense output or None, counters,
``success``, ``message``, whether the stop test ended the run, and (``auto``) the stretches: one
dict per method used in turn (:func:`urdf2links.integration.loops.auto.drive_auto`)."""


def wall_message(max_wall: float, t: float, steps: int) -> str:
    """The message of a run ended by its wall-clock budget."""
    return (f"max_wall={max_wall:.3g} s of wall time reached at t={t!r} after {steps} steps (the run did not finish "
            "within its wall-clock budget)")


class _Driver:
    """One run's shared bookkeeping: counters, budget, the guard, the callback and a Python stop.
    ``wall`` is None or ``(deadline, max_wall)`` (:func:`urdf2links.compilation.clock` seconds), asked after each chunk."""

    def __init__(self, rhs, d, *, callback, max_steps, stop, chunk, wall=None):
        self.compiled = isinstance(rhs, CompiledScene)
        self.cnt = np.zeros(4, np.int64)
        self.counters = (self.cnt, np.full(d + 1, np.nan))     # fail: where the right-hand side failed
        self.budget = np.inf if max_steps is None else int(max_steps)
        self.callback, self.stop, self.chunk = callback, stop, chunk
        self.wall, self.out_of_time = wall, False
        self.stopped = False
        self.guard = (np.zeros(0, np.int64), np.zeros(0))
        if self.compiled and isinstance(stop, AngleGuard):     # tested inside the compiled loop
            self.guard, self.stop = (stop.indices, stop.thresholds), None
        self.ready = set()

    def call(self, loops, name, *args):
        """``loops[name](*args)``; a compiled loop's first call in this run is compiled (or loaded from
        the cache) first, outside the run's time (:func:`urdf2links.compilation.ensure`): Radau5's loop
        only when a run of ``auto`` turns stiff."""
        if self.compiled and name not in self.ready:
            compilation.ensure(loops[name], args)
            self.ready.add(name)
        return loops[name](*args)

    def size(self) -> int:
        return int(min(self.chunk, self.budget - self.cnt[1]))

    def after_chunk(self, status, t, y) -> bool:
        """Callback and Python stop test after a chunk; True when the run ends here."""
        if self.callback is not None:
            self.callback(float(t), y)
        if status == 0 and self.stop is not None and self.cnt[1] > 0 and self.stop(t, y):
            self.stopped = True
            return True
        if status == 0 and self.wall is not None and compilation.clock() > self.wall[0]:
            self.out_of_time = True
            return True
        return status != 0 or self.cnt[1] >= self.budget


def structure_of(rhs, d: int) -> tuple[int, int]:
    """``(nq, nv)`` of the system Radau5 solves: a scene's ``y = (q, q', W)`` (``nq = nv = n``, E59)
    for a compiled scene, else ``(0, d)`` (no structure known: full systems)."""
    if isinstance(rhs, CompiledScene) and d % 2 == 1:
        return (d - 1) // 2, (d - 1) // 2
    return 0, d


def _drive_rk4(drv, loops, args, f0, y0, grid, need_dense):
    m, d = grid.size, y0.size
    ys, fs = np.empty((m, d)), np.empty((m, d))
    ys[0], fs[0] = y0, f0
    st = np.zeros(1)
    while True:
        status = drv.call(loops, "rk4_chunk", grid, (st, ys, fs), drv.guard, drv.counters, drv.size(), args)
        i = int(st[0])
        if drv.after_chunk(status, grid[i], ys[i]):
            break
    m = int(st[0]) + 1
    ts, ys, fs = grid[:m].copy(), ys[:m], fs[:m]
    return status, ts, ys, (DenseOutput(ts, ys, fs) if need_dense else None), 0


def _drive_midpoint(drv, loops, args, f0, t0, y0, rtol, atol, grid, need_dense, jac, evaluate_end):
    d = y0.size
    cap = grid.size + 16
    ts, ys, ks = np.empty(cap), np.empty((cap, d)), np.empty((cap, d))
    ts[0], ys[0], ks[0] = t0, y0, f0
    const = jac is not None and not callable(jac)
    J = np.array(jac, dtype=float) if const else np.zeros((d, d))
    if J.shape != (d, d):
        raise ValueError(f"jac must be callable or of shape {(d, d)}, got shape {J.shape}")
    st = np.array([0.0, 0.0, t0, 0.0 if const else 1.0, float(const), 0.0, 0.0, 0.0, 0.0, float(const), 0.0])
    state = (st, np.zeros(3), np.zeros((3, d)), J, np.zeros((d, d)))
    while True:
        status = drv.call(loops, "midpoint_chunk", grid, (rtol, atol), state, (ts, ys, ks), drv.guard, drv.counters,
                          drv.size(), args)
        if status == 3:
            ts, ys, ks = grow((ts, ys, ks), max(16, ts.size // 2))
            continue
        if drv.after_chunk(status, st[2], ys[int(st[1])]):
            break
    n = int(st[1])
    if status == -3:
        raise IntegrationError(f"implicit midpoint: Newton iteration did not converge at t={float(st[2])!r} (step {n + 1}, h={float(st[10])!r} "
                               f"after {MAX_HALVINGS} halvings of dt={float(grid[1] - grid[0])!r}; rtol={rtol!r})")
    ts, ys, ks = ts[:n + 1], ys[:n + 1], ks[:n]
    sol = midpoint_dense(ts, ys, ks, f0, evaluate_end(ts[n], ys[n])) if need_dense else None
    return status, ts, ys, sol, int(st[8])


def run(method, rhs, f0, t0, t1, y0, *, rtol, atol, dt, grid, callback=None, max_steps=None,
        need_dense=False, stop=None, jac=None, wall=None, structure=None) -> Outcome:
    """Integrate with one of the loops: compiled when ``rhs`` is a
    :class:`~urdf2links.scenes.scene_kernels.CompiledScene` (and ``stop`` None or an angle guard),
    interpreted otherwise (then ``callback`` and ``stop`` are asked after every step, ``jac`` is
    the midpoint's or Radau5's Jacobian: callable, constant matrix (midpoint) or None for finite
    differences; ``wall`` None or ``(deadline, max_wall)``: past the deadline the run ends
    unsuccessfully, saying so). ``f0 = rhs(t0, y0)``; ``atol`` (d,); ``grid`` the fixed-step methods'
    step times; ``structure`` Radau5's ``(nq, nv)`` (default :func:`structure_of`). RK45 and DOP853
    run compiled only (``auto`` runs DOP853 interpreted on a Python right-hand side)."""
    d = y0.size
    atol = np.ascontiguousarray(np.broadcast_to(np.asarray(atol, float), (d,)))
    drv = _Driver(rhs, d, callback=callback, max_steps=max_steps, stop=stop, chunk=CHUNK, wall=wall)
    compiled = drv.compiled and jac is None and drv.stop is None
    if compiled:
        loops, args = _compiled(), rhs.args
    else:
        drv.chunk = 1
        loops, args = _interpreted(user_jac=callable(jac)), (rhs, jac)
    structure = structure_of(rhs, d) if structure is None else tuple(int(k) for k in structure)

    def slope_at_end(t, y):
        drv.cnt[0] += 1
        return rhs(t, y)

    stretches = ()
    if method in TABLEAUX:
        if not compiled:
            raise ValueError(f"{method} runs compiled only (scipy's {method} serves Python right-hand sides)")
        out = run_erk(drv, loops, TABLEAUX[method], args, f0, t0, t1, y0, rtol, atol, dt, need_dense)
        status, ts, ys, sol, njev = out.status, out.t, out.y, out.sol, 0
    elif method == "Radau5":
        out = run_radau(drv, loops, args, f0, t0, t1, y0, rtol, atol, dt, need_dense, structure)
        status, ts, ys, sol, njev = out.status, out.t, out.y, out.sol, out.njev
    elif method == "auto":
        status, ts, ys, sol, njev, stretches = drive_auto(drv, loops, args, f0, t0, t1, y0, rtol, atol, dt,
                                                          need_dense, structure)
    elif method == "RK4":
        status, ts, ys, sol, njev = _drive_rk4(drv, loops, args, f0, y0, grid, need_dense)
    else:
        status, ts, ys, sol, njev = _drive_midpoint(drv, loops, args, f0, t0, y0, rtol, atol, grid, need_dense,
                                                    jac, slope_at_end)
    return _outcome(method, rhs, drv, status, ts, ys, sol, njev, dt, max_steps, stretches)


def _outcome(method, rhs, drv, status, ts, ys, sol, njev, dt, max_steps, stretches=()) -> Outcome:
    cnt, fail = drv.counters
    failed_at = float(fail[0])       # NaN unless the right-hand side failed somewhere
    if status in (-2, -1, -4) and drv.compiled and np.isfinite(failed_at):
        rhs.check(failed_at, fail[1:])      # raises the model's named error (A not positive definite) if it is one
    if status == -2:
        raise IntegrationError(f"{method}: non-finite state or right-hand side at t={failed_at!r}"
                               + (f" (dt={dt!r})" if dt else ""))
    stopped = status == 2 or drv.stopped
    success, message = True, "reached t_end"
    if status in (-1, -4):
        why = ("Required step size is less than spacing between numbers." if status == -1 else
               "Radau5's iteration matrix stayed singular over five halvings of the step.")
        if np.isfinite(failed_at):
            why += f" (The right-hand side was not finite at t={failed_at!r}.)"
        success, message = False, f"{method} failed at t={float(ts[-1])!r}: {why}"
    elif status == 0 and not stopped and drv.out_of_time:
        success, message = False, wall_message(drv.wall[1], float(ts[-1]), int(cnt[1]))
    elif status == 0 and not stopped and cnt[1] >= drv.budget:
        success, message = False, f"max_steps={max_steps} reached at t={float(ts[-1])!r}"
    elif stopped:
        message = f"stopped by stop(t, y) at t={float(ts[-1])!r}"
    return Outcome(ts, ys, sol, int(cnt[0]), njev, int(cnt[2]), success, message, stopped, tuple(stretches))

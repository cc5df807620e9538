"""Sweeps: many initial states of one scene integrated at once, in compiled loops, in parallel.

``simulate_batch(scene, q0, qd0)`` integrates ``B`` initial states with the scene's compiled
right-hand side (:mod:`urdf2links.scenes.scene_kernels`) and the compiled loops of
:mod:`urdf2links.integration.loops`, one trajectory per thread (numba ``prange``; each thread
has its own scratch). Samples are taken by landing steps exactly on the sample times (the step
size controller carries over), so no dense output is needed. A constrained scene's starts are projected onto
its constraints and every accepted step inside the loop (issue 45, E74), as in :func:`simulate`. A sweep pays Python's per-run costs
(plan compilation, result objects, energy bookkeeping) once instead of ``B`` times.

``simulate_batch(..., client=dask_client)`` splits the ``B`` states into chunks (one per worker by
default, ``chunks`` to choose), each run by this same compiled loop on a Dask worker (the scene and
the loaded model travel with the chunk: the workers need urdf2links, not the robot's files); the
result is the one machine's, bit for bit, since every trajectory is integrated on its own.
:func:`sweep_states` draws a seeded sweep of initial states around a scene's.
"""

from __future__ import annotations

import time
import uuid
from dataclasses import dataclass, replace

import numpy as np
from numba import njit, prange

from .. import compilation
from ..scenes.plan import as_plan
from ..scenes.constraint_arrays import reset_constraint_stats
from .constrained import project_state, refresh_rhs
from .simulate import Compilation, record_compilation
from .loops import TABLEAUX, erk_chunk, evaluate, initial_step

__all__ = ["BatchResult", "simulate_batch", "sweep_states", "split_rows"]


@dataclass(frozen=True, eq=False)
class BatchResult:
    """``t`` (m,), ``q`` and ``qd`` (B, m, n), ``work`` (B, m); ``nfev`` (B,), ``status`` (B,) (1 reached
    the end; otherwise the codes of :mod:`urdf2links.integration.loops.driver`); ``wall_time`` of
    the whole sweep (the compiled loop alone: its compilation is in ``compilation``); ``chunks``: for a sweep split across a Dask cluster, one ``{"rows": [i0, i1],
    "wall_time": s}`` per chunk (empty on one machine)."""

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    work: np.ndarray
    nfev: np.ndarray
    status: np.ndarray
    wall_time: float
    method: str
    coordinate_names: tuple
    chunks: tuple = ()
    compilation: object = None
    """:class:`~urdf2links.integration.simulate.Compilation` of the warm-up call before the timed one
    (numba's compilation, or loading from its cache, kept out of ``wall_time``); on a cluster, the warm-up
    of every worker before the timed round (its seconds the wait for it, its functions those the workers
    compiled)."""
    notes: tuple = ()
    """What the sweep did differently from the scene: its method when the scene's has no batch loop."""

    @property
    def success(self) -> bool:
        return bool(np.all(self.status == 1))


@njit(cache=True, parallel=True)
def _sweep_erk(tab, samples, rtol, atol, max_step, Y0, out, nfev, status, I, F, W, SI, SF, X, fn):
    """Each trajectory ``b`` from ``Y0[b]``; states at ``samples`` into ``out[b]`` (m, d)."""
    nb, d = Y0.shape
    m = samples.size
    for b in prange(nb):
        args = (I, F, W[b], SI, SF, X[b], fn)
        cnt = np.zeros(4, np.int64)
        counters = (cnt, np.zeros(d + 1))
        y = Y0[b].copy()
        f = np.empty(d)
        store = (np.empty(2), np.empty((2, d)), np.empty((0, 7, d)))
        guard = (np.zeros(0, np.int64), np.zeros(0))
        for i in range(d):
            out[b, 0, i] = y[i]
        code = 1
        if not evaluate(samples[0], y, f, args, counters):
            code = -2
        else:
            h_abs = initial_step(samples[0], y, f, samples[m - 1], max_step, tab.order, rtol, atol, args, counters)
            st = np.array([samples[0], h_abs, 1.0])
            state = (st, y, f, np.zeros((16, d)))
            for j in range(1, m):
                ctl = (samples[j], rtol, atol, max_step, False)
                while st[0] < samples[j]:
                    st[2] = 1.0
                    code = erk_chunk(tab, ctl, state, store, guard, counters, 1, args)
                    if code < 0:
                        break
                if code < 0:
                    break
                for i in range(d):
                    out[b, j, i] = y[i]
            if code >= 0:
                code = 1
        nfev[b] = cnt[0]
        status[b] = code
    return 0


def split_rows(count: int, parts: int) -> list[tuple[int, int]]:
    """``[(i0, i1), ...]``: ``count`` rows in at most ``parts`` contiguous chunks of sizes differing by
    at most one (no empty chunk)."""
    parts = max(1, min(int(parts), int(count)))
    edges = np.linspace(0, count, parts + 1).round().astype(int)
    return [(int(a), int(b)) for a, b in zip(edges[:-1], edges[1:]) if b > a]


def sweep_states(scene, model, count: int, *, seed: int = 0, spread: float = 0.1) -> tuple[np.ndarray, np.ndarray]:
    """``(q0, qd0)``, each (count, n): the scene's initial state with each coordinate of ``q0`` moved by
    a seeded uniform draw in ``[-spread, spread]`` (rad or m); ``qd0`` the scene's for every state."""
    if count < 1 or not np.isfinite(spread) or spread < 0:
        raise ValueError(f"sweep_states: need count >= 1 and a finite spread >= 0, got count={count!r}, "
                         f"spread={spread!r}")
    q, qd = scene.initial_state(model)
    rng = np.random.default_rng(seed)
    return q + rng.uniform(-spread, spread, (int(count), model.n)), np.tile(qd, (int(count), 1))


def _chunk(scene, model, q0, qd0, options: dict) -> BatchResult:
    """One chunk of a distributed sweep, alone in its worker process while it runs (numba's threading
    layer must not be entered by two threads at once)."""
    from .distributed import ONE_AT_A_TIME

    with ONE_AT_A_TIME:
        return simulate_batch(scene, q0, qd0, model=model, **options)


def _warm_chunk(scene, model, q0, qd0, options: dict):
    """One state over a few steps in this worker process: compiles, or loads from the cache, all that the
    sweep's chunks call here (the plan's right-hand side stays loaded in the process). Returns the
    compilation's ``(seconds, functions)`` of this process."""
    before = compilation.snapshot()
    _chunk(scene, model, q0, qd0, {**options, "t_end": 1e-3 * (options.get("t_end") or scene.run.t_end),
                                   "samples": 2})
    return before.since()


def _warm_workers(client, scene, model, Q0, QD0, options, run_id) -> Compilation:
    """Every worker warmed before the timed sweep (:func:`_warm_chunk`, one task pinned to each): the
    sweep's wall time leaves numba's compilation out, as on one machine (:func:`urdf2links.compilation.clock`);
    its seconds here (the slowest worker's, the wait before the timed round) and the functions compiled."""
    workers = list(client.scheduler_info().get("workers", {})) or [None]
    start = time.perf_counter()
    pinned = [{"workers": [w], "allow_other_workers": False} if w else {} for w in workers]
    futures = [client.submit(_warm_chunk, scene, model, Q0[:1], QD0[:1], options, pure=False,
                             key=f"urdf2links-sweep-warm-{run_id}-{k}", **where) for k, where in enumerate(pinned)]
    compiled = client.gather(futures)
    out = Compilation(seconds=time.perf_counter() - start)
    out.functions.extend(sorted({f for _, names in compiled for f in names}))
    compilation.elsewhere(sum(s for s, _ in compiled), out.functions)      # shown once by the command
    return out


def _on_cluster(client, scene, model, Q0, QD0, chunks, options) -> BatchResult:
    """The sweep split into chunks run on the client's workers, put back together in order; every worker
    warmed first (:func:`_warm_workers`), so that the wall time is the sweep's and not numba's."""
    from .distributed import worker_count

    bounds = split_rows(len(Q0), chunks or worker_count(client))
    run_id = uuid.uuid4().hex[:8]
    comp = _warm_workers(client, scene, model, Q0, QD0, options, run_id)
    start = compilation.clock()
    futures = [client.submit(_chunk, scene, model, Q0[i0:i1], QD0[i0:i1], options, pure=False,
                             key=f"urdf2links-sweep-{run_id}-{k}") for k, (i0, i1) in enumerate(bounds)]
    parts = client.gather(futures)
    wall = compilation.clock() - start
    first = parts[0]
    return BatchResult(t=first.t, q=np.concatenate([p.q for p in parts]), qd=np.concatenate([p.qd for p in parts]),
                       work=np.concatenate([p.work for p in parts]), nfev=np.concatenate([p.nfev for p in parts]),
                       status=np.concatenate([p.status for p in parts]), wall_time=wall, method=first.method,
                       coordinate_names=first.coordinate_names,
                       chunks=tuple({"rows": [i0, i1], "wall_time": p.wall_time} for (i0, i1), p in zip(bounds, parts)),
                       compilation=comp)


def simulate_batch(scene, q0, qd0=None, *, t_end: float | None = None, samples: int | None = None,
                   method: str | None = None, rtol: float | None = None, atol: float | None = None,
                   model=None, client=None, chunks: int | None = None) -> BatchResult:
    """Integrate ``B`` initial states of ``scene`` (a Scene, its compiled
    :class:`~urdf2links.scenes.plan.Plan`, or a path): ``q0`` (B, n), ``qd0``
    (B, n) (default zeros). ``method`` DOP853 (default) or RK45, with the scene's tolerances
    unless given; ``samples`` equally spaced sample times on ``[0, t_end]``. ``client``: a
    ``dask.distributed.Client`` to split the states across its workers in ``chunks`` chunks
    (default: one per worker); the same result as on one machine (module doc)."""
    plan = as_plan(scene, model=model)        # compiled once; a Plan passed in is used as it is
    scene, model = plan.scene, plan.model
    run = scene.run
    notes = ()
    if method is None and run.method not in TABLEAUX:
        notes = (f"the scene's method {run.method!r} has no batch loop; the sweep ran DOP853 (explicit: a stiff "
                 "scene costs its steps; `urdf2links simulate` runs one state with the scene's method)",)
    method = method or (run.method if run.method in TABLEAUX else "DOP853")
    if method not in TABLEAUX:
        raise ValueError(f"method must be one of {tuple(TABLEAUX)} for a batch, got {method!r}")
    n = model.n
    Q0 = np.atleast_2d(np.asarray(q0, float))
    if Q0.ndim != 2 or Q0.shape[1] != n:
        raise ValueError(f"q0 must have shape (B, {n}) for coordinates {model.coordinate_names}; got {np.shape(q0)}")
    QD0 = np.zeros_like(Q0) if qd0 is None else np.atleast_2d(np.asarray(qd0, float))
    if QD0.shape != Q0.shape:
        raise ValueError(f"qd0 must have the shape of q0 {Q0.shape}; got {QD0.shape}")
    if client is not None:
        options = {"t_end": t_end, "samples": samples, "method": method, "rtol": rtol, "atol": atol}
        return replace(_on_cluster(client, scene, model, Q0, QD0, chunks, options), notes=notes)
    nb, d = Q0.shape[0], 2 * n + 1
    Y0 = np.ascontiguousarray(np.hstack([Q0, QD0, np.zeros((nb, 1))]))
    refresh_rhs(plan)
    if plan.constraints is not None:     # issue 45: each start projected onto the constraints (E74); every
        for b in range(nb):              # accepted step is projected inside the loop (erk_chunk)
            Y0[b] = project_state(plan.rhs, 0.0, Y0[b])[0]
    T = run.t_end if t_end is None else float(t_end)
    ts = np.linspace(0.0, T, max(int(samples or run.samples), 2))
    tol_r = float(run.rtol if rtol is None else rtol)
    tol_a = np.full(d, float(run.atol if atol is None else atol))
    tab = TABLEAUX[method]
    rhs = plan.rhs
    W = np.zeros((nb, rhs.W.size))
    X = np.zeros((nb, rhs.X.size))
    for b in range(nb):
        reset_constraint_stats(rhs.SI, X[b])
    out = np.empty((nb, ts.size, d))
    nfev = np.zeros(nb, np.int64)
    status = np.zeros(nb, np.int64)
    with record_compilation() as comp:    # one state over a few steps: compiles (or loads) what the sweep calls
        _sweep_erk(tab, ts[:2] * min(1.0, 1e-3 / max(ts[1], 1e-300)), tol_r, tol_a, np.inf, Y0[:1].copy(),
                   np.empty((1, 2, d)), np.zeros(1, np.int64), np.zeros(1, np.int64), rhs.I, rhs.F, W[:1].copy(),
                   rhs.SI, rhs.SF, X[:1].copy(), rhs.function)
    start = compilation.clock()
    _sweep_erk(tab, ts, tol_r, tol_a, np.inf, Y0, out, nfev, status, rhs.I, rhs.F, W, rhs.SI, rhs.SF, X, rhs.function)
    wall = compilation.clock() - start
    return BatchResult(t=ts, q=out[:, :, :n], qd=out[:, :, n:2 * n], work=out[:, :, 2 * n], nfev=nfev,
                       status=status, wall_time=wall, method=method, coordinate_names=model.coordinate_names,
                       compilation=comp, notes=notes)

"""A scene with constraints integrated in the compiled loops (issue 45): what a run adds around them.

The constrained right-hand side is the scene's compiled one (:mod:`urdf2links.scenes.scene_kernels` with its
``constraints`` effect: the free forces, the fixed tendons (E76), the constraint terms from the evaluation's
own kinematics pass and the KKT block elimination (E72) with a pivoted Schur factorisation (E88),
:mod:`urdf2links.scenes.constraint_kernels`), so every loop runs it as it runs any scene: RK4, RK45, DOP853,
Radau5, ``auto`` (its stretches) and the batched sweeps. After every accepted step (and at the initial state
and at every dense-output sample) the loops project the state onto ``Phi = 0``, ``Phi' = 0`` (E74,
:func:`urdf2links.integration.loops.common.project`), with the same evaluation's ``A^-1 J^T`` and factor of
``S``; the derivative is evaluated again at the projected state (the next step's first stage). The
residual stays at rounding level (the projection stops at ``max |Phi| <= 1e-13``).

A change point (a Schur pivot at or below 1e-12: a row dependent on the others there) either drops that row
locally and goes on, the event recorded (``[constraints] change_point = "continue"``, the default), or stops
with the named DynamicsError (``"stop"``).

This module does what is around the loops: the initial projection (:func:`initial_state`), the samples'
projection (:func:`project_samples`), and ``Trajectory.stats["constraints"]`` (:func:`constraint_stats`):
rows, solved rows, residual ``max |Phi|`` and ``|Phi'|`` at every sample, the largest drift of any step
before its projection, ``lambda`` (S, m_solved) and ``J^T lambda`` (S, n) at the samples, the initial
projection, the method, the smallest Schur pivot and its time, and the change-point ``events``. The same law
in numpy, step by step, is the tests' oracle (:mod:`urdf2links.integration.constrained_oracle`).
"""

from __future__ import annotations

import numpy as np

from ..scenes.constraint_arrays import CM, CX, KEV, KST, reset_constraint_stats, set_keep, x_layout
from ..scenes.scene_arrays import S_CON
from ..scenes.scene_kernels import scene_rhs
from .constrained_oracle import ConstrainedRHS
from .loops.common import project

__all__ = ["ConstrainedRHS", "refresh_rhs", "initial_state", "project_state", "project_samples", "constraint_stats",
           "has_rows"]


def refresh_rhs(plan) -> None:
    """``plan.rhs`` compiled again when the plan's ``constraints`` were replaced after it was compiled (a test, a
    study dropping one constraint on our side): the compiled right-hand side carries the constraints it was
    built with."""
    from ..scenes.scene_kernels import CompiledScene, closure_parts

    now, packed = closure_parts(getattr(plan, "constraints", None)), getattr(plan.rhs, "closure_parts", ())
    if len(now) != len(packed) or any(a is not b for a, b in zip(now, packed)):     # its tendons replaced too
        plan.rhs = CompiledScene(plan)


def _layout(rhs):
    SI = rhs.SI
    c0 = int(SI[S_CON])
    m, n, nt = int(SI[c0 + CM]), int(SI[0]), int(SI[1])
    return m, n, int(SI[c0 + CX]), x_layout(m, n, nt)


def project_state(rhs, t: float, y, *, args=None) -> tuple[np.ndarray, float]:
    """``(y projected (E74), max |Phi| before)`` with the compiled projection; raises the named error where the
    right-hand side fails (A not positive definite, a change point where the scene stops)."""
    y = np.array(y, dtype=float)
    if not has_rows(rhs):
        return y, 0.0
    args = rhs.fresh_args() if args is None else args
    X = args[5]
    m, n, xc, lay = _layout(rhs)
    X[xc + lay[11] + 4] = 0.0
    f = np.empty(rhs.dim)
    counters = (np.zeros(4, np.int64), np.full(rhs.dim + 1, np.nan))
    if not project(float(t), y, f, args, counters):
        rhs.failure(float(counters[1][0]), counters[1][1:])
    return y, float(X[xc + lay[11] + 4])


def has_rows(rhs) -> bool:
    SI = rhs.SI
    return SI[S_CON] > 0 and SI[SI[S_CON] + CM] > 0


def initial_state(plan, q, qd) -> tuple[np.ndarray, dict]:
    """The initial state projected (E74) and what it moved; the redundant rows at ``q`` (E73) selected."""
    from ..dynamics.constrained import independent_rows

    rhs, cset = plan.rhs, plan.constraints.cset
    q, qd = np.asarray(q, float), np.asarray(qd, float)
    sel = independent_rows(cset.terms(q).J, cset.rows)
    if cset.m:
        set_keep(rhs.SI, sel.keep)
    reset_constraint_stats(rhs.SI, rhs.X)
    n = plan.model.n
    y, before = project_state(rhs, 0.0, np.r_[q, qd, 0.0])
    after = float(np.max(np.abs(cset.residual(y[:n])), initial=0.0))
    note = (f"initial state projected onto the constraints: |Phi| {before:.3g} -> {after:.3g}; q moved by "
            f"{np.max(np.abs(y[:n] - q), initial=0.0):.3g}, q' by {np.max(np.abs(y[n:2 * n] - qd), initial=0.0):.3g} "
            "(max over coordinates)")
    return y, {"note": note, "residual_before": before, "q_moved": float(np.max(np.abs(y[:n] - q), initial=0.0)),
               "qd_moved": float(np.max(np.abs(y[n:2 * n] - qd), initial=0.0)), "redundant": list(sel.notes),
               "rank": sel.rank}


def project_samples(plan, t, Y) -> None:
    """Every sample row of ``Y`` (S, 2n + 1) projected in place (E74): dense-output samples lie between two
    projected steps, off the constraints by up to one step's error."""
    rhs = plan.rhs
    if not has_rows(rhs):
        return
    args = rhs.fresh_args()
    for i in range(len(t)):
        Y[i] = project_state(rhs, t[i], Y[i], args=args)[0]


def constraint_stats(plan, t, Y, *, initial, method: str) -> dict:
    """``Trajectory.stats["constraints"]`` (module doc) from the compiled right-hand side at every sample and
    the run's statistics in the scene's scratch. ``solved_rows``: the rows solved at some sample (the start's
    choice, E73, and the rows chosen again where they lost rank on a floating base: ``row_changes`` times in the
    run), ``lambda`` (S, len(solved_rows)) their multipliers (0 at a sample where a row was not solved)."""
    rhs, cset = plan.rhs, plan.constraints.cset
    n, S = plan.model.n, len(t)
    lam_all, gen = np.zeros((S, cset.m)), np.zeros((S, n))
    solved = np.zeros(cset.m, bool)
    res, rate = np.zeros(S), np.zeros(S)
    stats = {"min_schur_pivot": np.inf, "min_schur_pivot_t": 0.0, "events": [], "max_step_drift": 0.0,
             "row_changes": 0}
    if cset.m:
        m, n_, xc, lay = _layout(rhs)
        args = rhs.fresh_args()
        X, out = args[5], np.empty(rhs.dim)
        for i in range(S):
            scene_rhs(float(t[i]), np.ascontiguousarray(Y[i]), out, *args)
            phi = X[xc + lay[0]:xc + lay[0] + m]
            J = X[xc + lay[2]:xc + lay[2] + m * n].reshape(m, n)
            solved |= X[xc + lay[8]:xc + lay[8] + m] != 0.0
            lam_all[i] = X[xc + lay[6]:xc + lay[6] + m]      # 0 on a row not solved here
            gen[i] = J.T @ lam_all[i]
            res[i], rate[i] = np.max(np.abs(phi)), np.max(np.abs(J @ Y[i, n:2 * n]))
        Xr = rhs.X
        st = Xr[xc + lay[11]:xc + lay[11] + KST]
        ev = Xr[xc + lay[12]:xc + lay[12] + 3 * int(min(st[2], KEV))].reshape(-1, 3)
        stats = {"min_schur_pivot": float(st[0]), "min_schur_pivot_t": float(st[1]), "max_step_drift": float(st[4]),
                 "events": [{"t": float(e[0]), "row": cset.rows[int(e[1])], "pivot": float(e[2]),
                             "what": f"change point: row {cset.rows[int(e[1])]!r} dependent on the others at "
                                     f"t = {e[0]:.6g} s (Schur pivot {e[2]:.3g}); dropped there, the run goes on"}
                            for e in ev],
                 "events_total": int(st[2]), "row_changes": int(st[7])}
    keep = np.nonzero(solved)[0]
    return {"rows": list(cset.rows), "solved_rows": [cset.rows[k] for k in keep], "residual": res,
            "rate_residual": rate, "max_residual": float(res.max(initial=0.0)), "lambda": lam_all[:, keep],
            "forces": gen, "initial": initial, "method": method, **stats}

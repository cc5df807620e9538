"""The literal oracle of a constrained run (issue 45): the KKT right-hand side in numpy, one step at a time,
projection after each step.

Constrained scenes run compiled (:mod:`urdf2links.integration.constrained`: the KKT solve inside the compiled
right-hand side, the projection inside the compiled loops). This module is the same law written plainly,
kept as the tests' oracle (``simulate_interpreted``) and for :class:`ConstrainedRHS` (the multipliers and
terms at one state, which the agreement studies read):

- the right-hand side is the scene's compiled free one (``plan.rhs`` without its constraints block) (every term the scene names: ``q''`` of
  the free tree and the power ``P``), turned into ``f = A q''_free = Q - e - G + ...`` with the compiled
  mass matrix, plus the fixed tendons' forces (E76), then solved with the multipliers (E72);
- the scene's method takes one step at a time (:mod:`urdf2links.integration.constrained_steps`: DOP853 or
  RK45 with the scene's ``rtol``, ``atol``; ``auto`` as DOP853; RK4 with its ``dt``; any other refused by
  name); after every accepted step
  the state is projected onto ``Phi = 0`` and ``Phi' = 0`` (E74) and the step's derivative is evaluated
  again at the projected state (the next step's first stage is the last one of the step before). Drift is
  thus bounded by one step's integration error and removed before it can grow: the residual stays at
  rounding level (the projection stops at ``max |Phi| <= 1e-13``). Samples are read from the step's dense
  output and projected the same way.
- the constraint forces do no work on the manifold (``lambda . Phi_q q' = 0`` there, fixed base), so
  ``W`` counts only the scene's own forces and ``h - h(0) - W`` stays the integration's energy error;
  the projection's own energy change is part of it.

``Trajectory.stats["constraints"]`` reports: the rows, the redundant ones (E73), the residual
``max |Phi|`` at every sample and the largest drift of any step before its projection, ``|Phi'|``,
the multipliers ``lambda`` (S, m) and the generalized constraint forces ``J^T lambda`` (S, n) at the
samples, and the initial projection.
"""

from __future__ import annotations

import numpy as np

from .. import compilation
from ..console import Progress
from ..dynamics.constrained import independent_rows, kkt_solve, project_position, project_velocity
from ..errors import IntegrationError
from .constrained_steps import check_constrained_method, constrained_stepper
from .trajectory import Trajectory

__all__ = ["ConstrainedRHS", "simulate_interpreted"]


class ConstrainedRHS:
    """``y' = (q', q'', P)`` of a plan with constraints (E72); :meth:`solve` also gives ``lambda``."""

    def __init__(self, plan, *, q0=None):
        self.plan = plan
        self.model = plan.model
        self.closure = plan.constraints
        self.cset = self.closure.cset
        self.where = str(plan.scene.path or plan.scene.name)
        self.nfev = 0
        from ..scenes.scene_kernels import CompiledScene

        self.free = CompiledScene(plan, constraints=False)     # plan.rhs solves the constraints itself (issue 45)
        self.min_pivot = (np.inf, 0.0)
        """The smallest eigenvalue of J A^-1 J^T scaled to a unit diagonal over every solve, and its time."""
        self.keep = np.arange(self.cset.m)
        self.selection = None
        if q0 is not None:
            self.select(q0)

    def select(self, q):
        """Redundant rows at ``q`` (E73): the solve keeps the independent ones."""
        T = self.cset.terms(q)
        self.selection = independent_rows(T.J, T.rows)
        self.keep = self.selection.keep
        return self.selection

    @property
    def kept_rows(self):
        return [self.cset.rows[k] for k in self.keep]

    def mass(self, t, q):
        return self.model.mass_matrix(q, t=t, base=self.plan.base_state(t))

    def free_forces(self, t, y, A):
        """``f`` of (E72): ``A q''_free`` of the scene's compiled right-hand side, plus the tendons (E76);
        and the free right-hand side (its ``P``, power of the scene's forces)."""
        n = self.model.n
        free = self.free(t, y)
        f = A @ free[n:2 * n]
        if self.closure.tendons:
            ft, pt = self.closure.tendon_forces(t, y[:n], y[n:2 * n])
            f = f + ft
            free[2 * n] += pt
        return f, free

    def solve(self, t, y):
        """``(y', lambda, terms)`` at ``(t, y)`` (E72)."""
        self.nfev += 1
        n = self.model.n
        q, qd = y[:n], y[n:2 * n]
        A = self.mass(t, q)
        f, out = self.free_forces(t, y, A)
        T = self.cset.terms(q, qd, t=t, base=self.plan.base_state(t))
        k = self.keep
        qdd, lam, Ls = kkt_solve(A, f, T.J[k], T.gamma[k], rows=self.kept_rows,
                                where=f"{self.where}: t = {t:.6g} s, q = {np.round(q, 6).tolist()}")
        if Ls is not None:      # how close the rows came to dependence (E72): the smallest eigenvalue of
            S = Ls @ Ls.T       # J A^-1 J^T scaled to a unit diagonal (rows of different units compare)
            d = 1.0 / np.sqrt(np.diag(S))
            pivot = float(np.linalg.eigvalsh(S * d[:, None] * d[None, :])[0])
            if pivot < self.min_pivot[0]:
                self.min_pivot = (pivot, float(t))
        out[n:2 * n] = qdd
        return out, lam, T

    def __call__(self, t, y):
        return self.solve(t, y)[0]

    def project(self, t, y):
        """``y`` with ``(q, q')`` projected onto ``Phi = 0``, ``Phi' = 0`` (E74); and the residual before."""
        n = self.model.n
        q, qd = y[:n], y[n:2 * n]
        base = self.plan.base_state(t)
        terms_of = lambda x: self.cset.terms(x, t=t, base=base)  # noqa: E731
        before = float(np.max(np.abs(terms_of(q).phi), initial=0.0))   # 0 rows: fixed tendons alone
        q2, _, _ = project_position(q, terms_of, lambda x: self.mass(t, x), self.keep, rows=self.cset.rows,
                                    where=f"{self.where}: projection at t = {t:.6g} s")
        T = self.cset.terms(q2, qd, t=t, base=base)
        qd2 = project_velocity(qd, T.J[self.keep], self.mass(t, q2), rows=self.kept_rows, where=self.where)
        out = np.array(y, float)
        out[:n], out[n:2 * n] = q2, qd2
        return out, before


def _initial(rhs, q, qd):
    """The initial state projected (E74), with what it moved."""
    sel = rhs.select(q)
    y0 = np.r_[q, qd, 0.0]
    y, before = rhs.project(0.0, y0)
    n = rhs.model.n
    note = (f"initial state projected onto the constraints: |Phi| {before:.3g} -> "
            f"{float(np.max(np.abs(rhs.cset.residual(y[:n])), initial=0.0)):.3g}; q moved by {np.max(np.abs(y[:n] - q)):.3g}, "
            f"q' by {np.max(np.abs(y[n:2 * n] - qd)):.3g} (max over coordinates)")
    return y, {"note": note, "residual_before": before, "q_moved": float(np.max(np.abs(y[:n] - q))),
               "qd_moved": float(np.max(np.abs(y[n:2 * n] - qd))), "redundant": list(sel.notes),
               "rank": sel.rank}


def simulate_interpreted(plan, run, q, qd, *, progress=None, max_wall=None, max_steps=10_000_000):
    """The run of a plan with constraints (module doc) -> :class:`~urdf2links.integration.trajectory.Trajectory`."""
    started, compiled0 = compilation.clock(), compilation.seconds()    # numba's compilation left out (one clock)
    rhs = ConstrainedRHS(plan)
    method = check_constrained_method(run, rhs.where, oracle=True)      # refused before any work: the method, scene, accepted
    model, n = plan.model, plan.model.n
    y, initial = _initial(rhs, np.asarray(q, float), np.asarray(qd, float))
    t_eval = np.linspace(0.0, run.t_end, max(run.samples, 2))
    Y = np.empty((t_eval.size, 2 * n + 1))
    Y[0] = y
    solver, label = constrained_stepper(rhs, y, run, rhs.where)
    bar = Progress(run.t_end, label=f"{plan.scene.name} {method}+projection", enabled=progress)
    k, steps, drift = 1, 0, 0.0
    t0 = compilation.clock()
    try:
        while solver.status == "running":
            msg = solver.step()
            if solver.status == "failed":
                raise IntegrationError(f"{rhs.where}: {label} with projection could not finish "
                                       f"the run to t_end = {run.t_end:g} s: {msg} at t = {solver.t:.6g} s")
            steps += 1
            dense = solver.dense_output()
            while k < t_eval.size and t_eval[k] <= solver.t:
                Y[k] = rhs.project(t_eval[k], dense(t_eval[k]))[0] if t_eval[k] < solver.t else np.nan
                k += 1
            yp, before = rhs.project(solver.t, solver.y)
            drift = max(drift, before)
            solver.y = yp
            solver.f = rhs(solver.t, yp)        # the first stage of the next step (FSAL)
            if np.isnan(Y[k - 1, 0]):
                Y[k - 1] = yp
            bar(solver.t)
            _limits(rhs, steps, max_steps, started, max_wall, solver.t)
    finally:
        bar.close()
    wall = compilation.clock() - t0
    return _trajectory(Trajectory, plan, rhs, run, t_eval, Y, steps, drift, initial, wall, (started, compiled0),
                       method=method)


def _limits(rhs, steps, max_steps, started, max_wall, t):
    if steps > max_steps:
        raise IntegrationError(f"{rhs.where}: more than max_steps = {max_steps} steps at t = {t:.6g} s")
    if max_wall is not None and compilation.clock() - started > max_wall:
        raise IntegrationError(f"{rhs.where}: max_wall = {max_wall:g} s spent at t = {t:.6g} s")


def _trajectory(Trajectory, plan, rhs, run, t, Y, steps, drift, initial, wall, started, *, method):
    model, n = plan.model, plan.model.n
    qs, qds, W = Y[:, :n], Y[:, n:2 * n], Y[:, 2 * n]
    E, V, h = plan.energies(t, qs, qds)
    if rhs.closure.tendons:
        V = V + np.array([rhs.closure.tendon_energy(q) for q in qs])
        h = h + (V - plan.energies(t, qs, qds)[1])
    lam = np.empty((t.size, len(rhs.keep)))
    gen = np.empty((t.size, n))
    res, rate = np.empty(t.size), np.empty(t.size)
    for i in range(t.size):
        _, lam[i], T = rhs.solve(t[i], Y[i])
        gen[i] = T.J[rhs.keep].T @ lam[i]
        res[i], rate[i] = np.max(np.abs(T.phi), initial=0.0), np.max(np.abs(T.rate), initial=0.0)
    info = {"rows": list(rhs.cset.rows), "solved_rows": rhs.kept_rows, "residual": res, "rate_residual": rate,
            "max_residual": float(res.max()), "max_step_drift": float(drift), "lambda": lam, "forces": gen,
            "initial": initial, "method": f"{method} + projection after every step (E74), interpreted path"
            + (" (auto: DOP853, the constrained path has no stiffness test)" if run.method == "auto" else ""),
            "min_schur_pivot": rhs.min_pivot[0], "min_schur_pivot_t": rhs.min_pivot[1]}
    stats = {"method": method, "scene_method": run.method, "integrator": f"{method}+projection", "rtol": run.rtol,
             "atol": run.atol, "dt": run.dt, "nfev": rhs.nfev, "nsteps": steps, "njev": 0,
             "stretches": [], "methods_used": f"{method} with projection", "wall_time": wall, "terms": plan.terms, "success": True, "message": "",
             "recharting": False, "n_recharts": 0, "recharts": [], "segments": 1, "limit_excursions": [],
             "spring_notes": list(plan.spring_set.notes), "constraints": info,
             "run_s": compilation.clock() - started[0], "compile_s": compilation.seconds() - started[1]}
    poses = {}
    if plan.scene.link_poses:       # [record] link_poses
        from .charts import link_poses

        poses = {link: np.empty((t.size, 4, 4)) for link in plan.scene.link_poses}
        for i in range(t.size):
            P = link_poses(model, list(poses), qs[i], t=t[i], base=plan.base_state(t[i]))
            for link in poses:
                poses[link][i] = P[link]
    return Trajectory(t=t, q=qs, qd=qds, coordinate_names=model.coordinate_names,
                      energy={"kinetic": E, "potential": V, "work": W, "function": h, "error": h - h[0] - W},
                      poses=poses, stats=stats, scene=plan.scene.name, robot=model.name)

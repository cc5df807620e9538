"""A constrained scene against MuJoCo (issue 36): terms at identical states, and MuJoCo converging as solref shrinks.

- :func:`constraint_terms`: at states on the constraints, the project's ``Phi_q`` (E71) against MuJoCo's
  ``efc_J`` rows of each equality, mapped (a connect's and a joint's rows are the same functions; a weld's
  rotation rows are MuJoCo's ``0.5 R_2^T (omega_1 - omega_2)``, i.e. ours times ``0.5 R_2^T``), and the
  multipliers ``lambda`` (E72) against ``efc_force`` (mapped the same way), and ``J^T lambda`` against
  ``qfrc_constraint``. MuJoCo's force differs from the exact one by its regularizer: at MuJoCo's largest
  impedance (``solimp`` 0.9999) by about 1e-4 relative.
- :func:`solref_study`: MuJoCo's trajectory (route 1: the scene's constraints written as MJCF equalities) from
  the project's projected initial state, for three ``solref`` time constants ``tau``; its largest distance from
  the project's trajectory, and the convergence rate ``log10(err(tau) / err(tau / 10))`` per decade (the issue
  asks at least 5x per 10x: a rate of 0.7).
- both are written as a report by :mod:`urdf2links.compare.reports.loops`.
"""

from __future__ import annotations

import numpy as np

from urdf2links.compilation import clock  # durations without numba's compilation
from urdf2links.integration.constrained import ConstrainedRHS

from ..mujoco_side.mjcf import mjcf_from_scene
from ..mujoco_side.mujoco_constraints import COMPARE_SOLREF, SOLIMP, equality_rows, with_constraints
from ..mujoco_side.mujoco_run import run_mujoco

__all__ = ["constraint_terms", "solref_study", "run_notes", "states_of", "TAUS"]

TAUS = (1e-2, 1e-3, 1e-4)       # solref time constants (s) of the study
STUDY_DT = 1e-5                 # MuJoCo's RK4 step in the study: tau / dt >= 10 at the smallest tau


def _mapped_rows(c, J, lam, R2):
    """Ours as MuJoCo writes them: a weld's rotation rows are ``0.5 R_2^T`` ours (module doc)."""
    if c.kind != "weld":
        return J, lam
    J, lam = J.copy(), lam.copy()
    J[3:] = 0.5 * R2.T @ J[3:]
    lam[3:] = 2.0 * R2.T @ lam[3:]
    return J, lam


def constraint_terms(plan, mj, states) -> dict:
    """Max differences over ``states`` ((q, qd) on the constraints) of ``Phi_q`` against ``efc_J``, ``lambda``
    against ``efc_force`` and ``J^T lambda`` against ``qfrc_constraint`` (absolute, and the scales)."""
    rhs = ConstrainedRHS(plan, q0=states[0][0])
    cs = rhs.cset
    dJ = dF = dQ = 0.0
    sJ = sF = sQ = 0.0
    for q, qd in states:
        y = np.r_[q, qd, 0.0]
        _, lam_kept, T = rhs.solve(0.0, y)
        lam = np.zeros(cs.m)
        lam[rhs.keep] = lam_kept
        d = mj.data(q, qd)
        poses = plan.model.link_poses(q)
        k = 0
        for e, c in enumerate(cs.constraints):
            rows = equality_rows(mj.model, d, e)
            nr = len(rows)
            R2 = np.eye(3) if c.link2 < 0 else poses[c.link2][:3, :3] @ c.frame2
            Jo, lo = _mapped_rows(c, T.J[k:k + nr], lam[k:k + nr], R2)
            Jm = np.asarray(d.efc_J).reshape(-1, mj.model.nv)[rows][:, mj.dof_index]
            dJ, sJ = max(dJ, np.abs(Jm - Jo).max()), max(sJ, np.abs(Jo).max())
            fm = np.asarray(d.efc_force)[rows]
            dF, sF = max(dF, np.abs(fm - lo).max()), max(sF, np.abs(lo).max())
            k += nr
        gen = T.J[rhs.keep].T @ lam_kept
        dQ = max(dQ, np.abs(np.asarray(d.qfrc_constraint)[mj.dof_index] - gen).max())
        sQ = max(sQ, np.abs(gen).max())
    return {"states": len(states), "jacobian": {"max_abs": dJ, "scale": sJ}, "force": {"max_abs": dF, "scale": sF},
            "generalized_force": {"max_abs": dQ, "scale": sQ},
            "note": "efc_J rows of every equality against Phi_q (a weld's rotation rows mapped by 0.5 R2^T); efc_force "
                    "against lambda; qfrc_constraint against J^T lambda; MuJoCo at solimp 0.9999: its regularizer, "
                    "(1 - d) / d = 1e-4 of the diagonal of J M^-1 J^T, shifts its forces by about that much, more "
                    "where rows share coordinates (J M^-1 J^T ill-conditioned)"}


def _route2_run(plan, traj, tau, timestep, solimp):
    """MuJoCo running the MJCF file itself (route 2) with its equalities on, every solref ``(tau, 1)``."""
    from ..mujoco_side.mujoco_mjcf import mujoco_from_mjcf, run_file

    mf = mujoco_from_mjcf(plan, timestep=timestep, integrator="RK4")
    mf.model.eq_solref[:] = (tau, 1.0)
    mf.model.eq_solimp[:] = solimp
    return run_file(mf, plan, t_end=float(traj.t[-1]), samples=len(traj.t), reference=traj.q)


def solref_study(plan, traj, *, taus=TAUS, timestep=STUDY_DT, solimp=SOLIMP, route: int = 1) -> dict:
    """MuJoCo (RK4 at ``timestep``) from the project's first sample, for each ``tau``: the largest distance
    ``max |q_mujoco - q|`` over the run's samples, and the rate per decade of ``tau``. ``route`` 1: the
    scene's constraints written as MJCF equalities; 2: an MJCF file run as written, its equalities on (from
    the scene's initial state, which must then be on the constraints)."""
    mj0 = mjcf_from_scene(plan.scene, plan.model, timestep=timestep, integrator="RK4") if route == 1 else None
    rows = []
    for tau in taus:
        t0 = clock()
        if route == 2:
            run = _route2_run(plan, traj, tau, timestep, solimp)
        else:
            mj = with_constraints(mj0, plan.constraints, solref=(tau, 1.0), solimp=solimp)
            run = run_mujoco(mj, plan.scene, q0=traj.q[0], qd0=traj.qd[0], t_end=float(traj.t[-1]),
                             samples=len(traj.t))
        err = np.abs(run.q - traj.q).max(axis=1)
        rows.append({"tau": tau, "max_error": float(err.max()), "error_t": err, "wall_s": clock() - t0,
                     "notes": run.notes})
    rates = [float(np.log10(a["max_error"] / b["max_error"]) / np.log10(a["tau"] / b["tau"]))
             for a, b in zip(rows, rows[1:])]
    ratios = [a["max_error"] / b["max_error"] for a, b in zip(rows, rows[1:])]
    return {"route": route, "timestep": timestep, "integrator": "RK4", "solimp": list(solimp), "dampratio": 1.0,
            "runs": rows,
            "rates": rates, "ratios": ratios, "t": traj.t,
            "holds": bool(all(r >= 5.0 for r in ratios))}      # the taus are a decade apart


def run_notes(plan, traj, mj=None) -> list[str]:
    """A comparison's notes on a constrained run (``compare_scene``): the project's residual and forces,
    the terms at identical states against MuJoCo's (route 1 ``mj``, at four samples of the run), and MuJoCo's
    softness."""
    c = traj.stats.get("constraints")
    if c is None:
        return []
    terms = []
    if mj is not None and plan.constraints.cset.m and len(traj.t) >= 6:
        t = constraint_terms(plan, mj, states_of(traj))
        terms = [f"constraint terms at {t['states']} states of the run: Phi_q against MuJoCo's efc_J rows "
                 f"{t['jacobian']['max_abs']:.2e} (of {t['jacobian']['scale']:.3g}); lambda against efc_force "
                 f"{t['force']['max_abs']:.2e} (of {t['force']['scale']:.3g}); J^T lambda against qfrc_constraint "
                 f"{t['generalized_force']['max_abs']:.2e} (of {t['generalized_force']['scale']:.3g})"]
    if not c["rows"]:       # fixed tendons alone (a stiffness, a damping): nothing to solve or project
        return [f"fixed tendons ({', '.join(td.name for td in plan.constraints.tendons)}) act on both engines "
                "(E76); no constraint rows: their forces act in the compiled right-hand side"]
    return terms + ([f"constraints ({', '.join(c['rows'])}): solved with multipliers and projected after every step "
             f"(E72-E74, {c['method']}); max |Phi| {c['max_residual']:.2e} at the samples, "
             f"{c['max_step_drift']:.2e} before any projection; lambda {c['lambda'].min():.4g} .. "
             f"{c['lambda'].max():.4g}", c["initial"]["note"]] + list(c["initial"]["redundant"])
            + [e["what"] for e in c.get("events", ())]      # issue 45: change points passed (change_point continue)
            + [f"MuJoCo's constraints are soft (solref {list(COMPARE_SOLREF)}, solimp {SOLIMP[0]:g}): how its run "
               "approaches the exact one as solref's time constant shrinks: python -m "
               "urdf2links.compare.reports.loops SCENE (reports/loops/)"])


def states_of(traj, k=4):
    """``k`` (q, qd) samples of a run, evenly spread inside it."""
    idx = np.linspace(0, len(traj.t) - 1, k + 2).astype(int)[1:-1]
    return [(traj.q[i], traj.qd[i]) for i in idx]

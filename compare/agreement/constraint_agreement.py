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

from dataclasses import dataclass

import numpy as np

from urdf2links.compilation import clock  # durations without numba's compilation
from urdf2links.integration.constrained import ConstrainedRHS

from ..mujoco_side.mjcf import mjcf_from_scene
from ..mujoco_side.mujoco_constraints import COMPARE_SOLREF, SOLIMP, equality_rows, with_constraints
from ..mujoco_side.mujoco_run import run_mujoco

__all__ = ["constraint_terms", "solref_study", "run_notes", "states_of", "TAUS", "loop_figures", "efc_series", "full_lambda",
           "RESIDUAL_BOUND", "FORCE_BOUND", "STUDY_WINDOW"]

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
    against ``efc_force`` (row by row) and ``J^T lambda`` of both engines through our ``Phi_q`` (MuJoCo's rows
    mapped to ours: unique where the rows' split of a force is not, and in our coordinates) (absolute, and the
    scales)."""
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
        gen_ours, gen_mj = np.zeros(plan.model.n), np.zeros(plan.model.n)
        for e, c in enumerate(cs.constraints):
            rows = equality_rows(mj.model, d, e)
            nr = len(rows)
            R2 = np.eye(3) if c.link2 < 0 else poses[c.link2][:3, :3] @ c.frame2
            Jo, lo = _mapped_rows(c, T.J[k:k + nr], lam[k:k + nr], R2)
            Jm = np.asarray(d.efc_J).reshape(-1, mj.model.nv)[rows][:, mj.dof_index]
            dJ, sJ = max(dJ, np.abs(Jm - Jo).max()), max(sJ, np.abs(Jo).max())
            fm = np.asarray(d.efc_force)[rows]
            dF, sF = max(dF, np.abs(fm - lo).max()), max(sF, np.abs(lo).max())
            gen_ours += Jo.T @ lo           # both engines' forces through our Phi_q (the rows mapped alike)
            gen_mj += Jo.T @ fm
            k += nr
        dQ = max(dQ, np.abs(gen_mj - gen_ours).max())
        sQ = max(sQ, np.abs(gen_ours).max())
    return {"states": len(states), "jacobian": {"max_abs": dJ, "scale": sJ}, "force": {"max_abs": dF, "scale": sF},
            "generalized_force": {"max_abs": dQ, "scale": sQ},
            "note": "efc_J rows of every equality against Phi_q (a weld's rotation rows mapped by 0.5 R2^T); efc_force "
                    "against lambda row by row (information: rows that share coordinates, a planar loop's dependent "
                    "rows, may split one force in any proportion); J^T lambda of both engines through our Phi_q (unique, "
                    "in our coordinates, a floating root's included); MuJoCo at solimp 0.9999: its regularizer, "
                    "(1 - d) / d = 1e-4 of the diagonal of J M^-1 J^T, shifts its forces by about that much, more "
                    "where rows share coordinates (J M^-1 J^T ill-conditioned)"}


def _route2_run(plan, traj, tau, timestep, solimp):
    """MuJoCo running the MJCF file itself (route 2) with its equalities on, every solref ``(tau, 1)``."""
    from ..mujoco_side.mujoco_mjcf import mujoco_from_mjcf, run_file

    mf = mujoco_from_mjcf(plan, timestep=timestep, integrator="RK4")
    mf.model.eq_solref[:] = (tau, 1.0)
    mf.model.eq_solimp[:] = solimp
    return run_file(mf, plan, t_end=float(traj.t[-1]), samples=len(traj.t), reference=traj.q)


def _window(traj, t_end):
    """The samples of ``traj`` up to ``t_end`` (all of them for None): ``(k, t_k)``, the count and the last time."""
    k = len(traj.t) if t_end is None else max(2, int(np.searchsorted(traj.t, t_end * (1 + 1e-12), side="right")))
    return k, float(traj.t[k - 1])


def solref_study(plan, traj, *, taus=TAUS, timestep=STUDY_DT, solimp=SOLIMP, route: int = 1,
                 t_end: float | None = None, steps_per_tau: float | None = None, floor: float = 0.0) -> dict:
    """MuJoCo (RK4 at ``timestep``) from the project's first sample, for each ``tau``: the largest distance
    ``max |q_mujoco - q|`` over the run's samples, and the rate per decade of ``tau``. ``route`` 1: the
    scene's constraints written as MJCF equalities; 2: an MJCF file run as written, its equalities on (from
    the scene's initial state, which must then be on the constraints). ``t_end``: only the samples up to it
    (the report's short study, :func:`loop_figures`); ``steps_per_tau``: MuJoCo's step ``min(timestep, tau /
    steps_per_tau)`` per run instead of ``timestep`` for all. ``holds``: every ratio at least 5 (a rate of 0.7
    per decade), a pair whose smaller error is at or below ``floor`` counting as converged (nothing left to
    approach)."""
    k, T = _window(traj, t_end)
    sub = traj if k == len(traj.t) else _Prefix(traj.t[:k], traj.q[:k], traj.qd[:k])
    mj0 = mjcf_from_scene(plan.scene, plan.model, timestep=timestep, integrator="RK4") if route == 1 else None
    rows = []
    for tau in taus:
        t0 = clock()
        dt = timestep if steps_per_tau is None else min(timestep, tau / steps_per_tau)
        if route == 2:
            run = _route2_run(plan, sub, tau, dt, solimp)
        else:
            mj = with_constraints(mj0, plan.constraints, solref=(tau, 1.0), solimp=solimp)
            run = run_mujoco(mj, plan.scene, q0=sub.q[0], qd0=sub.qd[0], t_end=T, samples=k, timestep=dt)
        err = np.abs(run.q - sub.q).max(axis=1)
        err = np.where(np.isfinite(err), err, np.inf)       # a blow-up is an infinite distance, not a NaN
        rows.append({"tau": tau, "timestep": dt, "steps": int(round(T / dt)), "max_error": float(err.max()),
                     "error_t": err, "wall_s": clock() - t0, "blow_ups": dict(run.blow_ups), "notes": run.notes})
    rates = [_rate(a, b) for a, b in zip(rows, rows[1:])]
    ratios = [a["max_error"] / b["max_error"] if b["max_error"] > 0 else np.inf for a, b in zip(rows, rows[1:])]
    held = [bool(r >= 5.0 or b["max_error"] <= floor) for r, b in zip(ratios, rows[1:])]
    return {"route": route, "timestep": timestep, "integrator": "RK4", "solimp": list(solimp), "dampratio": 1.0,
            "runs": rows, "t_end": T, "samples": k, "steps_per_tau": steps_per_tau, "floor": floor,
            "rates": rates, "ratios": ratios, "t": sub.t, "held": held,
            "holds": bool(all(held))}      # the taus are a decade apart


def _rate(a, b) -> float:
    """log10(err_a / err_b) per decade of tau; inf when b is exact, nan when a is."""
    if not (np.isfinite(a["max_error"]) and np.isfinite(b["max_error"])) or a["max_error"] <= 0:
        return float("nan")
    if b["max_error"] <= 0:
        return float("inf")
    return float(np.log10(a["max_error"] / b["max_error"]) / np.log10(a["tau"] / b["tau"]))


@dataclass(frozen=True)
class _Prefix:
    """The first samples of a run (``t``, ``q``, ``qd``): what the short study compares against."""

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray


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
                 f"{t['jacobian']['max_abs']:.2e} (of {t['jacobian']['scale']:.3g}); lambda against efc_force row by "
                 f"row {t['force']['max_abs']:.2e} (of {t['force']['scale']:.3g}; rows that share coordinates may "
                 f"split one force differently); J^T lambda of both engines through Phi_q "
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
               "approaches the exact one as solref's time constant shrinks is the report's solref study (section "
               "'Closed loops'; the full-length study: python -m urdf2links.compare.reports.loops SCENE)"])


def states_of(traj, k=4):
    """``k`` (q, qd) samples of a run, evenly spread inside it."""
    idx = np.linspace(0, len(traj.t) - 1, k + 2).astype(int)[1:-1]
    return [(traj.q[i], traj.qd[i]) for i in idx]


# --------------------------------------------------------------------------- the report's loop sections (issue 45)

#: The issue's bound on the project's residual max |Phi| over the run (m for point rows, rad for angles).
RESIDUAL_BOUND = 1e-9
#: MuJoCo's ``efc_force`` at the project's states (the project's free forces, MuJoCo's own constraint law) may differ
#: from ``lambda`` by this share of max |lambda|: its regularizer at solimp 0.9999 shifts a row by 1e-4 of the
#: row's own inertia, more where rows share coordinates (measured on the shipped loops: up to 1.5e-3, four-bar
#: 2.7e-4); a connect point 1 mm off gives forces of k Phi ~ 1e6 / s^2 x 1e-3 m x the mass: order 1.
FORCE_BOUND = 1e-2
#: MuJoCo's and our forces closer than this (N, N m) agree whatever the scale: a coupling that carries no force (the
#: symmetric gripper's: max |lambda| 2e-16, the difference 1.8e-11) has nothing to be relative to.
FORCE_FLOOR = 1e-8
#: The report's solref study compares the first seconds of the run (each of its three MuJoCo runs is that long).
STUDY_WINDOW = 0.25
#: MuJoCo's step in the study is at most tau / STEPS_PER_TAU (RK4 resolves the constraint's own time constant).
STEPS_PER_TAU = 10.0
#: A study error at or below this (rad, m) has nothing left to approach: a pair ending there counts as converged
#: (1e-6 of the divergence threshold; the four-bar reaches 1.2e-9 at tau 1e-4 over 2 s).
STUDY_FLOOR = 1e-9


def _units(c) -> list[str]:
    """The units of a constraint's rows (its ``lambda``): N on a point row, N m on an orientation row, the
    coordinate's generalized force (N m, or N on a slide) on a joint or tendon row."""
    if c.kind == "connect":
        return ["N"] * 3
    if c.kind == "weld":
        return ["N"] * 3 + ["N m"] * 3
    return ["N m (N on a slide)"]


def full_lambda(cons: dict) -> np.ndarray:
    """The project's multipliers (S, m) on every row of ``Trajectory.stats["constraints"]`` (``lambda`` holds the
    solved rows; a redundant row, E73, carries no force: 0)."""
    rows, solved = list(cons["rows"]), list(cons["solved_rows"])
    lam = np.asarray(cons["lambda"], float)
    out = np.zeros((lam.shape[0], len(rows)))
    for k, r in enumerate(solved):
        out[:, rows.index(r)] = lam[:, k]
    return out


def efc_series(mj, plan, t, Q, QD) -> dict:
    """MuJoCo's equality rows of route 1 ``mj`` at the states ``(t, Q, QD)`` ((S,), (S, n), (S, n)), after
    ``mj_forward`` with the scene's inputs at ``t`` (the compiled control callback: torques, loads, controls,
    contact), mapped to the project's rows ((S, m) each): ``force`` (``efc_force``; a weld's rotation rows as
    ``0.5 R_2`` MuJoCo's, the inverse of :func:`_mapped_rows`), ``pos`` (``efc_pos``: the soft constraint's
    violation) and ``vel`` (``efc_vel``, its rate)."""
    import mujoco

    from ..mujoco_side.mujoco_inputs import CompiledInputs

    m, cs = mj.model, plan.constraints.cset
    d = mujoco.MjData(m)
    S = len(t)
    out = {k: np.zeros((S, cs.m)) for k in ("force", "pos", "vel")}
    inputs = CompiledInputs(mj, plan, m, d)
    welds = any(c.kind == "weld" for c in cs.constraints)
    with inputs.installed():
        for i in range(S):
            d.time = float(t[i])
            mj.set_state(d, Q[i], QD[i], base=plan.base_state(float(t[i])) if mj.moving_base else None)
            mujoco.mj_forward(m, d)
            poses = plan.model.link_poses(Q[i]) if welds else None
            k = 0
            for e, c in enumerate(cs.constraints):
                rows = equality_rows(m, d, e)
                nr = len(_units(c))
                if len(rows) == nr:         # an inactive equality has no rows: zeros
                    for key, arr in (("force", d.efc_force), ("pos", d.efc_pos), ("vel", d.efc_vel)):
                        v = np.asarray(arr)[rows]
                        if c.kind == "weld" and key == "force":
                            R2 = np.eye(3) if c.link2 < 0 else poses[c.link2][:3, :3] @ c.frame2
                            v = np.r_[v[:3], 0.5 * R2 @ v[3:]]
                        out[key][i, k:k + nr] = v
                k += nr
    return out


def _generalized_figures(cs, traj, lam, theirs, plan) -> dict:
    """``J^T lambda`` of both engines at the project's samples, through the project's ``Phi_q`` of every row (E71):
    MuJoCo's rows mapped to ours (:func:`efc_series`) and ours (0 where a row was not solved there). Unique where
    the rows' multipliers are not: a planar loop's dependent rows (E73) share their force in any proportion (MuJoCo's
    regularized solve spreads it over all of them, ours solves the independent ones), so rows are compared through
    the generalized force they exert. :func:`_force_figures` of the two, by coordinate."""
    S, n = len(traj.t), plan.model.n
    ours, mj = np.zeros((S, n)), np.zeros((S, n))
    for i in range(S):
        J = cs.terms(traj.q[i], t=float(traj.t[i]), base=plan.base_state(float(traj.t[i]))).J
        ours[i], mj[i] = J.T @ lam[i], J.T @ theirs[i]
    return _force_figures(ours, mj, list(plan.model.coordinate_names))


def _force_figures(ours, theirs, rows) -> dict:
    """max |MuJoCo - ours| over samples and rows, the scale max |ours| and their ratio; per row."""
    diff = np.abs(theirs - ours)
    scale = float(np.abs(ours).max(initial=0.0))
    dmax = float(diff.max(initial=0.0))
    return {"max_abs": dmax, "scale": scale, "relative": dmax / scale if scale > 0 else (0.0 if dmax == 0 else np.inf),
            "by_row": {r: float(diff[:, j].max(initial=0.0)) for j, r in enumerate(rows)}}


def _at_times(t_from, X, t_to) -> np.ndarray:
    """``X`` (S, m) sampled at ``t_from`` read at ``t_to`` (linear; the same array when the times agree)."""
    if len(t_from) == len(t_to) and np.allclose(t_from, t_to, rtol=0, atol=1e-12):
        return X
    return np.stack([np.interp(t_to, t_from, X[:, j]) for j in range(X.shape[1])], axis=1)


def loop_figures(c, *, plan=None, window: float = STUDY_WINDOW, taus=TAUS) -> tuple[dict, dict]:
    """The report's loop sections of a comparison ``c``
    (:class:`~urdf2links.compare.agreement.trajectory.SceneComparison`) of a scene with constraint rows: the
    summary (JSON-ready, ``summary.json``'s ``constraints``) and the series the figures plot. Module doc of
    :mod:`urdf2links.compare.reports.loop_section` says what is compared; its cost: ``mj_forward`` at every
    sample of both runs and the three short MuJoCo runs of :func:`solref_study`."""
    from urdf2links.scenes.plan import compile_plan

    t0 = clock()
    plan = plan or compile_plan(c.scene, c.model)
    traj, run, cons = c.traj, c.run, c.traj.stats["constraints"]
    cs = plan.constraints.cset
    rows = list(cons["rows"])
    lam = full_lambda(cons)
    at_ours = efc_series(c.mj, plan, traj.t, traj.q, traj.qd)
    along = efc_series(c.mj, plan, run.t, run.q, run.qd)
    f_ours = _force_figures(lam, at_ours["force"], rows)
    f_along = _force_figures(_at_times(traj.t, lam, run.t), along["force"], rows)
    gen = _generalized_figures(cs, traj, lam, at_ours["force"], plan)
    t1 = clock()
    route = 2 if c.summary_route() == "route 2" else 1
    study = solref_study(plan, traj, taus=taus, timestep=float(run.timestep), route=route, t_end=window,
                         steps_per_tau=STEPS_PER_TAU, floor=STUDY_FLOOR)
    t2 = clock()
    res = {"max": float(cons["max_residual"]), "rate_max": float(np.max(cons["rate_residual"], initial=0.0)),
           "max_step_drift": float(cons.get("max_step_drift", np.nan)), "bound": RESIDUAL_BOUND,
           "mujoco_max": float(np.abs(along["pos"]).max(initial=0.0)),
           "mujoco_rate_max": float(np.abs(along["vel"]).max(initial=0.0)),
           "units": "m on point rows, rad on orientation and joint rows (|Phi'|: per second)"}
    res["ok"] = bool(res["max"] <= RESIDUAL_BOUND)
    units = dict(zip(rows, [u for con in cs.constraints for u in _units(con)]))
    forces = {"at_our_states": f_ours, "along_mujoco_run": f_along, "bound_relative": FORCE_BOUND,
              "floor": FORCE_FLOOR, "units": units,
              "generalized": gen,
              "ok": bool(gen["relative"] <= FORCE_BOUND or gen["max_abs"] <= FORCE_FLOOR),
              "sign": "the same on both: the generalized force is J^T lambda = efc_J^T efc_force (qfrc_constraint); "
                      "a point row's force acts on the first link's point along +axis, its reaction on the second",
              "what": "at_our_states: MuJoCo's efc_force of its equality rows by mj_forward at the project's samples "
                      "(the same state, time and inputs; there MuJoCo's Phi = Phi' = 0 and its force differs from "
                      "lambda by its regularizer only). along_mujoco_run: efc_force at MuJoCo's own samples, against "
                      "lambda at the same times: its soft constraint's violation adds -k Phi - b Phi' there"}
    summary = {"closed": [_described(con, plan.model) for con in cs.constraints], "rows": rows,
               "solved_rows": list(cons["solved_rows"]), "redundant": list(cons["initial"].get("redundant", [])),
               "method": cons.get("method"), "residual": res, "forces": forces,
               "mujoco": {"solref": list(COMPARE_SOLREF), "solimp": list(SOLIMP), "route": c.summary_route()},
               "study": _study_summary(study, c),
               "wall_s": {"forces_s": t1 - t0, "study_s": t2 - t1, "total_s": clock() - t0}}
    summary.update(_loop_agreement(summary, c))
    series = {"t": traj.t, "residual": np.asarray(cons["residual"]), "rate_residual": np.asarray(cons["rate_residual"]),
              "lambda": lam, "mj_at_ours": at_ours["force"], "t_mj": run.t, "mj_along": along["force"],
              "mj_pos": np.abs(along["pos"]).max(axis=1, initial=0.0) if len(rows) else np.zeros(len(run.t)),
              "rows": rows, "units": units, "study": study}
    return summary, series


def _described(con, model) -> dict:
    """A constraint in the summary: name, kind, what it joins, its source."""
    names = model.tree.link_names
    link = (lambda p: "world" if p < 0 else names[p])     # noqa: E731
    coords = model.coordinate_names
    if con.kind in ("connect", "weld"):
        joins = f"{link(con.link1)} - {link(con.link2)}"
    elif con.kind == "joint":
        joins = coords[con.coord1] + (f" - {coords[con.coord2]}" if con.coord2 >= 0 else "")
    else:
        joins = "two fixed tendons' lengths"
    return {"name": con.name, "kind": con.kind, "joins": joins, "rows": len(_units(con)), "source": con.source}


def _study_summary(study: dict, c) -> dict:
    """The study's JSON (the error series left out: the figure plots them)."""
    runs = [{k: v for k, v in r.items() if k not in ("error_t",)} for r in study["runs"]]
    finite = [r for r, b in zip(study["rates"], study["runs"][1:])     # the pairs above the floor: a rate measured
              if np.isfinite(r) and b["max_error"] > study["floor"]]
    return {"route": study["route"], "t_end": study["t_end"], "samples": study["samples"],
            "integrator": "RK4", "steps_per_tau": study["steps_per_tau"], "solimp": study["solimp"],
            "dampratio": study["dampratio"], "taus": [r["tau"] for r in runs], "runs": runs,
            "rates": study["rates"], "ratios": study["ratios"], "held": study["held"], "holds": study["holds"],
            "rate": min(finite) if finite else None, "floor": study["floor"], "required_ratio": 5.0,
            "what": (f"MuJoCo run {len(runs)} more times over the first {study['t_end']:g} s ("
                     + ("route 2: the MJCF file itself" if study["route"] == 2 else
                        "route 1: the project's tree, the scene's constraints as MJCF equalities")
                     + f"), RK4 at min({c.run.timestep:g} s, tau / {STEPS_PER_TAU:g}), solimp {SOLIMP[0]:g}, damping "
                       "ratio 1, from the project's first sample; error = max over samples and coordinates of "
                       "|q_MuJoCo - q_urdf2links|; rate = log10(error ratio) per decade of tau")}


def _loop_agreement(s: dict, c) -> dict:
    """The issue's agreement of a closed run (residual below 1e-9; MuJoCo approaching 5x per 10x smaller tau, or
    the trajectories within the divergence threshold) and MuJoCo's forces at our states within FORCE_BOUND."""
    res, f, st = s["residual"], s["forces"], s["study"]
    within = bool(np.all(np.abs(c.error) <= c.threshold)) if c.error.size else True
    reasons = []
    if not res["ok"]:
        reasons.append(f"residual max |Phi| {res['max']:.2g} > {RESIDUAL_BOUND:g}")
    if not f["ok"]:
        fa = f["generalized"]
        worst = max(fa["by_row"], key=fa["by_row"].get) if fa["by_row"] else "-"
        reasons.append(f"MuJoCo's generalized constraint forces J^T lambda at our states {fa['relative']:.2g} of "
                       f"max |J^T lambda| from ours (> {FORCE_BOUND:g}; worst coordinate {worst}: "
                       f"{fa['by_row'].get(worst, 0.0):.3g})")
    if not (st["holds"] or within):
        reasons.append("MuJoCo does not approach our run as solref's tau shrinks (errors "
                       + ", ".join(f"{r['max_error']:.2g}" for r in st["runs"]) + f" at tau "
                       + ", ".join(f"{r['tau']:g}" for r in st["runs"]) + " s; at least 5x per 10x needed)")
    rate = st["rate"]
    fa = f["generalized"]
    text = (f"the loops agree: residual {res['max']:.1e} (<= {RESIDUAL_BOUND:g}), MuJoCo's generalized constraint "
            "forces at our states " + (f"{fa['relative']:.1e} of max |J^T lambda| (<= {FORCE_BOUND:g})"
                                       if fa["max_abs"] > FORCE_FLOOR
                         else f"within {fa['max_abs']:.1e} (<= {FORCE_FLOOR:g} N)")
            + ", solref study: MuJoCo approaches ours "
            + (f"{rate:.2f} decades per decade of tau (>= 0.7)" if rate is not None else "(all at the floor)")
            + ("" if st["holds"] else ", not converging, but the trajectories agree within the divergence threshold")
            if not reasons else "the loops DISAGREE: " + "; ".join(reasons))
    return {"agree": not reasons, "reasons": reasons, "text": text, "trajectory_within_threshold": within}

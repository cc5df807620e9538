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
- :func:`constraint_report`: both, with the project's run (residual, energy, redundant rows, forces), as
  ``constraints.json`` and ``constraints.md``, and ``solref.png``.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import mujoco
import numpy as np

from urdf2links.integration import simulate
from urdf2links.integration.constrained import ConstrainedRHS
from urdf2links.scenes import as_plan

from ..figures import figure, save_png
from ..formatting import json_ready
from ..mujoco_side.mjcf import mjcf_from_scene
from ..mujoco_side.mujoco_constraints import COMPARE_SOLREF, SOLIMP, equality_rows, with_constraints
from ..mujoco_side.mujoco_run import run_mujoco

__all__ = ["constraint_terms", "solref_study", "constraint_report", "run_notes", "TAUS"]

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
                    "against lambda; qfrc_constraint against J^T lambda; MuJoCo at solimp 0.9999 (its regularizer "
                    "(1 - d) / d = 1e-4 of the rows' inertia makes its force that much smaller)"}


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
        t0 = time.perf_counter()
        if route == 2:
            run = _route2_run(plan, traj, tau, timestep, solimp)
        else:
            mj = with_constraints(mj0, plan.constraints, solref=(tau, 1.0), solimp=solimp)
            run = run_mujoco(mj, plan.scene, q0=traj.q[0], qd0=traj.qd[0], t_end=float(traj.t[-1]),
                             samples=len(traj.t))
        err = np.abs(run.q - traj.q).max(axis=1)
        rows.append({"tau": tau, "max_error": float(err.max()), "error_t": err, "wall_s": time.perf_counter() - t0,
                     "notes": run.notes})
    rates = [float(np.log10(a["max_error"] / b["max_error"]) / np.log10(a["tau"] / b["tau"]))
             for a, b in zip(rows, rows[1:])]
    ratios = [a["max_error"] / b["max_error"] for a, b in zip(rows, rows[1:])]
    return {"route": route, "timestep": timestep, "integrator": "RK4", "solimp": list(solimp), "dampratio": 1.0,
            "runs": rows,
            "rates": rates, "ratios": ratios, "t": traj.t,
            "holds": bool(all(r >= 5.0 for r in ratios))}      # the taus are a decade apart


def run_notes(plan, traj) -> list[str]:
    """A comparison's notes on a constrained run (``compare_scene``): the project's residual and forces, and
    MuJoCo's softness."""
    c = traj.stats.get("constraints")
    if c is None:
        return []
    return ([f"constraints ({', '.join(c['rows'])}): solved with multipliers and projected after every step "
             f"(E72-E74, DOP853 + projection); max |Phi| {c['max_residual']:.2e} at the samples, "
             f"{c['max_step_drift']:.2e} before any projection; lambda {c['lambda'].min():.4g} .. "
             f"{c['lambda'].max():.4g}", c["initial"]["note"]] + list(c["initial"]["redundant"])
            + [f"MuJoCo's constraints are soft (solref {list(COMPARE_SOLREF)}, solimp {SOLIMP[0]:g}): how its run "
               "approaches the exact one as solref's time constant shrinks: python -m "
               "urdf2links.compare.agreement.constraint_agreement SCENE (reports/loops/)"])


def _states(traj, k=4):
    idx = np.linspace(0, len(traj.t) - 1, k + 2).astype(int)[1:-1]
    return [(traj.q[i], traj.qd[i]) for i in idx]


def constraint_report(scene, out_dir, *, t_end=None, samples=201) -> dict:
    """The project's run, the terms at identical states and the solref study of ``scene``, written to
    ``out_dir`` (``constraints.json``, ``constraints.md``, ``solref.png``). Returns the summary."""
    plan = as_plan(scene)
    traj = simulate(plan, progress=False, t_end=t_end, samples=samples)
    c = traj.stats["constraints"]
    mj = with_constraints(mjcf_from_scene(plan.scene, plan.model), plan.constraints, solref=(1e-3, 1.0))
    terms = constraint_terms(plan, mj, _states(traj))
    study = solref_study(plan, traj)
    study2 = solref_study(plan, traj, route=2) if plan.scene.file_constraints else None
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    summary = {"scene": plan.scene.name, "robot": plan.model.name, "t_end": float(traj.t[-1]),
               "constraints": [r for r in c["rows"]], "solved_rows": c["solved_rows"],
               "redundant": c["initial"]["redundant"], "initial_projection": c["initial"]["note"],
               "max_residual": c["max_residual"], "max_step_drift": c["max_step_drift"],
               "max_rate_residual": float(c["rate_residual"].max()), "energy_error": traj.energy_error,
               "lambda_range": [float(c["lambda"].min()), float(c["lambda"].max())], "nsteps": traj.stats["nsteps"],
               "wall_s": traj.stats["wall_time"], "terms": terms,
               "solref": {**{k: v for k, v in study.items() if k != "t"},
                          "runs": [{k: v for k, v in r.items() if k != "error_t"} for r in study["runs"]]}}
    if study2 is not None:
        summary["solref_route2"] = {**{k: v for k, v in study2.items() if k != "t"},
                                    "runs": [{k: v for k, v in r.items() if k != "error_t"} for r in study2["runs"]]}
    (out / "constraints.json").write_text(json.dumps(json_ready(summary), indent=1))
    _figure(study, out / "solref.png", plan.scene.name)
    (out / "constraints.md").write_text(_markdown(summary))
    return summary


def _figure(study, path, name):
    fig = figure(6.4, 3.6)
    ax = fig.add_subplot(111)
    for r in study["runs"]:
        ax.semilogy(study["t"], np.maximum(r["error_t"], 1e-16), label=f"solref tau = {r['tau']:g} s")
    ax.set_xlabel("t (s)")
    ax.set_ylabel("max |q_MuJoCo - q| (rad, m)")
    ax.set_title(f"{name}: MuJoCo's soft constraints approaching the exact ones")
    ax.legend(fontsize=8)
    save_png(fig, path)


def _markdown(s) -> str:
    st, tm = s["solref"], s["terms"]
    lines = [f"# {s['scene']} ({s['robot']}): constraints against MuJoCo", "",
             f"Rows: {', '.join(s['constraints'])}; solved: {', '.join(s['solved_rows'])}.", ""]
    lines += [f"- {n}" for n in s["redundant"]] + [f"- {s['initial_projection']}", ""]
    lines += ["| figure | value | bound |", "|---|---|---|",
              f"| max residual max|Phi| over the run (samples) | {s['max_residual']:.2e} | 1e-9 |",
              f"| max residual of a step before its projection | {s['max_step_drift']:.2e} | 1e-9 |",
              f"| max |Phi'| | {s['max_rate_residual']:.2e} | |",
              f"| energy error (relative) | {s['energy_error']:.2e} | 1e-9 (no damping) |",
              f"| multipliers lambda | {s['lambda_range'][0]:.4g} .. {s['lambda_range'][1]:.4g} | |",
              f"| Phi_q - efc_J (max abs; scale) | {tm['jacobian']['max_abs']:.2e} ({tm['jacobian']['scale']:.3g}) | |",
              f"| lambda - efc_force (max abs; scale) | {tm['force']['max_abs']:.2e} ({tm['force']['scale']:.3g}) | |",
              f"| J^T lambda - qfrc_constraint (max abs; scale) | {tm['generalized_force']['max_abs']:.2e} "
              f"({tm['generalized_force']['scale']:.3g}) | |", "",
              f"MuJoCo (route 1: the constraints written as equalities, site semantic), RK4 at {st['timestep']:g} s, "
              f"solimp {st['solimp'][0]:g}, dampratio 1, from the project's projected initial state:", "",
              "| solref tau (s) | max |q_MuJoCo - q| | ratio to the next | rate per decade |", "|---|---|---|---|"]
    lines += _study_rows(st)
    if "solref_route2" in s:
        lines += ["", "MuJoCo running the MJCF file itself (route 2), its equalities and tendons on, the same solref:", "",
                  "| solref tau (s) | max |q_MuJoCo - q| | ratio to the next | rate per decade |", "|---|---|---|---|"]
        lines += _study_rows(s["solref_route2"])
    lines += ["", tm["note"] + ".", ""]
    return "\n".join(lines)


def _study_rows(st) -> list[str]:
    lines = []
    for k, r in enumerate(st["runs"]):
        ratio = f"{st['ratios'][k]:.3g}x" if k < len(st["ratios"]) else ""
        rate = f"{st['rates'][k]:.2f}" if k < len(st["rates"]) else ""
        lines.append(f"| {r['tau']:g} | {r['max_error']:.3e} | {ratio} | {rate} |")
    return lines + ["", "The issue asks at least 5x per 10x smaller tau (a rate of 0.7): "
                    + ("holds." if st["holds"] else "does NOT hold.")]


def main(argv=None):
    """``python -m urdf2links.compare.agreement.constraint_agreement SCENE... --out DIR``."""
    import argparse

    from urdf2links.locations import find_input

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scenes", nargs="+")
    ap.add_argument("--out", default="reports/loops")
    ap.add_argument("--t-end", type=float, default=None)
    a = ap.parse_args(argv)
    for s in a.scenes:
        path, _ = find_input(s, kinds=("scene",))
        summary = constraint_report(path, Path(a.out) / path.stem, t_end=a.t_end)
        print(f"{path.stem}: residual {summary['max_residual']:.2e}, energy {summary['energy_error']:.2e}, "
              f"solref ratios {[round(r, 1) for r in summary['solref']['ratios']]}")


if __name__ == "__main__":
    main()

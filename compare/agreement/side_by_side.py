"""The two runs side by side: the project's at MuJoCo's sample times, both engines' energy balances, and what the
report says about the runs besides figures.

:func:`project_at` samples the project's trajectory at MuJoCo's times (its dense output when they differ);
:func:`energy_balances` gives both engines' ``h - h(0) - W`` (docs/equations.md: the power balance; MuJoCo's without
``W`` when no work acts) and the energy scale the relative drifts are measured against; :func:`run_notes` the
notes of the runs (the cap on ``t_end``, resampling, re-charting, the scene's notes, limit excursions, the MJCF's
and MuJoCo run's notes). All three are steps of :func:`urdf2links.compare.agreement.trajectory.compare_scene`.
"""

from __future__ import annotations

import numpy as np

from urdf2links.console import shown_path
from urdf2links.integration.simulate import describe_stretches
from urdf2links.scenes.limits import LimitExcursion

from ..mujoco_side.contact_inputs import contact_energy
from ..mujoco_side.mujoco_run import energy_function

__all__ = ["project_at", "energy_balances", "run_notes", "ENERGY_ROUNDING_EPS"]

#: The energy scale of the relative drifts is at least this many eps times max|E + V| (the rounding level).
ENERGY_ROUNDING_EPS = 1000.0


def project_at(traj, plan, t, T):
    """The project's ``q``, ``qd``, work ``W``, ``E + V`` and ``h`` at MuJoCo's sample times ``t``: its
    own samples when the times agree, else its dense output (then the last value is True)."""
    n = plan.n
    if traj.t.shape == t.shape and np.max(np.abs(traj.t - t)) <= 1e-12 * max(1.0, T):
        EV = traj.energy["kinetic"] + traj.energy["potential"]
        return traj.q, traj.qd, traj.energy["work"], EV, traj.energy["function"], False
    if traj.sol is None:        # issue 45: a constrained run (its samples only): cubic Hermite on (q, q')
        q, qd, W = _hermite(traj, np.clip(t, traj.t[0], traj.t[-1]), n)
        E, V, h = plan.energies(t, q, qd)
        return q, qd, W, E + V, h, True
    Y = traj.sol(np.clip(t, traj.t[0], traj.t[-1]))
    q, qd, W = Y[:, :n], Y[:, n:2 * n], Y[:, 2 * n]
    E, V, h = plan.energies(t, q, qd)
    return q, qd, W, E + V, h, True



def _hermite(traj, t, n):
    """A run without dense output (the constrained path's samples) at times ``t``: ``q`` by the cubic Hermite
    polynomial of its samples' ``(q, q')`` (error O(h^4)), ``q'`` and ``W`` linearly between samples."""
    ts = np.asarray(traj.t, float)
    k = np.clip(np.searchsorted(ts, t, side="right") - 1, 0, len(ts) - 2)
    h = ts[k + 1] - ts[k]
    s = ((t - ts[k]) / h)[:, None]
    q0, q1, v0, v1 = traj.q[k], traj.q[k + 1], traj.qd[k] * h[:, None], traj.qd[k + 1] * h[:, None]
    q = ((2 * s**3 - 3 * s**2 + 1) * q0 + (s**3 - 2 * s**2 + s) * v0 + (-2 * s**3 + 3 * s**2) * q1
         + (s**3 - s**2) * v1)
    qd = (1 - s) * traj.qd[k] + s * traj.qd[k + 1]
    w = np.asarray(traj.energy["work"], float)
    W = (1 - s[:, 0]) * w[k] + s[:, 0] * w[k + 1]
    return q, qd, W


def energy_balances(scene, plan, mj, run, traj, EV_o, h_o, W) -> tuple[dict, dict]:
    """Both engines' balances ``h - h(0) - W`` (MuJoCo's without ``W`` when no work acts), the
    energy arrays for the report, and what the summary says about them."""
    tendon_work = any(td.damping or td.actuators for td in (plan.constraints.tendons if plan.constraints else ()))
    work_terms = tendon_work or any(term in plan.terms for term in ("Q", "tau", "damper", "base", "gravcomp", "actuator",
                                                                    "computed_torque", "contact"))
    # issue 37: the contact's elastic energy (E81) at MuJoCo's states, which MuJoCo's own energy does not count
    V_c = contact_energy(plan, run.t, run.q) if "contact" in plan.terms else 0.0
    EV_m = run.total_energy + V_c
    if scene.base is not None:
        h_m = energy_function(mj, run, plan) + V_c
        quantity, sym = "h = E2 - E0 + V (energy function; moving base)", "h"
    else:
        h_m = EV_m
        quantity, sym = "E + V", "(E + V)"
    bal_o = h_o - h_o[0] - W
    if work_terms:
        bal_m = h_m - h_m[0] - W
        what = [w for w, on in (("contact", "contact" in plan.terms), ("forces/moments", "Q" in plan.terms), ("joint torques", "tau" in plan.terms),
                                ("dampers", "damper" in plan.terms), ("the moving base", "base" in plan.terms),
                                ("gravcomp", "gravcomp" in plan.terms), ("actuators", "actuator" in plan.terms),
                                ("the computed torque", "computed_torque" in plan.terms),
                                ("tendons' dampers and actuators", tendon_work)) if on]     # issue 43
        note = (f"work terms present ({', '.join(what)}): both drifts use the project's work W "
                f"(integrated along the project's trajectory): max |{sym} - {sym}(0) - W|")
        if scene.base is not None:
            note += "; MuJoCo's h from its own kinetic energies at qd, -qd and 0 at its states and the prescribed base"
    else:
        bal_m = h_m - h_m[0]
        note = "no work terms: MuJoCo's drift is max |(E + V) - (E + V)(0)| of its own energies"
    motion = max(float(np.abs(traj.energy["kinetic"]).max()),
                 float(np.abs(traj.energy["potential"] - traj.energy["potential"][0]).max()),
                 float(np.abs(traj.energy["work"]).max()))
    # E + V is a sum of terms of size |V|: its rounding error is a few eps |V|, whatever the motion. A robot
    # that barely moves has a motion energy below that, and a drift measured against it would read as an
    # error when it is rounding; the scale is never below 1000 eps max|E + V|.
    floor = ENERGY_ROUNDING_EPS * float(np.finfo(float).eps) * max(float(np.abs(EV_o).max()), float(np.abs(EV_m).max()))
    scale = max(motion, floor, 1e-300)
    scale_note = (f"relative to the motion's energy {motion:.3g} J (max of E, |V - V(0)|, |W|)" if motion >= floor else
                  f"relative to the rounding level of E + V, {floor:.3g} J ({ENERGY_ROUNDING_EPS:g} eps max|E + V|): "
                  f"the motion's energy, {motion:.3g} J, is below it (the robot barely moves)")
    energy = {"ours_EV": EV_o, "mujoco_EV": EV_m, "ours_h": h_o, "mujoco_h": h_m, "ours_balance": bal_o,
              "mujoco_balance": bal_m, "work": W}
    return energy, {"energy_scale": scale, "energy_quantity": quantity, "energy_note": note, "work_terms": work_terms,
                    "energy_scale_note": scale_note}


def run_notes(scene, plan, mj, run, traj, t_end_note, *, resampled: bool) -> list[str]:
    """What the report says about the two runs besides figures: the cap on t_end, the default scene,
    resampling, re-charting, spring notes, limit excursions, the MJCF's and MuJoCo run's notes."""
    notes = []
    if t_end_note:
        notes.append(t_end_note)
    if scene.path is None:
        notes.append(f"no scene file: the robot's default scene ({scene.description}); `urdf2links inspect "
                     f"{shown_path(scene.robot)} --scene` shows it, --write-scene FILE.toml writes it")
    if resampled:
        notes.append("MuJoCo's sample times differ from the project's: the project's dense output was "
                     "evaluated at MuJoCo's times")
    if traj.stats.get("stretches") and len(traj.stats["stretches"]) > 1:
        notes.append(f"urdf2links' auto method ran {traj.stats['methods_used']}: "
                     + "; ".join(describe_stretches(traj.stats["stretches"])))
    if traj.stats.get("n_recharts"):
        notes.append(f"the project re-charted the ZYX angles of {sorted({r['link'] for r in traj.stats['recharts']})} "
                     f"{traj.stats['n_recharts']} times near phi_y = +-pi/2 (urdf2links.integration.charts); its q are converted "
                     "back to the loaded model's coordinates, which MuJoCo integrates as hinges through the singularity")
    # issue 43: the scene's own notes too (--ground's feet and loads, loading options given)
    notes += [f"scene: {x}" for x in (*plan.spring_set.notes, *plan.actuator_set.notes, *plan.scene.notes)]
    clamps = [a.name for a in plan.actuator_set.actuators if a.ctrlrange is not None or a.forcerange is not None]
    if clamps:
        notes.append(f"the clamps of {', '.join(clamps[:6])} (ctrlrange, forcerange) make the right-hand side non-smooth "
                     "where they engage: both integrators lose order across those instants (the project's error estimate "
                     "too); the difference shrinks with MuJoCo's step and the project's rtol")
    if plan.reference_funcs:
        notes.append("computed torque: MuJoCo's side applies the project's own torque (the scene's inverse dynamics at "
                     "the reference, E57) through qfrc_applied at every stage, evaluated by the compiled control callback; "
                     "MuJoCo's mj_inverse is compared with the project's inverse dynamics in the tests (1e-10)")
    notes += [f"limits: {LimitExcursion(**x).text()} (urdf2links' trajectory)" for x in traj.stats["limit_excursions"]]
    return notes + [f"MJCF: {x}" for x in mj.notes] + [f"MuJoCo run: {x}" for x in run.notes]

"""MuJoCo on stiff models: when the asked integrator blows up, a setting that stays stable, and the
evidence that its trajectory has converged.

MuJoCo's RK4 is explicit: on a stiff model (large joint damping on light links, stiff springs,
high-gain servos) its step must be below ~2.8 / |lambda|, and past that it meets NaN or huge values and
resets its state (``BADQACC``: :func:`~urdf2links.compare.mujoco_side.mujoco_run.instability_note`).
Its ``implicitfast`` and ``implicit`` integrators treat the velocity-dependent forces (damping, and a
servo's velocity gain) implicitly and stay stable there. :func:`stable_run` runs the asked setting and,
after a blow-up, tries in turn :data:`FALLBACKS` at the same timestep and then at timesteps 10x and
100x smaller, keeping the first run without a blow-up; that run is then repeated at half its timestep,
and the largest coordinate difference between the two (``convergence``) says how far the chosen run is
from the converged trajectory: the three integrators are of order 1 to 4, so the error of the chosen
run is at most about twice that difference (``2 d`` for order 1: ``e(h) = C h``, ``e(h) - e(h/2) =
C h / 2``). The record says what was asked, what blew up, what was chosen and the convergence figure.
"""

from __future__ import annotations

import numpy as np

from .mujoco_run import MujocoRun, instability_note, run_mujoco

__all__ = ["stable_run", "FALLBACKS", "fallback_note"]

#: The integrators tried after a blow-up, in order, at the asked timestep and then 10x and 100x smaller.
FALLBACKS = ("implicitfast", "implicit")
#: The timestep factors tried with each fallback integrator.
STEP_FACTORS = (1.0, 0.1, 0.01)


def _blew_up(run: MujocoRun) -> bool:
    return bool(run.blow_ups) or not (np.all(np.isfinite(run.q)) and np.all(np.isfinite(run.qd)))


def stable_run(mj, plan, *, t_end: float, samples: int, integrator: str, timestep: float,
               fallback: bool = True) -> tuple[MujocoRun, dict | None]:
    """MuJoCo's run of ``plan`` with ``integrator`` at ``timestep``; with ``fallback`` and a blow-up,
    the first stable setting of :data:`FALLBACKS` x :data:`STEP_FACTORS` instead (module doc).
    Returns ``(run, record)``: the run the comparison uses, and None when the asked one was kept, else
    the record (``asked``, ``blow_ups``, ``tried``, ``chosen``, ``convergence``, ``note``)."""
    run = run_mujoco(mj, plan, t_end=t_end, timestep=timestep, integrator=integrator, samples=samples)
    if not fallback or not _blew_up(run):
        return run, None
    asked = {"integrator": run.integrator, "timestep": float(run.timestep), "blow_ups": dict(run.blow_ups)}
    tried, chosen = [], None
    for factor in STEP_FACTORS:
        for integ in FALLBACKS:
            dt = float(timestep) * factor
            if dt * samples < 1e-12 or t_end / dt > 1e7:       # not a usable step for this run
                continue
            cand = run_mujoco(mj, plan, t_end=t_end, timestep=dt, integrator=integ, samples=samples)
            tried.append({"integrator": integ, "timestep": dt, "blow_ups": dict(cand.blow_ups),
                          "stable": not _blew_up(cand)})
            if not _blew_up(cand):
                chosen = cand
                break
        if chosen is not None:
            break
    record = {"asked": asked, "tried": tried, "chosen": None, "convergence": None}
    if chosen is None:
        record["note"] = (instability_note(run.blow_ups, run.integrator, run.timestep)
                          + f"; none of {', '.join(FALLBACKS)} at {', '.join(f'{f:g}' for f in STEP_FACTORS)} x "
                            "the timestep stayed stable either: the comparison shows the asked run")
        return run, record
    half = run_mujoco(mj, plan, t_end=t_end, timestep=chosen.timestep / 2, integrator=chosen.integrator,
                      samples=samples)
    diff = float(np.max(np.abs(half.q - chosen.q))) if chosen.q.size and not _blew_up(half) else float("nan")
    record["chosen"] = {"integrator": chosen.integrator, "timestep": float(chosen.timestep)}
    record["convergence"] = {"timestep": float(half.timestep), "max_abs_difference": diff,
                             "blow_ups": dict(half.blow_ups)}
    record["note"] = fallback_note(record)
    chosen.notes.insert(0, record["note"])
    return chosen, record


def fallback_note(record: dict) -> str:
    """The sentence the report and the corpus row show for a fallback ``record``."""
    a, c, v = record["asked"], record["chosen"], record["convergence"]
    blown = ", ".join(f"{w} x{k}" for w, k in a["blow_ups"].items()) or "non-finite state"
    if c is None:
        return record.get("note", "")
    return (f"MuJoCo {a['integrator']} at dt {a['timestep']:g} s blew up ({blown}): compared with MuJoCo "
            f"{c['integrator']} at dt {c['timestep']:g} s, which stays stable (it treats damping implicitly); "
            f"converged: at dt {v['timestep']:g} s it differs by {v['max_abs_difference']:.2g} (rad or m) at most, so "
            f"its own error is about twice that")

"""MuJoCo on stiff models: when the asked integrator blows up, a setting that stays stable, and the
evidence that its trajectory has converged.

MuJoCo's RK4 is explicit: on a stiff model (large joint damping on light links, stiff springs,
high-gain servos) its step must be below ~2.8 / |lambda|, and past that it meets NaN or huge values and
resets its state (``BADQACC``: :func:`~urdf2links.compare.mujoco_side.mujoco_stepping.instability_note`).
Its ``implicitfast`` and ``implicit`` integrators treat the velocity-dependent forces (damping, and a
servo's velocity gain) implicitly and stay stable there; a stiff spring is still explicit in them.
:func:`stable_run` runs the asked setting and, after a blow-up, tries in turn :data:`FALLBACKS` at the
same timestep, then, with the asked integrator too, at timesteps 10x and 100x smaller
(:data:`STEP_FACTORS`). A candidate that stays stable is run again at half its timestep: the largest
coordinate difference of the two says how far it is from the converged trajectory (of order ``p``:
``e(h) = C h^p``, ``e(h) - e(h/2) = (1 - 2^-p) e(h)``, so its own error is at most about twice that
difference, for the first-order implicit integrators). The first candidate whose
difference is below :data:`CONVERGED` is chosen; when none is, the stable one closest to
convergence, and the record says it did not converge. Stable is not enough: on the stiff spring
arm, ``implicitfast`` at 10 ms runs without a blow-up yet differs by 38 rad from its run at 5 ms.
"""

from __future__ import annotations

import numpy as np

from .mujoco_run import MujocoRun, run_mujoco
from .mujoco_stepping import instability_note

__all__ = ["stable_run", "FALLBACKS", "STEP_FACTORS", "CONVERGED", "fallback_note"]

#: The integrators tried after a blow-up, in order, at the asked timestep and then 10x and 100x smaller.
FALLBACKS = ("implicitfast", "implicit")
#: The timestep factors tried with each fallback integrator.
STEP_FACTORS = (1.0, 0.1, 0.01)
#: A candidate has converged when its run and the run at half its timestep differ by less than this (rad
#: or m): a tenth of the comparison's divergence threshold (1e-3), its own error about twice that.
CONVERGED = 1e-4
#: Candidates whose run would take more steps than this are not tried.
MAX_STEPS = 2_000_000


def _blew_up(run: MujocoRun) -> bool:
    return bool(run.blow_ups) or not (np.all(np.isfinite(run.q)) and np.all(np.isfinite(run.qd)))


def _candidate(run_at, integ, dt) -> tuple[MujocoRun | None, dict]:
    """One fallback setting: its run (None when it blew up) and what was seen, with the difference to
    the run at half its timestep when it stayed stable."""
    run = run_at(integ, dt)
    seen = {"integrator": integ, "timestep": dt, "blow_ups": dict(run.blow_ups), "stable": not _blew_up(run)}
    if not seen["stable"]:
        return None, seen
    half = run_at(integ, dt / 2)
    seen["half_timestep"] = dt / 2
    seen["max_abs_difference"] = float(np.max(np.abs(half.q - run.q))) if run.q.size and not _blew_up(half) else np.inf
    return run, seen


def stable_run(mj, plan, *, t_end: float, samples: int, integrator: str, timestep: float,
               fallback: bool = True, runner=None) -> tuple[MujocoRun, dict | None]:
    """MuJoCo's run of ``plan`` with ``integrator`` at ``timestep``; with ``fallback`` and a blow-up,
    the first converged stable setting of :data:`FALLBACKS` x :data:`STEP_FACTORS` instead (module
    doc). Returns ``(run, record)``: the run the comparison uses, and None when the asked one was kept,
    else the record (``asked``, ``tried``, ``chosen``, ``convergence``, ``converged``, ``note``).
    ``runner(integrator, timestep) -> MujocoRun`` runs another MuJoCo model the same way (the MJCF
    file's route: :func:`~urdf2links.compare.mujoco_side.mujoco_mjcf.file_runner`); by default the
    route-1 model ``mj`` runs ``plan`` (:func:`~urdf2links.compare.mujoco_side.mujoco_run.run_mujoco`)."""
    run_at = runner or (lambda integ, dt: run_mujoco(mj, plan, t_end=t_end, timestep=dt, integrator=integ,
                                                     samples=samples))
    run = run_at(integrator, timestep)
    if not fallback or not _blew_up(run):
        return run, None
    asked = {"integrator": run.integrator, "timestep": float(run.timestep), "blow_ups": dict(run.blow_ups)}
    tried, best, best_seen = [], None, None
    for factor in STEP_FACTORS:
        for integ in FALLBACKS + ((run.integrator,) if factor < 1.0 and run.integrator not in FALLBACKS else ()):
            dt = float(timestep) * factor
            if t_end / dt > MAX_STEPS:
                continue
            cand, seen = _candidate(run_at, integ, dt)
            tried.append(seen)
            if cand is not None and (best_seen is None or seen["max_abs_difference"] < best_seen["max_abs_difference"]):
                best, best_seen = cand, seen
            if cand is not None and seen["max_abs_difference"] < CONVERGED:
                break
        if best_seen is not None and best_seen["max_abs_difference"] < CONVERGED:
            break
    record = {"asked": asked, "tried": tried, "chosen": None, "convergence": None, "converged": False}
    if best is None:
        record["note"] = (instability_note(run.blow_ups, run.integrator, run.timestep)
                          + f"; none of {', '.join(FALLBACKS)} at {', '.join(f'{f:g}' for f in STEP_FACTORS)} x "
                            "the timestep stayed stable either: the comparison shows the asked run")
        return run, record
    record["chosen"] = {"integrator": best_seen["integrator"], "timestep": best_seen["timestep"]}
    record["convergence"] = {"timestep": best_seen["half_timestep"],
                             "max_abs_difference": best_seen["max_abs_difference"]}
    record["converged"] = bool(best_seen["max_abs_difference"] < CONVERGED)
    record["note"] = fallback_note(record)
    best.notes.insert(0, record["note"])
    return best, record


def fallback_note(record: dict) -> str:
    """The sentence the report and the corpus row show for a fallback ``record``."""
    a, c, v = record["asked"], record["chosen"], record["convergence"]
    if c is None:
        return record.get("note", "")
    blown = ", ".join(f"{w} x{k}" for w, k in a["blow_ups"].items()) or "non-finite state"
    head = (f"MuJoCo {a['integrator']} at dt {a['timestep']:g} s blew up ({blown}): compared with MuJoCo "
            f"{c['integrator']} at dt {c['timestep']:g} s, which stays stable"
            + (" (it treats damping implicitly); " if c["integrator"] in FALLBACKS else " (a smaller step); "))
    if record.get("converged"):
        return head + (f"converged: at dt {v['timestep']:g} s it differs by {v['max_abs_difference']:.2g} (rad or m) at "
                       "most, so its own error is at most about twice that")
    return head + (f"NOT converged: at dt {v['timestep']:g} s it still differs by {v['max_abs_difference']:.2g} (rad or m) "
                   f"(more than {CONVERGED:g}); no smaller step tried converged either")

"""One scene run by both engines and compared: terms, trajectories, energies, base, wall time.

:func:`compare_scene` is the MuJoCo cross-validation of one scene:

1. **Terms at identical states.** At ``states`` seeded random states (``q`` uniform within the
   joints' limits, a [-1, 1] window (rad or m) where a joint has none, ``qd`` standard normal; with a moving base also a random base pose
   (uniform in [-1, 1]) and rate (standard normal), accelerations zero since ``qfrc_bias``
   holds none), ``A`` against ``mj_fullM`` and ``e + G`` (the scene's gravity) against
   ``qfrc_bias``, as ``max|ours - MuJoCo| / max|MuJoCo|`` (:mod:`urdf2links.compare.agreement.scene_terms`):

   * route 1: the project's own tree written as MJCF (:mod:`urdf2links.compare.mujoco_side.mjcf`), built for the scene
     (its gravity, springs, moving base);
   * route 2: MuJoCo's own URDF import of the robot's file (:func:`urdf2links.compare.agreement.terms.compare_terms_urdf`),
     only for a fixed-base robot. When MuJoCo refuses the file, its reason is recorded and the
     comparison is repeated with the project's repair (the repaired inertias written into the
     text; a 1 g sphere on each massless moving link on BOTH sides when MuJoCo refuses those),
     labelled as such.

2. **Trajectories.** The project's :func:`urdf2links.integration.simulate.simulate` and MuJoCo
   (:func:`urdf2links.compare.mujoco_side.mujoco_run.run_mujoco`, route 1, base motion prescribed, the scene's torques
   and loads) from the same initial state; ``|q_ours - q_MuJoCo|`` per coordinate at MuJoCo's
   sample times (the project's dense output when the times differ). For every scene the
   divergence time (first time the largest coordinate error exceeds ``threshold``, default
   :data:`DIVERGENCE_THRESHOLD`); for a chaotic scene (``scene.chaotic``) also a fitted
   exponential growth rate (:func:`growth_fit`), reported as chaos, not as failure.

3. **Energy.** ``E + V`` of both engines (MuJoCo's ``mjENBL_ENERGY``) against time, and the drift
   of each: ``max |h - h(0) - W|`` (``h = E + V`` for a fixed base, ``W`` the work of torques,
   forces, dampers and the base). With no work terms, MuJoCo's drift is ``max |(E + V) - (E +
   V)(0)|`` of its own numbers; with work terms the project's ``W`` (integrated along its own
   trajectory) is used for both, and ``notes`` says so. With a moving base ``h`` is the energy
   function ``E2 - E0 + V`` (the conserved quantity's generalization), for MuJoCo from its own
   kinetic energies at ``qd``, ``-qd`` and ``0`` (``h = (E(qd) + E(-qd)) / 2 - 2 E(0) + V``) at its
   states and the prescribed base.

4. **Base tracking** (moving base): how far MuJoCo's ``base_A`` is from the prescribed pose.

5. **Coverage and verdict**: what the run exercised (:func:`urdf2links.scenes.coverage.coverage` of the
   project's run: per coordinate the range traversed, the largest ``|q'|``, the swing of its share of the
   kinetic energy, E66; weak evidence when fewer than half of the coordinates moved, E67), and the
   verdict that states it, the model's scope (constraints and tendons dropped) and MuJoCo's fallback
   after a blow-up (:mod:`urdf2links.compare.agreement.verdict`).

6. **Wall time** of each engine, timed the same way (not checked against baselines): urdf2links'
   integrator (:data:`urdf2links.integration.simulate.TIMED_REGION`) after a warm-up that compiles, or loads
   from numba's cache, every compiled function the run calls (:func:`urdf2links.integration.simulate.warm_up`;
   its time is reported on its own); MuJoCo's ``mj_step(nstep)`` calls
   (:data:`urdf2links.compare.mujoco_side.mujoco_run.TIMED_REGION`), inputs from the compiled control callback.
   Both sample at the same times and neither timed region contains the copying or evaluation at
   the samples; the whole calls are reported beside them (``wall_time.regions`` says what each
   figure contains).

:meth:`SceneComparison.summary` is the JSON-ready dictionary; the report is written by
:mod:`urdf2links.compare.reports.report`.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import mujoco
import numpy as np

from urdf2links.compilation import clock  # durations without numba's compilation
from urdf2links.console import shown_path
from urdf2links.errors import IntegrationError
from urdf2links.integration.simulate import TIMED_REGION as PROJECT_REGION
from urdf2links.integration.simulate import Trajectory, simulate, warm_up
from urdf2links.parsers.robot_file import is_mjcf_path
from urdf2links.parsers.xacro_input import is_xacro_path
from urdf2links.ranges import MAX_STEPS
from urdf2links.scenes.actuators import describe_actuator
from urdf2links.scenes.coverage import Coverage, coverage
from urdf2links.scenes.plan import compile_plan
from urdf2links.scenes.scene import Scene, robot_label
from urdf2links.scenes.scene_read import load_scene

from ..mujoco_side.mjcf import mjcf_from_scene
from ..mujoco_side.mjcf_model import MjcfModel
from ..mujoco_side.mujoco_mjcf import FILE_LABEL, file_route_inputs, file_runner, file_terms, mujoco_from_mjcf
from ..mujoco_side.mujoco_constraints import with_constraints
from ..mujoco_side.tendon_controls import tendon_actuators
from .constraint_agreement import run_notes as constraint_run_notes
from ..mujoco_side.mujoco_run import TIMED_REGION as MUJOCO_REGION
from ..mujoco_side.contact_inputs import contact_timestep
from .contact_reference import contact_reference
from ..mujoco_side.mujoco_run import MujocoRun
from ..mujoco_side.stable_run import stable_run
from .actuator_terms import file_actuators, merged, route1_actuators, route2_actuators
from .scene_terms import ROUTE1_LABEL, route1_terms, route2_terms
from .side_by_side import energy_balances, project_at, run_notes
from .plausibility import file_floors, plausibility
from .verdict import comparison_verdict, cut_scope, switched_off

__all__ = [
    "SceneComparison",
    "compare_scene",
    "growth_fit",
    "divergence_time",
    "scene_key",
    "DIVERGENCE_THRESHOLD",
]

#: Error (rad or m, largest over the coordinates) whose first crossing is the divergence time.
DIVERGENCE_THRESHOLD = 1e-3


def scene_key(scene: Scene, model=None) -> str:
    """``"<robot>/<scene>"``: the robot's name (:func:`~urdf2links.scenes.scene.robot_label`: its own name,
    else the file's stem) and the scene's name (the baselines' key and the report's folder)."""
    return f"{robot_label(scene, model)}/{scene.name}"


# --------------------------------------------------------------------------- trajectory analysis


def divergence_time(t, err, threshold: float = DIVERGENCE_THRESHOLD) -> float | None:
    """First time at which ``err`` (m,) exceeds ``threshold``; None if it never does."""
    above = np.nonzero(np.asarray(err) > threshold)[0]
    return float(t[above[0]]) if above.size else None


def growth_fit(t, err, *, end_time: float | None = None, rise: float = 10.0, min_samples: int = 10) -> dict | None:
    """Exponential growth ``err ~ C exp(rate t)`` fitted by least squares to ``log`` of the error's
    running maximum (its envelope; a difference that oscillates through zero has no log) over
    the growth phase: from the first time the envelope exceeds ``rise`` times the noise level
    (the envelope over the first 5 % of the run, the integrators' own error) up to ``end_time``
    (the divergence time; else the end of the run). None when the error never rises out of the
    noise or the phase has fewer than ``min_samples`` samples. Returns ``rate`` (1/s),
    ``e_folding_time`` (s), ``log10_intercept``, ``window`` [t0, t1], ``samples``, ``decades``."""
    t = np.asarray(t, float)
    env = np.maximum.accumulate(np.abs(np.asarray(err, float)))
    if t.size < min_samples or not np.any(env > 0):
        return None
    k0 = max(3, int(0.05 * t.size))
    early = env[:k0]
    noise = float(early[early > 0].max()) if np.any(early > 0) else float(env[env > 0].min())
    start = np.nonzero(env > rise * noise)[0]
    if not start.size:
        return None
    i0 = int(start[0])
    i1 = t.size - 1 if end_time is None else int(np.searchsorted(t, end_time, side="right") - 1)
    if i1 - i0 + 1 < min_samples:
        return None
    tt, yy = t[i0:i1 + 1], np.log(env[i0:i1 + 1])
    rate, intercept = np.polyfit(tt, yy, 1)
    return {"rate": float(rate), "e_folding_time": float(1.0 / rate) if rate > 0 else None,
            "log10_intercept": float(intercept / np.log(10.0)), "window": [float(tt[0]), float(tt[-1])],
            "samples": int(tt.size), "decades": float((yy[-1] - yy[0]) / np.log(10.0))}


# --------------------------------------------------------------------------- the comparison


@dataclass(eq=False)
class SceneComparison:
    """Everything :func:`compare_scene` measured, with the arrays the report plots.

    ``t`` (m,) MuJoCo's sample times; ``q_ours``/``q_mujoco`` (m, n) there; ``error`` (m, n)
    ``|q_ours - q_mujoco|``; ``energy``: dict of (m,) arrays ``ours_EV``, ``mujoco_EV``
    (kinetic + potential), ``ours_balance``, ``mujoco_balance`` (``h - h(0) - W``), ``work``;
    ``terms``: ``{"route1": ..., "route2": ...}``; ``growth``: :func:`growth_fit` or None;
    ``info``: settings and notes. :meth:`summary` is the JSON contract.
    """

    scene: Scene
    model: object
    mj: MjcfModel
    traj: Trajectory
    run: MujocoRun
    t: np.ndarray
    q_ours: np.ndarray
    q_mujoco: np.ndarray
    error: np.ndarray
    energy: dict
    terms: dict
    growth: dict | None
    threshold: float
    info: dict = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)
    contact: dict | None = None
    """Issue 37: a ``[[contact]]`` scene's ground and MuJoCo's native contact beside it
    (:func:`urdf2links.compare.agreement.contact_reference.contact_reference`), else None."""

    @property
    def key(self) -> str:
        return scene_key(self.scene, self.model)

    def summary_route(self) -> str:
        """Which of MuJoCo's models ran the trajectory: ``"route 1"`` (the project's tree as MJCF) or
        ``"route 2"`` (an MJCF file itself)."""
        return "route 2" if self.info.get("trajectory_route") == FILE_LABEL else "route 1"

    @property
    def coordinate_names(self) -> tuple[str, ...]:
        return tuple(self.model.coordinate_names)

    def _trajectory_summary(self) -> dict:
        sc = self.scene
        err_max = self.error.max(axis=1) if self.error.size else np.zeros(len(self.t))
        div = divergence_time(self.t, err_max, self.threshold)
        by_coord = {c: float(v) for c, v in zip(self.coordinate_names, self.error.max(axis=0))} if self.error.size else {}
        trajectory = {
            "max_abs_error": float(err_max.max()) if err_max.size else 0.0,
            "max_abs_error_by_coordinate": by_coord,
            "final_abs_error": float(err_max[-1]) if err_max.size else 0.0,
            "divergence_time": div,
            "divergence_threshold": self.threshold,
            "chaotic": bool(sc.chaotic),
            "growth_rate": None if self.growth is None else self.growth["rate"],
            "growth": self.growth,
            "units": "rad for angles, m for translations",
        }
        if sc.chaotic:
            g = self.growth
            trajectory["verdict"] = (
                "chaotic scene: the engines' difference grows exponentially"
                + (f" (rate {g['rate']:.3g} /s, e-folding {g['e_folding_time']:.3g} s, fitted over "
                   f"t = {g['window'][0]:.3g}..{g['window'][1]:.3g} s)" if g and g.get("e_folding_time") else "")
                + (f"; they diverge (error > {self.threshold:g}) at t = {div:.4g} s" if div is not None else
                   f"; no divergence (error > {self.threshold:g}) within the run")
                + ". This is chaos, not a failure.")
        else:
            trajectory["verdict"] = (f"the engines agree to {trajectory['max_abs_error']:.2e} over the run"
                                     if div is None else
                                     f"the engines DIVERGE at t = {div:.4g} s (error > {self.threshold:g}) in a "
                                     "scene that is not marked chaotic")
        return trajectory

    @property
    def coverage(self) -> Coverage:
        """What the run exercised (:func:`urdf2links.scenes.coverage.coverage` of the project's run)."""
        return self.info["coverage"]

    def verdict(self, trajectory: dict | None = None) -> dict:
        """The verdict (:func:`~urdf2links.compare.agreement.verdict.comparison_verdict`): the trajectories'
        agreement with the model's scope, MuJoCo's fallback and the weak-evidence mark stated in it."""
        trajectory = trajectory or self._trajectory_summary()
        return comparison_verdict(trajectory["verdict"], scope=self.info["scope"], coverage=self.coverage,
                                  mujoco_integrator=self.run.integrator, mujoco_timestep=float(self.run.timestep),
                                  blow_ups=dict(self.run.blow_ups), fallback=self.info.get("mujoco_fallback"),
                                  off=self.info.get("switched_off", ()), plausibility=self.info.get("plausibility"))

    def _energy_summary(self) -> dict:
        e = self.energy
        return {
            "project_drift": float(np.max(np.abs(e["ours_balance"]))),
            "mujoco_drift": float(np.max(np.abs(e["mujoco_balance"]))),
            "scale": float(self.info["energy_scale"]),
            "scale_note": self.info["energy_scale_note"],
            "project_drift_rel": float(np.max(np.abs(e["ours_balance"])) / self.info["energy_scale"]),
            "mujoco_drift_rel": float(np.max(np.abs(e["mujoco_balance"])) / self.info["energy_scale"]),
            "max_engine_difference": float(np.max(np.abs(e["ours_EV"] - e["mujoco_EV"]))),
            "quantity": self.info["energy_quantity"],
            "work_terms": bool(self.info["work_terms"]),
            "units": "J",
            "note": self.info["energy_note"],
        }

    def _wall_time_summary(self) -> dict:
        traj, run, warm = self.traj, self.run, self.info["warm_up"]
        r1, r2 = self.terms["route1"], self.terms["route2"]
        return {
            "project_s": float(traj.stats["wall_time"]), "mujoco_s": float(run.wall_time),
            "project_run_s": float(traj.stats["run_s"]), "mujoco_harness_s": float(run.harness_time),
            "project_warmup_s": float(warm.seconds), "project_compiled": list(warm.functions),
            "mujoco_inputs": run.inputs, "mujoco_callback_calls": int(run.callback_calls),
            "mujoco_callback_load_s": float(run.compilation.seconds),
            "mujoco_callback_compiled": list(run.compilation.functions),
            "terms_s": float(r1.get("wall_time_s", 0.0) + r2.get("wall_time_s", 0.0)),
            "total_s": float(self.info["total_s"]),
            "regions": {
                "project_s": PROJECT_REGION,
                "mujoco_s": MUJOCO_REGION,
                "project_run_s": "the whole simulate() call: plan, integration, samples, energies, poses",
                "mujoco_harness_s": "the whole run_mujoco() call: model copy, control callback set-up (and its "
                                    "loading or compilation), stepping, sample copies, the energy pass",
                "project_warmup_s": "the warm-up run before the timed one: numba's compilation of the functions "
                                    "in project_compiled (none: loaded from numba's disk cache)",
                "mujoco_callback_load_s": "loading (or compiling: mujoco_callback_compiled) the compiled control "
                                          "callback, once per process, inside mujoco_harness_s",
            },
            "note": "each engine's integration timed the same way (compilation and sampling outside the timed "
                    "regions; the same sample times); not checked against baselines",
        }

    def summary(self) -> dict:
        """The JSON-ready summary. Contract keys (nested): ``terms.max_rel_error``,
        ``trajectory.max_abs_error``, ``trajectory.divergence_time`` (None if none),
        ``energy.project_drift``, ``energy.mujoco_drift``, ``wall_time.project_s``,
        ``wall_time.mujoco_s``, ``mujoco.integrator``, ``mujoco.timestep``, ``route``."""
        sc, run, traj = self.scene, self.run, self.traj
        r1, r2 = self.terms["route1"], self.terms["route2"]
        term_max = max([r["max_rel_error"] for r in (r1, r2) if "max_rel_error" in r])
        trajectory, energy = self._trajectory_summary(), self._energy_summary()
        verdict = self.verdict(trajectory)
        trajectory["verdict"] = verdict["text"]
        moving = self.mj.moving_base
        return {
            "schema": 1,
            "key": self.key,
            "robot": robot_label(sc, self.model),
            "robot_name": self.model.name,
            "scene": sc.name,
            "scene_file": shown_path(sc.path) or f"(none: the default scene of {shown_path(sc.robot)})",
            "description": sc.description,
            "chaotic": bool(sc.chaotic),
            "effects": list(self.info["effects"]),
            "actuators": [{"name": a.name, "coordinate": a.coordinate, "source": a.source, "law": describe_actuator(a)}
                          for a in self.info.get("actuators", ())],
            "coordinates": list(self.coordinate_names),
            "route": ("route 2 (MuJoCo runs the MJCF file)" if self.info.get("trajectory_route") == FILE_LABEL
                      else "route 1 (the project's tree as MJCF)"),
            "route_description": self.info.get("trajectory_route", ROUTE1_LABEL)
                                 + ("; base motion prescribed" if moving else ""),
            "t_end": float(self.info["t_end"]),
            "t_end_scene": float(sc.run.t_end),
            "t_end_note": self.info.get("t_end_note"),
            "samples": int(len(self.t)),
            "initial": {"q": self.info["q0"], "qd": self.info["qd0"]},
            "project": {"method": traj.stats["method"], "rtol": traj.stats["rtol"], "atol": traj.stats["atol"],
                        "dt": traj.stats["dt"], "nsteps": int(traj.stats["nsteps"]), "nfev": int(traj.stats["nfev"]),
                        "njev": int(traj.stats.get("njev", 0)), "methods_used": traj.stats.get("methods_used"),
                        "stretches": list(traj.stats.get("stretches", [])), "terms": list(traj.stats["terms"])},
            "mujoco": {"integrator": run.integrator, "timestep": float(run.timestep), "nsteps": int(run.nsteps),
                       "blow_ups": dict(run.blow_ups), "fallback": self.info.get("mujoco_fallback"),
                       "version": mujoco.__version__, "folded_links": list(self.mj.folded_links),
                       "tiny_mass_links": list(self.mj.tiny_mass_links), "notes": list(run.notes)},
            "terms": {"max_rel_error": float(term_max),
                      "max_rel_error_route1": float(r1["max_rel_error"]),
                      "max_rel_error_route2": r2.get("max_rel_error"),
                      "route1": r1, "route2": r2},
            "verdict": verdict,
            "plausibility": self.info["plausibility"].summary() if self.info.get("plausibility") else None,
            "coverage": self.coverage.summary(),
            "trajectory": trajectory,
            "energy": energy,
            "limit_excursions": list(traj.stats.get("limit_excursions", [])),
            "base": {"moving": bool(moving),
                     "tracking_error": float(run.base_tracking_error) if moving else None},
            "wall_time": self._wall_time_summary(),
            "notes": list(self.notes),
            **({"contact": self.contact} if self.contact is not None else {}),     # issue 37
        }


def compare_scene(scene, *, t_end: float | None = None, mujoco_integrator: str = "RK4", mujoco_dt: float = 1e-4,
                  method: str | None = None, rtol: float | None = None, atol: float | None = None,
                  samples: int | None = None, states: int = 8, seed: int = 0,
                  threshold: float = DIVERGENCE_THRESHOLD, t_end_note: str | None = None,
                  progress: bool | None = None, log: Callable[[str], None] | None = None,
                  max_wall: float | None = None, model=None, mujoco_fallback: bool = True) -> SceneComparison:
    """Run ``scene`` (a :class:`~urdf2links.scenes.scene.Scene` or a path to its TOML) with the project's
    integrator (the scene's ``[run]`` unless ``method``/``rtol``/``atol`` say otherwise) and with
    MuJoCo (``mujoco_integrator``, ``mujoco_dt``) over ``t_end`` (default the scene's) and compare
    them (module doc). ``samples`` defaults to the scene's, scaled down with a shortened
    ``t_end`` (at least 101). ``t_end_note`` is recorded when the caller capped ``t_end``.
    ``log(message)`` receives stage messages; ``progress`` the project's progress bar. ``max_wall``
    (seconds, from the start of the comparison) bounds the project's integration, and MuJoCo's run is
    not started once it is spent: :class:`~urdf2links.errors.IntegrationError` says so. ``model``: the
    scene's robot when the caller has already loaded it (with the scene's options). The scene is
    loaded once and compiled once (its :class:`~urdf2links.scenes.plan.Plan`); the warm-up, the
    project's run and MuJoCo's inputs all take that plan. When MuJoCo's run blows up (a stiff model),
    ``mujoco_fallback`` runs a stable setting instead and shows its convergence
    (:func:`urdf2links.compare.mujoco_side.stable_run.stable_run`; ``summary()["mujoco"]["fallback"]``)."""
    start = clock()
    say = log or (lambda _m: None)
    setup = _prepare(scene, t_end=t_end, samples=samples, mujoco_dt=mujoco_dt, model=model)
    say(f"terms at {states} seeded states (route 1" + (", route 2)" if not setup.scene.load_options.get("floating_base")
                                                       else ")"))
    mujoco_models = _mujoco_models(setup, mujoco_dt=mujoco_dt, mujoco_integrator=mujoco_integrator)
    terms = _terms(setup, mujoco_models, states=states, seed=seed)
    traj, warm = _run_project(setup, method=method, rtol=rtol, atol=atol, progress=progress, max_wall=max_wall,
                              start=start, say=say)
    runs = _run_mujoco(setup, mujoco_models, traj, mujoco_dt=mujoco_dt, mujoco_integrator=mujoco_integrator,
                       mujoco_fallback=mujoco_fallback, say=say)
    agreement = _agreement(setup, mujoco_models, runs, threshold=threshold)
    notes = _notes(setup, mujoco_models, runs, resampled=agreement.resampled, t_end_note=t_end_note)
    info = {**agreement.info, **_coverage_and_gate(setup, mujoco_models, runs, agreement)}
    info.update({"t_end_note": t_end_note, "warm_up": warm, "total_s": clock() - start})
    contact = None
    if "contact" in setup.plan.terms:       # issue 37: MuJoCo's own contact on the same scene, as a reference
        say("MuJoCo's native contact (a reference, not an error)")
        contact, info["contact_series"] = contact_reference(setup.plan, mujoco_models.mj, runs.t, agreement.q,
                                                            agreement.qd, setup.T, setup.samples)
    return SceneComparison(
        scene=setup.scene, model=setup.model, mj=mujoco_models.mj, traj=traj, run=runs.run, t=runs.t,
        q_ours=agreement.q, q_mujoco=runs.run.q, error=agreement.error, energy=agreement.energy, terms=terms,
        growth=agreement.growth, threshold=threshold, info=info, notes=notes, contact=contact)


# --------------------------------------------------------------------------- the comparison's steps


@dataclass(frozen=True)
class _Setup:
    """The scene, its robot and compiled plan (loaded and compiled once), ``T`` and ``samples`` of both runs."""

    scene: Scene
    model: object
    plan: object
    T: float
    samples: int


@dataclass(frozen=True)
class _MujocoModels:
    """Route 1's MJCF of the project's tree (``mj``) and, for an MJCF robot, MuJoCo running the file (``mf``)."""

    mj: MjcfModel
    mf: object | None


@dataclass(frozen=True)
class _Runs:
    """The project's run (``traj``) and MuJoCo's (``run``, at its times ``t``), MuJoCo's ``fallback`` after a
    blow-up, whether it ran the file itself (``file_run``), the contact's timestep note."""

    traj: Trajectory
    run: MujocoRun
    t: np.ndarray
    fallback: dict | None
    file_run: bool
    step_note: str | None


@dataclass(frozen=True)
class _Agreement:
    """The project's ``q``, ``qd`` at MuJoCo's times, ``|q_ours - q_mujoco|``, the chaotic growth, the energies and
    the summary's energy figures (``info``), whether the project's run was resampled."""

    q: np.ndarray
    qd: np.ndarray
    error: np.ndarray
    growth: dict | None
    energy: dict
    info: dict
    resampled: bool


def _prepare(scene, *, t_end, samples, mujoco_dt, model) -> _Setup:
    """The scene loaded, its robot (``model`` when the caller loaded it), the run's length checked against MuJoCo's
    step limit, the samples (scaled down with a shortened ``t_end``), the plan compiled once."""
    if isinstance(scene, (str, Path)):
        scene = load_scene(scene)
    if model is None:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # audit findings: the scene chose how to load its robot
            model = scene.model()
    else:
        scene.check_names(model)
    T = float(scene.run.t_end if t_end is None else t_end)
    _check_mujoco_steps(scene, T, mujoco_dt)
    if samples is None:
        s = scene.run.samples
        samples = s if T >= scene.run.t_end else max(101, int(round((s - 1) * T / scene.run.t_end)) + 1)
    return _Setup(scene, model, compile_plan(scene, model), T, samples)   # the compiled run, passed down


def _mujoco_models(setup: _Setup, *, mujoco_dt, mujoco_integrator) -> _MujocoModels:
    """Route 1 (the project's tree as MJCF, the scene's constraints and tendons as equalities) and, for an MJCF
    robot, route 2 (MuJoCo runs the file itself)."""
    mj = mjcf_from_scene(setup.scene, setup.model, timestep=mujoco_dt, integrator=mujoco_integrator)
    if setup.plan.constraints is not None:    # issue 36: the scene's constraints and tendons as MuJoCo equalities
        mj = with_constraints(mj, setup.plan.constraints)
    mf = None
    if is_mjcf_path(setup.scene.robot):       # route 2: MuJoCo runs the file itself
        mf = mujoco_from_mjcf(setup.plan, timestep=mujoco_dt, integrator=mujoco_integrator)
    return _MujocoModels(mj, mf)


def _terms(setup: _Setup, models: _MujocoModels, *, states, seed) -> dict:
    """The terms at identical seeded states, both routes; the actuators' forces beside them (module doc, 1)."""
    scene, model, plan, mj, mf = setup.scene, setup.model, setup.plan, models.mj, models.mf
    if mf is not None:
        route2 = file_terms(mf, model, scene, states=states, seed=seed)
    else:
        route2 = route2_terms(scene, states=states, seed=seed, model=model)
    terms = {"route1": route1_terms(mj, model, scene, states=states, seed=seed), "route2": route2}
    if plan.actuator_set.actuators or tendon_actuators(plan):   # the actuators' forces at identical states, both routes
        terms["route1"] = merged(terms["route1"], route1_actuators(plan, mj, states=states, seed=seed))
        act2 = (file_actuators(plan, mf, states=states, seed=seed) if mf is not None else
                route2_actuators(plan, scene.robot, states=states, seed=seed) if not is_xacro_path(scene.robot)
                else {"label": "route 2", "skipped": "a xacro robot: route 2's actuators are checked on URDF files"})
        terms["route2"] = merged(terms["route2"], act2)
    return terms


def _run_project(setup: _Setup, *, method, rtol, atol, progress, max_wall, start, say):
    """The warm-up (its compilation reported apart) and the project's run, within ``max_wall`` from ``start``."""
    scene, T = setup.scene, setup.T
    meth = method or scene.run.method
    warm = warm_up(setup.plan, methods=(meth,))      # its compilation: in the summary, and on the command's one line
    say(f"project: {meth}" + (f" rtol {rtol or scene.run.rtol:g}" if meth not in ("RK4", "midpoint") else "")
        + f", t = 0..{T:g} s")
    left = None if max_wall is None else max_wall - (clock() - start)
    if left is not None and left <= 0:
        raise IntegrationError(f"{scene.path or scene.name}: max_wall={max_wall:g} s spent before the project's run "
                               "(loading and terms)")
    traj = simulate(setup.plan, t_end=T, method=method, rtol=rtol, atol=atol, samples=setup.samples,
                    progress=progress, max_wall=left)
    if max_wall is not None and clock() - start > max_wall:
        raise IntegrationError(f"{scene.path or scene.name}: max_wall={max_wall:g} s spent before MuJoCo's run")
    return traj, warm


def _run_mujoco(setup: _Setup, models: _MujocoModels, traj, *, mujoco_dt, mujoco_integrator, mujoco_fallback,
                say) -> _Runs:
    """MuJoCo's run (the file's route when it takes the scene's inputs, else route 1), with the contact's step and
    the stable fallback after a blow-up."""
    plan, T, samples, mf = setup.plan, setup.T, setup.samples, models.mf
    step_note = None
    if "contact" in plan.terms:         # issue 37: MuJoCo's step resolves the contact's stiffest mode
        mujoco_dt, step_note = contact_timestep(plan, traj, mujoco_dt)
        if step_note:
            say(step_note)
    say(f"MuJoCo: {mujoco_integrator} dt {mujoco_dt:g}, {int(round(T / mujoco_dt))} steps")
    plan = _projected_start(plan, traj, say)
    file_run = mf is not None and not file_route_inputs(setup.scene, plan)
    runner = (file_runner(mf, plan, t_end=T, samples=samples, reference=traj.q if len(traj.q) == samples else None)
              if file_run else None)     # the file's route falls back like route 1 when MuJoCo blows up
    run, fallback = stable_run(models.mj, plan, t_end=T, samples=samples, integrator=mujoco_integrator,
                               timestep=mujoco_dt, fallback=mujoco_fallback, runner=runner)
    if fallback is not None:
        say(fallback["note"])
    return _Runs(traj, run, np.asarray(run.t, float), fallback, file_run, step_note)


def _projected_start(plan, traj, say):
    """Issue 45: a constrained run starts from its initial state projected onto the constraints (E74); MuJoCo
    starts there too (not off the loop, where its soft constraint would snap it back in its first steps). The
    plan unchanged when the projection moved nothing, else a copy whose scene starts at the projected state."""
    import copy
    import dataclasses

    if plan.constraints is None or not plan.constraints.cset.m or not len(traj.q):
        return plan
    q0, qd0 = plan.scene.initial_state(plan.model)
    moved = max(float(np.max(np.abs(traj.q[0] - q0), initial=0.0)),
                float(np.max(np.abs(traj.qd[0] - qd0), initial=0.0)))
    if moved == 0.0:
        return plan
    names = plan.model.coordinate_names
    out = copy.copy(plan)
    out.scene = dataclasses.replace(plan.scene, q0={nm: float(v) for nm, v in zip(names, traj.q[0])},
                                    qd0={nm: float(v) for nm, v in zip(names, traj.qd[0])})
    say(f"MuJoCo starts from the project's initial state projected onto the constraints (moved by {moved:.3g})")
    return out


def _agreement(setup: _Setup, models: _MujocoModels, runs: _Runs, *, threshold) -> _Agreement:
    """The trajectories' and energies' agreement (module doc, 2 and 3): the project at MuJoCo's times, the error,
    a chaotic scene's growth up to the divergence, both energy balances."""
    t = runs.t
    q_o, qd_o, W, EV_o, h_o, resampled = project_at(runs.traj, setup.plan, t, setup.T)
    error = np.abs(q_o - runs.run.q)
    err_max = error.max(axis=1) if setup.model.n else np.zeros(len(t))
    div = divergence_time(t, err_max, threshold)
    growth = growth_fit(t, err_max, end_time=div) if setup.scene.chaotic else None
    energy, info = energy_balances(setup.scene, setup.plan, models.mj, runs.run, runs.traj, EV_o, h_o, W)
    return _Agreement(q_o, qd_o, error, growth, energy, info, resampled)


def _notes(setup: _Setup, models: _MujocoModels, runs: _Runs, *, resampled: bool, t_end_note) -> list[str]:
    """The report's notes on the runs: both runs', the constraints', the contact's step, route 2's."""
    scene, plan, model, mf = setup.scene, setup.plan, setup.model, models.mf
    notes = run_notes(scene, plan, models.mj, runs.run, runs.traj, t_end_note, resampled=resampled)
    notes += constraint_run_notes(plan, runs.traj, models.mj)   # issue 36: closed loops, couplings, tendons
    notes += [runs.step_note] if runs.step_note else []      # issue 37: MuJoCo's step for the contact
    if mf is not None:
        notes += ([f"route 2 (the MJCF file in MuJoCo): {x}" for x in mf.notes]
                  + [f"import: {x}" for x in model.info.get("notes", [])])
        if not runs.file_run:
            notes.append(f"the scene's {', '.join(file_route_inputs(scene, plan))} are inputs that the run of the "
                         "MJCF file does not take yet: MuJoCo's trajectory is route 1's (the project's tree as MJCF)")
    return notes


def _coverage_and_gate(setup: _Setup, models: _MujocoModels, runs: _Runs, agreement: _Agreement) -> dict:
    """What the run exercised (E66, E67), the plausibility gate before any verdict (issue 43), the model's scope and
    the effects switched off: the summary's ``info`` beside the energy figures."""
    scene, plan, model, mf, energy = setup.scene, setup.plan, setup.model, models.mf, agreement.energy
    q0, qd0 = scene.initial_state(model)
    floors = file_floors(mf.model) if mf is not None else []    # issue 43: the gate before any verdict
    gate = plausibility(plan, t=runs.t, runs={"urdf2links": (agreement.q, agreement.qd),
                                              "MuJoCo": (runs.run.q, runs.run.qd)},
                        balances={"urdf2links": (energy["ours_balance"], "h - h(0) - W"),
                                  "MuJoCo": (energy["mujoco_h"] - energy["mujoco_h"][0], "h - h(0)")},
                        energy_scale=agreement.info["energy_scale"], t_end=setup.T, qd0=qd0, floors=floors)
    return {"plausibility": gate, "switched_off": switched_off(model, plan, mf.model if mf is not None else None),
            "floors": [{"name": nm, "normal": n.tolist(), "height": h} for nm, n, h in floors],
            "trajectory_route": FILE_LABEL if runs.file_run else ROUTE1_LABEL, "mujoco_fallback": runs.fallback,
            "coverage": coverage(agreement.q, agreement.qd, model=model),
            "scope": cut_scope(model, scene.load_options, plan), "t_end": setup.T, "effects": plan.terms,
            "actuators": plan.actuator_set.actuators + tuple(ta.actuator for ta in tendon_actuators(plan)),
            "q0": dict(zip(model.coordinate_names, q0.tolist())), "qd0": dict(zip(model.coordinate_names, qd0.tolist()))}


def _check_mujoco_steps(scene, T: float, mujoco_dt) -> None:
    """MuJoCo's run is ``T / mujoco_dt`` steps, known in advance: refused before it starts when that is
    more than :data:`~urdf2links.ranges.MAX_STEPS` (or the timestep is not positive)."""
    steps = T / mujoco_dt if isinstance(mujoco_dt, (int, float)) and mujoco_dt > 0 else math.inf
    if not steps <= MAX_STEPS:
        raise IntegrationError(f"{scene.path or scene.name}: MuJoCo timestep {mujoco_dt!r} over t_end = {T:g} s makes "
                               f"{steps:.3g} steps, more than the {MAX_STEPS:g} a run may take: give a timestep in "
                               f"[{T / MAX_STEPS:g}, {T:g}] s")

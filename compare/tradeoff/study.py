"""Work-precision study of one scene: what each level of accuracy costs, in both engines.

:func:`run_study` runs, on the same scene from the same initial state over ``t = 0..T``:

1. **the reference**: DOP853 at rtol 1e-13, atol 1e-14, checked against a second run (default:
   Radau at rtol 1e-13, atol 1e-14, an implicit method of another family; ``quick``: DOP853 at
   rtol 1e-12, cheaper, whose difference bounds the reference's error from above when the
   method converges regularly). The largest coordinate difference of the two over the samples is
   the reference's **error estimate**; errors below it are not resolved by the study.
2. **every method of the project** (:data:`urdf2links.integration.integrators.METHODS`): the adaptive ones
   over a ladder of rtol (``atol = 1e-2 rtol``; a decade costs DOP853 about 1.25-1.35x more
   evaluations), ``RK4`` and ``midpoint`` (Newton tolerance rtol 1e-10, atol 1e-12) over the
   ladder of steps :data:`DTS`;
3. **MuJoCo's** ``Euler``, ``implicitfast``, ``implicit`` and ``RK4`` over the ladder of timesteps
   :data:`MUJOCO_DTS` (route 1: the project's tree as MJCF,
   :func:`urdf2links.compare.mujoco_side.mjcf.mjcf_from_scene`, run by
   :func:`urdf2links.compare.mujoco_side.mujoco_run.run_mujoco`). Both step ladders are ``0.01 s / j``
   with ``j`` about 1.25x apart (1, 2, 4, 5, 8, 10, 16, 20, 25, 32, ...): steps that divide the
   0.01 s sample interval and a cost axis resolved as finely as the rtol ladder's.

For each run: the error against the reference in the coordinates (max over coordinates of
``|q - q_ref|``, rad or m) at the final time and the maximum over the common sample times (the
reference's dense output at MuJoCo's actual sample times); the energy drift, ``max |h - h(0) - W|``
over the reference's energy scale (project: its own power balance; MuJoCo: ``h`` from its own
energies as :mod:`urdf2links.compare.agreement.trajectory` does, ``W`` the reference's work when work acts); the wall
time; the dynamics evaluations (project: every call of the right-hand side, Jacobian differences
included; MuJoCo: steps x stages, Euler 1, implicitfast 1, implicit 1, RK4 4).

**Timing.** Every run is first made once, with samples, for its errors (not timed). Then
``repeats`` rounds run every configuration that succeeded once more each, from t = 0 to T with
nothing sampled in between, engines interleaved and the order reversed every other round; the
median, minimum and maximum over the rounds are kept (the spread). Both engines are timed the same
way, in this one process, after a warm-up (:func:`urdf2links.integration.simulate.warm_up`: numba's
compilation is never timed): the project's time is :func:`urdf2links.integration.integrators.integrate`'s
``wall_time`` on the scene's compiled right-hand side (the integration loop; no dense output, no
samples, no energies; a scene whose floating links are re-charted is timed through
:func:`~urdf2links.integration.simulate.simulate`); MuJoCo's is ``MujocoRun.wall_time``, one
``mj_step(m, d, nstep=K)`` call with the energy flag off (inputs from the compiled control
callback).

**Budget.** A configuration whose predicted wall time exceeds ``budget`` seconds (evaluations x
the measured cost of one, extrapolated from the looser rungs for the adaptive methods) is skipped,
and so are the tighter rungs of the same method (a failed rung does not stop the ladder); so are the
rungs after one whose error came within :data:`FLOOR_STOP` times the reference's error estimate
(they would not be resolved), and after one that reached the method's own rounding floor: within
:data:`ROUNDING_BAND` times the estimate, its error no smaller than a looser rung's (MuJoCo's RK4
levels off near 1e-10 on the UR5-like arm while the estimate is 4e-11). Runs that fail (step
underflow, non-finite state, failed factorization, MuJoCo's instability reset) are recorded as
failed with the reason.

**Crossover** (:func:`crossover`): at each error level, the fastest run of each engine reaching
it (median time); an engine is faster there only when its slowest round beats the other's fastest
(the spreads do not overlap), otherwise the level is a tie; the level below which the project is
faster than MuJoCo, with the spread of both times, or the statement that it is not.

Files, plots and the report section: :mod:`urdf2links.compare.tradeoff.report`. Command: ``urdf2links tradeoff``
(:mod:`urdf2links.compare.commands`).
"""

from __future__ import annotations

import math
import statistics
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from urdf2links.compilation import clock as _clock  # durations without numba's compilation
from urdf2links.console import shown_path
from urdf2links.integration.charts import floating_links
from urdf2links.integration.integrators import METHODS, integrate
from urdf2links.integration.simulate import simulate, warm_up
from urdf2links.scenes.plan import compile_plan
from urdf2links.scenes.scene import robot_label
from urdf2links.scenes.scene_read import load_scene

from ..agreement.trajectory import scene_key
from ..formatting import json_ready, machine_info
from ..mujoco_side.mjcf import mjcf_from_scene
from ..mujoco_side.mujoco_constraints import with_constraints
from ..mujoco_side.mujoco_run import energy_function, run_mujoco
from .crossover import crossover

__all__ = ["run_study", "crossover", "STAGES", "MUJOCO_INTEGRATORS", "ADAPTIVE", "FIXED"]

ADAPTIVE = tuple(m for m in METHODS if m not in ("RK4", "midpoint"))
FIXED = ("RK4", "midpoint")
MUJOCO_INTEGRATORS = ("Euler", "implicitfast", "implicit", "RK4")
#: Dynamics evaluations per MuJoCo step.
STAGES = {"Euler": 1, "implicitfast": 1, "implicit": 1, "RK4": 4}

RTOLS = (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12)
QUICK_RTOLS = (1e-4, 1e-6, 1e-8)
#: Steps per 0.01 s of the fixed-step ladders: 2^a 5^b, about 1.25x apart from 4 on.
STEPS_PER_CENTISECOND = (1, 2, 4, 5, 8, 10, 16, 20, 25, 32, 40, 50, 64, 80, 100, 125, 160, 200, 250, 320, 400, 500,
                         640, 800, 1000, 1250, 1600, 2000, 2500, 3200, 4000, 5000, 6400, 8000, 10000)
#: The project's RK4 and midpoint steps: 1e-2 .. 1e-5 s.
DTS = tuple(1e-2 / j for j in STEPS_PER_CENTISECOND if j <= 1000)
QUICK_DTS = (1e-2, 5e-3, 2.5e-3)
#: MuJoCo's timesteps: 1e-2 .. 1e-6 s.
MUJOCO_DTS = tuple(1e-2 / j for j in STEPS_PER_CENTISECOND)
QUICK_MUJOCO_DTS = (8e-3, 4e-3, 2e-3, 1e-3)
REFERENCE = {"method": "DOP853", "rtol": 1e-13, "atol": 1e-14}
CHECK = {"method": "Radau", "rtol": 1e-13, "atol": 1e-14}
QUICK_CHECK = {"method": "DOP853", "rtol": 1e-12, "atol": 1e-13}
MIDPOINT_NEWTON = {"rtol": 1e-10, "atol": 1e-12}
DEFAULT_T_CAP = 2.0
#: A method's ladder stops once a run's error is within this factor of the reference's error estimate.
FLOOR_STOP = 3.0
#: ... or once a run within this factor of the estimate is no more accurate than a looser rung of
#: its ladder (the method's own rounding floor: tighter runs cost more and gain nothing).
ROUNDING_BAND = 100.0
DEFAULT_BUDGET = 30.0
QUICK_BUDGET = 5.0


@dataclass(frozen=True)
class Config:
    engine: str       # "urdf2links" | "MuJoCo"
    method: str
    param: str        # "rtol" | "dt"
    value: float

    @property
    def label(self) -> str:
        return f"{self.engine} {self.method} {self.param} {self.value:g}"


def _say(log, msg):
    if log is not None:
        log(msg)


def _qerr(q, q_ref) -> tuple[float, float]:
    """(final, max over samples) of the largest coordinate error."""
    e = np.abs(np.asarray(q, float) - np.asarray(q_ref, float))
    e = e.max(axis=1) if e.ndim == 2 and e.shape[1] else np.zeros(len(e))
    return float(e[-1]), float(e.max())


def _options(cfg: Config) -> dict:
    """The integrator's options of a project rung (method, step or tolerances)."""
    kw = {"method": cfg.method}
    if cfg.param == "dt":
        kw["dt"] = cfg.value
        if cfg.method == "midpoint":
            kw.update(MIDPOINT_NEWTON)
    else:
        kw.update(rtol=cfg.value, atol=1e-2 * cfg.value)
    return kw


def _project(st: "_Study", cfg: Config):
    """The run for the errors: :func:`simulate` with the study's samples (not timed)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return simulate(st.plan, t_end=st.T, samples=st.S, progress=False, **_options(cfg))


def _time_project(st: "_Study", cfg: Config) -> float:
    """One timing run: :func:`integrate` of the compiled right-hand side from 0 to T, nothing
    sampled (re-charted scenes: :func:`simulate` with the two end samples); its ``wall_time``."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        if st.charted:
            return float(simulate(st.plan, t_end=st.T, samples=2, progress=False,
                                  **_options(cfg)).stats["wall_time"])
        res = integrate(st.plan.rhs, (0.0, st.T), st.y0, **_options(cfg))
    if not res.success:
        raise RuntimeError(res.message)
    return float(res.wall_time)


def _mujoco(st: "_Study", cfg: Config, samples: int):
    return run_mujoco(st.mj, st.plan, t_end=st.T, timestep=cfg.value, integrator=cfg.method, samples=samples)


def _mujoco_failure(run, T) -> str | None:
    if not (np.all(np.isfinite(run.q)) and np.all(np.isfinite(run.qd))):
        return "MuJoCo's state became non-finite"
    if run.blow_ups:       # MuJoCo reset its state (and its time): the samples after it are no solution
        return ("MuJoCo reset the simulation (unstable: "
                + ", ".join(f"{w} x{k}" for w, k in run.blow_ups.items()) + ")")
    if np.any(np.diff(run.t) < 0) or abs(run.t[-1] - run.nsteps * run.timestep) > 1e-6 * max(T, 1.0):
        return "MuJoCo reset the simulation (unstable: bad acceleration)"
    return None


def _predict(cfg: Config, T, done: list[dict], cost: dict) -> float:
    """Predicted wall time (s) of ``cfg`` from the cost of one evaluation or step and the looser
    rungs of the same method already run (``done``: their rows, loosest first)."""
    if cfg.engine == "MuJoCo":
        return math.ceil(T / cfg.value) * cost["mujoco_step_s"][cfg.method]
    per_eval = cost["project_eval_s"]
    prev = [r for r in done if r["status"] == "ok" and r.get("nfev")]
    if prev and prev[-1].get("first_run_s"):  # this method's own cost per evaluation
        per_eval = prev[-1]["first_run_s"] / prev[-1]["nfev"]
    if cfg.param == "dt":
        if prev:
            p = prev[-1]
            return p["nfev"] * p["value"] / cfg.value * per_eval
        per_step = 4 if cfg.method == "RK4" else 3
        return per_step * math.ceil(T / cfg.value) * per_eval
    if len(prev) >= 2:  # evaluations grow geometrically per decade of rtol: extrapolate
        a, b = prev[-2], prev[-1]
        per_decade = max(b["nfev"] / a["nfev"], 1.0) ** (1.0 / max(math.log10(a["value"] / b["value"]), 1e-9))
        return b["nfev"] * max(per_decade, 1.2) ** math.log10(b["value"] / cfg.value) * per_eval
    if prev:
        return prev[-1]["nfev"] * 2.0 ** math.log10(prev[-1]["value"] / cfg.value) * per_eval
    return 0.0


def _ladder(quick, methods, mujoco_integrators):
    cfgs = []
    for m in methods:
        if m in FIXED:
            cfgs += [Config("urdf2links", m, "dt", v) for v in (QUICK_DTS if quick else DTS)]
        else:
            cfgs += [Config("urdf2links", m, "rtol", v) for v in (QUICK_RTOLS if quick else RTOLS)]
    for m in mujoco_integrators:
        cfgs += [Config("MuJoCo", m, "dt", v) for v in (QUICK_MUJOCO_DTS if quick else MUJOCO_DTS)]
    return cfgs


@dataclass
class _Study:
    """What one study works with: the scene, its model, plan and MJCF, run length and samples, the
    reference run and its error estimate, the energy scale and the per-step costs."""

    scene: object
    model: object
    plan: object
    mj: object
    T: float
    S: int
    ref: object = None
    est_max: float = 0.0
    scale: float = 1.0
    work_terms: bool = False
    cost: dict | None = None
    y0: np.ndarray | None = None
    charted: bool = False
    warm: dict | None = None


def _settings(scene, t_end, quick, repeats, budget, samples, methods, mujoco_integrators, check):
    """Checked settings: methods, integrators, repeats, budget, ``T`` and its note, samples, check."""
    methods = tuple(METHODS if methods is None else methods)
    mujoco_integrators = tuple(MUJOCO_INTEGRATORS if mujoco_integrators is None else mujoco_integrators)
    for m in methods:
        if m not in METHODS:
            raise ValueError(f"methods: unknown method {m!r}; expected some of {', '.join(METHODS)}")
    for m in mujoco_integrators:
        if m not in STAGES:
            raise ValueError(f"mujoco_integrators: unknown integrator {m!r}; expected some of {', '.join(STAGES)}")
    repeats = (1 if quick else 3) if repeats is None else int(repeats)
    if repeats < 1:
        raise ValueError(f"repeats must be >= 1, got {repeats!r}")
    budget = (QUICK_BUDGET if quick else DEFAULT_BUDGET) if budget is None else float(budget)
    if t_end is None:
        T = min(scene.run.t_end, DEFAULT_T_CAP)
        t_note = (f"t_end {T:g} s: the scene's {scene.run.t_end:g} s capped at {DEFAULT_T_CAP:g} s by default "
                  "(--t-end to change)") if T < scene.run.t_end else None
    else:
        T = float(t_end)
        if not (math.isfinite(T) and T > 0):
            raise ValueError(f"t_end must be a finite number > 0, got {t_end!r}")
        t_note = None if T == scene.run.t_end else f"t_end {T:g} s set by --t-end (the scene's is {scene.run.t_end:g} s)"
    S = int(samples) if samples is not None else int(min(2001, max(51, round(T / 0.01) + 1)))
    check = dict(check or (QUICK_CHECK if quick else CHECK))
    return methods, mujoco_integrators, repeats, budget, T, t_note, S, check


def _warm_up(st: _Study, methods, check, log) -> dict:
    """numba compiles at the first call, which must be neither timed nor used to predict costs:
    one short run of every method here (:func:`urdf2links.integration.simulate.warm_up`; the timing runs call
    the same compiled loops). Returns what was compiled and how long it took."""
    wu = warm_up(st.plan, methods=tuple(dict.fromkeys(methods + (REFERENCE["method"], check["method"]))),
                 t_end=min(st.T, 0.02))
    if wu.happened:
        _say(log, wu.describe("warm-up"))
    return {"seconds": wu.seconds, "compiled": list(wu.functions)}


def _reference(st: _Study, check, log):
    """The reference run, its check run and the error estimate; the energy scale."""
    _say(log, f"reference: {REFERENCE['method']} rtol {REFERENCE['rtol']:g}, t = 0..{st.T:g} s, {st.S} samples")
    ref = simulate(st.plan, t_end=st.T, samples=st.S, progress=False, method=REFERENCE["method"],
                   rtol=REFERENCE["rtol"], atol=REFERENCE["atol"])
    if not ref.stats["success"]:
        raise RuntimeError(f"the reference run failed: {ref.stats['message']}")
    _say(log, f"  {ref.stats['nsteps']} steps, {ref.stats['nfev']} evaluations, {ref.stats['wall_time']:.2f} s; "
              f"check: {check['method']} rtol {check['rtol']:g}")
    chk = simulate(st.plan, t_end=st.T, samples=st.S, progress=False, method=check["method"],
                   rtol=check["rtol"], atol=check["atol"])
    est_final, est_max = _qerr(chk.q, ref.q)
    _say(log, f"  check {chk.stats['nfev']} evaluations, {chk.stats['wall_time']:.2f} s: reference error estimate "
              f"{est_max:.2e} (max over the run), {est_final:.2e} (final)")
    en = ref.energy
    st.ref, st.est_max = ref, est_max
    st.scale = max(float(np.abs(en["kinetic"]).max()), float(np.abs(en["potential"] - en["potential"][0]).max()),
                   float(np.abs(en["work"]).max()), 1e-300)
    st.work_terms = any(t in st.plan.terms for t in ("Q", "tau", "damper", "base", "gravcomp", "actuator",
                                                      "computed_torque"))
    return chk, est_final


def _costs(st: _Study, mujoco_integrators) -> dict:
    """Cost of one evaluation (project) and of one step (MuJoCo), for the budget."""
    ref = st.ref
    cost = {"project_eval_s": ref.stats["wall_time"] / max(ref.stats["nfev"], 1), "mujoco_step_s": {}}
    for m in mujoco_integrators:
        dt_probe = 1e-3
        probe = run_mujoco(st.mj, st.plan, t_end=min(st.T, 200 * dt_probe), timestep=dt_probe, integrator=m,
                           samples=2)
        cost["mujoco_step_s"][m] = probe.wall_time / max(probe.nsteps, 1)
    return cost


def _new_row(cfg: Config) -> dict:
    row = {"engine": cfg.engine, "method": cfg.method, "param": cfg.param, "value": cfg.value,
           "status": "ok", "reason": None, "error_final": None, "error_max": None, "energy_drift_rel": None,
           "wall_time_s": None, "wall_time_min_s": None, "wall_time_max_s": None, "wall_times_s": [], "nfev": None,
           "nsteps": None, "notes": []}
    if cfg.engine == "urdf2links" and cfg.method == "midpoint":
        row["notes"].append(f"Newton tolerance rtol {MIDPOINT_NEWTON['rtol']:g}, atol {MIDPOINT_NEWTON['atol']:g}")
    if cfg.engine == "urdf2links" and cfg.param == "rtol":
        row["atol"] = 1e-2 * cfg.value
    return row


def _skip_reason(st: _Study, cfg: Config, done: list[dict], budget: float, row: dict) -> str | None:
    """Why ``cfg`` is not run: over the budget (its own prediction, or a looser rung's), or a looser
    rung already reached the reference's error estimate. A failure does not stop the ladder (a
    coarse step that blows up or whose Newton iteration fails says nothing of finer ones)."""
    stop = next((r for r in done if r["status"] == "skipped" and "budget" in (r["reason"] or "")), None)
    floored = next((r for r in done if r["status"] == "ok" and r["error_max"] <= FLOOR_STOP * st.est_max), None)
    stalled, best = _rounding_floor(done, st.est_max)
    pred = _predict(cfg, st.T, done, st.cost)
    row["predicted_s"] = pred
    if stop is not None:
        return f"a looser rung ({stop['param']} {stop['value']:g}) was over the budget"
    if floored is not None:
        return (f"a looser rung ({floored['param']} {floored['value']:g}) already reached the reference's error "
                f"estimate (error {floored['error_max']:.1e} <= {FLOOR_STOP:g} x {st.est_max:.1e}): tighter runs "
                "are not resolved")
    if stalled is not None:
        return (f"the rung {stalled['param']} {stalled['value']:g} reached this method's rounding floor: its error "
                f"{stalled['error_max']:.1e} is no smaller than a looser rung's ({best:.1e}), within "
                f"{ROUNDING_BAND:g} x the reference's error estimate {st.est_max:.1e}: tighter runs cost more and "
                "gain nothing")
    if pred > budget:
        return f"predicted {pred:.3g} s > budget {budget:g} s"
    return None


def _rounding_floor(done: list[dict], est: float) -> tuple[dict | None, float]:
    """The first run of a ladder (loosest first) that is within :data:`ROUNDING_BAND` times the
    reference's error estimate ``est`` and no more accurate than a looser successful rung, with
    that rung's error; ``(None, inf)`` when there is none."""
    best = math.inf
    for r in done:
        if r["status"] != "ok":
            continue
        if r["error_max"] <= ROUNDING_BAND * est and r["error_max"] >= best:
            return r, best
        best = min(best, r["error_max"])
    return None, math.inf


def _measure_project(st: _Study, cfg: Config, row: dict) -> None:
    tr = _project(st, cfg)
    if not tr.stats["success"]:
        row.update(status="failed", reason=str(tr.stats["message"]))
    elif not np.all(np.isfinite(tr.q)):
        row.update(status="failed", reason="non-finite state")
    else:
        row["error_final"], row["error_max"] = _qerr(tr.q, st.ref.q)
        row["energy_drift_rel"] = float(np.abs(tr.energy["error"]).max() / st.scale)
    row.update(nfev=int(tr.stats["nfev"]), nsteps=int(tr.stats["nsteps"]), first_run_s=float(tr.stats["wall_time"]))


def _measure_mujoco(st: _Study, cfg: Config, row: dict) -> None:
    n = st.model.n
    run = _mujoco(st, cfg, st.S)
    row.update(nsteps=int(run.nsteps), nfev=int(run.nsteps) * STAGES[cfg.method], first_run_s=float(run.wall_time))
    row["notes"] += list(run.notes)
    bad = _mujoco_failure(run, st.T)
    if bad:
        row.update(status="failed", reason=bad)
        return
    Y = st.ref.sol(np.clip(run.t, 0.0, st.T))
    row["error_final"], row["error_max"] = _qerr(run.q, Y[:, :n])
    h = run.total_energy if st.scene.base is None else energy_function(st.mj, run, st.plan)
    bal = h - h[0] - (Y[:, 2 * n] if st.work_terms else 0.0)
    row["energy_drift_rel"] = float(np.abs(bal).max() / st.scale)


def _ladders(st: _Study, cfgs, budget, log) -> list[dict]:
    """Every configuration once, with samples, for its errors (not timed): the rows."""
    rows: list[dict] = []
    by_method: dict[tuple, list[dict]] = {}
    for k, cfg in enumerate(cfgs, 1):
        done = by_method.setdefault((cfg.engine, cfg.method), [])
        row = _new_row(cfg)
        why = _skip_reason(st, cfg, done, budget, row)
        if why is not None:
            row.update(status="skipped", reason=why)
        else:
            try:
                (_measure_project if cfg.engine == "urdf2links" else _measure_mujoco)(st, cfg, row)
            except Exception as err:  # a failed run is a result, not a crash of the study
                row.update(status="failed", reason=f"{type(err).__name__}: {err}")
        done.append(row)
        rows.append(row)
        _say(log, f"[{k}/{len(cfgs)}] {cfg.label}: " + (
            f"error {row['error_max']:.2e} (final {row['error_final']:.2e}), {row['nfev']} evaluations, "
            f"{row['first_run_s']:.3g} s" if row["status"] == "ok" else f"{row['status'].upper()}: {row['reason']}"))
    return rows


def _timing_rounds(st: _Study, cfgs, rows, repeats, log) -> None:
    """Timing rounds: engines interleaved, order reversed every other round; median, min and max."""
    ok = [(cfg, row) for cfg, row in zip(cfgs, rows) if row["status"] == "ok"]
    proj = [x for x in ok if x[0].engine == "urdf2links"]
    mjc = [x for x in ok if x[0].engine == "MuJoCo"]
    order = [x for pair in zip(proj, mjc) for x in pair] + proj[len(mjc):] + mjc[len(proj):]
    for r in range(repeats):
        t0 = _clock()
        for cfg, row in (order if r % 2 == 0 else order[::-1]):
            try:
                if cfg.engine == "urdf2links":
                    row["wall_times_s"].append(_time_project(st, cfg))
                else:
                    row["wall_times_s"].append(float(_mujoco(st, cfg, 2).wall_time))
            except Exception as err:
                row["notes"].append(f"timing round {r + 1} failed: {type(err).__name__}: {err}")
        _say(log, f"timing round {r + 1}/{repeats}: {len(order)} runs in {_clock() - t0:.1f} s")
    for _, row in ok:
        if row["wall_times_s"]:
            row["wall_time_s"] = float(statistics.median(row["wall_times_s"]))
            row["wall_time_min_s"] = float(min(row["wall_times_s"]))
            row["wall_time_max_s"] = float(max(row["wall_times_s"]))


def _reference_record(st: _Study, chk, check, est_final) -> dict:
    ref = st.ref
    return {
        "method": REFERENCE["method"], "rtol": REFERENCE["rtol"], "atol": REFERENCE["atol"],
        "nsteps": int(ref.stats["nsteps"]), "nfev": int(ref.stats["nfev"]), "wall_time_s": float(ref.stats["wall_time"]),
        "energy_drift_rel": float(np.abs(ref.energy["error"]).max() / st.scale),
        "check": {**check, "nsteps": int(chk.stats["nsteps"]), "nfev": int(chk.stats["nfev"]),
                  "wall_time_s": float(chk.stats["wall_time"]), "success": bool(chk.stats["success"])},
        "error_estimate": st.est_max, "error_estimate_final": est_final,
        "note": (f"error estimate: max over the samples and coordinates of |q_ref - q_check|, the check run being "
                 f"{check['method']} at rtol {check['rtol']:g}; errors below it are not resolved"),
    }


def _study_record(st: _Study, rows, reference, *, quick, budget, repeats, t_note) -> dict:
    scene, model = st.scene, st.model
    return {
        "schema": 1, "kind": "work-precision", "key": scene_key(scene, st.model), "robot": robot_label(scene, st.model),
        "robot_name": model.name, "scene": scene.name, "scene_file": shown_path(scene.path),
        "description": scene.description, "chaotic": bool(scene.chaotic), "coordinates": list(model.coordinate_names),
        "effects": list(st.plan.terms), "t_end": st.T, "t_end_scene": float(scene.run.t_end), "t_end_note": t_note,
        "samples": st.S, "quick": bool(quick), "budget_s": budget, "reference": reference,
        "error": {"metric": "max over coordinates of |q - q_ref| (rad or m); 'max' over the common sample times, "
                            "'final' at the end", "floor": st.est_max},
        "energy": {"scale_J": st.scale, "work_terms": bool(st.work_terms),
                   "metric": "max |h - h(0) - W| / scale (h = E + V for a fixed base; MuJoCo: its own energies"
                             + ("; W: the reference's work along the reference trajectory" if st.work_terms else "")
                             + ")"},
        "timing": {"repeats": repeats, "statistic": "median", "spread": "min and max over the rounds",
                   "interleaved": True, "same_process": True, "warm_up": st.warm,
                   "project": ("urdf2links.integration.integrators.integrate() of the scene's compiled right-hand side from 0 to T: "
                               "the integration loop only (no dense output, no samples, no energies)"
                               if not st.charted else "simulate()'s wall_time with 2 samples (re-charted floating "
                               "links): the integration with its dense output, not the sampling nor the energies"),
                   "mujoco": "MujocoRun.wall_time: one mujoco.mj_step(m, d, nstep=K) call, energy flag off (inputs "
                             "from the compiled control callback)",
                   "compilation": "numba's compilation happens in the warm-up, before any run (warm_up)"},
        "ladders": {"rtol": list(QUICK_RTOLS if quick else RTOLS), "atol": "1e-2 x rtol",
                    "dt": list(QUICK_DTS if quick else DTS), "mujoco_dt": list(QUICK_MUJOCO_DTS if quick else MUJOCO_DTS),
                    "midpoint_newton": MIDPOINT_NEWTON},
        "cost": {"project_eval_us": st.cost["project_eval_s"] * 1e6,
                 "mujoco_step_us": {k: v * 1e6 for k, v in st.cost["mujoco_step_s"].items()}},
        "evaluations": "project: calls of the right-hand side (Jacobian differences included); MuJoCo: steps x "
                       "stages (Euler 1, implicitfast 1, implicit 1, RK4 4)",
        "rows": rows,
        "machine": machine_info(),
        "total_s": None,
    }


def run_study(scene, *, t_end: float | None = None, quick: bool = False, repeats: int | None = None,
              budget: float | None = None, samples: int | None = None, methods=None, mujoco_integrators=None,
              check: dict | None = None, log: Callable[[str], None] | None = None) -> dict:
    """The work-precision study of ``scene`` (a Scene or a path): see the module doc. Returns the
    JSON-ready dictionary that :func:`~urdf2links.compare.tradeoff.report.write_study` writes
    (``rows``, ``reference``, ``crossover``, ``timing``, ``machine``, ...). ``t_end`` defaults to the
    scene's, capped at :data:`DEFAULT_T_CAP`; ``quick``: short ladders, one timing round, a cheaper
    check run."""
    start = _clock()
    if isinstance(scene, (str, Path)):
        scene = load_scene(scene)
    methods, mujoco_integrators, repeats, budget, T, t_note, S, check = _settings(
        scene, t_end, quick, repeats, budget, samples, methods, mujoco_integrators, check)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = scene.model()
    plan = compile_plan(scene, model)
    mj = mjcf_from_scene(scene, model)
    if plan.constraints is not None:    # issue 45: our loops carry the constraints; MuJoCo gets them as equalities
        mj = with_constraints(mj, plan.constraints)
    st = _Study(scene, model, plan, mj, T, S)
    q0, qd0 = scene.initial_state(model)
    st.y0 = np.r_[q0, qd0, 0.0]
    st.charted = bool(floating_links(model)) and bool(scene.run.recharting)
    st.warm = _warm_up(st, methods, check, log)
    chk, est_final = _reference(st, check, log)
    st.cost = _costs(st, mujoco_integrators)
    cfgs = _ladder(quick, methods, mujoco_integrators)
    rows = _ladders(st, cfgs, budget, log)
    _timing_rounds(st, cfgs, rows, repeats, log)
    data = _study_record(st, rows, _reference_record(st, chk, check, est_final), quick=quick, budget=budget,
                         repeats=repeats, t_note=t_note)
    data["crossover"] = crossover(rows, st.est_max)
    data["total_s"] = _clock() - start
    _say(log, data["crossover"]["statement"])
    return json_ready(data)

"""MuJoCo's time in the comparison harness against MuJoCo alone: before and after issue 13.

For each scene and integrator, in one process, over the same model and the same number of steps,
the three variants below interleaved in the same rounds (the order reversed every other round):

* ``plain``: ``mujoco.mj_step(m, d, nstep=K)`` on a fresh ``MjData`` of the route-1 model, the
  energy flag off and no control callback: MuJoCo by itself, without the scene's inputs;
* ``engine``: :func:`urdf2links.compare.mujoco_side.mujoco_run.run_mujoco` as ``urdf2links compare`` runs it
  (``mj_step(nstep)`` from sample to sample, the energy flag off, the scene's inputs from the
  compiled control callback): its ``wall_time`` (MuJoCo's engine) and ``harness_time`` (the whole
  call: set-up, sample copies, energy pass);
* ``before``: the harness as it was: a Python ``for`` loop of one ``mj_step`` per call, the energy
  flag on, ``mj_forward`` + copies + energies at each sample inside the timed loop, and the scene's
  inputs from the Python control callback (:class:`~urdf2links.compare.mujoco_side.mujoco_run.PythonInputs`) at
  every RK4 stage (tens of seconds on scenes with inputs).

Ratios: of the medians, of the minima, and the tie rule's verdict (benchmarking.compare). The
issue's criterion: ``engine`` within 2x of ``plain`` for ``urdf2links compare
robots/ship_crane.toml --t-end 2`` (RK4, dt 1e-4 s). Usage::

    python benchmarks/mujoco_harness.py [--rounds 5] [--cases ship_crane:RK4 ...] [--out reports/benchmarks/mujoco_harness.json]
"""

from __future__ import annotations

import copy
import time

import mujoco
import numpy as np

from benchmarking import compare, fmt_ratio, fmt_spread, markdown_table, rounds, run_benchmark, spread
from urdf2links.compare.mujoco_side.mjcf import mjcf_from_scene
from urdf2links.compare.mujoco_side.mujoco_run import PythonInputs, robot_energy, run_mujoco
from urdf2links.locations import shipped_robots_dir
from urdf2links.scenes.plan import compile_plan
from urdf2links.scenes.scene_read import load_scene

#: (scene, integrator, dt): the Done-when scene first, then a driven arm, then two scenes without inputs.
CASES = (("ship_crane", "RK4", 1e-4), ("spring_arm_torques", "RK4", 1e-4), ("ur5_falling", "RK4", 1e-4),
         ("ur5_falling", "Euler", 1e-4), ("double_pendulum_chaos", "RK4", 1e-4), ("double_pendulum_chaos", "Euler", 1e-4))
T_END = 2.0
SAMPLES = 201


def _setup(name, integrator, dt):
    scene = load_scene(shipped_robots_dir() / f"{name}.toml")
    model = scene.model()
    mj = mjcf_from_scene(scene, model, timestep=dt, integrator=integrator)
    return scene, model, mj, compile_plan(scene, model)


def plain(scene, model, mj, K):
    """MuJoCo alone: the same model and steps, no inputs, energy flag off."""
    m = copy.deepcopy(mj.model)
    m.opt.enableflags &= ~int(mujoco.mjtEnableBit.mjENBL_ENERGY)
    d = mujoco.MjData(m)
    q0, qd0 = scene.initial_state(model)
    mj.set_state(d, q0, qd0)
    t0 = time.perf_counter()
    mujoco.mj_step(m, d, nstep=K)
    return time.perf_counter() - t0


def before(scene, model, mj, plan, K):
    """The harness before issue 13 (see the module doc); the seconds of its timed loop."""
    m = copy.deepcopy(mj.model)
    m.opt.enableflags |= int(mujoco.mjtEnableBit.mjENBL_ENERGY)
    d = mujoco.MjData(m)
    q0, qd0 = scene.initial_state(model)
    driven = scene.base is not None or bool(scene.torques) or bool(scene.loads)
    base = plan.base_state if scene.base is not None else None
    mj.set_state(d, q0, qd0, base=base(0.0) if base else None)
    inputs = PythonInputs(mj, m, d, base=base, torques=plan.torques if plan.torque_funcs else None,
                          loads=plan.wrenches if plan.loads else None) if driven else None
    ks = np.rint(np.linspace(0.0, T_END, SAMPLES) / m.opt.timestep).astype(int)
    out = np.empty((SAMPLES, 2 * mj.n + 2))
    j = 0
    previous = mujoco.get_mjcb_control()
    if inputs is not None:
        mujoco.set_mjcb_control(inputs)
    try:
        t0 = time.perf_counter()
        for k in range(K + 1):
            while j < SAMPLES and ks[j] == k:
                mujoco.mj_forward(m, d)
                out[j, :mj.n] = d.qpos[mj.qpos_index]
                out[j, mj.n:2 * mj.n] = d.qvel[mj.dof_index]
                out[j, 2 * mj.n:] = robot_energy(mj, m, d)
                j += 1
            if k < K:
                mujoco.mj_step(m, d)
        return time.perf_counter() - t0
    finally:
        mujoco.set_mjcb_control(previous)


def measure(case, n_rounds, log) -> dict:
    name, integ, dt = case
    scene, model, mj, plan = _setup(name, integ, dt)
    K = int(round(T_END / dt))
    harness: list[float] = []
    info = {}

    def engine():
        run = run_mujoco(mj, scene, t_end=T_END, samples=SAMPLES)
        harness.append(run.harness_time)
        info.update(inputs=run.inputs, calls=run.callback_calls)
        return run.wall_time

    engine()   # the compiled callback is loaded (or compiled) once per process: not in a round
    harness.clear()
    log(f"{name} {integ} dt {dt:g}: {K} steps")
    times = rounds({"plain": lambda: plain(scene, model, mj, K), "engine": engine,
                    "before": lambda: before(scene, model, mj, plan, K)}, n_rounds, log=log)
    row = {"scene": name, "integrator": integ, "dt": dt, "t_end": T_END, "steps": K, "samples": SAMPLES,
           "inputs": info["inputs"], "callback_calls": info["calls"],
           **{k: spread(v) for k, v in times.items()}, "harness": spread(harness)}
    row.update(comparisons(row))
    log(f"  engine / plain {fmt_ratio(row['engine_vs_plain'])}; before / engine {fmt_ratio(row['before_vs_engine'])}")
    return row


def comparisons(row) -> dict:
    """engine against plain, before against engine and plain, under the tie rule (from the spreads: the
    render recomputes them)."""
    return {"engine_vs_plain": compare(row["engine"], row["plain"]),
            "before_vs_engine": compare(row["before"], row["engine"]),
            "before_vs_plain": compare(row["before"], row["plain"])}


def table(rows) -> str:
    head = ["scene", "MuJoCo", "steps", "inputs", "plain mj_step(nstep) s", "engine s", "engine / plain",
            "whole run_mujoco s", "before s", "before / engine"]
    body = [[r["scene"], f"{r['integrator']} dt {r['dt']:g}", r["steps"], r["inputs"], fmt_spread(r["plain"]),
             fmt_spread(r["engine"]), fmt_ratio(r["engine_vs_plain"]), fmt_spread(r["harness"]),
             fmt_spread(r["before"]), fmt_ratio(r["before_vs_engine"])] for r in rows]
    crane = next((r for r in rows if r["scene"] == "ship_crane"), None)
    verdict = "" if crane is None else (
        f"\n\n`urdf2links compare robots/ship_crane.toml --t-end 2`: MuJoCo's engine time is "
        f"{crane['engine_vs_plain']['median']:.2f}x (minima: {crane['engine_vs_plain']['min']:.2f}x) the plain "
        f"mj_step(nstep) run of the same model and steps "
        f"({'within' if crane['engine_vs_plain']['median'] <= 2.0 else 'NOT within'} 2x).")
    return ("# MuJoCo in the comparison harness, against MuJoCo alone\n\n"
            f"t = 0..{T_END:g} s, {SAMPLES} samples; seconds: median (min-max) of {rows[0]['plain']['rounds']} rounds "
            "in one process, the three variants interleaved in every round. Ratios: of the medians, (min: of the "
            "minima), and the tie rule's verdict (faster or slower only when the spreads do not overlap). "
            "plain: mj_step(m, d, nstep=K), no inputs, energy flag off. engine: run_mujoco's timed region "
            "(mj_step(nstep) from sample to sample, inputs from the compiled control callback). whole run_mujoco: "
            "the same call's set-up, sample copies and energy pass included. before: the harness before issue 13 "
            "(a Python loop of single mj_step calls, energy flag on, samples inside the loop, inputs from the Python "
            "callback at every stage).\n\n" + markdown_table(head, body) + verdict)


def plot(rows):
    from urdf2links.compare.figures import figure

    fig = figure(9.5, 0.55 * len(rows) + 1.8, dpi=100)
    ax = fig.subplots()
    labels = [f"{r['scene']} {r['integrator']}" for r in rows]
    y = np.arange(len(rows))
    for k, (key, colour, text) in enumerate((("plain", "#999999", "plain mj_step(nstep), no inputs"),
                                             ("engine", "#cb181d", "engine (compiled callback)"),
                                             ("harness", "#fd8d3c", "whole run_mujoco"),
                                             ("before", "#6a51a3", "before: Python loop + Python callback"))):
        med = np.array([r[key]["median"] for r in rows])
        err = np.array([[r[key]["median"] - r[key]["min"], r[key]["max"] - r[key]["median"]] for r in rows]).T
        ax.barh(y + (k - 1.5) * 0.2, med, height=0.19, color=colour, label=text, xerr=err, capsize=2)
    ax.set_xscale("log")
    ax.set_yticks(y, labels)
    ax.invert_yaxis()
    ax.set_xlabel(f"seconds for t = 0..{T_END:g} s (median; bars min-max over the rounds)")
    ax.set_title("MuJoCo's time in the comparison harness, same model and steps", fontsize=10)
    ax.grid(axis="x", which="both", alpha=0.3)
    ax.legend(fontsize=8, loc="lower right")
    return fig


def measure_all(args, log) -> dict:
    cases = [c for c in CASES if not args.cases or f"{c[0]}:{c[1]}" in args.cases]
    return {"t_end": T_END, "samples": SAMPLES, "rounds": args.rounds, "rows": [measure(c, args.rounds, log) for c in cases]}


def render(data):
    for r in data["rows"]:
        r.update(comparisons(r))
    return table(data["rows"]), plot(data["rows"])


def options(p):
    p.add_argument("--cases", nargs="+", help="only these cases, as scene:integrator (e.g. ur5_falling:Euler)")


if __name__ == "__main__":
    run_benchmark("mujoco_harness", __doc__, measure_all, render, options=options)

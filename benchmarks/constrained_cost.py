"""Cost of one constrained right-hand-side evaluation against the same scene with its constraints removed
(issue 45's target: at most 1.5x), and of a whole constrained run against MuJoCo's.

Timed regions, per scene (interleaved rounds; each figure the median (min-max) over the rounds):

* ``free``: a numba loop of ``K`` calls of :func:`urdf2links.scenes.scene_kernels.scene_rhs` (the function the
  compiled integrators call) on the scene compiled WITHOUT its constraint rows (``CompiledScene(plan,
  rows=False)``: every other term the scene names, its fixed tendons included), at one state, divided by ``K``;
* ``constrained``: the same loop on the scene's own compiled right-hand side (the free forces, the fixed
  tendons (E76), the constraint terms from the same kinematics pass, the KKT block elimination with the
  pivoted Schur factorisation (E72, E88)), at the same state (projected onto the constraints first);
* ``ratio``: constrained / free (the target: at most 1.5);
* ``run``: ``simulate(scene)`` with the scene's method and tolerances (compiled loops, projection after every
  step, E74): its ``wall_time`` (the loop only; numba's compilation outside, warmed first) and evaluations;

Wall time against MuJoCo at MuJoCo's accuracy is the work-precision study's (``urdf2links tradeoff SCENE``,
docs/speed.md), which times MuJoCo with ``mj_step(m, d, nstep=K)``.

The state is the scene's initial one with ``q'`` random (normal, seed 0) projected onto the tangent space, so
that no rate update is skipped. Usage::

    python benchmarks/constrained_cost.py [--evals 20000] [--rounds 5] [--out reports/benchmarks/constrained_cost.json]
    python benchmarks/constrained_cost.py --render-only
"""

from __future__ import annotations

import time
import warnings
import numpy as np

from benchmarking import eval_loop, run_benchmark
from urdf2links.integration.constrained import project_state
from urdf2links.integration.simulate import simulate
from urdf2links.locations import shipped_robots_dir
from urdf2links.scenes.plan import as_plan
from urdf2links.scenes.scene_kernels import CompiledScene
from urdf2links.scenes.scene_read import load_scene, scene_from_dict

LOOPS = shipped_robots_dir() / "loops"


def scenes() -> list:
    """The shipped loops (four-bar, closed leg, parallel gripper, mimic gripper) and dm_control's quadruped with
    its file's couplings (four tendon equalities: one joint coupling per leg) and its fixed tendons."""
    out = [(name, load_scene(LOOPS / f"{name}.toml"))
           for name in ("four_bar_crank", "closed_leg_swing", "gripper2f_close", "mimic_gripper_swing")]
    try:
        import importlib.resources

        path = importlib.resources.files("dm_control") / "suite" / "quadruped.xml"
        data = {"robot": {"mjcf": str(path)}, "gravity": {"magnitude": 9.81}, "constraints": {"from_file": True},
                "run": {"t_end": 0.5, "samples": 21}}
        out.append(("dm_control quadruped (4 couplings)", scene_from_dict(data, where="quadruped.toml")))
    except ModuleNotFoundError:
        pass
    return out


def _state(plan, seed=0):
    q, _ = plan.scene.initial_state(plan.model)
    qd = np.random.default_rng(seed).normal(size=plan.model.n)
    y, _ = project_state(plan.rhs, 0.0, np.r_[q, qd, 0.0])
    return np.ascontiguousarray(y)


def _per_eval(args, y, K) -> float:
    out = np.empty(y.size)
    eval_loop(y, out, 10, *args)
    t0 = time.perf_counter()
    eval_loop(y, out, K, *args)
    return (time.perf_counter() - t0) / K


def measure(args, log) -> dict:
    evals, rounds = args.evals, args.rounds
    rows = []
    for name, scene in scenes():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            plan = as_plan(scene)
        free = CompiledScene(plan, rows=False)
        y = _state(plan)
        figs = {"free": [], "constrained": []}
        for _ in range(rounds):
            figs["free"].append(_per_eval(free.args, y, evals))
            figs["constrained"].append(_per_eval(plan.rhs.args, y, evals))
        ratio = [c / f for c, f in zip(figs["constrained"], figs["free"])]
        best = min(figs["constrained"]) / min(figs["free"])     # the fastest round of each: least disturbed
        simulate(plan, t_end=min(0.01, scene.run.t_end), progress=False)        # warm
        tr = simulate(plan, progress=False)
        c = tr.stats["constraints"]
        rows.append({"scene": name, "n": plan.model.n, "rows": len(c["rows"]), "solved_rows": len(c["solved_rows"]),
                     "tendons": len(plan.constraints.tendons),
                     "free_us": [1e6 * v for v in figs["free"]],
                     "constrained_us": [1e6 * v for v in figs["constrained"]],
                     "ratio": ratio, "ratio_of_fastest": best,
                     "run": {"method": tr.stats["method"], "t_end": float(tr.t[-1]), "rtol": tr.stats["rtol"],
                             "wall_time_s": float(tr.stats["wall_time"]), "nfev": int(tr.stats["nfev"]),
                             "nsteps": int(tr.stats["nsteps"]), "max_residual": float(c["max_residual"])}})
        log(f"{name}: ratio {np.median(ratio):.2f} (free {1e6 * np.median(figs['free']):.2f} us, constrained "
              f"{1e6 * np.median(figs['constrained']):.2f} us); run {tr.stats['wall_time']:.3f} s, {tr.stats['nfev']} "
              f"evaluations, residual {c['max_residual']:.2g}", flush=True)
    return {"evals": evals, "rounds": rounds, "rows": rows}


def _fmt(v):
    v = np.asarray(v)
    return f"{np.median(v):.3g} ({v.min():.3g}-{v.max():.3g})"


def render(data: dict) -> str:
    lines = ["# Constrained evaluations against the same scenes without their constraints", "",
             "`benchmarks/constrained_cost.py` (module doc: what is timed). Issue 45's target: a "
             "constrained evaluation at most 1.5x the free one (judged on the fastest round of each, the least "
             "disturbed by the machine's other load). Each figure the median (min-max) over "
             f"{data['rounds']} interleaved rounds of {data['evals']} evaluations each, one "
             "process. The run: the scene's own method and tolerances over its t_end, wall time of the loop.", "",
             "| scene | n | rows (solved) | tendons | free (us) | constrained (us) | ratio | fastest / fastest | "
             "target | run (method, t_end) | run wall (s) | evaluations | max residual |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in data["rows"]:
        run = r["run"]
        lines.append(f"| {r['scene']} | {r['n']} | {r['rows']} ({r['solved_rows']}) | {r['tendons']} | "
                     f"{_fmt(r['free_us'])} | {_fmt(r['constrained_us'])} | {_fmt(r['ratio'])} | "
                     f"{r['ratio_of_fastest']:.2f} | "
                     f"{'met' if r['ratio_of_fastest'] <= 1.5 else 'not met'} | "
                     f"{run['method']} rtol {run['rtol']:g}, {run['t_end']:g} s | {run['wall_time_s']:.3g} | "
                     f"{run['nfev']} | {run['max_residual']:.2g} |")
    return "\n".join(lines), None


def options(p):
    p.add_argument("--evals", type=int, default=20000, help="evaluations per round (default 20000)")


def main(argv=None):
    return run_benchmark("constrained_cost", __doc__, measure, render, options=options, argv=argv)


if __name__ == "__main__":
    main()

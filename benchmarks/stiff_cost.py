"""What a stiff robot costs the project's integrator: the Allegro hands' default scene against the UR5's,
in the same run. Same process, interleaved rounds, median (min-max).

The corpus's setting (``urdf2links report --corpus``): each robot's default scene (gravity, fixed base,
seeded random q0 within the joint limits, at rest, the URDF's damping: on the hands 3-10 N m s/rad on
finger links of a few grams, eigenvalues to ~2e6 /s), t = 0..0.5 s, the scenes' rtol 1e-10. For each
robot: ``auto`` (the default), ``Radau5`` and ``DOP853`` (the default before ``auto``), their steps,
evaluations (deterministic) and wall times (the integration: :func:`~urdf2links.integration.simulate.simulate`'s
``wall_time``, samples and energies not in it), and each robot's ``auto`` time and evaluations over the
UR5's ``auto``: the issue's bound is 10x (engine times; the tie rule applies to the wall-time ratio).
Usage::

    python benchmarks/stiff_cost.py [--rounds 5] [--t-end 0.5] [--skip-dop853] [--out reports/benchmarks/stiff_cost.json]
"""

from __future__ import annotations

import warnings

import numpy as np

from benchmarking import compare, fmt_ratio, fmt_spread, markdown_table, rounds, run_benchmark, spread
from urdf2links.integration.simulate import simulate, warm_up
from urdf2links.scenes.plan import as_plan
from urdf2links.scenes.default_scenes import default_scene

ROBOTS = {"ur5": "ur_description/urdf/ur5_robot.urdf",
          "allegro_left": "allegro_hand_description/urdf/allegro_left_hand.urdf",
          "allegro_right": "allegro_hand_description/urdf/allegro_right_hand.urdf"}
METHODS = ("auto", "Radau5", "DOP853")
#: the issue's bound on a hand's auto time over the UR5's
BOUND = 10.0


def _plan(path, T):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return as_plan(default_scene(path, t_end=T, q0="random", seed=0))


def measure_all(args, log) -> dict:
    from urdf2links.locations import example_robot_data_dir

    root = example_robot_data_dir()
    if root is None:
        raise SystemExit("stiff_cost: the example-robot-data corpus is not installed (pip install example-robot-data)")
    plans = {name: _plan(root / rel, args.t_end) for name, rel in ROBOTS.items()}
    methods = [m for m in METHODS if not (args.skip_dop853 and m == "DOP853")]
    for plan in plans.values():
        warm_up(plan, methods=tuple(methods))
    counts, variants = {}, {}
    for name, plan in plans.items():
        for m in methods:
            def run(plan=plan, m=m, key=(name, m)):
                tr = simulate(plan, method=m, samples=2, progress=False)
                counts[key] = {"steps": int(tr.stats["nsteps"]), "nfev": int(tr.stats["nfev"]),
                               "njev": int(tr.stats["njev"]), "methods_used": tr.stats["methods_used"]}
                return float(tr.stats["wall_time"])
            variants[f"{name} {m}"] = run
    times = rounds(variants, args.rounds, log=log)
    rows = [{"robot": name, "file": ROBOTS[name], "n": plans[name].model.n, "method": m, "t_end": args.t_end,
             **counts[(name, m)], "wall_s": spread(times[f"{name} {m}"])} for name in plans for m in methods]
    return {"rounds": args.rounds, "t_end": args.t_end, "bound": BOUND, "rows": rows}


def _ratios(data):
    ur5 = next(r for r in data["rows"] if r["robot"] == "ur5" and r["method"] == "auto")
    out = {}
    for r in data["rows"]:
        if r["method"] == "auto" and r["robot"] != "ur5":
            out[r["robot"]] = {"time": compare(r["wall_s"], ur5["wall_s"]), "nfev": r["nfev"] / ur5["nfev"]}
    return out


def table(data) -> str:
    head = ["robot", "n", "method", "ran", "steps", "evaluations", "Jacobians", "wall s, median (min-max)"]
    body = [[r["robot"], r["n"], r["method"], r["methods_used"], r["steps"], r["nfev"], r["njev"],
             fmt_spread(r["wall_s"])] for r in data["rows"]]
    ratios = _ratios(data)
    rh = ["robot", "auto time / UR5's auto time", "auto evaluations / UR5's", f"within {data['bound']:g}x"]
    rb = [[k, fmt_ratio(v["time"]), f"{v['nfev']:.2f}", "yes" if v["time"]["median"] <= data["bound"] else "NO"]
          for k, v in ratios.items()]
    return ("# What a stiff robot costs\n\nThe corpus's default scene (gravity, fixed base, seeded random q0, at rest, "
            f"URDF damping), t = 0..{data['t_end']:g} s, rtol 1e-10; wall time: the integration (simulate()'s "
            "wall_time), median (min-max) of interleaved rounds; evaluations include the Jacobians' differences.\n\n"
            + markdown_table(head, body) + "\n\n## The hands against the UR5\n\nRatio of the medians (min: of the "
            "minima) and the tie rule's verdict; evaluations are deterministic, times are this machine's.\n\n"
            + markdown_table(rh, rb))


def plot(data):
    from urdf2links.compare.figures import figure

    fig = figure(8.0, 4.0, dpi=100)
    ax = fig.subplots()
    colours = {"auto": "#000000", "Radau5": "#00a087", "DOP853": "#2171b5"}
    robots = list(dict.fromkeys(r["robot"] for r in data["rows"]))
    methods = list(dict.fromkeys(r["method"] for r in data["rows"]))
    w = 0.8 / len(methods)
    for j, m in enumerate(methods):
        rows = [next(r for r in data["rows"] if r["robot"] == rb and r["method"] == m) for rb in robots]
        x = np.arange(len(robots)) + (j - (len(methods) - 1) / 2) * w
        med = np.array([r["wall_s"]["median"] for r in rows])
        lo = med - np.array([r["wall_s"]["min"] for r in rows])
        hi = np.array([r["wall_s"]["max"] for r in rows]) - med
        ax.bar(x, med, w, color=colours.get(m, "0.5"), label=m, yerr=[lo, hi], capsize=2)
    ax.set_yscale("log")
    ax.set_xticks(np.arange(len(robots)), robots)
    ax.set_ylabel("integration wall time (s)")
    ax.set_title(f"Default scene, t = 0..{data['t_end']:g} s, rtol 1e-10: median, bars min-max", fontsize=10)
    ax.grid(axis="y", which="both", alpha=0.3)
    ax.legend(fontsize=8)
    return fig


def render(data):
    return table(data), plot(data)


def options(p):
    p.add_argument("--t-end", type=float, default=0.5, help="run length, s (default 0.5: the corpus's)")
    p.add_argument("--skip-dop853", action="store_true", help="leave DOP853 out (about 7 s a run on each hand)")


if __name__ == "__main__":
    run_benchmark("stiff_cost", __doc__, measure_all, render, options=options, rounds_default=5)

"""Cost of one dynamics evaluation: urdf2links forward_dynamics / mass_matrix against MuJoCo's
mj_forward on the same model (route 1: the project's tree as MJCF), in the same process.

Prints a table of median times over interleaved repetitions and the ratios project / MuJoCo, for
n-link chains and for the shipped and (when installed) real robots; both are called from Python
the same way (one call per evaluation, arguments already in arrays). With ``--out`` it also writes
the JSON (machine and versions included), a Markdown table next to it (``.md``) and a plot of cost
against n with fitted slopes (``.png``). ``--render-only`` rewrites the Markdown from the JSON at
``--out`` without timing anything. Usage:

    python benchmarks/eval_cost.py [--reps 300] [--out reports/benchmarks/eval_cost.json]
    python benchmarks/eval_cost.py --render-only --out reports/benchmarks/eval_cost.json
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time
import warnings
from pathlib import Path

import mujoco
import numpy as np

import urdf2links
from urdf2links.compare.mjcf import mjcf_from_model
from urdf2links import LinkSpec, Model, build_tree
from urdf2links.locations import example_robot_data_dir, shipped_robots_dir

ROUNDS = 7   # interleaved rounds of --reps calls each; the median of the rounds' medians is kept
REAL_ROBOTS = ("ur_description/urdf/ur5_robot.urdf", "panda_description/urdf/panda.urdf",
               "talos_data/robots/talos_reduced.urdf", "g1_description/urdf/g1_29dof_rev_1_0.urdf")


def chain(n: int) -> Model:
    """A spatial pendulum of n rods, hinge axes alternating x / y."""
    specs = []
    for i in range(n):
        H = np.zeros((4, 4))
        m, c = 1.0, np.array([0.0, 0.0, -0.25])
        S = np.diag([0.02, 0.02, 0.002]) * 0.5 + m * np.outer(c, c)
        H[:3, :3], H[:3, 3], H[3, :3], H[3, 3] = S, m * c, m * c, m
        specs.append(LinkSpec(f"l{i}", None if i == 0 else f"l{i - 1}", params=(0, 0, 0 if i == 0 else -0.5, 0, 0, 0),
                              coordinates={"phi_x" if i % 2 == 0 else "phi_y": f"q{i}"}, H=H))
    return Model(build_tree(specs), name=f"chain{n}")


def median_time(fn, reps: int) -> float:
    times = []
    for _ in range(reps):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return float(np.median(times))


def measure(model: Model, reps: int) -> dict:
    mj = mjcf_from_model(model, gravity=model.gravity_vector)
    d = mujoco.MjData(mj.model)
    rng = np.random.default_rng(0)
    q, qd = rng.uniform(-1, 1, model.n), rng.normal(size=model.n)
    d.qpos[mj.qpos_index] = q
    d.qvel[mj.dof_index] = qd
    fd, mm, mf = [], [], []
    model.forward_dynamics(q, qd), model.mass_matrix(q)      # compile / load the kernels first
    for _ in range(ROUNDS):  # interleaved rounds, median of each
        fd.append(median_time(lambda: model.forward_dynamics(q, qd), reps))
        mm.append(median_time(lambda: model.mass_matrix(q), reps))
        mf.append(median_time(lambda: mujoco.mj_forward(mj.model, d), reps))
    fd, mm, mf = (float(np.median(x)) for x in (fd, mm, mf))
    return {"robot": model.name, "n": model.n, "forward_dynamics_s": fd, "mass_matrix_s": mm,
            "mj_forward_s": mf, "ratio_forward": fd / mf, "ratio_mass_matrix": mm / mf}


def plot(rows, slope, slope_mj, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    chains = [r for r in rows if r["robot"].startswith("chain")]
    n = np.array([r["n"] for r in chains])
    fig, ax = plt.subplots(figsize=(7, 4.5))
    ax.loglog(n, [1e6 * r["forward_dynamics_s"] for r in chains], "o-", color="C0",
              label=f"urdf2links forward_dynamics (slope {slope:.2f})")
    ax.loglog(n, [1e6 * r["mass_matrix_s"] for r in chains], "s--", color="C0", alpha=0.6,
              label="urdf2links mass_matrix")
    ax.loglog(n, [1e6 * r["mj_forward_s"] for r in chains], "o-", color="C3",
              label=f"MuJoCo mj_forward (slope {slope_mj:.2f})")
    for r in rows:
        if not r["robot"].startswith("chain"):
            ax.plot(r["n"], 1e6 * r["forward_dynamics_s"], "^", color="C0")
            ax.plot(r["n"], 1e6 * r["mj_forward_s"], "^", color="C3")
            ax.annotate(r["robot"], (r["n"], 1e6 * r["forward_dynamics_s"]), fontsize=7,
                        xytext=(3, 3), textcoords="offset points")
    ax.set_xlabel("degrees of freedom n (chains: lines; real robots: triangles)")
    ax.set_ylabel("time per evaluation [us] (median)")
    ax.set_title("Cost of one dynamics evaluation, same process")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _us(seconds: float) -> str:
    us = 1e6 * seconds
    return f"{us:.1f} us" if us < 100 else f"{us:.0f} us"


def render_markdown(data: dict, png: str | None = None, out: str = "reports/benchmarks/eval_cost.json") -> str:
    """The Markdown table of an eval_cost JSON: one row per model, times in microseconds, the ratios to
    mj_forward, the chains' log-log slopes; ``png`` is the plot's file name, linked when given."""
    reps = data.get("reps")
    how = (f"medians of {data.get('rounds', ROUNDS)} interleaved rounds of {reps} calls"
           if reps else f"medians of {data.get('rounds', ROUNDS)} interleaved rounds")
    versions = ", ".join(f"{k} {data[k]}" for k in ("cpus", "python", "numpy", "numba", "mujoco") if k in data)
    lines = ["# Cost of one dynamics evaluation against mj_forward", "",
             f"Generated by `python benchmarks/eval_cost.py --out {out}` "
             "(`--render-only` rewrites this table from the JSON). Both engines called from Python in the "
             f"same process on the same model (the project's tree as MJCF), {how}. "
             f"Machine: {data.get('machine', '?')}; {versions}.", "",
             "| robot | n | forward_dynamics | mass_matrix | mj_forward | forward_dynamics / mj_forward "
             "| mass_matrix / mj_forward |", "|---|---|---|---|---|---|---|"]
    for r in data["rows"]:
        lines.append(f"| {r['robot']} | {r['n']} | {_us(r['forward_dynamics_s'])} | {_us(r['mass_matrix_s'])} | "
                     f"{_us(r['mj_forward_s'])} | {r['ratio_forward']:.1f}x | {r['ratio_mass_matrix']:.1f}x |")
    chains = sorted(r["n"] for r in data["rows"] if r["robot"].startswith("chain"))
    lines += ["", f"Cost growth in a chain (log-log slope of forward_dynamics over n = {chains[0]}..{chains[-1]}): "
              f"urdf2links {data['slope_project']:.2f}, MuJoCo mj_forward {data['slope_mujoco']:.2f}.", "",
              "chainN: a spatial pendulum of N rods, hinges alternating x / y (this script's `chain`); ur5_like: "
              "robots/ur5_like.urdf; the others from example-robot-data (loaded with inertia=\"repair\"): "
              + ", ".join(f"`{p}`" for p in REAL_ROBOTS) + "."]
    if png:
        lines += ["", f"![cost of one evaluation against n]({png})"]
    return "\n".join(lines) + "\n"


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--reps", type=int, default=300)
    parser.add_argument("--out", default=None)
    parser.add_argument("--render-only", action="store_true",
                        help="rewrite the Markdown table from the JSON at --out; time nothing")
    args = parser.parse_args(argv)
    if args.render_only:
        if not args.out:
            parser.error("--render-only needs --out (the JSON to render)")
        out = Path(args.out)
        png = out.with_suffix(".png")
        out.with_suffix(".md").write_text(render_markdown(json.loads(out.read_text()),
                                                          png.name if png.exists() else None, args.out))
        print(f"wrote {out.with_suffix('.md')}")
        return
    models = [chain(n) for n in (2, 4, 8, 16, 32, 64)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        models.append(urdf2links.load_urdf(shipped_robots_dir() / "ur5_like.urdf"))
        root = example_robot_data_dir()
        if root is not None:
            for rel in REAL_ROBOTS:
                models.append(urdf2links.load_urdf(root / rel, inertia="repair"))
    rows = []
    print(f"{'robot':28s} {'n':>3s} {'forward (us)':>13s} {'mass matrix (us)':>17s} {'mj_forward (us)':>16s} {'ratio':>7s}")
    for model in models:
        r = measure(model, args.reps)
        rows.append(r)
        print(f"{r['robot'][:28]:28s} {r['n']:3d} {1e6 * r['forward_dynamics_s']:13.1f} {1e6 * r['mass_matrix_s']:17.1f} "
              f"{1e6 * r['mj_forward_s']:16.2f} {r['ratio_forward']:7.1f}", flush=True)
    chains = [r for r in rows if r["robot"].startswith("chain")]
    slope = np.polyfit(np.log([r["n"] for r in chains]), np.log([r["forward_dynamics_s"] for r in chains]), 1)[0]
    slope_mj = np.polyfit(np.log([r["n"] for r in chains]), np.log([r["mj_forward_s"] for r in chains]), 1)[0]
    print(f"cost growth in a chain (log-log slope): urdf2links {slope:.2f}, MuJoCo {slope_mj:.2f}")
    if args.out:
        import numba

        out = Path(args.out)
        out.parent.mkdir(parents=True, exist_ok=True)
        data = {"machine": platform.platform(), "processor": platform.processor(), "cpus": os.cpu_count(),
                "python": platform.python_version(), "numpy": np.__version__, "numba": numba.__version__,
                "mujoco": mujoco.__version__, "reps": args.reps, "rounds": ROUNDS, "rows": rows,
                "slope_project": slope, "slope_mujoco": slope_mj}
        out.write_text(json.dumps(data, indent=2))
        plot(rows, slope, slope_mj, out.with_suffix(".png"))
        out.with_suffix(".md").write_text(render_markdown(data, out.with_suffix(".png").name, args.out))
        print(f"wrote {out}, {out.with_suffix('.md')} and {out.with_suffix('.png')}")


if __name__ == "__main__":
    main()

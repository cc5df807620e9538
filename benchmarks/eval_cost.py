"""Cost of one dynamics evaluation: urdf2links forward_dynamics / mass_matrix against MuJoCo's
mj_forward on the same model (route 1: the project's tree as MJCF), in the same process.

Prints a table of median times over interleaved repetitions and the ratios project / MuJoCo, for
n-link chains and for the shipped and (when installed) real robots; both are called from Python
the same way (one call per evaluation, arguments already in arrays). With ``--out`` it also writes
the JSON (machine and versions included) and a plot of cost against n with fitted slopes. Usage:

    python benchmarks/eval_cost.py [--reps 300] [--out reports/benchmarks/eval_cost.json]
"""

from __future__ import annotations

import argparse
import json
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
    for _ in range(7):  # interleaved rounds, median of each
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


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--reps", type=int, default=300)
    parser.add_argument("--out", default=None)
    args = parser.parse_args(argv)
    models = [chain(n) for n in (2, 4, 8, 16, 32, 64)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        models.append(urdf2links.load_urdf(shipped_robots_dir() / "ur5_like.urdf"))
        root = example_robot_data_dir()
        if root is not None:
            for rel in ("ur_description/urdf/ur5_robot.urdf", "panda_description/urdf/panda.urdf",
                        "talos_data/robots/talos_reduced.urdf", "g1_description/urdf/g1_29dof_rev_1_0.urdf"):
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
        out.write_text(json.dumps({"machine": platform.platform(), "processor": platform.processor(),
                                   "python": platform.python_version(), "numpy": np.__version__,
                                   "numba": numba.__version__, "mujoco": mujoco.__version__, "rows": rows,
                                   "slope_project": slope, "slope_mujoco": slope_mj}, indent=2))
        plot(rows, slope, slope_mj, out.with_suffix(".png"))
        print(f"wrote {out} and {out.with_suffix('.png')}")


if __name__ == "__main__":
    main()

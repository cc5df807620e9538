"""Cost of one dynamics evaluation: urdf2links forward_dynamics / mass_matrix against MuJoCo's
mj_forward on the same model (route 1: the project's tree as MJCF), in the same process.

Both are called from Python the same way (one call per evaluation, arguments already in arrays);
a round times ``--reps`` calls of each and keeps their median, rounds interleave the three and
each figure is the median (min-max) over the rounds. Models: n-link chains (spatial pendulums,
hinges alternating x / y) and the shipped and (when installed) real robots.

Growth with n, both engines: the **local slope** ``log(t2 / t1) / log(n2 / n1)`` between
neighbouring chain sizes (the curve is not a straight line: fixed per-call costs dominate small
n, the O(n^2) mass matrix and the O(n^3) factorization large n), and a least-squares **fit over
the large-n end** (the :data:`LARGE_N` largest chains). Usage::

    python benchmarks/eval_cost.py [--reps 300] [--rounds 7] [--out reports/benchmarks/eval_cost.json]
    python benchmarks/eval_cost.py --render-only      # the table and plot again from the JSON
"""

from __future__ import annotations

import time

import mujoco
import numpy as np

from benchmarking import fmt_spread, load_models, markdown_table, rounds, run_benchmark, spread
from urdf2links import LinkSpec, Model, build_tree
from urdf2links.compare.mujoco_side.mjcf import mjcf_from_model

CHAIN_SIZES = (2, 4, 8, 16, 24, 32, 48, 64, 96, 128)
#: The fit over the large-n end uses this many of the largest chains.
LARGE_N = 4
REAL = ("ur_description/urdf/ur5_robot.urdf", "panda_description/urdf/panda.urdf",
        "talos_data/robots/talos_reduced.urdf", "g1_description/urdf/g1_29dof_rev_1_0.urdf")
VARIANTS = ("forward_dynamics", "mass_matrix", "mj_forward")


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
    times = np.empty(reps)
    for k in range(reps):
        t0 = time.perf_counter()
        fn()
        times[k] = time.perf_counter() - t0
    return float(np.median(times))


def measure(model: Model, reps: int, n_rounds: int) -> dict:
    mj = mjcf_from_model(model, gravity=model.gravity_vector)
    d = mujoco.MjData(mj.model)
    rng = np.random.default_rng(0)
    q, qd = rng.uniform(-1, 1, model.n), rng.normal(size=model.n)
    d.qpos[mj.qpos_index] = q
    d.qvel[mj.dof_index] = qd
    model.forward_dynamics(q, qd), model.mass_matrix(q)      # compile / load the kernels first
    times = rounds({"forward_dynamics": lambda: median_time(lambda: model.forward_dynamics(q, qd), reps),
                    "mass_matrix": lambda: median_time(lambda: model.mass_matrix(q), reps),
                    "mj_forward": lambda: median_time(lambda: mujoco.mj_forward(mj.model, d), reps)}, n_rounds)
    row = {"robot": model.name, "n": model.n, "chain": model.name.startswith("chain"),
           **{f"{k}_s": spread(v) for k, v in times.items()}}
    row["ratio_forward"] = row["forward_dynamics_s"]["median"] / row["mj_forward_s"]["median"]
    row["ratio_mass_matrix"] = row["mass_matrix_s"]["median"] / row["mj_forward_s"]["median"]
    return row


def growth(chains: list[dict], key: str) -> dict:
    """Local slopes between neighbouring sizes and the fit over the :data:`LARGE_N` largest."""
    n = np.array([r["n"] for r in chains], float)
    t = np.array([r[f"{key}_s"]["median"] for r in chains])
    local = [{"n": [int(n[i]), int(n[i + 1])], "slope": float(np.log(t[i + 1] / t[i]) / np.log(n[i + 1] / n[i]))}
             for i in range(len(n) - 1)]
    k = min(LARGE_N, len(n))
    slope, intercept = np.polyfit(np.log(n[-k:]), np.log(t[-k:]), 1)
    return {"local": local, "large_n": {"n": [int(x) for x in n[-k:]], "slope": float(slope),
                                        "intercept_log_s": float(intercept)}}


def table(rows, slopes) -> str:
    head = ["robot", "n", "forward_dynamics us", "mass_matrix us", "mj_forward us", "forward / mj_forward"]
    body = [[r["robot"], r["n"], fmt_spread(r["forward_dynamics_s"], 1e6), fmt_spread(r["mass_matrix_s"], 1e6),
             fmt_spread(r["mj_forward_s"], 1e6), f"{r['ratio_forward']:.2f}"] for r in rows]
    loc_head = ["chain sizes", "urdf2links forward_dynamics", "MuJoCo mj_forward"]
    loc = [[f"{a['n'][0]} -> {a['n'][1]}", f"{a['slope']:.2f}", f"{b['slope']:.2f}"]
           for a, b in zip(slopes["forward_dynamics"]["local"], slopes["mj_forward"]["local"])]
    big = slopes["forward_dynamics"]["large_n"]
    return ("# Cost of one dynamics evaluation\n\n"
            "Microseconds per call from Python, median (min-max) over interleaved rounds, each round the median of "
            "its calls; same process, same model (route 1).\n\n" + markdown_table(head, body) + "\n\n"
            "## Growth with the number of links (chains)\n\nLocal log-log slope between neighbouring sizes:\n\n"
            + markdown_table(loc_head, loc) + "\n\n"
            f"Fit over the large-n end (n = {', '.join(map(str, big['n']))}): urdf2links forward_dynamics "
            f"{big['slope']:.2f}, MuJoCo mj_forward {slopes['mj_forward']['large_n']['slope']:.2f}; urdf2links "
            f"mass_matrix {slopes['mass_matrix']['large_n']['slope']:.2f}.")


def plot(rows, slopes):
    from urdf2links.compare.figures import figure

    fig = figure(10.5, 4.6, dpi=100)
    ax, bx = fig.subplots(1, 2, width_ratios=[1.4, 1])
    chains = [r for r in rows if r["chain"]]
    n = np.array([r["n"] for r in chains])
    styles = {"forward_dynamics": ("o-", "C0", "urdf2links forward_dynamics"),
              "mass_matrix": ("s--", "C9", "urdf2links mass_matrix"), "mj_forward": ("o-", "C3", "MuJoCo mj_forward")}
    for key, (fmt_, colour, label) in styles.items():
        med = np.array([1e6 * r[f"{key}_s"]["median"] for r in chains])
        err = np.array([[1e6 * (r[f"{key}_s"]["median"] - r[f"{key}_s"]["min"]),
                         1e6 * (r[f"{key}_s"]["max"] - r[f"{key}_s"]["median"])] for r in chains]).T
        big = slopes[key]["large_n"]
        ax.errorbar(n, med, yerr=err, fmt=fmt_, color=colour, capsize=2,
                    label=f"{label} (large-n slope {big['slope']:.2f})")
        nn = np.array(big["n"], float)
        ax.plot(nn, 1e6 * np.exp(big["intercept_log_s"]) * nn ** big["slope"], ":", color=colour, lw=1)
    for r in rows:
        if not r["chain"]:
            ax.plot(r["n"], 1e6 * r["forward_dynamics_s"]["median"], "^", color="C0")
            ax.plot(r["n"], 1e6 * r["mj_forward_s"]["median"], "^", color="C3")
            ax.annotate(r["robot"], (r["n"], 1e6 * r["forward_dynamics_s"]["median"]), fontsize=7, xytext=(3, 3),
                        textcoords="offset points")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("degrees of freedom n (chains: lines; real robots: triangles)")
    ax.set_ylabel("time per evaluation (us): median, bars min-max")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    mid = [np.sqrt(a["n"][0] * a["n"][1]) for a in slopes["forward_dynamics"]["local"]]
    for key in ("forward_dynamics", "mj_forward"):
        _, colour, label = styles[key]
        bx.semilogx(mid, [a["slope"] for a in slopes[key]["local"]], "o-", color=colour, label=label)
    bx.set_xlabel("n (geometric middle of neighbouring sizes)")
    bx.set_ylabel("local slope d log t / d log n")
    bx.axhline(1, color="0.6", lw=0.8, ls=":")
    bx.axhline(2, color="0.6", lw=0.8, ls=":")
    bx.grid(True, which="both", alpha=0.3)
    bx.legend(fontsize=7)
    fig.suptitle("Cost of one dynamics evaluation, same process", fontsize=10)
    return fig


def measure_all(args, log) -> dict:
    models = [chain(n) for n in CHAIN_SIZES] + load_models(("ur5_like.urdf",), REAL)
    rows = []
    for model in models:
        rows.append(measure(model, args.reps, args.rounds))
        r = rows[-1]
        log(f"{r['robot'][:28]:28s} n {r['n']:3d}: forward {fmt_spread(r['forward_dynamics_s'], 1e6)} us, "
            f"mj_forward {fmt_spread(r['mj_forward_s'], 1e6)} us, ratio {r['ratio_forward']:.2f}")
    chains = [r for r in rows if r["chain"]]
    return {"reps": args.reps, "rounds": args.rounds, "rows": rows, "large_n_points": LARGE_N,
            "growth": {k: growth(chains, k) for k in VARIANTS}}


def render(data):
    return table(data["rows"], data["growth"]), plot(data["rows"], data["growth"])


def options(p):
    p.add_argument("--reps", type=int, default=300, help="calls per round and variant (default 300)")


if __name__ == "__main__":
    run_benchmark("eval_cost", __doc__, measure_all, render, options=options, rounds_default=7)

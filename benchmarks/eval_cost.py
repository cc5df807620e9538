"""Cost of every public ``Model`` call against MuJoCo's mj_forward on the same model (route 1: the
project's tree as MJCF), in the same process.

Timed, one call per evaluation from Python, arguments already in arrays: ``forward_dynamics(q, qd)``,
``mass_matrix(q)``, ``bias(q, qd)``, ``gravity(q)``, ``generalized_forces(q, [one Wrench])`` (a force,
a moment and an offset point on the last link), ``kinetic_energy(q, qd)``, ``potential_energy(q)``
and ``mujoco.mj_forward(m, d)``; at one random state (q uniform in [-1, 1], qd normal, seed 0). A
round times ``--reps`` calls of each and keeps their median; rounds interleave all eight (the order
reversed every other round); each figure is the median (min-max) over the rounds, and a model whose
spread is wide is measured again (benchmarking.measured). Each call is compared with mj_forward and
with forward_dynamics under the tie rule (benchmarking.compare): ratio of medians, ratio of minima,
and faster / slower only when the spreads do not overlap. Models: n-link chains (spatial pendulums,
hinges alternating x / y) and the shipped and (when installed) real robots.

Growth with n, both engines: the **local slope** ``log(t2 / t1) / log(n2 / n1)`` between
neighbouring chain sizes (the curve is not a straight line: fixed per-call costs dominate small
n, the O(n^2) mass matrix and the O(n^3) factorization large n), and a least-squares **fit over
the large-n end** (the :data:`LARGE_N` largest chains). Usage::

    python benchmarks/eval_cost.py [--reps 300] [--rounds 7] [--sizes 2 4 ...] [--out reports/benchmarks/eval_cost.json]
    python benchmarks/eval_cost.py --render-only      # the table and plot again from the JSON
"""

from __future__ import annotations

import time

import mujoco
import numpy as np

from benchmarking import (
    chain, compare, fmt_ratio, fmt_spread, load_models, markdown_table, measured, real, run_benchmark, spread,
)
from urdf2links import Model, Wrench
from urdf2links.compare.mujoco_side.mjcf import mjcf_from_model

CHAIN_SIZES = (2, 4, 8, 16, 24, 32, 48, 64, 96, 128)
#: The fit over the large-n end uses this many of the largest chains.
LARGE_N = 4
#: Every public call of Model, in the tables' order.
CALLS = ("forward_dynamics", "mass_matrix", "bias", "gravity", "generalized_forces", "kinetic_energy",
         "potential_energy")
VARIANTS = (*CALLS, "mj_forward")
#: The curves of the growth section and the plot.
GROWTH = ("forward_dynamics", "mass_matrix", "mj_forward")


def median_time(fn, reps: int) -> float:
    times = np.empty(reps)
    for k in range(reps):
        t0 = time.perf_counter()
        fn()
        times[k] = time.perf_counter() - t0
    return float(np.median(times))


def calls(model: Model, q, qd) -> dict:
    """Each public call of ``model`` at ``(q, qd)``, as a function of nothing."""
    loads = [Wrench(model.link_names[-1], force=[1.0, -2.0, 3.0], moment=[0.1, 0.2, -0.3], point=[0.05, 0.0, -0.1])]
    return {"forward_dynamics": lambda: model.forward_dynamics(q, qd), "mass_matrix": lambda: model.mass_matrix(q),
            "bias": lambda: model.bias(q, qd), "gravity": lambda: model.gravity(q),
            "generalized_forces": lambda: model.generalized_forces(q, loads),
            "kinetic_energy": lambda: model.kinetic_energy(q, qd), "potential_energy": lambda: model.potential_energy(q)}


def measure(model: Model, reps: int, n_rounds: int, log=None) -> dict:
    mj = mjcf_from_model(model, gravity=model.gravity_vector)
    d = mujoco.MjData(mj.model)
    rng = np.random.default_rng(0)
    q, qd = rng.uniform(-1, 1, model.n), rng.normal(size=model.n)
    d.qpos[mj.qpos_index] = q
    d.qvel[mj.dof_index] = qd
    ours = calls(model, q, qd)
    for fn in ours.values():                                 # compile / load the kernels first
        fn()
    variants = {k: (lambda fn=fn: median_time(fn, reps)) for k, fn in ours.items()}
    variants["mj_forward"] = lambda: median_time(lambda: mujoco.mj_forward(mj.model, d), reps)
    times, attempts = measured(variants, n_rounds, log=log)
    row = {"robot": model.name, "n": model.n, "chain": model.name.startswith("chain"), "attempts": attempts,
           **{f"{k}_s": spread(v) for k, v in times.items()}}
    row.update(comparisons(row))
    return row


def comparisons(row) -> dict:
    """Each call against mj_forward and against forward_dynamics, under the tie rule (from the spreads:
    the render recomputes them, so that a table never disagrees with its figures)."""
    return {"vs_mj_forward": {k: compare(row[f"{k}_s"], row["mj_forward_s"]) for k in CALLS},
            "vs_forward_dynamics": {k: compare(row[f"{k}_s"], row["forward_dynamics_s"]) for k in CALLS[1:]}}


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


def table(data) -> str:
    rows, slopes = data["rows"], data["growth"]
    us = markdown_table(["robot", "n", "mj_forward", *CALLS],
                        [[r["robot"], r["n"], fmt_spread(r["mj_forward_s"], 1e6),
                          *(fmt_spread(r[f"{k}_s"], 1e6) for k in CALLS)] for r in rows])
    vs_mj = markdown_table(["robot", "n", *(f"{k} / mj_forward" for k in CALLS)],
                           [[r["robot"], r["n"], *(fmt_ratio(r["vs_mj_forward"][k]) for k in CALLS)] for r in rows])
    vs_fd = markdown_table(["robot", "n", *(f"{k} / forward_dynamics" for k in CALLS[1:])],
                           [[r["robot"], r["n"], *(fmt_ratio(r["vs_forward_dynamics"][k]) for k in CALLS[1:])]
                            for r in rows])
    again = [f"{r['robot']} ({r['attempts']} attempts)" for r in rows if r["attempts"] > 1]
    loc = [[f"{a['n'][0]} -> {a['n'][1]}", f"{a['slope']:.2f}", f"{b['slope']:.2f}"]
           for a, b in zip(slopes["forward_dynamics"]["local"], slopes["mj_forward"]["local"])]
    big = slopes["forward_dynamics"]["large_n"]
    return ("# Cost of every Model call against mj_forward\n\n"
            f"Microseconds per call from Python, median (min-max) over {data['rounds']} interleaved rounds, each round "
            f"the median of its {data['reps']} calls; same process, same model (route 1), one random state. "
            "generalized_forces: one Wrench (force, moment, offset point) on the last link.\n\n" + us + "\n\n"
            "## Against mj_forward\n\nEach call's time over mj_forward's: ratio of the medians, (min: ratio of the "
            "minima), and the verdict of the tie rule: faster or slower only when the spreads over the rounds do not "
            "overlap, else tie.\n\n" + vs_mj + "\n\n"
            "## Against forward_dynamics\n\nEach call's time over forward_dynamics' (what one evaluation of q'' "
            "costs), same rule.\n\n" + vs_fd + "\n\n"
            + (f"Measured again for a wide spread (max/min > {data['wide']:g}): {', '.join(again)}.\n\n" if again else "")
            + "## Growth with the number of links (chains)\n\nLocal log-log slope between neighbouring sizes:\n\n"
            + markdown_table(["chain sizes", "urdf2links forward_dynamics", "MuJoCo mj_forward"], loc) + "\n\n"
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
    from benchmarking import WIDE

    models = [chain(n) for n in args.sizes] + load_models(("ur5_like.urdf",), real("ur5", "panda", "talos", "g1"))
    rows = []
    for model in models:
        rows.append(measure(model, args.reps, args.rounds, log))
        r = rows[-1]
        log(f"{r['robot'][:28]:28s} n {r['n']:3d}: forward {fmt_spread(r['forward_dynamics_s'], 1e6)} us, "
            f"mj_forward {fmt_spread(r['mj_forward_s'], 1e6)} us: {fmt_ratio(r['vs_mj_forward']['forward_dynamics'])}")
    chains = [r for r in rows if r["chain"]]
    return {"reps": args.reps, "rounds": args.rounds, "wide": WIDE, "rows": rows, "large_n_points": LARGE_N,
            "growth": {k: growth(chains, k) for k in GROWTH}}


def render(data):
    for r in data["rows"]:
        r.update(comparisons(r))
    return table(data), plot(data["rows"], data["growth"])


def options(p):
    p.add_argument("--reps", type=int, default=300, help="calls per round and variant (default 300)")
    p.add_argument("--sizes", type=int, nargs="+", default=list(CHAIN_SIZES),
                   help=f"chain sizes (default {' '.join(map(str, CHAIN_SIZES))}; at least 2 for the slopes)")


if __name__ == "__main__":
    run_benchmark("eval_cost", __doc__, measure_all, render, options=options, rounds_default=7)

"""Cost of one right-hand-side evaluation inside the project's compiled loops against one MuJoCo
Euler step in MuJoCo's own C loop, same model (route 1), gravity only, one process.

Timed regions, per model (interleaved rounds; each figure the median (min-max) over the rounds; a
model whose spread is wide is measured again):

* ``rhs``: a numba loop of ``K`` calls of :func:`urdf2links.scenes.scene_kernels.scene_rhs` (the function
  the compiled integrators call: ``y' = (q', q'', P)`` of ``y = (q, q', W)``, gravity only, fixed
  base, no springs or dampers) at one state, divided by ``K``; no Python inside the region. The
  state has random ``q`` (uniform in [-1, 1]) and random ``q'`` (normal), as eval_cost's: at
  ``q' = 0`` the kernels skip every rate update.
* ``rk4``: :func:`urdf2links.integration.integrators.integrate` with the compiled RK4 loop, ``dt`` 1e-4 s, for
  ``K / 4`` steps: its ``wall_time`` (the loop: stages, storage of every step) divided by the number
  of evaluations (4 per step, + 1).
* ``mj_step``: ``mujoco.mj_step(m, d, nstep=K)`` on the route-1 model
  (:func:`urdf2links.compare.mujoco_side.mjcf.mjcf_from_model`: contacts, limits, equality and friction loss
  disabled), Euler, ``dt`` 1e-4 s, energy flag off, no control callback, from the same ``(q, q')``,
  divided by ``K``: one forward dynamics plus the integration, in MuJoCo's C loop.

``K`` is ``--evals`` for n <= 8 and ``--evals * 8 / n`` (at least 2000) above: the table gives each
row's. Issue 14's target: ``rhs`` at or below one ``mj_step``, under the tie rule: **met** when the
rhs's slowest round beats mj_step's fastest, **tie** when the spreads overlap, **not met**
otherwise. From Python (``forward_dynamics`` against ``mj_forward``) see ``benchmarks/eval_cost.py``.
Chains (spatial pendulums, ``benchmarking.chain``) give the growth with n as local slopes. Usage::

    python benchmarks/loop_cost.py [--evals 20000] [--rounds 5] [--models double_pendulum chain8 ...] [--out reports/benchmarks/loop_cost.json]
    python benchmarks/loop_cost.py --render-only
"""

from __future__ import annotations

import time
from pathlib import Path

import mujoco
import numpy as np

from benchmarking import (
    WIDE, chain, compare, eval_loop, fmt_ratio, fmt_spread, load_models, markdown_table, measured, real, run_benchmark,
    spread,
)
from urdf2links.compare.mujoco_side.mjcf import mjcf_from_model
from urdf2links.integration.integrators import integrate
from urdf2links.scenes.plan import compile_plan
from urdf2links.scenes.scene import Scene

CHAINS = (8, 16, 32, 64)
DT = 1e-4
VARIANTS = ("rhs", "rk4", "mj_step")


def models() -> list:
    """The shipped double pendulum and UR5-like arm, example-robot-data's UR5, Panda, Talos (reduced)
    and G1 (29 dof) when installed, and the chains."""
    out = load_models(("double_pendulum.urdf", "ur5_like.urdf"), real("ur5", "panda", "talos", "g1"))
    return out + [chain(n) for n in CHAINS]


def gravity_plan(model):
    """The compiled plan of ``model`` under gravity alone (fixed base, no springs, dampers or loads)."""
    scene = Scene(name="gravity", path=None, robot=Path(model.name or "model"), load_options={},
                  gravity=np.asarray(model.gravity_vector, float))
    return compile_plan(scene, model)


def measure(model, K: int, n_rounds: int, log=None) -> dict:
    plan = gravity_plan(model)
    rng = np.random.default_rng(0)
    q, qd = rng.uniform(-1, 1, model.n), rng.normal(size=model.n)
    y0 = np.r_[q, qd, 0.0]
    out = np.empty(y0.size)
    mj = mjcf_from_model(model, gravity=model.gravity_vector, timestep=DT, integrator="Euler")
    m = mj.model
    m.opt.enableflags &= ~int(mujoco.mjtEnableBit.mjENBL_ENERGY)
    d = mujoco.MjData(m)
    steps = max(K // 4, 1)
    counts = {}

    def rhs():
        t0 = time.perf_counter()
        eval_loop(y0, out, K, *plan.rhs.args)
        return (time.perf_counter() - t0) / K

    def rk4():
        res = integrate(plan.rhs, (0.0, steps * DT), y0, method="RK4", dt=DT)
        counts["rk4"] = res.nfev
        return res.wall_time / res.nfev

    def step():
        mujoco.mj_resetData(m, d)
        mj.set_state(d, q, qd)
        t0 = time.perf_counter()
        mujoco.mj_step(m, d, nstep=K)
        return (time.perf_counter() - t0) / K

    eval_loop(y0, out, 10, *plan.rhs.args)                  # compile / load first
    integrate(plan.rhs, (0.0, 4 * DT), y0, method="RK4", dt=DT)
    times, attempts = measured({"rhs": rhs, "rk4": rk4, "mj_step": step}, n_rounds, log=log)
    row = {"robot": model.name, "n": model.n, "chain": model.name.startswith("chain"), "evals": K,
           "rk4_nfev": counts["rk4"], "attempts": attempts, **{f"{k}_s": spread(v) for k, v in times.items()}}
    row.update(comparisons(row))
    return row


def comparisons(row) -> dict:
    """rhs and RK4 against mj_step under the tie rule, and the target's verdict (from the spreads: the
    render recomputes them)."""
    rhs = compare(row["rhs_s"], row["mj_step_s"])
    return {"rhs_vs_mj_step": rhs, "rk4_vs_mj_step": compare(row["rk4_s"], row["mj_step_s"]),
            "target": {"faster": "met", "tie": "tie", "slower": "not met"}[rhs["verdict"]]}


def slopes(rows, key) -> list[dict]:
    ch = [r for r in rows if r["chain"]]
    return [{"n": [a["n"], b["n"]], "slope": float(np.log(b[f"{key}_s"]["median"] / a[f"{key}_s"]["median"])
                                                  / np.log(b["n"] / a["n"]))} for a, b in zip(ch, ch[1:])]


def table(data) -> str:
    rows = data["rows"]
    head = ["robot", "n", "evaluations per region", "rhs in a compiled loop us", "RK4 loop us/eval",
            "MuJoCo Euler mj_step us", "rhs / mj_step", "RK4 / mj_step", "target: rhs at or below mj_step"]
    body = [[r["robot"], r["n"], r["evals"], fmt_spread(r["rhs_s"], 1e6), fmt_spread(r["rk4_s"], 1e6),
             fmt_spread(r["mj_step_s"], 1e6), fmt_ratio(r["rhs_vs_mj_step"]), fmt_ratio(r["rk4_vs_mj_step"]),
             r["target"]] for r in rows]
    again = [f"{r['robot']} ({r['attempts']} attempts)" for r in rows if r["attempts"] > 1]
    sl = data["slopes"]
    loc = [[f"{a['n'][0]} -> {a['n'][1]}", f"{a['slope']:.2f}", f"{b['slope']:.2f}"]
           for a, b in zip(sl["rhs"], sl["mj_step"])]
    return ("# One evaluation inside compiled loops against one MuJoCo Euler step\n\n"
            f"Microseconds per evaluation, median (min-max) over {data['rounds']} interleaved rounds in one process, "
            "at one random state (q uniform in [-1, 1], q' normal). **rhs**: a numba loop of scene_rhs calls "
            "(gravity only, fixed base). **RK4 loop**: the compiled RK4 integrator's wall time (dt 1e-4 s, stages and "
            "storage included) per evaluation. **mj_step**: mj_step(m, d, nstep=K) on the route-1 model, Euler, "
            "dt 1e-4 s, energy flag off, no callback, from the same state: one forward dynamics and the integration "
            "per step. Ratios: of the medians, (min: of the minima), and the tie rule's verdict (faster or slower "
            "only when the spreads do not overlap). Target: met when faster, tie when the spreads overlap. From "
            "Python: [eval_cost.md](eval_cost.md).\n\n" + markdown_table(head, body) + "\n\n"
            + (f"Measured again for a wide spread (max/min > {data['wide']:g}): {', '.join(again)}.\n\n" if again else "")
            + "## Growth with n (chains): local log-log slopes\n\n"
            + markdown_table(["chain sizes", "urdf2links rhs", "MuJoCo mj_step"], loc))


def plot(data):
    from urdf2links.compare.figures import figure

    rows = data["rows"]
    fig = figure(11.0, 4.6, dpi=100)
    ax, bx = fig.subplots(1, 2, width_ratios=[1.6, 1])
    x = np.arange(len(rows))
    styles = (("rhs", "#2171b5", "urdf2links rhs in a compiled loop"), ("rk4", "#6baed6", "urdf2links RK4 loop per eval"),
              ("mj_step", "#cb181d", "MuJoCo Euler mj_step(nstep)"))
    for k, (key, colour, label) in enumerate(styles):
        med = np.array([1e6 * r[f"{key}_s"]["median"] for r in rows])
        err = np.array([[1e6 * (r[f"{key}_s"]["median"] - r[f"{key}_s"]["min"]),
                         1e6 * (r[f"{key}_s"]["max"] - r[f"{key}_s"]["median"])] for r in rows]).T
        ax.bar(x + (k - 1) * 0.27, med, 0.26, color=colour, label=label, yerr=err, capsize=2)
    ax.set_yscale("log")
    ax.set_xticks(x, [f"{r['robot']}\nn={r['n']}" for r in rows], fontsize=7, rotation=45, ha="right")
    ax.set_ylabel("us per evaluation (median; bars min-max)")
    ax.grid(axis="y", which="both", alpha=0.3)
    ax.legend(fontsize=7)
    bx.bar(x - 0.2, [r["rhs_vs_mj_step"]["median"] for r in rows], 0.4, color="#2171b5", label="rhs / mj_step")
    bx.bar(x + 0.2, [r["rk4_vs_mj_step"]["median"] for r in rows], 0.4, color="#6baed6", label="RK4 per eval / mj_step")
    bx.plot(x - 0.2, [r["rhs_vs_mj_step"]["min"] for r in rows], "k_", ms=9, label="ratio of the minima")
    bx.plot(x + 0.2, [r["rk4_vs_mj_step"]["min"] for r in rows], "k_", ms=9)
    for xi, r in zip(x, rows):
        if r["rhs_vs_mj_step"]["verdict"] == "tie":
            bx.annotate("tie", (xi - 0.2, r["rhs_vs_mj_step"]["median"]), fontsize=6, ha="center",
                        xytext=(0, 2), textcoords="offset points")
    bx.axhline(1.0, color="0.3", lw=1, ls="--", label="target 1.0")
    bx.set_xticks(x, [r["robot"] for r in rows], fontsize=7, rotation=45, ha="right")
    bx.set_ylabel("ratio to one MuJoCo Euler step (of the medians)")
    bx.grid(axis="y", alpha=0.3)
    bx.legend(fontsize=7)
    fig.suptitle("One evaluation in compiled loops against one MuJoCo Euler step (same model, one process)",
                 fontsize=10)
    return fig


def measure_all(args, log) -> dict:
    rows = []
    for model in models():
        if args.models and model.name not in args.models:
            continue
        K = max(2000, min(args.evals, int(args.evals * 8 / max(model.n, 1))))
        rows.append(measure(model, K, args.rounds, log))
        r = rows[-1]
        log(f"{r['robot'][:24]:24s} n {r['n']:3d}: rhs {fmt_spread(r['rhs_s'], 1e6)} us, rk4 "
            f"{fmt_spread(r['rk4_s'], 1e6)} us, mj_step {fmt_spread(r['mj_step_s'], 1e6)} us: "
            f"{fmt_ratio(r['rhs_vs_mj_step'])}")
    return {"evals": args.evals, "rounds": args.rounds, "wide": WIDE, "dt": DT, "rows": rows,
            "slopes": {k: slopes(rows, k) for k in VARIANTS}}


def render(data):
    for r in data["rows"]:
        r.update(comparisons(r))
    return table(data), plot(data)


def options(p):
    p.add_argument("--evals", type=int, default=20000, help="evaluations (steps) per timed region for n <= 8; "
                   "fewer for larger n, at least 2000 (default 20000)")
    p.add_argument("--models", nargs="+", help="only these models, by name (e.g. double_pendulum chain8)")


if __name__ == "__main__":
    run_benchmark("loop_cost", __doc__, measure_all, render, options=options)

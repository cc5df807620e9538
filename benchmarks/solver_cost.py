"""Where the time of a run goes: evaluations against wall time in the project's integrators, and
what a sweep saves. Same process, interleaved rounds, median (min-max).

For each scene: the compiled loop (DOP853, RK4, midpoint), the same methods with Python loops
(scipy's OdeSolver / the Python RK4 and midpoint) on the same compiled right-hand side, and the
cost of one evaluation inside a compiled loop; "loop overhead" is wall / (nfev x evaluation cost).
Wall times are :func:`urdf2links.integration.integrators.integrate`'s (the integration, no samples).

Then a sweep of ``B`` initial states: :func:`urdf2links.integration.batch.simulate_batch` (numba threads)
against ``B`` calls of :func:`~urdf2links.integration.integrators.integrate` one after the other, both returning
the same outputs: the states ``(q, qd, W)`` at the same sample times (the batch lands its steps on
them, a single run reads them from its dense output). Each side is the whole call (the batch's
plan compilation and allocations; the single runs' Python per call). Usage::

    python benchmarks/solver_cost.py [--t-end 2] [--batch 32] [--rounds 3] [--out reports/benchmarks/solver_cost.json]
"""

from __future__ import annotations

import time

import numba
import numpy as np

from benchmarking import compare, eval_loop, fmt_ratio, fmt_spread, markdown_table, rounds, run_benchmark, spread
from urdf2links.integration.batch import simulate_batch
from urdf2links.integration.integrators import integrate
from urdf2links.locations import shipped_robots_dir
from urdf2links.scenes.plan import compile_plan
from urdf2links.scenes.scene_read import load_scene

SCENES = ("double_pendulum_chaos", "ur5_falling", "spring_arm_torques", "ship_crane")
SWEEP_SCENES = ("double_pendulum_chaos", "ur5_falling")
SWEEP_SAMPLES = 101


def eval_cost(plan, y):
    """Seconds per evaluation of the compiled right-hand side inside a compiled loop (best of 5)."""
    out = np.empty(y.size)
    eval_loop(y, out, 10, *plan.rhs.args)
    best = np.inf
    for _ in range(5):
        t0 = time.perf_counter()
        eval_loop(y, out, 20000, *plan.rhs.args)
        best = min(best, (time.perf_counter() - t0) / 20000)
    return best


def loops_rows(name, T, n_rounds, log) -> list[dict]:
    scene = load_scene(shipped_robots_dir() / f"{name}.toml")
    model = scene.model()
    plan = compile_plan(scene, model)
    q, qd = scene.initial_state(model)
    y0 = np.r_[q, qd, 0.0]
    T = min(T, scene.run.t_end)
    ev = eval_cost(plan, y0)
    rows = []
    for method, kw in (("DOP853", dict(rtol=scene.run.rtol, atol=scene.run.atol)), ("RK4", dict(dt=1e-3)),
                       ("midpoint", dict(dt=1e-3, rtol=1e-10, atol=1e-12))):
        counts = {}

        def run(loop, rhs, method=method, kw=kw):
            res = integrate(rhs, (0.0, T), y0, method=method, **kw)
            counts[loop] = (res.nfev, res.nsteps)
            return res.wall_time

        integrate(plan.rhs, (0.0, min(T, 0.01)), y0, method=method, **kw)   # compile / load first
        times = rounds({"compiled": lambda: run("compiled", plan.rhs),
                        "python": lambda: run("python", lambda t, y: plan.rhs(t, y))}, n_rounds)
        row = {"scene": name, "n": model.n, "method": method, "t_end": T, "eval_us": 1e6 * ev}
        for loop in ("compiled", "python"):
            s = spread(times[loop])
            nfev, nsteps = counts[loop]
            row.update({f"{loop}_wall": s, f"{loop}_nfev": nfev, f"{loop}_steps": nsteps,
                        f"{loop}_us_per_eval": 1e6 * s["median"] / nfev, f"{loop}_overhead": s["median"] / (nfev * ev)})
        rows.append(row)
        log(f"{name:24s} {method:9s} eval {1e6 * ev:6.2f} us | compiled {fmt_spread(row['compiled_wall'])} s "
            f"(x{row['compiled_overhead']:.2f}) | python loop {fmt_spread(row['python_wall'])} s (x{row['python_overhead']:.1f})")
    return rows


def sweep_row(name, T, B, n_rounds, log) -> dict:
    scene = load_scene(shipped_robots_dir() / f"{name}.toml")
    model = scene.model()
    q, qd = scene.initial_state(model)
    T = min(T, scene.run.t_end)
    rng = np.random.default_rng(0)
    Q0 = q + 0.01 * rng.normal(size=(B, model.n))
    QD0 = np.tile(qd, (B, 1))
    ts = np.linspace(0.0, T, SWEEP_SAMPLES)
    tol = dict(rtol=scene.run.rtol, atol=scene.run.atol)
    plan = compile_plan(scene, model)
    simulate_batch(scene, Q0[:2], QD0[:2], t_end=T, samples=SWEEP_SAMPLES, model=model)   # compile / load first
    integrate(plan.rhs, (0.0, T), np.r_[Q0[0], QD0[0], 0.0], method="DOP853", t_eval=ts, **tol)
    out = {}

    def batch():
        out["batch"] = simulate_batch(scene, Q0, QD0, t_end=T, samples=SWEEP_SAMPLES, model=model, method="DOP853", **tol)

    def singles():
        out["single"] = [integrate(plan.rhs, (0.0, T), np.r_[Q0[b], QD0[b], 0.0], method="DOP853", t_eval=ts, **tol)
                         for b in range(B)]

    times = rounds({"batch": batch, "one at a time": singles}, n_rounds)
    diff = max(float(np.max(np.abs(out["batch"].q[b] - out["single"][b].y[:, :model.n]))) for b in range(B))
    row = {"scene": name, "B": B, "t_end": T, "samples": SWEEP_SAMPLES, "threads": numba.get_num_threads(),
           "outputs": "(q, qd, W) at the same sample times", "batch_s": spread(times["batch"]),
           "single_s": spread(times["one at a time"]), "batch_nfev_mean": float(np.mean(out["batch"].nfev)),
           "single_nfev_mean": float(np.mean([r.nfev for r in out["single"]])), "max_difference": diff,
           "success": bool(out["batch"].success)}
    row["batch_vs_single"] = compare(row["batch_s"], row["single_s"])       # the render recomputes it
    log(f"sweep {name}: {B} trajectories, batch {fmt_spread(row['batch_s'])} s vs one at a time "
        f"{fmt_spread(row['single_s'])} s (batch / single {fmt_ratio(row['batch_vs_single'])}; {row['threads']} threads)")
    return row


def table(rows, sweeps) -> str:
    head = ["scene", "n", "method", "eval us", "compiled loop s", "us/eval", "overhead", "Python loop s", "us/eval",
            "overhead"]
    body = [[r["scene"], r["n"], r["method"], f"{r['eval_us']:.2f}", fmt_spread(r["compiled_wall"]),
             f"{r['compiled_us_per_eval']:.2f}", f"{r['compiled_overhead']:.2f}", fmt_spread(r["python_wall"]),
             f"{r['python_us_per_eval']:.1f}", f"{r['python_overhead']:.1f}"] for r in rows]
    sh = ["scene", "B", "threads", "batch s", "one at a time s", "batch / one at a time",
          "evaluations per trajectory (batch / single)", "max difference"]
    sb = [[s["scene"], s["B"], s["threads"], fmt_spread(s["batch_s"]), fmt_spread(s["single_s"]),
           fmt_ratio(s["batch_vs_single"]), f"{s['batch_nfev_mean']:.0f} / {s['single_nfev_mean']:.0f}",
           f"{s['max_difference']:.1e}"] for s in sweeps]
    return ("# Where the time of a run goes\n\nIntegration wall times (integrate(), no samples), median (min-max) of "
            "interleaved rounds; overhead = wall / (evaluations x one evaluation's cost in a compiled loop).\n\n"
            + markdown_table(head, body) + "\n\n## Sweeps\n\nsimulate_batch against the same number of integrate() "
            "calls one after the other; both return (q, qd, W) at the same sample times (DOP853, the scene's "
            "tolerances). batch / one at a time: ratio of the medians, (min: of the minima), and the tie rule's "
            "verdict (faster or slower only when the spreads do not overlap).\n\n" + markdown_table(sh, sb))


def plot(rows):
    from urdf2links.compare.figures import figure

    fig = figure(9.0, 4.0, dpi=100)
    ax = fig.subplots()
    labels = [f"{r['scene']}\n{r['method']}" for r in rows]
    x = np.arange(len(rows))
    ax.bar(x - 0.2, [r["compiled_overhead"] for r in rows], 0.4, color="#2171b5", label="compiled loop")
    ax.bar(x + 0.2, [r["python_overhead"] for r in rows], 0.4, color="#fd8d3c", label="Python loop")
    ax.set_yscale("log")
    ax.axhline(1.0, color="0.4", lw=0.8, ls=":")
    ax.set_xticks(x, labels, fontsize=6.5, rotation=60, ha="right")
    ax.set_ylabel("wall / (evaluations x evaluation cost)")
    ax.set_title("Integration loop overhead per evaluation (median of the rounds)", fontsize=10)
    ax.grid(axis="y", which="both", alpha=0.3)
    ax.legend(fontsize=8)
    return fig


def measure_all(args, log) -> dict:
    rows = [r for name in SCENES for r in loops_rows(name, args.t_end, args.rounds, log)]
    sweeps = [sweep_row(name, args.t_end, args.batch, args.rounds, log) for name in SWEEP_SCENES]
    return {"rounds": args.rounds, "rows": rows, "sweeps": sweeps}


def render(data):
    for s in data["sweeps"]:
        s["batch_vs_single"] = compare(s["batch_s"], s["single_s"])
    return table(data["rows"], data["sweeps"]), plot(data["rows"])


def options(p):
    p.add_argument("--t-end", type=float, default=2.0, help="run length, s (default 2, at most the scene's)")
    p.add_argument("--batch", type=int, default=32, help="trajectories of a sweep (default 32)")


if __name__ == "__main__":
    run_benchmark("solver_cost", __doc__, measure_all, render, options=options, rounds_default=3)

"""Where the time of a run goes: evaluations against wall time in the project's integrators, and
what a sweep saves. Same process, interleaved repetitions, medians. Usage:

    python benchmarks/solver_cost.py [--out reports/benchmarks/solver_cost.json]

For each scene: the compiled loop (DOP853, RK4, midpoint), the same methods with Python loops
(scipy's OdeSolver / the Python RK4 and midpoint) on the same compiled right-hand side, and the
cost of one evaluation inside a compiled loop; "loop overhead" is wall / (nfev x evaluation cost).
Then a sweep of B initial states (simulate_batch) against B calls of simulate().
"""

from __future__ import annotations

import argparse
import json
import platform
import time
from pathlib import Path

import numpy as np
from numba import njit

from urdf2links.batch import simulate_batch
from urdf2links.integrators import integrate
from urdf2links.locations import shipped_robots_dir
from urdf2links.plan import compile_plan
from urdf2links.scene import load_scene
from urdf2links.scene_kernels import scene_rhs
from urdf2links.simulate import simulate

SCENES = ("double_pendulum_chaos", "ur5_falling", "spring_arm_torques", "ship_crane")


@njit(cache=True)
def _eval_loop(y, out, reps, I, F, W, SI, SF, X):
    for r in range(reps):
        scene_rhs(0.01 * r, y, out, I, F, W, SI, SF, X)


def eval_cost(plan, y):
    out = np.empty(y.size)
    _eval_loop(y, out, 10, *plan.rhs.args)
    best = np.inf
    for _ in range(5):
        t0 = time.perf_counter()
        _eval_loop(y, out, 20000, *plan.rhs.args)
        best = min(best, (time.perf_counter() - t0) / 20000)
    return best


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=None)
    parser.add_argument("--t-end", type=float, default=2.0)
    parser.add_argument("--batch", type=int, default=32)
    args = parser.parse_args(argv)
    rows, sweeps = [], []
    for name in SCENES:
        scene = load_scene(shipped_robots_dir() / f"{name}.toml")
        model = scene.model()
        plan = compile_plan(scene, model)
        q, qd = scene.initial_state(model)
        y0 = np.r_[q, qd, 0.0]
        T = min(args.t_end, scene.run.t_end)
        ev = eval_cost(plan, y0)
        configs = [("DOP853", dict(rtol=scene.run.rtol, atol=scene.run.atol)),
                   ("RK4", dict(dt=1e-3)), ("midpoint", dict(dt=1e-3, rtol=1e-10, atol=1e-12))]
        for method, kw in configs:
            walls = {"compiled": [], "python": []}
            for _ in range(3):
                for loop, rhs in (("compiled", plan.rhs), ("python", lambda t, y: plan.rhs(t, y))):
                    res = integrate(rhs, (0.0, T), y0, method=method, **kw)
                    walls[loop].append(res.wall_time)
                    walls[loop + "_nfev"] = res.nfev
                    walls[loop + "_steps"] = res.nsteps
            row = {"scene": name, "n": model.n, "method": method, "t_end": T, "eval_us": 1e6 * ev}
            for loop in ("compiled", "python"):
                w = float(np.median(walls[loop]))
                row.update({f"{loop}_wall_s": w, f"{loop}_nfev": walls[loop + "_nfev"],
                            f"{loop}_steps": walls[loop + "_steps"],
                            f"{loop}_us_per_eval": 1e6 * w / walls[loop + "_nfev"],
                            f"{loop}_overhead": w / (walls[loop + "_nfev"] * ev)})
            rows.append(row)
            print(f"{name:24s} {method:9s} eval {1e6 * ev:6.2f} us | compiled {row['compiled_wall_s']:8.4f} s "
                  f"({row['compiled_us_per_eval']:6.2f} us/eval, x{row['compiled_overhead']:.2f}) | python loop "
                  f"{row['python_wall_s']:8.3f} s ({row['python_us_per_eval']:6.1f} us/eval, x{row['python_overhead']:.1f})",
                  flush=True)
        if name in ("double_pendulum_chaos", "ur5_falling"):
            rng = np.random.default_rng(0)
            B = args.batch
            Q0 = q + 0.01 * rng.normal(size=(B, model.n))
            simulate_batch(scene, Q0[:2], t_end=T, samples=101, model=model)   # compile first
            t0 = time.perf_counter()
            res = simulate_batch(scene, Q0, t_end=T, samples=101, model=model)
            tb = (time.perf_counter() - t0) / B
            k = min(B, 8)
            t0 = time.perf_counter()
            for b in range(k):
                simulate(scene, q0=Q0[b], t_end=T, samples=101, model=model, progress=False)
            ts = (time.perf_counter() - t0) / k
            sweeps.append({"scene": name, "B": B, "t_end": T, "batch_s_per_trajectory": tb,
                           "single_s_per_trajectory": ts, "speedup": ts / tb, "success": res.success})
            print(f"sweep {name}: {B} trajectories, {1e3 * tb:.2f} ms each in a batch vs {1e3 * ts:.2f} ms "
                  f"one at a time (x{ts / tb:.1f})", flush=True)
    if args.out:
        import mujoco
        import numba

        out = Path(args.out)
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(json.dumps({"machine": platform.platform(), "python": platform.python_version(),
                                   "numpy": np.__version__, "numba": numba.__version__,
                                   "mujoco": mujoco.__version__, "rows": rows, "sweeps": sweeps}, indent=2))
        print(f"wrote {out}")


if __name__ == "__main__":
    main()

"""Sweeps of many initial states: urdf2links' simulate_batch against MuJoCo's rollout at matched
accuracy, same threads, same outputs.

For the double pendulum and the UR5-like arm: ``B`` initial states (the scene's, perturbed by
0.01 N(0, 1) in every coordinate, seed 0), ``t = 0..T``, the states ``(q, qd)`` at the same ``S``
sample times from both engines, on the same number of threads, in one process.

A time ratio at unequal accuracy is not a speed comparison, so MuJoCo's step is chosen to match
the project's error first (untimed):

1. each engine's error, on the first ``--check`` trajectories, against DOP853 at rtol 1e-13 (max
   over samples and coordinates of ``|q - q_ref|``): urdf2links at the scene's tolerances, and
   MuJoCo RK4 at ``k`` steps per sample interval (dt = interval / k) for k on a doubling ladder,
   then bisected between the last rung less accurate than urdf2links and the first as accurate;
2. **matched**: the fewest steps ``k*`` at which MuJoCo's error is at most urdf2links' (its
   cheapest run at least as accurate; one step fewer is less accurate). If the ladder's finest
   rung is still less accurate, that rung is used and the row says so.

Then, in interleaved rounds (the order reversed every other round; median (min-max)):

* urdf2links: :func:`urdf2links.integration.batch.simulate_batch` (DOP853 at the scene's tolerances, one
  trajectory per numba thread, steps landing on the sample times); its ``wall_time``;
* MuJoCo, ``rollout per sample``: ``mujoco.rollout.Rollout(nthread).rollout`` from one sample to the
  next (``nstep = k*``), RK4 as ``urdf2links compare`` runs it; the loop over the samples is timed;
* MuJoCo, ``rollout, one call``: one ``rollout`` of all steps, every step's state stored
  (``B x K x nstate``), the samples read afterwards (not timed);
* both engines' work-precision curves (``--curve``, on by default): urdf2links at the rtols of
  :data:`RTOLS` (atol = rtol / 10) and MuJoCo per sample at the ``k`` of :data:`CURVE_STEPS`.

The headline ratio is urdf2links against the faster of MuJoCo's two ways at ``k*``, with the ratio
of the minima and the tie rule's verdict. Usage::

    python benchmarks/sweeps.py [--batch 32] [--threads N] [--rounds 5] [--no-curve] [--out reports/benchmarks/sweeps.json]
"""

from __future__ import annotations

import copy
import os
import time

import mujoco
import numba
import numpy as np
from mujoco import rollout as mj_rollout

from benchmarking import compare, fastest, fmt_ratio, fmt_spread, markdown_table, rounds, run_benchmark, spread
from urdf2links.compare.mujoco_side.mjcf import mjcf_from_scene
from urdf2links.integration.batch import simulate_batch
from urdf2links.integration.simulate import simulate
from urdf2links.locations import shipped_robots_dir
from urdf2links.scenes.scene_read import load_scene

SCENES = ("double_pendulum_chaos", "ur5_falling")
T_END = 2.0
SAMPLES = 201
INTERVAL = T_END / (SAMPLES - 1)
#: MuJoCo RK4 steps per sample interval tried first (dt = INTERVAL / k), before bisecting.
LADDER = (5, 10, 20, 40, 80, 160, 320, 640)
#: The work-precision curves: urdf2links' rtols (atol = rtol / 10) and MuJoCo's steps per interval.
RTOLS = (1e-6, 1e-8, 1e-10, 1e-12)
CURVE_STEPS = (10, 20, 40, 80, 160)
#: A one-call rollout storing every state is skipped above this many bytes.
ONE_CALL_BYTES = 2e9
OURS, PER_SAMPLE, ONE_CALL = "urdf2links simulate_batch", "MuJoCo rollout per sample", "MuJoCo rollout, one call"


class MujocoSweep:
    """B initial states of the route-1 model stepped by ``mujoco.rollout`` on ``threads`` threads, RK4
    at ``k`` steps per sample interval."""

    def __init__(self, mj, Q0, QD0, threads, k):
        self.mj, self.k = mj, k
        self.m = copy.deepcopy(mj.model)
        self.m.opt.timestep = INTERVAL / k
        self.models = [self.m] * len(Q0)          # one per trajectory: rollout's checks skipped
        self.datas = [mujoco.MjData(self.m) for _ in range(threads)]
        self.pool = mj_rollout.Rollout(nthread=threads if threads > 1 else 0)
        spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
        self.nstate = mujoco.mj_stateSize(self.m, spec)
        d = mujoco.MjData(self.m)
        self.x0 = np.empty((len(Q0), self.nstate))
        for b in range(len(Q0)):
            mujoco.mj_resetData(self.m, d)
            mj.set_state(d, Q0[b], QD0[b])
            mujoco.mj_getState(self.m, d, self.x0[b], spec)
        # where q sits in a FULLPHYSICS state: time (1), qpos (nq), qvel (nv), ...
        self.q_at = 1 + np.asarray(mj.qpos_index)

    def per_sample(self):
        """States at the samples, one rollout per sample interval; (seconds, q)."""
        B = len(self.x0)
        buf = np.empty((B, self.k, self.nstate))
        x = self.x0.copy()
        q = np.empty((B, SAMPLES, len(self.q_at)))
        q[:, 0] = x[:, self.q_at]
        t0 = time.perf_counter()
        for j in range(1, SAMPLES):
            self.pool.rollout(self.models, self.datas, x, nstep=self.k, state=buf, skip_checks=True)
            x[:] = buf[:, -1]
            q[:, j] = x[:, self.q_at]
        return time.perf_counter() - t0, q

    def one_call_bytes(self) -> float:
        return 8.0 * len(self.x0) * self.k * (SAMPLES - 1) * self.nstate

    def one_call(self):
        """All steps in one rollout, every state stored; (seconds, q at the samples)."""
        B, K = len(self.x0), self.k * (SAMPLES - 1)
        buf = np.empty((B, K, self.nstate))
        t0 = time.perf_counter()
        self.pool.rollout(self.models, self.datas, self.x0, nstep=K, state=buf, skip_checks=True)
        wall = time.perf_counter() - t0
        q = np.concatenate([self.x0[:, None, self.q_at], buf[:, self.k - 1::self.k][:, :, self.q_at]], axis=1)
        return wall, q

    def close(self):
        self.pool.close()


def error(q, refs) -> float:
    """Max over the checked trajectories, samples and coordinates of |q - q_ref|."""
    return max(float(np.max(np.abs(q[b] - ref))) for b, ref in enumerate(refs))


def match_steps(err_at, target: float, log) -> tuple[int, bool, dict]:
    """The fewest MuJoCo steps per interval whose error (``err_at(k)``) is at most ``target``: up the
    doubling :data:`LADDER`, then bisected between the last rung above and the first at or below.
    Returns (k, matched, {k: error of every k tried})."""
    tried: dict[int, float] = {}

    def err(k):
        if k not in tried:
            tried[k] = err_at(k)
            log(f"  MuJoCo RK4 {k} steps per interval (dt {INTERVAL / k:.3g} s): error {tried[k]:.2e}")
        return tried[k]

    hi = next((k for k in LADDER if err(k) <= target), None)
    if hi is None:
        return LADDER[-1], False, tried
    lo = max([k for k in LADDER if k < hi], default=0)
    while hi - lo > 1:                       # err(lo) > target >= err(hi)
        mid = (lo + hi) // 2
        if err(mid) <= target:
            hi = mid
        else:
            lo = mid
    return hi, True, tried


def measure(name, B, threads, n_rounds, n_check, curve, log) -> dict:
    scene = load_scene(shipped_robots_dir() / f"{name}.toml")
    model = scene.model()
    q, qd = scene.initial_state(model)
    rng = np.random.default_rng(0)
    Q0 = q + 0.01 * rng.normal(size=(B, model.n))
    QD0 = np.tile(qd, (B, 1))
    n_check = min(n_check, B)
    mj = mjcf_from_scene(scene, model, timestep=INTERVAL / 100, integrator="RK4")
    log(f"{name}: {B} trajectories, {threads} threads, t = 0..{T_END:g} s, {SAMPLES} samples")
    refs = [simulate(scene, q0=Q0[b], qd0=QD0[b], t_end=T_END, samples=SAMPLES, method="DOP853", rtol=1e-13,
                     atol=1e-14, model=model, progress=False).q for b in range(n_check)]
    tol = {"rtol": scene.run.rtol, "atol": scene.run.atol}

    def ours(rtol, atol, rows=B):
        return simulate_batch(scene, Q0[:rows], QD0[:rows], t_end=T_END, samples=SAMPLES, model=model,
                              method="DOP853", rtol=rtol, atol=atol)

    ours(**tol, rows=threads)                                   # compile / load first
    target = error(ours(**tol, rows=n_check).q, refs)
    log(f"  urdf2links DOP853 rtol {tol['rtol']:g}: error {target:.2e}")

    def mujoco_error(k):
        sweep = MujocoSweep(mj, Q0[:n_check], QD0[:n_check], threads, k)
        try:
            return error(sweep.per_sample()[1], refs)
        finally:
            sweep.close()

    k_star, matched, tried = match_steps(mujoco_error, target, log)
    sweeps = {k: MujocoSweep(mj, Q0, QD0, threads, k) for k in sorted({k_star, *(CURVE_STEPS if curve else ())})}
    rtols = sorted({*(RTOLS if curve else ()), tol["rtol"]}, reverse=True)
    out: dict = {}

    def project(rtol):
        atol = tol["atol"] if rtol == tol["rtol"] else rtol / 10
        res = out[("ours", rtol)] = ours(rtol, atol)
        return res.wall_time

    def per_sample(k):
        wall, out[("per_sample", k)] = sweeps[k].per_sample()
        return wall

    def one_call():
        wall, out["one_call"] = sweeps[k_star].one_call()
        return wall

    variants = {OURS: lambda: project(tol["rtol"]), PER_SAMPLE: lambda: per_sample(k_star)}
    if sweeps[k_star].one_call_bytes() <= ONE_CALL_BYTES:
        variants[ONE_CALL] = one_call
    for r in rtols:
        if r != tol["rtol"]:
            variants[f"urdf2links rtol {r:g}"] = lambda r=r: project(r)
    for k in sweeps:
        if k != k_star:
            variants[f"MuJoCo {k} steps"] = lambda k=k: per_sample(k)
    try:
        times = rounds(variants, n_rounds, log=log)
    finally:
        for s in sweeps.values():
            s.close()
    seconds = {k: spread(times[k]) for k in (OURS, PER_SAMPLE, ONE_CALL) if k in times}
    errors = {OURS: error(out[("ours", tol["rtol"])].q, refs), PER_SAMPLE: error(out[("per_sample", k_star)], refs)}
    if "one_call" in out:
        errors[ONE_CALL] = error(out["one_call"], refs)
    curves = {
        "urdf2links": [{"rtol": r, "error": error(out[("ours", r)].q, refs),
                        "s": spread(times[OURS if r == tol["rtol"] else f"urdf2links rtol {r:g}"])} for r in rtols],
        "mujoco": [{"steps_per_interval": k, "dt": INTERVAL / k, "error": error(out[("per_sample", k)], refs),
                    "s": spread(times[PER_SAMPLE if k == k_star else f"MuJoCo {k} steps"])} for k in sorted(sweeps)]}
    res = out[("ours", tol["rtol"])]
    return {"scene": name, "n": model.n, "B": B, "threads": threads, "t_end": T_END, "samples": SAMPLES,
            "project": {"method": res.method, "rtol": tol["rtol"], "atol": tol["atol"],
                        "nfev_mean": float(np.mean(res.nfev)), "success": res.success},
            "mujoco": {"integrator": "RK4", "steps_per_interval": k_star, "dt": INTERVAL / k_star,
                       "steps": k_star * (SAMPLES - 1), "matched": matched,
                       "errors_tried": {str(k): v for k, v in sorted(tried.items())}},
            "seconds": seconds, "per_trajectory_s": {k: spread([x / B for x in times[k]]) for k in seconds},
            "max_error": errors, "checked_trajectories": n_check, "curves": curves, **comparisons(seconds)}


def comparisons(seconds) -> dict:
    """The faster of MuJoCo's two ways at the matched step and urdf2links against it under the tie rule
    (from the spreads: the render recomputes them)."""
    way = fastest({k: v for k, v in seconds.items() if k != OURS})
    return {"mujoco_way": way, "vs_mujoco": compare(seconds[OURS], seconds[way])}


def table(data) -> str:
    rows = data["rows"]
    head = ["scene", "B x threads", "engine", "settings", "s per sweep", "ms per trajectory", "max error vs reference"]
    body = []
    for r in rows:
        for k, s in r["seconds"].items():
            setting = (f"DOP853 rtol {r['project']['rtol']:g}" if k == OURS
                       else f"RK4 dt {r['mujoco']['dt']:.3g} ({r['mujoco']['steps']} steps)")
            body.append([r["scene"], f"{r['B']} x {r['threads']}", k, setting, fmt_spread(s),
                         fmt_spread(r["per_trajectory_s"][k], 1e3), f"{r['max_error'][k]:.1e}"])
    verdicts = markdown_table(
        ["scene", "MuJoCo's step matched to urdf2links' error", "faster MuJoCo way", "urdf2links / MuJoCo"],
        [[r["scene"], (f"{r['mujoco']['steps_per_interval']} steps per {INTERVAL:g} s "
                       f"(error {r['max_error'][PER_SAMPLE]:.1e} <= {r['max_error'][OURS]:.1e})")
          if r["mujoco"]["matched"] else
          f"**not matched**: MuJoCo's finest step tried is less accurate ({r['max_error'][PER_SAMPLE]:.1e} > "
          f"{r['max_error'][OURS]:.1e})", r["mujoco_way"], fmt_ratio(r["vs_mujoco"])] for r in rows])
    curve_rows = []
    for r in rows:
        for c in r["curves"]["urdf2links"]:
            curve_rows.append([r["scene"], "urdf2links", f"DOP853 rtol {c['rtol']:g}", f"{c['error']:.1e}",
                               fmt_spread({k: v / r["B"] for k, v in c["s"].items() if k != "rounds"}, 1e3)])
        for c in r["curves"]["mujoco"]:
            curve_rows.append([r["scene"], "MuJoCo", f"RK4 dt {c['dt']:.3g} ({c['steps_per_interval']} per sample)",
                               f"{c['error']:.1e}",
                               fmt_spread({k: v / r["B"] for k, v in c["s"].items() if k != "rounds"}, 1e3)])
    return ("# Sweeps: simulate_batch against mujoco.rollout at matched accuracy\n\n"
            f"t = 0..{T_END:g} s; both engines return the states at the same {SAMPLES} sample times, on the same "
            "number of threads. Max error: max over samples and coordinates of |q - q_ref| (rad) on the first "
            f"{rows[0]['checked_trajectories']} trajectories, q_ref from DOP853 at rtol 1e-13. MuJoCo's RK4 step is "
            "the largest at which its error is at most urdf2links' (chosen before timing): a time ratio at unequal "
            f"accuracy is not a speed comparison. Seconds: median (min-max) of {data['rounds']} interleaved rounds in "
            "one process.\n\n" + markdown_table(head, body) + "\n\n"
            "## At matched accuracy\n\nurdf2links against the faster of MuJoCo's two ways at the matched step: "
            "ratio of the medians, (min: of the minima), and the tie rule's verdict (faster or slower only when the "
            "spreads do not overlap).\n\n" + verdicts
            + ("\n\n## Work-precision curves\n\nms per trajectory, median (min-max), against the error bought; "
               "MuJoCo per sample.\n\n" + markdown_table(["scene", "engine", "settings", "max error", "ms per trajectory"],
                                                        curve_rows) if curve_rows else ""))


def plot(data):
    from urdf2links.compare.figures import figure

    rows = data["rows"]
    fig = figure(9.5, 4.0, dpi=100)
    axes = np.atleast_1d(fig.subplots(1, len(rows)))
    for ax, r in zip(axes, rows):
        for side, colour, label in (("urdf2links", "#2171b5", "urdf2links simulate_batch (DOP853, rtol)"),
                                    ("mujoco", "#cb181d", "MuJoCo rollout per sample (RK4, dt)")):
            pts = sorted(r["curves"][side], key=lambda c: c["error"])
            if not pts:
                continue
            e = np.array([max(c["error"], 1e-16) for c in pts])
            med = np.array([1e3 * c["s"]["median"] / r["B"] for c in pts])
            err = np.array([[1e3 * (c["s"]["median"] - c["s"]["min"]) / r["B"],
                             1e3 * (c["s"]["max"] - c["s"]["median"]) / r["B"]] for c in pts]).T
            ax.errorbar(e, med, yerr=err, fmt="o-", color=colour, label=label, capsize=2, ms=4)
        ours, way = r["per_trajectory_s"][OURS], r["per_trajectory_s"][r["mujoco_way"]]
        ax.plot(max(r["max_error"][OURS], 1e-16), 1e3 * ours["median"], "*", color="#08306b", ms=13,
                label="urdf2links at the scene's rtol")
        ax.plot(max(r["max_error"][r["mujoco_way"]], 1e-16), 1e3 * way["median"], "*", color="#67000d", ms=13,
                label=f"MuJoCo matched ({r['mujoco']['steps_per_interval']} steps per sample)")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("max error vs reference (rad)")
        ax.set_ylabel("ms per trajectory (median, min-max)")
        ax.set_title(f"{r['scene']}: {r['B']} trajectories, {r['threads']} threads\n"
                     f"urdf2links / MuJoCo at matched accuracy {fmt_ratio(r['vs_mujoco'])}", fontsize=8)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=6)
    fig.suptitle("Sweeps: work against precision, both engines, same samples and threads", fontsize=10)
    return fig


def measure_all(args, log) -> dict:
    threads = min(args.threads, numba.config.NUMBA_NUM_THREADS)
    numba.set_num_threads(threads)
    return {"rounds": args.rounds, "interval": INTERVAL,
            "rows": [measure(s, args.batch, threads, args.rounds, args.check, args.curve, log) for s in SCENES]}


def render(data):
    for r in data["rows"]:
        r.update(comparisons(r["seconds"]))
    return table(data), plot(data)


def options(p):
    p.add_argument("--batch", type=int, default=32, help="trajectories per sweep (default 32)")
    p.add_argument("--threads", type=int, default=os.cpu_count() or 1, help="threads of both engines (default: CPUs)")
    p.add_argument("--check", type=int, default=4, help="trajectories checked against the reference (default 4)")
    p.add_argument("--no-curve", dest="curve", action="store_false", help="time the matched runs only, no "
                   "work-precision curves")


if __name__ == "__main__":
    run_benchmark("sweeps", __doc__, measure_all, render, options=options)

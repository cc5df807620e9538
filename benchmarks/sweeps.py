"""Sweeps of many initial states: urdf2links' simulate_batch against MuJoCo's rollout, same threads, same outputs.

For the double pendulum and the UR5-like arm: ``B`` initial states (the scene's, perturbed by
0.01 N(0, 1) in every coordinate, seed 0), ``t = 0..T``, the states ``(q, qd)`` at the same ``S``
sample times from both engines, on the same number of threads, in one process and interleaved
rounds:

* urdf2links: :func:`urdf2links.integration.batch.simulate_batch` (DOP853 at the scene's tolerances, one
  trajectory per numba thread, steps landing on the sample times); its ``wall_time``;
* MuJoCo, ``rollout per sample``: ``mujoco.rollout.Rollout(nthread).rollout`` from one sample to the
  next (``nstep`` = steps per sample interval), RK4 at dt 1e-4 s as ``urdf2links compare`` runs it;
  the loop over the samples is timed (the same outputs: the states at the samples);
* MuJoCo, ``rollout, one call``: one ``rollout`` of all ``K`` steps, every step's state stored
  (``B x K x nstate``), the samples read afterwards (not timed).

Each engine's accuracy is measured too, against DOP853 at rtol 1e-13 on the first
``--check`` trajectories (max over samples and coordinates of ``|q - q_ref|``), so that the times
are read with what they buy. Usage::

    python benchmarks/sweeps.py [--batch 32] [--threads N] [--rounds 5] [--out reports/benchmarks/sweeps.json]
"""

from __future__ import annotations

import os

import mujoco
import numba
import numpy as np
from mujoco import rollout as mj_rollout

from benchmarking import fmt_spread, markdown_table, rounds, run_benchmark, spread
from urdf2links.integration.batch import simulate_batch
from urdf2links.compare.mujoco_side.mjcf import mjcf_from_scene
from urdf2links.locations import shipped_robots_dir
from urdf2links.scenes.scene import load_scene
from urdf2links.integration.simulate import simulate

SCENES = ("double_pendulum_chaos", "ur5_falling")
T_END = 2.0
SAMPLES = 201
MUJOCO_DT = 1e-4


class MujocoSweep:
    """B initial states of the route-1 model stepped by ``mujoco.rollout`` on ``threads`` threads."""

    def __init__(self, mj, Q0, QD0, threads):
        self.mj, self.m = mj, mj.model
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
        # where q and qd sit in a FULLPHYSICS state: time (1), qpos (nq), qvel (nv), ...
        self.q_at = 1 + np.asarray(mj.qpos_index)
        self.qd_at = 1 + self.m.nq + np.asarray(mj.dof_index)

    def per_sample(self, per):
        """States at the samples, one rollout per sample interval of ``per`` steps; (seconds, q)."""
        B = len(self.x0)
        buf = np.empty((B, per, self.nstate))
        x = self.x0.copy()
        q = np.empty((B, SAMPLES, len(self.q_at)))
        q[:, 0] = x[:, self.q_at]
        t0 = _clock()
        for j in range(1, SAMPLES):
            self.pool.rollout(self.models, self.datas, x, nstep=per, state=buf, skip_checks=True)
            x[:] = buf[:, -1]
            q[:, j] = x[:, self.q_at]
        return _clock() - t0, q

    def one_call(self, per):
        """All K steps in one rollout, every state stored; (seconds, q at the samples)."""
        B, K = len(self.x0), per * (SAMPLES - 1)
        buf = np.empty((B, K, self.nstate))
        t0 = _clock()
        self.pool.rollout(self.models, self.datas, self.x0, nstep=K, state=buf, skip_checks=True)
        wall = _clock() - t0
        q = np.concatenate([self.x0[:, None, self.q_at], buf[:, per - 1::per][:, :, self.q_at]], axis=1)
        return wall, q


def _clock():
    import time

    return time.perf_counter()


def measure(name, B, threads, n_rounds, n_check, log) -> dict:
    scene = load_scene(shipped_robots_dir() / f"{name}.toml")
    model = scene.model()
    q, qd = scene.initial_state(model)
    rng = np.random.default_rng(0)
    Q0 = q + 0.01 * rng.normal(size=(B, model.n))
    QD0 = np.tile(qd, (B, 1))
    mj = mjcf_from_scene(scene, model, timestep=MUJOCO_DT, integrator="RK4")
    sweep = MujocoSweep(mj, Q0, QD0, threads)
    per = int(round(T_END / (SAMPLES - 1) / MUJOCO_DT))
    simulate_batch(scene, Q0[:threads], QD0[:threads], t_end=T_END, samples=SAMPLES, model=model)  # compile / load
    out = {}

    def project():
        res = simulate_batch(scene, Q0, QD0, t_end=T_END, samples=SAMPLES, model=model)
        out["project"] = res
        return res.wall_time

    def per_sample():
        wall, out["per_sample"] = sweep.per_sample(per)
        return wall

    def one_call():
        wall, out["one_call"] = sweep.one_call(per)
        return wall

    log(f"{name}: {B} trajectories, {threads} threads, t = 0..{T_END:g} s, {SAMPLES} samples")
    times = rounds({"urdf2links simulate_batch": project, "MuJoCo rollout per sample": per_sample,
                    "MuJoCo rollout, one call": one_call}, n_rounds, log=log)
    errors = {k: 0.0 for k in ("urdf2links simulate_batch", "MuJoCo rollout per sample", "MuJoCo rollout, one call")}
    for b in range(min(n_check, B)):
        ref = simulate(scene, q0=Q0[b], qd0=QD0[b], t_end=T_END, samples=SAMPLES, method="DOP853", rtol=1e-13,
                       atol=1e-14, model=model, progress=False)
        for k, qs in (("urdf2links simulate_batch", out["project"].q[b]), ("MuJoCo rollout per sample", out["per_sample"][b]),
                      ("MuJoCo rollout, one call", out["one_call"][b])):
            errors[k] = max(errors[k], float(np.max(np.abs(qs - ref.q))))
    res = out["project"]
    return {"scene": name, "n": model.n, "B": B, "threads": threads, "t_end": T_END, "samples": SAMPLES,
            "project": {"method": res.method, "rtol": scene.run.rtol, "atol": scene.run.atol,
                        "nfev_mean": float(np.mean(res.nfev)), "success": res.success},
            "mujoco": {"integrator": "RK4", "dt": MUJOCO_DT, "steps": per * (SAMPLES - 1)},
            "seconds": {k: spread(v) for k, v in times.items()},
            "per_trajectory_s": {k: spread([x / B for x in v]) for k, v in times.items()},
            "max_error": errors, "checked_trajectories": min(n_check, B)}


def table(rows) -> str:
    head = ["scene", "B x threads", "engine", "settings", "s per sweep", "ms per trajectory", "max error vs reference"]
    body = []
    for r in rows:
        for k, s in r["seconds"].items():
            setting = (f"DOP853 rtol {r['project']['rtol']:g}" if k.startswith("urdf2links")
                       else f"RK4 dt {r['mujoco']['dt']:g} ({r['mujoco']['steps']} steps)")
            body.append([r["scene"], f"{r['B']} x {r['threads']}", k, setting, fmt_spread(s),
                         fmt_spread(r["per_trajectory_s"][k], 1e3), f"{r['max_error'][k]:.1e}"])
    return ("# Sweeps: simulate_batch against mujoco.rollout\n\n"
            f"t = 0..{T_END:g} s; both engines return the states at the same {SAMPLES} sample times, on the same "
            "number of threads. Seconds: median (min-max) of interleaved rounds in one process. Max error: max over "
            "samples and coordinates of |q - q_ref| (rad) on the first checked trajectories, q_ref from DOP853 at "
            "rtol 1e-13.\n\n" + markdown_table(head, body))


def plot(rows):
    from urdf2links.compare.figures import figure

    fig = figure(8.5, 3.6, dpi=100)
    axes = fig.subplots(1, len(rows))
    colours = {"urdf2links simulate_batch": "#2171b5", "MuJoCo rollout per sample": "#cb181d",
               "MuJoCo rollout, one call": "#fd8d3c"}
    for ax, r in zip(np.atleast_1d(axes), rows):
        keys = list(r["per_trajectory_s"])
        med = [1e3 * r["per_trajectory_s"][k]["median"] for k in keys]
        err = [[1e3 * (r["per_trajectory_s"][k]["median"] - r["per_trajectory_s"][k]["min"]) for k in keys],
               [1e3 * (r["per_trajectory_s"][k]["max"] - r["per_trajectory_s"][k]["median"]) for k in keys]]
        ax.bar(range(len(keys)), med, color=[colours[k] for k in keys], yerr=err, capsize=3)
        ax.set_xticks(range(len(keys)), [k.replace(" ", "\n", 1) + f"\nerr {r['max_error'][k]:.0e}" for k in keys],
                      fontsize=7)
        ax.set_title(f"{r['scene']}: {r['B']} trajectories, {r['threads']} threads", fontsize=9)
        ax.set_ylabel("ms per trajectory (median, min-max)")
        ax.grid(axis="y", alpha=0.3)
    return fig


def measure_all(args, log) -> dict:
    threads = min(args.threads, numba.config.NUMBA_NUM_THREADS)
    numba.set_num_threads(threads)
    return {"rounds": args.rounds, "rows": [measure(s, args.batch, threads, args.rounds, args.check, log)
                                            for s in SCENES]}


def render(data):
    return table(data["rows"]), plot(data["rows"])


def options(p):
    p.add_argument("--batch", type=int, default=32, help="trajectories per sweep (default 32)")
    p.add_argument("--threads", type=int, default=os.cpu_count() or 1, help="threads of both engines (default: CPUs)")
    p.add_argument("--check", type=int, default=4, help="trajectories checked against the reference (default 4)")


if __name__ == "__main__":
    run_benchmark("sweeps", __doc__, measure_all, render, options=options)

"""Batched dynamics: ``Model.forward_dynamics(Q, QD)`` on B states in one compiled call against
``mujoco.rollout`` of one Euler step (``nstep=1``) from the same B states, 1 thread and all threads.

Timed regions (one process, interleaved rounds, median (min-max) over the rounds):

* ``urdf2links``: one call ``model.forward_dynamics(Q, QD)`` with ``Q``, ``QD`` (B, n) (gravity,
  no torques): argument checks, the compiled batch (numba ``prange`` over chunks of rows) and the
  (B, n) result, with ``numba.set_num_threads(k)``.
* ``mujoco.rollout``: one ``Rollout(nthread=k).rollout(models, datas, x0, nstep=1, state=buf,
  skip_checks=True)`` from the B full-physics states ``x0`` of the same ``(q, q')`` (route-1 model,
  Euler, dt 1e-4 s, energy flag off): one ``mj_step`` (forward dynamics and the Euler update) per row
  and the copy of its state into ``buf``; ``k`` ``MjData`` (one per thread), the pool made beforehand.

Both sides compute ``q''`` of every row (MuJoCo integrates it as well); the JSON records the largest
difference between our ``q''`` and MuJoCo's ``(q'_1 - q'_0) / dt`` (rounding of the Euler update
divided by dt: ~1e-11 relative). Threads: 1 and ``numba.get_num_threads()`` at start (all, or
``NUMBA_NUM_THREADS``). Usage::

    python benchmarks/batch_cost.py [--batches 1000 10000] [--rounds 5] [--out reports/benchmarks/batch_cost.json]
    python benchmarks/batch_cost.py --render-only
"""

from __future__ import annotations

import time

import mujoco
import numba
import numpy as np
from mujoco import rollout as mj_rollout

from benchmarking import fmt_spread, load_models, markdown_table, rounds, run_benchmark, spread
from eval_cost import chain
from urdf2links.compare.mujoco_side.mjcf import mjcf_from_model
from urdf2links.locations import example_robot_data_dir

DT = 1e-4
REAL = ("ur_description/urdf/ur5_robot.urdf", "talos_data/robots/talos_reduced.urdf",
        "g1_description/urdf/g1_29dof_rev_1_0.urdf")


def models() -> list:
    # without example-robot-data, the shipped UR5-like arm stands in for its robots
    spare = () if example_robot_data_dir() is not None else ("ur5_like.urdf",)
    out = load_models(("double_pendulum.urdf", *spare), REAL)
    return out + [chain(64)]


class MujocoBatch:
    """B states of the route-1 model, one Euler step each through ``mujoco.rollout`` on ``k`` threads."""

    def __init__(self, model, Q, QD, threads):
        mj = mjcf_from_model(model, gravity=model.gravity_vector, timestep=DT, integrator="Euler")
        m = mj.model
        m.opt.enableflags &= ~int(mujoco.mjtEnableBit.mjENBL_ENERGY)
        self.mj, self.m = mj, m
        spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
        nstate = mujoco.mj_stateSize(m, spec)
        d = mujoco.MjData(m)
        self.x0 = np.empty((len(Q), nstate))
        for b in range(len(Q)):
            mujoco.mj_resetData(m, d)
            mj.set_state(d, Q[b], QD[b])
            mujoco.mj_getState(m, d, self.x0[b], spec)
        self.models = [m] * len(Q)
        self.datas = [mujoco.MjData(m) for _ in range(threads)]
        self.pool = mj_rollout.Rollout(nthread=threads if threads > 1 else 0)
        self.buf = np.empty((len(Q), 1, nstate))
        self.qd_at = 1 + m.nq + np.asarray(mj.dof_index)

    def step(self) -> float:
        t0 = time.perf_counter()
        self.pool.rollout(self.models, self.datas, self.x0, nstep=1, state=self.buf, skip_checks=True)
        return time.perf_counter() - t0

    def qdd(self) -> np.ndarray:
        return (self.buf[:, 0, self.qd_at] - self.x0[:, self.qd_at]) / DT

    def close(self):
        self.pool.close()


def measure(model, B, threads, n_rounds, log) -> dict:
    rng = np.random.default_rng(0)
    Q, QD = rng.uniform(-1, 1, (B, model.n)), rng.normal(size=(B, model.n))
    model.forward_dynamics(Q[:2], QD[:2])                     # compile / load first
    row = {"robot": model.name, "n": model.n, "B": B}
    for k in sorted({1, threads}):
        mjb = MujocoBatch(model, Q, QD, k)

        def ours(k=k):
            numba.set_num_threads(k)
            t0 = time.perf_counter()
            row["_qdd"] = model.forward_dynamics(Q, QD)
            return time.perf_counter() - t0

        try:
            times = rounds({"urdf2links": ours, "mujoco.rollout": mjb.step}, n_rounds)
            ref = mjb.qdd()
        finally:
            numba.set_num_threads(threads)
            mjb.close()
        qdd = row.pop("_qdd")
        row[f"threads_{k}"] = {"threads": k, "urdf2links_s": spread(times["urdf2links"]),
                               "rollout_s": spread(times["mujoco.rollout"]),
                               "max_rel_difference": float(np.abs(qdd - ref).max() / np.abs(ref).max())}
        t = row[f"threads_{k}"]
        t["ratio"] = t["urdf2links_s"]["median"] / t["rollout_s"]["median"]
        log(f"{model.name[:20]:20s} n {model.n:3d} B {B:6d} threads {k}: urdf2links {fmt_spread(t['urdf2links_s'], 1e3)} ms, "
            f"rollout {fmt_spread(t['rollout_s'], 1e3)} ms: x{t['ratio']:.2f} (max rel diff {t['max_rel_difference']:.1e})")
    return row


def _thread_keys(data):
    return [f"threads_{k}" for k in sorted({1, data["threads"]})]


def table(data) -> str:
    keys = _thread_keys(data)
    head = ["robot", "n", "B"]
    for key in keys:
        k = key.split("_")[1]
        head += [f"urdf2links {k} thr. ms", f"rollout {k} thr. ms", f"ratio ({k} thr.)"]
    head.append("max rel. difference of q''")
    body = []
    for r in data["rows"]:
        line = [r["robot"], r["n"], r["B"]]
        for key in keys:
            t = r[key]
            line += [fmt_spread(t["urdf2links_s"], 1e3), fmt_spread(t["rollout_s"], 1e3), f"{t['ratio']:.2f}"]
        line.append(f"{max(r[key]['max_rel_difference'] for key in keys):.1e}")
        body.append(line)
    return ("# Batched forward dynamics against mujoco.rollout (one Euler step)\n\n"
            f"Milliseconds per batch of B states, median (min-max) over {data['rounds']} interleaved rounds in one "
            "process. urdf2links: one call model.forward_dynamics(Q, QD) (gravity, fixed base), numba threads set "
            "with numba.set_num_threads. mujoco.rollout: Rollout(nthread).rollout(..., nstep=1) from the same states "
            "(route-1 model, Euler, dt 1e-4 s), one MjData per thread: one mj_step per row and its state copied out. "
            "ratio: urdf2links / rollout. Last column: largest difference between our q'' and MuJoCo's "
            "(q'_1 - q'_0) / dt, relative to its largest entry.\n\n" + markdown_table(head, body))


def plot(data):
    from urdf2links.compare.figures import figure

    keys = _thread_keys(data)
    rows = data["rows"]
    fig = figure(10.0, 4.4, dpi=100)
    axes = fig.subplots(1, len(data["batches"]), squeeze=False)[0]
    colours = {"urdf2links": ("#2171b5", "#6baed6"), "rollout": ("#cb181d", "#fc9272")}
    for ax, B in zip(axes, data["batches"]):
        sub = [r for r in rows if r["B"] == B]
        x = np.arange(len(sub))
        j = 0
        for side, label in (("urdf2links", "urdf2links forward_dynamics"), ("rollout", "mujoco.rollout nstep=1")):
            for ki, key in enumerate(keys):
                med = np.array([r[key][f"{side}_s"]["median"] * 1e6 / B for r in sub])
                ax.bar(x + (j - 1.5) * 0.2, med, 0.19, color=colours[side][ki],
                       label=f"{label}, {r_threads(key)} thread(s)")
                j += 1
        ax.set_yscale("log")
        ax.set_xticks(x, [f"{r['robot']}\nn={r['n']}" for r in sub], fontsize=7, rotation=30, ha="right")
        ax.set_title(f"B = {B}", fontsize=9)
        ax.set_ylabel("us per state (median of the rounds)")
        ax.grid(axis="y", which="both", alpha=0.3)
    axes[0].legend(fontsize=7)
    fig.suptitle("Batched forward dynamics against mujoco.rollout (one Euler step), same states", fontsize=10)
    return fig


def r_threads(key) -> str:
    return key.split("_")[1]


def measure_all(args, log) -> dict:
    threads = numba.get_num_threads()
    rows = [measure(model, B, threads, args.rounds, log) for B in args.batches for model in models()]
    return {"rounds": args.rounds, "batches": list(args.batches), "threads": threads, "dt": DT, "rows": rows}


def render(data):
    return table(data), plot(data)


def options(p):
    p.add_argument("--batches", type=int, nargs="+", default=[1000, 10000], help="batch sizes (default 1000 10000)")


if __name__ == "__main__":
    run_benchmark("batch_cost", __doc__, measure_all, render, options=options)

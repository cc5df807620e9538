"""Batched dynamics: ``Model.forward_dynamics(Q, QD)`` on B states in one compiled call against MuJoCo's
two batched ways to get the same ``q''`` from the same B states, on 1 thread and all threads; each
row compared with the faster MuJoCo way.

Timed regions (one process; per batch size, every model, thread count and engine interleaved in the
same rounds, the order reversed every other round; median (min-max) over the rounds; a model whose
spread is wide is measured again):

* ``urdf2links``: one call ``model.forward_dynamics(Q, QD)`` with ``Q``, ``QD`` (B, n) (gravity,
  no torques): argument checks, the compiled batch in SIMD lanes (blocks of states, numba ``prange`` over
  chunks of blocks, issue 48) and the (B, n) result, with ``numba.set_num_threads(k)``.
* ``scalar rows``: the same call with ``lanes=False``: one state after another (``prange`` over chunks of
  rows), the batch before issue 48, for the lanes' gain.
* ``Batch.forward``: ``mujoco.batch.Batch(m, nsim=B, nthread=k).forward()``: ``mj_forward`` of every
  row on MuJoCo's thread pool, each row's state loaded into an ``MjData`` and ``qacc`` copied out
  (bound before timing); the route-1 model, energy flag off.
* ``rollout``: ``Rollout(nthread=k).rollout(models, datas, x0, nstep=1, state=buf,
  skip_checks=True)``: one Euler ``mj_step`` per row (forward dynamics and the update, dt 1e-4 s)
  and its state copied into ``buf``: more work than ``q''`` alone, timed because it was the
  benchmark's only MuJoCo way before issue 23.

The ratio is urdf2links / the faster MuJoCo way of the row (smaller median), with the ratio of the
minima and the tie rule's verdict. The JSON records the largest difference between our ``q''`` and
``Batch.forward``'s ``qacc`` (rounding: ~1e-13 relative) and rollout's ``(q'_1 - q'_0) / dt``
(the Euler update's rounding divided by dt: ~1e-11). It also records what numba's threads do after a
batched call (``spin_cpu_ms``: the CPU time this process burns in the 50 ms after one, threads
asleep: ~0; libgomp's default active wait spins ~6 ms of a core after every parallel region, taking
it from whatever runs next -- urdf2links sets ``OMP_WAIT_POLICY=PASSIVE`` unless the user chose
otherwise, docs/speed.md). Threads: 1 and ``numba.get_num_threads()`` at start (all, or
``NUMBA_NUM_THREADS``). Usage::

    python benchmarks/batch_cost.py [--batches 1000 10000] [--rounds 5] [--out reports/benchmarks/batch_cost.json]
    python benchmarks/batch_cost.py --render-only
"""

from __future__ import annotations

import os
import time

import mujoco
import numba
import numpy as np
from mujoco import rollout as mj_rollout
from mujoco.batch import Batch

from benchmarking import (
    WIDE, chain, compare, fastest, fmt_ratio, fmt_spread, is_wide, load_models, markdown_table, measured, real,
    rounds, run_benchmark, spread,
)
from urdf2links.compare.mujoco_side.mjcf import mjcf_from_model
from urdf2links.locations import example_robot_data_dir

DT = 1e-4
MUJOCO_WAYS = ("Batch.forward", "rollout")


def models() -> list:
    # without example-robot-data, the shipped UR5-like arm stands in for its robots
    spare = () if example_robot_data_dir() is not None else ("ur5_like.urdf",)
    out = load_models(("double_pendulum.urdf", *spare), real("ur5", "talos", "g1"))
    return out + [chain(64)]


class MujocoStates:
    """B states ``(q, q')`` of the route-1 model and MuJoCo's two batched ways from them on ``k`` threads."""

    def __init__(self, model, Q, QD):
        mj = mjcf_from_model(model, gravity=model.gravity_vector, timestep=DT, integrator="Euler")
        m = mj.model
        m.opt.enableflags &= ~int(mujoco.mjtEnableBit.mjENBL_ENERGY)
        self.mj, self.m, self.B = mj, m, len(Q)
        d = mujoco.MjData(m)
        full, integ = mujoco.mjtState.mjSTATE_FULLPHYSICS, mujoco.mjtState.mjSTATE_INTEGRATION
        self.x0 = np.empty((len(Q), mujoco.mj_stateSize(m, full)))
        self.rows = np.empty((len(Q), mujoco.mj_stateSize(m, integ)))
        for b in range(len(Q)):
            mujoco.mj_resetData(m, d)
            mj.set_state(d, Q[b], QD[b])
            mujoco.mj_getState(m, d, self.x0[b], full)
            mujoco.mj_getState(m, d, self.rows[b], integ)
        self.buf = np.empty((len(Q), 1, self.x0.shape[1]))
        self.qd_at = 1 + m.nq + np.asarray(mj.dof_index)
        self.pools, self.batches, self.qacc = {}, {}, {}

    def ways(self, k: int) -> dict:
        """``{"Batch.forward": fn, "rollout": fn}`` on ``k`` threads; each ``fn()`` returns its seconds."""
        batch = Batch(self.m, self.B, nthread=k)
        batch.state[:] = self.rows
        self.qacc[k] = batch.bind("qacc")                     # registered before timing: copied out by every call
        self.batches[k] = batch
        pool = self.pools[k] = mj_rollout.Rollout(nthread=k if k > 1 else 0)
        datas = [mujoco.MjData(self.m) for _ in range(k)]
        models = [self.m] * self.B

        def forward():
            batch.state[:] = self.rows                        # the same states every round (forward keeps them)
            t0 = time.perf_counter()
            batch.forward()
            return time.perf_counter() - t0

        def step():
            t0 = time.perf_counter()
            pool.rollout(models, datas, self.x0, nstep=1, state=self.buf, skip_checks=True)
            return time.perf_counter() - t0

        return {"Batch.forward": forward, "rollout": step}

    def qdd_forward(self, k) -> np.ndarray:
        return np.array(self.qacc[k][:, np.asarray(self.mj.dof_index)])

    def qdd_rollout(self) -> np.ndarray:
        return (self.buf[:, 0, self.qd_at] - self.x0[:, self.qd_at]) / DT

    def close(self):
        for pool in self.pools.values():
            pool.close()


def spin_cpu_ms(model, Q, QD, k: int) -> float:
    """CPU milliseconds this process burns in the 50 ms after one batched call on ``k`` threads, while
    the calling thread sleeps: numba's worker threads waiting actively for the next call (median of 5)."""
    numba.set_num_threads(k)
    burnt = []
    for _ in range(5):
        model.forward_dynamics(Q, QD)
        c0 = time.process_time()
        time.sleep(0.05)
        burnt.append(1e3 * (time.process_time() - c0))
    return float(np.median(burnt))


def _key(name, k, side):
    return f"{name}|{k}|{side}"


SIDES = ("urdf2links", "rows")       # lanes (the default call) and the scalar rows (lanes=False)


def measure_batch(B, ms, ks, n_rounds, log) -> list[dict]:
    """Every model at batch size B: all models, thread counts ``ks`` and engines interleaved in one set of rounds."""
    rng = np.random.default_rng(0)
    setups, variants = [], {}
    for model in ms:
        Q, QD = rng.uniform(-1, 1, (B, model.n)), rng.normal(size=(B, model.n))
        model.forward_dynamics(Q[:2], QD[:2])                 # compile / load first
        states = MujocoStates(model, Q, QD)
        out = {}
        setups.append((model, Q, QD, states, out))
        model.forward_dynamics(Q[:2], QD[:2], lanes=False)
        for k in ks:
            def ours(k=k, model=model, Q=Q, QD=QD, out=out):
                numba.set_num_threads(k)
                t0 = time.perf_counter()
                out[k] = model.forward_dynamics(Q, QD)
                return time.perf_counter() - t0

            def rows(k=k, model=model, Q=Q, QD=QD, out=out):
                numba.set_num_threads(k)
                t0 = time.perf_counter()
                out[-k] = model.forward_dynamics(Q, QD, lanes=False)
                return time.perf_counter() - t0

            variants[_key(model.name, k, "urdf2links")] = ours
            variants[_key(model.name, k, "rows")] = rows
            for way, fn in states.ways(k).items():
                variants[_key(model.name, k, way)] = fn
    log(f"B = {B}: {len(ms)} models x threads {ks} x 4 ways, interleaved")
    try:
        times = rounds(variants, n_rounds)
        attempts = {model.name: 1 for model in ms}
        for model, *_ in setups:
            mine = {k: v for k, v in variants.items() if k.startswith(model.name + "|")}
            if any(is_wide(spread(times[k])) for k in mine):
                again, n = measured(mine, n_rounds, log=log)
                widest = max(max(times[k]) / min(times[k]) for k in mine)
                if max(max(v) / min(v) for v in again.values()) < widest:
                    times.update(again)
                attempts[model.name] += n
        rows = []
        for model, Q, QD, states, out in setups:
            row = {"robot": model.name, "n": model.n, "B": B, "attempts": attempts[model.name]}
            for k in ks:
                t = {"threads": k, **{f"{side}_s": spread(times[_key(model.name, k, side)])
                                      for side in (*SIDES, *MUJOCO_WAYS)}}
                ref = states.qdd_forward(k)
                t["max_rel_difference"] = {
                    "Batch.forward": float(np.abs(out[k] - ref).max() / np.abs(ref).max()),
                    "rollout": float(np.abs(out[k] - states.qdd_rollout()).max() / np.abs(ref).max()),
                    "rows": float(np.abs(out[k] - out[-k]).max() / np.abs(out[-k]).max())}
                t.update(comparisons(t))
                row[f"threads_{k}"] = t
                us = per_state_us(t, B)
                log(f"{model.name[:20]:20s} n {model.n:3d} B {B:6d} threads {k}: per state: lanes {us['urdf2links']:.3g} us, "
                    f"scalar rows {us['rows']:.3g} us, {t['mujoco']} {us['mujoco']:.3g} us; batch: lanes "
                    f"{fmt_spread(t['urdf2links_s'], 1e3)} ms, rows {fmt_spread(t['rows_s'], 1e3)} ms, Batch.forward "
                    f"{fmt_spread(t['Batch.forward_s'], 1e3)} ms, rollout {fmt_spread(t['rollout_s'], 1e3)} ms: "
                    f"lanes / {t['mujoco']} {fmt_ratio(t['vs_mujoco'])}, lanes / rows {fmt_ratio(t['vs_rows'])}")
            rows.append(row)
        return rows
    finally:
        numba.set_num_threads(max(ks))
        for *_, states, _out in setups:
            states.close()


def per_state_us(t, B) -> dict:
    """Microseconds per state (medians): lanes, scalar rows (when timed) and the faster MuJoCo way."""
    out = {"urdf2links": 1e6 * t["urdf2links_s"]["median"] / B, "mujoco": 1e6 * t[f"{t['mujoco']}_s"]["median"] / B}
    if "rows_s" in t:
        out["rows"] = 1e6 * t["rows_s"]["median"] / B
    return out


def comparisons(t) -> dict:
    """The faster MuJoCo way of a row and thread count, and urdf2links against it and against each way
    under the tie rule (from the spreads: the render recomputes them); the lanes against the scalar rows."""
    way = fastest({w: t[f"{w}_s"] for w in MUJOCO_WAYS})
    out = {"mujoco": way, "vs_mujoco": compare(t["urdf2links_s"], t[f"{way}_s"]),
           "vs_ways": {w: compare(t["urdf2links_s"], t[f"{w}_s"]) for w in MUJOCO_WAYS}}
    if "rows_s" in t:
        out["vs_rows"] = compare(t["urdf2links_s"], t["rows_s"])
    return out


def _thread_keys(data):
    return [f"threads_{k}" for k in data.get("thread_counts", sorted({1, data["threads"]}))]


def lanes_line(data) -> str:
    """The CPU's vector width and the lanes' block width, as measured (empty for a JSON from before issue 48)."""
    w = data.get("lanes")
    if not w:
        return ""
    return (f"Lanes: {w['vector_doubles']} doubles per vector register ({w['isa']}), blocks of {w['width']} states "
            f"({w['reason']}); numba may use {data['cpu_threads']} threads (NUMBA_NUM_THREADS), os.cpu_count() "
            f"{data['cpu_count']}.")


def table(data) -> str:
    if data.get("lanes"):
        return table_lanes(data)
    head = ["robot", "n", "B", "threads", "urdf2links ms", "Batch.forward ms", "rollout nstep=1 ms", "faster MuJoCo",
            "urdf2links / faster MuJoCo", "max rel. difference of q''"]
    body = []
    for r in data["rows"]:
        for key in _thread_keys(data):
            t = r[key]
            body.append([r["robot"], r["n"], r["B"], t["threads"], fmt_spread(t["urdf2links_s"], 1e3),
                         fmt_spread(t["Batch.forward_s"], 1e3), fmt_spread(t["rollout_s"], 1e3), t["mujoco"],
                         fmt_ratio(t["vs_mujoco"]), f"{t['max_rel_difference']['Batch.forward']:.1e}"])
    again = [f"{r['robot']} at B = {r['B']} ({r['attempts']} attempts)" for r in data["rows"] if r["attempts"] > 1]
    spin = data["after_a_call"]
    return ("# Batched forward dynamics against MuJoCo's batched calls\n\n"
            f"Milliseconds per batch of B states, median (min-max) over {data['rounds']} rounds in one process; at each "
            "B every model, thread count and engine runs in the same rounds (interleaved, the order reversed every "
            "other round). urdf2links: one call model.forward_dynamics(Q, QD) (gravity, fixed base), numba threads "
            "set with numba.set_num_threads. Batch.forward: mujoco.batch.Batch(m, B, nthread).forward(), mj_forward "
            "of every row on MuJoCo's thread pool, qacc copied out. rollout nstep=1: Rollout(nthread).rollout(..., "
            "nstep=1) from the same states (Euler, dt 1e-4 s): one mj_step per row and its state copied out (more "
            "work than q''). The ratio is against the faster MuJoCo way of the row: ratio of the medians, (min: of "
            "the minima), and the tie rule's verdict (faster or slower only when the spreads do not overlap). Last "
            "column: largest difference between our q'' and Batch.forward's qacc, relative to its largest entry.\n\n"
            + markdown_table(head, body) + "\n\n"
            + (f"Measured again for a wide spread (max/min > {data['wide']:g}): {', '.join(again)}.\n\n" if again else "")
            + f"After a batched call on {data['threads']} threads numba's worker threads burnt "
              f"{spin['spin_cpu_ms']:.1f} ms of CPU in the next 50 ms (threading layer {spin['threading_layer']}, "
              f"OMP_WAIT_POLICY {spin['OMP_WAIT_POLICY']}): CPU taken from whatever runs next, MuJoCo's threads here.")


def table_lanes(data) -> str:
    """The table of a JSON with the lanes (issue 48): lanes, scalar rows, both MuJoCo ways, per-state times."""
    head = ["robot", "n", "B", "threads", "urdf2links lanes ms", "scalar rows ms", "Batch.forward ms",
            "rollout nstep=1 ms", "us per state: lanes / rows / faster MuJoCo", "faster MuJoCo",
            "lanes / faster MuJoCo", "lanes / rows", "max rel. difference of q'' (MuJoCo; rows)"]
    body = []
    for r in data["rows"]:
        for key in _thread_keys(data):
            t = r[key]
            us = per_state_us(t, r["B"])
            d = t["max_rel_difference"]
            body.append([r["robot"], r["n"], r["B"], t["threads"], fmt_spread(t["urdf2links_s"], 1e3),
                         fmt_spread(t["rows_s"], 1e3), fmt_spread(t["Batch.forward_s"], 1e3),
                         fmt_spread(t["rollout_s"], 1e3), f"{us['urdf2links']:.3g} / {us['rows']:.3g} / {us['mujoco']:.3g}",
                         t["mujoco"], fmt_ratio(t["vs_mujoco"]), fmt_ratio(t["vs_rows"]),
                         f"{d['Batch.forward']:.1e}; {d['rows']:.1e}"])
    again = [f"{r['robot']} at B = {r['B']} ({r['attempts']} attempts)" for r in data["rows"] if r["attempts"] > 1]
    spin = data["after_a_call"]
    return ("# Batched forward dynamics against MuJoCo's batched calls\n\n"
            f"Milliseconds per batch of B states, median (min-max) over {data['rounds']} rounds in one process; at each "
            "B every model, thread count and engine runs in the same rounds (interleaved, the order reversed every "
            "other round). urdf2links lanes: one call model.forward_dynamics(Q, QD) (gravity, fixed base): blocks of "
            "states in SIMD lanes (issue 48); scalar rows: the same call with lanes=False, one state after another. "
            "Numba threads set with numba.set_num_threads. Batch.forward: mujoco.batch.Batch(m, B, nthread).forward(), "
            "mj_forward of every row on MuJoCo's thread pool, qacc copied out. rollout nstep=1: "
            "Rollout(nthread).rollout(..., nstep=1) from the same states (Euler, dt 1e-4 s): one mj_step per row and "
            "its state copied out (more work than q''). Ratios: of the medians, (min: of the minima), and the tie "
            "rule's verdict (faster or slower only when the spreads do not overlap). Last column: largest "
            "difference of our q'' from Batch.forward's qacc, and of the lanes from the scalar rows, relative to "
            "the largest entry.\n\n"
            + lanes_line(data) + "\n\n"
            + markdown_table(head, body) + "\n\n"
            + (f"Measured again for a wide spread (max/min > {data['wide']:g}): {', '.join(again)}.\n\n" if again else "")
            + f"After a batched call on {data['threads']} threads numba's worker threads burnt "
              f"{spin['spin_cpu_ms']:.1f} ms of CPU in the next 50 ms (threading layer {spin['threading_layer']}, "
              f"OMP_WAIT_POLICY {spin['OMP_WAIT_POLICY']}): CPU taken from whatever runs next, MuJoCo's threads here.")


def plot(data):
    from urdf2links.compare.figures import figure

    keys = _thread_keys(data)
    rows = data["rows"]
    fig = figure(10.0, 4.4, dpi=100)
    axes = fig.subplots(1, len(data["batches"]), squeeze=False)[0]
    colours = {"urdf2links": ("#2171b5", "#6baed6"), "mujoco": ("#cb181d", "#fc9272")}
    for ax, B in zip(axes, data["batches"]):
        sub = [r for r in rows if r["B"] == B]
        x = np.arange(len(sub))
        j = 0
        for side in ("urdf2links", "mujoco"):
            for ki, key in enumerate(keys):
                k = key.split("_")[1]
                spreads = [r[key][f"{r[key]['mujoco'] if side == 'mujoco' else side}_s"] for r in sub]
                med = np.array([s["median"] * 1e6 / B for s in spreads])
                err = np.array([[(s["median"] - s["min"]) * 1e6 / B, (s["max"] - s["median"]) * 1e6 / B]
                                for s in spreads]).T
                label = (f"urdf2links forward_dynamics{' (lanes)' if data.get('lanes') else ''}, {k} thread(s)"
                         if side == "urdf2links"
                         else f"faster MuJoCo way, {k} thread(s)")
                ax.bar(x + (j - 1.5) * 0.2, med, 0.19, color=colours[side][ki % 2], label=label, yerr=err, capsize=2)
                j += 1
        for xi, r in zip(x, sub):
            for ki, key in enumerate(keys):
                if r[key]["vs_mujoco"]["verdict"] == "tie":
                    top = r[key]["urdf2links_s"]["max"] * 1e6 / B
                    ax.annotate("tie", (xi + (ki - 1.5) * 0.2, top), fontsize=6, ha="center", xytext=(0, 2),
                                textcoords="offset points")
        ax.set_yscale("log")
        ax.set_xticks(x, [f"{r['robot']}\nn={r['n']}" for r in sub], fontsize=7, rotation=30, ha="right")
        ax.set_title(f"B = {B}", fontsize=9)
        ax.set_ylabel("us per state (median; bars min-max)")
        ax.grid(axis="y", which="both", alpha=0.3)
    axes[0].legend(fontsize=7)
    fig.suptitle("Batched forward dynamics against the faster of MuJoCo's Batch.forward and rollout(nstep=1)",
                 fontsize=10)
    return fig


def thread_counts(spec) -> list[int]:
    """``--threads`` as numbers: ``all`` is every thread numba may use (``numba.config.NUMBA_NUM_THREADS``)."""
    out = set()
    for x in spec:
        k = numba.config.NUMBA_NUM_THREADS if x == "all" else int(x)
        if not 1 <= k <= numba.config.NUMBA_NUM_THREADS:
            raise SystemExit(f"--threads {x}: numba may use 1 to {numba.config.NUMBA_NUM_THREADS} threads here "
                             "(NUMBA_NUM_THREADS); give a number in that range or all")
        out.add(k)
    return sorted(out)


def measure_all(args, log) -> dict:
    from urdf2links.dynamics.lane_batch import lane_width

    ks = thread_counts(args.threads)
    threads = max(ks)
    w = lane_width()
    lanes = {"width": w.width, "vector_doubles": w.vector_doubles, "isa": w.isa, "reason": w.reason}
    log(f"lanes: {w.reason}; threads {ks} (numba may use {numba.config.NUMBA_NUM_THREADS}, os.cpu_count() "
        f"{os.cpu_count()})")
    ms = models()
    rows = [r for B in args.batches for r in measure_batch(B, ms, ks, args.rounds, log)]
    model = ms[-1]
    rng = np.random.default_rng(1)
    Q, QD = rng.uniform(-1, 1, (1000, model.n)), rng.normal(size=(1000, model.n))
    after = {"spin_cpu_ms": spin_cpu_ms(model, Q, QD, threads), "threading_layer": numba.threading_layer(),
             "OMP_WAIT_POLICY": os.environ.get("OMP_WAIT_POLICY", "unset"), "model": model.name, "B": 1000}
    numba.set_num_threads(threads)
    log(f"after a batched call: {after['spin_cpu_ms']:.1f} ms of CPU burnt in 50 ms")
    return {"rounds": args.rounds, "wide": WIDE, "batches": list(args.batches), "threads": threads, "dt": DT,
            "thread_counts": ks, "cpu_threads": numba.config.NUMBA_NUM_THREADS, "cpu_count": os.cpu_count(),
            "lanes": lanes, "after_a_call": after, "rows": rows}


def render(data):
    for r in data["rows"]:
        for key in _thread_keys(data):
            r[key].update(comparisons(r[key]))
    return table(data), plot(data)


def options(p):
    p.add_argument("--batches", type=int, nargs="+", default=[1000, 10000], help="batch sizes (default 1000 10000)")
    p.add_argument("--threads", nargs="+", default=["1", "all"],
                   help="numba thread counts, numbers or all (NUMBA_NUM_THREADS) (default 1 all)")


if __name__ == "__main__":
    run_benchmark("batch_cost", __doc__, measure_all, render, options=options)

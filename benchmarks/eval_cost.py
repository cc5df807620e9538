"""Cost of every public ``Model`` call against MuJoCo's mj_forward on the same model (route 1: the
project's tree as MJCF), in the same process.

Timed, one call per evaluation from Python, arguments already in arrays: ``forward_dynamics(q, qd)``,
``mass_matrix(q)``, ``bias(q, qd)``, ``gravity(q)``, ``generalized_forces(q, [one Wrench])`` (a force,
a moment and an offset point on the last link), ``kinetic_energy(q, qd)``, ``potential_energy(q)``,
``inverse_dynamics(q, qd, qdd)`` and ``mujoco.mj_forward(m, d)``; for the inverse dynamics also its
peers, ``mujoco.mj_inverse(m, d)`` (``qacc`` set once) and Pinocchio's ``pin.rnea(model, data, q, v, a)``
(from Python too, the same way; Pinocchio reads the same URDF, the chains as URDF text of the same
rods); at one random state (q uniform in [-1, 1], qd and qdd normal, seed 0). A round times ``--reps``
calls of each and keeps their median; rounds interleave all of them (the order reversed every other
round); each figure is the median (min-max) over the rounds, and a model whose spread is wide is
measured again (benchmarking.measured). Each call is compared with mj_forward and with
forward_dynamics, and inverse_dynamics with mj_inverse and rnea, under the tie rule
(benchmarking.compare): ratio of medians, ratio of minima, and faster / slower only when the spreads
do not overlap. Models: n-link chains (spatial pendulums, hinges alternating x / y) and the shipped
and (when installed) real robots. Without Pinocchio (``pip install pin``, in the test extra) its
column is left out.

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
         "potential_energy", "inverse_dynamics")
#: The inverse dynamics' peers: MuJoCo's and Pinocchio's (timed from Python like every call here).
ID_PEERS = ("mj_inverse", "pin_rnea")
VARIANTS = (*CALLS, "mj_forward", *ID_PEERS)
#: The curves of the growth section and the plot.
GROWTH = ("forward_dynamics", "mass_matrix", "mj_forward")


def median_time(fn, reps: int) -> float:
    times = np.empty(reps)
    for k in range(reps):
        t0 = time.perf_counter()
        fn()
        times[k] = time.perf_counter() - t0
    return float(np.median(times))


def calls(model: Model, q, qd, qdd) -> dict:
    """Each public call of ``model`` at ``(q, qd)`` (and ``qdd``), as a function of nothing."""
    loads = [Wrench(model.link_names[-1], force=[1.0, -2.0, 3.0], moment=[0.1, 0.2, -0.3], point=[0.05, 0.0, -0.1])]
    return {"forward_dynamics": lambda: model.forward_dynamics(q, qd), "mass_matrix": lambda: model.mass_matrix(q),
            "bias": lambda: model.bias(q, qd), "gravity": lambda: model.gravity(q),
            "generalized_forces": lambda: model.generalized_forces(q, loads),
            "kinetic_energy": lambda: model.kinetic_energy(q, qd), "potential_energy": lambda: model.potential_energy(q),
            "inverse_dynamics": lambda: model.inverse_dynamics(q, qd, qdd)}


def chain_urdf(n: int) -> str:
    """benchmarking.chain(n) as URDF text (the same rods: 1 kg, COM 0.25 m below the joint, inertia about the
    COM diag(0.011, 0.011, 0.02), joints 0.5 m apart, axes alternating x / y), for Pinocchio."""
    parts = ['<robot name="chain"><link name="world"/>']
    for i in range(n):
        parts.append(f'<joint name="q{i}" type="continuous"><parent link="{"world" if i == 0 else f"l{i - 1}"}"/>'
                     f'<child link="l{i}"/><origin xyz="0 0 {0 if i == 0 else -0.5}"/>'
                     f'<axis xyz="{"1 0 0" if i % 2 == 0 else "0 1 0"}"/></joint>'
                     f'<link name="l{i}"><inertial><origin xyz="0 0 -0.25"/><mass value="1"/>'
                     '<inertia ixx="0.011" iyy="0.011" izz="0.02" ixy="0" ixz="0" iyz="0"/></inertial></link>')
    return "".join(parts) + "</robot>"


def pinocchio_rnea(model: Model, q, qd, qdd):
    """Pinocchio's ``rnea`` on the same robot at the same state, as a function of nothing (None without
    Pinocchio), and the state map (joint names; a continuous joint is ``(cos, sin)`` in Pinocchio's q).
    ``check()`` returns the largest difference to ``model.inverse_dynamics`` (the same model, or not timed)."""
    try:
        import pinocchio as pin
    except ImportError:
        return None
    pm = pin.buildModelFromXML(chain_urdf(model.n)) if model.name.startswith("chain") else \
        pin.buildModelFromUrdf(str(model.source))
    qp, vp, ap = pin.neutral(pm), np.zeros(pm.nv), np.zeros(pm.nv)
    for i, name in enumerate(model.coordinate_names):
        jm = pm.joints[pm.getJointId(name)]
        if jm.nq == 2:
            qp[jm.idx_q:jm.idx_q + 2] = (np.cos(q[i]), np.sin(q[i]))
        else:
            qp[jm.idx_q] = q[i]
        vp[jm.idx_v], ap[jm.idx_v] = qd[i], qdd[i]
    data = pin.Data(pm)
    perm = [pm.joints[pm.getJointId(name)].idx_v for name in model.coordinate_names]
    fn = lambda: pin.rnea(pm, data, qp, vp, ap)     # noqa: E731
    repaired = any(getattr(r, "action", "") == "repaired" for r in model.audit)   # Pinocchio reads the file as written
    fn.check = (lambda: None) if repaired else (lambda: float(np.abs(fn()[perm] - model.inverse_dynamics(q, qd, qdd)).max()))
    return fn


def measure(model: Model, reps: int, n_rounds: int, log=None) -> dict:
    mj = mjcf_from_model(model, gravity=model.gravity_vector)
    d = mujoco.MjData(mj.model)
    rng = np.random.default_rng(0)
    q, qd, qdd = rng.uniform(-1, 1, model.n), rng.normal(size=model.n), rng.normal(size=model.n)
    d.qpos[mj.qpos_index] = q
    d.qvel[mj.dof_index] = qd
    di = mujoco.MjData(mj.model)
    di.qpos[mj.qpos_index], di.qvel[mj.dof_index], di.qacc[mj.dof_index] = q, qd, qdd
    ours = calls(model, q, qd, qdd)
    for fn in ours.values():                                 # compile / load the kernels first
        fn()
    variants = {k: (lambda fn=fn: median_time(fn, reps)) for k, fn in ours.items()}
    variants["mj_forward"] = lambda: median_time(lambda: mujoco.mj_forward(mj.model, d), reps)
    variants["mj_inverse"] = lambda: median_time(lambda: mujoco.mj_inverse(mj.model, di), reps)
    rnea = pinocchio_rnea(model, q, qd, qdd)
    agree = {"mj_inverse": _agreement(mj, di, model, q, qd, qdd)}
    if rnea is not None:
        agree["pin_rnea"] = rnea.check()
        variants["pin_rnea"] = lambda: median_time(rnea, reps)
    times, attempts = measured(variants, n_rounds, log=log)
    row = {"robot": model.name, "n": model.n, "chain": model.name.startswith("chain"), "attempts": attempts,
           "inverse_agreement": agree, **{f"{k}_s": spread(v) for k, v in times.items()}}
    row.update(comparisons(row))
    return row


def _agreement(mj, d, model, q, qd, qdd) -> float:
    """``max |inverse_dynamics - qfrc_inverse|`` at the timed state (the timed calls compute the same)."""
    mujoco.mj_inverse(mj.model, d)
    return float(np.abs(np.asarray(d.qfrc_inverse)[mj.dof_index] - model.inverse_dynamics(q, qd, qdd)).max())


def _calls(row) -> tuple[str, ...]:
    """The calls a row has (a JSON written before inverse_dynamics was timed renders without it)."""
    return tuple(k for k in CALLS if f"{k}_s" in row)


def comparisons(row) -> dict:
    """Each call against mj_forward and against forward_dynamics, inverse_dynamics against mj_inverse and
    rnea, under the tie rule (from the spreads: the render recomputes them, so that a table never disagrees
    with its figures)."""
    calls_ = _calls(row)
    out = {"vs_mj_forward": {k: compare(row[f"{k}_s"], row["mj_forward_s"]) for k in calls_},
           "vs_forward_dynamics": {k: compare(row[f"{k}_s"], row["forward_dynamics_s"]) for k in calls_[1:]}}
    if "inverse_dynamics_s" in row:
        out["vs_inverse_peers"] = {k: compare(row["inverse_dynamics_s"], row[f"{k}_s"]) for k in ID_PEERS
                                   if f"{k}_s" in row}
    return out


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


def _inverse_section(rows) -> str:
    """inverse_dynamics against mj_inverse and Pinocchio's rnea (rows that timed them)."""
    rows = [r for r in rows if "inverse_dynamics_s" in r]
    if not rows:
        return ""
    peers = [k for k in ID_PEERS if any(f"{k}_s" in r for r in rows)]
    names = {"mj_inverse": "MuJoCo mj_inverse", "pin_rnea": "Pinocchio rnea"}
    body = markdown_table(
        ["robot", "n", "inverse_dynamics", *(names[k] for k in peers), *(f"inverse_dynamics / {names[k]}" for k in peers),
         "max difference (N m)"],
        [[r["robot"], r["n"], fmt_spread(r["inverse_dynamics_s"], 1e6),
          *(fmt_spread(r[f"{k}_s"], 1e6) if f"{k}_s" in r else "-" for k in peers),
          *(fmt_ratio(r["vs_inverse_peers"][k]) if k in r["vs_inverse_peers"] else "-" for k in peers),
          ", ".join(f"{names[k].split()[-1]} " + ("- (inertias repaired)" if v is None else f"{v:.1e}")
                    for k, v in r.get("inverse_agreement", {}).items())]
         for r in rows])
    return ("## Inverse dynamics against mj_inverse and Pinocchio's rnea\n\n`inverse_dynamics(q, qd, qdd)` (one compiled "
            "O(n) pass, E54) against MuJoCo's `mj_inverse` (`qacc` set, route 1's model) and Pinocchio's `pin.rnea` (the "
            "same URDF), all three called from Python at the same state; microseconds, median (min-max), the ratio "
            "under the tie rule, and the largest difference of the results at that state.\n\n" + body + "\n\n")


def table(data) -> str:
    rows, slopes = data["rows"], data["growth"]
    calls_ = _calls(rows[0])
    us = markdown_table(["robot", "n", "mj_forward", *calls_],
                        [[r["robot"], r["n"], fmt_spread(r["mj_forward_s"], 1e6),
                          *(fmt_spread(r[f"{k}_s"], 1e6) for k in calls_)] for r in rows])
    vs_mj = markdown_table(["robot", "n", *(f"{k} / mj_forward" for k in calls_)],
                           [[r["robot"], r["n"], *(fmt_ratio(r["vs_mj_forward"][k]) for k in calls_)] for r in rows])
    vs_fd = markdown_table(["robot", "n", *(f"{k} / forward_dynamics" for k in calls_[1:])],
                           [[r["robot"], r["n"], *(fmt_ratio(r["vs_forward_dynamics"][k]) for k in calls_[1:])]
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
            "costs), same rule.\n\n" + vs_fd + "\n\n" + _inverse_section(rows)
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

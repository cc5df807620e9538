"""What identification costs: the regressor, the base parameters and the fit, on one core.

For the Panda (7 arm joints and its 2 finger joints: 9 coordinates, 146 parameters) and Talos
(talos_reduced, 32 joints, 448 parameters) of example-robot-data: a smooth excitation (per coordinate a sum of
5 sines, within +-1 rad, with its exact q' and q''), 20,000 samples, torques from the description's
regressor with planted joint terms (damping, Coulomb friction, offset) and Gaussian noise (0.01 N m). Every
link parameter (10 per moving link) and every joint parameter (damping, friction, armature, offset) is fitted.

Timed, warm (the compiled code loaded and run once before), numba on one thread and BLAS on one thread
(``NUMBA_NUM_THREADS=1``, ``OPENBLAS_NUM_THREADS=1``, set before numpy loads), ``--rounds`` interleaved rounds,
median (min-max):

* ``base``: ``base_parameters`` (the regressor on 200 spread samples, the QR, the null space's pivoted QR, E91);
* ``normal``: ``normal_equations`` over all samples (the compiled regressor in blocks, each coordinate's own
  base columns, BLAS per coordinate);
* ``identify``: the whole least-squares fit (``identify``: both of the above, the solve, the standard
  deviations): the figure the targets are about (Panda <= 1 s, Talos <= 10 s);
* ``consistent``: the semidefinite program of the consistent fit (E92) on the fit's normal equations (cvxpy,
  Clarabel), beside, not in the targets.

Usage::

    python benchmarks/identify_cost.py [--rounds 3] [--samples 20000]
    python benchmarks/identify_cost.py --render-only
"""

from __future__ import annotations

import os

os.environ.setdefault("NUMBA_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import time  # noqa: E402
import warnings  # noqa: E402

import numpy as np  # noqa: E402

from benchmarking import REAL_ROBOTS, fmt_spread, markdown_table, measured, run_benchmark, spread  # noqa: E402
from urdf2links import load_urdf  # noqa: E402
from urdf2links.identification import (ParameterSet, base_parameters, consistent_fit, identify,  # noqa: E402
                                       normal_equations, regressor)
from urdf2links.locations import example_robot_data_dir  # noqa: E402

TARGETS = {"panda": 1.0, "talos": 10.0}


def excitation(n, S, seed, dt=0.002):
    """``t, q, q', q''`` (S, n): per coordinate 5 sines of 0.1-1 Hz, amplitudes summing to 1 rad."""
    rng = np.random.default_rng(seed)
    t = np.arange(S) * dt
    w = 2 * np.pi * rng.uniform(0.1, 1.0, (5, n))
    a = rng.uniform(0.2, 1.0, (5, n))
    a /= a.sum(axis=0)
    c = rng.uniform(0, 2 * np.pi, (5, n))
    ph = t[:, None, None] * w[None] + c[None]
    return (t, np.sum(a * np.sin(ph), axis=1), np.sum(a * w * np.cos(ph), axis=1),
            -np.sum(a * w ** 2 * np.sin(ph), axis=1))


def case(name, S):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = load_urdf(example_robot_data_dir() / REAL_ROBOTS[name])
    params = ParameterSet.from_model(model)
    _, Q, QD, QDD = excitation(model.n, S, 1)
    rng = np.random.default_rng(2)
    truth = params.values.copy()
    for kind in ("damping", "friction", "offset"):
        for cn in model.coordinate_names:
            truth[params.index(f"{kind}_{cn}")] = rng.uniform(0.05, 0.5)
    TAU = np.concatenate([regressor(params, Q[k:k + 2000], QD[k:k + 2000], QDD[k:k + 2000]) @ truth
                          for k in range(0, S, 2000)])
    TAU += 0.01 * rng.normal(size=TAU.shape)
    return model, params, (Q, QD, QDD, TAU)


def measure(args, log):
    rows, state = [], {}
    for name in ("panda", "talos"):
        model, params, data = case(name, args.samples)
        Q, QD, QDD, TAU = data
        fit = identify(params, *data)          # warm: compiled code loaded and run once
        state[name] = fit
        base = fit.base
        t0 = time.perf_counter()
        cfit = consistent_fit(fit)
        cons_first = time.perf_counter() - t0
        variants = {
            f"{name} base": lambda p=params: base_parameters(p, Q, QD, QDD) and None,
            f"{name} normal": lambda b=base: normal_equations(b, Q, QD, QDD, TAU) and None,
            f"{name} identify": lambda p=params: identify(p, Q, QD, QDD, TAU) and None,
            f"{name} consistent": lambda f=fit: consistent_fit(f) and None,
        }
        times, attempts = measured(variants, args.rounds, log=log)
        rows.append({"robot": name, "file": REAL_ROBOTS[name], "n": model.n, "parameters": params.p,
                     "identifiable": base.r, "unidentifiable": len(base.dependent), "samples": args.samples,
                     "condition_number": fit.condition_number, "sigma": fit.sigma,
                     "rms_before": float(np.sqrt(np.mean(fit.rms_before ** 2))),
                     "rms_after": float(np.sqrt(np.mean(fit.rms_after ** 2))), "target_s": TARGETS[name],
                     "consistent_moved": len(cfit.consistency.moved), "consistent_first_s": cons_first,
                     "attempts": attempts, **{k.split()[1] + "_s": spread(v) for k, v in times.items()}})
    return {"rounds": args.rounds, "samples": args.samples, "threads": {"numba": os.environ["NUMBA_NUM_THREADS"],
            "blas": os.environ["OPENBLAS_NUM_THREADS"]}, "load": os.getloadavg(), "rows": rows}


def render(data):
    head = ["robot", "n", "parameters", "identifiable", "cond", "base s", "normal equations s", "identify s",
            "target s", "within", "consistent SDP s"]
    body = [[r["robot"], r["n"], r["parameters"], r["identifiable"], f"{r['condition_number']:.3g}",
             fmt_spread(r["base_s"]), fmt_spread(r["normal_s"]), fmt_spread(r["identify_s"]), f"{r['target_s']:g}",
             "yes" if r["identify_s"]["median"] <= r["target_s"] else "NO", fmt_spread(r["consistent_s"])]
            for r in data["rows"]]
    fits = [[r["robot"], r["samples"], f"{r['sigma']:.4g}", f"{r['rms_before']:.4g}", f"{r['rms_after']:.4g}",
             r["unidentifiable"], r["consistent_moved"]] for r in data["rows"]]
    load = ", ".join(f"{x:.1f}" for x in data["load"])
    md = ("# What identification costs\n\n"
          f"{data['samples']} samples of a smooth excitation, every link and joint parameter; one core (numba "
          f"threads {data['threads']['numba']}, BLAS threads {data['threads']['blas']}); warm; seconds, median "
          f"(min-max) of {data['rounds']} interleaved rounds. `identify` is the whole least-squares fit (base "
          "parameters + normal equations + solve + standard deviations); the consistent fit's semidefinite program "
          f"is beside it. Load average while measuring: {load} (a shared 2-core machine: the figures are upper "
          "bounds of a quiet core's).\n\n" + markdown_table(head, body)
          + "\n\nMuJoCo's system-identification toolbox on this kind of 2-core machine (issue 46's figures, not "
          "measured here): a Panda from 15 s of data (7,500 steps) in 0.75 s for 4 parameters and 4.1 s for 22 "
          "(finite differences over rollouts, 2 threads). A linear regressor needs no rollouts.\n\n"
          "## The fits\n\nNoise 0.01 N m planted; sigma is the estimate; the torque residual's root mean square "
          "over the coordinates with the description's values (before: the planted joint terms) and the "
          "identified ones (after).\n\n"
          + markdown_table(["robot", "samples", "sigma", "rms before", "rms after", "kept at description",
                            "links the consistent fit moved"], fits))
    return md, None


def options(p):
    p.add_argument("--samples", type=int, default=20000, help="samples per robot (default 20000)")


if __name__ == "__main__":
    run_benchmark("identify_cost", __doc__, measure, render, options=options, rounds_default=3)

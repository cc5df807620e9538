"""``urdf2links identify DESCRIPTION --data FILE``: a robot's log read, checked, differentiated and fitted.

The options are added to the ``identify`` command by :func:`add_data_options`; :func:`run_identify_data`
runs them (no MuJoCo: the log is the data). Steps, as docs/logs.md says: :func:`read_log` (CSV, NPZ, a
ROS 2 bag with ``--topic``; ``--from``/``--to``), :func:`check_log` (named errors), :func:`derivatives`
(the stated filter, its figure), the base parameters and :func:`check_samples`, then
:func:`~urdf2links.identification.from_log.identify_log` (accelerations and the energy form, weighted least
squares, 95% intervals). A floating base without efforts (``--base-topic`` or ``base.*`` columns) is fitted
from its base rows (:mod:`urdf2links.identification.floating`). Every bad-data error is printed as its one
line and the command returns 2.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

__all__ = ["add_data_options", "run_identify_data"]


def add_data_options(p) -> None:
    """``--data`` and its options on the ``identify`` parser."""
    p.add_argument("--data", metavar="FILE", help="fit to a robot's log instead: CSV, NPZ or a ROS 2 bag (docs/logs.md)")
    p.add_argument("--topic", default="/joint_states", help="the bag's sensor_msgs/JointState topic (default /joint_states)")
    p.add_argument("--wrench-topic", help="a bag's geometry_msgs/WrenchStamped topic: contact wrenches on the base")
    p.add_argument("--base-topic", help="a bag's Odometry or PoseStamped topic: a floating base's pose")
    p.add_argument("--from", dest="t_from", type=float, help="start of the segment, s (the log's own time)")
    p.add_argument("--to", dest="t_to", type=float, help="end of the segment, s")
    p.add_argument("--filter", choices=("savgol", "spline"), default="savgol", help="the derivatives' filter")
    p.add_argument("--cutoff", type=float, help="the filter's -3 dB bandwidth in Hz (default 10)")
    p.add_argument("--order", type=int, default=5, help="Savitzky-Golay polynomial order (default 5: its acceleration is flat to 0.2%% at a tenth of the bandwidth; 3 biases it by ~1%%)")


def _load(args):
    from urdf2links.identification import ParameterSet
    from urdf2links.parsers.robot_file import load_robot

    floating = bool(args.base_topic) or _has_base_columns(args.data)
    model = load_robot(args.file, floating_base=True) if floating else load_robot(args.file)
    # a floating base's rows see no joint term, and the root's six coordinates have none: links only (E97)
    return model, ParameterSet.from_model(model, joints=() if floating else ("damping", "friction", "armature",
                                                                               "offset")), floating


def _has_base_columns(path) -> bool:
    p = Path(path)
    if p.suffix.lower() != ".csv" or not p.is_file():
        return False
    with p.open() as f:
        return "base.qw" in f.readline()


def run_identify_data(args) -> int:
    """Read, check, differentiate, fit, print; write ``identify.json`` and ``filter.png`` into ``--out``."""
    from urdf2links.robot_logs import LogError, angular_limits, check_log, check_samples, derivatives, read_log

    try:
        model, params, floating = _load(args)
        log = read_log(args.data, topic=args.topic, wrench_topic=args.wrench_topic, base_topic=args.base_topic,
                       t_from=args.t_from, t_to=args.t_to)
        print(log.describe())
        joints = [c for c in model.coordinate_names if "." not in c] if floating else model.coordinate_names
        log = check_log(log, joints=joints, limits=angular_limits(model))
        d = derivatives(log, method=args.filter, cutoff_hz=args.cutoff, order=args.order)
        print(d.describe())
        for note in (*log.notes, *d.notes):
            print(f"  note: {note}")
        if floating:
            from urdf2links.identification.floating import identify_floating

            result = identify_floating(params, d)
            check_samples(log, n_base=result.base.r, equations_per_sample=6)
        else:
            from urdf2links.identification.base import base_parameters
            from urdf2links.identification.from_log import identify_log

            sl = d.interior
            base = base_parameters(params, d.positions[sl], d.velocities[sl], d.accelerations[sl])
            check_samples(log, n_base=base.r)
            result = identify_log(params, d, base=base)
    except LogError as err:
        print(f"urdf2links identify: {err}", file=sys.stderr)
        return 2
    out = Path(args.out) if args.out else Path("out/reports/identify") / Path(args.file).stem
    out.mkdir(parents=True, exist_ok=True)
    d.plot(out / "filter.png")
    _print(result, floating)
    (out / "identify.json").write_text(json.dumps({"summary": result.summary(), "table": result.table()}, indent=1))
    print(f"wrote {out / 'identify.json'} and {out / 'filter.png'}")
    return 0


def _print(result, floating: bool) -> None:
    s = result.summary()
    fit = result.acceleration if not floating else result.fit
    print(f"{result.base.r} base parameters of {result.params.p}; condition number {fit.condition_number:.4g}; "
          f"noise per row: " + ", ".join(f"{x:.3g}" for x in fit.sigma))
    for w in fit.warnings:
        print(f"  warning: {w}")
    for row in result.table():
        lo, hi = row["interval95"]
        extra = (f"   energy {row['energy']:.6g} +- {row['energy_std']:.2g}" if "energy" in row else "")
        est = row.get("acceleration", row.get("identified"))
        print(f"  {row['combination'][:70]:<70} {est:.6g} +- {row['std']:.2g} [{lo:.6g}, {hi:.6g}]{extra}")
    if not floating and result.energy is not None:
        print("accelerations vs energy form: torque residual RMS per joint "
              + ", ".join(f"{a:.3g}/{b:.3g}" for a, b in zip(result.acceleration.rms, result.energy_rms))
              + f"; largest difference {s['agreement_max']:.2f} standard deviations")
    for note in s["notes"]:
        print(f"  note: {note}")
    _ = np

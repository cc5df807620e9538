"""The ``identify`` command's handler (its options: :mod:`urdf2links.commands.identify`)."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from urdf2links.locations import DEFAULT_OUT

from ..pairs.mapping import parse_map
from .pipeline import identify
from .report import write_outputs
from .writers import inconsistent_bodies, planned_changes, urdf_values, write_mjcf, write_urdf

__all__ = ["identify_command"]


def design_command(args) -> int:
    """``--design OUT.toml``: the excitation scene (:mod:`.design`)."""
    from urdf2links.parsers.parts import parts_model, robot_parts

    from .design import design_trajectory, scene_toml
    from .excitation import bounds_of_parts

    parts = robot_parts(args.file)
    model = parts_model(parts).model
    d = design_trajectory(model, bounds_of_parts(parts, model.coordinate_names), seed=args.seed)
    Path(args.design).parent.mkdir(parents=True, exist_ok=True)
    Path(args.design).write_text(scene_toml(d, args.file, out=args.design))
    print(f"wrote {args.design}: condition number of the base regressor {d.condition:.4g} (first candidate "
          f"{d.start_condition:.4g}, {d.evaluations} evaluations); period {d.trajectory.period:g} s; peak |tau| "
          + ", ".join(f"{x:.3g}" for x in d.peak_effort))
    return 0


def identify_command(args) -> int:
    """Record, fit, write the report (and the corrected URDF); print the changes and the residuals."""
    if args.design:
        return design_command(args)
    if not args.against:
        print("urdf2links identify: --against OTHER is required (the description whose motion to fit)", file=sys.stderr)
        return 2
    seeds = tuple(range(args.seed, args.seed + args.runs))
    ident = identify(args.file, args.against, seeds=seeds, held_out_seed=args.seed + 100, t_end=args.t_end,
                     band=args.band, explicit_map=parse_map(args.map))
    changes = []
    if args.write_urdf:
        changes = write_urdf(ident, args.write_urdf)
    elif args.write_mjcf:
        changes = write_mjcf(ident, args.write_mjcf)
    out = Path(args.out) if args.out else DEFAULT_OUT / "identify" / Path(args.file).stem
    s = write_outputs(ident, out, changes)
    f = ident.fit
    print(f"identify {args.file} --against {args.against}: {s['samples']} samples ({s['samples_fitted']} fitted), "
          f"{s['rank']} base parameters of "
          f"{s['parameters_total']}, condition {s['condition']:.3g}")
    for i, nm in enumerate(ident.names):
        print(f"  {nm:<24} torque residual RMS {ident.residual_before[i]:.3e} -> {ident.residual_after[i]:.3e} N m "
              f"(held out {ident.heldout_before[i]:.3e} -> {ident.heldout_after[i]:.3e})")
    for v in ident.validation:
        print(f"  held-out run, {v.label} on {v.engine}: " + (f"max |q - q_OTHER| {np.max(v.error):.3e}"
                                                              if v.error is not None else v.note))
    written = args.write_urdf or args.write_mjcf
    if written:
        print(f"wrote {written}: {len(changes)} change(s)")
        for c in changes:
            print("  " + c.line())
        _, new_H = planned_changes(ident, urdf_values(ident.fit))
        bad = inconsistent_bodies(new_H)
        if bad:
            print(f"urdf2links identify: warning: {written}: the inertia of {', '.join(bad)} is not positive definite "
                  "(physically inconsistent: MuJoCo refuses the file); the fit kept the unidentifiable parameters at "
                  "the description's values without the consistency constraint", file=sys.stderr)
    else:
        flag = "--write-mjcf" if ident.pair.parts.format == "mjcf" else "--write-urdf"
        print(f"{int(f.changed.sum())} parameter(s) changed ({flag} OUT writes them)")
    print(f"report: {out / 'report.html'}")
    return 0

"""The work-precision studies of stiff scenes committed in reports/: one `urdf2links tradeoff` per entry
of :data:`STUDIES`, written where the report of that robot and scene lives (reports/<robot>/<scene>/).

A stiff scene joins the studies with one line in :data:`STUDIES`. Each study times both engines in one
process (its own interleaved rounds, compilation excluded: docs/accuracy.md); like every timed figure
here, regenerate them on an otherwise idle machine. Not a benchmark of reports/benchmarks/: its files
are the studies' own (tradeoff.json, tradeoff.md, work_precision.png, energy_drift.png). Usage::

    python benchmarks/stiff_studies.py                 # every study, full ladders (minutes each)
    python benchmarks/stiff_studies.py --only allegro_left --quick --out-root /tmp/studies
    python benchmarks/stiff_studies.py --list          # the equivalent urdf2links tradeoff commands
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

#: name -> (where the robot or scene is: "example-robot-data" or "shipped", its path there). A robot runs
#: in its default scene (`urdf2links tradeoff ROBOT.urdf`: gravity, fixed base, at rest, URDF damping, 1 s).
STUDIES = {
    "allegro_left": ("example-robot-data", "allegro_hand_description/urdf/allegro_left_hand.urdf"),
    "allegro_right": ("example-robot-data", "allegro_hand_description/urdf/allegro_right_hand.urdf"),
    "ur5_stiff_servo": ("shipped", "ur5_stiff_servo.toml"),
    "quad12_drop": ("shipped", "quad12_drop.toml"),      # ground contact (issue 37): stiff by nature
}


def source(where: str, rel: str) -> Path:
    from urdf2links.locations import example_robot_data_dir, shipped_robots_dir

    base = example_robot_data_dir() if where == "example-robot-data" else shipped_robots_dir()
    if base is None:
        raise SystemExit(f"stiff_studies: {where} is not installed (pip install example-robot-data)")
    return base / rel


def scene_of(path: Path):
    from urdf2links.scenes.default_scenes import default_scene
    from urdf2links.scenes.scene_read import load_scene

    return load_scene(path) if path.suffix == ".toml" else default_scene(path)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    p.add_argument("--only", help="comma-separated names of STUDIES (default: all)")
    p.add_argument("--quick", action="store_true", help="short ladders, one timing round (checks, not figures)")
    p.add_argument("--out-root", default=str(ROOT / "reports"), help="where reports/<robot>/<scene>/ go "
                   "(default: the checkout's reports/)")
    p.add_argument("--list", action="store_true", help="print the equivalent urdf2links tradeoff commands; run nothing")
    args = p.parse_args(argv)
    names = list(STUDIES) if not args.only else [x.strip() for x in args.only.split(",")]
    unknown = [x for x in names if x not in STUDIES]
    if unknown:
        raise SystemExit(f"--only: unknown {unknown}; choose from {', '.join(STUDIES)}")
    from urdf2links.compare.tradeoff.report import write_study
    from urdf2links.compare.tradeoff.study import run_study

    for name in names:
        path = source(*STUDIES[name])
        if args.list:
            print(f"urdf2links tradeoff {path}" + (" --quick" if args.quick else "")
                  + f" --out {args.out_root}/<robot>/<scene>")
            continue
        scene = scene_of(path)
        data = run_study(scene, quick=args.quick, log=lambda m, name=name: print(f"  {name}: {m}", file=sys.stderr))
        out = Path(args.out_root) / data["robot"] / data["scene"]
        cmd = f"urdf2links tradeoff {STUDIES[name][1]}" + (" --quick" if args.quick else "")
        paths = write_study(data, out, command=cmd)
        print(f"{name}: {data['crossover']['statement']}\n  wrote {paths['json']}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""The sweep of issue 33: every example-robot-data URDF against MuJoCo's import of itself with its root turned.

Each URDF is imported by MuJoCo (``save_mujoco_import``; balanced when MuJoCo refuses it as written) with its
top-level bodies turned by one rotation and moved (a mount), and compared (``compare_descriptions_of``, timed):
the comparison must list no sign flip (``joint_mapping.negated``), no ``axis`` and no ``origin`` that the
untouched import does not list, and one ``root_pose``. Writes ``reports/benchmarks/pairs_rotated_roots.md``.

    python benchmarks/pairs_rotated_roots.py
"""

from __future__ import annotations

import sys
import tempfile
import time
import warnings
from pathlib import Path

from urdf2links.compare.mujoco_side.mujoco_urdf import MujocoRefused
from urdf2links.compare.pairs.mujoco_import import save_mujoco_import
from urdf2links.compare.pairs.pair import compare_descriptions_of
from urdf2links.errors import DescriptionError
from urdf2links.locations import example_robot_data_dir

POSE = ((0.1, 0.2, 0.3), (0.3, 0.5, -0.2, 0.7))
OUT = Path(__file__).resolve().parents[1] / "reports" / "benchmarks" / "pairs_rotated_roots.md"


def one(path: Path, folder: Path) -> dict:
    rows = {}
    for label, pose in (("untouched", None), ("turned", POSE)):
        out = folder / f"{path.stem}_{label}.xml"
        try:
            try:
                save_mujoco_import(path, out, keep_geometry=False, root_pose=pose)
            except MujocoRefused:
                save_mujoco_import(path, out, keep_geometry=False, balance=True, root_pose=pose)
            t = time.perf_counter()
            c = compare_descriptions_of(path, out)
            rows[label] = (c, time.perf_counter() - t)
        except (MujocoRefused, DescriptionError, ValueError) as exc:
            return {"error": str(exc).splitlines()[0][:100]}
    (c0, _), (c1, secs) = rows["untouched"], rows["turned"]
    kinds = lambda c: sorted(d.label() for d in c.differences if d.kind in ("axis", "origin"))  # noqa: E731
    return {"joints": len(c1.mapping.matches), "negated": c1.mapping.to_json()["negated"],
            "new_axis_origin": sorted(set(kinds(c1)) - set(kinds(c0))),
            "root_pose": sum(d.kind == "root_pose" for d in c1.differences), "seconds": secs}


def main() -> int:
    root = example_robot_data_dir()
    files = sorted(root.rglob("*.urdf"))
    lines = ["# example-robot-data with the roots turned: no sign flips", "",
             f"MuJoCo's import of each URDF, its top-level bodies turned by quat {POSE[1]} and moved by {POSE[0]} "
             "(`python benchmarks/pairs_rotated_roots.py`).", "",
             "| robot | joints | negated | axis/origin not in the untouched import | root_pose | compare (s) |",
             "|---|---|---|---|---|---|"]
    bad = 0
    with tempfile.TemporaryDirectory() as tmp, warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for f in files:
            r = one(f, Path(tmp))
            rel = f.relative_to(root).as_posix()
            if "error" in r:
                lines.append(f"| {rel} | not compared: {r['error']} | | | | |")
            else:
                bad += bool(r["negated"] or r["new_axis_origin"])
                lines.append(f"| {rel} | {r['joints']} | {len(r['negated'])} | {len(r['new_axis_origin'])} | "
                             f"{r['root_pose']} | {r['seconds']:.2f} |")
            print(lines[-1], file=sys.stderr, flush=True)
    lines += ["", f"{bad} robot(s) with a sign flip or a new axis/origin difference."]
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text("\n".join(lines) + "\n")
    print(f"{OUT}: {bad} with flips")
    return 1 if bad else 0


if __name__ == "__main__":
    raise SystemExit(main())

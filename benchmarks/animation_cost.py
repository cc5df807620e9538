"""What the animation adds to a scene report: bytes and seconds. Usage:

    python benchmarks/animation_cost.py [--out reports/benchmarks/animation_cost.json] [--quick]

For every shipped scene (at the length ``urdf2links report`` runs it) and for the UR5, Panda, Talos
and G1 of example-robot-data (falling for 1 s; when the test extra is installed) one comparison
with MuJoCo is run; then the animation of the report's Motion section (30 frames per simulated
second, both engines, the difference panels) is built 3 times (median: "extra time"; the rest of
the page does not change, and measuring the whole report twice drowns the difference in the noise of
its plots) after a first build ("first": it also reads and decimates the robot's meshes and, for the
first robot with meshes, imports trimesh), and the report is written with and without it (bytes).
Writes JSON and a Markdown table next to it. ``--quick``: every run 0.5 s.
"""

from __future__ import annotations

import argparse
import base64
import json
import platform
import statistics
import tempfile
import time
import warnings
from pathlib import Path

from urdf2links.view.animation import read_animation_data
from urdf2links.compare.commands import report_t_end, shipped_scenes
from urdf2links.compare.reports.report import write_report
from urdf2links.compare.reports.motion import comparison_animation
from urdf2links.compare.agreement.trajectory import compare_scene
from urdf2links.locations import example_robot_data_dir
from urdf2links.scenes.scene import load_scene

REAL = {"ur5": "ur_description/urdf/ur5_robot.urdf", "panda": "panda_description/urdf/panda.urdf",
        "talos": "talos_data/robots/talos_reduced.urdf", "g1": "g1_description/urdf/g1_29dof_rev_1_0.urdf"}
BUDGET_MB, BUDGET_S = 5.0, 5.0


def cases(quick: bool, tmp: Path):
    for f in shipped_scenes():
        scene = load_scene(f)
        T = 0.5 if quick else report_t_end(scene, t_end=None, cap=5.0)[0]
        yield scene.name, f, T
    if example_robot_data_dir() is None:
        return
    for name, rel in REAL.items():
        toml = tmp / f"{name}_falling.toml"
        toml.write_text(f'[robot]\nexample_robot_data = "{rel}"\ninertia = "repair"\n[gravity]\nmagnitude = 9.81\n'
                        f'[run]\nt_end = 1.0\nrtol = 1e-10\nsamples = 101\n')
        yield f"{name} (example-robot-data)", toml, 0.5 if quick else 1.0


def measure(c, out: Path, repeats: int = 3) -> dict:
    """Seconds of the animation itself (it is all a report adds: the rest of the page is the same) and
    the bytes of the report with and without it."""
    t0 = time.perf_counter()
    comparison_animation(c)
    first = time.perf_counter() - t0
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        comparison_animation(c)
        times.append(time.perf_counter() - t0)
    with_, without = write_report(c, out / "with"), write_report(c, out / "without", animation_fps=0)
    size_with, size_without = with_["html"].stat().st_size, without["html"].stat().st_size
    return {"first_s": first, "extra_s": statistics.median(times), "report_mb": size_with / 1e6,
            "animation_mb": (size_with - size_without) / 1e6}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="reports/benchmarks/animation_cost.json")
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args(argv)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        for name, path, T in cases(args.quick, tmp):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                c = compare_scene(path, t_end=T, states=2, progress=False)
            row = {"case": name, "t_end": T, **measure(c, tmp / name)}
            data = read_animation_data((tmp / name / "with" / "report.html").read_text())
            row.update(frames=len(data["t"]), links=len(data["links"]),
                       mesh_triangles=sum(len(base64.b64decode(s["faces"])) // (6 if s["index"] == "u16" else 12)
                                          for s in data["shapes"] if s["kind"] == "mesh"))
            rows.append(row)
            print(f"{name:32s} t_end {T:4g} s  frames {row['frames']:4d}  report {row['report_mb']:.2f} MB "
                  f"(animation {row['animation_mb']:.2f} MB)  +{row['extra_s']:.2f} s (first {row['first_s']:.2f} s)")
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps({"machine": platform.platform(), "python": platform.python_version(),
                               "budget": {"report_mb": BUDGET_MB, "extra_s": BUDGET_S}, "rows": rows}, indent=2) + "\n")
    md = ["| case | t_end (s) | frames | links | mesh triangles | report (MB) | of which animation (MB) | "
          "extra time (s) | first build (s) |", "|---|---|---|---|---|---|---|---|---|"]
    md += [f"| {r['case']} | {r['t_end']:g} | {r['frames']} | {r['links']} | {r['mesh_triangles']} | "
           f"{r['report_mb']:.2f} | {r['animation_mb']:.2f} | {r['extra_s']:.2f} | {r['first_s']:.2f} |" for r in rows]
    out.with_suffix(".md").write_text("\n".join(md) + "\n")
    print(f"wrote {out} and {out.with_suffix('.md')}")


if __name__ == "__main__":
    main()

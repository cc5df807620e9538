"""What the animation adds to a scene report: bytes and seconds.

For every shipped scene, at the length ``urdf2links report`` runs it (its own ``t_end``: the report's
default ``--cap`` is 0, whole scenes), and for the UR5, Panda, Talos and G1 of example-robot-data
(falling for 1 s; when the test extra is installed): one comparison with MuJoCo (as ``report``
runs it: terms at 8 states, RK4 dt 1e-4 s), outside every timed region. Then, per case:

* ``first``: the first build of the animation of the report's Motion section (30 frames per
  simulated second, both engines, the difference panels); it also reads and decimates the robot's
  meshes (and, for the first robot with meshes, imports trimesh);
* ``extra``: the same build again, in ``--rounds`` interleaved rounds over all cases (the order
  reversed every other round), median (min-max): the time a report spends on its animation (the
  rest of the page does not change with it; timing two whole reports would drown it in the noise
  of their plots);
* bytes: the report written with and without the animation (``animation_fps=0``).

Budgets (docs/animation.md): a report at most 5 MB and 5 s of extra time. ``--quick`` runs every
case for 0.5 s (a check of the script, not the report's figures). Usage::

    python benchmarks/animation_cost.py [--rounds 5] [--quick] [--out reports/benchmarks/animation_cost.json]
    python benchmarks/animation_cost.py --render-only
"""

from __future__ import annotations

import base64
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

from benchmarking import REAL_ROBOTS, fmt_spread, markdown_table, rounds, run_benchmark, spread
from urdf2links.compare.agreement.trajectory import compare_scene
from urdf2links.compare.commands import REPORT_CAP_S, report_t_end, shipped_scenes
from urdf2links.compare.reports.motion import comparison_animation
from urdf2links.compare.reports.report import write_report
from urdf2links.locations import example_robot_data_dir
from urdf2links.scenes.scene_read import load_scene
from urdf2links.view.animation import DEFAULT_FPS, read_animation_data

BUDGET_MB, BUDGET_S = 5.0, 5.0
#: Terms at as many states as ``urdf2links report`` (its ``--states`` default).
REPORT_STATES = 8


def cases(quick: bool, tmp: Path):
    """(name, scene file, t_end, how t_end was chosen) of every case."""
    for f in shipped_scenes():
        scene = load_scene(f)
        T = 0.5 if quick else report_t_end(scene, t_end=None, cap=REPORT_CAP_S)[0]
        yield scene.name, f, T, "--quick" if quick else "as urdf2links report"
    if example_robot_data_dir() is None:
        return
    for name, rel in REAL_ROBOTS.items():
        toml = tmp / f"{name}_falling.toml"
        toml.write_text(f'[robot]\nexample_robot_data = "{rel}"\ninertia = "repair"\n[gravity]\nmagnitude = 9.81\n'
                        f'[run]\nt_end = 1.0\nrtol = 1e-10\nsamples = 101\n')
        yield f"{name} (example-robot-data)", toml, 0.5 if quick else 1.0, "--quick" if quick else "falling 1 s"


def _mesh_triangles(data) -> int:
    return sum(len(base64.b64decode(s["faces"])) // (6 if s["index"] == "u16" else 12)
               for s in data["shapes"] if s["kind"] == "mesh")


def measure(args, log) -> dict:
    rows, comparisons = [], {}
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        for name, path, T, why in cases(args.quick, tmp):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                c = compare_scene(path, t_end=T, states=REPORT_STATES, progress=False)
            t0 = time.perf_counter()
            comparison_animation(c)
            first = time.perf_counter() - t0
            out = tmp / name
            with_, without = write_report(c, out / "with"), write_report(c, out / "without", animation_fps=0)
            size_with, size_without = with_["html"].stat().st_size, without["html"].stat().st_size
            data = read_animation_data(with_["html"].read_text())
            rows.append({"case": name, "t_end": T, "t_end_from": why, "frames": len(data["t"]),
                         "links": len(data["links"]), "mesh_triangles": _mesh_triangles(data), "first_s": first,
                         "report_mb": size_with / 1e6, "animation_mb": (size_with - size_without) / 1e6})
            comparisons[name] = c
            log(f"{name:32s} t_end {T:4g} s  frames {rows[-1]['frames']:4d}  report {rows[-1]['report_mb']:.2f} MB "
                f"(animation {rows[-1]['animation_mb']:.2f} MB), first build {first:.2f} s")
    def build(c):
        return lambda: (comparison_animation(c), None)[1]      # the call's own duration counts

    times = rounds({name: build(c) for name, c in comparisons.items()}, args.rounds, log=log)
    for row in rows:
        row["extra_s"] = spread(times[row["case"]])
        row["within_budget"] = row["report_mb"] <= BUDGET_MB and row["extra_s"]["median"] <= BUDGET_S
    return {"rounds": args.rounds, "quick": args.quick, "fps": DEFAULT_FPS, "states": REPORT_STATES,
            "budget": {"report_mb": BUDGET_MB, "extra_s": BUDGET_S}, "rows": rows}


def render(data):
    from urdf2links.compare.figures import figure

    rows = data["rows"]
    head = ["case", "t_end (s)", "frames", "links", "mesh triangles", "report (MB)", "of which animation (MB)",
            "extra time (s)", "first build (s)", "within budget"]
    body = [[r["case"], f"{r['t_end']:g}", r["frames"], r["links"], r["mesh_triangles"], f"{r['report_mb']:.2f}",
             f"{r['animation_mb']:.2f}", fmt_spread(r["extra_s"], digits=2), f"{r['first_s']:.2f}",
             "yes" if r["within_budget"] else "**no**"] for r in rows]
    md = ("# What the animation adds to a report\n\n"
          + ("**--quick: every case 0.5 s, not the report's lengths.** " if data["quick"] else
             "Shipped scenes at the length `urdf2links report` runs them (whole scenes), the example-robot-data "
             "robots falling for 1 s. ")
          + f"The report's animation ({data['fps']:g} frames per simulated second, both engines, the difference "
          "panels): its bytes (the report written with and without it) and its build time, extra time: median "
          f"(min-max) over {data['rounds']} interleaved rounds; first build: the first, which also reads and "
          f"decimates the meshes. Budget: a report at most {data['budget']['report_mb']:g} MB and "
          f"{data['budget']['extra_s']:g} s of extra time.\n\n" + markdown_table(head, body))
    fig = figure(9.0, 3.6, dpi=100)
    ax, bx = fig.subplots(1, 2)
    y = np.arange(len(rows))
    ax.barh(y, [r["report_mb"] - r["animation_mb"] for r in rows], color="#bdbdbd", label="report without animation")
    ax.barh(y, [r["animation_mb"] for r in rows], left=[r["report_mb"] - r["animation_mb"] for r in rows],
            color="#2171b5", label="animation")
    ax.axvline(data["budget"]["report_mb"], color="C3", ls="--", lw=1, label="budget")
    ax.set_yticks(y, [r["case"] for r in rows], fontsize=7)
    ax.invert_yaxis()
    ax.set_xlabel("report size (MB)")
    ax.legend(fontsize=7)
    med = np.array([r["extra_s"]["median"] for r in rows])
    err = np.array([[r["extra_s"]["median"] - r["extra_s"]["min"], r["extra_s"]["max"] - r["extra_s"]["median"]]
                    for r in rows]).T
    bx.barh(y, med, xerr=err, color="#6baed6", capsize=2, label="extra time (median, min-max)")
    bx.plot([r["first_s"] for r in rows], y, "k|", ms=10, label="first build")
    bx.set_yticks(y, [])
    bx.invert_yaxis()
    bx.set_xlabel("seconds")
    bx.legend(fontsize=7)
    for a in (ax, bx):
        a.grid(axis="x", alpha=0.3)
    fig.suptitle("What the animation adds to a report", fontsize=10)
    return md, fig


def options(p):
    p.add_argument("--quick", action="store_true", help="every case 0.5 s (a check of the script)")


if __name__ == "__main__":
    run_benchmark("animation_cost", __doc__, measure, render, options=options, rounds_default=5)

"""Issue 43: every example-robot-data quadruped with ``--floating --ground`` in its default scene, and the MJCF
files with a floor (gymnasium's ant, dm_control's quadruped) in theirs, compared with MuJoCo: do they stand?

Per robot: the feet chosen, the base's height above the ground at the start and its lowest (both engines), its
largest tilt, the joints' largest excursion past their limits (negative: inside), the engines' agreement
(max |dq|), the deepest foot (the law's; against the smallest foot's radius), the verdict, MuJoCo's step and the wall times (compare_scene's whole call, the project's
integrator, MuJoCo's engine). Writes ``reports/benchmarks/standing_quadrupeds.md`` (docs/contact.md shows it).

    python benchmarks/standing_quadrupeds.py [--t-end 1.0]
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

from urdf2links.compare.agreement.trajectory import compare_scene
from urdf2links.locations import example_robot_data_dir
from urdf2links.scenes.default_scenes import default_scene
from urdf2links.scenes.stance import ground_for, stance_figures

OUT = Path(__file__).resolve().parents[1] / "reports" / "benchmarks" / "standing_quadrupeds.md"
QUADRUPEDS = {
    "go1": "go1_description/urdf/go1.urdf", "go2": "go2_description/urdf/go2.urdf",
    "solo12": "solo_description/robots/solo12.urdf", "anymal_b": "anymal_b_simple_description/robots/anymal.urdf",
    "anymal_c": "anymal_c_simple_description/urdf/anymal.urdf", "a1": "a1_description/urdf/a1.urdf",
    "hyq": "hyq_description/robots/hyq_no_sensors.urdf", "laikago": "laikago_description/urdf/laikago.urdf",
    "b1": "b1_description/urdf/b1.urdf", "quadruped": "quadruped_description/urdf/quadruped.urdf",
}


def _files() -> dict:
    import dm_control
    import gymnasium

    root = example_robot_data_dir()
    out = {k: (root / v, True) for k, v in QUADRUPEDS.items()}
    out["gymnasium ant.xml (floor)"] = (Path(gymnasium.__file__).parent / "envs/mujoco/assets/ant.xml", False)
    out["dm_control quadruped.xml (floor)"] = (Path(dm_control.__file__).parent / "suite/quadruped.xml", False)
    return out


def one(path: Path, urdf: bool, t_end: float) -> dict:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = default_scene(path, floating=urdf, t_end=t_end)
        model = scene.model()
    scene = ground_for(scene, model, ground=True)
    start = time.perf_counter()
    c = compare_scene(scene, model=model, states=1, progress=False)
    wall = time.perf_counter() - start
    s = c.summary()
    ground = float(scene.contacts[0].height)
    ours, theirs = (stance_figures(model, q, ground=ground) for q in (c.q_ours, c.q_mujoco))
    depth = float(max(c.info["contact_series"]["depth_ours"]))
    radius = min(sp.radius for sp in scene.contacts[0].spheres)
    return {"feet": ", ".join(sp.link for sp in scene.contacts[0].spheres), "start": ours.start_height,
            "min_ours": ours.min_height, "min_mujoco": theirs.min_height, "tilt": max(ours.max_tilt, theirs.max_tilt),
            "past": max(ours.max_past_limit, theirs.max_past_limit), "dq": s["trajectory"]["max_abs_error"],
            "depth": depth, "radius": radius, "verdict": s["verdict"]["text"], "dt": s["mujoco"]["timestep"], "wall": wall,
            "project": s["wall_time"]["project_s"], "mujoco": s["wall_time"]["mujoco_s"]}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--t-end", type=float, default=1.0)
    args = p.parse_args(argv)
    rows = []
    for name, (path, urdf) in _files().items():
        r = one(path, urdf, args.t_end)
        rows.append((name, r))
        print(f"{name}: {r}", file=sys.stderr, flush=True)
    lines = [f"# Standing on the ground: `--floating --ground` and a file's floor ({args.t_end:g} s, seed 0)", "",
             "`python benchmarks/standing_quadrupeds.py` (issue 43). Heights are the base's (root link origin) above "
             "the ground; \"past limit\" is the joints' largest excursion past a limit over both engines' runs "
             "(negative: inside by that much; the tests' margin is 0.1 rad); \"max |dq|\" the engines' agreement "
             "(the same contact law in both); wall: compare_scene's whole call (terms, both runs, MuJoCo's native "
             "contact), then the project's integrator and MuJoCo's engine. One run on a shared 2-core machine.", "",
             "| robot | feet | base at start (m) | lowest: urdf2links / MuJoCo (m) | max tilt (rad) | past limit (rad) "
             "| deepest foot (mm; / radius) | max \\|dq\\| | MuJoCo dt (s) | wall (s): compare / integrator / MuJoCo |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for name, r in rows:
        lines.append(f"| {name} | {r['feet']} | {r['start']:.3f} | {r['min_ours']:.3f} / {r['min_mujoco']:.3f} | "
                     f"{r['tilt']:.3f} | {r['past']:+.3f} | {1e3 * r['depth']:.1f}; {r['depth'] / r['radius']:.2f} | "
                     f"{r['dq']:.1e} | {r['dt']:g} | "
                     f"{r['wall']:.1f} / {r['project']:.2f} / {r['mujoco']:.2f} |")
    lines += ["", "Verdicts:", ""] + [f"- {name}: {r['verdict']}" for name, r in rows] + [""]
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text("\n".join(lines))
    print(f"wrote {OUT}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())

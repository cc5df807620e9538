"""Command line: ``urdf2links inspect FILE.urdf|FILE.xacro|FILE.xml|SCENE.toml``, ``urdf2links simulate
SCENE.toml|ROBOT.urdf``, ``urdf2links sweep SCENE.toml|ROBOT.urdf``, ``urdf2links compare
SCENE.toml|ROBOT.urdf``, ``urdf2links report [--corpus DIR ...]``, ``urdf2links tradeoff SCENE.toml`` and
``urdf2links check [PATH]`` (the MuJoCo comparison, the work-precision study and a repository's model regression
check, docs/ci.md: the handlers import the ``compare`` package,
and with it MuJoCo, only when they run). A robot file given to
``simulate`` or ``compare`` runs in its default scene (:func:`urdf2links.scenes.scene.default_scene`)."""

from __future__ import annotations

import argparse
import os
import sys
import warnings

from .errors import DescriptionError, DynamicsError, IntegrationError, SceneError
from .ranges import Q0_CHOICES

__all__ = ["main", "build_parser", "format_tree", "scene_from_args", "xacro_args_of", "write_scene_option"]

# numpy, numba and the stages are imported by the handlers that use them: `urdf2links --help` (and the
# parser) load only argparse and the base modules.
_LAZY = {"scene_from_args": "scenes.scene_toml", "xacro_args_of": "scenes.scene_toml",
         "write_scene_option": "scenes.scene_toml", "hold_of": "scenes.scene_toml", "load_options_of": "scenes.scene_toml"}


def __getattr__(name: str):
    """The scene helpers this module re-exports, imported at first use."""
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(f".{_LAZY[name]}", __package__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def format_tree(model) -> str:
    """The tree as a table: link, parent, the six parameters (coordinates marked ``[name]``),
    mass, COM, eigenvalues of H; then the audit findings and the importer's notes."""
    import numpy as np

    from .dynamics.transforms import PARAMETERS

    tree = model.tree
    rows = [("link", "parent", *PARAMETERS, "mass", "COM", "eig(H)")]
    for p, name in enumerate(tree.link_names):
        parent = tree.link_names[tree.parent[p]] if tree.parent[p] >= 0 else "{A}"
        cells = []
        for k in range(6):
            i = tree.coord[p, k]
            v = tree.params[p, k]
            if i >= 0:
                off = f"{v:+.4g}+" if v != 0 else ""
                cells.append(f"{off}[{tree.coordinate_names[i]}]")
            else:
                cells.append("0" if v == 0 else f"{v:.4g}")
        m = tree.H[p, 3, 3]
        com = "-" if m <= 0 else "(" + ", ".join(f"{c:.3g}" for c in tree.com[p]) + ")"
        eig = "massless" if not np.any(tree.H[p]) else ", ".join(f"{e:.3g}" for e in np.linalg.eigvalsh(tree.H[p]))
        rows.append((name, parent, *cells, f"{m:.4g}", com, eig))
    lines = _table(rows)
    out = [f"robot {model.name!r} from {model.source}: {tree.n_links} links, {model.n} coordinates", ""] + lines
    out += _joint_lines(model.info.get("joints", []))
    out += _constraint_lines(model.info)
    out += ["", f"inertia audit: {len(model.audit)} finding(s)"]
    out += [f"  - {r}" for r in model.audit]
    notes = model.info.get("notes", [])
    if notes:
        out += ["", "import notes:"] + [f"  - {n}" for n in notes]
    return "\n".join(out)


def _constraint_lines(info) -> list[str]:
    """An MJCF model's equalities and tendons (issue 36): read, and acting in scenes with ``[constraints]
    from_file = true`` (docs/constraints.md)."""
    from .parsers.mjcf_constraints import inspect_rows

    eq, td = inspect_rows(info)
    out = []
    if eq:
        out += ["", "equalities (read; constraints of scenes with [constraints] from_file = true, E68-E70):"] + _table(eq)
    if td:
        out += ["", "tendons (fixed ones act in scenes with [constraints] from_file = true, E76):"] + _table(td)
    return out


def _table(rows) -> list[str]:
    """Rows of cells as aligned text lines, a rule under the first (the header)."""
    widths = [max(len(r[c]) for r in rows) for c in range(len(rows[0]))]
    lines = ["  ".join(cell.ljust(w) for cell, w in zip(r, widths)).rstrip() for r in rows]
    lines.insert(1, "  ".join("-" * w for w in widths))
    return lines


def _num(v) -> str:
    return "-" if v is None else f"{v:.4g}"


def _mjcf_joint_lines(joints) -> list[str]:
    """An MJCF model's joints: type, coordinates, limits, armature (in A), damping, stiffness at springref."""
    rows = [("joint", "type", "coordinates", "lower", "upper", "armature", "damping", "stiffness", "springref",
             "frictionloss")]
    for j in joints:
        rows.append((j["name"], j["type"], ", ".join(j["coordinates"]), _num(j["lower"]), _num(j["upper"]),
                     _num(j["armature"]), _num(j["damping"]), _num(j["stiffness"]), _num(j["springref"]),
                     _num(j["friction"])))
    lines = _table(rows)
    return ["", "joints (MuJoCo's compiled values; qpos of hinges and slides is the coordinate; armature is part of A; "
            "damping, stiffness and gravcomp act in scenes that ask ([dampers], [springs], [gravcomp] from_file, as "
            "the default scene does); limits not enforced; friction not modelled):"] + lines


def _joint_lines(joints) -> list[str]:
    """The URDF joints with what ``<limit>`` and ``<dynamics>`` say (limits are not enforced; damping acts
    only in scenes with ``[dampers] from_urdf = true``; friction is not modelled); an MJCF model's
    joints with armature, damping and stiffness (:func:`_mjcf_joint_lines`)."""
    if joints and "armature" in joints[0]:
        return _mjcf_joint_lines(joints)
    moving = [j for j in joints if j["type"] != "fixed"]
    if not moving:
        return []
    rows = [("joint", "type", "coordinates", "lower", "upper", "effort", "velocity", "damping", "friction")]
    for j in moving:
        rows.append((j["name"], j["type"], ", ".join(j["coordinates"]) or "(coupled)", _num(j["lower"]),
                     _num(j["upper"]), _num(j["effort"]), _num(j["velocity"]), _num(j["damping"]),
                     _num(j["friction"])))
    lines = _table(rows)
    return ["", "joints (limits not enforced, noted when a run leaves them; damping acts in scenes with [dampers] "
            "from_urdf = true; friction not modelled):"] + lines


def _inspect(args) -> int:
    from .scenes.plan import compile_plan
    from .scenes.scene_toml import ground_of, hold_of, load_options_of, scene_or_robot, scene_with_plan

    if args.scene or str(args.file).endswith(".toml"):
        scene = scene_or_robot(args.file, q0=args.q0, seed=args.seed, t_end=args.t_end, load=load_options_of(args),
                               hold=hold_of(args))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            model = scene.model()
        scene = ground_of(args, scene, model)     # issues 37, 43: --ground, the file's floor
        print(scene_with_plan(scene, compile_plan(scene, model).describe()))     # a default scene: TOML that parses
        return 0
    from .parsers.robot_file import load_robot

    opts = load_options_of(args)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the findings are printed in the table below
        model = load_robot(args.file, **opts)
    print(format_tree(model))
    return 0


def _list(args) -> int:
    """``urdf2links list``: the shipped robots and scenes, one line each, runnable by name from anywhere."""
    from .locations import shipped, shipped_robots_dir

    items = shipped()
    width = max(len(s.name) for s in items)
    kind_width = max(len(s.kind) for s in items)
    print(f"shipped robots and scenes ({shipped_robots_dir()}); run them by name from any folder, e.g. "
          "`urdf2links simulate ship_crane`, `urdf2links inspect ur5_like`:")
    for s in items:
        print(f"  {s.name:{width}s}  {s.kind:{kind_width}s}  {s.summary}")
    return 0


def _simulate(args) -> int:
    from pathlib import Path

    from .integration.simulate import describe_stretches, simulate
    from .scenes.limits import LimitExcursion
    from .scenes.scene import robot_label
    from .scenes.scene_toml import scene_from_args, write_scene_option

    scene = scene_from_args(args)
    write_scene_option(args, scene)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore" if scene.path is None else "default")  # default scene: audit in inspect
        model = scene.model()
    traj = simulate(scene, model=model, t_end=args.t_end, method=args.method, rtol=args.rtol, dt=args.dt,
                    progress=False if args.quiet else None, max_wall=args.max_wall)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    stem = scene.name if scene.path is not None else f"{robot_label(scene, model)}_{scene.name}"  # default scene
    npz = traj.save_npz(out / f"{stem}.npz")
    csv_path = traj.save_csv(out / f"{stem}.csv")
    s = traj.stats
    print(f"{scene.name}: {model.name}, {model.n} coordinates, t = 0..{traj.t[-1]:g} s, {s['method']}"
          f" (rtol {s['rtol']:g}" + (f", dt {s['dt']:g}" if s["dt"] else "") + f"): {s['nsteps']} steps, "
          f"{s['nfev']} evaluations, {s['wall_time']:.3f} s wall")
    print(f"  terms: {', '.join(s['terms'])}; energy balance error {traj.energy_error:.2e} (relative)")
    if s["stretches"]:
        print(f"  methods: {s['methods_used']}")
        for line in describe_stretches(s["stretches"]):
            print(f"    {line}")
    for note in [*model.info.get("missing_files", ()), *s["spring_notes"]]:     # issue 42: a missing mesh named
        print(f"  note: {note}")
    for e in s["limit_excursions"]:
        print(f"  note: {LimitExcursion(**e).text()}")
    print(f"  wrote {npz} and {csv_path}")
    if args.plot:
        from .view.plots import plot_trajectory

        png = plot_trajectory(traj, out / f"{stem}.png")
        print(f"  plot {png}")
    if args.animate:
        from .view.animation import write_trajectory_page
        from .view.visuals import scene_shapes

        page = write_trajectory_page(out / f"{stem}.html", traj, model, fps=args.animation_fps or 30.0,
                                     base=scene.base_state if scene.base is not None else None,
                                     shapes=scene_shapes(scene, model))
        print(f"  animation {page} ({page.stat().st_size / 1e6:.1f} MB)")
    return 0


def _cache(args) -> int:
    from .numba_cache import cache_dir, cache_folders, clear_cache

    folder = cache_dir()
    if args.clear:
        gone = clear_cache(folder, which="all" if args.all else "stale")
        print(f"{folder}: removed {len(gone)} folder(s), {sum(f.size for f in gone) / 1e6:.1f} MB"
              + ("" if args.all else " (other installs' and removed installs'; --all removes this install's too)"))
    rows = cache_folders(folder)
    if not rows:
        print(f"{folder}: empty (nothing compiled yet; the first run compiles and fills it)")
        return 0
    words = {"current": "this install", "other": "another install", "gone": "sources removed (stale)",
             "unknown": "no origin recorded: an older version's, or being written (stale)"}
    print(f"{folder}: {len(rows)} folder(s), {sum(f.size for f in rows) / 1e6:.1f} MB")
    for f in rows:
        print(f"  {f.path.name:<32} {f.size / 1e6:7.1f} MB {f.files:5d} files  {words[f.status]}"
              + (f": {f.source}" if f.source is not None else ""))
    return 0


def _compare(args) -> int:
    from .compare.commands import compare_command

    return compare_command(args)


def _report(args) -> int:
    from .compare.commands import report_command

    return report_command(args)


def _check(args) -> int:
    from .compare.check.command import check_command

    return check_command(args)


def _sweep(args) -> int:
    """``urdf2links sweep``: seeded initial states around the scene's, integrated by the compiled batch
    loop here or split across a Dask cluster (``--scheduler``); an .npz of the trajectories."""
    from pathlib import Path

    import numpy as np

    from .integration.batch import simulate_batch, sweep_states
    from .scenes.scene import robot_label
    from .scenes.scene_toml import scene_from_args, write_scene_option

    scene = scene_from_args(args)
    write_scene_option(args, scene)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore" if scene.path is None else "default")
        model = scene.model()
    try:
        q0, qd0 = sweep_states(scene, model, args.count, seed=args.seed, spread=args.spread)
    except ValueError as exc:
        raise SceneError(f"urdf2links sweep: {exc}") from None
    client = None
    if args.scheduler:
        from .integration.distributed import connect

        try:
            client = connect(args.scheduler)
        except (ImportError, OSError) as exc:
            print(f"urdf2links sweep: error: {exc}", file=sys.stderr)
            return 2
    try:
        res = simulate_batch(scene, q0, qd0, t_end=args.t_end, samples=args.samples, method=args.method,
                             rtol=args.rtol, model=model, client=client, chunks=args.chunks)
    finally:
        if client is not None:
            client.close()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    stem = scene.name if scene.path is not None else f"{robot_label(scene, model)}_{scene.name}"
    npz = out / f"{stem}_sweep.npz"
    np.savez_compressed(npz, t=res.t, q=res.q, qd=res.qd, work=res.work, nfev=res.nfev, status=res.status, q0=q0,
                        qd0=qd0, coordinate_names=np.array(res.coordinate_names))
    where = f"on {len(res.chunks)} chunks at {args.scheduler}" if client is not None else "on this machine"
    for note in res.notes:
        print(f"note: {note}")
    print(f"{scene.name}: {model.name}, {args.count} initial states (seed {args.seed}, spread {args.spread:g}), "
          f"t = 0..{res.t[-1]:g} s, {res.method}, {where}: {int(np.sum(res.status == 1))} reached the end, "
          f"{res.wall_time:.2f} s wall, {int(res.nfev.sum())} evaluations")
    spread = res.q[:, -1, :].std(axis=0) if len(res.q) > 1 else np.zeros(model.n)
    print(f"  final spread of q (std over the sweep): largest {float(spread.max(initial=0.0)):.3g} "
          f"({model.coordinate_names[int(np.argmax(spread))] if model.n else '-'})")
    print(f"  wrote {npz}")
    return 0 if np.all(res.status == 1) else 1


def _tradeoff(args) -> int:
    from .compare.commands import tradeoff_command

    return tradeoff_command(args)


def _add_mujoco_options(p) -> None:
    p.add_argument("--mujoco-integrator", default="RK4", choices=("RK4", "Euler", "implicit", "implicitfast"),
                   help="MuJoCo's integrator (default RK4)")
    p.add_argument("--mujoco-dt", type=float, default=1e-4, help="MuJoCo's timestep in s (default 1e-4)")
    p.add_argument("--t-end", type=float, help="run length in s (default: the scene's [run] t_end)")
    p.add_argument("--states", type=int, default=8, help="seeded random states for the terms (default 8)")
    p.add_argument("--factor", type=float, help="allowed growth of an error over its baseline (default: the "
                   "baselines file's factor, 10)")
    p.add_argument("--quiet", action="store_true", help="no progress on stderr")
    _add_animation_option(p)
    _add_max_wall(p)


def _max_wall(text: str) -> float:
    """``--max-wall SECONDS``: a positive number of seconds."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"--max-wall {text!r}: not a number of seconds") from None
    if not (value > 0 and value < float("inf")):
        raise argparse.ArgumentTypeError(f"--max-wall {text!r}: must be a finite number of seconds > 0")
    return value


def _add_max_wall(p) -> None:
    p.add_argument("--max-wall", type=_max_wall, metavar="SECONDS", help="wall-clock budget of the project's "
                   "integration (per scene): past it the run ends with an IntegrationError (exit 2) instead of "
                   "running on (default: none; step-size underflow and 1e7 steps end a run anyway)")


def _add_animation_option(p) -> None:
    p.add_argument("--animation-fps", type=float, default=30.0, metavar="FPS",
                   help="frames per second of simulated time in the report's animation (default 30; 0: no animation)")


def _add_load_options(p) -> None:
    """How the robot is loaded: the same options on every command that loads one. For a scene file they
    replace its ``[robot]`` options (the scene's notes say so)."""
    from .ranges import INERTIA_POLICIES, MIMIC_POLICIES

    g = p.add_argument_group("loading the robot (for a scene file: replaces its [robot] options, noted)")
    g.add_argument("--floating-base", "--floating", dest="floating", action="store_true",
                   help="six coordinates for the root link (default: fixed base; robot files only)")
    g.add_argument("--inertia", choices=INERTIA_POLICIES, help="audit (default: inconsistent inertias noted), strict "
                   "(refused), repair (replaced by the nearest consistent one or one from the geometry, noted)")
    g.add_argument("--mimic", choices=MIMIC_POLICIES, help="mimic joints as independent coordinates (default) or "
                   "coupled to their leader")
    g.add_argument("--strict", action="store_true", help="refuse what the default reading tolerates like urdfdom")
    g.add_argument("--package-dir", action="append", default=[], metavar="DIR",
                   help="folder searched for package:// meshes and $(find pkg) (repeat for more)")
    g.add_argument("--xacro-arg", action="append", default=[], metavar="NAME:=VALUE",
                   help="argument of a .xacro robot (repeat for more)")


def _add_default_scene_options(p, *, seed: bool = True, write_scene: bool = True) -> None:
    """Options of a robot file run in its default scene."""
    g = p.add_argument_group("a robot file's default scene")
    g.add_argument("--q0", choices=Q0_CHOICES, default="excite", help="initial state: excite (default: q0 and q' "
                   "random, every coordinate moving a good part of its range in the run, a floating base with a "
                   "random twist), random (q0 random within the joint limits, at rest), rest (q = 0 at rest; zero "
                   "is its old name)")
    if seed:
        g.add_argument("--seed", type=int, default=0, help="seed of --q0 excite and random (default 0)")
    g.add_argument("--hold", action="store_true", help="hold the robot at q0: a position servo on every coordinate, "
                   "critically damped at --hold-bandwidth, gains from the mass matrix at q0 (both engines)")
    g.add_argument("--hold-bandwidth", type=float, metavar="HZ", help="the servos' bandwidth with --hold (default 2 Hz)")
    g.add_argument("--ground", action="store_true", help="a floating robot standing on the ground (docs/contact.md)")
    g.add_argument("--no-floor", action="store_true", help="drop an MJCF file's own floor (kept by default)")
    if write_scene:
        g.add_argument("--write-scene", metavar="FILE.toml", help="also write the default scene to FILE.toml, to "
                       "edit and run by name")


_INPUT = ("a scene .toml, a robot (.urdf, .xacro), or the name of a shipped one from any folder (`urdf2links "
          "list`)")


def _list_parser(sub) -> None:
    p = sub.add_parser("list", help="the shipped robots and scenes, one line each (run them by name)")
    p.set_defaults(func=_list)


def _inspect_parser(sub) -> None:
    """The ``inspect`` command's options."""
    p = sub.add_parser("inspect", help="print a robot's tree of links, joints, inertia audit and import notes (or a "
                                       "scene's plan)")
    p.add_argument("file", help=_INPUT + "; a scene prints its plan")
    p.add_argument("--scene", action="store_true", help="print the robot's default scene (TOML) and its plan")
    p.add_argument("--t-end", type=float, help="default scene's run length in s (default 1)")
    _add_load_options(p)
    _add_default_scene_options(p, write_scene=False)
    p.set_defaults(func=_inspect)


def _simulate_parser(sub) -> None:
    """The ``simulate`` command's options."""
    p = sub.add_parser("simulate", help="simulate a scene (TOML), or a robot in its default scene, and save the "
                                        "trajectory")
    p.add_argument("scene", help=_INPUT + "; a robot runs in its default scene: gravity, fixed base, at rest, URDF "
                                          "damping, 1 s")
    _add_load_options(p)
    _add_default_scene_options(p)
    p.add_argument("--t-end", type=float, help="override [run] t_end (s)")
    p.add_argument("--method", help="auto (the default: DOP853, Radau5 while stiff), RK45, DOP853, Radau5, Radau, "
                                    "BDF, LSODA, RK4 or midpoint")
    p.add_argument("--rtol", type=float)
    p.add_argument("--dt", type=float, help="step for RK4 and midpoint (s)")
    p.add_argument("--out", default="out", help="folder for .npz, .csv and .png (default: out)")
    p.add_argument("--plot", action="store_true", help="also plot coordinates and energy against time (PNG)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument("--animate", action="store_true", help="also write <out>/<scene>.html: the robot moving, with "
                   "play/pause and a time slider (self-contained, works offline)")
    _add_animation_option(p)
    _add_max_wall(p)
    p.set_defaults(func=_simulate)


def _compare_parser(sub) -> None:
    """The ``compare`` command's options."""
    p = sub.add_parser("compare", help="run a scene with urdf2links and MuJoCo and write the comparison report",
                       description="Run a scene with urdf2links and with MuJoCo (route 1: the project's tree as MJCF, "
                                   "base motion prescribed) from the same initial state; compare the terms at identical "
                                   "states (routes 1 and 2), the trajectories, the energies and the wall times; write "
                                   "report.html, summary.json and summary.md.")
    p.add_argument("scene", help=_INPUT + "; a robot runs in its default scene")
    _add_load_options(p)
    _add_default_scene_options(p, seed=False)
    _add_mujoco_options(p)
    p.add_argument("--method", help="the project's integrator (default: the scene's)")
    p.add_argument("--rtol", type=float, help="the project's rtol (default: the scene's)")
    p.add_argument("--seed", type=int, default=0, help="seed of the terms' random states and of --q0 random "
                   "(default 0)")
    p.add_argument("--out", help="folder of the report (default out/reports/<robot>/<scene>/)")
    p.add_argument("--json", help="also write the summary JSON to this file")
    p.add_argument("--check", metavar="BASELINE.json", help="exit 1, naming the figure, when a discrepancy grew "
                   "past its baseline (wall times are not checked)")
    p.add_argument("--against", metavar="ROBOT.xml", help="a second description of the same robot (MJCF, URDF or "
                   "xacro): both compared part by part and in motion, first in the report (docs/pairs.md)")
    p.add_argument("--map", action="append", default=[], metavar="URDF_JOINT=MJCF_JOINT",
                   help="with --against: a joint of the first file and its name in the second (repeat for more)")
    p.set_defaults(func=_compare)


def _report_parser(sub) -> None:
    """The ``report`` command's options."""
    p = sub.add_parser("report", help="compare every shipped scene (or every robot of a corpus) with MuJoCo; "
                                      "reports and an index page",
                       description="Run `compare` on every shipped scene (robots/*.toml, or the scenes given) and "
                                   "write reports/<robot>/<scene>/ and reports/index.html. With --corpus: every robot "
                                   "file found there in its default scene (gravity, fixed base, every coordinate moving "
                                   "from a seeded random q0 and qd0, 0.5 s), in parallel processes (--jobs) or on a Dask cluster (--scheduler); writes "
                                   "index.html, corpus.json, corpus.md and a page per robot into reports/corpus/. "
                                   "Progress on stderr.")
    p.add_argument("scenes", nargs="*", help="scene files or names of shipped scenes (default: every shipped scene; "
                   "in a urdf2links checkout, its robots/*.toml)")
    p.add_argument("--out", help="folder of the reports and index.html (default out/reports; with --corpus "
                   "out/reports/corpus); --out reports regenerates a checkout's committed reports")
    p.add_argument("--corpus", nargs="+", metavar="DIR|FILE|GLOB", help="every .urdf and .xacro under these folders "
                   "(and these files, and the files these patterns match): one row each, its default scene run for 0.5 s "
                   "(--t-end); 'example-robot-data': the installed example-robot-data robots")
    p.add_argument("--pairs", metavar="PAIRS.toml", help="pairs of descriptions of one robot (a URDF and its MJCF, "
                   "...), compared part by part and in motion: a page per pair and an index in out/reports/pairs/; "
                   "exit 1 when a pair differs past the tolerances the file gives (schema: docs/pairs.md)")
    p.add_argument("--jobs", type=int, help="--corpus: run the robots in N processes on this machine (default: "
                   "every core; 1: one after the other here)")
    p.add_argument("--scheduler", metavar="ADDRESS", help="--corpus: run the robots on the Dask cluster whose "
                   "scheduler is at ADDRESS (tcp://host:8786; `dask scheduler` prints it); needs "
                   "pip install 'urdf2links[distributed]'")
    p.add_argument("--seed", type=int, default=0, help="--corpus: seed of each robot's random q0 and qd0 and of the "
                   "terms' states (default 0)")
    _add_load_options(p)
    p.add_argument("--no-thumbnails", action="store_true", help="--corpus: no picture of each robot in the index "
                   "(saves the few seconds a robot its meshes take)")
    _add_mujoco_options(p)
    p.add_argument("--cap", type=float, default=0.0, help="cap (s) on t_end of scenes with time-dependent inputs "
                   "(moving base, torques, loads); 0: none (default)")
    p.add_argument("--check", metavar="BASELINE.json", help="baselines to check every scene against (default "
                   "<out>/baselines.json when it exists); exit 1 on a failure")
    p.add_argument("--write-baselines", nargs="?", const=True, metavar="FILE",
                   help="accept this run's figures: add them to <out>/baselines.json (or FILE), replacing a run of "
                        "the same t_end and MuJoCo setting")
    p.set_defaults(func=_report)


def _sweep_parser(sub) -> None:
    """The ``sweep`` command's options."""
    p = sub.add_parser("sweep", help="integrate many initial states of a scene at once (compiled, in parallel; on a "
                                     "Dask cluster with --scheduler)",
                       description="Draw COUNT initial states around a scene's (each coordinate of q0 moved by a seeded "
                                   "uniform draw in [-spread, spread]), integrate them with the compiled batch loop "
                                   "(DOP853 or RK45, one trajectory per thread), on this machine or split across the "
                                   "workers of a Dask cluster (same results), and save them as an .npz.")
    p.add_argument("scene", help=_INPUT + "; a robot runs in its default scene")
    _add_load_options(p)
    _add_default_scene_options(p, seed=False)
    p.add_argument("--count", type=int, default=100, help="number of initial states (default 100)")
    p.add_argument("--seed", type=int, default=0, help="seed of the states' draw (and of --q0 random; default 0)")
    p.add_argument("--spread", type=float, default=0.1, help="half-width of the uniform draw around q0, rad or m "
                   "(default 0.1)")
    p.add_argument("--t-end", type=float, help="override [run] t_end (s)")
    p.add_argument("--samples", type=int, help="sample times on [0, t_end] (default: the scene's)")
    p.add_argument("--method", choices=("DOP853", "RK45"), help="default DOP853 (or the scene's, if one of these)")
    p.add_argument("--rtol", type=float)
    p.add_argument("--scheduler", metavar="ADDRESS", help="split the states across the Dask cluster whose scheduler "
                   "is at ADDRESS (pip install 'urdf2links[distributed]')")
    p.add_argument("--chunks", type=int, help="with --scheduler: number of chunks (default: one per worker)")
    p.add_argument("--out", default="out", help="folder of the .npz (default: out)")
    p.set_defaults(func=_sweep)


def _tradeoff_parser(sub) -> None:
    """The ``tradeoff`` command's options."""
    p = sub.add_parser("tradeoff", help="work-precision study of a scene: error against wall time, both engines",
                       description="Run a scene with every method of urdf2links over a ladder of tolerances or steps "
                                   "and with MuJoCo's Euler, implicitfast and RK4 over a ladder of timesteps, against a "
                                   "reference (DOP853 rtol 1e-13, checked by a second method); errors, energy drift, "
                                   "median wall time of interleaved rounds, evaluations; the crossover. Writes "
                                   "tradeoff.json, tradeoff.md, work_precision.png, energy_drift.png (and the section "
                                   "of report.html when the folder has one). Progress on stderr.")
    p.add_argument("scene", help=_INPUT + "; a robot runs in its default scene")
    _add_load_options(p)
    _add_default_scene_options(p, write_scene=False)
    p.add_argument("--t-end", type=float, help="run length in s (default: the scene's, at most 2 s)")
    p.add_argument("--out", help="output folder (default out/reports/<robot>/<scene>/)")
    p.add_argument("--quick", action="store_true", help="short ladders, one timing round, DOP853 rtol 1e-12 as the "
                   "reference's check (instead of Radau rtol 1e-13)")
    p.add_argument("--repeats", type=int, help="timing rounds, median kept (default 3; --quick 1)")
    p.add_argument("--budget", type=float, help="skip a run predicted to take longer than this many seconds "
                   "(default 30; --quick 5)")
    p.add_argument("--methods", help="comma-separated project methods (default all: RK45,DOP853,Radau,BDF,LSODA,RK4,"
                   "midpoint)")
    p.add_argument("--mujoco-integrators", help="comma-separated MuJoCo integrators (default Euler,implicitfast,RK4)")
    p.add_argument("--quiet", action="store_true", help="no progress on stderr")
    p.set_defaults(func=_tradeoff)


def _check_parser(sub) -> None:
    """The ``check`` command's options."""
    p = sub.add_parser("check", help="check a repository's robots, pairs and scenes (urdf2links.toml or "
                                     "[tool.urdf2links]) for CI: exit 0, 1 when a check falls short, 2 when unusable",
                       description="Read the configuration ([tool.urdf2links] of pyproject.toml, or urdf2links.toml, "
                                   "in PATH or above): load every robot (a load error, an inertia finding not allowed "
                                   "or a change since its accepted fingerprint fails), compare every pair part by part "
                                   "(a difference not accepted by name fails), run every scene against its baselines. "
                                   "Exit 0 when all hold, 1 when a check falls short, 2 when the configuration or a "
                                   "file cannot be used (docs/ci.md).")
    p.add_argument("path", nargs="?", default=".", help="the repository's folder, or its configuration file "
                   "(default: here)")
    p.add_argument("--junit", metavar="FILE", help="also write JUnit XML: one test case per robot, pair and scene")
    p.add_argument("--markdown", metavar="FILE", help="also write a Markdown summary, largest problems first (a pull "
                   "request comment, $GITHUB_STEP_SUMMARY)")
    p.add_argument("--changed-since", metavar="GIT_REF", help="check only what depends on files changed since this "
                   "commit (the robot files, their meshes and xacro includes, scene files)")
    p.add_argument("--jobs", type=int, help="run the checks in N processes (default 1: here)")
    p.add_argument("--write-baselines", action="store_true", help="accept this run (scene figures, fingerprints)")
    p.add_argument("--init", action="store_true", help="write urdf2links.toml for PATH: every robot found, pairs "
                   "guessed by robot name, the current state accepted (differences by name, baselines written)")
    p.add_argument("--write-workflow", nargs="?", const=True, metavar="FILE", help="write the CI workflow (docs/ci.md) "
                   "to .github/workflows/urdf2links-check.yml (or FILE)")
    p.add_argument("--from", dest="source", metavar="GIT_URL@COMMIT|PATH", help="where the workflow installs urdf2links")
    p.add_argument("--quiet", action="store_true", help="no line per check while it runs")
    p.set_defaults(func=_check)


def _cache_parser(sub) -> None:
    p = sub.add_parser("cache", help="list (default) or clear numba's cache of compiled code (the first run of a "
                       "command compiles; the next ones load it)")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--list", action="store_true", help="the cache's folders: size, and the install each serves (default)")
    g.add_argument("--clear", action="store_true", help="remove the folders of other and removed installs")
    p.add_argument("--all", action="store_true", help="with --clear: this install's too (the next run compiles again)")
    p.set_defaults(func=_cache)


def build_parser() -> argparse.ArgumentParser:
    """The ``urdf2links`` command line: one sub-command per handler above."""
    parser = argparse.ArgumentParser(prog="urdf2links", description="URDF robots as trees of links of the trace "
                                     "method, simulated, and compared with MuJoCo.")
    sub = parser.add_subparsers(dest="command", required=True)
    for add in (_list_parser, _inspect_parser, _simulate_parser, _compare_parser, _report_parser, _sweep_parser,
                _tradeoff_parser, _check_parser, _cache_parser):
        add(sub)
    return parser


def _resolve_inputs(args) -> None:
    """The command's file arguments as paths: a file as given, or a shipped robot or scene by name
    (:func:`urdf2links.locations.find_input`; a stand-in is said on stderr)."""
    from .locations import find_input

    for attr in ("file", "scene", "against"):
        if isinstance(getattr(args, attr, None), str):
            path, note = find_input(getattr(args, attr))
            setattr(args, attr, str(path))
            if note:
                print(f"urdf2links {args.command}: {note}", file=sys.stderr)
    if getattr(args, "scenes", None):
        paths = []
        for a in args.scenes:
            path, note = find_input(a, kinds=("scene",))
            paths.append(str(path))
            if note:
                print(f"urdf2links {args.command}: {note}", file=sys.stderr)
        args.scenes = paths


#: Errors whose message is the whole story (a bad file, value or run): printed as they are.
_USER_ERRORS = (DescriptionError, SceneError, DynamicsError, IntegrationError, ValueError, OSError)


def main(argv=None) -> int:
    """Run a command; every error ends in one message on stderr and exit status 2, never a traceback
    (``URDF2LINKS_DEBUG=1`` shows the traceback of an internal error)."""
    args = build_parser().parse_args(argv)
    from . import compilation

    compilation.show_progress(not getattr(args, "quiet", False))
    try:
        _resolve_inputs(args)
        return args.func(args)
    except KeyboardInterrupt:
        print(f"urdf2links {args.command}: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:          # the reader of stdout left (`| head`): stop quietly
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 1
    except _USER_ERRORS as err:
        print(f"urdf2links {args.command}: error: {err}", file=sys.stderr)
        return 2
    except Exception as err:  # noqa: BLE001 -- never a traceback: say what, and how to see more
        if os.environ.get("URDF2LINKS_DEBUG"):
            raise
        print(f"urdf2links {args.command}: error: {type(err).__name__}: {err} (an internal error of urdf2links: "
              "please report it; URDF2LINKS_DEBUG=1 shows the traceback)", file=sys.stderr)
        return 2
    finally:
        compilation.show_progress(False)
        _say_compilation()


def _say_compilation() -> None:
    """The command's one line about numba's compilation, when it compiled anything (stderr)."""
    from . import compilation
    from .numba_cache import cache_dir
    line = compilation.summary(cache_dir())      # None when nothing compiled, here or in a worker process
    if line:
        print(line, file=sys.stderr)


if __name__ == "__main__":
    sys.exit(main())

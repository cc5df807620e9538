"""``urdf2links compare``, ``report``, ``tradeoff`` and ``check``: the commands that run MuJoCo beside the project.

Their options are declared here; their handlers live in ``urdf2links.compare`` (:mod:`urdf2links.compare.commands`,
:mod:`urdf2links.compare.check.command`) and are imported only when one of them runs, so that the parser (and
``urdf2links --help``) never imports MuJoCo.
"""

from __future__ import annotations

from .options import add_load_options, add_mujoco_options, add_open_loops, add_scene_input

__all__ = ["add_compare", "run_compare", "add_report", "run_report", "add_tradeoff", "run_tradeoff", "add_check",
           "run_check"]


def add_compare(p) -> None:
    """The ``compare`` command's options."""
    add_scene_input(p, seed=False)
    add_mujoco_options(p)
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


def run_compare(args) -> int:
    from ..compare.commands import compare_command

    return compare_command(args)


def add_report(p) -> None:
    """The ``report`` command's options."""
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
    add_load_options(p)
    add_open_loops(p)
    p.add_argument("--no-thumbnails", action="store_true", help="--corpus: no picture of each robot in the index "
                   "(saves the few seconds a robot its meshes take)")
    add_mujoco_options(p)
    p.add_argument("--cap", type=float, default=0.0, help="cap (s) on t_end of scenes with time-dependent inputs "
                   "(moving base, torques, loads); 0: none (default)")
    p.add_argument("--check", metavar="BASELINE.json", help="baselines to check every scene against (default "
                   "<out>/baselines.json when it exists); exit 1 on a failure")
    p.add_argument("--write-baselines", nargs="?", const=True, metavar="FILE",
                   help="accept this run's figures: add them to <out>/baselines.json (or FILE), replacing a run of "
                        "the same t_end and MuJoCo setting")


def run_report(args) -> int:
    from ..compare.commands import report_command

    return report_command(args)


def add_tradeoff(p) -> None:
    """The ``tradeoff`` command's options."""
    add_scene_input(p, write_scene=False)
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


def run_tradeoff(args) -> int:
    from ..compare.commands import tradeoff_command

    return tradeoff_command(args)


def add_check(p) -> None:
    """The ``check`` command's options."""
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
    add_open_loops(p)


def run_check(args) -> int:
    from ..compare.check.command import check_command

    return check_command(args)

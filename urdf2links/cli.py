"""Command line: ``urdf2links inspect FILE.urdf|FILE.xacro|FILE.xml|SCENE.toml``, ``urdf2links simulate
SCENE.toml|ROBOT.urdf``, ``urdf2links sweep SCENE.toml|ROBOT.urdf``, ``urdf2links compare
SCENE.toml|ROBOT.urdf``, ``urdf2links report [--corpus DIR ...]``, ``urdf2links tradeoff SCENE.toml`` and
``urdf2links check [PATH]`` (the MuJoCo comparison, the work-precision study and a repository's model regression
check, docs/ci.md: the handlers import the ``compare`` package,
and with it MuJoCo, only when they run). A robot file given to
``simulate`` or ``compare`` runs in its default scene (:func:`urdf2links.scenes.default_scenes.default_scene`).

The sub-commands are a table, :data:`COMMANDS` (as pip's ``commands/__init__.py``): each names the function that
declares its options and the handler that runs it, in the modules of :mod:`urdf2links.commands`; their shared
options are written once in :mod:`urdf2links.commands.options`."""

from __future__ import annotations

import argparse
import os
import sys
from typing import Callable, NamedTuple

from .commands import comparisons, identify, inspect, run
from .errors import DescriptionError, DynamicsError, IntegrationError, SceneError

__all__ = ["main", "build_parser", "format_tree", "scene_from_args", "xacro_args_of", "write_scene_option",
           "COMMANDS", "Command"]

# numpy, numba and the stages are imported by the handlers that use them: `urdf2links --help` (and the
# parser) load only argparse and the base modules.
_LAZY = {"scene_from_args": "scenes.scene_toml", "xacro_args_of": "scenes.scene_toml",
         "write_scene_option": "scenes.scene_toml", "hold_of": "scenes.scene_toml", "load_options_of": "scenes.scene_toml",
         "format_tree": "commands.inspect"}


def __getattr__(name: str):
    """The scene helpers (and ``inspect``'s table of a tree) this module re-exports, imported at first use."""
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(f".{_LAZY[name]}", __package__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


class Command(NamedTuple):
    """A sub-command: ``add_arguments(parser)`` declares its options (None: it has none), ``run(args)`` runs it and
    returns the exit status; ``help`` is its line in ``urdf2links --help``, ``description`` the paragraph atop
    ``urdf2links NAME --help`` (None: none)."""

    add_arguments: Callable | None
    run: Callable
    help: str
    description: str | None = None


#: The sub-commands, in the order of ``urdf2links --help``: name -> :class:`Command`.
COMMANDS: dict[str, Command] = {
    "list": Command(
        None, inspect.run_list,
        help="the shipped robots and scenes, one line each (run them by name)"),
    "inspect": Command(
        inspect.add_inspect, inspect.run_inspect,
        help="print a robot's tree of links, joints, inertia audit and import notes (or a scene's plan)"),
    "simulate": Command(
        run.add_simulate, run.run_simulate,
        help="simulate a scene (TOML), or a robot in its default scene, and save the trajectory"),
    "compare": Command(
        comparisons.add_compare, comparisons.run_compare,
        help="run a scene with urdf2links and MuJoCo and write the comparison report",
        description="Run a scene with urdf2links and with MuJoCo (route 1: the project's tree as MJCF, base motion "
                    "prescribed) from the same initial state; compare the terms at identical states (routes 1 and "
                    "2), the trajectories, the energies and the wall times; write report.html, summary.json and "
                    "summary.md."),
    "report": Command(
        comparisons.add_report, comparisons.run_report,
        help="compare every shipped scene (or every robot of a corpus) with MuJoCo; reports and an index page",
        description="Run `compare` on every shipped scene (robots/*.toml, or the scenes given) and write "
                    "reports/<robot>/<scene>/ and reports/index.html. With --corpus: every robot file found there "
                    "in its default scene (gravity, fixed base, every coordinate moving from a seeded random q0 and "
                    "qd0, 0.5 s), in parallel processes (--jobs) or on a Dask cluster (--scheduler); writes "
                    "index.html, corpus.json, corpus.md and a page per robot into reports/corpus/. Progress on "
                    "stderr."),
    "sweep": Command(
        run.add_sweep, run.run_sweep,
        help="integrate many initial states of a scene at once (compiled, in parallel; on a Dask cluster with "
             "--scheduler)",
        description="Draw COUNT initial states around a scene's (each coordinate of q0 moved by a seeded uniform "
                    "draw in [-spread, spread]), integrate them with the compiled batch loop (DOP853 or RK45, one "
                    "trajectory per thread), on this machine or split across the workers of a Dask cluster (same "
                    "results), and save them as an .npz."),
    "tradeoff": Command(
        comparisons.add_tradeoff, comparisons.run_tradeoff,
        help="work-precision study of a scene: error against wall time, both engines",
        description="Run a scene with every method of urdf2links over a ladder of tolerances or steps and with "
                    "MuJoCo's Euler, implicitfast and RK4 over a ladder of timesteps, against a reference (DOP853 "
                    "rtol 1e-13, checked by a second method); errors, energy drift, median wall time of "
                    "interleaved rounds, evaluations; the crossover. Writes tradeoff.json, tradeoff.md, "
                    "work_precision.png, energy_drift.png (and the section of report.html when the folder has "
                    "one). Progress on stderr."),
    "check": Command(
        comparisons.add_check, comparisons.run_check,
        help="check a repository's robots, pairs and scenes (urdf2links.toml or [tool.urdf2links]) for CI: exit 0, "
             "1 when a check falls short, 2 when unusable",
        description="Read the configuration ([tool.urdf2links] of pyproject.toml, or urdf2links.toml, in PATH or "
                    "above): load every robot (a load error, an inertia finding not allowed or a change since its "
                    "accepted fingerprint fails), compare every pair part by part (a difference not accepted by "
                    "name fails), run every scene against its baselines. Exit 0 when all hold, 1 when a check "
                    "falls short, 2 when the configuration or a file cannot be used (docs/ci.md)."),
    "identify": Command(
        identify.add_identify, identify.run_identify,
        help="fit a description's dynamic parameters so that it moves as a second description does in MuJoCo",
        description="Run OTHER in MuJoCo along excitation trajectories (known applied torques), record q, q', q'' "
                    "and the torques in the description's coordinates, fit the description's link inertias and "
                    "joint damping, friction, armature and offsets (base parameters, named), and write "
                    "report.html, identify.json, identify.md; --write-urdf OUT the corrected file, every change "
                    "listed (docs/identify.md)."),
    "cache": Command(
        run.add_cache, run.run_cache,
        help="list (default) or clear numba's cache of compiled code (the first run of a command compiles; the "
             "next ones load it)"),
}


def build_parser() -> argparse.ArgumentParser:
    """The ``urdf2links`` command line: one sub-command per entry of :data:`COMMANDS`."""
    parser = argparse.ArgumentParser(prog="urdf2links", description="URDF robots as trees of links of the trace "
                                     "method, simulated, and compared with MuJoCo.")
    sub = parser.add_subparsers(dest="command", required=True)
    for name, command in COMMANDS.items():
        extra = {} if command.description is None else {"description": command.description}
        p = sub.add_parser(name, help=command.help, **extra)
        if command.add_arguments is not None:
            command.add_arguments(p)
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
        return COMMANDS[args.command].run(args)
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

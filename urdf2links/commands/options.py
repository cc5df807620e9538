"""The options several commands share, written once: how a robot is loaded, a robot file's default scene, MuJoCo's
run and the report's animation, the wall-clock budget, and the scene (or robot) a command runs (pip's
``cli/cmdoptions.py`` does the same for its commands)."""

from __future__ import annotations

import argparse

from ..ranges import INERTIA_POLICIES, MIMIC_POLICIES, Q0_CHOICES

__all__ = ["INPUT", "add_scene_input", "add_load_options", "add_default_scene_options", "add_mujoco_options",
           "add_animation_option", "add_max_wall", "add_open_loops"]

#: The help of a command's scene argument, before what the command does with a robot file.
INPUT = ("a scene .toml, a robot (.urdf, .xacro), or the name of a shipped one from any folder (`urdf2links "
         "list`)")


def add_mujoco_options(p) -> None:
    """How MuJoCo runs beside the project (integrator, timestep), the run's length, the terms' states, the
    baselines' allowed growth, progress, the report's animation and the wall-clock budget: ``compare`` and
    ``report``."""
    p.add_argument("--mujoco-integrator", default="RK4", choices=("RK4", "Euler", "implicit", "implicitfast"),
                   help="MuJoCo's integrator (default RK4)")
    p.add_argument("--mujoco-dt", type=float, default=1e-4, help="MuJoCo's timestep in s (default 1e-4)")
    p.add_argument("--t-end", type=float, help="run length in s (default: the scene's [run] t_end)")
    p.add_argument("--states", type=int, default=8, help="seeded random states for the terms (default 8)")
    p.add_argument("--factor", type=float, help="allowed growth of an error over its baseline (default: the "
                   "baselines file's factor, 10)")
    p.add_argument("--quiet", action="store_true", help="no progress on stderr")
    add_animation_option(p)
    add_max_wall(p)


def _max_wall(text: str) -> float:
    """``--max-wall SECONDS``: a positive number of seconds."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"--max-wall {text!r}: not a number of seconds") from None
    if not (value > 0 and value < float("inf")):
        raise argparse.ArgumentTypeError(f"--max-wall {text!r}: must be a finite number of seconds > 0")
    return value


def add_max_wall(p) -> None:
    """``--max-wall``: the project's integration stops past this many seconds (:func:`_max_wall`)."""
    p.add_argument("--max-wall", type=_max_wall, metavar="SECONDS", help="wall-clock budget of the project's "
                   "integration (per scene): past it the run ends with an IntegrationError (exit 2) instead of "
                   "running on (default: none; step-size underflow and 1e7 steps end a run anyway)")


def add_animation_option(p) -> None:
    """``--animation-fps``: the animation's frame rate (0: none)."""
    p.add_argument("--animation-fps", type=float, default=30.0, metavar="FPS",
                   help="frames per second of simulated time in the report's animation (default 30; 0: no animation)")


def add_load_options(p) -> None:
    """How the robot is loaded: the same options on every command that loads one. For a scene file they
    replace its ``[robot]`` options (the scene's notes say so)."""
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


def add_default_scene_options(p, *, seed: bool = True, write_scene: bool = True) -> None:
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
    add_open_loops(g)
    if write_scene:
        g.add_argument("--write-scene", metavar="FILE.toml", help="also write the default scene to FILE.toml, to "
                       "edit and run by name")


def add_open_loops(p) -> None:
    """``--open-loops`` (issue 45): the file's own equalities and fixed tendons (and a URDF's mimic constraints)
    dropped on both engines, as a scene's ``[constraints] from_file = false`` does; the verdict says so."""
    p.add_argument("--open-loops", action="store_true", help="drop the robot file's own closed loops and couplings "
                   "(an MJCF file's equalities and fixed tendons, a URDF's mimic constraints) on both engines; they "
                   "act by default, as in MuJoCo (a scene file: its [constraints] from_file = false says the same)")


def add_scene_input(p, *, seed: bool = True, write_scene: bool = True,
                    scene_help: str = INPUT + "; a robot runs in its default scene") -> None:
    """The scene a command runs (a scene file, or a robot in its default scene), how its robot is loaded and the
    default scene's options: ``simulate``, ``sweep``, ``compare`` and ``tradeoff`` take them alike."""
    p.add_argument("scene", help=scene_help)
    add_load_options(p)
    add_default_scene_options(p, seed=seed, write_scene=write_scene)

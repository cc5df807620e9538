"""A robot file's default scene: what ``urdf2links simulate|compare ROBOT.urdf`` runs when no scene file is given
(gravity, the file's damping, an excited, random or resting initial state; :func:`default_scene`), and its name
(:func:`default_scene_name`)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from ..ranges import MAX_SAMPLES, Q0_CHOICES
from .actuators import hold_actuators
from .excitation import DAMPER_TORQUE_TEXT, coordinate_ranges, damper_torques, excited_state
from .scene import RunSettings, Scene
from .scene_checks import SceneReader

__all__ = ["default_scene", "default_scene_name", "DEFAULT_SCENE_NAME"]

#: Name of the scene :func:`default_scene` makes (reports go to ``reports/<robot>/default/``).
DEFAULT_SCENE_NAME = "default"
#: The default scene's initial states (:data:`urdf2links.ranges.Q0_CHOICES`): ``excite`` (every coordinate moving,
#: E65; the default), ``random`` (random q0, at rest), ``rest`` (q = 0 or qpos0, at rest; ``zero`` is its old name).


def _random_q0(model, rng) -> dict:
    """A seeded initial configuration: each joint coordinate uniform within its range
    (:func:`~urdf2links.scenes.excitation.coordinate_ranges`: its limits when finite, below
    :data:`~urdf2links.scenes.excitation.NO_LIMIT` in magnitude and lower < upper, else a window of +-1 (rad or m) around its start);
    a floating root's position stays at the origin."""
    r = coordinate_ranges(model)
    q = rng.uniform(r.lower, r.upper)
    return {name: float(v) for name, v, root in zip(r.names, q, r.root) if not root}


def default_scene(robot, *, floating: bool = False, q0: str = "excite", seed: int = 0, t_end: float = 1.0,
                  xacro_args=None, package_dirs=(), inertia: str = "audit", mimic: str = "independent",
                  strict: bool = False, model=None, hold: float | None = None, open_loops: bool = False) -> Scene:
    """The scene ``urdf2links simulate|compare ROBOT.urdf`` runs when no scene file is given.

    Gravity (9.81 m/s^2 along -z); a fixed base, or with ``floating`` six coordinates for the root
    link; the URDF's joint damping as dampers (``[dampers] from_urdf = true``). The initial state
    (``q0``, :data:`Q0_CHOICES`): ``"excite"`` (the default) moves every coordinate a good part of its
    range within the run, a floating root too (:func:`~urdf2links.scenes.excitation.excited_state`, E65,
    seeded by ``seed``); ``"random"`` a seeded random configuration at rest (:func:`_random_q0`);
    ``"rest"`` (or ``"zero"``) at rest at the zero configuration (an MJCF file's qpos0). ``t_end``
    seconds with the default integrator (``RunSettings``: auto, i.e. DOP853 and Radau5 while the
    scene is stiff, rtol 1e-10), 500 samples a second (at least 101).
    ``robot`` is a ``.urdf`` or ``.xacro`` path (with ``xacro_args``); ``model`` an already loaded model
    of it (loaded here otherwise, to know its coordinates and limits). ``hold`` (a bandwidth in Hz,
    ``--hold``): a position servo on every coordinate holding the initial ``q``
    (:func:`~urdf2links.scenes.actuators.hold_actuators`). The scene is named
    :func:`default_scene_name`; :func:`urdf2links.scenes.scene_toml.write_scene` writes it as TOML to edit.
    An MJCF file's own equalities and fixed tendons act (issue 45, as in MuJoCo); ``open_loops``
    (``--open-loops``) drops them (:func:`~urdf2links.scenes.file_constraints.open_loops`, noted).
    """
    where = f"default scene of {robot}"
    r = SceneReader(where)
    r.choice(q0, "q0", Q0_CHOICES)
    q0 = "rest" if q0 == "zero" else q0
    t_end = r.number(t_end, "t_end", positive=True, quantity="time")
    from ..parsers.robot_file import is_mjcf_path, load_robot

    mjcf = is_mjcf_path(robot)
    if mjcf and (floating or xacro_args or package_dirs or mimic != "independent"):
        r.fail("robot", f"{robot} is an MJCF file: --floating, --xacro-arg, --package-dir and --mimic apply to URDF "
                        "files (an MJCF file says itself how its bodies move)")
    options = ({"inertia": inertia, "strict": bool(strict)} if mjcf else
               {"floating_base": bool(floating), "inertia": inertia, "mimic": mimic, "strict": bool(strict)})
    if package_dirs:
        options["package_dirs"] = tuple(Path(p) for p in package_dirs)
    if xacro_args:
        options["xacro_args"] = {str(k): str(v) for k, v in xacro_args.items()}
    if model is None:
        import warnings

        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the audit is in model.audit; inspect shows it
            model = load_robot(robot, **options)
    q_init, qd_init, state = _default_state(model, q0, seed, t_end, mjcf)
    held, held_text = (), ""
    if hold is not None:
        start = model.info.get("q0")
        start = np.zeros(model.n) if start is None else np.asarray(start, float)
        held = hold_actuators(model, [q_init.get(nm, start[i]) for i, nm in enumerate(model.coordinate_names)],
                              bandwidth=hold)
        held_text = f", held at q0 by position servos (critically damped at {hold:g} Hz)"
    run = RunSettings(t_end=t_end, samples=min(MAX_SAMPLES, max(101, int(round(500 * t_end)) + 1)))
    name = default_scene_name(floating=floating, q0=q0, seed=seed, inertia=inertia, mimic=mimic, hold=hold,
                              open_loops=open_loops)
    scene = _default_scene(robot, mjcf, model, options, name, state + held_text, q_init, qd_init, run, held, floating)
    if open_loops:
        from .file_constraints import open_loops as opened

        scene = opened(scene)
    if q0 in ("excite", "random"):      # issue 45: a random start carried onto the closed loops, when they act
        from .loop_start import start_on_loops

        scene = start_on_loops(scene, model)
        qd_init = scene.qd0
    if q0 != "excite" or held:      # --hold's servos hold the joints: no damper torque to fight them
        return scene
    torques = damper_torques(scene.springs_for(model).springs, qd_init)
    if not torques:
        return scene
    return dataclasses.replace(scene, torques=torques, description=scene.description + "; " + DAMPER_TORQUE_TEXT)


def _default_scene(robot, mjcf, model, options, name, state, q_init, qd_init, run, held, floating) -> Scene:
    """The default scene's :class:`Scene` for an MJCF file (its own gravity, damping, springs) or a URDF."""
    if mjcf:
        g = np.asarray(model.info["option"]["gravity"], float)
        off = model.info["option"].get("disabled", [])
        effects = [w for w, on in (("joint damping", "damper" not in off), ("stiffness (at springref)", "spring" not in off),
                                   ("gravcomp", True)) if on]
        return Scene(name=name, path=None, robot=Path(robot), load_options=options,
                     description=f"default scene of an MJCF file: the file's gravity {g.tolist()}, its "
                                 + ", ".join(effects) + "; " + state,
                     gravity=g if np.any(g) else None, q0=q_init, qd0=qd_init, urdf_damping="damper" not in off,
                     file_springs="spring" not in off, gravcomp=True, run=run, actuators=held)
    base = "floating base" if floating else "fixed base"
    return Scene(name=name, path=None, robot=Path(robot), load_options=options,
                 description=f"default scene: gravity, {base}, URDF damping, {state}",
                 gravity=np.array([0.0, 0.0, -9.81]), q0=q_init, qd0=qd_init, urdf_damping=True, run=run,
                 actuators=held)


def _default_state(model, q0: str, seed: int, t_end: float, mjcf: bool) -> tuple[dict, dict, str]:
    """The default scene's ``(q0, qd0, phrase for its description)`` for the choice ``q0``."""
    zero = "MuJoCo's qpos0" if mjcf else "q = 0"
    if q0 == "excite":
        ex = excited_state(model, seed=seed, t_end=t_end)
        return ex.q0, ex.qd0, ex.text
    if q0 == "random":
        return (_random_q0(model, np.random.default_rng(seed)), {},
                f"at rest, q0 random within the joint limits (seed {seed})")
    return {}, {}, f"at rest at {zero} (--q0 rest)"


def default_scene_name(*, floating: bool = False, q0: str = "excite", seed: int = 0, inertia: str = "audit",
                       mimic: str = "independent", hold: float | None = None, open_loops: bool = False) -> str:
    """:data:`DEFAULT_SCENE_NAME`, with what differs from the plain default scene appended
    (``default-floating-random-seed3-repair``, ``default-rest``, ``default-seed2``), so that reports of
    one robot in other settings do not replace each other."""
    q0 = "rest" if q0 == "zero" else q0
    parts = [DEFAULT_SCENE_NAME] + (["floating"] if floating else [])
    parts += {"random": [f"random-seed{seed}"], "rest": ["rest"]}.get(q0, [f"seed{seed}"] if seed else [])
    parts += [inertia] if inertia != "audit" else []
    parts += [mimic] if mimic != "independent" else []
    parts += [] if hold is None else ["hold" if hold == 2.0 else f"hold{hold:g}hz"]
    parts += ["open-loops"] if open_loops else []
    return "-".join(parts)

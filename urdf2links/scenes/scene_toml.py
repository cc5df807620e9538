"""Scenes as TOML text, and a scene from a file that is either a scene or a robot.

:func:`scene_toml` writes a :class:`~urdf2links.scenes.scene.Scene` in the schema :func:`~urdf2links.scenes.scene_read.load_scene`
reads -- robot, gravity, springs, ``[dampers]``, initial state, run, recorded poses -- so that
``urdf2links simulate ROBOT.urdf --write-scene FILE.toml`` hands the user the default scene to edit
(it reads back to the same scene). Time functions (a moving base, loads, torques) have no TOML
writer: such a scene is refused by name. :func:`scene_or_robot` is what the CLI runs: a ``.toml``
file is loaded as a scene, anything else is a robot run in its :func:`~urdf2links.scenes.default_scenes.default_scene`.

Public API: :func:`scene_toml`, :func:`write_scene`, :func:`scene_or_robot`.
"""

from __future__ import annotations

import json
from dataclasses import fields
from pathlib import Path

from .contact import contact_toml
from ..errors import SceneError, URDFError
from ..parsers.xacro_input import parse_xacro_arg
from .constraints import constraint_toml
from .expect import expect_toml
from .default_scenes import default_scene
from .scene import RunSettings, Scene
from .scene_read import load_scene

__all__ = ["scene_toml", "scene_with_plan", "write_scene", "scene_or_robot", "scene_from_args", "write_scene_option",
           "xacro_args_of", "hold_of", "ground_of"]


def _value(v) -> str:
    """A TOML scalar, list or inline table (JSON's spelling is TOML's for these)."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return repr(v)
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{_key(k)} = {_value(x)}" for k, x in v.items()) + " }" if v else "{}"
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    if isinstance(v, int):
        return str(v)
    return json.dumps(str(v))


def _key(k: str) -> str:
    return k if k.replace("_", "").replace("-", "").isalnum() else json.dumps(k)


def _robot_lines(scene: Scene, folder: Path | None) -> list[str]:
    robot = Path(scene.robot).resolve()
    if folder is not None and robot.is_relative_to(folder.resolve()):  # else absolute: no ../../ chains
        robot = robot.relative_to(folder.resolve())
    key = "mjcf" if robot.suffix.lower() in (".xml", ".mjcf") else "urdf"
    lines = ["[robot]", f"{key} = {_value(robot.as_posix())}"]
    for key, value in scene.load_options.items():
        if key == "package_dirs":
            value = [Path(p).resolve().as_posix() for p in value]
        lines.append(f"{key} = {_value(value)}")
    return lines


def _run_lines(run: RunSettings) -> list[str]:
    lines = ["[run]"]
    for f in fields(RunSettings):
        value = getattr(run, f.name)
        if value is not None:
            lines.append(f"{f.name} = {_value(value)}")
    return lines


def scene_toml(scene: Scene, *, folder=None) -> str:
    """``scene`` as TOML text (robot path relative to ``folder`` when given). SceneError for a scene
    with time functions (base motion, loads, torques that are not constant), which this writer does not spell."""
    from .functions import Constant, Sines

    functions = [w for w, on in (("[base]", scene.base is not None), ("[[force]]/[[moment]]", bool(scene.loads)),
                                 ("[[torque]]", any(not isinstance(f, Constant) for _, f in scene.torques)),
                                 ("[[computed_torque]]", bool(scene.computed_torque)),
                                 ("[[actuator]] ctrl", any(not isinstance(a.ctrl, (Constant, Sines)) for a in scene.actuators)))
                 if on]
    if functions:
        raise SceneError(f"scene {scene.name!r}: {', '.join(functions)} hold functions of time, which cannot be "
                         "written back as TOML; copy the scene file instead")
    folder = None if folder is None else Path(folder)
    out = ["# urdf2links scene (edit freely; `urdf2links simulate` / `compare` run it)",
           f"description = {_value(scene.description)}", f"chaotic = {_value(scene.chaotic)}", ""]
    out += _robot_lines(scene, folder) + [""]
    if scene.gravity is not None:
        g = [float(x) for x in scene.gravity]
        mag = sum(x * x for x in g) ** 0.5
        out += ["[gravity]", f"magnitude = {_value(mag)}",
                f"direction = {_value([x / mag for x in g] if mag else [0.0, 0.0, -1.0])}", ""]
    for s in scene.springs:
        out += ["[[spring]]", f"coordinate = {_value(s.coordinate)}", f"stiffness = {_value(float(s.stiffness))}",
                f"rest = {_value(float(s.rest))}", f"damping = {_value(float(s.damping))}", ""]
    out += ["[dampers]", "# each joint's damping (URDF <dynamics damping>, MJCF damping) as a damper on its coordinate",
            f"from_urdf = {_value(scene.urdf_damping)}", ""]
    if scene.file_springs:
        out += ["[springs]", "# each MJCF hinge's and slide's stiffness as a spring at its springref", "from_file = true", ""]
    if scene.gravcomp or scene.gravcomp_factor is not None or scene.gravcomp_bodies:
        out += ["[gravcomp]", "# MuJoCo's body gravcomp: a force -gravcomp m g at each body's COM"]
        out += ["from_file = true"] if scene.gravcomp else []
        out += [f"factor = {_value(float(scene.gravcomp_factor))}"] if scene.gravcomp_factor is not None else []
        out += [f"bodies = {_value({b: float(f) for b, f in scene.gravcomp_bodies})}"] if scene.gravcomp_bodies else []
        out += [""]
    for coord, f in scene.torques:       # constant ones (the default scene's damper torques, E65)
        out += ["[[torque]]", f"coordinate = {_value(coord)}", f"value = {_value(float(f.value))}", ""]
    out += _actuator_lines(scene.actuators)
    out += constraint_toml(scene, _value)       # issue 36: [constraints], [[constraint]]
    out += contact_toml(scene.contacts, _value)     # issue 37
    out += ["[initial]", f"q = {_value({k: float(v) for k, v in scene.q0.items()})}",
            f"qd = {_value({k: float(v) for k, v in scene.qd0.items()})}", ""]
    out += _run_lines(scene.run) + [""]
    if scene.link_poses:
        out += ["[record]", f"link_poses = {_value(list(scene.link_poses))}", ""]
    out += expect_toml(scene.expected_stop, _value)     # issue 42: a hard case that stops by design
    return "\n".join(out)


def scene_with_plan(scene: Scene, plan_text: str) -> str:
    """What ``urdf2links inspect ... --scene`` prints: a scene file's plan as it is; a default scene as its TOML
    followed by the plan as TOML comments, so that ``inspect ROBOT --scene > f.toml`` writes a scene file that
    parses (issue 43)."""
    if scene.path is not None:
        return plan_text
    comments = "\n".join(f"# {line}".rstrip() for line in plan_text.splitlines())
    return f"{scene_toml(scene).rstrip()}\n\n# the plan of this scene (urdf2links inspect):\n{comments}"


def _actuator_lines(actuators) -> list[str]:
    """``[[actuator]]`` blocks of actuators whose ctrl is a constant (``--hold``'s servos, or a scene's)."""
    out = []
    for a in actuators:
        out.append("[[actuator]]" + {"hold": "  # --hold: critically damped on A_ii at q0 (E56)",
                                      "stand": "  # --ground: the stance's servo (docs/contact.md)"}.get(a.source, ""))
        out.append(f"name = {_value(a.name)}")
        if a.coordinate is not None:
            out += [f"coordinate = {_value(a.coordinate)}", f"kind = {_value(a.kind)}"]
            if a.kind == "position":
                out += [f"kp = {_value(float(a.kp))}", f"kv = {_value(float(a.kv))}"]
            elif a.kind == "velocity":
                out += [f"kv = {_value(float(a.kv))}"]
            elif a.kind == "general":
                out += [f"gainprm = {_value([float(a.gain)])}", f"biasprm = {_value([float(b) for b in a.bias])}"]
            out.append(f"gear = {_value(float(a.gear))}")
            out += [f"ctrlrange = {_value(list(map(float, a.ctrlrange)))}"] if a.ctrlrange is not None else []
            out += [f"forcerange = {_value(list(map(float, a.forcerange)))}"] if a.forcerange is not None else []
        out += [f"ctrl = {_ctrl_value(a.ctrl)}", ""]
    return out


def _ctrl_value(f) -> str:
    """A constant ctrl, or a sum of sines (the stance's sway, issue 43) as its TOML table."""
    if hasattr(f, "value"):
        return _value(float(f.value))
    return (f"{{ offset = {_value(float(f.offset))}, rate = {_value(float(f.rate))}, sines = "
            f"{_value([[float(x) for x in term] for term in f.terms])} }}")


def write_scene(scene: Scene, path) -> Path:
    """Write :func:`scene_toml` of ``scene`` to ``path`` (robot path relative to its folder)."""
    path = Path(path)
    if path.suffix != ".toml":
        raise SceneError(f"{path}: a scene file must end in .toml")
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(scene_toml(scene, folder=path.parent))
    return path


#: The loading options every command that loads a robot takes (``urdf2links ... --inertia repair``).
LOAD_OPTIONS = ("floating_base", "inertia", "mimic", "strict", "package_dirs", "xacro_args")


def scene_or_robot(path, *, floating: bool = False, q0: str = "excite", seed: int = 0, t_end: float | None = None,
                   xacro_args=None, package_dirs=(), load: dict | None = None, hold: float | None = None,
                   open_loops: bool = False) -> Scene:
    """A scene file (``.toml``), or the default scene of a robot file (``.urdf``, ``.xacro``, ...) with
    these options (``t_end`` default 1 s). ``load``: loading options given on the command line
    (``inertia``, ``mimic``, ``strict``, ``package_dirs``, ``xacro_args``; :func:`load_options_of`);
    for a scene file they replace those of its ``[robot]`` (:func:`override_loading` says so). The
    default scene's options (``--floating``, ``--q0``) are refused for a scene file, which says its own
    robot and initial state; so is ``hold`` (``--hold``: the default scene's servos; a scene file names its
    actuators)."""
    path = Path(path)
    load = dict(load or {})
    if xacro_args:
        load["xacro_args"] = dict(xacro_args)
    if package_dirs:
        load["package_dirs"] = tuple(package_dirs)
    if path.suffix == ".toml":
        given = [o for o, on in (("--floating", floating or load.pop("floating_base", False)),
                                 ("--q0", q0 != "excite"), ("--hold", hold is not None)) if on]
        if given:
            raise SceneError(f"{path}: {', '.join(given)} apply to a robot file run in its default scene; a scene "
                             "file names its robot, initial state and actuators in [robot], [initial] and [[actuator]]")
        scene = override_loading(load_scene(path), load)
        if open_loops:      # issue 45: --open-loops drops the file's equalities (noted)
            from .file_constraints import open_loops as opened

            scene = opened(scene)
        return scene
    opts = {k: v for k, v in load.items() if k in ("inertia", "mimic", "strict")}
    return default_scene(path, floating=floating or bool(load.get("floating_base")), q0=q0, seed=seed,
                         t_end=1.0 if t_end is None else t_end, xacro_args=load.get("xacro_args"),
                         package_dirs=load.get("package_dirs", ()), hold=hold, open_loops=open_loops, **opts)


def override_loading(scene: Scene, load: dict) -> Scene:
    """``scene`` with the loading options ``load`` in place of its ``[robot]``'s; each replaced value is
    recorded in ``scene.notes`` (nothing changes silently)."""
    load = {k: v for k, v in load.items() if v not in (None, (), {}, False)}
    if not load:
        return scene
    import dataclasses

    was = scene.load_options
    notes = [f"{k} = {v!r} from the command line" + (f" (the scene file says {was[k]!r})" if k in was else "")
             for k, v in load.items() if was.get(k) != v]
    return dataclasses.replace(scene, load_options={**was, **load}, notes=tuple(scene.notes) + tuple(notes))


# -- command-line options shared by the commands that load a robot ------------------------------
def xacro_args_of(args) -> dict:
    """``--xacro-arg name:=value`` options as a dict (a URDFError names a malformed one)."""
    try:
        return dict(parse_xacro_arg(a) for a in (getattr(args, "xacro_arg", None) or []))
    except ValueError as err:
        raise URDFError(f"--xacro-arg: {err}") from None


def load_options_of(args) -> dict:
    """The loading options given on the command line (``--floating``, ``--inertia``, ``--mimic``,
    ``--strict``, ``--package-dir``, ``--xacro-arg``), only those given."""
    out = {"floating_base": bool(getattr(args, "floating", False)), "inertia": getattr(args, "inertia", None),
           "mimic": getattr(args, "mimic", None), "strict": bool(getattr(args, "strict", False)),
           "package_dirs": tuple(getattr(args, "package_dir", None) or ()), "xacro_args": xacro_args_of(args)}
    return {k: v for k, v in out.items() if v not in (None, (), {}, False)}


def hold_of(args) -> float | None:
    """``--hold`` (with ``--hold-bandwidth``): the servos' bandwidth in Hz, or None; a SceneError for a
    bandwidth given without ``--hold``."""
    from .actuators import HOLD_BANDWIDTH_HZ

    bandwidth = getattr(args, "hold_bandwidth", None)
    if not getattr(args, "hold", False):
        if bandwidth is not None:
            raise SceneError("--hold-bandwidth sets the servos of --hold: give --hold too")
        return None
    return HOLD_BANDWIDTH_HZ if bandwidth is None else bandwidth


def scene_from_args(args):
    """The scene a ``simulate``/``compare``/``sweep``/``tradeoff`` command runs: ``args.scene`` as a scene
    file (with the loading options given), or a robot file in its default scene with ``--floating``,
    ``--q0``, ``--seed``, ``--t-end``, ``--hold``, ``--ground`` and the loading options."""
    scene = scene_or_robot(args.scene, q0=getattr(args, "q0", "excite"), seed=getattr(args, "seed", 0),
                           t_end=getattr(args, "t_end", None), load=load_options_of(args), hold=hold_of(args),
                           open_loops=bool(getattr(args, "open_loops", False)))
    return ground_of(args, scene)


def ground_of(args, scene, model=None):
    """``--ground`` (issue 37) and a file's floor (issue 43, ``--no-floor`` drops it) on a robot's default scene
    (:func:`urdf2links.scenes.stance.ground_for`); the feet chosen are said on stderr."""
    import warnings

    from ..console import err
    from ..parsers.robot_file import is_mjcf_path
    from .stance import ground_for

    ground = bool(getattr(args, "ground", False))
    if scene.path is not None and not ground or not (ground or is_mjcf_path(scene.robot)):
        return scene
    if model is None:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")     # the default scene's audit is inspect's
            model = scene.model()
    out = ground_for(scene, model, ground=ground, floor=not getattr(args, "no_floor", False),
                     q0=getattr(args, "q0", "excite") or "excite", seed=getattr(args, "seed", 0) or 0)
    for note in out.notes[len(scene.notes):]:
        err(f"{scene.name}: {note}")
    return out


def write_scene_option(args, scene) -> None:
    """``--write-scene FILE``: write the scene a command ran as TOML, and say where."""
    if getattr(args, "write_scene", None):
        print(f"  scene written to {write_scene(scene, args.write_scene)} (edit it, then run it by name)")

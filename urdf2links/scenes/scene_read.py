"""A scene's TOML form: a scene file read into a :class:`~urdf2links.scenes.scene.Scene`, every key checked (an
unknown key, a value out of its range or of the wrong kind is a SceneError naming the file and the key;
:mod:`urdf2links.scenes.scene_checks`). A scene file names a robot, the effects that act on it, its initial state
and the run.

Schema (every table optional except ``[robot]``; an effect that is not named does not act and is
not computed, see :mod:`urdf2links.scenes.plan`)::

    description = "what the scene shows"
    chaotic = false                         # the comparison reports a divergence time, not an error

    [robot]
    urdf = "double_pendulum.urdf"           # path relative to this file (.urdf, .xacro, or .xml: MJCF); or
    # mjcf = "ant.xml"                      # an MJCF file (the same as urdf = "ant.xml")
    # shipped = "double_pendulum"           # a robot of robots/; or
    # example_robot_data = "ur_description/urdf/ur5_robot.urdf"
    floating_base = false
    inertia = "audit"                       # audit | strict | repair
    mimic = "independent"                   # independent | coupled
    strict = false                          # refuse what the default reading tolerates (notes)
    xacro_args = { prefix = "left_" }       # arguments of a .xacro robot (name:=value)

    [gravity]                               # absent: no gravity
    magnitude = 9.81                        # m/s^2
    direction = [0, 0, -1]

    [base]                                  # prescribed motion of {A}: x, y, z [m], phi_x, phi_y, phi_z [rad]
    z = { sines = [[0.8, 0.1, 0.0]] }       # each a function of time (urdf2links.scenes.functions)

    [[force]]                               # (E23): a force on a link
    link = "lower"; point = [0, 0, -1.0]    # application point in the link's (URDF) frame [m]
    frame = "world"                         # axes of the vector: link | world
    value = [0, 0, { sines = [[2.0, 0.5]] }]   # N, three functions of time

    [[moment]]                              # (E23): link, frame, value [N m]
    [[torque]]                              # coordinate = "shoulder"; value = function [N m or N]
    [[spring]]                              # coordinate, stiffness [N m/rad], rest [rad], damping [N m s/rad]

    [dampers]
    from_urdf = true                        # each joint's <dynamics damping> (MJCF: damping) as a damper (a
                                            # [[spring]]'s own damping on the same coordinate takes precedence);
                                            # from_file = true says the same
    [springs]
    from_file = true                        # MJCF: each hinge's and slide's stiffness, at its springref
    [gravcomp]                              # MuJoCo's body gravcomp: a force -gravcomp m g at each body's COM
    from_file = true                        # MJCF: each body's own gravcomp
    factor = 1.0                            # every body (URDF link or MJCF body) with mass
    bodies = { upper_arm_link = 0.5 }       # these bodies (after factor and from_file)

    [[actuator]]                            # MuJoCo's actuator law (urdf2links.scenes.actuators, E55)
    coordinate = "elbow"; kind = "position" # motor | position | velocity | general
    kp = 300.0; kv = 30.0; gear = 1.0       # general: gainprm = [k], biasprm = [b0, b1, b2]
    ctrl = { sines = [[0.8, 1.0, 0.0]] }    # a function of time
    ctrlrange = [-2.0, 2.0]; forcerange = [-20.0, 20.0]   # optional clamps
    # name = "shoulder_motor"; ctrl = 0.3   # an MJCF robot's own actuator: the scene sets its ctrl

    [[computed_torque]]                     # inverse dynamics of a reference (E57): q = reference exactly
    coordinate = "elbow"                    # when the model matches; other coordinates held at [initial]
    reference = { sines = [[0.5, 0.5]] }

    [constraints]                           # closed loops (docs/constraints.md): from_file = true (an MJCF file's
                                            # equalities and fixed tendons), mimic = true (URDF <mimic> as rows),
    change_point = "continue"               # issue 45: at a loop's change point drop the dependent row there and
                                            # go on, the event named ("continue", default), or "stop" (DynamicsError)

    [initial]
    q = { shoulder = 1.2 }                  # by coordinate name; unnamed coordinates start at 0
    qd = {}

    [run]
    t_end = 10.0; method = "auto"; rtol = 1e-10; atol = 1e-12; dt = 1e-3; samples = 1001
                                            # method: auto (default: DOP853, Radau5 while stiff), RK45, DOP853,
                                            # Radau5, Radau, BDF, LSODA, RK4, midpoint
    recharting = true                       # floating links pass phi_y = +-pi/2 (urdf2links.integration.charts)

    [record]
    link_poses = ["lower"]                  # {0}-poses of these links at every sample
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..dynamics.transforms import PARAMETERS
from ..errors import SceneError
from ..locations import example_robot_data_dir, read_toml, shipped_robots_dir
from ..ranges import MAX_SAMPLES, METHODS
from .actuators import parse_actuators
from .constraints import constraint_options, parse_constraints
from .contact import parse_contacts
from .expect import parse_expect
from .functions import Constant
from .scene import AppliedLoad, RunSettings, Scene, Spring, did_you_mean
from .scene_checks import SceneReader, check_run

__all__ = ["load_scene", "scene_from_dict"]

_TOP = ("description", "chaotic", "robot", "gravity", "base", "force", "moment", "torque", "spring",
        "dampers", "springs", "gravcomp", "initial", "run", "record", "actuator", "computed_torque",
        "constraint", "constraints",   # issue 36: [[constraint]], [constraints] from_file
        "contact", "expect")       # issue 37; issue 42: [expect] a hard case's stop (urdf2links.scenes.expect)
_ROBOT = ("urdf", "mjcf", "shipped", "example_robot_data", "floating_base", "inertia", "mimic", "package_dirs",
          "strict", "xacro_args")
_RUN = ("t_end", "method", "rtol", "atol", "dt", "samples", "recharting")


def load_scene(path) -> Scene:
    """Read and validate a scene file (names of links and coordinates are checked by :meth:`Scene.model`)."""
    path = Path(path)
    data = read_toml(path, error=SceneError, what="scene file")
    return scene_from_dict(data, where=str(path), directory=path.parent, name=path.stem, path=path)


def scene_from_dict(data: dict, *, where: str = "<scene>", directory: Path | None = None, name: str = "scene",
                    path: Path | None = None) -> Scene:
    """A :class:`Scene` from the parsed TOML ``data``; ``where`` names the file in errors,
    ``directory`` is where relative robot paths start."""
    r = SceneReader(where)
    r.keys(data, _TOP, "")
    if "robot" not in data:
        r.fail("[robot]", "missing: name the robot with urdf = 'file.urdf', shipped = 'name' or example_robot_data = '...'")
    robot_t = data["robot"]
    r.keys(robot_t, _ROBOT, "robot")
    robot = _robot_path(r, robot_t, directory)
    options, gravity, base = _robot_options(r, robot_t, directory), _gravity(r, data), _base(r, data)
    loads, torques, springs = _loads(r, data), _torques(r, data), _springs(r, data)
    (q0, qd0), run, link_poses = _initial(r, data), _run(r, data), _record(r, data)
    urdf_damping = _dampers(r, data)
    file_springs = _from_file(r, data, "springs")
    gravcomp, gravcomp_factor, gravcomp_bodies = _gravcomp(r, data)
    actuators, computed = parse_actuators(r, data), _computed_torque(r, data)
    description = data.get("description", "")
    chaotic = data.get("chaotic", False)
    if not isinstance(description, str):
        r.fail("description", "must be a string")
    if not isinstance(chaotic, bool):
        r.fail("chaotic", f"must be true or false, got {chaotic!r}")
    return Scene(name=name, path=path, robot=robot, load_options=options, description=description,
                 chaotic=chaotic, gravity=gravity, base=base, loads=loads, torques=torques, springs=springs,
                 q0=q0, qd0=qd0, run=run, link_poses=link_poses, urdf_damping=urdf_damping,
                 file_springs=file_springs, gravcomp=gravcomp, actuators=actuators, computed_torque=computed,
                 gravcomp_factor=gravcomp_factor, gravcomp_bodies=gravcomp_bodies,
                 constraints=parse_constraints(r, data), **constraint_options(r, data),
                 contacts=parse_contacts(r, data), expected_stop=parse_expect(r, data))     # issues 37, 42


def _gravcomp(r: SceneReader, data: dict) -> tuple[bool, float | None, tuple]:
    """``[gravcomp]``: ``from_file`` (MJCF), ``factor`` (every body), ``bodies`` ({name: factor})."""
    if "gravcomp" not in data:
        return False, None, ()
    t = data["gravcomp"]
    r.keys(t, ("from_file", "factor", "bodies"), "gravcomp")
    from_file = t.get("from_file", False)
    if not isinstance(from_file, bool):
        r.fail("gravcomp.from_file", f"must be true or false, got {from_file!r}")
    factor = r.number(t["factor"], "gravcomp.factor", quantity="scale") if "factor" in t else None
    bodies = t.get("bodies", {})
    r.keys(bodies, tuple(bodies) if isinstance(bodies, dict) else (), "gravcomp.bodies")
    return from_file, factor, tuple((str(b), r.number(v, f"gravcomp.bodies.{b}", quantity="scale"))
                                    for b, v in bodies.items())


def _computed_torque(r: SceneReader, data: dict) -> tuple:
    """``[[computed_torque]]`` blocks: ``(coordinate, reference function of time)``, each coordinate once."""
    out, seen = [], set()
    for i, item in enumerate(r.items(data, "computed_torque")):
        key = f"computed_torque[{i}]"
        r.keys(item, ("coordinate", "reference"), key)
        if not isinstance(item.get("coordinate"), str) or "reference" not in item:
            r.fail(key, "needs coordinate = 'name' and reference = a function of time (its value, rate and "
                        "acceleration are the reference's)")
        if item["coordinate"] in seen:
            r.fail(f"{key}.coordinate", f"{item['coordinate']!r} has a reference already")
        seen.add(item["coordinate"])
        out.append((item["coordinate"], r.function(item["reference"], f"{key}.reference")))
    return tuple(out)


def _dampers(r: SceneReader, data: dict) -> bool:
    """``[dampers] from_urdf`` (or ``from_file``): whether the file's joint damping acts
    (:meth:`Scene.springs_for`)."""
    if "dampers" not in data:
        return False
    r.keys(data["dampers"], ("from_urdf", "from_file"), "dampers")
    values = [data["dampers"][k] for k in ("from_urdf", "from_file") if k in data["dampers"]]
    for k in ("from_urdf", "from_file"):
        if k in data["dampers"] and not isinstance(data["dampers"][k], bool):
            r.fail(f"dampers.{k}", f"must be true or false, got {data['dampers'][k]!r}")
    if len(set(values)) > 1:
        r.fail("dampers", "from_urdf and from_file say the same thing: give one, or the same value")
    return bool(values and values[0])


def _from_file(r: SceneReader, data: dict, table: str) -> bool:
    """``[springs] from_file`` / ``[gravcomp] from_file``: whether the MJCF file's joint stiffness (at
    springref) or its bodies' gravcomp act."""
    if table not in data:
        return False
    r.keys(data[table], ("from_file",), table)
    value = data[table].get("from_file", False)
    if not isinstance(value, bool):
        r.fail(f"{table}.from_file", f"must be true or false, got {value!r}")
    return value


def _robot_options(r: SceneReader, robot_t: dict, directory) -> dict:
    """``[robot]``'s loading options for :func:`~urdf2links.parsers.importer.load_urdf`."""
    options = {}
    if "floating_base" in robot_t:
        if not isinstance(robot_t["floating_base"], bool):
            r.fail("robot.floating_base", f"must be true or false, got {robot_t['floating_base']!r}")
        options["floating_base"] = robot_t["floating_base"]
    if "inertia" in robot_t:
        options["inertia"] = r.choice(robot_t["inertia"], "robot.inertia", ("audit", "strict", "repair"))
    if "mimic" in robot_t:
        options["mimic"] = r.choice(robot_t["mimic"], "robot.mimic", ("independent", "coupled"))
    if "package_dirs" in robot_t:
        dirs = r.strings(robot_t["package_dirs"], "robot.package_dirs")
        options["package_dirs"] = tuple((directory or Path.cwd()) / p for p in dirs)
    if "strict" in robot_t:
        if not isinstance(robot_t["strict"], bool):
            r.fail("robot.strict", f"must be true or false, got {robot_t['strict']!r}")
        options["strict"] = robot_t["strict"]
    if "xacro_args" in robot_t:
        args = robot_t["xacro_args"]
        r.keys(args, tuple(args) if isinstance(args, dict) else (), "robot.xacro_args")
        options["xacro_args"] = {str(k): str(v) for k, v in args.items()}
    return options


def _gravity(r: SceneReader, data: dict):
    """``[gravity]``: the vector (3,) in m/s^2, or None when the scene names no gravity."""
    if "gravity" not in data:
        return None
    g = data["gravity"]
    r.keys(g, ("magnitude", "direction"), "gravity")
    mag = r.number(g.get("magnitude", 9.81), "gravity.magnitude", nonnegative=True, quantity="acceleration")
    d = r.vector(g.get("direction", [0, 0, -1]), "gravity.direction", quantity="scale")
    if np.linalg.norm(d) < 1e-9:
        r.fail("gravity.direction", "must not be the zero vector")
    return mag * d / np.linalg.norm(d)


def _base(r: SceneReader, data: dict):
    """``[base]``: six functions of time (x, y, z, phi_x, phi_y, phi_z of {A}), or None (fixed)."""
    if "base" not in data:
        return None
    r.keys(data["base"], PARAMETERS, "base")
    return tuple(r.function(data["base"][p], f"base.{p}") if p in data["base"] else Constant(0.0)
                 for p in PARAMETERS)


def _loads(r: SceneReader, data: dict) -> tuple:
    """``[[force]]`` and ``[[moment]]`` blocks as :class:`AppliedLoad`."""
    loads = []
    for kind in ("force", "moment"):
        for i, item in enumerate(r.items(data, kind)):
            key = f"{kind}[{i}]"
            allowed = ("link", "point", "frame", "value") if kind == "force" else ("link", "frame", "value")
            r.keys(item, allowed, key)
            if not isinstance(item.get("link"), str):
                r.fail(f"{key}.link", "must name a link")
            if "value" not in item:
                r.fail(f"{key}.value", "missing: three functions of time (N or N m)")
            loads.append(AppliedLoad(
                kind=kind, link=item["link"],
                frame=r.choice(item.get("frame", "link"), f"{key}.frame", ("link", "world")),
                value=r.vector_function(item["value"], f"{key}.value"),
                point=r.vector(item["point"], f"{key}.point", quantity="length") if "point" in item else np.zeros(3)))
    return tuple(loads)


def _torques(r: SceneReader, data: dict) -> tuple:
    """``[[torque]]`` blocks: ``(coordinate, function of time)``."""
    torques = []
    for i, item in enumerate(r.items(data, "torque")):
        r.keys(item, ("coordinate", "value"), f"torque[{i}]")
        if not isinstance(item.get("coordinate"), str) or "value" not in item:
            r.fail(f"torque[{i}]", "needs coordinate = 'name' and value = a function of time")
        torques.append((item["coordinate"], r.function(item["value"], f"torque[{i}].value")))
    return tuple(torques)


def _springs(r: SceneReader, data: dict) -> tuple:
    """``[[spring]]`` blocks as :class:`Spring` (stiffness, rest, damping)."""
    springs = []
    for i, item in enumerate(r.items(data, "spring")):
        key = f"spring[{i}]"
        r.keys(item, ("coordinate", "stiffness", "rest", "damping"), key)
        if not isinstance(item.get("coordinate"), str):
            r.fail(f"{key}.coordinate", "must name a coordinate")
        springs.append(Spring(item["coordinate"],
                              r.number(item.get("stiffness", 0.0), f"{key}.stiffness", nonnegative=True,
                                       quantity="damping"),
                              r.number(item.get("rest", 0.0), f"{key}.rest", quantity="state"),
                              r.number(item.get("damping", 0.0), f"{key}.damping", nonnegative=True,
                                       quantity="damping")))
    return tuple(springs)


def _initial(r: SceneReader, data: dict) -> tuple[dict, dict]:
    """``[initial]``: ``q`` and ``qd`` by coordinate name (the others start at zero)."""
    q0, qd0 = {}, {}
    if "initial" in data:
        r.keys(data["initial"], ("q", "qd"), "initial")
        for target, key in ((q0, "q"), (qd0, "qd")):
            table = data["initial"].get(key, {})
            r.keys(table, tuple(table) if isinstance(table, dict) else (), f"initial.{key}")
            for coord, v in table.items():
                target[coord] = r.number(v, f"initial.{key}.{coord}", quantity="state")
    return q0, qd0


def _run(r: SceneReader, data: dict) -> RunSettings:
    """``[run]``: length, method, tolerances or step, samples, re-charting."""
    run = RunSettings()
    if "run" not in data:
        return run
    t = data["run"]
    r.keys(t, _RUN, "run")
    samples = t.get("samples", run.samples)
    if isinstance(samples, float) and samples.is_integer():
        samples = int(samples)
    if not isinstance(samples, int) or isinstance(samples, bool):
        r.fail("run.samples", f"must be a whole number in [1, {MAX_SAMPLES}], got {samples!r}")
    run = RunSettings(t_end=t.get("t_end", run.t_end), method=r.choice(t.get("method", run.method), "run.method", METHODS),
                      rtol=t.get("rtol", run.rtol), atol=t.get("atol", run.atol), dt=t.get("dt"), samples=samples,
                      recharting=t.get("recharting", True))
    return check_run(run, r.where, prefix="run.")


def _record(r: SceneReader, data: dict) -> tuple:
    """``[record]``: link poses to keep along the run."""
    if "record" not in data:
        return ()
    r.keys(data["record"], ("link_poses",), "record")
    return r.strings(data["record"].get("link_poses", []), "record.link_poses")


def _robot_path(r: SceneReader, t: dict, directory) -> Path:
    given = [k for k in ("urdf", "mjcf", "shipped", "example_robot_data") if k in t]
    if len(given) != 1:
        r.fail("robot", f"name the robot exactly one way: urdf = 'path', mjcf = 'path.xml', shipped = 'name' or "
                        f"example_robot_data = 'path inside its robots/ folder'; got {given or 'none'}")
    key = given[0]
    value = t[key]
    if not isinstance(value, str):
        r.fail(f"robot.{key}", f"must be a string, got {value!r}")
    if key in ("urdf", "mjcf"):
        p = Path(value)
        p = p if p.is_absolute() else (directory or Path.cwd()) / p
    elif key == "shipped":
        # the scene's own folder (shipped scenes live next to the robots), then the project's robots/
        # (checkout or editable install), then ./robots
        folders = [f for f in (directory, shipped_robots_dir(), Path.cwd() / "robots") if f is not None and f.is_dir()]
        found = [f / f"{value}.urdf" for f in folders if (f / f"{value}.urdf").is_file()]
        if not found:
            names = sorted({x.stem for f in folders for x in f.glob("*.urdf")})
            r.fail("robot.shipped", f"no shipped robot {value!r}{did_you_mean(value, names)}; shipped robots are {names}")
        p = found[0]
    else:
        root = example_robot_data_dir()
        if root is None:
            r.fail("robot.example_robot_data", "the example-robot-data package is not installed (pip install example-robot-data)")
        p = root / value
    if not p.is_file():
        r.fail(f"robot.{key}", f"file {p} does not exist")
    return p

"""Scenes: a TOML file that names a robot, the effects that act on it, its initial state and the run.

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

import dataclasses
import difflib
import math
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..dynamics.transforms import PARAMETERS, BaseState
from ..errors import SceneError
from ..locations import example_robot_data_dir, shipped_robots_dir
from ..ranges import MAX_SAMPLES, MAX_STEPS, METHODS, MIN_ATOL, Q0_CHOICES, MIN_T_END, RANGES, RTOL_FLOOR
from .contact import parse_contacts
from .actuators import ActuatorSpec, hold_actuators, parse_actuators
from .constraints import constraint_options, parse_constraints
from .expect import ExpectedStop, parse_expect
from .excitation import DAMPER_TORQUE_TEXT, coordinate_ranges, damper_torques, excited_state
from .functions import Constant, SceneValueError, TimeFunction, VectorFunction, parse_function, vector_function

__all__ = ["Scene", "AppliedLoad", "Spring", "SpringSet", "RunSettings", "load_scene", "shipped_robots_dir",
           "robot_stem", "robot_label", "default_scene", "default_scene_name", "DEFAULT_SCENE_NAME", "Q0_CHOICES"]

#: Name of the scene :func:`default_scene` makes (reports go to ``reports/<robot>/default/``).
DEFAULT_SCENE_NAME = "default"
#: The default scene's initial states: ``excite`` (every coordinate moving, E65; the default), ``random``
#: (random q0, at rest), ``rest`` (q = 0 or qpos0, at rest; ``zero`` is its old name).

_TOP = ("description", "chaotic", "robot", "gravity", "base", "force", "moment", "torque", "spring",
        "dampers", "springs", "gravcomp", "initial", "run", "record", "actuator", "computed_torque",
        "constraint", "constraints",   # issue 36: [[constraint]], [constraints] from_file
        "contact", "expect")       # issue 37; issue 42: [expect] a hard case's stop (urdf2links.scenes.expect)
_ROBOT = ("urdf", "mjcf", "shipped", "example_robot_data", "floating_base", "inertia", "mimic", "package_dirs",
          "strict", "xacro_args")
#: Joint types whose damping (URDF or MJCF) becomes a damper on their one coordinate.
_DAMPED_TYPES = ("revolute", "continuous", "prismatic", "hinge", "slide")


def robot_label(scene: "Scene", model=None) -> str:
    """The name reports and outputs of ``scene`` go by: the robot's own name (``<robot name>`` of the
    URDF, or the model's) when it is a plain name, else the file's stem (:func:`robot_stem`); so
    pybullet's ``kuka_iiwa/model.urdf`` reports as ``lbr_iiwa``, not ``model``."""
    name = (getattr(model, "name", "") or "").strip()
    return name if re.fullmatch(r"[A-Za-z0-9][\w.+-]{0,80}", name) else robot_stem(scene.robot)


def robot_stem(path) -> str:
    """The robot file's name without ``.xacro`` and ``.urdf`` (``robot.urdf.xacro`` -> ``robot``): the
    ``<robot>`` part of a report's key."""
    name = Path(path).name
    for suffix in (".xacro", ".urdf", ".xml", ".mjcf"):
        name = name.removesuffix(suffix)
    return name
_RUN = ("t_end", "method", "rtol", "atol", "dt", "samples", "recharting")


@dataclass(frozen=True)
class AppliedLoad:
    """A force (``kind="force"``, at ``point`` (3,) in the link frame) or moment on URDF link ``link``;
    ``value`` gives its three components in ``frame`` axes (``"link"`` or ``"world"``) at time t."""

    kind: str
    link: str
    frame: str
    value: VectorFunction
    point: np.ndarray = field(default_factory=lambda: np.zeros(3))


@dataclass(frozen=True)
class Spring:
    """Joint spring and damper on ``coordinate``: force ``-stiffness (q - rest) - damping qd``,
    i.e. V += 0.5 k (q - rest)^2 and the dissipation function D = 0.5 c qd^2 of docs/equations.md (E16)."""

    coordinate: str
    stiffness: float = 0.0
    rest: float = 0.0
    damping: float = 0.0


@dataclass(frozen=True)
class SpringSet:
    """The springs and dampers that act in a scene on a model (:meth:`Scene.springs_for`): the
    scene's ``[[spring]]`` blocks merged with the URDF's damping when ``[dampers] from_urdf``;
    ``notes`` says what was added, overridden or left out, and that Coulomb friction is not modelled."""

    springs: tuple[Spring, ...]
    notes: tuple[str, ...] = ()


@dataclass(frozen=True)
class RunSettings:
    t_end: float = 5.0
    method: str = "auto"
    rtol: float = 1e-10
    atol: float = 1e-12
    dt: float | None = None
    samples: int = 501
    recharting: bool = True


@dataclass(frozen=True)
class Scene:
    """A parsed, validated scene. ``base`` is None or six functions (x, y, z, phi_x, phi_y, phi_z)."""

    name: str
    path: Path | None
    robot: Path
    load_options: dict
    description: str = ""
    chaotic: bool = False
    gravity: np.ndarray | None = None
    base: tuple[TimeFunction, ...] | None = None
    loads: tuple[AppliedLoad, ...] = ()
    torques: tuple[tuple[str, TimeFunction], ...] = ()
    springs: tuple[Spring, ...] = ()
    q0: dict = field(default_factory=dict)
    qd0: dict = field(default_factory=dict)
    run: RunSettings = RunSettings()
    link_poses: tuple[str, ...] = ()
    urdf_damping: bool = False
    file_springs: bool = False
    gravcomp: bool = False
    notes: tuple[str, ...] = ()
    """What was changed from the scene file (loading options given on the command line, ...)."""
    actuators: tuple[ActuatorSpec, ...] = ()
    """``[[actuator]]`` blocks (and ``--hold``'s servos): :mod:`urdf2links.scenes.actuators`."""
    computed_torque: tuple[tuple[str, TimeFunction], ...] = ()
    """``[[computed_torque]]``: ``(coordinate, reference q_r(t))``."""
    gravcomp_factor: float | None = None
    gravcomp_bodies: tuple[tuple[str, float], ...] = ()
    constraints: tuple = ()
    """``[[constraint]]`` blocks (:mod:`urdf2links.scenes.constraints`; issue 36)."""
    file_constraints: bool = False    # [constraints] from_file: an MJCF file's own equalities and fixed tendons act
    mimic_constraints: bool = False
    """``[constraints] mimic``: a URDF's ``<mimic>`` joints as exact joint constraints (E70)."""
    contacts: tuple = ()          # [[contact]] blocks (issue 37): urdf2links.scenes.contact.ContactSpec
    expected_stop: ExpectedStop | None = None     # [expect]: a hard case that stops by design (issue 42)

    def model(self):
        """Load the scene's robot with its options (a :class:`~urdf2links.dynamics.model.Model`)."""
        from ..parsers.robot_file import load_robot

        model = load_robot(self.robot, **self.load_options)
        self.check_names(model)
        return model

    def check_names(self, model) -> None:
        """Every link and coordinate the scene names exists in ``model`` (SceneError otherwise)."""
        where = self.path or "<scene>"
        links = set(model.info.get("frame_of", {}) or model.link_names)
        for load in self.loads:
            if load.link not in links:
                raise SceneError(f"{where}: [[{load.kind}]] link = {load.link!r} is not a link of robot "
                                 f"{model.name!r}{_hint(load.link, links)}; links are {sorted(links)}")
        for link in self.link_poses:
            if link not in links:
                raise SceneError(f"{where}: [record] link_poses names {link!r}, not a link of {model.name!r}"
                                 f"{_hint(link, links)}")
        for body, _ in self.gravcomp_bodies:
            if body not in links:
                raise SceneError(f"{where}: [gravcomp] bodies names {body!r}, not a link (body) of {model.name!r}"
                                 f"{_hint(body, links)}")
        names = model.coordinate_names
        for what, coord in ([("torque", c) for c, _ in self.torques] + [("spring", s.coordinate) for s in self.springs]
                            + [("initial.q", c) for c in self.q0] + [("initial.qd", c) for c in self.qd0]
                            + [("actuator", a.coordinate) for a in self.actuators if a.coordinate is not None]
                            + [("computed_torque", c) for c, _ in self.computed_torque]):
            if coord not in names:
                raise SceneError(f"{where}: [{what}] coordinate {coord!r} is not a coordinate of robot {model.name!r}"
                                 f"{_hint(coord, names)}; coordinates are {list(names)}")

    def base_state(self, t) -> BaseState | None:
        """Pose, rate and acceleration of {A} at ``t`` from ``[base]``; None for a fixed base."""
        if self.base is None:
            return None
        f = self.base
        return BaseState(np.array([g(t) for g in f]), np.array([g.derivative(t) for g in f]),
                         np.array([g.second_derivative(t) for g in f]))

    def springs_for(self, model) -> SpringSet:
        """The springs and dampers acting on ``model``: ``[[spring]]`` blocks, plus with ``[dampers]
        from_urdf = true`` a damper ``c = <dynamics damping>`` on the coordinate of every revolute,
        continuous or prismatic joint (the URDF joint position), unless a ``[[spring]]`` gives that
        coordinate a damping of its own. Damping of floating, planar or spherical joints, of coupled
        mimic followers and negative damping are left out, with a note."""
        joints = model.info.get("joints", [])
        friction = [j["name"] for j in joints if j.get("friction")]
        notes = [f"joint friction (URDF <dynamics friction>, MJCF frictionloss: Coulomb friction) is not modelled, "
                 f"on either engine: joints {', '.join(friction)}"] if friction else []
        springs = self.springs
        if self.file_springs:
            springs, more = _file_springs(model, springs)
            notes += more
        else:
            stiff = [j["name"] for j in joints if j.get("stiffness")]
            if stiff:
                notes.append(f"joint stiffness of the file not applied (the scene does not ask: [springs] from_file = "
                             f"true): joints {', '.join(stiff)}")
        if not self.urdf_damping:
            damped = [j["name"] for j in joints if j.get("damping")]
            if damped:
                notes.append(f"joint damping of the file not applied (the scene does not ask: [dampers] from_urdf = "
                             f"true): joints {', '.join(damped)}")
            return SpringSet(tuple(springs), tuple(notes))
        own = {s.coordinate: s for s in springs}
        added, skipped = {}, []
        for j in joints:
            c = j.get("damping")
            if not c:
                continue
            coord = j["coordinates"][0] if len(j["coordinates"]) == 1 else None
            if j["type"] not in _DAMPED_TYPES:
                skipped.append(f"{j['name']} ({j['type']} joint: no single joint axis to damp)")
            elif coord is None or coord not in model.coordinate_names:
                skipped.append(f"{j['name']} (coupled to the joint it mimics)")
            elif c < 0:
                skipped.append(f"{j['name']} (negative damping {c:g})")
            elif own.get(coord) is not None and own[coord].damping > 0:
                skipped.append(f"{j['name']} (the scene's [[spring]] damping {own[coord].damping:g} is used instead)")
            else:
                added[coord] = c
        springs = [Spring(s.coordinate, s.stiffness, s.rest, added.get(s.coordinate, s.damping)) for s in springs]
        springs += [Spring(coord, damping=c) for coord, c in added.items() if coord not in own]
        if added:
            notes.append("joint damping of the file applied as dampers ([dampers] from_urdf = true): "
                         + ", ".join(f"{coord} {c:g}" for coord, c in added.items()))
        if skipped:
            notes.append(f"joint damping of the file not applied: {'; '.join(skipped)}")
        return SpringSet(tuple(springs), tuple(notes))

    def gravcomp_table(self, model) -> dict:
        """``{body: factor}`` of MuJoCo's body gravcomp acting in this scene: the MJCF file's own with
        ``[gravcomp] from_file``, then ``factor`` on every body with mass, then ``bodies`` (zeros dropped).
        A body is a URDF link or an MJCF body (``model.info['body_mass_com']``)."""
        table = dict(model.info.get("gravcomp") or {}) if self.gravcomp else {}
        if self.gravcomp_factor is not None:
            masses = model.info.get("body_mass_com", {})
            table.update({b: self.gravcomp_factor for b, (m, _) in masses.items() if m > 0.0})
        table.update(dict(self.gravcomp_bodies))
        return {b: f for b, f in table.items() if f != 0.0}

    def gravcomp_loads(self, model) -> tuple[tuple[AppliedLoad, ...], tuple[str, ...]]:
        """MuJoCo's gravity compensation (``[gravcomp]``, :meth:`gravcomp_table`): a constant world-frame
        force ``-gravcomp m g`` at the COM of every body that has one (MuJoCo's ``qfrc_gravcomp``), for
        the scene's gravity; and notes."""
        table = self.gravcomp_table(model)
        own = model.info.get("gravcomp") or {}
        if not table:
            return (), ((f"gravcomp of bodies {', '.join(own)} not applied (the scene does not ask: [gravcomp] "
                         "from_file = true)",) if own and not self.gravcomp else ())
        if self.gravity is None:
            return (), ("gravcomp not applied: the scene has no gravity to compensate",)
        masses = model.info.get("body_mass_com", {})
        loads = []
        for body, frac in table.items():
            m, com = masses[body]
            f = -frac * m * np.asarray(self.gravity, float)
            loads.append(AppliedLoad("force", body, "world", VectorFunction(tuple(Constant(float(x)) for x in f)),
                                     np.asarray(com, float)))
        how = "[gravcomp] from_file = true" if self.gravcomp and table == own else "[gravcomp]"
        return tuple(loads), (f"gravcomp applied ({how}): a force -gravcomp m g at the COM of "
                              + ", ".join(f"{b} ({v:g})" for b, v in table.items()),)

    def initial_state(self, model) -> tuple[np.ndarray, np.ndarray]:
        """``(q0, qd0)``: the scene's ``[initial]``; unnamed coordinates on their ``[[computed_torque]]``
        reference (its value and rate at t = 0), else at rest and at 0, or for an MJCF robot at MuJoCo's
        default ``qpos0`` (``model.info['q0']``)."""
        names = model.coordinate_names
        base = model.info.get("q0")
        base = np.zeros(len(names)) if base is None else np.asarray(base, float)
        ref = dict(self.computed_torque)      # a computed torque's coordinate starts on its reference
        q = np.array([float(self.q0.get(n, ref[n](0.0) if n in ref else base[i])) for i, n in enumerate(names)])
        qd = np.array([float(self.qd0.get(n, ref[n].derivative(0.0) if n in ref else 0.0)) for n in names])
        return q, qd


def _file_springs(model, springs) -> tuple[list, list[str]]:
    """The scene's springs plus, with ``[springs] from_file``, every hinge's and slide's ``stiffness`` at
    its ``springref`` (MJCF); a ``[[spring]]`` of the scene on the same coordinate takes precedence."""
    own = {s.coordinate: s for s in springs}
    out, added, skipped = list(springs), [], []
    for j in model.info.get("joints", []):
        k = j.get("stiffness")
        if not k:
            continue
        if j["type"] not in ("hinge", "slide") or len(j["coordinates"]) != 1:
            skipped.append(f"{j['name']} ({j['type']} joint)")
            continue
        coord = j["coordinates"][0]
        if coord in own and own[coord].stiffness > 0:
            skipped.append(f"{j['name']} (the scene's [[spring]] stiffness {own[coord].stiffness:g} is used instead)")
            continue
        rest = float(j.get("springref") or 0.0)
        if coord in own:
            out = [Spring(s.coordinate, k, rest, s.damping) if s.coordinate == coord else s for s in out]
        else:
            out.append(Spring(coord, stiffness=k, rest=rest))
        added.append(f"{coord} k {k:g} rest {rest:g}")
    notes = ["joint stiffness of the file applied as springs ([springs] from_file = true): " + ", ".join(added)] if added else []
    if skipped:
        notes.append(f"joint stiffness of the file not applied: {'; '.join(skipped)}")
    return out, notes


def _hint(name, choices) -> str:
    close = difflib.get_close_matches(str(name), [str(c) for c in choices], n=1)
    return f" (did you mean {close[0]!r}?)" if close else ""


class _Reader:
    def __init__(self, where: str):
        self.where = where

    def fail(self, key: str, problem: str):
        raise SceneError(f"{self.where}: {key}: {problem}")

    def keys(self, table, allowed, key):
        if not isinstance(table, dict):
            self.fail(key, f"must be a table, got {type(table).__name__} {table!r}")
        for k in table:
            if k not in allowed:
                self.fail(f"{key}.{k}" if key else k, f"unknown key{_hint(k, allowed)}; valid keys are {list(allowed)}")

    def number(self, value, key, *, positive=False, nonnegative=False, quantity: str | None = None,
               low: float | None = None, high: float | None = None):
        """A finite number (not a bool), checked where it is read: ``positive``/``nonnegative``, within
        the physical range of ``quantity`` (:data:`urdf2links.ranges.RANGES`) and within ``[low, high]``;
        the SceneError names the key, the value and the valid range."""
        bound = RANGES[quantity][0] if quantity else math.inf
        lo = 0.0 if (positive or nonnegative) else -bound
        lo = lo if low is None else max(lo, low)
        hi = bound if high is None else min(bound, high)
        unit = f" {RANGES[quantity][1]}" if quantity and RANGES[quantity][1] else ""
        valid = (f"{'(' if positive and low is None else '['}{lo:g}, {hi:g}]{unit}")
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            self.fail(key, f"must be a finite number in {valid}, got {value!r}")
        if lo == 0 and (value < 0 or (positive and value == 0)):
            self.fail(key, f"must {'be positive' if positive else 'not be negative'}, got {value!r}: valid range {valid}")
        if value < lo or value > hi:
            self.fail(key, f"{value!r} is outside the valid range {valid}")
        return float(value)

    def vector(self, value, key, *, quantity: str | None = None):
        if not isinstance(value, list) or len(value) != 3:
            self.fail(key, f"must be a list of 3 numbers, got {value!r}")
        return np.array([self.number(v, f"{key}[{i}]", quantity=quantity) for i, v in enumerate(value)])

    def items(self, data, kind: str) -> list:
        """The ``[[kind]]`` blocks of ``data`` (an array of tables)."""
        items = data.get(kind, [])
        if not isinstance(items, list):
            self.fail(f"[[{kind}]]", f"must be an array of tables ([[{kind}]] blocks), got {items!r}")
        return items

    def strings(self, value, key) -> tuple:
        if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
            self.fail(key, f"must be a list of strings, got {value!r}")
        return tuple(value)

    def choice(self, value, key, choices):
        if value not in choices:
            self.fail(key, f"{value!r} is not one of {list(choices)}{_hint(value, choices)}")
        return value

    def function(self, spec, key) -> TimeFunction:
        try:
            return parse_function(spec, where=f"{self.where}: {key}")
        except SceneValueError as err:
            raise SceneError(str(err)) from None

    def vector_function(self, spec, key) -> VectorFunction:
        try:
            return vector_function(spec, where=f"{self.where}: {key}", length=3)
        except SceneValueError as err:
            raise SceneError(str(err)) from None


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
                  strict: bool = False, model=None, hold: float | None = None) -> Scene:
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
    """
    where = f"default scene of {robot}"
    r = _Reader(where)
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
    name = default_scene_name(floating=floating, q0=q0, seed=seed, inertia=inertia, mimic=mimic, hold=hold)
    scene = _default_scene(robot, mjcf, model, options, name, state + held_text, q_init, qd_init, run, held, floating)
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
                       mimic: str = "independent", hold: float | None = None) -> str:
    """:data:`DEFAULT_SCENE_NAME`, with what differs from the plain default scene appended
    (``default-floating-random-seed3-repair``, ``default-rest``, ``default-seed2``), so that reports of
    one robot in other settings do not replace each other."""
    q0 = "rest" if q0 == "zero" else q0
    parts = [DEFAULT_SCENE_NAME] + (["floating"] if floating else [])
    parts += {"random": [f"random-seed{seed}"], "rest": ["rest"]}.get(q0, [f"seed{seed}"] if seed else [])
    parts += [inertia] if inertia != "audit" else []
    parts += [mimic] if mimic != "independent" else []
    parts += [] if hold is None else ["hold" if hold == 2.0 else f"hold{hold:g}hz"]
    return "-".join(parts)


def load_scene(path) -> Scene:
    """Read and validate a scene file (names of links and coordinates are checked by :meth:`Scene.model`)."""
    path = Path(path)
    where = str(path)
    try:
        data = tomllib.loads(path.read_text())
    except FileNotFoundError:
        raise SceneError(f"scene file {where} does not exist") from None
    except tomllib.TOMLDecodeError as err:
        raise SceneError(f"{where}: not valid TOML: {err}") from None
    return scene_from_dict(data, where=where, directory=path.parent, name=path.stem, path=path)


def scene_from_dict(data: dict, *, where: str = "<scene>", directory: Path | None = None, name: str = "scene",
                    path: Path | None = None) -> Scene:
    """A :class:`Scene` from the parsed TOML ``data``; ``where`` names the file in errors,
    ``directory`` is where relative robot paths start."""
    r = _Reader(where)
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


def _gravcomp(r: _Reader, data: dict) -> tuple[bool, float | None, tuple]:
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


def _computed_torque(r: _Reader, data: dict) -> tuple:
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


def _dampers(r: _Reader, data: dict) -> bool:
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


def _from_file(r: _Reader, data: dict, table: str) -> bool:
    """``[springs] from_file`` / ``[gravcomp] from_file``: whether the MJCF file's joint stiffness (at
    springref) or its bodies' gravcomp act."""
    if table not in data:
        return False
    r.keys(data[table], ("from_file",), table)
    value = data[table].get("from_file", False)
    if not isinstance(value, bool):
        r.fail(f"{table}.from_file", f"must be true or false, got {value!r}")
    return value


def _robot_options(r: _Reader, robot_t: dict, directory) -> dict:
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


def _gravity(r: _Reader, data: dict):
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


def _base(r: _Reader, data: dict):
    """``[base]``: six functions of time (x, y, z, phi_x, phi_y, phi_z of {A}), or None (fixed)."""
    if "base" not in data:
        return None
    r.keys(data["base"], PARAMETERS, "base")
    return tuple(r.function(data["base"][p], f"base.{p}") if p in data["base"] else Constant(0.0)
                 for p in PARAMETERS)


def _loads(r: _Reader, data: dict) -> tuple:
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


def _torques(r: _Reader, data: dict) -> tuple:
    """``[[torque]]`` blocks: ``(coordinate, function of time)``."""
    torques = []
    for i, item in enumerate(r.items(data, "torque")):
        r.keys(item, ("coordinate", "value"), f"torque[{i}]")
        if not isinstance(item.get("coordinate"), str) or "value" not in item:
            r.fail(f"torque[{i}]", "needs coordinate = 'name' and value = a function of time")
        torques.append((item["coordinate"], r.function(item["value"], f"torque[{i}].value")))
    return tuple(torques)


def _springs(r: _Reader, data: dict) -> tuple:
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


def _initial(r: _Reader, data: dict) -> tuple[dict, dict]:
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


def _run(r: _Reader, data: dict) -> RunSettings:
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


def check_run(run: RunSettings, where: str, *, prefix: str = "run.") -> RunSettings:
    """``run`` with every setting checked where it is given (a scene's ``[run]``, or the overrides of
    :func:`urdf2links.integration.simulate.simulate`): a SceneError names ``where``, the key, the value and its
    valid range. ``t_end`` in [1e-9, 1e6] s (:data:`~urdf2links.ranges.MIN_T_END`); ``rtol`` in [100 eps, 1) (float64 delivers no more);
    ``atol`` in [1e-30, 1e3] (:data:`~urdf2links.ranges.MIN_ATOL`); ``dt`` in (0, 1e6] s with at most :data:`~urdf2links.ranges.MAX_STEPS`
    steps; ``samples`` in [1, :data:`~urdf2links.ranges.MAX_SAMPLES`]."""
    r = _Reader(where)
    t_end = r.number(run.t_end, f"{prefix}t_end", positive=True, quantity="time", low=MIN_T_END)
    rtol = r.number(run.rtol, f"{prefix}rtol", low=RTOL_FLOOR, high=0.999)
    atol = r.number(run.atol, f"{prefix}atol", positive=True, low=MIN_ATOL, high=1e3)
    dt = None
    if run.dt is not None:
        dt = r.number(run.dt, f"{prefix}dt", positive=True, quantity="time")
        if t_end / dt > MAX_STEPS:
            r.fail(f"{prefix}dt", f"{run.dt!r} makes {t_end / dt:.3g} steps over t_end = {t_end:g} s, more than the "
                                  f"{MAX_STEPS:g} a run may take: valid range [{t_end / MAX_STEPS:g}, 1e+06] s")
    samples = run.samples
    if isinstance(samples, bool) or not isinstance(samples, (int, np.integer)) or not 1 <= samples <= MAX_SAMPLES:
        r.fail(f"{prefix}samples", f"must be a whole number in [1, {MAX_SAMPLES}], got {samples!r}")
    if not isinstance(run.recharting, bool):
        r.fail(f"{prefix}recharting", f"must be true or false, got {run.recharting!r}")
    method = r.choice(run.method, f"{prefix}method", METHODS)
    if method in ("RK4", "midpoint") and dt is None:
        r.fail(f"{prefix}dt", f"method {method!r} takes a fixed step: give dt (seconds)")
    return RunSettings(t_end=t_end, method=method, rtol=rtol, atol=atol, dt=dt, samples=int(samples),
                       recharting=run.recharting)


def _record(r: _Reader, data: dict) -> tuple:
    """``[record]``: link poses to keep along the run."""
    if "record" not in data:
        return ()
    r.keys(data["record"], ("link_poses",), "record")
    return r.strings(data["record"].get("link_poses", []), "record.link_poses")


def _robot_path(r: _Reader, t: dict, directory) -> Path:
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
            r.fail("robot.shipped", f"no shipped robot {value!r}{_hint(value, names)}; shipped robots are {names}")
        p = found[0]
    else:
        root = example_robot_data_dir()
        if root is None:
            r.fail("robot.example_robot_data", "the example-robot-data package is not installed (pip install example-robot-data)")
        p = root / value
    if not p.is_file():
        r.fail(f"robot.{key}", f"file {p} does not exist")
    return p

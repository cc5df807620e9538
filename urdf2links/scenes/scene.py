"""A scene's data: the robot (its file and loading options), the effects that act on it, its initial state and
the run, as frozen dataclasses (:class:`Scene`, :class:`AppliedLoad`, :class:`Spring`, :class:`RunSettings`), and what a
scene makes of its robot's model (its springs and dampers, gravcomp loads, initial state; names checked).

A scene is read from its TOML form by :func:`urdf2links.scenes.scene_read.load_scene` (the schema is there), its
values checked where they are read (:mod:`urdf2links.scenes.scene_checks`); a robot file's default scene is made by
:func:`urdf2links.scenes.default_scenes.default_scene`.
"""

from __future__ import annotations

import difflib
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..dynamics.transforms import BaseState
from ..errors import SceneError
from .actuators import ActuatorSpec
from .expect import ExpectedStop
from .functions import Constant, TimeFunction, VectorFunction

__all__ = ["Scene", "AppliedLoad", "Spring", "SpringSet", "RunSettings", "robot_stem", "robot_label", "did_you_mean"]

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
    file_constraints: bool = True     # [constraints] from_file: an MJCF file's own equalities and fixed tendons act
                                      # (issue 45: on by default, as in MuJoCo; --open-loops or from_file = false drop them)
    mimic_constraints: bool = True
    change_point: str = "continue"    # [constraints] change_point (issue 45): "continue" drops the row there, "stop"
    """``[constraints] mimic``: a URDF's ``<mimic>`` joints (loaded ``mimic = "independent"``) as exact joint
    constraints (E70); on by default since issue 45, as MuJoCo's URDF import makes each a joint equality."""
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
                                 f"{model.name!r}{did_you_mean(load.link, links)}; links are {sorted(links)}")
        for link in self.link_poses:
            if link not in links:
                raise SceneError(f"{where}: [record] link_poses names {link!r}, not a link of {model.name!r}"
                                 f"{did_you_mean(link, links)}")
        for body, _ in self.gravcomp_bodies:
            if body not in links:
                raise SceneError(f"{where}: [gravcomp] bodies names {body!r}, not a link (body) of {model.name!r}"
                                 f"{did_you_mean(body, links)}")
        names = model.coordinate_names
        for what, coord in ([("torque", c) for c, _ in self.torques] + [("spring", s.coordinate) for s in self.springs]
                            + [("initial.q", c) for c in self.q0] + [("initial.qd", c) for c in self.qd0]
                            + [("actuator", a.coordinate) for a in self.actuators if a.coordinate is not None]
                            + [("computed_torque", c) for c, _ in self.computed_torque]):
            if coord not in names:
                raise SceneError(f"{where}: [{what}] coordinate {coord!r} is not a coordinate of robot {model.name!r}"
                                 f"{did_you_mean(coord, names)}; coordinates are {list(names)}")

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


def did_you_mean(name, choices) -> str:
    """`` (did you mean 'x'?)`` naming the choice closest to ``name``, or nothing: for a scene's errors."""
    close = difflib.get_close_matches(str(name), [str(c) for c in choices], n=1)
    return f" (did you mean {close[0]!r}?)" if close else ""

"""A robot file as its bodies and joints, in one form for URDF and MJCF: what a comparison of two descriptions reads.

The tree of links (:mod:`urdf2links.dynamics.tree`) folds fixed joints and aligns each joint's axis
with a link axis, so two descriptions of one robot give trees whose links sit in different frames.
Compared part by part, the descriptions need their own terms back: each body (a URDF link, an MJCF
body) with its frame relative to its parent's at the home pose, its own inertia, and the joints that
move it. :func:`robot_parts` reads them from the file (a URDF through :func:`~urdf2links.parsers.urdf.parse_urdf`,
an MJCF file through MuJoCo's compiler, :func:`~urdf2links.parsers.mjcf.compile_mjcf`), and
:func:`parts_model` builds the tree of links back from them (docs/equations.md (E51)), exactly as
the two importers do, so that a comparison can change one part and recompute ``A`` and ``G``.

One form for both (E51): a body ``b`` with parent ``p`` sits at ``W_b = W_p P_b J_1(q_1) ... J_k(q_k)``
(``P_b`` its ``pose`` (4, 4) at home), each joint ``J`` acting in the body frame as moved by the joints
before it:

- hinge about the unit ``axis`` ``u`` through ``anchor`` ``a``: ``Trans(a) Rot(u, q - ref) Trans(-a)``;
  a URDF revolute or continuous joint is a hinge with ``a = 0`` and ``ref = 0`` (its child link frame is
  the joint frame), an MJCF hinge has MuJoCo's ``pos`` and ``ref`` (its coordinate is MuJoCo's qpos);
- slide along ``u``: ``Trans(u (q - ref))``;
- ball: ``Trans(a) R(phi) Trans(-a)`` (three ZYX angles, E3);
- free (a top-level body): the body's pose is the six coordinates themselves (``home`` holds the
  coordinates of its pose at home); a URDF loaded with ``floating_base`` has one on its root link;
- planar (URDF only): ``x``, ``y`` in the plane normal to ``u`` and ``phi_z`` about it.

A body without joints is welded to its parent (a URDF fixed joint, named in ``fixed_joint``; an MJCF
body without joints). ``H`` is the body's own pseudo-inertia (E10) in its frame.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from ..dynamics.inertia import pseudo_inertia
from ..dynamics.model import DEFAULT_GRAVITY, Model
from ..dynamics.rotations import axis_alignment, homogeneous, matrix_to_xyz_angles, rpy_to_matrix
from ..dynamics.transforms import PARAMETERS
from ..dynamics.tree import LinkSpec, build_tree
from .mjcf import compile_mjcf, is_mjcf_path
from .mjcf_state import quat_to_matrix
from .urdf import parse_urdf

__all__ = ["JointPart", "BodyPart", "RobotParts", "robot_parts", "parts_model", "PartsModel", "home_poses",
           "JOINT_KINDS"]

#: The joint kinds of :class:`JointPart`, with their coordinates' slots (E3).
JOINT_KINDS = {"hinge": ("phi_z",), "slide": ("z",), "ball": ("phi_x", "phi_y", "phi_z"), "free": PARAMETERS,
               "planar": ("x", "y", "phi_z")}
_URDF_KINDS = {"revolute": "hinge", "continuous": "hinge", "prismatic": "slide", "spherical": "ball",
               "floating": "free", "planar": "planar"}
_MJ_KINDS = {0: "free", 1: "ball", 2: "slide", 3: "hinge"}
_I4 = np.eye(4)


@dataclass(frozen=True)
class JointPart:
    """One joint as the file says it (module doc): ``kind`` (:data:`JOINT_KINDS`), unit ``axis`` (3,)
    and ``anchor`` (3,) in the body frame, ``home`` the coordinates' values at the home pose (MJCF
    ``ref``; a free joint's pose), limits (None: unlimited), ``damping``, ``stiffness`` at
    ``springref``, ``armature`` (E49), ``friction``; ``source_type`` the file's own word for it; ``effort`` and
    ``velocity`` the largest joint force and speed the file states (URDF ``<limit>``; MJCF: module doc of
    :func:`_actuator_limits`), None when it states none; ``effort_source`` where an MJCF's comes from, in words."""

    name: str
    kind: str
    axis: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, 1.0]))
    anchor: np.ndarray = field(default_factory=lambda: np.zeros(3))
    home: tuple[float, ...] = (0.0,)
    lower: float | None = None
    upper: float | None = None
    damping: float = 0.0
    stiffness: float = 0.0
    springref: float = 0.0
    armature: float = 0.0
    friction: float = 0.0
    source_type: str = ""
    written_axis: np.ndarray | None = None
    effort: float | None = None
    velocity: float | None = None
    effort_source: str = ""

    @property
    def built_axis(self) -> np.ndarray:
        """The axis the tree is built with: as the file wrote it (a URDF axis need not be unit: the importer
        aligns the written one, E8), unless ``axis`` was changed since."""
        return np.asarray(self.axis if self.written_axis is None else self.written_axis, float)

    @property
    def coordinates(self) -> tuple[str, ...]:
        """The names of its coordinates, as the importers name them."""
        slots = JOINT_KINDS[self.kind]
        return (self.name,) if len(slots) == 1 else tuple(f"{self.name}.{s}" for s in slots)

    @property
    def ref(self) -> float:
        """The coordinate at home of a one-coordinate joint (0 for the others)."""
        return float(self.home[0]) if len(self.home) == 1 else 0.0


@dataclass(frozen=True)
class BodyPart:
    """One body (URDF link, MJCF body): ``parent`` body name (None: the world), ``pose`` (4, 4) of its
    frame in the parent's at home, own pseudo-inertia ``H`` (4, 4) in its frame, the ``joints`` that
    move it (empty: welded; ``fixed_joint`` names the URDF fixed joint that welds it)."""

    name: str
    parent: str | None
    pose: np.ndarray
    H: np.ndarray
    joints: tuple[JointPart, ...] = ()
    fixed_joint: str | None = None


@dataclass(frozen=True)
class RobotParts:
    """A description's bodies in tree order (parents first); ``format`` ``"urdf"`` or ``"mjcf"``;
    ``gravity`` (3,) the file's (MJCF ``<option gravity>``; the default for a URDF); ``notes``; ``compiler``:
    the attributes of an MJCF file's top-level ``<compiler>`` (how MuJoCo treats its inertias: ``boundmass``,
    ``balanceinertia``, ...); ``sites``: an MJCF file's sites as ``(name, body, pose (4, 4) in the body's frame)``;
    ``velocity_actuators``: the MJCF file states a joint speed through a velocity actuator somewhere."""

    name: str
    source: str
    format: str
    bodies: tuple[BodyPart, ...]
    gravity: np.ndarray = field(default_factory=lambda: np.array(DEFAULT_GRAVITY))
    notes: tuple[str, ...] = ()
    compiler: dict = field(default_factory=dict)
    sites: tuple = ()
    velocity_actuators: bool = False

    def body(self, name: str) -> BodyPart:
        for b in self.bodies:
            if b.name == name:
                return b
        raise KeyError(f"{self.source}: no body (link) named {name!r}")

    @property
    def joints(self) -> tuple[tuple[JointPart, BodyPart], ...]:
        """Every joint with the body it moves, in tree order."""
        return tuple((j, b) for b in self.bodies for j in b.joints)

    def replaced(self, name: str, **changes) -> "RobotParts":
        """A copy with body ``name``'s fields changed (``pose``, ``H``, ``joints``, ...)."""
        return replace(self, bodies=tuple(replace(b, **changes) if b.name == name else b for b in self.bodies))

    def with_joint(self, name: str, **changes) -> "RobotParts":
        """A copy with joint ``name``'s fields changed (``axis``, ``armature``, ``anchor``, ...; a new ``axis``
        is the one built with)."""
        if "axis" in changes:
            changes.setdefault("written_axis", None)
        bodies = []
        for b in self.bodies:
            if any(j.name == name for j in b.joints):
                b = replace(b, joints=tuple(replace(j, **changes) if j.name == name else j for j in b.joints))
            bodies.append(b)
        return replace(self, bodies=tuple(bodies))


def robot_parts(path, *, floating_base: bool = False, package_dirs=(), strict: bool = False, xacro_args=None,
                **_ignored) -> RobotParts:
    """The bodies and joints of a robot file (``.urdf``, ``.xacro``, or MJCF ``.xml``), module doc.
    ``floating_base`` gives a URDF's root a free joint (an MJCF file says itself how its bodies move)."""
    if is_mjcf_path(path):
        return _mjcf_parts(path)
    return _urdf_parts(path, floating_base=floating_base, package_dirs=package_dirs, strict=strict,
                       xacro_args=xacro_args)


def _urdf_parts(path, *, floating_base, package_dirs, strict, xacro_args) -> RobotParts:
    desc = parse_urdf(path, package_dirs=package_dirs, strict=strict, xacro_args=xacro_args)
    by_child = {j.child: j for j in desc.joints}
    bodies = []
    order = [desc.root] + [j.child for j in desc.joints]
    for name in order:
        link = desc.links[name]
        i = link.inertial
        H = np.zeros((4, 4)) if i is None else pseudo_inertia(i.mass, i.origin.xyz, i.inertia,
                                                              rotation=rpy_to_matrix(i.origin.rpy))
        j = by_child.get(name)
        if j is None:     # the root
            joints = (JointPart(name, "free", home=(0.0,) * 6, source_type="floating base"),) if floating_base else ()
            bodies.append(BodyPart(name, None, _I4.copy(), H, joints))
            continue
        pose = homogeneous(rpy_to_matrix(j.origin.rpy), np.asarray(j.origin.xyz, float))
        if j.type == "fixed":
            bodies.append(BodyPart(name, j.parent, pose, H, (), fixed_joint=j.name))
            continue
        kind = _URDF_KINDS[j.type]
        u = np.asarray(j.axis, float)
        u = np.array([0.0, 0.0, 1.0]) if kind in ("ball", "free") else u / np.linalg.norm(u)
        lo, hi = (j.limit_lower, j.limit_upper) if j.type in ("revolute", "prismatic") else (None, None)
        jp = JointPart(j.name, kind, axis=u, home=(0.0,) * len(JOINT_KINDS[kind]), lower=lo, upper=hi,
                       damping=float(j.damping or 0.0), friction=float(j.friction or 0.0), source_type=j.type,
                       effort=float(j.limit_effort) if j.limit_effort else None,
                       velocity=float(j.limit_velocity) if j.limit_velocity else None,
                       written_axis=None if kind in ("ball", "free") else np.asarray(j.axis, float))
        bodies.append(BodyPart(name, j.parent, pose, H, (jp,)))
    return RobotParts(desc.name, str(desc.source), "urdf", tuple(bodies), notes=tuple(desc.notes))


def _mjcf_parts(path) -> RobotParts:
    import mujoco

    notes: list[str] = []
    m, where = compile_mjcf(str(path), notes)
    sources: dict = {}
    effort, speed = _actuator_limits(m, sources)

    def name(obj, i, fallback):
        return mujoco.mj_id2name(m, getattr(mujoco.mjtObj, obj), i) or fallback

    bodies = []
    for b in range(1, m.nbody):
        parent = int(m.body_parentid[b])
        pose = homogeneous(quat_to_matrix(m.body_quat[b]), np.asarray(m.body_pos[b], float))
        H = pseudo_inertia(float(m.body_mass[b]), m.body_ipos[b], np.diag(m.body_inertia[b]),
                           rotation=quat_to_matrix(m.body_iquat[b]))
        bname = name("mjOBJ_BODY", b, f"body{b}")
        joints = []
        for j in range(int(m.body_jntadr[b]), int(m.body_jntadr[b]) + int(m.body_jntnum[b])):
            kind = _MJ_KINDS[int(m.jnt_type[j])]
            qa, da = int(m.jnt_qposadr[j]), int(m.jnt_dofadr[j])
            if kind in ("hinge", "slide"):
                home = (float(m.qpos0[qa]),)
            elif kind == "ball":
                home = (0.0, 0.0, 0.0)
            else:
                home = tuple(np.r_[m.qpos0[qa:qa + 3], matrix_to_xyz_angles(quat_to_matrix(m.qpos0[qa + 3:qa + 7]))])
            limited = bool(m.jnt_limited[j]) and kind in ("hinge", "slide")
            joints.append(JointPart(
                name("mjOBJ_JOINT", j, f"{bname}:{kind}{j}"), kind, axis=np.array(m.jnt_axis[j], float),
                anchor=np.array(m.jnt_pos[j], float), home=home,
                lower=float(m.jnt_range[j, 0]) if limited else None, upper=float(m.jnt_range[j, 1]) if limited else None,
                damping=float(m.dof_damping[da]), stiffness=float(m.jnt_stiffness[j]),
                springref=float(m.qpos_spring[qa]) if kind in ("hinge", "slide") else 0.0,
                armature=float(m.dof_armature[da]), friction=float(m.dof_frictionloss[da]), source_type=kind,
                effort=effort.get(j), velocity=speed.get(j), effort_source=sources.get(j, "")))
        bodies.append(BodyPart(bname, None if parent == 0 else name("mjOBJ_BODY", parent, f"body{parent}"), pose, H,
                               tuple(joints)))
    g = np.array(m.opt.gravity, float)
    if int(m.opt.disableflags) & int(mujoco.mjtDisableBit.mjDSBL_GRAVITY):
        g = np.zeros(3)
    model_name = name("mjOBJ_MODEL", 0, "") or (Path(where).stem if where != "<string>" else "mjcf")
    sites = tuple((name("mjOBJ_SITE", s, f"site{s}"), name("mjOBJ_BODY", int(m.site_bodyid[s]), "world"),
                   homogeneous(quat_to_matrix(m.site_quat[s]), np.asarray(m.site_pos[s], float))) for s in range(m.nsite))
    return RobotParts(model_name, where, "mjcf", tuple(bodies), gravity=g, notes=tuple(notes),
                      compiler=_compiler_settings(path), sites=sites, velocity_actuators=bool(speed))


def _actuator_limits(m, sources: dict | None = None) -> tuple[dict, dict]:
    """``({joint id: largest force}, {joint id: largest speed})`` an MJCF model states. The force: the smallest
    of the joint's ``actuatorfrcrange``, and for each actuator on the joint (transmission ``joint``, gear ``g``;
    or ``tendon`` on a fixed tendon whose coefficient at the joint is ``c``: the joint's share ``|g c|``)
    ``|g c| forcerange`` and, for a motor (force = ctrl: gain 1, no bias), ``|g c| ctrlrange``; the largest
    absolute end of each range. The speed: a velocity actuator's (bias ``-kv qdot``) ``ctrlrange`` over ``|g|``
    (its control is the transmission's speed ``g qdot``; joint transmissions only). ``sources`` (a dict) gets
    ``{joint id: where the force limit comes from, in words}``."""
    import mujoco

    force, speed = {}, {}
    sources = {} if sources is None else sources
    for j in range(m.njnt):
        if m.jnt_actfrclimited[j]:
            force[j] = float(np.max(np.abs(m.jnt_actfrcrange[j])))
            sources[j] = "actuatorfrcrange"
    for k in range(m.nu):
        g = abs(float(m.actuator_gear[k, 0]))
        if g == 0.0:
            continue
        ends = []
        if m.actuator_forcelimited[k]:
            ends.append(("forcerange", float(np.max(np.abs(m.actuator_forcerange[k])))))
        bias, gain = np.asarray(m.actuator_biasprm[k], float), np.asarray(m.actuator_gainprm[k], float)
        motor = int(m.actuator_biastype[k]) == 0 and gain[0] == 1.0 and int(m.actuator_dyntype[k]) == 0
        if motor and m.actuator_ctrllimited[k]:
            ends.append(("ctrlrange", float(np.max(np.abs(m.actuator_ctrlrange[k])))))
        name = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_ACTUATOR, k) or f"actuator {k}"
        for j, share, via in _transmission_shares(m, k):
            for what, end in ends:
                if g * share * end < force.get(j, np.inf):
                    force[j] = g * share * end
                    sources[j] = f"{name}'s {what} x gear {g:g}" + via
        velocity = int(m.actuator_biastype[k]) == 1 and bias[2] != 0.0 and bias[1] == 0.0 and gain[0] == -bias[2]
        joint = int(m.actuator_trntype[k]) == int(mujoco.mjtTrn.mjTRN_JOINT)
        if velocity and joint and m.actuator_ctrllimited[k]:
            speed[int(m.actuator_trnid[k, 0])] = float(np.max(np.abs(m.actuator_ctrlrange[k]))) / g
    return force, speed


def _transmission_shares(m, k) -> list[tuple[int, float, str]]:
    """``[(joint id, |c|, words)]`` of actuator ``k``'s transmission: its joint (``c`` = 1), or each joint of its
    fixed tendon (``c`` the tendon's coefficient there: the tendon's force ``f`` is ``c f`` at the joint); none for
    other transmissions (a site's, a spatial tendon's: their share depends on the configuration)."""
    import mujoco

    kind, target = int(m.actuator_trntype[k]), int(m.actuator_trnid[k, 0])
    if kind == int(mujoco.mjtTrn.mjTRN_JOINT):
        return [(target, 1.0, "")]
    if kind != int(mujoco.mjtTrn.mjTRN_TENDON):
        return []
    adr, num = int(m.tendon_adr[target]), int(m.tendon_num[target])
    if any(int(m.wrap_type[i]) != int(mujoco.mjtWrap.mjWRAP_JOINT) for i in range(adr, adr + num)):
        return []
    tendon = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_TENDON, target) or f"tendon {target}"
    return [(int(m.wrap_objid[i]), abs(float(m.wrap_prm[i])), f" x coef {float(m.wrap_prm[i]):g} of tendon {tendon}")
            for i in range(adr, adr + num) if float(m.wrap_prm[i]) != 0.0]


def _compiler_settings(path) -> dict:
    """The attributes of the file's top-level ``<compiler>`` elements (later ones win), {} when unreadable."""
    try:
        from lxml import etree

        root = etree.parse(str(path), etree.XMLParser(resolve_entities=False, no_network=True)).getroot()
    except Exception:  # noqa: BLE001 -- MuJoCo compiled it; this is only for the notes
        return {}
    out = {}
    for comp in root.findall("compiler"):
        out.update({str(k): str(v) for k, v in comp.attrib.items()})
    return out


# -- back to a tree of links ----------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class PartsModel:
    """A :class:`~urdf2links.dynamics.model.Model` built from parts, with ``frame_of`` (body -> (tree link
    index, ``X`` (4, 4)): ``r_t = X r_b``) and ``link_of_joint`` (joint -> tree link index)."""

    model: Model
    frame_of: dict
    link_of_joint: dict

    def part_H(self, body: str) -> np.ndarray:
        """The tree link's whole ``H`` (every body folded into it) in ``body``'s frame (4, 4), E11 inverted."""
        t, X = self.frame_of[body]
        Xi = np.linalg.inv(X)
        return Xi @ self.model.tree.H[t] @ Xi.T


def _trans(v) -> np.ndarray:
    return homogeneous(np.eye(3), np.asarray(v, float))


def _params(F) -> np.ndarray:
    return np.r_[F[:3, 3], matrix_to_xyz_angles(F[:3, :3])]


class _Builder:
    """Parts -> link specs, each joint as the importers make it (URDF: importer, MJCF: mjcf._Builder)."""

    def __init__(self, parts: RobotParts):
        self.parts = parts
        self.specs: list[LinkSpec] = []
        self.H: list[np.ndarray] = []
        self.link_of_joint: dict[str, int] = {}

    def add(self, name, parent, params, coords=None, armature=None) -> int:
        taken = {s.name for s in self.specs}
        while name in taken:
            name += "_"
        self.specs.append(LinkSpec(name, None if parent is None else self.specs[parent].name,
                                   tuple(float(x) for x in params), coords or {}, None, armature or {}))
        self.H.append(np.zeros((4, 4)))
        return len(self.specs) - 1

    def joint(self, j: JointPart, link: str, t, X):
        slots = JOINT_KINDS[j.kind]
        coords = dict(zip(slots, j.coordinates))
        arm = {s: j.armature for s in slots} if j.armature else None
        if j.kind == "free":
            if t is None:                 # MJCF (top level only), or a URDF root loaded with a floating base
                return self.add(link, None, np.zeros(6), coords, arm), _I4
            if np.array_equal(X[:3, :3], np.eye(3)):          # a URDF floating joint below a link (the importer)
                return self.add(link, t, np.r_[X[:3, 3], 0, 0, 0], coords, arm), _I4
            t = self.add(f"{j.name}.frame", t, _params(X))
            return self.add(link, t, np.zeros(6), coords, arm), _I4
        if j.kind == "ball":
            F = X @ _trans(j.anchor)
            if not np.array_equal(F[:3, :3], np.eye(3)):
                t, F = self.add(f"{j.name}.frame", t, _params(F)), _I4
            return self.add(link, t, np.r_[F[:3, 3], 0, 0, 0], coords, arm), _trans(-np.asarray(j.anchor))
        Ra = homogeneous(axis_alignment(j.built_axis), np.zeros(3))
        if j.kind == "hinge":
            params = _params(X @ _trans(j.anchor) @ Ra)
            params[5] -= j.ref
            return self.add(link, t, params, coords, arm), Ra.T @ _trans(-np.asarray(j.anchor))
        F = X @ Ra                                            # slide, planar: translations along link axes
        offset = np.array([0, 0, j.ref, 0, 0, 0]) if j.kind == "slide" else np.zeros(6)
        if np.array_equal(F[:3, :3], np.eye(3)):
            return self.add(link, t, np.r_[F[:3, 3], 0, 0, 0] - offset, coords, arm), Ra.T
        t = self.add(f"{j.name}.frame", t, _params(F))
        return self.add(link, t, -offset, coords, arm), Ra.T

    def build(self, overrides: dict) -> PartsModel:
        frame_of: dict[str, tuple[int | None, np.ndarray]] = {}
        for b in self.parts.bodies:
            t, X = (None, _I4) if b.parent is None else frame_of[b.parent]
            free = len(b.joints) == 1 and b.joints[0].kind == "free" and b.parent is None
            X = X if free else X @ b.pose
            for k, j in enumerate(b.joints):
                t, X = self.joint(j, b.name if k == len(b.joints) - 1 else f"{b.name}:{j.name}", t, X)
                self.link_of_joint[j.name] = t
            if t is None:             # welded to the world: a link of its own under {A}
                t, X = self.add(b.name, None, _params(X)), _I4
            frame_of[b.name] = (t, X)
            self.H[t] = self.H[t] + X @ b.H @ X.T
        for body, H in overrides.items():      # a whole tree link's H given in one body's frame
            t, X = frame_of[body]
            self.H[t] = X @ np.asarray(H, float) @ X.T
        if not self.specs:        # every body welded to the world (or none): a tree of one massless link
            self.add("world", None, np.zeros(6))
        specs = [LinkSpec(s.name, s.parent, s.params, s.coordinates, 0.5 * (H + H.T), s.armature)
                 for s, H in zip(self.specs, self.H)]
        tree = build_tree(specs)
        return PartsModel(Model(tree, gravity=self.parts.gravity, name=self.parts.name, source=self.parts.source),
                          frame_of, dict(self.link_of_joint))


def parts_model(parts: RobotParts, *, overrides: dict | None = None) -> PartsModel:
    """The tree of links of ``parts`` and its Model (E51): the same tree the importers build from the
    file (``A``, ``G`` equal to theirs to rounding), with a tree link's whole ``H`` replaced where
    ``overrides`` (body -> H (4, 4) in that body's frame) says."""
    return _Builder(parts).build(dict(overrides or {}))


def home_poses(parts: RobotParts) -> dict[str, np.ndarray]:
    """Every body's frame in the world (4, 4) at the home pose (each joint at ``home``)."""
    out: dict[str, np.ndarray] = {}
    for b in parts.bodies:
        W = _I4 if b.parent is None else out[b.parent]
        if len(b.joints) == 1 and b.joints[0].kind == "free" and b.parent is None:
            from ..dynamics.transforms import link_transform

            out[b.name] = link_transform(np.asarray(b.joints[0].home, float))
        else:
            out[b.name] = W @ b.pose
    return out

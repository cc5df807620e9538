"""Route 1 of the MuJoCo comparison: the project's OWN tree of links written as an MJCF model.

Same frames, same ``H``, same coordinates in the same order (through ``qpos_index`` /
``dof_index``), so that MuJoCo and the trace method integrate literally the same model and any
difference is the solver's or the integrator's (route 2, :mod:`urdf2links.compare.mujoco_side.mujoco_urdf`,
checks the importer instead).

One MJCF body per tree link, nested as the tree. The body's frame IS the link's frame, at every
``q`` (checked in the tests against :meth:`urdf2links.dynamics.model.Model.link_poses`).

How a link's ``T~ = T1 T2 T3 T4 T5 T6`` (docs/equations.md (E3)) becomes a body with joints
-------------------------------------------------------------------------------------------
MuJoCo's multi-joint semantics (``mj_kinematics``): the body frame starts at
``parent * (pos, quat)``; then the body's joints are applied IN ORDER, each about an axis (and,
for a hinge, through an anchor ``pos``) given in the body's local frame *as moved by the joints
before it*: ``F <- F * Rot(axis_j, anchor_j, q_j)`` for a hinge, ``F <- F * Trans(axis_j q_j)``
for a slide. So a body is ``T = M * J_1(q_1) * J_2(q_2) * ...`` with constant ``M = (pos, quat)``
and joint factors in the body's frame.

A link's transform is a chain of constant factors ``K`` and coordinate factors ``J``::

    T~ = Trans(p) [S_x(q)] [S_y(q)] [S_z(q)] Rx(c_x) [R_x(q)] Ry(c_y) [R_y(q)] Rz(c_z) [R_z(q)]

(``p`` and ``c`` are ``params``, which hold the coordinates' offsets too: ``Rx(c + q) = Rx(c) Rx(q)``).
Every constant factor is moved to the front by conjugation:
``K_0 J_1 K_1 J_2 K_2 ... = (K_0 K_1 K_2 ...) * J_1' * J_2' * ...`` with
``J_i' = G_i^{-1} J_i G_i`` and ``G_i`` the product of the constants to the right of ``J_i``. A
rotation about ``e`` through the origin conjugated by ``G = (R, t)`` is a rotation about
``R^T e`` through the point ``-R^T t``; a slide along ``e`` becomes a slide along ``R^T e``. For one
link the constants right of a joint are pure rotations, so this is exactly: ``pos = p``,
``quat = C`` (all constant rotations), slides along ``C^T e_k`` (along the parent's axis ``k``),
hinges through the body origin about the axes of the conjugation. Joints are written in the
project's slot order ``x, y, z, phi_x, phi_y, phi_z``, which is the coordinates' order.

Massless links with joints
--------------------------
MuJoCo refuses a body with joints whose own mass or inertia is below ``mjMINVAL``
("mass and inertia of moving bodies must be larger than mjMINVAL"), while the trace method is
fine with a massless link as long as something after it has mass. Chosen fix (exact): a massless
link that carries joints and has exactly ONE child is *folded* into that child: the child's body
gets the massless link's joints first, then its own, with all constants moved to the front as
above (hinge anchors are then not at the body origin in general). The same rule cascades down a
chain of massless links, as long as the receiving body keeps at most 6 dofs (MuJoCo refuses
"more than 6 dofs in body"). Only a massless link carrying joints with zero or several children
(or whose fold would exceed 6 dofs) cannot be folded; that body gets a negligible mass (``TINY_MASS_FRACTION`` of the robot's mass,
at its origin, inertia ``m_tiny * 1 m^2`` on the diagonal) and ``notes`` says so. A folded link
has no body (``body_of_link[p] == -1``); :meth:`MjcfModel.link_poses` still gives its pose, and
loads on it are mapped with the host body's Jacobian restricted to the folded link's own joints
and those before it (see :mod:`urdf2links.compare.mujoco_side.mujoco_run`).

Physics switched off (everything the project does not model): contacts, limits, equality
constraints, friction loss; springs and dampers unless a spring/damper is given (then as joint
``stiffness``/``springref``/``damping``); armature the model's own on each coordinate's joint (E49;
not the shared armature of a ball's three angles, :func:`route1_armature`); no geoms, inertias exactly as given
(``inertiafromgeom="false" balanceinertia="false" boundmass="0" boundinertia="0"``).

Moving base ``{A}`` (``moving_base=True``): a root body ``base_A`` at the world origin with three
slide joints along the world axes then three hinges about x, y, z of its own (moving) frame,
``Trans(x, y, z) Rx Ry Rz`` = ``0_A T`` of (E13) exactly; its qpos are the six base parameters.
It has a small mass (``BASE_MASS_FRACTION`` of the robot's); its motion is prescribed by
:func:`urdf2links.compare.mujoco_side.mujoco_run.run_mujoco`, so the mass does not enter the robot's motion.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Iterable
from xml.sax.saxutils import quoteattr

import mujoco
import numpy as np

from urdf2links.dynamics.inertia import inertial_from_pseudo
from urdf2links.dynamics.transforms import PARAMETERS, BaseState, elementary, link_transform

__all__ = [
    "MjcfModel",
    "MjcfRefused",
    "mjcf_from_model",
    "mjcf_from_scene",
    "INTEGRATORS",
    "BASE_BODY",
    "BASE_JOINTS",
    "TINY_MASS_FRACTION",
    "BASE_MASS_FRACTION",
    "route1_armature",
    "body_gravcomp",
]


class MjcfRefused(ValueError):
    """MuJoCo's compiler refused the route-1 MJCF of a model (most often an inertia it will not take:
    a link whose principal moments are negative or break the triangle inequality, which the project's
    audit reports and ``inertia="repair"`` fixes). ``reason`` is MuJoCo's own text."""

    def __init__(self, model_name: str, reason: str):
        self.model_name, self.reason = model_name, reason
        super().__init__(f"MuJoCo refused the MJCF of model {model_name!r}: {reason}")


#: MJCF integrator names accepted (MuJoCo's spelling).
INTEGRATORS = ("Euler", "RK4", "implicit", "implicitfast")
#: Name of the body that carries the moving base {A} and its joints (x, y, z, phi_x, phi_y, phi_z).
BASE_BODY = "base_A"
BASE_JOINTS = tuple(f"{BASE_BODY}:{s}" for s in PARAMETERS)
#: Mass of an unfoldable massless moving link, as a fraction of the robot's total mass.
TINY_MASS_FRACTION = 1e-12
#: Mass of the ``base_A`` body as a fraction of the robot's total mass (its motion is prescribed).
BASE_MASS_FRACTION = 1e-3


@dataclass(frozen=True, eq=False)
class MjcfModel:
    """The project's tree compiled by MuJoCo from MJCF text.

    ``xml``: the MJCF text; ``model``: the ``mujoco.MjModel``.
    ``qpos_index`` / ``dof_index`` (n,): coordinate ``i`` of the project (``coordinate_names[i]``)
    is MuJoCo's ``qpos[qpos_index[i]]`` / ``qvel[dof_index[i]]`` (same value, same sign: MuJoCo's
    qpos IS the project's q).
    ``base_dofs`` / ``base_qpos`` (6,) or empty: the dofs / qpos of ``base_A`` (x, y, z, phi_x,
    phi_y, phi_z of {A}) when built with ``moving_base=True``.
    ``body_of_link`` (L,): MuJoCo body id of each tree link, ``-1`` for a folded massless link.
    ``host_body`` (L,): the body that carries a link's joints (its own body, or for a folded link
    the body it is folded into). ``folded_links``, ``tiny_mass_links``: link names.
    ``source``: the project :class:`~urdf2links.dynamics.model.Model`; ``gravity`` (3,) or None;
    ``springs``: the springs/dampers built in; ``notes``: what was done and why.
    """

    xml: str
    model: mujoco.MjModel
    qpos_index: np.ndarray
    dof_index: np.ndarray
    base_dofs: np.ndarray
    base_qpos: np.ndarray
    body_of_link: np.ndarray
    host_body: np.ndarray
    coordinate_names: tuple[str, ...]
    source: object
    gravity: np.ndarray | None
    springs: tuple = ()
    folded_links: tuple[str, ...] = ()
    tiny_mass_links: tuple[str, ...] = ()
    base_body: int = -1
    notes: list[str] = field(default_factory=list)
    actuators: tuple = ()
    """The scene's actuators written as MuJoCo ``<general>`` actuators, in this order (E55)."""
    gravcomp_in_bodies: bool = False
    """The scene's gravcomp written as the bodies' own ``gravcomp`` (MuJoCo's ``qfrc_passive``), not as loads."""

    @property
    def n(self) -> int:
        return len(self.coordinate_names)

    @property
    def moving_base(self) -> bool:
        return self.base_body >= 0

    # -- states ------------------------------------------------------------------------------------
    def set_state(self, d: mujoco.MjData, q, qd=None, *, base: BaseState | None = None) -> None:
        """Write the project's ``q``, ``qd`` (n,) (and the base pose/rate) into ``d.qpos``/``d.qvel``."""
        q = np.asarray(q, float)
        if q.shape != (self.n,):
            raise ValueError(f"q must have shape ({self.n},) for coordinates {self.coordinate_names}")
        d.qpos[self.qpos_index] = q
        if qd is not None:
            qd = np.asarray(qd, float)
            if qd.shape != (self.n,):
                raise ValueError(f"qd must have shape ({self.n},)")
            d.qvel[self.dof_index] = qd
        if base is not None:
            if not self.moving_base:
                raise ValueError("a base state was given but the MJCF model was built with moving_base=False")
            d.qpos[self.base_qpos] = np.asarray(base.pose, float)
            d.qvel[self.base_dofs] = np.asarray(base.rate, float)

    def data(self, q, qd=None, *, base: BaseState | None = None, t: float = 0.0) -> mujoco.MjData:
        """A fresh ``MjData`` at the given state after ``mj_forward`` (no control callback:
        ``qacc`` is MuJoCo's free acceleration, the base NOT prescribed)."""
        d = mujoco.MjData(self.model)
        d.time = float(t)
        self.set_state(d, q, qd, base=base)
        mujoco.mj_forward(self.model, d)
        return d

    def terms(self, q, qd, *, base: BaseState | None = None) -> tuple[np.ndarray, np.ndarray]:
        """``(M, bias)`` of the robot's coordinates in the project's order: ``mj_fullM`` (n, n)
        and ``qfrc_bias`` (n,) (= ``e + G`` of the project for the gravity built in; with a moving
        base, the robot rows at the base's pose and RATE, i.e. without the base's acceleration)."""
        d = self.data(q, qd, base=base)
        M = np.zeros((self.model.nv, self.model.nv))
        mujoco.mj_fullM(self.model, d, M)
        i = self.dof_index
        return M[np.ix_(i, i)].copy(), np.array(d.qfrc_bias[i])

    def link_poses(self, d: mujoco.MjData) -> np.ndarray:
        """(L, 4, 4) {0}-pose of every tree link from MuJoCo's ``xpos``/``xmat`` (after
        kinematics); a folded link's pose is its parent's pose times its own ``T~`` at MuJoCo's
        qpos (its joints live in its child's body)."""
        tree = self.source.tree
        out = np.empty((tree.n_links, 4, 4))
        for p in range(tree.n_links):
            b = int(self.body_of_link[p])
            if b >= 0:
                out[p] = _body_pose(d, b)
            else:
                out[p] = self._parent_pose(d, out, p) @ self.link_transform(d, p)
        return out

    def link_pose(self, d: mujoco.MjData, p: int) -> np.ndarray:
        """(4, 4) {0}-pose of tree link ``p`` (see :meth:`link_poses`)."""
        b = int(self.body_of_link[p])
        if b >= 0:
            return _body_pose(d, b)
        par = int(self.source.tree.parent[p])
        parent_pose = self._frame_of_parent(d, par)
        return parent_pose @ self.link_transform(d, p)

    def _frame_of_parent(self, d, par: int) -> np.ndarray:
        if par >= 0:
            return self.link_pose(d, par)
        return _body_pose(d, self.base_body) if self.moving_base else np.eye(4)

    def _parent_pose(self, d, done, p) -> np.ndarray:
        par = int(self.source.tree.parent[p])
        if par >= 0:
            return done[par]
        return _body_pose(d, self.base_body) if self.moving_base else np.eye(4)

    def link_transform(self, d: mujoco.MjData, p: int) -> np.ndarray:
        """``T~`` (4, 4) of tree link ``p`` at MuJoCo's current qpos."""
        tree = self.source.tree
        v = np.array(tree.params[p], float)
        for k in range(6):
            c = int(tree.coord[p, k])
            if c >= 0:
                v[k] += d.qpos[self.qpos_index[c]]
        return link_transform(v)


def _body_pose(d: mujoco.MjData, b: int) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3] = np.asarray(d.xmat[b]).reshape(3, 3)
    T[:3, 3] = d.xpos[b]
    return T


# --------------------------------------------------------------------------- building


def _num(x) -> str:
    x = float(x)
    if not math.isfinite(x):
        raise ValueError(f"non-finite number {x!r} in the MJCF model")
    return "0" if x == 0.0 else repr(x)


def _vec(v) -> str:
    return " ".join(_num(x) for x in v)


def _link_factors(tree, p: int) -> list:
    """``T~`` of link ``p`` as a chain: ``("const", (4, 4))`` and ``(kind, axis k, coordinate)``."""
    params, coord = tree.params[p], tree.coord[p]
    K = np.eye(4)
    K[:3, 3] = params[:3]
    chain: list = [("const", K)]
    for k in range(3):
        if coord[k] >= 0:
            chain.append(("slide", k, int(coord[k])))
    for k in range(3, 6):
        if params[k] != 0.0:
            chain.append(("const", elementary(k, params[k])))
        if coord[k] >= 0:
            chain.append(("hinge", k - 3, int(coord[k])))
    return chain


def _conjugate(chain: list) -> tuple[np.ndarray, list]:
    """``(M, joints)``: ``chain = M * J_1' * J_2' ...`` with every constant moved to the front.
    ``joints`` in chain order: ``(kind, axis (3,), anchor (3,), coordinate)`` in the body frame."""
    G = np.eye(4)
    joints = []
    for item in reversed(chain):
        if item[0] == "const":
            G = item[1] @ G
            continue
        kind, k, c = item
        R, t = G[:3, :3], G[:3, 3]
        axis = R.T[:, k].copy()  # R^T e_k
        anchor = -R.T @ t if kind == "hinge" else np.zeros(3)
        joints.append((kind, axis, anchor, c))
    joints.reverse()
    return G, joints


def _quat(R: np.ndarray) -> np.ndarray:
    q = np.zeros(4)
    mujoco.mju_mat2Quat(q, np.ascontiguousarray(R, dtype=float).reshape(9))
    return q


def _unique(name: str, taken: set[str]) -> str:
    out = name
    while out in taken:
        out = out + "_"
    taken.add(out)
    return out


def _fold(tree, massless) -> tuple[list[bool], list[str]]:
    """Which links fold into their child: a massless link carrying joints with exactly one child
    goes into that child's body, unless the body would get more than 6 dofs (MuJoCo's limit).
    Returns the flags and the links left unfolded for that reason."""
    L, children = tree.n_links, tree.children
    own = [int(np.count_nonzero(tree.coord[p] >= 0)) for p in range(L)]
    folded = [False] * L
    carried = [0] * L  # dofs the body holding this link's joints would have up to this link
    too_many: list[str] = []
    for p in range(L):
        par = int(tree.parent[p])
        carried[p] = own[p] + (carried[par] if par >= 0 and folded[par] else 0)
        if massless[p] and carried[p] > 0 and len(children[p]) == 1:
            if carried[p] + own[children[p][0]] <= 6:
                folded[p] = True
            else:
                too_many.append(tree.link_names[p])
    return folded, too_many


class _Bodies:
    """Writes the ``<body>`` elements of the tree: one body per non-folded link, its inertial (a
    negligible mass for a massless moving link that cannot be folded) and its joints."""

    def __init__(self, model, names, spring_of, folded, massless, tiny):
        self.tree, self.names, self.spring_of = model.tree, names, spring_of
        self.folded, self.massless, self.tiny = folded, massless, tiny
        self.taken = {"world"}
        self.body_name_of: dict[int, str] = {}
        self.tiny_links: list[str] = []
        self.notes: list[str] = []
        self.lines: list[str] = []
        self.armature, self.ball_armature = route1_armature(self.tree)
        self.gravcomp: dict[int, float] = {}       # tree link -> its body's gravcomp

    def chain_of(self, p: int) -> list[int]:
        """Links whose factors make the body of non-folded link p, top first."""
        out = [p]
        par = int(self.tree.parent[p])
        while par >= 0 and self.folded[par]:
            out.append(par)
            par = int(self.tree.parent[par])
        return out[::-1]

    def body_children(self, p: int) -> list[int]:
        """Non-folded links whose bodies are children of link p's body (through folded links)."""
        out = []
        for c in self.tree.children[p]:
            out.extend([c] if not self.folded[c] else self.body_children(c))
        return out

    def top(self) -> list[int]:
        roots = [p for p in range(self.tree.n_links) if self.tree.parent[p] < 0]
        return [x for r in roots for x in ([r] if not self.folded[r] else self.body_children(r))]

    def emit(self, p: int, indent: str) -> None:
        tree, lines = self.tree, self.lines
        factors = [f for lk in self.chain_of(p) for f in _link_factors(tree, lk)]
        M, joints = _conjugate(factors)
        bname = _unique(tree.link_names[p], self.taken)
        if bname != tree.link_names[p]:
            self.notes.append(f"link {tree.link_names[p]!r} is MuJoCo body {bname!r} (name taken)")
        self.body_name_of[p] = bname
        gc = f' gravcomp="{_num(self.gravcomp[p])}"' if self.gravcomp.get(p) else ""
        lines.append(f'{indent}<body name={quoteattr(bname)} pos="{_vec(M[:3, 3])}" quat="{_vec(_quat(M[:3, :3]))}"{gc}>')
        ind = indent + "  "
        if not self.massless[p]:
            m, com, I = inertial_from_pseudo(tree.H[p])
            I = 0.5 * (I + I.T)
            full = (I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2])
            lines.append(f'{ind}<inertial pos="{_vec(com)}" mass="{_num(m)}" fullinertia="{_vec(full)}"/>')
        elif joints:
            self.tiny_links.append(tree.link_names[p])
            lines.append(f'{ind}<inertial pos="0 0 0" mass="{_num(self.tiny)}" '
                         f'diaginertia="{_vec([self.tiny] * 3)}"/>')
        for kind, axis, anchor, c in joints:
            lines.append(f"{ind}{self._joint(kind, axis, anchor, c)}")
        for ch in self.body_children(p):
            self.emit(ch, ind)
        lines.append(f"{indent}</body>")

    def _joint(self, kind, axis, anchor, c) -> str:
        cname = self.names[c]
        extra = ""
        s = self.spring_of.get(cname)
        if s is not None:
            extra = f' stiffness="{_num(s.stiffness)}" springref="{_num(s.rest)}" damping="{_num(s.damping)}"'
        if self.armature[c] != 0.0:
            extra += f' armature="{_num(self.armature[c])}"'
        pos = f' pos="{_vec(anchor)}"' if kind == "hinge" and np.any(anchor != 0.0) else ""
        return f'<joint name={quoteattr(cname)} type="{kind}" axis="{_vec(axis)}"{pos}{extra}/>'

    def base_body(self, bm: float, joint_names, indent: str) -> str:
        """The prescribed base {A}: a body with slides x, y, z and hinges about x, y, z, the tree inside."""
        bname = _unique(BASE_BODY, self.taken)
        self.lines.append(f'{indent}<body name={quoteattr(bname)} pos="0 0 0">')
        self.lines.append(f'{indent}  <inertial pos="0 0 0" mass="{_num(bm)}" diaginertia="{_vec([bm] * 3)}"/>')
        for k, jn in enumerate(joint_names):
            axis = np.eye(3)[k % 3]
            self.lines.append(f'{indent}  <joint name={quoteattr(jn)} type="{"slide" if k < 3 else "hinge"}" '
                              f'axis="{_vec(axis)}"/>')
        for r in self.top():
            self.emit(r, indent + "  ")
        self.lines.append(f"{indent}</body>")
        return bname


def route1_armature(tree) -> tuple[np.ndarray, list[str]]:
    """The armature route 1 writes on each coordinate's joint (E49: a coordinate's own ``0.5 a q'^2``),
    and the links whose three angles share an armature on their angular velocity (a ball or free joint
    of an MJCF file): route 1 writes those angles as three hinges, where that armature has no
    equivalent, so it is left out there (``route1_terms`` compares with it left out too)."""
    arm = np.array(tree.armature, float)
    balls = []
    for p in range(tree.n_links):
        tri = tree.coord[p, 3:6]
        if np.all(tri >= 0) and arm[tri[0]] != 0.0:
            arm[tri] = 0.0
            balls.append(tree.link_names[p])
    return arm, balls


def _actuator_lines(actuators) -> list[str]:
    """The scene's actuators (:mod:`urdf2links.scenes.actuators`) as MuJoCo ``general`` actuators on their
    coordinates' joints: dynamics none, gain fixed, bias affine, the gear, and both clamps when given (E55)."""
    if not actuators:
        return []
    out = ["  <actuator>"]
    for a in actuators:
        rng = ""
        if a.ctrlrange is not None:
            rng += f' ctrllimited="true" ctrlrange="{_vec(a.ctrlrange)}"'
        else:
            rng += ' ctrllimited="false"'
        if a.forcerange is not None:
            rng += f' forcelimited="true" forcerange="{_vec(a.forcerange)}"'
        else:
            rng += ' forcelimited="false"'
        out.append(f'    <general name={quoteattr(a.name)} joint={quoteattr(a.coordinate)} dyntype="none" gaintype="fixed" '
                   f'biastype="affine" gainprm="{_num(a.gain)}" biasprm="{_vec(a.bias)}" gear="{_num(a.gear)}"{rng}/>')
    return out + ["  </actuator>"]


def _document(model, body_lines, g, springs, timestep, integrator, actuators=(), gravcomp=False) -> tuple[str, str]:
    """The whole MJCF text around the bodies (only the scene's physics enabled) and its note. With
    ``gravcomp`` the spring flag stays on (every stiffness 0): MuJoCo's ``mj_passive``, which applies body
    gravcomp, does nothing when springs and dampers are both disabled."""
    has_spring = any(s.stiffness > 0 for s in springs) or gravcomp
    has_damper = any(s.damping > 0 for s in springs)
    flags = ['contact="disable"', 'limit="disable"', 'equality="disable"', 'frictionloss="disable"']
    if not has_spring:
        flags.append('spring="disable"')
    if not has_damper:
        flags.append('damper="disable"')
    gtxt = "0 0 0" if g is None else _vec(g)
    head = [
        f"<mujoco model={quoteattr('route1_' + (model.name or 'robot'))}>",
        '  <compiler angle="radian" inertiafromgeom="false" balanceinertia="false" boundmass="0" '
        'boundinertia="0" autolimits="false"/>',
        f'  <option timestep="{_num(timestep)}" integrator="{integrator}" gravity="{gtxt}">',
        f"    <flag {' '.join(flags)}/>",
        "  </option>",
        "  <default>",
        '    <joint armature="0" damping="0" stiffness="0" frictionloss="0" limited="false"/>',
        "  </default>",
        "  <worldbody>",
    ]
    xml = "\n".join(head + body_lines + ["  </worldbody>"] + _actuator_lines(actuators) + ["</mujoco>", ""])
    note = ("gravity " + ("off (0 0 0)" if g is None else f"{g.tolist()} m/s^2")
            + "; disabled: contact, limit, equality, frictionloss"
            + ("" if has_spring else ", spring") + ("" if has_damper else ", damper")
            + "; armature " + ("the model's (E49)" if model.tree.has_armature else "0")
            + f"; no geoms; integrator {integrator}, timestep {timestep:g} s"
            + (f"; {len(actuators)} general actuator(s) on their coordinates' joints (MuJoCo's law, E55)" if actuators
               else ""))
    return xml, note


def _spring_map(names, springs) -> dict:
    spring_of: dict[str, object] = {}
    for s in springs:
        if s.coordinate not in names:
            raise KeyError(f"spring on unknown coordinate {s.coordinate!r}; coordinates are {list(names)}")
        spring_of[s.coordinate] = s
    return spring_of


def _check_model(model, integrator, timestep, moving_base: bool = False) -> tuple[list[bool], list[str]]:
    """Refuse what route 1 cannot write; returns which links are written massless, and notes.

    A link with zero mass but non-zero second moments is no physical body, and MuJoCo has no such
    body. When no coordinate moves it and the base is fixed, it has no effect on the equations
    (A, e and G involve moving links only): it is written without inertia, and noted. When it moves,
    :class:`MjcfRefused` names it and the fix."""
    if model.coupling is not None:
        raise ValueError(f"model {model.name!r} has coupled coordinates (mimic='coupled'); route 1 "
                         "builds the tree's own coordinates only: load with mimic='independent'")
    if integrator not in INTEGRATORS:
        raise ValueError(f"integrator must be one of {INTEGRATORS}, got {integrator!r}")
    if not (timestep > 0 and math.isfinite(timestep)):
        raise ValueError(f"timestep must be a positive number, got {timestep!r}")
    tree = model.tree
    mass = tree.H[:, 3, 3]
    massless = [bool(np.all(tree.H[p] == 0.0)) for p in range(tree.n_links)]
    moves = [False] * tree.n_links          # a coordinate on the path from {A} to the link
    for p in range(tree.n_links):           # parents come before their children
        par = int(tree.parent[p])
        moves[p] = bool(np.any(tree.coord[p] >= 0)) or (par >= 0 and moves[par])
    notes, static = [], []
    for p in range(tree.n_links):
        if mass[p] == 0.0 and not massless[p]:
            if not moves[p] and not moving_base:
                massless[p] = True
                static.append(tree.link_names[p])
                continue
            raise MjcfRefused(model.name, f"link {tree.link_names[p]!r} has zero mass but non-zero second moments: "
                              "no physical body has that, and MuJoCo cannot represent it. Load the robot with "
                              "--inertia repair (inertia='repair': its inertia from its geometry, noted in the "
                              "audit), or give the link a mass in the file")
    if static:
        notes.append(f"links with zero mass but non-zero second moments that nothing moves (welded to a fixed base; "
                     f"no effect on A, e or G) written without inertia: {', '.join(static)}")
    return massless, notes


def _fold_notes(tree, folded, too_many, tiny_links, tiny) -> list[str]:
    notes = []
    folded_names = tuple(tree.link_names[p] for p in range(tree.n_links) if folded[p])
    if folded_names:
        notes.append("massless links with joints folded into their only child's body (exact; MuJoCo refuses "
                     f"massless moving bodies): {', '.join(folded_names)}")
    if too_many:
        notes.append("not folded because the child's body would have more than 6 dofs (MuJoCo's limit): "
                     + ", ".join(too_many))
    if tiny_links:
        notes.append(f"massless moving links that cannot be folded (no child or several) got a negligible mass "
                     f"{tiny:.3g} kg and inertia {tiny:.3g} kg m^2 at their origin (MuJoCo refuses massless "
                     f"moving bodies; A differs by that much): {', '.join(tiny_links)}")
    return notes


def mjcf_from_model(model, *, gravity=None, springs: Iterable = (), moving_base: bool = False,
                    timestep: float = 1e-4, integrator: str = "RK4", actuators: Iterable = (),
                    gravcomp: dict | None = None) -> MjcfModel:
    """The project's tree of ``model`` as an MJCF model compiled by MuJoCo (see module doc).

    Parameters
    ----------
    model : urdf2links.dynamics.model.Model (uncoupled: mimic joints as independent coordinates)
    gravity : None (no gravity: ``0 0 0``) or (3,) m/s^2 in {0}; e.g. ``model.gravity_vector``.
    springs : iterable of :class:`urdf2links.scenes.scene.Spring` (coordinate, stiffness, rest, damping):
        joint ``stiffness``/``springref``/``damping``; MuJoCo's spring (damper) flag stays enabled
        only when some stiffness (damping) is positive.
    moving_base : add the ``base_A`` body carrying the six base parameters as joints.
    timestep, integrator : MuJoCo's ``<option>``; integrator one of :data:`INTEGRATORS`.
    actuators : resolved actuators (:class:`urdf2links.scenes.actuators.Actuator`), written as ``<general>``
        on their coordinates' joints, in order (MuJoCo's actuator ``k`` is ``actuators[k]``).
    gravcomp : ``{tree link index: factor}`` written as the bodies' ``gravcomp`` (:func:`body_gravcomp`).
    """
    massless, check_notes = _check_model(model, integrator, timestep, moving_base)
    tree = model.tree
    names = tuple(model.coordinate_names)
    g = None if gravity is None else np.asarray(gravity, float).reshape(3)
    springs = tuple(springs)
    total_mass = float(tree.H[:, 3, 3].sum())
    folded, too_many = _fold(tree, massless)
    tiny = TINY_MASS_FRACTION * max(total_mass, 1.0)
    bodies = _Bodies(model, names, _spring_map(names, springs), folded, massless, tiny)
    bodies.gravcomp = dict(gravcomp or {})
    actuators = tuple(actuators)
    for a in actuators:
        if a.coordinate not in names:
            raise KeyError(f"actuator {a.name!r} on unknown coordinate {a.coordinate!r}; coordinates are {list(names)}")
    base_joint_names: tuple[str, ...] = ()
    notes = bodies.notes
    bname = None
    if moving_base:
        bm = BASE_MASS_FRACTION * max(total_mass, 1.0)
        taken_joints: set[str] = set(names)
        base_joint_names = tuple(_unique(j, taken_joints) for j in BASE_JOINTS)
        bname = bodies.base_body(bm, base_joint_names, "    ")
        notes.append(f"moving base: body {bname!r} (mass {bm:.3g} kg) with slides x, y, z along the world "
                     "axes then hinges about its own x, y, z: Trans(x, y, z) Rx Ry Rz = 0_A T "
                     "(docs/equations.md (E13)); "
                     "its motion is prescribed by run_mujoco (qfrc_applied from mjcb_control)")
    else:
        for r in bodies.top():
            bodies.emit(r, "    ")
    notes += check_notes + _fold_notes(tree, folded, too_many, bodies.tiny_links, tiny)
    if bodies.ball_armature:
        notes.append("armature of the three angles of " + ", ".join(bodies.ball_armature) + " (on their angular "
                     "velocity, E49) left out: route 1 writes them as three hinges, where it has no equivalent; "
                     "route 1's terms are compared without it")
    xml, note = _document(model, bodies.lines, g, springs, timestep, integrator, actuators, bool(gravcomp))
    notes.append(note)
    try:
        mm = mujoco.MjModel.from_xml_string(xml)
    except ValueError as err:
        raise MjcfRefused(model.name, str(err).strip()) from None
    out = _compiled(mm, xml, model, names, base_joint_names, bname, bodies, folded, g, springs, notes)
    return dataclasses.replace(out, actuators=actuators, gravcomp_in_bodies=bool(gravcomp))


def _compiled(mm, xml, model, names, base_joint_names, bname, bodies, folded, g, springs, notes) -> MjcfModel:
    """The :class:`MjcfModel`: MuJoCo's indices of the coordinates, the base and the bodies."""
    tree = model.tree
    L, n = tree.n_links, tree.n

    def jid(name):
        return mujoco.mj_name2id(mm, mujoco.mjtObj.mjOBJ_JOINT, name)

    qpos_index = np.array([mm.jnt_qposadr[jid(nm)] for nm in names], dtype=np.int64)
    dof_index = np.array([mm.jnt_dofadr[jid(nm)] for nm in names], dtype=np.int64)
    if bname is not None:
        base_qpos = np.array([mm.jnt_qposadr[jid(nm)] for nm in base_joint_names], dtype=np.int64)
        base_dofs = np.array([mm.jnt_dofadr[jid(nm)] for nm in base_joint_names], dtype=np.int64)
        base_body = mujoco.mj_name2id(mm, mujoco.mjtObj.mjOBJ_BODY, bname)
    else:
        base_qpos = base_dofs = np.zeros(0, dtype=np.int64)
        base_body = -1
    body_of_link = np.full(L, -1, dtype=np.int64)
    for p, bn in bodies.body_name_of.items():
        body_of_link[p] = mujoco.mj_name2id(mm, mujoco.mjtObj.mjOBJ_BODY, bn)
    host = body_of_link.copy()
    for p in range(L - 1, -1, -1):  # a folded link's only child comes after it
        if folded[p]:
            host[p] = host[tree.children[p][0]]
    if mm.nv != n + (6 if bname is not None else 0):
        raise AssertionError(f"MJCF has {mm.nv} dofs, expected {n}")
    for a in (qpos_index, dof_index, base_qpos, base_dofs, body_of_link, host):
        a.setflags(write=False)
    folded_names = tuple(tree.link_names[p] for p in range(L) if folded[p])
    return MjcfModel(
        xml=xml, model=mm, qpos_index=qpos_index, dof_index=dof_index, base_dofs=base_dofs,
        base_qpos=base_qpos, body_of_link=body_of_link, host_body=host, coordinate_names=names,
        source=model, gravity=g, springs=springs, folded_links=folded_names,
        tiny_mass_links=tuple(bodies.tiny_links), base_body=int(base_body), notes=notes,
    )


def mjcf_from_scene(scene, model, *, timestep: float | None = None, integrator: str | None = None) -> MjcfModel:
    """:func:`mjcf_from_model` with a scene's gravity, springs and dampers (URDF damping included when
    the scene asks, :meth:`~urdf2links.scenes.scene.Scene.springs_for`) and base; ``timestep`` defaults to
    the scene's ``run.dt`` (else 1e-4 s), ``integrator`` to RK4 when the scene names none of
    MuJoCo's."""
    from urdf2links.scenes.actuators import resolve_actuators

    scene.check_names(model)
    dt = timestep if timestep is not None else (scene.run.dt or 1e-4)
    integ = integrator if integrator is not None else (scene.run.method if scene.run.method in INTEGRATORS else "RK4")
    actuators = resolve_actuators(scene.actuators, model, where=str(scene.path or scene.name)).actuators
    gravcomp, note = body_gravcomp(model, scene.gravcomp_table(model) if scene.gravity is not None else {})
    mj = mjcf_from_model(model, gravity=scene.gravity, springs=scene.springs_for(model).springs,
                         moving_base=scene.base is not None, timestep=dt, integrator=integ, actuators=actuators,
                         gravcomp=gravcomp)
    if note:
        mj.notes.append(note)
    return mj


def body_gravcomp(model, table: dict) -> tuple[dict, str | None]:
    """``({tree link index: factor}, note)``: a scene's gravcomp (``{body: factor}``, URDF links or MJCF
    bodies) as route 1's bodies' own ``gravcomp`` (MuJoCo applies ``-gravcomp m g`` at each body's COM
    through ``qfrc_passive``). A route-1 body is a tree link, the union of the bodies folded into it: its
    own gravcomp is exact when every body of it with mass has the same factor (the parallel forces then
    sum to ``-f M g`` at the union's COM). Otherwise none is written (empty dict) and the note says the
    scene's gravcomp is applied as loads through the control callback instead."""
    if not table:
        return {}, None
    frame_of = model.info.get("frame_of") or {}
    masses = model.info.get("body_mass_com", {})
    index = {nm: i for i, nm in enumerate(model.tree.link_names)}
    factors: dict[int, set] = {}
    for body, (m, _) in masses.items():
        if m > 0.0 and body in frame_of:
            factors.setdefault(index[frame_of[body][0]], set()).add(float(table.get(body, 0.0)))
    mixed = [model.tree.link_names[t] for t, f in factors.items() if len(f) > 1]
    if mixed:
        return {}, (f"gravcomp: the bodies folded into tree link(s) {', '.join(mixed[:6])} have different factors, "
                    "which no single MuJoCo body gravcomp represents: route 1 applies the scene's gravcomp as loads "
                    "(xfrc_applied from the control callback)")
    out = {t: f.pop() for t, f in factors.items()}
    return {t: f for t, f in out.items() if f != 0.0}, ("gravcomp written as the bodies' own gravcomp (MuJoCo's "
                                                        "qfrc_passive, as body gravcomp acts in MuJoCo)")

"""Route 1's ``<body>`` elements: the project's tree of links as nested MJCF bodies with joints and inertials.

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
has no body (``body_of_link[p] == -1``); :meth:`~urdf2links.compare.mujoco_side.mjcf_model.MjcfModel.link_poses` still gives its pose, and
loads on it are mapped with the host body's Jacobian restricted to the folded link's own joints
and those before it (see :mod:`urdf2links.compare.mujoco_side.mujoco_run`).

Moving base ``{A}`` (``moving_base=True``): a root body ``base_A`` at the world origin with three
slide joints along the world axes then three hinges about x, y, z of its own (moving) frame,
``Trans(x, y, z) Rx Ry Rz`` = ``0_A T`` of (E13) exactly; its qpos are the six base parameters.
It has a small mass (``BASE_MASS_FRACTION`` of the robot's); its motion is prescribed by
:func:`urdf2links.compare.mujoco_side.mujoco_run.run_mujoco`, so the mass does not enter the robot's motion.
"""

from __future__ import annotations

import math
from xml.sax.saxutils import quoteattr

import mujoco
import numpy as np

from urdf2links.dynamics.inertia import inertial_from_pseudo
from urdf2links.dynamics.transforms import PARAMETERS, elementary

__all__ = ["Bodies", "fold_links", "fold_notes", "route1_armature", "num", "vec", "unique_name", "BASE_BODY",
           "BASE_JOINTS", "TINY_MASS_FRACTION", "BASE_MASS_FRACTION"]

#: Name of the body that carries the moving base {A} and its joints (x, y, z, phi_x, phi_y, phi_z).
BASE_BODY = "base_A"
BASE_JOINTS = tuple(f"{BASE_BODY}:{s}" for s in PARAMETERS)
#: Mass of an unfoldable massless moving link, as a fraction of the robot's total mass.
TINY_MASS_FRACTION = 1e-12
#: Mass of the ``base_A`` body as a fraction of the robot's total mass (its motion is prescribed).
BASE_MASS_FRACTION = 1e-3


def num(x) -> str:
    x = float(x)
    if not math.isfinite(x):
        raise ValueError(f"non-finite number {x!r} in the MJCF model")
    return "0" if x == 0.0 else repr(x)


def vec(v) -> str:
    return " ".join(num(x) for x in v)


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


def unique_name(name: str, taken: set[str]) -> str:
    out = name
    while out in taken:
        out = out + "_"
    taken.add(out)
    return out


def fold_links(tree, massless) -> tuple[list[bool], list[str]]:
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


class Bodies:
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
        bname = unique_name(tree.link_names[p], self.taken)
        if bname != tree.link_names[p]:
            self.notes.append(f"link {tree.link_names[p]!r} is MuJoCo body {bname!r} (name taken)")
        self.body_name_of[p] = bname
        gc = f' gravcomp="{num(self.gravcomp[p])}"' if self.gravcomp.get(p) else ""
        lines.append(f'{indent}<body name={quoteattr(bname)} pos="{vec(M[:3, 3])}" quat="{vec(_quat(M[:3, :3]))}"{gc}>')
        ind = indent + "  "
        if not self.massless[p]:
            m, com, I = inertial_from_pseudo(tree.H[p])
            I = 0.5 * (I + I.T)
            full = (I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2])
            lines.append(f'{ind}<inertial pos="{vec(com)}" mass="{num(m)}" fullinertia="{vec(full)}"/>')
        elif joints:
            self.tiny_links.append(tree.link_names[p])
            lines.append(f'{ind}<inertial pos="0 0 0" mass="{num(self.tiny)}" '
                         f'diaginertia="{vec([self.tiny] * 3)}"/>')
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
            extra = f' stiffness="{num(s.stiffness)}" springref="{num(s.rest)}" damping="{num(s.damping)}"'
        if self.armature[c] != 0.0:
            extra += f' armature="{num(self.armature[c])}"'
        pos = f' pos="{vec(anchor)}"' if kind == "hinge" and np.any(anchor != 0.0) else ""
        return f'<joint name={quoteattr(cname)} type="{kind}" axis="{vec(axis)}"{pos}{extra}/>'

    def write(self, *, moving_base: bool, total_mass: float) -> tuple[tuple[str, ...], str | None]:
        """Every body's lines, under the prescribed base {A} (``moving_base``) or under the world:
        ``(the base's joint names, the base's body name)``, empty and None without the base."""
        if not moving_base:
            for r in self.top():
                self.emit(r, "    ")
            return (), None
        bm = BASE_MASS_FRACTION * max(total_mass, 1.0)
        taken_joints: set[str] = set(self.names)
        joint_names = tuple(unique_name(j, taken_joints) for j in BASE_JOINTS)
        bname = self.base_body(bm, joint_names, "    ")
        self.notes.append(f"moving base: body {bname!r} (mass {bm:.3g} kg) with slides x, y, z along the world "
                          "axes then hinges about its own x, y, z: Trans(x, y, z) Rx Ry Rz = 0_A T "
                          "(docs/equations.md (E13)); "
                          "its motion is prescribed by run_mujoco (qfrc_applied from mjcb_control)")
        return joint_names, bname

    def base_body(self, bm: float, joint_names, indent: str) -> str:
        """The prescribed base {A}: a body with slides x, y, z and hinges about x, y, z, the tree inside."""
        bname = unique_name(BASE_BODY, self.taken)
        self.lines.append(f'{indent}<body name={quoteattr(bname)} pos="0 0 0">')
        self.lines.append(f'{indent}  <inertial pos="0 0 0" mass="{num(bm)}" diaginertia="{vec([bm] * 3)}"/>')
        for k, jn in enumerate(joint_names):
            axis = np.eye(3)[k % 3]
            self.lines.append(f'{indent}  <joint name={quoteattr(jn)} type="{"slide" if k < 3 else "hinge"}" '
                              f'axis="{vec(axis)}"/>')
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



def fold_notes(tree, folded, too_many, tiny_links, tiny) -> list[str]:
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

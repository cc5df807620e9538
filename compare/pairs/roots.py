"""Where each description puts its robot: the roots' pose difference, taken out once before anything is compared.

Two files of one robot may place it differently in their worlds: an MJCF mounts a hand with
``quat="0 1 0 1"``, gives a floating base its initial yaw (``quat="0 0 0 1"``), or lifts a fixed arm
onto a table. None of that is a difference of the robot's parts, and compared in the world it would
turn every axis below (sign flips that are not there). So both descriptions are compared in the frame
of their **root pair**: the topmost pair of bodies both have (:func:`match_bodies`: the bodies of
matched joints, then equal names; the first in the first description's tree order with no matched
ancestor). The alignment ``D = W_urdf(root) W_mjcf(root)^-1`` (4, 4) (docs/equations.md (E63)) carries
the second description's world into the first's; every world pose of the second is compared as
``D W_mjcf``. ``D`` itself is reported once, as kind ``root_pose``:

- a **fixed** root's mount (a body welded to the world, placed differently) is one description
  difference: undoing it (``D`` applied to every top-level body of the second) is what it does to
  ``G`` (gravity turned relative to the robot) and ``A``;
- a **floating** root's pose at home (a free joint's initial ``qpos``) is a state, not a description
  difference: both descriptions are evaluated and run from the same state (the free joint's
  coordinates map with offset 0, :func:`urdf2links.compare.pairs.mapping.coordinate_map`), so it changes
  nothing, and it is listed once, so that a user sees where the files start.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from urdf2links.dynamics.rotations import matrix_to_rpy, matrix_to_xyz_angles
from urdf2links.dynamics.transforms import link_transform
from urdf2links.parsers.mjcf_state import matrix_to_quat
from urdf2links.parsers.parts import RobotParts, home_poses

__all__ = ["RootPair", "match_bodies", "root_pair", "fixed_root", "paired_bodies", "alignment", "is_free_root", "align_second", "pose_words"]


@dataclass(frozen=True)
class RootPair:
    """The topmost pair of bodies both descriptions have (``urdf``, ``mjcf`` body names; None when no body
    pairs), and whether each is a floating root (a free joint on a top-level body)."""

    urdf: str | None
    mjcf: str | None
    floating: tuple[bool, bool] = (False, False)

    def to_json(self) -> dict:
        return {"urdf": self.urdf, "mjcf": self.mjcf, "floating": list(self.floating)}


def _last_joint_body(parts: RobotParts) -> dict[str, str]:
    """Joint -> its body, for joints that are their body's last (whose tree link the body's mass is in)."""
    return {b.joints[-1].name: b.name for b in parts.bodies if b.joints}


def match_bodies(U: RobotParts, M: RobotParts, pairs) -> dict[str, str]:
    """``{first's body: second's body}``: the bodies whose last joints ``pairs`` (``[(urdf joint, mjcf joint)]``)
    match, then the bodies of equal names not taken."""
    lu, lm = _last_joint_body(U), _last_joint_body(M)
    out = {}
    for a, b in pairs:
        if a in lu and b in lm:
            out[lu[a]] = lm[b]
    taken = set(out.values())
    names_m = {b.name for b in M.bodies}
    for b in U.bodies:
        if b.name not in out and b.name in names_m and b.name not in taken:
            out[b.name] = b.name
            taken.add(b.name)
    return out


def is_free_root(parts: RobotParts, body: str | None) -> bool:
    """``body`` is a top-level body moved by a free joint (a floating base)."""
    if body is None:
        return False
    b = parts.body(body)
    return b.parent is None and len(b.joints) == 1 and b.joints[0].kind == "free"


def _ancestors(parts: RobotParts, body: str) -> list[str]:
    """``body`` and every body above it, nearest first."""
    parent = {b.name: b.parent for b in parts.bodies}
    out = [body]
    while parent[out[-1]] is not None:
        out.append(parent[out[-1]])
    return out


def fixed_root(parts: RobotParts) -> str | None:
    """The deepest body above (or at) every moving body when neither it nor a body above it has a joint: the
    body the robot is fixed by (a hand's palm, a fixed humanoid's pelvis, an arm's base); None when a joint
    moves it (a floating base, a chain whose first body moves) or nothing moves."""
    common = None
    for b in parts.bodies:
        if b.joints:
            a = _ancestors(parts, b.name)
            common = a if common is None else [x for x in common if x in a]
    if not common:
        return None
    if any(parts.body(x).joints for x in common):
        return None
    return common[0]


def root_pair(U: RobotParts, M: RobotParts, bodies: dict) -> RootPair:
    """The root pair (module doc): the topmost matched pair of ``bodies`` when it sits at or above both
    sides' fixed roots (or either side has none), else the fixed roots (unless ``bodies`` pairs either of
    them with another body: then the names' pair stands)."""
    top = _topmost(U, M, bodies)
    fu, fm = fixed_root(U), fixed_root(M)
    if fu is None or fm is None:
        return top
    if top.urdf is not None and top.urdf in _ancestors(U, fu) and top.mjcf in _ancestors(M, fm):
        return top
    if bodies.get(fu, fm) != fm or any(v == fm and k != fu for k, v in bodies.items()):
        return top
    return RootPair(fu, fm, (False, False))


def _topmost(U: RobotParts, M: RobotParts, bodies: dict) -> RootPair:
    """The first matched body of ``bodies`` in the first description's tree order with no matched ancestor."""
    parent = {b.name: b.parent for b in U.bodies}
    for b in U.bodies:
        if b.name not in bodies:
            continue
        p = parent[b.name]
        while p is not None and p not in bodies:
            p = parent[p]
        if p is None:
            rm = bodies[b.name]
            return RootPair(b.name, rm, (is_free_root(U, b.name), is_free_root(M, rm)))
    return RootPair(None, None)


def paired_bodies(U: RobotParts, M: RobotParts, pairs, root: RootPair | None = None) -> dict[str, str]:
    """:func:`match_bodies` with the root pair added (``root``; by :func:`root_pair` when None): the bodies
    both descriptions have, the roots among them even when their names differ."""
    bodies = match_bodies(U, M, pairs)
    root = root_pair(U, M, bodies) if root is None else root
    if root.urdf is not None and root.urdf not in bodies and root.mjcf not in bodies.values():
        bodies[root.urdf] = root.mjcf
    return bodies


def alignment(U: RobotParts, M: RobotParts, root: RootPair | None, WU=None, WM=None) -> np.ndarray:
    """``D`` (4, 4) (E63): the second description's world into the first's, so that the root pair coincides
    (the identity without one). ``WU``, ``WM``: the home poses when already computed."""
    if root is None or root.urdf is None:
        return np.eye(4)
    WU = home_poses(U) if WU is None else WU
    WM = home_poses(M) if WM is None else WM
    return WU[root.urdf] @ np.linalg.inv(WM[root.mjcf])


def align_second(M: RobotParts, D) -> RobotParts:
    """``M`` with its world carried by ``D`` (4, 4): every top-level body's pose (a floating root's free
    joint at home) replaced by ``D`` times it: the undo of ``root_pose``."""
    D = np.asarray(D, float)
    bodies = []
    for b in M.bodies:
        if b.parent is None:
            if len(b.joints) == 1 and b.joints[0].kind == "free":
                F = D @ link_transform(np.asarray(b.joints[0].home, float))
                home = tuple(np.r_[F[:3, 3], matrix_to_xyz_angles(F[:3, :3])])
                b = _replace(b, joints=(_replace(b.joints[0], home=home),))
            else:
                b = _replace(b, pose=D @ np.asarray(b.pose, float))
        bodies.append(b)
    return _replace(M, bodies=tuple(bodies))


def _replace(obj, **changes):
    from dataclasses import replace

    return replace(obj, **changes)


def pose_words(W, fmt: str) -> str:
    """A pose (4, 4) in a file's own terms: ``xyz="..." rpy="..."`` (URDF) or ``pos="..." quat="..."`` (MJCF)."""
    W = np.asarray(W, float)
    p = " ".join(f"{x:.6g}" for x in np.where(np.abs(W[:3, 3]) < 5e-13, 0.0, W[:3, 3]))
    if fmt == "urdf":
        r = " ".join(f"{x:.6g}" for x in np.where(np.abs(matrix_to_rpy(W[:3, :3])) < 5e-13, 0.0,
                                                   matrix_to_rpy(W[:3, :3])))
        return f'xyz="{p}" rpy="{r}"'
    q = np.asarray(matrix_to_quat(W[:3, :3]), float)
    q = -q if q[0] < 0 else q
    return f'pos="{p}" quat="' + " ".join(f"{x:.6g}" for x in np.where(np.abs(q) < 5e-13, 0.0, q)) + '"'

"""States in MuJoCo's terms for a model read from MJCF: ``qpos``/``qvel`` to and from the project's ``q``/``q'``.

MuJoCo's state is ``qpos`` (nq,) and ``qvel`` (nv,), in the compiled file's joint order. The
project's coordinates of a model loaded by :func:`urdf2links.parsers.mjcf.load_mjcf` follow the same
joints in the same order (docs/equations.md (E50)):

- hinge, slide: one coordinate, **equal to MuJoCo's qpos** (``ref`` included: the tree's offset is
  ``-ref``, so ``q = qpos0`` is the compiled pose); ``qvel = q'``;
- ball: three ZYX angles ``<joint>.phi_x, .phi_y, .phi_z`` with ``Rx Ry Rz(phi) = R(quat)`` (the
  body's rotation about the anchor relative to its pose at the identity quaternion); ``qvel`` is the
  angular velocity in the body's axes, ``omega = E(phi) phi'`` (E43);
- free: six coordinates ``<joint>.x, .y, .z`` (the body origin in the world, MuJoCo's
  ``qpos[0:3]``) and three ZYX angles of ``quat``; ``qvel = (x', y', z', E(phi) phi')``: world
  linear velocity, then body-frame angular velocity.

So ``qvel = J(q) q'`` with ``J`` block-diagonal (1, ``E``, or ``diag(1, E)``), and the project's
equations are MuJoCo's transformed: ``A = J^T M J``, ``e + G = J^T (c + M J' q')`` (``M`` MuJoCo's
``mj_fullM``, ``c`` its ``qfrc_bias``), which is how the comparison maps MuJoCo's terms
(:meth:`MujocoMap.jacobian`, :meth:`MujocoMap.jacobian_rate`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..dynamics.rotations import matrix_to_xyz_angles, xyz_angles_to_matrix

__all__ = ["MujocoJoint", "MujocoMap", "quat_to_matrix", "matrix_to_quat", "rate_matrix", "rate_matrix_dot"]


def quat_to_matrix(qw) -> np.ndarray:
    """Rotation (3, 3) of a unit quaternion ``(w, x, y, z)`` (MuJoCo's order; normalised first)."""
    w, x, y, z = np.asarray(qw, float) / np.linalg.norm(qw)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def matrix_to_quat(R) -> np.ndarray:
    """Unit quaternion ``(w, x, y, z)`` with ``w >= 0`` of a rotation (3, 3) (Shepperd's method)."""
    R = np.asarray(R, float)
    t = np.trace(R)
    if t > 0:
        s = 2.0 * math.sqrt(1.0 + t)
        q = np.array([0.25 * s, (R[2, 1] - R[1, 2]) / s, (R[0, 2] - R[2, 0]) / s, (R[1, 0] - R[0, 1]) / s])
    else:
        i = int(np.argmax(np.diag(R)))
        j, k = (i + 1) % 3, (i + 2) % 3
        s = 2.0 * math.sqrt(max(1.0 + R[i, i] - R[j, j] - R[k, k], 0.0))
        q = np.empty(4)
        q[0] = (R[k, j] - R[j, k]) / s
        q[1 + i] = 0.25 * s
        q[1 + j] = (R[j, i] + R[i, j]) / s
        q[1 + k] = (R[k, i] + R[i, k]) / s
    q /= np.linalg.norm(q)
    return q if q[0] >= 0 else -q


def rate_matrix(phi) -> np.ndarray:
    """``E(phi)`` (3, 3) of (E43): ``omega = E phi'`` in the link's own axes for ``R = Rx Ry Rz(phi)``."""
    _, b, c = phi
    cb, sb, cc, sc = math.cos(b), math.sin(b), math.cos(c), math.sin(c)
    return np.array([[cb * cc, sc, 0.0], [-cb * sc, cc, 0.0], [sb, 0.0, 1.0]])


def rate_matrix_dot(phi, phid) -> np.ndarray:
    """``dE/dt`` (3, 3) at ``(phi, phi')``."""
    _, b, c = phi
    _, bd, cd = phid
    cb, sb, cc, sc = math.cos(b), math.sin(b), math.cos(c), math.sin(c)
    return np.array([[-sb * cc * bd - cb * sc * cd, cc * cd, 0.0],
                     [sb * sc * bd - cb * cc * cd, -sc * cd, 0.0],
                     [cb * bd, 0.0, 0.0]])


@dataclass(frozen=True)
class MujocoJoint:
    """One MuJoCo joint: ``name``, ``kind`` (``hinge``, ``slide``, ``ball``, ``free``), its ``qpos``
    and ``qvel`` addresses and the project's coordinate indices (1, 3 or 6, in slot order)."""

    name: str
    kind: str
    qposadr: int
    dofadr: int
    coordinates: tuple[int, ...]


def _nearest(angles, reference) -> np.ndarray:
    """Of the two ZYX branches of one rotation (E7), plus multiples of 2 pi, the one nearest ``reference``."""
    a, b, c = angles
    best = None
    for cand in (np.array([a, b, c]), np.array([a + math.pi, math.pi - b, c + math.pi])):
        cand = cand + 2 * math.pi * np.round((reference - cand) / (2 * math.pi))
        if best is None or np.sum((cand - reference) ** 2) < np.sum((best - reference) ** 2):
            best = cand
    return best


@dataclass(frozen=True)
class MujocoMap:
    """The map between the project's ``(q, q')`` (n,) and MuJoCo's ``(qpos, qvel)`` (nq,), (nv,) of
    the compiled file (module doc); ``joints`` in MuJoCo's order, ``qpos0`` MuJoCo's default qpos."""

    joints: tuple[MujocoJoint, ...]
    n: int
    nq: int
    nv: int
    qpos0: np.ndarray

    def _check(self, x, size, what):
        a = np.asarray(x, float)
        if a.shape != (size,):
            raise ValueError(f"{what} must have shape ({size},); got {a.shape}")
        return a

    def to_mujoco(self, q, qd=None):
        """``(qpos, qvel)`` of the project's state (``qvel`` None when ``qd`` is None)."""
        q = self._check(q, self.n, "q")
        qd = None if qd is None else self._check(qd, self.n, "qd")
        qpos = np.array(self.qpos0, float)
        qvel = None if qd is None else np.zeros(self.nv)
        for j in self.joints:
            c = list(j.coordinates)
            if j.kind in ("hinge", "slide"):
                qpos[j.qposadr] = q[c[0]]
                if qd is not None:
                    qvel[j.dofadr] = qd[c[0]]
                continue
            lin = 3 if j.kind == "free" else 0
            if lin:
                qpos[j.qposadr:j.qposadr + 3] = q[c[:3]]
                if qd is not None:
                    qvel[j.dofadr:j.dofadr + 3] = qd[c[:3]]
            phi = q[c[lin:]]
            qpos[j.qposadr + lin:j.qposadr + lin + 4] = matrix_to_quat(xyz_angles_to_matrix(phi))
            if qd is not None:
                qvel[j.dofadr + lin:j.dofadr + lin + 3] = rate_matrix(phi) @ qd[c[lin:]]
        return qpos, qvel

    def from_mujoco(self, qpos, qvel=None, *, reference=None):
        """``(q, q')`` of MuJoCo's state. The angles of a ball or free joint are the ZYX angles of its
        quaternion (E7), on the branch nearest ``reference`` (n,) when given (either branch, plus
        multiples of 2 pi), their rates ``E(phi)^-1 omega`` (infinite at ``|cos phi_y| = 0``)."""
        qpos = self._check(qpos, self.nq, "qpos")
        qvel = None if qvel is None else self._check(qvel, self.nv, "qvel")
        ref = None if reference is None else self._check(reference, self.n, "reference")
        q = np.zeros(self.n)
        qd = None if qvel is None else np.zeros(self.n)
        for j in self.joints:
            c = list(j.coordinates)
            if j.kind in ("hinge", "slide"):
                q[c[0]] = qpos[j.qposadr]
                if qvel is not None:
                    qd[c[0]] = qvel[j.dofadr]
                continue
            lin = 3 if j.kind == "free" else 0
            if lin:
                q[c[:3]] = qpos[j.qposadr:j.qposadr + 3]
                if qvel is not None:
                    qd[c[:3]] = qvel[j.dofadr:j.dofadr + 3]
            phi = matrix_to_xyz_angles(quat_to_matrix(qpos[j.qposadr + lin:j.qposadr + lin + 4]))
            if ref is not None:
                phi = _nearest(phi, ref[c[lin:]])
            q[c[lin:]] = phi
            if qvel is not None:
                try:
                    qd[c[lin:]] = np.linalg.solve(rate_matrix(phi), qvel[j.dofadr + lin:j.dofadr + lin + 3])
                except np.linalg.LinAlgError:
                    qd[c[lin:]] = math.inf
        return q, qd

    def jacobian(self, q) -> np.ndarray:
        """``J`` (nv, n): ``qvel = J(q) q'`` (module doc)."""
        q = self._check(q, self.n, "q")
        J = np.zeros((self.nv, self.n))
        for j in self.joints:
            c = list(j.coordinates)
            lin = 3 if j.kind == "free" else 0
            if j.kind in ("hinge", "slide"):
                J[j.dofadr, c[0]] = 1.0
                continue
            for k in range(lin):
                J[j.dofadr + k, c[k]] = 1.0
            J[np.ix_(range(j.dofadr + lin, j.dofadr + lin + 3), c[lin:])] = rate_matrix(q[c[lin:]])
        return J

    def jacobian_rate(self, q, qd) -> np.ndarray:
        """``J' q'`` (nv,): the part of MuJoCo's ``qacc`` that the project's ``q'`` carries at ``q'' = 0``."""
        q, qd = self._check(q, self.n, "q"), self._check(qd, self.n, "qd")
        out = np.zeros(self.nv)
        for j in self.joints:
            if j.kind in ("hinge", "slide"):
                continue
            lin = 3 if j.kind == "free" else 0
            c = list(j.coordinates)[lin:]
            out[j.dofadr + lin:j.dofadr + lin + 3] = rate_matrix_dot(q[c], qd[c]) @ qd[c]
        return out

"""Rotation matrices and the conversion between URDF ``rpy`` and the project's ZYX angles.

Two angle conventions meet in this project (docs/equations.md (E3), (E6), (E7)):

* URDF ``rpy = (roll, pitch, yaw)``: ``R = Rz(yaw) Ry(pitch) Rx(roll)``
  (:func:`rpy_to_matrix`).
* The ZYX angles, a link's parameters ``(phi_x, phi_y, phi_z)``: ``R = Rx(phi_x) Ry(phi_y) Rz(phi_z)``,
  i.e. ``T4 T5 T6`` of (E1), (E3), the trace method's "ZYX Euler angles" (:func:`matrix_to_xyz_angles`).

All functions are pure, take array-likes and return new ``float`` arrays. Matrices are
``(3, 3)`` rotations or ``(4, 4)`` homogeneous transforms acting on column vectors.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import URDFValueError

__all__ = [
    "rot_x",
    "rot_y",
    "rot_z",
    "rpy_to_matrix",
    "matrix_to_xyz_angles",
    "matrix_to_rpy",
    "xyz_angles_to_matrix",
    "rpy_to_xyz_angles",
    "axis_alignment",
    "homogeneous",
]


def rot_x(a: float) -> np.ndarray:
    """Rotation by angle ``a`` (rad) about the x axis, ``(3, 3)``: ``T4`` of (E1)."""
    c, s = math.cos(a), math.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rot_y(a: float) -> np.ndarray:
    """Rotation by angle ``a`` (rad) about the y axis, ``(3, 3)``: ``T5`` of (E1)."""
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rot_z(a: float) -> np.ndarray:
    """Rotation by angle ``a`` (rad) about the z axis, ``(3, 3)``: ``T6`` of (E1)."""
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _vector3(value, name: str) -> np.ndarray:
    v = np.asarray(value, dtype=float)
    if v.shape != (3,):
        raise URDFValueError(f"{name} must have 3 components, got shape {v.shape}: {value!r}")
    if not np.all(np.isfinite(v)):
        raise URDFValueError(f"{name} must be finite, got {v.tolist()}")
    return v


def rpy_to_matrix(rpy) -> np.ndarray:
    """URDF ``rpy`` to a rotation matrix.

    Parameters
    ----------
    rpy : array_like, shape (3,)
        ``(roll, pitch, yaw)`` in radians, as in ``<origin rpy="...">``.

    Returns
    -------
    R : ndarray, shape (3, 3)
        ``Rz(yaw) @ Ry(pitch) @ Rx(roll)`` (fixed axes x, then y, then z).
    """
    roll, pitch, yaw = _vector3(rpy, "rpy")
    return rot_z(yaw) @ rot_y(pitch) @ rot_x(roll)


def xyz_angles_to_matrix(angles) -> np.ndarray:
    """ZYX angles (E3) to a matrix: ``Rx(phi_x) @ Ry(phi_y) @ Rz(phi_z)``, shape (3, 3)."""
    ax, ay, az = _vector3(angles, "angles (phi_x, phi_y, phi_z)")
    return rot_x(ax) @ rot_y(ay) @ rot_z(az)


# Below this value of cos(phi_y) the matrix is treated as exactly in gimbal lock. With
# cos(phi_y) = 0 only phi_x + phi_z (or phi_z - phi_x) is determined; a floating-point
# matrix built with pitch = pi/2 has cos(phi_y) ~ 6e-17 and phi_x would be noise. The
# choice phi_z = 0 made below changes the reconstructed matrix by at most about
# cos(phi_y) * 2 pi, i.e. < 1e-14, so the threshold costs no accuracy; above it phi_x is
# solved from the entries and every error it carries is multiplied by cos(phi_y).
_GIMBAL_COS = 1e-15


def matrix_to_xyz_angles(R) -> tuple[float, float, float]:
    """Angles ``(phi_x, phi_y, phi_z)`` with ``Rx(phi_x) @ Ry(phi_y) @ Rz(phi_z) == R``.

    Parameters
    ----------
    R : array_like, shape (3, 3)
        A rotation matrix (orthonormal, det +1; not checked beyond shape and finiteness).

    Returns
    -------
    phi_x, phi_y, phi_z : float
        ``phi_y`` in ``[-pi/2, pi/2]`` (the branch with ``cos(phi_y) >= 0``), ``phi_x`` and
        ``phi_z`` in ``(-pi, pi]``.

    Notes
    -----
    With ``c = cos``, ``s = sin``::

        R = [[ cy cz,             -cy sz,             sy   ],
             [ cx sz + sx sy cz,   cx cz - sx sy sz,  -sx cy],
             [ sx sz - cx sy cz,   sx cz + cx sy sz,   cx cy]]

    ``phi_y = atan2(r02, hypot(r00, r01))`` is accurate at every pitch (no ``asin`` of a
    number near 1). ``phi_x = atan2(-r12, r22)``; then ``phi_z`` is solved from the
    residual ``Ry(phi_y)^T Rx(phi_x)^T R`` (a rotation about z), so that whatever error
    ``phi_x`` carries near gimbal lock is compensated in ``phi_z`` and the product
    reproduces ``R`` to rounding error.

    Gimbal lock (``cos(phi_y) < 1e-15``, e.g. pitch exactly ``+-pi/2``): the choice is
    ``phi_z = 0`` and ``phi_x`` is solved from the residual ``R Ry(phi_y)^T = Rx(phi_x)``.
    """
    M = np.asarray(R, dtype=float)
    if M.shape != (3, 3):
        raise URDFValueError(f"rotation matrix must be 3x3, got shape {M.shape}")
    if not np.all(np.isfinite(M)):
        raise URDFValueError(f"rotation matrix must be finite, got {M.tolist()}")
    cy = math.hypot(M[0, 0], M[0, 1])
    phi_y = math.atan2(M[0, 2], cy)
    if cy < _GIMBAL_COS:
        phi_z = 0.0
        N = M @ rot_y(phi_y).T  # = Rx(phi_x)
        phi_x = math.atan2(N[2, 1], N[1, 1])
    else:
        phi_x = math.atan2(-M[1, 2], M[2, 2])
        N = rot_y(phi_y).T @ rot_x(phi_x).T @ M  # = Rz(phi_z)
        phi_z = math.atan2(N[1, 0], N[0, 0])
    return phi_x, phi_y, phi_z


def matrix_to_rpy(R) -> tuple[float, float, float]:
    """URDF ``(roll, pitch, yaw)`` with ``Rz(yaw) @ Ry(pitch) @ Rx(roll) == R``: since
    ``R^T = Rx(-roll) Ry(-pitch) Rz(-yaw)``, minus the angles of ``R^T`` (:func:`matrix_to_xyz_angles`)."""
    a = matrix_to_xyz_angles(np.asarray(R, dtype=float).T)
    return -a[0], -a[1], -a[2]


def rpy_to_xyz_angles(rpy) -> tuple[float, float, float]:
    """URDF ``rpy`` to the ZYX angles ``(phi_x, phi_y, phi_z)``: the same rotation, other sequence.

    ``xyz_angles_to_matrix(rpy_to_xyz_angles(rpy)) == rpy_to_matrix(rpy)`` to rounding error,
    including at pitch ``+-pi/2`` (see :func:`matrix_to_xyz_angles`).
    """
    return matrix_to_xyz_angles(rpy_to_matrix(rpy))


def axis_alignment(axis) -> np.ndarray:
    """A proper rotation ``Ra`` that carries ``e_z`` onto the unit vector along ``axis``.

    Used to make a URDF joint axis the z axis of a link frame: with ``u = axis/|axis|``,
    ``Rot(u, q) = Ra @ rot_z(q) @ Ra.T`` exactly.

    Parameters
    ----------
    axis : array_like, shape (3,)
        Any non-zero finite direction (need not be normalized).

    Returns
    -------
    Ra : ndarray, shape (3, 3)
        Orthonormal, ``det(Ra) = +1``, last column ``u``.

    Raises
    ------
    URDFValueError
        If ``axis`` is not 3 finite numbers or ``|axis| < 1e-12``.

    Notes
    -----
    The columns are the orthonormal basis of Duff et al., "Building an orthonormal basis,
    revisited" (JCGT 2017): with ``s = +1`` if ``u_z >= 0`` else ``-1`` and
    ``a = -1/(s + u_z)``, ``b = u_x u_y a``::

        Ra = [[1 + s u_x^2 a,  b,            u_x],
              [s b,            s + u_y^2 a,  u_y],
              [-s u_x,         -u_y,         u_z]]

    The only division is by ``s + u_z``, whose magnitude is at least 1, so every direction
    (coordinate axes, negative and skewed axes, axes nearly along ``+-z``) is equally well
    conditioned; the result is a deterministic function of ``u``. For ``u_z >= 0`` it is the
    shortest-arc rotation from ``e_z`` to ``u`` (identity for ``+z``, ``Ry(pi/2)`` for ``+x``,
    ``Rx(-pi/2)`` for ``+y``); for ``u_z < 0`` it is the shortest-arc rotation from ``-e_z`` to
    ``u`` composed with ``Rx(pi)`` (``Rx(pi)`` itself for ``-z``).
    """
    v = np.asarray(axis, dtype=float)
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise URDFValueError(f"joint axis must be 3 finite numbers, got {np.asarray(axis).tolist()!r}")
    n = float(np.linalg.norm(v))
    if n < 1e-12:
        raise URDFValueError(
            f"joint axis {v.tolist()} has length {n:.3g} < 1e-12; give a non-zero direction"
        )
    x, y, z = v / n
    s = 1.0 if z >= 0.0 else -1.0
    a = -1.0 / (s + z)
    b = x * y * a
    return np.array(
        [
            [1.0 + s * x * x * a, b, x],
            [s * b, s + y * y * a, y],
            [-s * x, -y, z],
        ]
    )


def homogeneous(R, p) -> np.ndarray:
    """Homogeneous transform ``[[R, p], [0, 0, 0, 1]]``, shape (4, 4), from ``R`` (3, 3) and ``p`` (3,)."""
    R = np.asarray(R, dtype=float)
    p = np.asarray(p, dtype=float)
    if R.shape != (3, 3) or p.shape != (3,):
        raise URDFValueError(f"homogeneous needs R (3, 3) and p (3,), got {R.shape} and {p.shape}")
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = p
    return T

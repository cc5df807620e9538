"""A floating base's pose in a log (motion capture or a state estimator), as the project's floating
coordinates.

A floating root has six coordinates ``x, y, z, phi_x, phi_y, phi_z`` (:data:`BASE_SLOTS`): its origin in
the world and its ZYX angles, ``R = Rx(phi_x) Ry(phi_y) Rz(phi_z)`` (docs/equations.md (E3)). A log holds
the pose as a position and a unit quaternion (ROS: ``nav_msgs/msg/Odometry`` or
``geometry_msgs/msg/PoseStamped``; a table: the columns ``base.x``, ``base.y``, ``base.z``, ``base.qw``,
``base.qx``, ``base.qy``, ``base.qz``). :func:`base_coordinates` interpolates it at the joint samples'
times (linearly, and by slerp), turns it into the six coordinates with the angles unwrapped, and refuses
what cannot be: a quaternion that is not of unit norm (the row named), a pitch so close to +-90 degrees
that the ZYX angles' rates are meaningless (the time named), times outside the topic's range.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation, Slerp

from ..dynamics.rotations import matrix_to_xyz_angles
from .errors import LogError, LogFormatError
from .log import require_increasing

__all__ = ["BASE_SLOTS", "BASE_COLUMNS", "BasePoses", "base_coordinates", "QUATERNION_TOLERANCE", "GIMBAL_COS"]

BASE_SLOTS = ("x", "y", "z", "phi_x", "phi_y", "phi_z")
#: A table's base columns: position, then the quaternion w, x, y, z.
BASE_COLUMNS = ("base.x", "base.y", "base.z", "base.qw", "base.qx", "base.qy", "base.qz")
#: | |quaternion| - 1 | above this is an error (a log's quaternions are normalised to float32 at worst).
QUATERNION_TOLERANCE = 1e-3
#: cos(phi_y) below this (pitch within 1.1 degrees of +-90) is an error: the ZYX rates blow up there.
GIMBAL_COS = 0.02


@dataclass(frozen=True)
class BasePoses:
    """The base's poses as logged: ``source`` (the topic, or "columns"), ``frame`` (the world frame's
    name, when the log says it), ``times`` (B,) in the log's seconds, ``positions`` (B, 3) m,
    ``quaternions`` (B, 4) as w, x, y, z, and ``rows`` (B,) each pose's row or message in the file."""

    source: str
    frame: str
    times: np.ndarray
    positions: np.ndarray
    quaternions: np.ndarray
    rows: np.ndarray

    def check(self, log_source: str) -> None:
        """Increasing times, finite values and unit quaternions; the first bad row named."""
        if self.source != "columns":        # a table's rows are the joints' samples, checked with them
            require_increasing(self.times, what=f"the base poses of {self.source}", source=log_source,
                               topic=self.source)
        bad = np.flatnonzero(~np.all(np.isfinite(self.positions), axis=1) | ~np.all(np.isfinite(self.quaternions),
                                                                                        axis=1))
        norm = np.linalg.norm(self.quaternions, axis=1)
        off = np.flatnonzero(np.abs(norm - 1.0) > QUATERNION_TOLERANCE)
        for idx, what in ((bad, "a value that is not finite"),
                          (off, "a quaternion that is not of unit norm")):
            if idx.size:
                k = int(idx[0])
                raise LogError(f"{log_source}: the base pose ({self.source}) has {what} at row {self.rows[k]} "
                               f"(t = {self.times[k]:.9g} s; |q| = {norm[k]:.6g}); the base's orientation must be "
                               "a unit quaternion w, x, y, z", source=log_source, column=self.source,
                               row=int(self.rows[k]), time=float(self.times[k]))

    def at(self, times: np.ndarray, *, source: str = "") -> tuple[np.ndarray, np.ndarray]:
        """((S, 3) positions, (S, 3, 3) rotation matrices) at ``times`` (S,): linear and slerp; no
        extrapolation (a time outside the poses' range is an error naming it)."""
        t = np.asarray(times, dtype=float)
        outside = np.flatnonzero((t < self.times[0]) | (t > self.times[-1]))
        if outside.size:
            k = int(outside[0])
            raise LogFormatError(f"{source}: the base poses ({self.source}) run from {self.times[0]:.9g} to "
                                 f"{self.times[-1]:.9g} s; sample {k + 1} at t = {t[k]:.9g} s lies outside them: "
                                 "choose a segment (--from/--to) that both cover", source=source, time=float(t[k]))
        p = np.column_stack([np.interp(t, self.times, self.positions[:, i]) for i in range(3)])
        w, x, y, z = self.quaternions.T
        rot = Rotation.from_quat(np.column_stack([x, y, z, w]))      # scipy's order is x, y, z, w
        return p, Slerp(self.times, rot)(t).as_matrix()


def base_coordinates(poses: BasePoses, times: np.ndarray, *, source: str = "") -> np.ndarray:
    """(S, 6) the floating coordinates :data:`BASE_SLOTS` at ``times`` (S,), the angles unwrapped over
    time (module doc for what is refused)."""
    poses.check(source)
    p, R = poses.at(times, source=source)
    ang = np.array([matrix_to_xyz_angles(r) for r in R]).reshape(-1, 3)
    cos_y = np.cos(ang[:, 1])
    near = np.flatnonzero(cos_y < GIMBAL_COS)
    if near.size:
        k = int(near[0])
        raise LogError(f"{source}: the base's pitch phi_y reaches {np.degrees(ang[k, 1]):.3f} degrees at t = "
                       f"{times[k]:.9g} s; the ZYX angles of a floating base have no meaningful rates within "
                       f"{np.degrees(np.arccos(GIMBAL_COS)):.1f} degrees of +-90: choose a segment away from it",
                       source=source, column=poses.source, time=float(times[k]))
    return np.column_stack([p, np.unwrap(ang, axis=0)])

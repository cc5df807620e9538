"""Tests of urdf2links.dynamics.rotations: URDF rpy <-> ZYX angles (docs/equations.md (E6), (E7)), axis alignment."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from urdf2links.errors import URDFValueError
from urdf2links.dynamics.rotations import (
    axis_alignment, homogeneous, matrix_to_xyz_angles, rot_x, rot_y, rot_z, rpy_to_matrix, rpy_to_xyz_angles,
    xyz_angles_to_matrix,
)

PI = math.pi
HALF = PI / 2
E_Z = np.array([0.0, 0.0, 1.0])


def rodrigues(u, q):
    """Rotation by q about the unit vector u, written independently of the module."""
    u = np.asarray(u, dtype=float) / np.linalg.norm(u)
    K = np.array([[0, -u[2], u[1]], [u[2], 0, -u[0]], [-u[1], u[0], 0]])
    return np.eye(3) + math.sin(q) * K + (1 - math.cos(q)) * K @ K


# ---------------------------------------------------------------- elementary rotations


@pytest.mark.parametrize("rot, axis", [(rot_x, 0), (rot_y, 1), (rot_z, 2)])
def test_elementary_rotations_match_rodrigues(rot, axis):
    for q in np.linspace(-4, 4, 17):
        np.testing.assert_allclose(rot(q), rodrigues(np.eye(3)[axis], q), atol=1e-15)


def test_rpy_convention_is_fixed_axes_x_then_y_then_z():
    r, p, y = 0.3, -0.4, 1.1
    np.testing.assert_allclose(rpy_to_matrix([r, p, y]), rot_z(y) @ rot_y(p) @ rot_x(r), atol=0)
    # yaw alone turns x into y
    np.testing.assert_allclose(rpy_to_matrix([0, 0, HALF]) @ [1, 0, 0], [0, 1, 0], atol=1e-15)


def test_homogeneous():
    R = rpy_to_matrix([0.1, 0.2, 0.3])
    T = homogeneous(R, [1, 2, 3])
    assert T.shape == (4, 4)
    np.testing.assert_array_equal(T[:3, :3], R)
    np.testing.assert_array_equal(T[:, 3], [1, 2, 3, 1])
    np.testing.assert_array_equal(T[3, :3], 0)


# ---------------------------------------------------------------- rpy -> xyz angles


def _check_round_trip(rpy):
    R = rpy_to_matrix(rpy)
    angles = rpy_to_xyz_angles(rpy)
    back = rot_x(angles[0]) @ rot_y(angles[1]) @ rot_z(angles[2])
    err = np.abs(back - R).max()
    assert err < 1e-12, (rpy, angles, err)
    assert -HALF <= angles[1] <= HALF
    return err


def test_round_trip_random_angles():
    rng = np.random.default_rng(20240611)
    rpys = rng.uniform(-PI, PI, size=(1000, 3))
    worst = max(_check_round_trip(rpy) for rpy in rpys)
    assert worst < 1e-14  # in practice a few ulps


DEGENERATE_VALUES = [0.0, HALF, -HALF, PI, -PI, HALF + 1e-9, HALF - 1e-9, -HALF + 1e-9, -HALF - 1e-9, 0.7, -2.3]


@pytest.mark.parametrize("pitch", [HALF, -HALF, HALF + 1e-9, HALF - 1e-9, -HALF + 1e-9, -HALF - 1e-9, 0.0, PI, -PI])
def test_round_trip_degenerate_pitch(pitch):
    for roll, yaw in itertools.product(DEGENERATE_VALUES, repeat=2):
        _check_round_trip([roll, pitch, yaw])


def test_round_trip_multiples_of_half_pi():
    for k in itertools.product(range(-4, 5), repeat=3):
        _check_round_trip(np.array(k) * HALF)


@pytest.mark.parametrize("phi_y", [HALF, -HALF, HALF - 1e-9, -HALF + 1e-9, HALF - 1e-14, HALF - 1e-17])
def test_reference_gimbal_lock_matrices(phi_y):
    """Matrices built directly in the ZYX-angle sequence Rx Ry Rz with phi_y at or near +-pi/2."""
    rng = np.random.default_rng(7)
    for ax, az in itertools.chain(rng.uniform(-PI, PI, size=(50, 2)), itertools.product([0, HALF, -PI, 1.0], repeat=2)):
        R = rot_x(ax) @ rot_y(phi_y) @ rot_z(az)
        a = matrix_to_xyz_angles(R)
        np.testing.assert_allclose(xyz_angles_to_matrix(a), R, rtol=0, atol=1e-14)


def test_exact_gimbal_lock_choice_is_phi_z_zero():
    R = rot_x(0.4) @ rot_y(HALF) @ rot_z(0.5)  # only phi_x + phi_z = 0.9 is determined
    ax, ay, az = matrix_to_xyz_angles(R)
    assert az == 0.0
    assert ay == pytest.approx(HALF, abs=1e-15)
    assert ax == pytest.approx(0.9, abs=1e-14)
    R = rot_x(0.4) @ rot_y(-HALF) @ rot_z(0.5)  # only phi_z - phi_x = 0.1 is determined
    ax, ay, az = matrix_to_xyz_angles(R)
    assert (az, ax) == (0.0, pytest.approx(-0.1, abs=1e-14))


def test_regular_angles_recovered_exactly():
    for a in [(0.1, 0.2, 0.3), (-3.0, 1.5, 3.1), (2.0, -1.2, -0.5)]:
        np.testing.assert_allclose(matrix_to_xyz_angles(xyz_angles_to_matrix(a)), a, atol=1e-14)


def test_matrix_to_xyz_angles_rejects_bad_input():
    with pytest.raises(URDFValueError, match="3x3"):
        matrix_to_xyz_angles(np.eye(4))
    with pytest.raises(URDFValueError, match="finite"):
        matrix_to_xyz_angles(np.full((3, 3), np.nan))
    with pytest.raises(URDFValueError, match="rpy"):
        rpy_to_matrix([0.0, np.inf, 0.0])


# ---------------------------------------------------------------- axis alignment


def _axes_to_check():
    rng = np.random.default_rng(12345)
    axes = list(np.eye(3)) + list(-np.eye(3))
    axes += list(rng.normal(size=(300, 3)))
    axes += list(rng.normal(size=(100, 3)) * 1e-6)  # short but valid
    for eps in [1e-3, 1e-8, 1e-12, 1e-16, 1e-300]:
        for sz in (1.0, -1.0):  # nearly parallel to +z and -z
            axes += [np.array([eps, 0.0, sz]), np.array([-eps, eps, sz]), np.array([0.0, -eps, sz])]
    axes += [np.array([1.0, 1.0, 0.0]), np.array([1.0, -2.0, -0.0]), np.array([-1.0, -1.0, -1.0]), np.array([0.0, 0.0, 5.0])]
    axes += [np.array([3.0, 0.0, -1e-17]), np.array([0.0, 1.0, 1e-17])]
    return axes


def test_axis_alignment_is_rotation_mapping_ez_to_axis():
    for axis in _axes_to_check():
        Ra = axis_alignment(axis)
        u = axis / np.linalg.norm(axis)
        np.testing.assert_allclose(Ra.T @ Ra, np.eye(3), rtol=0, atol=1e-14, err_msg=str(axis))
        assert abs(np.linalg.det(Ra) - 1.0) < 1e-14, axis
        np.testing.assert_allclose(Ra @ E_Z, u, rtol=0, atol=1e-14, err_msg=str(axis))


def test_axis_alignment_conjugates_rz_into_rotation_about_axis():
    qs = [0.0, 0.3, -1.7, HALF, PI, 5.0]
    for axis in _axes_to_check():
        Ra = axis_alignment(axis)
        for q in qs:
            np.testing.assert_allclose(Ra @ rot_z(q) @ Ra.T, rodrigues(axis, q), rtol=0, atol=1e-14, err_msg=f"{axis} {q}")


def test_axis_alignment_of_coordinate_axes():
    np.testing.assert_array_equal(axis_alignment([0, 0, 1]), np.eye(3))
    np.testing.assert_allclose(axis_alignment([0, 0, -1]), rot_x(PI), atol=1e-15)
    np.testing.assert_allclose(axis_alignment([1, 0, 0]), rot_y(HALF), atol=1e-15)
    np.testing.assert_allclose(axis_alignment([0, 1, 0]), rot_x(-HALF), atol=1e-15)
    # scale does not matter, the result is deterministic
    np.testing.assert_array_equal(axis_alignment([0, 2.5, 0]), axis_alignment([0, 1, 0]))


def test_axis_alignment_is_shortest_arc_for_upper_half():
    rng = np.random.default_rng(3)
    for _ in range(100):
        u = rng.normal(size=3)
        u[2] = abs(u[2])
        u /= np.linalg.norm(u)
        angle = math.acos(np.clip(u[2], -1, 1))
        k = np.cross(E_Z, u)
        if np.linalg.norm(k) > 1e-9:
            np.testing.assert_allclose(axis_alignment(u), rodrigues(k, angle), atol=1e-14)


@pytest.mark.parametrize("bad", [[0, 0, 0], [1e-13, 0, 0], [np.nan, 0, 1], [np.inf, 0, 0], [1, 0]])
def test_axis_alignment_rejects_bad_axes(bad):
    with pytest.raises(URDFValueError, match="axis"):
        axis_alignment(bad)

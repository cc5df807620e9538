"""Every shipped robot (robots/*.urdf): loads strictly, has the documented coordinates, and its
kinematics, mass and mass matrix agree with an independent numpy reading of the URDF text.

The reference here uses only xml.etree and numpy (joint origin ``rpy`` as ``Rz(y) Ry(p) Rx(r)``,
joint axes by Rodrigues, link velocities by central differences); it shares no code with urdf2links.
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
import yourdfpy

from urdf2links import load_urdf, urdf_link_poses

ROBOTS = Path(__file__).resolve().parent.parent / "robots"
URDFS = sorted(ROBOTS.glob("*.urdf"))

# The coordinates documented in robots/README.md, with the load options they need.
EXPECTED = {
    "pendulum.urdf": ({}, ("hinge",)),
    "double_pendulum.urdf": ({}, ("shoulder", "elbow")),
    "prismatic_revolute.urdf": ({}, ("slide", "swing")),
    "free_body.urdf": ({"floating_base": True},
                       ("body.x", "body.y", "body.z", "body.phi_x", "body.phi_y", "body.phi_z")),
    "ur5_like.urdf": ({}, ("shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint",
                           "wrist_1_joint", "wrist_2_joint", "wrist_3_joint")),
    "deck_crane.urdf": ({}, ("slew", "luff", "sway_x", "sway_y")),
    "spring_arm.urdf": ({}, ("j1", "j2", "j3")),
    "quad12.urdf": ({"floating_base": True}, ('trunk.x', 'trunk.y', 'trunk.z', 'trunk.phi_x', 'trunk.phi_y', 'trunk.phi_z', 'FL_hip', 'FL_thigh', 'FL_knee', 'FR_hip', 'FR_thigh', 'FR_knee', 'RL_hip', 'RL_thigh', 'RL_knee', 'RR_hip', 'RR_thigh', 'RR_knee')),
    "biped10.urdf": ({"floating_base": True}, ('torso.x', 'torso.y', 'torso.z', 'torso.phi_x', 'torso.phi_y', 'torso.phi_z', 'L_hip_roll', 'L_hip_pitch', 'L_knee', 'L_ankle_pitch', 'L_ankle_roll', 'R_hip_roll', 'R_hip_pitch', 'R_knee', 'R_ankle_pitch', 'R_ankle_roll')),
}
SEED = 20240611
G = 9.81


def ids(paths):
    return [p.name for p in paths]


def options(path):
    assert path.name in EXPECTED, (f"{path.name} is shipped but not documented: add a section to "
                                   f"robots/README.md and an entry to EXPECTED here")
    return EXPECTED[path.name][0]


def load(path):
    return load_urdf(path, inertia="strict", **options(path))


# --------------------------------------------------------------------------- independent reference


def _floats(text, default):
    return np.array([float(v) for v in text.split()]) if text is not None else np.array(default, float)


def rpy_matrix(rpy):
    r, p, y = rpy
    Rx = np.array([[1, 0, 0], [0, np.cos(r), -np.sin(r)], [0, np.sin(r), np.cos(r)]])
    Ry = np.array([[np.cos(p), 0, np.sin(p)], [0, 1, 0], [-np.sin(p), 0, np.cos(p)]])
    Rz = np.array([[np.cos(y), -np.sin(y), 0], [np.sin(y), np.cos(y), 0], [0, 0, 1]])
    return Rz @ Ry @ Rx


def rodrigues(axis, angle):
    u = np.asarray(axis, float) / np.linalg.norm(axis)
    K = np.array([[0, -u[2], u[1]], [u[2], 0, -u[0]], [-u[1], u[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


def origin_matrix(el):
    o = el.find("origin")
    T = np.eye(4)
    if o is not None:
        T[:3, :3] = rpy_matrix(_floats(o.get("rpy"), (0, 0, 0)))
        T[:3, 3] = _floats(o.get("xyz"), (0, 0, 0))
    return T


class Reference:
    """The URDF text read with xml.etree: joints, links' inertials, forward kinematics."""

    def __init__(self, path):
        root = ET.parse(path).getroot()
        self.links = {ln.get("name"): ln for ln in root.findall("link")}
        self.joints = root.findall("joint")
        children = {j.find("child").get("link") for j in self.joints}
        (self.root,) = [name for name in self.links if name not in children]
        self.moving = [j for j in self.joints if j.get("type") != "fixed"]

    def inertials(self):
        """{link: (mass, T_com (4, 4) in the link frame, I (3, 3) about the COM in T_com's axes)}."""
        out = {}
        for name, ln in self.links.items():
            i = ln.find("inertial")
            if i is None:
                continue
            t = i.find("inertia").attrib
            I = np.array([[t["ixx"], t["ixy"], t["ixz"]], [t["ixy"], t["iyy"], t["iyz"]],
                          [t["ixz"], t["iyz"], t["izz"]]], float)
            out[name] = (float(i.find("mass").get("value")), origin_matrix(i), I)
        return out

    def limits(self, joint):
        lim = joint.find("limit")
        if joint.get("type") == "continuous" or lim is None:
            return -np.pi, np.pi
        return float(lim.get("lower", -np.pi)), float(lim.get("upper", np.pi))

    def poses(self, q: dict) -> dict:
        """{0}-pose (4, 4) of every link for joint positions ``q`` (by joint name)."""
        T = {self.root: np.eye(4)}
        pending = list(self.joints)
        while pending:
            for j in list(pending):
                parent = j.find("parent").get("link")
                if parent not in T:
                    continue
                M = T[parent] @ origin_matrix(j)
                kind = j.get("type")
                axis = _floats(j.find("axis").get("xyz") if j.find("axis") is not None else None, (1, 0, 0))
                J = np.eye(4)
                if kind in ("revolute", "continuous"):
                    J[:3, :3] = rodrigues(axis, q[j.get("name")])
                elif kind == "prismatic":
                    J[:3, 3] = axis / np.linalg.norm(axis) * q[j.get("name")]
                elif kind != "fixed":
                    raise NotImplementedError(kind)
                T[j.find("child").get("link")] = M @ J
                pending.remove(j)
        return T

    def mass_matrix(self, names, q, h=1e-6):
        """A = sum over links of m Jv^T Jv + Jw^T I_world Jw, Jacobians by central differences."""
        q = np.asarray(q, float)
        inert = self.inertials()
        n = len(names)
        A = np.zeros((n, n))

        def com_frames(qq):
            T = self.poses(dict(zip(names, qq)))
            return {k: T[k] @ Tc for k, (_, Tc, _) in inert.items()}

        F0 = com_frames(q)
        plus = [com_frames(q + h * e) for e in np.eye(n)]
        minus = [com_frames(q - h * e) for e in np.eye(n)]
        for k, (m, _, I) in inert.items():
            R = F0[k][:3, :3]
            Jv = np.stack([(plus[i][k][:3, 3] - minus[i][k][:3, 3]) / (2 * h) for i in range(n)], axis=1)
            Jw = np.zeros((3, n))
            for i in range(n):
                W = (plus[i][k][:3, :3] - minus[i][k][:3, :3]) / (2 * h) @ R.T
                Jw[:, i] = 0.5 * np.array([W[2, 1] - W[1, 2], W[0, 2] - W[2, 0], W[1, 0] - W[0, 1]])
            A += m * Jv.T @ Jv + Jw.T @ (R @ I @ R.T) @ Jw
        return A

    def potential_energy(self, names, q):
        T = self.poses(dict(zip(names, q)))
        return sum(m * G * (T[k] @ Tc)[2, 3] for k, (m, Tc, _) in self.inertials().items())


def random_configurations(path, model, count=5):
    """``count`` configurations, seeded: inside the joint limits for joint coordinates,
    uniform in [-1, 1] for a floating base's."""
    rng = np.random.default_rng(SEED)
    ref = Reference(path)
    joints = {j.get("name"): j for j in ref.moving}
    bounds = [ref.limits(joints[nm]) if nm in joints else (-1.0, 1.0) for nm in model.coordinate_names]
    lo, hi = np.array(bounds).T
    return [rng.uniform(lo, hi) for _ in range(count)]


# --------------------------------------------------------------------------- the tests


def test_robots_are_shipped_and_documented():
    names = {p.name for p in URDFS}
    assert set(EXPECTED) <= names, f"missing robots: {sorted(set(EXPECTED) - names)}"
    readme = (ROBOTS / "README.md").read_text()
    sections = dict(re.findall(r"^## `([^`]+)`\n(.*?)(?=^## |\Z)", readme, flags=re.M | re.S))
    for p in URDFS:
        assert p.name in sections, f"robots/README.md has no section for {p.name}"
        for coordinate in EXPECTED[p.name][1]:
            assert f"`{coordinate}`" in sections[p.name], f"{p.name}: {coordinate} not documented"


@pytest.mark.parametrize("path", URDFS, ids=ids(URDFS))
def test_loads_strictly_with_documented_coordinates(path):
    model = load(path)           # inertia="strict" raises on any finding
    assert model.audit == []
    assert model.coordinate_names == EXPECTED[path.name][1]
    assert model.n == len(EXPECTED[path.name][1])


@pytest.mark.parametrize("path", URDFS, ids=ids(URDFS))
def test_total_mass_is_the_sum_of_the_inertials(path):
    model = load(path)
    expected = sum(float(m.get("value")) for m in ET.parse(path).getroot().iter("mass"))
    assert expected > 0
    assert model.tree.H[:, 3, 3].sum() == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize("path", URDFS, ids=ids(URDFS))
def test_mass_matrix_positive_definite(path):
    model = load(path)
    for q in [np.zeros(model.n)] + random_configurations(path, model):
        A = model.mass_matrix(q)
        np.testing.assert_allclose(A, A.T, rtol=0, atol=1e-12 * np.abs(A).max())
        eig = np.linalg.eigvalsh(A)
        assert eig[0] > 1e-9 * eig[-1], f"{path.name}: A not positive definite at q={q}: {eig}"
        assert np.all(np.isfinite(model.forward_dynamics(q, np.zeros(model.n))))


FIXED_BASE = [p for p in URDFS if not EXPECTED.get(p.name, ({}, ()))[0].get("floating_base")]


@pytest.mark.parametrize("path", FIXED_BASE, ids=ids(FIXED_BASE))
def test_link_poses_match_independent_forward_kinematics(path):
    model = load(path)
    ref = Reference(path)
    for q in [np.zeros(model.n)] + random_configurations(path, model):
        got = urdf_link_poses(model, q)
        want = ref.poses(dict(zip(model.coordinate_names, q)))
        assert set(got) == set(want)
        for link, T in want.items():
            np.testing.assert_allclose(got[link], T, atol=1e-12, err_msg=f"{path.name}: link {link} at q={q}")


@pytest.mark.parametrize("path", FIXED_BASE, ids=ids(FIXED_BASE))
def test_mass_matrix_and_potential_match_independent_computation(path):
    model = load(path)
    ref = Reference(path)
    for q in [np.zeros(model.n)] + random_configurations(path, model, count=3):
        A = model.mass_matrix(q)
        np.testing.assert_allclose(A, ref.mass_matrix(model.coordinate_names, q), rtol=0,
                                   atol=1e-8 * np.abs(A).max(), err_msg=f"{path.name} at q={q}")
        assert model.potential_energy(q) == pytest.approx(ref.potential_energy(model.coordinate_names, q),
                                                          rel=1e-10, abs=1e-9)


# --------------------------------------------------------------------------- ur5_like: tool0

UR5 = ROBOTS / "ur5_like.urdf"
UR5_OTHER_Q = np.array([0.3, -1.1, 1.4, -0.6, 1.2, -2.0])


def test_ur5_like_tool0_at_zero_is_the_ur5_home_pose():
    """q = 0: arm stretched along +x. By hand from the joint origins: x = 0.425 + 0.39225,
    y = 0.13585 - 0.1197 + 0.093 + 0.0823, z = 0.089159 - 0.09465. Rotation
    Ry(pi/2) Ry(pi/2) Rx(-pi/2) = Ry(pi) Rx(-pi/2): tool0's x along -x, y along +z, z along +y
    (the flange faces sideways, as the UR5's does at zero)."""
    model = load(UR5)
    T = urdf_link_poses(model, np.zeros(6))["tool0"]
    np.testing.assert_allclose(T[:3, 3], [0.81725, 0.19145, -0.005491], atol=1e-12)
    np.testing.assert_allclose(T[:3, :3], [[-1, 0, 0], [0, 0, 1], [0, 1, 0]], atol=1e-12)


@pytest.mark.parametrize("q", [np.zeros(6), UR5_OTHER_Q], ids=["zero", "other"])
def test_ur5_like_tool0_matches_numpy_forward_kinematics(q):
    model = load(UR5)
    want = Reference(UR5).poses(dict(zip(model.coordinate_names, q)))["tool0"]
    np.testing.assert_allclose(urdf_link_poses(model, q)["tool0"], want, atol=1e-12)


@pytest.mark.parametrize("q", [np.zeros(6), UR5_OTHER_Q], ids=["zero", "other"])
def test_ur5_like_tool0_matches_yourdfpy(q):
    robot = yourdfpy.URDF.load(str(UR5), build_scene_graph=True, load_meshes=False)
    model = load(UR5)
    robot.update_cfg(dict(zip(model.coordinate_names, q)))
    want = robot.get_transform("tool0", "world")
    np.testing.assert_allclose(urdf_link_poses(model, q)["tool0"], want, atol=1e-12)

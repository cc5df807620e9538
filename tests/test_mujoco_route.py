"""Route 2 of the MuJoCo comparison: MuJoCo's own URDF import, terms keyed by joint name."""

from __future__ import annotations

import importlib.metadata
import logging
from pathlib import Path

import numpy as np
import pytest
import yourdfpy

import mujoco  # a declared dependency: a broken MuJoCo fails the suite

from urdf2links.compare import MujocoRefused, mujoco_data_at, mujoco_from_urdf, mujoco_terms  # noqa: E402

# --------------------------------------------------------------------------- double pendulum

G = 9.81
M1, C1, L1 = 1.7, 0.31, 0.8      # link 1: mass, COM distance below its hinge, hinge-to-hinge
M2, C2 = 0.9, 0.45               # link 2: mass, COM distance below its hinge
# Inertia tensors in the ROTATED inertial frames (full, with products of inertia).
J1 = np.array([[0.051, 0.004, -0.007], [0.004, 0.043, 0.002], [-0.007, 0.002, 0.021]])
J2 = np.array([[0.032, -0.003, 0.001], [-0.003, 0.027, 0.005], [0.001, 0.005, 0.012]])
RPY1 = (0.4, -0.7, 1.1)
RPY2 = (-1.3, 0.25, 2.2)


def rpy_matrix(r, p, y):
    """URDF fixed-axis roll-pitch-yaw: R = Rz(y) Ry(p) Rx(r) (independent of the code tested)."""
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    return rz @ ry @ rx


def _inertia_xx_in_link_frame(J, rpy):
    R = rpy_matrix(*rpy)
    return (R @ J @ R.T)[0, 0]


# Moments about the hinge-parallel (x) axis through each COM, in the link frame.
I1 = _inertia_xx_in_link_frame(J1, RPY1)
I2 = _inertia_xx_in_link_frame(J2, RPY2)


def _inertia_xml(J):
    J = [[float(v) for v in row] for row in J]
    return (f'<inertia ixx="{J[0][0]!r}" ixy="{J[0][1]!r}" ixz="{J[0][2]!r}" '
            f'iyy="{J[1][1]!r}" iyz="{J[1][2]!r}" izz="{J[2][2]!r}"/>')


def _f(x):
    return " ".join(repr(float(v)) for v in x)


def pendulum_urdf(m1=M1, m2=M2, base_inertial=""):
    return f"""<?xml version="1.0"?>
<robot name="double_pendulum">
  <link name="base">{base_inertial}
    <visual><geometry><mesh filename="package://nowhere/base.stl"/></geometry></visual>
  </link>
  <joint name="shoulder" type="continuous">
    <parent link="base"/><child link="upper"/>
    <origin xyz="0 0 2" rpy="0 0 0"/><axis xyz="1 0 0"/>
    <dynamics damping="0.7" friction="0.2"/>
  </joint>
  <link name="upper">
    <inertial>
      <origin xyz="0 0 {-C1!r}" rpy="{_f(RPY1)}"/>
      <mass value="{m1!r}"/>
      {_inertia_xml(J1)}
    </inertial>
    <visual><geometry><mesh filename="package://nowhere/upper.dae"/></geometry></visual>
    <collision><geometry><cylinder radius="0.02" length="{L1!r}"/></geometry></collision>
  </link>
  <joint name="elbow" type="revolute">
    <parent link="upper"/><child link="lower"/>
    <origin xyz="0.1 0 {-L1!r}" rpy="0 0 0"/><axis xyz="1 0 0"/>
    <limit lower="-0.1" upper="0.1" effort="1" velocity="1"/>
  </joint>
  <link name="lower">
    <inertial>
      <origin xyz="0 0 {-C2!r}" rpy="{_f(RPY2)}"/>
      <mass value="{m2!r}"/>
      {_inertia_xml(J2)}
    </inertial>
    <collision><geometry><mesh filename="package://nowhere/lower.stl"/></geometry></collision>
  </link>
</robot>
"""


def pendulum_closed_form(q, qd):
    """A, e, G of the double pendulum (hinges along x, COMs at (0,0,-c), theta=0 hanging)."""
    t1, t2 = q
    d1, d2 = qd
    c2, s2 = np.cos(t2), np.sin(t2)
    a11 = I1 + M1 * C1**2 + I2 + M2 * (L1**2 + C2**2 + 2 * L1 * C2 * c2)
    a12 = I2 + M2 * (C2**2 + L1 * C2 * c2)
    a22 = I2 + M2 * C2**2
    A = np.array([[a11, a12], [a12, a22]])
    h = M2 * L1 * C2 * s2
    e = np.array([-h * (2 * d1 * d2 + d2**2), h * d1**2])
    Gv = G * np.array([M1 * C1 * np.sin(t1) + M2 * (L1 * np.sin(t1) + C2 * np.sin(t1 + t2)),
                       M2 * C2 * np.sin(t1 + t2)])
    return A, e, Gv


def assert_rel(got, exp, rtol=1e-10):
    scale = max(np.abs(exp).max(), 1e-300)
    err = np.abs(np.asarray(got) - exp).max() / scale
    assert err <= rtol, f"relative error {err:.3e} > {rtol:g}\ngot\n{got}\nexpected\n{exp}"


STATES = [(np.array([0.0, 0.0]), np.array([0.0, 0.0])),
          (np.array([0.3, -1.2]), np.array([0.7, -2.1])),
          (np.array([2.9, 1.7]), np.array([-1.4, 3.3])),
          (np.array([-2.2, 0.05]), np.array([5.0, 0.4]))]


@pytest.mark.parametrize("fusestatic", [True, False])
@pytest.mark.parametrize("k", range(len(STATES)))
def test_double_pendulum_terms_match_closed_form(k, fusestatic):
    q, qd = STATES[k]
    mj = mujoco_from_urdf(pendulum_urdf(), fusestatic=fusestatic)
    assert mj.joint_names == ("shoulder", "elbow")
    assert mj.dof_of_joint == {"shoulder": 0, "elbow": 1}
    t = mujoco_terms(mj, {"shoulder": q[0], "elbow": q[1]}, {"elbow": qd[1], "shoulder": qd[0]},
                     order=["shoulder", "elbow"])
    A, e, Gv = pendulum_closed_form(q, qd)
    assert t.names == ("shoulder", "elbow")
    assert_rel(t.M, A)
    assert_rel(t.bias, e + Gv)
    # gravity and velocity parts separately: zero velocity isolates G
    t0 = mujoco_terms(mj, {"shoulder": q[0], "elbow": q[1]}, {"shoulder": 0, "elbow": 0})
    assert_rel(t0.bias, Gv)


def test_rotated_inertial_origin_is_applied():
    """MuJoCo issue #3559 (inertial <origin rpy> dropped) must not affect this MuJoCo."""
    mj = mujoco_from_urdf(pendulum_urdf())
    m = mj.model
    for body, J, rpy in (("upper", J1, RPY1), ("lower", J2, RPY2)):
        b = m.body(body)
        R = np.zeros(9)
        mujoco.mju_quat2Mat(R, b.iquat)
        R = R.reshape(3, 3)
        full = R @ np.diag(b.inertia) @ R.T
        Rl = rpy_matrix(*rpy)
        np.testing.assert_allclose(full, Rl @ J @ Rl.T, rtol=0, atol=1e-13)
    # with the rotation dropped the shoulder's a22 would use J2[0,0], not I2
    assert abs(J2[0, 0] - I2) > 1e-3


def test_order_and_name_errors():
    mj = mujoco_from_urdf(pendulum_urdf())
    q = {"shoulder": 0.4, "elbow": -0.9}
    qd = {"shoulder": 1.1, "elbow": 0.3}
    a = mujoco_terms(mj, q, qd)
    b = mujoco_terms(mj, q, qd, order=("elbow", "shoulder"))
    assert b.names == ("elbow", "shoulder")
    np.testing.assert_array_equal(b.M, a.M[::-1, ::-1])
    np.testing.assert_array_equal(b.bias, a.bias[::-1])
    with pytest.raises(KeyError, match="unknown joint name.*'wrist'"):
        mujoco_terms(mj, {**q, "wrist": 0.0}, qd)
    with pytest.raises(KeyError, match="missing joint name.*'elbow'"):
        mujoco_terms(mj, q, {"shoulder": 0.0})
    with pytest.raises(KeyError, match="missing joint name.*'shoulder'"):
        mujoco_terms(mj, q, qd, order=["elbow"])
    with pytest.raises(KeyError, match="repeated"):
        mujoco_terms(mj, q, qd, order=["elbow", "shoulder", "elbow"])


def test_physics_is_restricted_and_notes_say_so():
    mj = mujoco_from_urdf(pendulum_urdf(), gravity=(0, 0, -3.0))
    m = mj.model
    np.testing.assert_array_equal(m.opt.gravity, [0, 0, -3.0])
    assert not m.dof_damping.any() and not m.dof_armature.any()
    assert not m.dof_frictionloss.any()
    for flag in ("mjDSBL_CONTACT", "mjDSBL_LIMIT", "mjDSBL_EQUALITY", "mjDSBL_FRICTIONLOSS",
                 "mjDSBL_SPRING", "mjDSBL_DAMPER"):
        assert m.opt.disableflags & int(getattr(mujoco.mjtDisableBit, flag)), flag
    assert m.ngeom == 0  # meshes that do not exist were stripped, not needed
    text = "\n".join(mj.notes)
    assert "removed 4 <visual>/<collision>" in text
    assert "fusestatic merged 1 link(s)" in text and "base" in text
    assert "dof_damping" in text  # it was non-zero in the file
    # the elbow limit (+-0.1) is outside the state: no constraint force may appear
    d = mujoco_data_at(mj, {"shoulder": 0.0, "elbow": 1.0}, {"shoulder": 0, "elbow": 0})
    assert d.nefc == 0


def test_mujoco_warnings_and_mimic_end_up_in_notes():
    inertial = ('<inertial><mass value="1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" '
                'iyz="0" izz="1"/></inertial>')
    text = f"""<robot name="m"><link name="a"/>
      <link name="b">{inertial}</link><link name="c">{inertial}</link>
      <joint name="j1" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/>
        <limit lower="0.5" upper="0.5" effort="1" velocity="1"/></joint>
      <joint name="j2" type="prismatic"><parent link="b"/><child link="c"/><axis xyz="1 0 0"/>
        <limit lower="-1" upper="1" effort="1" velocity="1"/>
        <mimic joint="j1" multiplier="2" offset="0.1"/></joint></robot>"""
    mj = mujoco_from_urdf(text)
    notes = "\n".join(mj.notes)
    assert "MuJoCo said: WARNING: joint 'j1' has equal lower and upper limits" in notes
    assert "1 equality constraint(s)" in notes and mj.model.neq == 1
    assert mj.joint_names == ("j1", "j2")
    # mimic disabled: j2 is an independent coordinate, its qpos is not tied to j1
    d = mujoco_data_at(mj, {"j1": 0.3, "j2": -0.4})
    assert d.nefc == 0 and d.qpos[1] == -0.4


def test_empty_robot_loads_with_a_note():
    mj = mujoco_from_urdf('<robot name="e"><link name="only"/></robot>')
    assert mj.joint_names == () and mj.model.nv == 0
    assert any("no degrees of freedom" in n for n in mj.notes)


# --------------------------------------------------------------------------- refusals


def test_zero_mass_moving_link_is_refused_with_mujocos_reason(tmp_path):
    path = tmp_path / "massless.urdf"
    path.write_text(pendulum_urdf(m2=0.0))
    with pytest.raises(MujocoRefused) as info:
        mujoco_from_urdf(path)
    err = info.value
    assert isinstance(err, RuntimeError)
    assert "mass and inertia of moving bodies must be larger than mjMINVAL" in err.reason
    assert "lower" in err.reason
    assert str(path) in str(err) and err.reason in str(err)


def test_triangle_inequality_is_refused_not_balanced():
    bad = pendulum_urdf().replace(_inertia_xml(J2), '<inertia ixx="0.01" ixy="0" ixz="0" '
                                  'iyy="0.01" iyz="0" izz="0.05"/>')
    with pytest.raises(MujocoRefused, match="A \\+ B >= C") as info:
        mujoco_from_urdf(bad)
    assert "<string>" in str(info.value)


def test_repaired_text_is_loaded_instead_and_noted(tmp_path):
    path = tmp_path / "massless.urdf"
    path.write_text(pendulum_urdf(m2=0.0))
    mj = mujoco_from_urdf(path, repair_urdf_text=pendulum_urdf())
    text = "\n".join(mj.notes)
    assert "REPAIRED" in text and "mjMINVAL" in text
    assert mj.model.body("lower").mass[0] == pytest.approx(M2)


# --------------------------------------------------------------------------- floating base


M0 = 2.5
BASE_INERTIAL = (f'<inertial><mass value="{M0}"/><inertia ixx="0.1" ixy="0" ixz="0" '
                 'iyy="0.1" iyz="0" izz="0.1"/></inertial>')


def test_floating_base_with_massless_root_is_refused():
    """Once free, the massless root link is a moving body: MuJoCo refuses it."""
    with pytest.raises(MujocoRefused, match="mjMINVAL") as info:
        mujoco_from_urdf(pendulum_urdf(), floating_base=True)
    assert "base" in info.value.reason


def test_floating_base_adds_a_free_joint():
    mj = mujoco_from_urdf(pendulum_urdf(base_inertial=BASE_INERTIAL), floating_base=True)
    assert mj.floating and mj.root_body == "base" and mj.free_dofs == tuple(range(6))
    assert mj.joint_names == ("shoulder", "elbow")
    assert mj.dof_of_joint == {"shoulder": 6, "elbow": 7}
    t = mujoco_terms(mj, {"shoulder": 0.2, "elbow": 0.5}, {"shoulder": 0, "elbow": 0},
                     order=["elbow", "shoulder"])
    assert t.dof_labels[:6] == tuple(f"floating_base:{s}" for s in ("vx", "vy", "vz", "wx", "wy", "wz"))
    np.testing.assert_allclose(t.M_full[:3, :3], (M0 + M1 + M2) * np.eye(3), rtol=1e-12)
    # a free body in gravity: the base's vertical bias force is its total weight
    assert t.bias_full[2] == pytest.approx((M0 + M1 + M2) * G, rel=1e-12)
    assert t.M.shape == (2, 2) and t.M[0, 0] == t.M_full[7, 7]


# --------------------------------------------------------------------------- UR5 kinematics


def _ur5_path() -> Path | None:
    try:
        dist = importlib.metadata.distribution("example-robot-data")
    except importlib.metadata.PackageNotFoundError:
        return None
    p = Path(dist.locate_file(
        "cmeel.prefix/share/example-robot-data/robots/ur_description/urdf/ur5_robot.urdf"))
    return p if p.is_file() else None


UR5 = _ur5_path()


@pytest.mark.parametrize("fusestatic", [True, False])
def test_ur5_joint_zero_and_sign_match_urdf_forward_kinematics(fusestatic):
    """MuJoCo hinge qpos = URDF joint angle: zero at the URDF zero pose, sign of the axis."""
    assert UR5 is not None, "example-robot-data (a test dependency) is missing: pip install -e '.[test]'"
    logging.getLogger("yourdfpy").setLevel(logging.CRITICAL)
    robot = yourdfpy.URDF.load(str(UR5), build_scene_graph=True, load_meshes=False)
    mj = mujoco_from_urdf(UR5, fusestatic=fusestatic)
    assert set(mj.joint_names) == {j.name for j in robot.robot.joints if j.type != "fixed"}
    rng = np.random.default_rng(5)
    for _ in range(3):
        cfg = {n: float(v) for n, v in zip(mj.joint_names, rng.uniform(-3, 3, len(mj.joint_names)))}
        robot.update_cfg(cfg)
        d = mujoco_data_at(mj, cfg)
        checked = 0
        for i in range(1, mj.model.nbody):
            name = mj.model.body(i).name
            T = robot.get_transform(name, "world")
            np.testing.assert_allclose(d.xpos[i], T[:3, 3], atol=1e-12, err_msg=name)
            np.testing.assert_allclose(d.xmat[i].reshape(3, 3), T[:3, :3], atol=1e-12,
                                       err_msg=name)
            checked += 1
        assert checked >= 6

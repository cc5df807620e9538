"""Spherical joints (issue 12): three coordinates, the reference's ZYX angles ``<joint>.phi_x/.phi_y/.phi_z``
(``R = Rx Ry Rz`` relative to the joint frame), re-charted near ``phi_y = +-pi/2`` like floating links.

Checked against MuJoCo route 1 (three hinges) on the terms, against the rotation they must give,
and on energy through passes of the chart's singularity."""

from __future__ import annotations

import numpy as np
import pytest

from urdf2links import load_urdf, urdf_link_poses
from urdf2links.integration.charts import floating_links
from urdf2links.dynamics.rotations import rpy_to_matrix, xyz_angles_to_matrix
from urdf2links.scenes.scene_read import scene_from_dict
from urdf2links.integration.simulate import simulate

ORIGIN_RPY = (0.3, -0.2, 0.1)
URDF = f"""<robot name="ball_arm">
  <link name="base"/>
  <joint name="ball" type="spherical">
    <origin xyz="0 0 1" rpy="{' '.join(map(str, ORIGIN_RPY))}"/><parent link="base"/><child link="arm"/>
  </joint>
  <link name="arm"><inertial><origin xyz="0.1 0.05 -0.4" rpy="0.2 0 0.4"/><mass value="2"/>
    <inertia ixx="0.12" ixy="0.01" ixz="0" iyy="0.10" iyz="0.0" izz="0.04"/></inertial></link>
  <joint name="wrist" type="revolute"><origin xyz="0 0 -0.8"/><parent link="arm"/><child link="hand"/>
    <axis xyz="0 1 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <link name="hand"><inertial><origin xyz="0.05 0 -0.1"/><mass value="0.5"/>
    <inertia ixx="0.004" ixy="0" ixz="0" iyy="0.005" iyz="0" izz="0.003"/></inertial></link>
</robot>"""


@pytest.fixture
def robot(tmp_path):
    f = tmp_path / "ball_arm.urdf"
    f.write_text(URDF)
    return f


def test_angles_are_the_zyx_rotation_in_the_joint_frame(robot):
    m = load_urdf(robot)
    assert m.coordinate_names == ("ball.phi_x", "ball.phi_y", "ball.phi_z", "wrist")
    assert [f.name for f in floating_links(m)] == ["arm"]  # re-charted like a floating link
    q = np.array([0.4, -1.1, 2.0, 0.0])
    pose = urdf_link_poses(m, q)["arm"]
    np.testing.assert_allclose(pose[:3, :3], rpy_to_matrix(ORIGIN_RPY) @ xyz_angles_to_matrix(q[:3]), atol=1e-14)
    np.testing.assert_allclose(pose[:3, 3], [0, 0, 1], atol=1e-15)


def test_terms_agree_with_mujoco_route1(robot):
    """MuJoCo integrates the three angles as three hinges (route 1). Tolerance 1e-10 relative: both sides
    evaluate the same rigid-body terms in double precision (measured ~1e-15), as for the shipped scenes."""
    from urdf2links.compare.mujoco_side.mjcf import mjcf_from_scene
    from urdf2links.compare.agreement.scene_terms import route1_terms

    scene = scene_from_dict({"robot": {"urdf": str(robot)}, "gravity": {}})
    model = scene.model()
    r = route1_terms(mjcf_from_scene(scene, model), model, scene, states=16, seed=3)
    assert r["max_rel_error"] < 1e-10, r


@pytest.mark.parametrize("gravity", [False, True])
def test_energy_is_conserved_through_phi_y_pi_half(robot, gravity):
    """Started at phi_y = 1 rad turning at 3 rad/s, the arm passes the chart's singularity (|cos phi_y|
    of the loaded chart comes within 0.02 of 0 without gravity); the run re-charts and keeps
    E + V to the integrator's tolerance: relative energy error < 1e-8 at rtol 1e-10 (measured 2e-10)."""
    data = {"robot": {"urdf": str(robot)}, "initial": {"q": {"ball.phi_y": 1.0}, "qd": {"ball.phi_y": 3.0, "wrist": 0.5}},
            "run": {"t_end": 2.0}}
    if gravity:
        data["gravity"] = {}
    traj = simulate(scene_from_dict(data), progress=False)
    assert traj.stats["n_recharts"] >= 2
    assert traj.energy_error < 1e-8
    R0 = rpy_to_matrix(ORIGIN_RPY)
    cos_y = [np.hypot(*(R0.T @ P[:3, :3])[0, :2]) for P in traj.poses["arm"]]  # |cos phi_y| of the loaded chart
    assert min(cos_y) < (0.25 if gravity else 0.02)

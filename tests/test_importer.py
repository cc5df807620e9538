"""The importer: URDF -> tree of links, against the models built in code, yourdfpy's kinematics,
exact identities (fixed joints, mimic), and the whole example-robot-data corpus."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest
import yourdfpy

import builders
import corpus
from urdf2links import DynamicsError, InertiaError, Model, URDFError
from urdf2links.parsers.importer import load_urdf, load_urdf_string, urdf_link_poses

ROBOTS = Path(__file__).resolve().parent.parent / "robots"


@pytest.mark.parametrize("name, options", [
    ("pendulum", {}), ("double_pendulum", {}), ("prismatic_revolute", {}), ("free_body", {"floating_base": True}),
])
def test_shipped_urdf_equals_model_built_in_code(name, options):
    loaded = load_urdf(ROBOTS / f"{name}.urdf", **options)
    built = getattr(builders, name)()
    if name == "free_body":  # the code-built free body floats in zero gravity
        loaded = Model(loaded.tree, gravity=built.gravity_vector)
    assert loaded.coordinate_names == built.coordinate_names
    assert loaded.audit == []
    rng = np.random.default_rng(11)
    for _ in range(5):
        q, qd = rng.uniform(-1.3, 1.3, built.n), rng.normal(size=built.n)
        scale = np.abs(built.mass_matrix(q)).max()
        # Both are exact to rounding: the URDF route adds the axis alignment rotation (~1e-16).
        np.testing.assert_allclose(loaded.mass_matrix(q), built.mass_matrix(q), rtol=0, atol=1e-13 * scale)
        np.testing.assert_allclose(loaded.bias(q, qd), built.bias(q, qd), rtol=0, atol=1e-13 * scale)
        np.testing.assert_allclose(loaded.gravity(q), built.gravity(q), rtol=0, atol=1e-12 * scale)


# A hand-made URDF with the awkward cases: skewed, negative, unnormalized axes; 90-degree pitch
# origins; a skewed prismatic; fixed joints carrying mass; a rotated inertial. (The prismatic axis is
# a unit vector: yourdfpy slides by axis * q without normalizing, while this importer, like MuJoCo,
# normalizes axes and says so; see test_unnormalized_prismatic_axis_is_normalized_and_reported.)
AWKWARD = """<robot name="awkward">
  <link name="base"><inertial><mass value="2"/><inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
    <origin xyz="0.1 0.2 0.3" rpy="0.3 1.5707963267948966 -0.4"/><axis xyz="0 0 -2"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <link name="l1"><inertial><origin xyz="0.1 0 0.2" rpy="0.2 -0.3 0.5"/><mass value="1.5"/>
    <inertia ixx="0.05" iyy="0.04" izz="0.03" ixy="0.001" ixz="-0.002" iyz="0.003"/></inertial></link>
  <joint name="j2" type="prismatic"><parent link="l1"/><child link="l2"/>
    <origin xyz="0.5 0 0" rpy="0 -1.5707963267948966 0.7"/><axis xyz="0.6666666666666666 -0.6666666666666666 0.3333333333333333"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <link name="l2"><inertial><origin xyz="0 0.1 0"/><mass value="0.7"/>
    <inertia ixx="0.01" iyy="0.02" izz="0.025" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="fix" type="fixed"><parent link="l2"/><child link="tool"/><origin xyz="0 0 0.3" rpy="0.1 0.2 0.3"/></joint>
  <link name="tool"><inertial><origin xyz="0.05 0 0"/><mass value="0.4"/>
    <inertia ixx="0.002" iyy="0.003" izz="0.004" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="j3" type="continuous"><parent link="tool"/><child link="l3"/>
    <origin xyz="0 0.2 0" rpy="3.14159 0 0"/><axis xyz="0.3 0.4 -0.5"/></joint>
  <link name="l3"><inertial><origin xyz="0.2 0 0"/><mass value="0.5"/>
    <inertia ixx="0.002" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="j4" type="revolute"><parent link="base"/><child link="side"/>
    <origin xyz="0 -0.3 0" rpy="-1.5707963267948966 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <link name="side"><inertial><origin xyz="0 0 0.1"/><mass value="0.9"/>
    <inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
</robot>"""


def _against_yourdfpy(model, robot: yourdfpy.URDF, q):
    """Max error of every URDF link pose: ours at q against yourdfpy's at the same joint values."""
    cfg = {name: q[i] for i, name in enumerate(model.coordinate_names) if name in robot.actuated_joint_names}
    robot.update_cfg(cfg)
    ours = urdf_link_poses(model, q)
    return max(np.abs(ours[link] - robot.get_transform(link, robot.base_link)).max() for link in ours)


def test_coordinates_equal_urdf_joint_positions_awkward_axes():
    """Same zero, same sign: every link pose equals yourdfpy's forward kinematics (independent code)."""
    model = load_urdf_string(AWKWARD)
    assert model.coordinate_names == ("j1", "j2", "j3", "j4")
    robot = yourdfpy.URDF.load_from_string(AWKWARD) if hasattr(yourdfpy.URDF, "load_from_string") else None
    if robot is None:
        import io
        robot = yourdfpy.URDF.load(io.StringIO(AWKWARD), build_scene_graph=True, load_meshes=False)
    rng = np.random.default_rng(5)
    for _ in range(10):
        assert _against_yourdfpy(model, robot, rng.uniform(-2, 2, model.n)) < 1e-12
    notes = " ".join(model.info["notes"])
    assert "axis [0.0, 0.0, -2.0] normalized" in notes and "'tool' folded into 'l2'" in notes
    assert "massless frame 'j2.frame'" in notes


def test_unnormalized_prismatic_axis_is_normalized_and_reported():
    model = load_urdf_string(AWKWARD.replace("0.6666666666666666 -0.6666666666666666 0.3333333333333333", "2 -2 1"))
    assert "joint 'j2': axis [2.0, -2.0, 1.0] normalized (length 3)" in model.info["notes"]
    poses = urdf_link_poses(model, np.array([0.0, 0.5, 0.0, 0.0]))
    zero = urdf_link_poses(model, np.zeros(4))
    assert np.linalg.norm(poses["l2"][:3, 3] - zero["l2"][:3, 3]) == pytest.approx(0.5, rel=1e-14)


def test_fixed_joint_folds_exactly():
    """A fixed joint gives the same A as a revolute joint at q = 0 with its row and column removed."""
    revolute = AWKWARD.replace('name="fix" type="fixed"', 'name="fix" type="revolute"').replace(
        '<child link="tool"/><origin xyz="0 0 0.3" rpy="0.1 0.2 0.3"/></joint>',
        '<child link="tool"/><origin xyz="0 0 0.3" rpy="0.1 0.2 0.3"/><axis xyz="0 1 0"/>'
        '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>')
    folded, unfolded = load_urdf_string(AWKWARD), load_urdf_string(revolute)
    assert unfolded.coordinate_names == ("j1", "j2", "fix", "j3", "j4")
    keep = [0, 1, 3, 4]
    rng = np.random.default_rng(8)
    for _ in range(5):
        q = rng.uniform(-2, 2, 4)
        qfull = np.insert(q, 2, 0.0)
        A_f, A_u = folded.mass_matrix(q), unfolded.mass_matrix(qfull)[np.ix_(keep, keep)]
        np.testing.assert_allclose(A_f, A_u, rtol=0, atol=1e-13 * np.abs(A_u).max())
        np.testing.assert_allclose(folded.gravity(q), unfolded.gravity(qfull)[keep], rtol=0, atol=1e-12 * np.abs(A_u).max() * 10)


MIMIC = """<robot name="gripper">
  <link name="palm"><inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="left" type="prismatic"><parent link="palm"/><child link="lf"/><origin xyz="0 0.05 0"/>
    <axis xyz="0 1 0"/><limit lower="0" upper="0.04" effort="10" velocity="1"/></joint>
  <link name="lf"><inertial><mass value="0.1"/><inertia ixx="1e-4" iyy="1e-4" izz="1e-4" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="right" type="prismatic"><parent link="palm"/><child link="rf"/><origin xyz="0 -0.05 0"/>
    <axis xyz="0 1 0"/><limit lower="-0.04" upper="0" effort="10" velocity="1"/>
    <mimic joint="left" multiplier="-1" offset="0.01"/></joint>
  <link name="rf"><inertial><mass value="0.1"/><inertia ixx="1e-4" iyy="1e-4" izz="1e-4" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="tilt" type="revolute"><parent link="palm"/><child link="cam"/><axis xyz="1 0 0"/>
    <limit lower="-1" upper="1" effort="10" velocity="1"/><mimic joint="left" multiplier="2"/></joint>
  <link name="cam"><inertial><origin xyz="0 0 0.1"/><mass value="0.2"/><inertia ixx="1e-3" iyy="1e-3" izz="1e-3" ixy="0" ixz="0" iyz="0"/></inertial></link>
</robot>"""


def test_mimic_independent_and_coupled():
    independent = load_urdf_string(MIMIC)
    coupled = load_urdf_string(MIMIC, mimic="coupled")
    assert independent.coordinate_names == ("left", "right", "tilt")
    assert coupled.coordinate_names == ("left",)
    q = np.array([0.03])
    qfull = np.array([0.03, -0.03 + 0.01, 0.06])
    C = np.array([[1.0], [-1.0], [2.0]])
    np.testing.assert_allclose(coupled.mass_matrix(q), C.T @ independent.mass_matrix(qfull) @ C, rtol=1e-14)
    np.testing.assert_allclose(coupled.gravity(q), C.T @ independent.gravity(qfull), rtol=1e-14, atol=1e-15)
    # the coupled poses follow the leader as yourdfpy's mimic does
    import io
    robot = yourdfpy.URDF.load(io.StringIO(MIMIC), build_scene_graph=True, load_meshes=False)
    robot.update_cfg({"left": 0.03})
    ours = urdf_link_poses(coupled, q)
    for link in ("rf", "cam"):
        np.testing.assert_allclose(ours[link], robot.get_transform(link, robot.base_link), atol=1e-12)


BAD_INERTIA = """<robot name="flawed">
  <link name="base"/>
  <joint name="shoulder" type="revolute"><parent link="base"/><child link="arm"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <link name="arm"><inertial><origin xyz="0.25 0 0"/><mass value="2"/>
    <inertia ixx="0.001" iyy="0.001" izz="0.05" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><origin xyz="0.25 0 0"/><geometry><box size="0.5 0.05 0.05"/></geometry></collision></link>
  <joint name="wrist" type="revolute"><parent link="arm"/><child link="hand"/><origin xyz="0.5 0 0"/><axis xyz="1 0 0"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <link name="hand"/>
</robot>"""


def test_audit_reports_once_and_strict_raises():
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        model = load_urdf_string(BAD_INERTIA)
    assert len([w for w in caught if "inertia finding" in str(w.message)]) == 1
    kinds = {(r.link, r.kind) for r in model.audit}
    assert ("arm", "triangle_inequality") in kinds
    assert ("hand", "massless_moving_subtree") in kinds
    assert all(r.action == "reported" for r in model.audit)
    with pytest.raises(DynamicsError, match="wrist"):
        model.forward_dynamics(np.zeros(2), np.zeros(2))
    with pytest.raises(InertiaError, match="triangle") as info:
        load_urdf_string(BAD_INERTIA, inertia="strict")
    assert "arm" in str(info.value) and "inertia='repair'" in str(info.value)


def test_repair_fixes_every_finding_and_says_how():
    model = load_urdf_string(BAD_INERTIA, inertia="repair")
    assert {r.action for r in model.audit} == {"repaired"}
    arm = next(r for r in model.audit if r.link == "arm")
    assert "collision geometry (box" in arm.fix
    # the arm's inertia is now the box's, with the URDF's mass kept: Izz = m (a^2 + b^2) / 12 about the COM
    m, a, b = 2.0, 0.5, 0.05
    A = model.mass_matrix(np.zeros(2))
    assert A[0, 0] > m * (a * a + b * b) / 12 + m * 0.25**2 - 1e-12
    assert np.linalg.eigvalsh(A).min() > 0
    qdd = model.forward_dynamics(np.zeros(2), np.zeros(2))
    assert np.all(np.isfinite(qdd))


def test_bad_options_are_named():
    with pytest.raises(ValueError, match="inertia must be one of"):
        load_urdf(ROBOTS / "pendulum.urdf", inertia="fix")
    with pytest.raises(ValueError, match="mimic must be one of"):
        load_urdf(ROBOTS / "pendulum.urdf", mimic="both")
    with pytest.raises(URDFError, match="malformed|XML|not well-formed"):
        load_urdf_string("<robot name='x'><link name='a'></robot>")


# ---- the real corpus ----------------------------------------------------------------------------

@corpus.needs_corpus
@pytest.mark.parametrize("rel", corpus.corpus_files())
def test_corpus_loads_or_refuses_clearly(rel):
    """Every URDF of example-robot-data loads or raises URDFError; repaired, A is positive definite."""
    f = corpus.path(rel)
    if rel in corpus.KNOWN_BAD:
        with pytest.raises(URDFError):
            load_urdf(f)
        return
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        audited = load_urdf(f)
        repaired = load_urdf(f, inertia="repair")
    # every finding of the audit is repaired (repairs may uncover more, e.g. a joint whose subtree
    # had only a broken inertia)
    assert {(r.link, r.kind) for r in audited.audit} <= {(r.link, r.kind) for r in repaired.audit}
    assert all(r.action == "repaired" for r in repaired.audit), [str(r) for r in repaired.audit if r.action != "repaired"]
    rng = np.random.default_rng(0)
    for _ in range(2):
        q = rng.uniform(-1, 1, repaired.n)
        if repaired.n:
            assert np.linalg.eigvalsh(repaired.mass_matrix(q)).min() > 0
            assert np.all(np.isfinite(repaired.forward_dynamics(q, np.zeros(repaired.n))))


@corpus.needs_corpus
@pytest.mark.parametrize("name", sorted(corpus.NAMED))
def test_corpus_kinematics_against_yourdfpy(name):
    f = corpus.path(corpus.NAMED[name])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = load_urdf(f, mimic="coupled")  # yourdfpy drives mimic joints from their leaders
    robot = yourdfpy.URDF.load(str(f), build_scene_graph=True, load_meshes=False, build_collision_scene_graph=False)
    rng = np.random.default_rng(3)
    for _ in range(3):
        assert _against_yourdfpy(model, robot, rng.uniform(-1.5, 1.5, model.n)) < 1e-10


PLANAR_FLOATING = """<robot name="sled">
  <link name="ground"/>
  <joint name="table" type="planar"><parent link="ground"/><child link="puck"/>
    <origin xyz="0 0 0.5" rpy="0.4 0 0"/><axis xyz="0 0 1"/></joint>
  <link name="puck"><inertial><mass value="2.0"/>
    <inertia ixx="0.1" iyy="0.2" izz="0.25" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="drone" type="floating"><parent link="ground"/><child link="body"/>
    <origin xyz="1 0 0" rpy="0 0 0.3"/></joint>
  <link name="body"><inertial><mass value="1.5"/>
    <inertia ixx="0.01" iyy="0.02" izz="0.025" ixy="0" ixz="0" iyz="0"/></inertial></link>
</robot>"""


def test_planar_and_floating_joints():
    """Planar: x, y in the plane normal to the axis and a turn about it; floating: six coordinates.
    At zero angles with the COM at the link origin, A is diag(m, m, I_axis) and diag(m, m, m, I)."""
    model = load_urdf_string(PLANAR_FLOATING, inertia="strict")
    assert model.coordinate_names == ("table.x", "table.y", "table.phi_z",
                                      "drone.x", "drone.y", "drone.z", "drone.phi_x", "drone.phi_y", "drone.phi_z")
    A = model.mass_matrix(np.zeros(model.n))
    np.testing.assert_allclose(A, np.diag([2.0, 2.0, 0.25, 1.5, 1.5, 1.5, 0.01, 0.02, 0.025]), atol=1e-14)
    # the planar joint's plane is tilted by the origin's roll: sliding along table.y climbs
    poses = urdf_link_poses(model, np.r_[0.0, 1.0, 0.0, np.zeros(6)])
    np.testing.assert_allclose(poses["puck"][:3, 3], [0.0, np.cos(0.4), 0.5 + np.sin(0.4)], atol=1e-14)
    # the floating joint's translations are along the joint frame's axes (origin yaw 0.3)
    poses = urdf_link_poses(model, np.r_[np.zeros(3), 1.0, 0.0, 0.0, 0, 0, 0])
    np.testing.assert_allclose(poses["body"][:3, 3], [1 + np.cos(0.3), np.sin(0.3), 0.0], atol=1e-14)
    assert np.linalg.eigvalsh(model.mass_matrix(np.random.default_rng(1).uniform(-1, 1, model.n))).min() > 0

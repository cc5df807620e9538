"""Two descriptions of one robot (issue 33): the roots' poses taken out, and a planted test per joint kind.

A rotated root is not a difference of the robot's parts: MuJoCo's import of a URDF with its root turned (a fixed
arm mounted elsewhere, a floating base started at another yaw) lists ``root_pose`` once and no sign flip, axis or
origin; a floating root's pose is a state (the residual stays at MuJoCo's 6 written digits), a fixed root's mount
is one difference whose undoing removes G's difference. Then one planted difference per joint kind (damping,
stiffness, friction, limits, type), each named first and alone.
"""

from __future__ import annotations

import math
import warnings

import mujoco
import numpy as np
import pytest

from corpus import needs_corpus
from urdf2links.compare.pairs.mujoco_import import save_mujoco_import
from urdf2links.compare.pairs.pair import compare_descriptions_of
from urdf2links.locations import example_robot_data_dir, shipped_robots_dir

ROOT = example_robot_data_dir()
QUAT = (0.3, 0.5, -0.2, 0.7)          # w x y z: a turn of 142 deg about no particular axis
POS = (0.1, 0.2, 0.3)


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    return tmp_path_factory.mktemp("drifts")


def _compare(urdf, mjcf, **load):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return compare_descriptions_of(urdf, mjcf, load=load or None)


# -- the roots ----------------------------------------------------------------------------------------------
@needs_corpus       # a test extra: missing fails naming it (tests/corpus.py), never a skip
def test_a_floating_robots_rotated_twin_lists_only_root_pose(folder):
    urdf = ROOT / "solo_description/robots/solo12.urdf"
    same = save_mujoco_import(urdf, folder / "solo_same.xml", keep_geometry=False, floating_base=True,
                              root_pose=((0, 0, 0), (1, 0, 0, 0))).path
    turned = save_mujoco_import(urdf, folder / "solo_turned.xml", keep_geometry=False, floating_base=True,
                                root_pose=(POS, QUAT)).path
    c0 = _compare(urdf, same, floating_base=True)
    c = _compare(urdf, turned, floating_base=True)
    assert [d.kind for d in c0.differences] == []
    assert [d.kind for d in c.differences] == ["root_pose"]
    assert c.mapping.to_json()["negated"] == [] and all(m.sign == 1 for m in c.mapping.matches)
    rp = c.differences[0]
    assert rp.difference == pytest.approx(2 * math.acos(QUAT[0] / np.linalg.norm(QUAT)), abs=1e-6)
    assert rp.effect["at_rounding"] is True and rp.part == "link"      # a state: it changes neither A nor G
    # the residual is the untouched import's: MuJoCo's 6 written digits (1.8e-6 measured on both)
    for term in ("A", "G"):
        assert c.effects["after_undoing_all"][term] < 1e-5
        assert c.effects["mapped"][term]["max_rel_difference"] == pytest.approx(
            c0.effects["mapped"][term]["max_rel_difference"], rel=1e-3, abs=1e-12)
    s = c.summary()
    assert s["description_counts"]["root_pose"] == {"count": 1, "floating": True}
    assert s["description_counts"]["dynamics"]["count"] == 0 and c.check() == []   # a state: no tolerance fails


def test_a_fixed_arms_mount_is_one_difference_that_explains_G(folder):
    urdf = shipped_robots_dir() / "ur5_like.urdf"
    mjcf = save_mujoco_import(urdf, folder / "ur5_mounted.xml", keep_geometry=False, root_pose=(POS, QUAT),
                              keep_frames=True).path
    c = _compare(urdf, mjcf)
    assert [d.kind for d in c.differences] == ["root_pose"]
    assert all(m.sign == 1 for m in c.mapping.matches)
    assert "the mount" in c.differences[0].what and 'quat="' in c.differences[0].what
    assert c.effects["mapped"]["G"]["max_rel_difference"] > 0.1          # gravity turned against the arm
    assert c.effects["mapped"]["G"]["explained_by"]["kind"] == "root_pose"
    assert c.effects["mapped"]["G"]["explained_by"]["explains"] > 0.999
    assert c.effects["after_undoing_all"]["G"] < 1e-5
    assert c.summary()["description_counts"]["root_pose"] == {"count": 1, "floating": False}


# -- one planted joint difference each ------------------------------------------------------------------------
@pytest.fixture(scope="module")
def arm(folder):
    urdf = shipped_robots_dir() / "ur5_like.urdf"
    return urdf, save_mujoco_import(urdf, folder / "arm.xml", keep_geometry=False, keep_frames=True).path


def _planted(arm, folder, name, edit):
    spec = mujoco.MjSpec.from_file(str(arm[1]))
    edit(spec)
    spec.compile()
    out = folder / f"{name}.xml"
    out.write_text(spec.to_xml())
    return _compare(arm[0], out)


@pytest.mark.parametrize("kind, attr, value, unit", [("damping", "damping", 2.5, "N m s/rad"),
                                                     ("stiffness", "stiffness", 40.0, "N m/rad"),
                                                     ("friction", "frictionloss", 1.5, "N m")])
def test_a_joints_own_coefficient(arm, folder, kind, attr, value, unit):
    def edit(spec):
        j = spec.joint("elbow_joint")
        old = np.asarray(getattr(j, attr), float)
        setattr(j, attr, value if old.ndim == 0 else np.r_[value, np.zeros(old.size - 1)])   # MuJoCo 4: arrays
    c = _planted(arm, folder, kind, edit)
    assert [(d.kind, d.urdf) for d in c.differences] == [(kind, "elbow_joint")]
    d = c.differences[0]
    assert d.difference == pytest.approx(value) and d.unit == unit
    assert c.summary()["description_counts"]["dynamics"]["count"] == 1


def test_a_joints_range(arm, folder):
    def edit(spec):
        spec.joint("elbow_joint").range = [-2.0, 2.5]
    c = _planted(arm, folder, "limits", edit)
    assert [(d.kind, d.urdf) for d in c.differences] == [("limits", "elbow_joint")]
    assert c.differences[0].difference == pytest.approx(math.pi - 2.0, abs=1e-5)
    n = c.summary()["description_counts"]
    assert n["non_dynamic"] == {"count": 1, "kinds": ["limits"]} and n["dynamics"]["count"] == 0


def test_a_joints_type(arm, folder):
    def edit(spec):
        spec.joint("wrist_2_joint").type = mujoco.mjtJoint.mjJNT_SLIDE
    c = _planted(arm, folder, "type", edit)
    assert [(d.kind, d.urdf) for d in c.differences if d.kind != "limits"] == [("type", "wrist_2_joint")]
    assert c.first_of("type").urdf_value == "revolute" and c.first_of("type").mjcf_value == "slide"


# -- a representative sample of the sweep (benchmarks/pairs_rotated_roots.py runs all 68) -------------------------
@needs_corpus       # a test extra: missing fails naming it (tests/corpus.py), never a skip
@pytest.mark.parametrize("rel", ["allegro_hand_description/urdf/allegro_right_hand.urdf",   # a hand, balanced
                                 "go1_description/urdf/go1.urdf",                            # a quadruped
                                 "talos_data/robots/talos_reduced.urdf"])                    # a humanoid, 32 joints
def test_example_robot_data_with_the_root_turned_lists_no_sign_flip(folder, rel):
    urdf = ROOT / rel
    rows = {}
    for label, pose in (("untouched", None), ("turned", (POS, QUAT))):
        out = folder / f"{urdf.stem}_{label}.xml"
        try:
            save_mujoco_import(urdf, out, keep_geometry=False, root_pose=pose)
        except Exception:     # MuJoCo refuses the allegro hand's inertias as written: its compiler balances them
            save_mujoco_import(urdf, out, keep_geometry=False, balance=True, root_pose=pose)
        rows[label] = _compare(urdf, out)
    c0, c = rows["untouched"], rows["turned"]
    assert c.mapping.to_json()["negated"] == []
    frames = lambda x: sorted(d.label() for d in x.differences if d.kind in ("axis", "origin"))  # noqa: E731
    assert frames(c) == frames(c0)
    assert sum(d.kind == "root_pose" for d in c.differences) == 1


def test_a_joints_effort(arm, folder):
    """URDF <limit effort="150"> against an MJCF actuatorfrcrange lowered to +-100: a limit, not the dynamics."""
    def edit(spec):
        spec.joint("elbow_joint").actfrcrange = [-100.0, 100.0]
    c = _planted(arm, folder, "effort", edit)
    assert [(d.kind, d.urdf) for d in c.differences] == [("effort", "elbow_joint")]
    assert c.differences[0].difference == pytest.approx(50 / 150)
    assert c.summary()["description_counts"]["non_dynamic"] == {"count": 1, "kinds": ["effort"]}


# -- effort and velocity from actuators, couplings, frames (issue 33, part II) ---------------------------------
def _actuator(spec, joint, *, gear, **attrs):
    a = spec.add_actuator(name=f"{joint}_act", target=joint, trntype=mujoco.mjtTrn.mjTRN_JOINT)
    a.gear = [gear, 0, 0, 0, 0, 0]
    for k, v in attrs.items():
        setattr(a, k, v)
    return a


@pytest.mark.parametrize("how", ["ctrlrange", "forcerange"])
def test_a_joints_effort_through_an_actuator(arm, folder, how):
    """A motor of gear 50 and ctrlrange +-2, or of gear 2 and forcerange +-50: 100 N m at the elbow, under the
    URDF's 150 (and the import's actuatorfrcrange 150, the smallest counts)."""
    def edit(spec):
        if how == "ctrlrange":
            _actuator(spec, "elbow_joint", gear=50.0, ctrllimited=1, ctrlrange=[-2.0, 2.0])
        else:
            _actuator(spec, "elbow_joint", gear=2.0, forcelimited=1, forcerange=[-50.0, 50.0])
    c = _planted(arm, folder, f"effort_{how}", edit)
    assert [(d.kind, d.urdf) for d in c.differences] == [("effort", "elbow_joint")]
    assert c.differences[0].difference == pytest.approx(50 / 150) and c.differences[0].mjcf_value == 100.0


def test_a_joints_velocity(arm, folder):
    """A velocity actuator (kv 20, gear 2, ctrlrange +-5: 2.5 rad/s) at the elbow against <limit velocity="3.15">;
    the other joints' URDF speeds are then limited on one side only (the file states speeds, not theirs)."""
    def edit(spec):
        a = _actuator(spec, "elbow_joint", gear=2.0, ctrllimited=1, ctrlrange=[-5.0, 5.0])
        a.set_to_velocity(kv=20.0)
    c = _planted(arm, folder, "velocity", edit)
    vel = {d.urdf: d for d in c.differences if d.kind == "velocity"}
    assert {d.kind for d in c.differences} == {"velocity"} and len(vel) == 6
    assert vel["elbow_joint"].difference == pytest.approx((3.15 - 2.5) / 3.15)
    assert all(math.isinf(d.difference) for n, d in vel.items() if n != "elbow_joint")
    assert c.summary()["description_counts"]["non_dynamic"]["kinds"] == ["velocity"]


def test_a_coupling(arm, mimic_arm, folder):
    """MuJoCo's import turns <mimic> into a joint equality (no difference); its multiplier planted 1.5; a joint
    equality the URDF does not have (1 row); a mimic the MJCF does not have. Coupling changes the motion."""
    assert [d.kind for d in _compare(*mimic_arm).differences] == []

    def edit(spec):
        eq = next(iter(spec.equalities))
        eq.data = np.r_[0.1, 1.5, np.zeros(eq.data.size - 2)]
    c = _planted(mimic_arm, folder, "coupling", edit)
    assert [(d.kind, d.urdf) for d in c.differences] == [("coupling", "wrist_3_joint")]
    assert c.differences[0].difference == pytest.approx(0.5)
    assert c.summary()["description_counts"]["dynamics"]["kinds"] == ["coupling"]
    one = _compare(mimic_arm[0], arm[1])                         # the mimic's MJCF side dropped
    assert [(d.kind, d.urdf, d.difference) for d in one.differences] == [("coupling", "wrist_3_joint", 1.0)]


def test_a_frame_kept_moved_or_dropped(arm, folder):
    """The tool0 frame: kept as a site (nothing), its site moved 1 cm (0.01 m), dropped as MuJoCo's import drops
    it (1 frame, explained)."""
    def edit(spec):
        spec.site("tool0").pos = np.asarray(spec.site("tool0").pos) + [0.0, 0.01, 0.0]
    c = _planted(arm, folder, "frame", edit)
    assert [(d.kind, d.urdf) for d in c.differences] == [("frame_missing", "tool0_joint")]
    assert c.differences[0].difference == pytest.approx(0.01, abs=1e-6) and c.differences[0].unit == "m"
    assert c.summary()["description_counts"]["non_dynamic"] == {"count": 1, "kinds": ["frame_missing"]}
    dropped = save_mujoco_import(arm[0], folder / "arm_dropped.xml", keep_geometry=False).path
    d = _compare(arm[0], dropped).differences
    assert [(x.kind, x.urdf, x.difference) for x in d] == [("frame_missing", "tool0_joint", 1.0)]
    assert "fuses it" in d[0].explanation


@pytest.fixture(scope="module")
def meshed_arm(folder):
    """ur5_like with the flange's cylinder as an STL mesh (visual and collision), its MuJoCo import, and the URDF
    with the collision mesh written 10 times the visual (scale 10: the units mistake users hit)."""
    import trimesh

    trimesh.creation.cylinder(radius=0.045, height=0.06, sections=32).export(folder / "flange.stl")
    text = (shipped_robots_dir() / "ur5_like.urdf").read_text()
    old = '<geometry><cylinder radius="0.045" length="0.06"/></geometry>\n    </collision>'
    assert text.count(old) == 1
    mesh = '<geometry><mesh filename="flange.stl"{}/></geometry>'
    visual = '    <visual>\n      <origin xyz="0 0.0523 0" rpy="-1.5707963267948966 0 0"/>\n      {}\n    </visual>'
    urdfs = {}
    for label, scale in (("right", ""), ("tenfold", ' scale="10 10 10"')):
        urdfs[label] = folder / f"ur5_mesh_{label}.urdf"
        urdfs[label].write_text(text.replace(old, mesh.format(scale) + "\n    </collision>\n"
                                             + visual.format(mesh.format(""))))
    return urdfs, save_mujoco_import(urdfs["right"], folder / "ur5_mesh.xml", keep_frames=True).path


def test_a_collision_mesh_ten_times_the_visual(meshed_arm):
    """The collision mesh at scale 10 against MuJoCo's import of the right one: one collision difference at the
    flange, volume x1000 (relative 0.999), its box 10 times larger; the import itself agrees (the visual geoms,
    contype 0, are not collision geometry)."""
    urdfs, mjcf = meshed_arm
    assert _compare(urdfs["right"], mjcf).differences == []
    c = _compare(urdfs["tenfold"], mjcf)
    assert [(d.kind, d.urdf) for d in c.differences] == [("collision", "wrist_3_link")]
    d = c.differences[0]
    assert d.urdf_value[0] == pytest.approx(1000 * d.mjcf_value[0], rel=1e-4)     # the rounding level (MuJoCo's import: 2.3e-8 on solo12's meshes)
    assert d.difference == pytest.approx(0.999, abs=1e-4)
    assert c.summary()["description_counts"]["non_dynamic"] == {"count": 1, "kinds": ["collision"]}

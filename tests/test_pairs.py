"""Two descriptions of one robot (issue 25): a URDF against MuJoCo's own import of it saved as MJCF shows nothing
above rounding; copies with one planted difference each name the planted part first of its kind and attribute
the effect on A and G to it.

The robot is ``robots/ur5_like.urdf`` with two additions that real arms have and conversions get wrong: a fixed
flange with a turned frame between the forearm and the wrist (``forearm_flange_joint``, rpy about the forearm's
axis, with a mass off its centre), and a tool of 0.8 kg on the rotated fixed frame ``tool0`` (its inertia
elongated along the tool's axis). MuJoCo's import (``fusestatic``, its default) merges both into their parents.
"""

from __future__ import annotations

import math
import re

import mujoco
import numpy as np
import pytest

from urdf2links.compare.pairs.mujoco_import import save_mujoco_import
from urdf2links.compare.pairs.pair import compare_descriptions_of
from urdf2links.dynamics.inertia import pseudo_inertia
from urdf2links.dynamics.rotations import rpy_to_matrix
from urdf2links.locations import shipped_robots_dir
from urdf2links.parsers.parts import robot_parts

FLANGE_RPY = "0 0 0.4"     # a turn about the forearm's own axis: wrist_1's axis points elsewhere without it


def _urdf_text(*, flange_rpy: str = FLANGE_RPY) -> str:
    text = (shipped_robots_dir() / "ur5_like.urdf").read_text()
    text = text.replace('''    <parent link="forearm_link"/>
    <child link="wrist_1_link"/>
    <origin xyz="0 0 0.39225" rpy="0 1.5707963267948966 0"/>''', '''    <parent link="forearm_flange"/>
    <child link="wrist_1_link"/>
    <origin xyz="0 0.02 0" rpy="0 1.5707963267948966 0"/>''')
    flange = f'''
  <joint name="forearm_flange_joint" type="fixed">
    <parent link="forearm_link"/>
    <child link="forearm_flange"/>
    <origin xyz="0 0 0.39225" rpy="{flange_rpy}"/>
  </joint>
  <link name="forearm_flange">
    <inertial>
      <origin xyz="0.03 0.01 -0.01" rpy="0 0 0"/>
      <mass value="0.3"/>
      <inertia ixx="0.0004" ixy="0" ixz="0" iyy="0.0003" iyz="0" izz="0.0002"/>
    </inertial>
  </link>
'''
    tool = '''<link name="tool0">
    <inertial>
      <origin xyz="0 0 0.05" rpy="0 0 0"/>
      <mass value="0.8"/>
      <inertia ixx="0.002" ixy="0" ixz="0" iyy="0.0018" iyz="0" izz="0.0004"/>
    </inertial>
  </link>'''
    assert '<link name="tool0"/>' in text and "forearm_flange" in text
    text = text.replace('<link name="tool0"/>', tool)
    return text.replace("</robot>", flange + "</robot>")


@pytest.fixture(scope="module")
def base(tmp_path_factory):
    """``(urdf path, faithful MJCF path, folder)``: the test arm and MuJoCo's import of it."""
    folder = tmp_path_factory.mktemp("pairs")
    urdf = folder / "arm.urdf"
    urdf.write_text(_urdf_text())
    mjcf = save_mujoco_import(urdf, folder / "arm_mujoco.xml").path
    return urdf, mjcf, folder


def _edited(base, name, edit) -> str:
    """A copy of the faithful MJCF with ``edit(spec)`` applied (MuJoCo's MjSpec, written back by MuJoCo)."""
    _urdf, mjcf, folder = base
    spec = mujoco.MjSpec.from_file(str(mjcf))
    edit(spec)
    spec.compile()
    out = folder / f"{name}.xml"
    out.write_text(spec.to_xml())
    return str(out)


def _named(d, name) -> bool:
    return name in (d.urdf, d.mjcf) or name in d.through or name in d.links


def _attributed(c, term, kind, name, *, view="mapped", share=0.5):
    """``term``'s difference is explained most by the ``kind`` difference naming ``name``, by more than ``share``."""
    by = c.effects[view][term]["explained_by"]
    assert by is not None, f"{term} ({view}) is explained by nothing: {c.effects[view][term]}"
    assert by["kind"] == kind and name in (by["urdf"], by["mjcf"]), (term, view, by)
    assert by["explains"] > share, (term, view, by)


# -- the faithful conversion ------------------------------------------------------------------------------
def test_mujoco_import_of_a_urdf_shows_nothing_above_rounding(base):
    urdf, mjcf, _ = base
    c = compare_descriptions_of(urdf, mjcf)
    assert [d.label() for d in c.differences] == []
    assert c.mapping.mapped_fraction == 1.0 and all(m.by == "name" and m.sign == 1 for m in c.mapping.matches)
    # MuJoCo writes 6 significant digits: A and G agree to that (the largest entry, relative)
    assert c.effects["mapped"]["A"]["max_rel_difference"] < 1e-5
    assert c.effects["mapped"]["G"]["max_rel_difference"] < 1e-5
    # ... and MuJoCo did merge the fixed children: the comparison folded the URDF the same way
    names = {b.name for b in robot_parts(mjcf).bodies}
    assert "tool0" not in names and "forearm_flange" not in names


def test_the_shipped_pair_shows_its_armature_and_nothing_else():
    """robots/ur5_like_mujoco.xml: MuJoCo's import of ur5_like.urdf plus armature on every joint."""
    d = shipped_robots_dir()
    c = compare_descriptions_of(d / "ur5_like.urdf", d / "ur5_like_mujoco.xml")
    assert {x.kind for x in c.differences} == {"armature"} and len(c.differences) == 6
    assert all(x.explanation for x in c.differences)
    # the three large joints' 0.1 kg m^2 come first, each explaining about a third of A's squared difference
    assert {x.urdf for x in c.differences[:3]} == {"shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint"}
    assert sum(x.effect["explains_A"] for x in c.differences) == pytest.approx(1.0, abs=1e-6)
    assert c.effects["mapped"]["G"]["max_rel_difference"] < 1e-12      # armature is in A only (E49)


# -- one planted difference each ------------------------------------------------------------------------------
def test_a_links_mass(base):
    def edit(spec):
        spec.body("forearm_link").mass *= 1.3
    c = compare_descriptions_of(base[0], _edited(base, "mass", edit))
    first = c.first_of("mass")
    # a link's mass is named by its link on both sides (issue 43: not by the joint that moves it)
    assert (first.urdf, first.mjcf, first.part) == ("forearm_link", "forearm_link", "link")
    assert first.difference == pytest.approx(0.3 / 1.3, rel=1e-4)     # relative to the larger mass
    assert c.differences[0] is first
    _attributed(c, "G", "mass", "forearm_link", share=0.9)
    _attributed(c, "A", "mass", "forearm_link", share=0.9)


def test_an_inertial_frame_turned_as_when_an_rpy_is_dropped(base):
    def edit(spec):           # upper_arm_link's inertial has rpy (0.2745, 0, 0) in the URDF: dropped
        spec.body("upper_arm_link").iquat = [1.0, 0.0, 0.0, 0.0]
    c = compare_descriptions_of(base[0], _edited(base, "iquat", edit))
    first = c.first_of("inertia")
    assert (first.urdf, first.mjcf) == ("upper_arm_link", "upper_arm_link") and first.unit == "rad"
    assert first.difference == pytest.approx(0.27453536618280727, abs=1e-5)     # the dropped roll itself
    assert c.first_of("com") is None and c.first_of("mass") is None
    _attributed(c, "A", "inertia", "upper_arm_link", share=0.99)
    assert c.effects["mapped"]["G"]["max_rel_difference"] < 1e-5      # the COM did not move: G unchanged


def test_an_axis_negated(base):
    def edit(spec):
        spec.joint("elbow_joint").axis = -np.asarray(spec.joint("elbow_joint").axis)
    c = compare_descriptions_of(base[0], _edited(base, "axis", edit))
    first = c.first_of("axis")
    assert _named(first, "elbow_joint") and first.difference == pytest.approx(math.pi, abs=1e-5)
    assert c.mapping.of_urdf("elbow_joint").sign == -1.0 and c.mapping.to_json()["negated"] == ["elbow_joint"]
    # mapped with the sign, the two describe the same dynamics; taken as equal by name, they do not, and the
    # axis is why
    assert c.effects["mapped"]["A"]["max_rel_difference"] < 1e-5
    assert c.effects["mapped"]["G"]["max_rel_difference"] < 1e-5
    _attributed(c, "G", "axis", "elbow_joint", view="as_named", share=0.99)
    _attributed(c, "A", "axis", "elbow_joint", view="as_named", share=0.99)


def test_a_joint_origin_moved(base):
    def edit(spec):
        spec.body("forearm_link").pos = np.asarray(spec.body("forearm_link").pos) + [0.03, 0.0, 0.0]
    c = compare_descriptions_of(base[0], _edited(base, "origin", edit))
    origins = [d for d in c.differences if d.kind == "origin"]
    assert len(origins) == 1, [d.label() for d in origins]      # the bodies below moved with it: not differences
    assert _named(origins[0], "elbow_joint") and origins[0].difference == pytest.approx(0.03, abs=1e-6)
    _attributed(c, "G", "origin", "elbow_joint", share=0.99)


def test_armature_added(base):
    def edit(spec):
        spec.joint("wrist_1_joint").armature = 0.05
    c = compare_descriptions_of(base[0], _edited(base, "armature", edit))
    first = c.first_of("armature")
    assert _named(first, "wrist_1_joint") and first.difference == pytest.approx(0.05)
    assert [d.kind for d in c.differences] == ["armature"]
    _attributed(c, "A", "armature", "wrist_1_joint", share=0.999)


@pytest.mark.parametrize("fusestatic", [True, False], ids=["merged", "kept"])
def test_a_fixed_joints_rpy_lost(base, fusestatic):
    """The conversion lost forearm_flange_joint's rpy: MuJoCo's import of the URDF without it. Merged
    (fusestatic, MuJoCo's default) the flange is gone from the MJCF, and the difference is named at the next
    joint, through the fixed one; kept, it is named at the fixed joint itself."""
    urdf, _mjcf, folder = base
    lost = folder / f"lost_{fusestatic}.urdf"
    lost.write_text(_urdf_text(flange_rpy="0 0 0"))
    mjcf = save_mujoco_import(lost, folder / f"lost_{fusestatic}.xml", fusestatic=fusestatic).path
    c = compare_descriptions_of(urdf, mjcf)
    first = c.first_of("origin")
    assert first.unit == "rad" and first.difference == pytest.approx(0.4, abs=1e-5)
    if fusestatic:
        assert first.urdf == "wrist_1_joint" and first.through == ("forearm_flange_joint",)
    else:
        assert first.urdf == "forearm_flange_joint" and first.mjcf == "forearm_flange"
        assert [d.kind for d in c.differences] == ["origin"]
    # the phantom gravity torque: G differs, and the lost rotation explains it
    assert c.effects["mapped"]["G"]["max_rel_difference"] > 0.01
    _attributed(c, "G", "origin", first.urdf, share=0.9)


def test_two_bodies_merged_with_a_rotated_child(base):
    """wrist_3_link and the tool on the rotated tool0 merged into one body, the tool's inertia added in its own
    axes instead of wrist_3's (its rotation ignored; its COM placed right)."""
    urdf = base[0]
    U = robot_parts(urdf)
    w3, tool = U.body("wrist_3_link"), U.body("tool0")
    m_t = float(tool.H[3, 3])
    c_t = tool.pose[:3, :3] @ (tool.H[:3, 3] / m_t) + tool.pose[:3, 3]        # right: in wrist_3's frame
    I_t = np.diag([0.002, 0.0018, 0.0004])                                       # the tool's, in its own axes
    H = w3.H + pseudo_inertia(m_t, c_t, I_t)
    m = float(H[3, 3])
    com = H[:3, 3] / m
    Sc = H[:3, :3] - m * np.outer(com, com)
    w, V = np.linalg.eigh(np.trace(Sc) * np.eye(3) - Sc)
    if np.linalg.det(V) < 0:
        V[:, 0] *= -1
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, V.ravel())

    def edit(spec):
        b = spec.body("wrist_3_link")
        b.mass, b.ipos, b.iquat, b.inertia = m, com, quat, w
    c = compare_descriptions_of(urdf, _edited(base, "merged", edit))
    first = c.first_of("inertia")
    assert (first.urdf, first.mjcf) == ("wrist_3_link", "wrist_3_link")
    assert c.first_of("mass") is None and c.first_of("com") is None
    assert c.differences[0] is first
    _attributed(c, "A", "inertia", "wrist_3_link", share=0.99)
    # the right sum (MuJoCo's own) is what the faithful import has: check that the planted one differs from it
    # by the tool's rotation about x (tool0's rpy -pi/2)
    R = rpy_to_matrix([-math.pi / 2, 0, 0])
    assert not np.allclose(R @ I_t @ R.T, I_t)


# -- the part of the attribution that says what is left ---------------------------------------------------------
def test_undoing_every_difference_leaves_rounding(base):
    """Several planted differences at once: undone together they leave A and G at rounding (the list is whole)."""
    def edit(spec):
        spec.body("forearm_link").mass *= 1.2
        spec.joint("wrist_2_joint").armature = 0.03
        spec.body("upper_arm_link").iquat = [1.0, 0.0, 0.0, 0.0]
        spec.body("wrist_1_link").pos = np.asarray(spec.body("wrist_1_link").pos) + [0.0, 0.01, 0.02]
    c = compare_descriptions_of(base[0], _edited(base, "several", edit))
    assert {d.kind for d in c.differences} == {"mass", "armature", "inertia", "origin"}
    assert c.effects["mapped"]["A"]["max_rel_difference"] > 1e-2
    assert c.effects["after_undoing_all"]["A"] < 1e-5 and c.effects["after_undoing_all"]["G"] < 1e-5


def test_joints_named_differently_are_mapped_by_structure_or_by_map(base):
    urdf, mjcf, folder = base
    text = mjcf.read_text()
    renamed = folder / "renamed.xml"
    renamed.write_text(re.sub(r'<joint name="(\w+)_joint"', r'<joint name="j_\1"', text))
    c = compare_descriptions_of(urdf, renamed)
    assert c.mapping.mapped_fraction == 1.0 and {m.by for m in c.mapping.matches} == {"structure"}
    assert [(m.urdf, m.mjcf) for m in c.mapping.matches][2] == ("elbow_joint", "j_elbow")
    assert c.differences == []
    c = compare_descriptions_of(urdf, renamed, explicit_map={"elbow_joint": "j_elbow"})
    assert c.mapping.of_urdf("elbow_joint").by == "map"
    with pytest.raises(Exception, match="no moving joint 'j_nope'"):
        compare_descriptions_of(urdf, renamed, explicit_map={"elbow_joint": "j_nope"})


def test_a_joint_or_a_body_the_other_side_lacks(base):
    """A URDF joint made fixed in the MJCF: joint_missing names it, its body still compares by name; the body
    removed too: link_missing names it with its mass (the tool folded into it)."""
    def fixed(spec):
        spec.delete(spec.joint("wrist_3_joint"))
    c = compare_descriptions_of(base[0], _edited(base, "fixed", fixed))
    assert [(d.kind, d.urdf) for d in c.differences] == [("joint_missing", "wrist_3_joint")]
    assert c.mapping.unmatched_urdf == ("wrist_3_joint",) and c.mapping.mapped_fraction == pytest.approx(5 / 6)

    def removed(spec):
        spec.delete(spec.body("wrist_3_link"))
    c = compare_descriptions_of(base[0], _edited(base, "removed", removed))
    kinds = {d.kind: d for d in c.differences}
    assert kinds["joint_missing"].urdf == "wrist_3_joint" and kinds["link_missing"].urdf == "wrist_3_link"
    assert kinds["link_missing"].difference == pytest.approx(1.2 + 0.8)

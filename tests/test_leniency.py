"""Reading like urdfdom (issue 12): every tolerated defect loads with a note naming element, link or
joint and what was done; ``strict=True`` refuses it as before; what truly cannot be read stays an
error in both modes. urdfdom's behaviour for each case is in docs/importing.md (checked in its
source, 4.0, and measured on the urdfdom 6.0 that Pinocchio 4 loads with)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from urdf2links import load_urdf
from urdf2links.errors import URDFError, URDFStructureError, URDFSyntaxError, URDFValueError
from urdf2links.parsers.urdf import parse_urdf
from urdf2links.dynamics.rotations import rpy_to_matrix

INERTIAL = ('<inertial><mass value="1"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/>'
            '</inertial>')
LIMIT = '<limit lower="-1" upper="1" effort="1" velocity="1"/>'


def robot(a="", b="", jbody=LIMIT, jtype="revolute", extra="", head="", attrs=' name="r"'):
    """Two links with inertia, ``a`` and ``b``, joined by joint ``j``; the pieces go where named."""
    return (f'{head}<robot{attrs}><link name="a">{INERTIAL}{a}</link><link name="b">{INERTIAL}{b}</link>'
            f'<joint name="j" type="{jtype}"><parent link="a"/><child link="b"/>{jbody}</joint>{extra}</robot>')


def loads_with_note(text, *words, **options):
    """Load ``text`` (default reading): one note holds every word; strict reading raises a URDFError."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = load_urdf(text, **options)
    notes = model.info["notes"]
    assert any(all(w in n for w in words) for n in notes), notes
    with pytest.raises(URDFError):
        parse_urdf(text, strict=True)
    return model


# --------------------------------------------------------------------------- tolerated, with a note


@pytest.mark.parametrize("version", ["0.0", "2.0"])
def test_unusual_xml_declaration(version):
    text = robot(head=f'<?xml version="{version}" ?>\n')
    loads_with_note(text, "XML declaration", f'version="{version}"', "read as 1.0")
    with pytest.raises(URDFSyntaxError, match="XML declaration"):
        parse_urdf(text, strict=True)


@pytest.mark.parametrize("shape", ['<capsule radius="0.1" length="1"/>', '<plane normal="0 0 1"/>',
                                   '<vendor_shape file="x"/>'])
@pytest.mark.parametrize("where", ["visual", "collision"])
def test_unknown_shape_is_ignored_for_dynamics(shape, where):
    name = shape.split()[0][1:].rstrip("/>")
    m = loads_with_note(robot(b=f"<{where}><geometry>{shape}</geometry></{where}>"),
                        f"link 'b' <{where}>", f"unknown shape <{name}>", "ignored for the dynamics")
    assert m.n == 1 and m.tree.H[1, 3, 3] == 1.0  # the link keeps its <inertial>


def test_unknown_shape_refused_by_name_when_inertia_must_come_from_it():
    """A link without usable mass whose only geometry is a capsule: the repair cannot use it and says so."""
    text = robot(b='<collision><geometry><capsule radius="0.1" length="1"/></geometry></collision>'
                   ).replace(f'<link name="b">{INERTIAL}', '<link name="b">')
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = load_urdf(text, inertia="repair")
    fixes = [r.fix for r in m.audit if r.link == "b"]
    assert fixes and all("capsule" in f and "unusable" in f for f in fixes), fixes


def test_geometry_with_extra_elements():
    after = robot(b='<visual><geometry><box size="1 2 3"/><material name="m"/></geometry></visual>')
    loads_with_note(after, "link 'b' <visual> <geometry>", "extra element(s) <material> ignored", "<box>")
    before = robot(b='<visual><geometry><material name="m"/><box size="1 2 3"/></geometry></visual>')
    desc = parse_urdf(before)
    assert desc.links["b"].visuals[0].kind == "box" and list(desc.links["b"].visuals[0].size) == [1, 2, 3]


@pytest.mark.parametrize("visual, words", [
    ('<visual><origin xyz="0 0 0 1"/><geometry><box size="1 1 1"/></geometry></visual>',
     ["expected 3 numbers, found 4", "ignored for the dynamics"]),
    ('<visual><geometry><box size="-1 1 1"/></geometry></visual>', ["negative", "ignored for the dynamics"]),
    ('<visual><geometry><sphere radius="x"/></geometry></visual>', ["'x' is not a number"]),
    ('<visual><origin xyz="0 0 0"/></visual>', ["no <geometry>"]),
    ('<collision><geometry/></collision>', ["holds 0 shapes"]),
])
def test_unusable_visual_or_collision_is_noted(visual, words):
    loads_with_note(robot(b=visual), "link 'b'", *words)


def test_mesh_scale_of_one_number_is_noted():
    desc = parse_urdf(robot(b='<visual><geometry><mesh filename="m.stl" scale="2"/></geometry></visual>'))
    assert list(desc.links["b"].visuals[0].scale) == [2, 2, 2]
    assert any('scale="2"' in n and "one number read as 3" in n for n in desc.notes), desc.notes


def test_mimic_naming_no_joint():
    text = robot(jbody=LIMIT + '<mimic joint="nope"/>')
    m = loads_with_note(text, "joint 'j' <mimic joint=\"nope\">", "no joint named 'nope'", "no effect")
    assert m.coordinate_names == ("j",)
    with pytest.raises(URDFStructureError, match="joint 'j' <mimic joint=\"nope\">.*coupled"):
        load_urdf(text, mimic="coupled")


def test_negative_mass_goes_to_the_audit():
    text = robot().replace('<link name="b"><inertial><mass value="1"/>', '<link name="b"><inertial><mass value="-2"/>')
    m = loads_with_note(text, "link 'b' <inertial> <mass", "negative", "audit")
    assert any(r.link == "b" and r.kind == "non_positive_mass" for r in m.audit)


@pytest.mark.parametrize("jtype", ["fixed", "floating"])
def test_axis_of_jointless_types_is_not_read(jtype):
    loads_with_note(robot(jtype=jtype, jbody='<axis xyz="0 0"/>'), "joint 'j' <axis>", "not read")


# --------------------------------------------------------------------------- noted, never silently dropped


def test_unused_and_unknown_elements_are_listed():
    text = robot(a='<self_collide/>', jbody=LIMIT + '<origin xyz="0 0 1"/><origin xyz="9 9 9"/>'
                 '<safety_controller k_velocity="1"/><calibration rising="0"/><dynamics damping="0.5" friction="0.1"/>',
                 extra='<transmission name="t1"/><gazebo reference="a"/><material name="red"/><sensor name="s"/>'
                       '<link name="c"><visual><geometry><box size="1 1 1"/></geometry><shine/></visual></link>'
                       '<joint name="k" type="fixed"><parent link="b"/><child link="c"/>'
                       '<safety_controller k_velocity="1"/></joint>')
    desc = parse_urdf(text)
    notes = "\n".join(desc.notes)
    for words in (["<link> <self_collide> in link 'a'", "unknown element"],
                  ["a second <joint> <origin> in joint 'j'", "only the first"],
                  ["<joint> <safety_controller> in joints 'j', 'k'", "not used"],
                  ["<link> <visual> <shine> in link 'c'", "unknown element"],
                  ["<joint> <calibration> in joint 'j'", "not used"],
                  ["<transmission>: 1 element(s) (t1)", "not used"], ["<gazebo>", "not used"],
                  ["<material>: 1 element(s) (red)", "visual only"], ["<sensor>", "unknown element"],
                  ["<dynamics damping> on joints 'j'", "from_urdf"],
                  ["<dynamics friction> on joints 'j'", "not modelled"],
                  ["<limit lower upper> on joints 'j'", "not enforced"],
                  ["<limit effort velocity> on joints 'j'", "not used"]):
        assert any(all(w in n for w in words) for n in desc.notes), (words, notes)
    assert desc.joints[0].origin.xyz.tolist() == [0, 0, 1]  # the first <origin>, as urdfdom
    assert (desc.joints[0].damping, desc.joints[0].friction) == (0.5, 0.1)


def test_revolute_without_limit_and_empty_dynamics_are_noted():
    desc = parse_urdf(robot(jbody="<dynamics/>"))
    assert any("without <limit>" in n and "unbounded" in n for n in desc.notes), desc.notes
    assert any("<dynamics>" in n and "neither damping nor friction" in n for n in desc.notes), desc.notes


def test_robot_version_and_quat_xyzw():
    q = '<origin xyz="0 0 1" quat_xyzw="0 0 0.7071067811865476 0.7071067811865476"/>'
    desc = parse_urdf(robot(jbody=LIMIT + q, attrs=' name="r" version="1.1"'))
    np.testing.assert_allclose(rpy_to_matrix(desc.joints[0].origin.rpy), rpy_to_matrix([0, 0, np.pi / 2]),
                               atol=1e-15)
    old = parse_urdf(robot(jbody=LIMIT + q))  # version 1.0: urdfdom ignores quat_xyzw, and says so
    assert old.joints[0].origin.rpy.tolist() == [0, 0, 0]
    assert any("quat_xyzw" in n and "ignored" in n for n in old.notes), old.notes
    odd = parse_urdf(robot(attrs=' name="r" version="7.3"'))
    assert any('<robot version="7.3">' in n for n in odd.notes), odd.notes


def test_robot_without_name_is_noted():
    desc = parse_urdf(robot(attrs=""))
    assert desc.name == "robot" and any("no name" in n for n in desc.notes)


def test_spherical_joint_has_three_named_angles():
    m = load_urdf(robot(jtype="spherical", jbody='<origin xyz="0 0 1" rpy="0.1 0.2 0.3"/>'))
    assert m.coordinate_names == ("j.phi_x", "j.phi_y", "j.phi_z")
    assert any("spherical" in n and "extension" in n for n in m.info["notes"])


# --------------------------------------------------------------------------- still errors, in both modes


@pytest.mark.parametrize("text, cls, words", [
    (robot().replace('<link name="a">', '<linkx name="a">').replace("</link><link", "</linkx><link", 1)
     .replace('<link name="b">', '<linkx name="b">').replace("</link><joint", "</linkx><joint"), URDFStructureError,
     ["no <link> elements"]),
    (robot(extra='<joint name="k" type="fixed"><parent link="b"/><child link="a"/></joint>'), URDFStructureError,
     ["cycle"]),
    (robot(extra='<link name="c"/>'), URDFStructureError, ["2 separate trees"]),
    (robot(jbody='<origin xyz="nan 0 0"/>'), URDFValueError, ["not finite"]),
    (robot(jbody='<origin xyz="0 0 1 5"/>'), URDFValueError, ["expected 3 numbers, found 4"]),
    (robot(jbody='<axis xyz="0 0 1 0"/>'), URDFValueError, ["expected 3 numbers, found 4"]),
    (robot(jbody='<limit lower="a" upper="1" effort="1" velocity="1"/>'), URDFValueError, ["'a' is not a number"]),
    (robot().replace('<mass value="1"/>', '<mass value="1kg"/>', 1), URDFValueError, ["'1kg' is not a number"]),
    (robot(jtype="hinge"), URDFValueError, ["type 'hinge' is unknown"]),
    (robot(jbody='<axis xyz="0 0 0"/>'), URDFValueError, ["nonzero axis"]),
])
def test_what_cannot_be_read_stays_an_error(text, cls, words):
    for strict in (False, True):
        with pytest.raises(cls) as info:
            parse_urdf(text, strict=strict)
        assert all(w in str(info.value) for w in words), str(info.value)


def test_leftover_xacro_in_a_urdf_is_an_error(tmp_path):
    f = tmp_path / "r.urdf"
    f.write_text(robot(extra='<xacro:macro xmlns:xacro="http://www.ros.org/wiki/xacro" name="leg"/>'))
    with pytest.raises(URDFSyntaxError, match=r"xacro elements that were never expanded: <xacro:macro> \(line 1\)"):
        load_urdf(f)
    with pytest.raises(URDFValueError, match="xacro"):
        parse_urdf(robot(jbody='<origin xyz="${x} 0 0"/>'))

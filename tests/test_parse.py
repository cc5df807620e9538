"""Tests of urdf2links.parsers.urdf: validation errors, a round trip, mesh paths, the real corpus."""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
import pytest
import yourdfpy

from urdf2links.locations import example_robot_data_dir

from urdf2links.errors import MeshError, URDFError, URDFStructureError, URDFSyntaxError, URDFValueError
from urdf2links.parsers.urdf import parse_urdf, require_mesh, resolve_mesh_path

# --------------------------------------------------------------------------- helpers

INERTIA = '<inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/>'


def link(name, body=""):
    return f'<link name="{name}">{body}</link>'


def joint(name, parent, child, jtype="revolute", body=""):
    return (f'<joint name="{name}" type="{jtype}"><parent link="{parent}"/>'
            f'<child link="{child}"/>{body}</joint>')


def robot(*parts, name="r"):
    return f'<robot name="{name}">' + "".join(parts) + "</robot>"


def two_links(jbody="", jtype="revolute", abody=""):
    return robot(link("a", abody), link("b"), joint("j", "a", "b", jtype, jbody))


def raises(cls, text, *words):
    """Parse ``text`` strictly (tests/test_leniency.py covers the default reading), expect ``cls``,
    check the message names the file and every word."""
    with pytest.raises(cls) as info:
        parse_urdf(text, strict=True)
    msg = str(info.value)
    assert type(info.value) is cls, msg
    assert "<string>" in msg, msg
    for w in words:
        assert w in msg, f"{w!r} not in {msg!r}"
    return msg


def rpy_matrix(rpy):
    r, p, y = rpy
    cx, sx, cy, sy, cz, sz = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return rz @ ry @ rx


def origin_matrix(origin):
    t = np.eye(4)
    t[:3, :3] = rpy_matrix(origin.rpy)
    t[:3, 3] = origin.xyz
    return t


# --------------------------------------------------------------------------- syntax


def test_malformed_xml_names_line():
    text = '<robot name="r">\n<link name="a">\n</robot>'
    msg = raises(URDFSyntaxError, text, "line", "malformed XML")
    assert "line 3" in msg


def test_root_is_not_robot():
    raises(URDFSyntaxError, '<sdf version="1.6"><link name="a"/></sdf>', "<sdf>", "<robot")


def test_missing_file_is_urdf_error(tmp_path):
    missing = tmp_path / "nope.urdf"
    with pytest.raises(URDFError, match="does not exist") as info:
        parse_urdf(missing)
    assert str(missing) in str(info.value)


def test_error_names_the_file_path(tmp_path):
    f = tmp_path / "bad.urdf"
    f.write_text(two_links(jtype="hinge"))
    with pytest.raises(URDFValueError) as info:
        parse_urdf(f)
    assert str(f) in str(info.value) and "line 1" in str(info.value)


# --------------------------------------------------------------------------- structure


def test_unknown_parent_link():
    text = robot(link("a"), link("b"), joint("elbow", "base", "b"))
    raises(URDFStructureError, text, "joint 'elbow'", "<parent link=\"base\">", "no link named 'base'")


def test_unknown_child_link_suggests_close_name():
    text = robot(link("a"), link("forearm"), joint("elbow", "a", "forarm"))
    raises(URDFStructureError, text, "joint 'elbow'", "'forarm'", "did you mean 'forearm'")


def test_link_child_of_two_joints():
    text = robot(link("a"), link("b"), link("c"), joint("j1", "a", "c"), joint("j2", "b", "c"))
    raises(URDFStructureError, text, "link 'c'", "'j1'", "'j2'", "at most one parent")


def test_cycle():
    # every link has one parent at most, so a cycle is cut off from the root
    text = robot(link("a"), link("b"), link("c"), link("d"), link("e"), joint("j0", "a", "b"),
                 joint("j1", "c", "d"), joint("j2", "d", "e"), joint("j3", "e", "c"))
    msg = raises(URDFStructureError, text, "cycle", "'c' -> [j1] 'd' -> [j2] 'e' -> [j3] 'c'")
    assert "remove one joint" in msg


def test_self_loop_is_a_cycle():
    raises(URDFStructureError, robot(link("a"), link("b"), link("c"), joint("j", "a", "b"),
                                     joint("k", "c", "c")), "joints 'k'", "cycle 'c' -> [k] 'c'")


def test_two_roots_are_listed():
    text = robot(link("a"), link("b"), link("c"), link("d"), joint("j", "a", "b"), joint("k", "c", "d"))
    raises(URDFStructureError, text, "2 separate trees", "'a'", "'c'", "fixed")


def test_no_links():
    raises(URDFStructureError, robot(), "no <link>")


def test_duplicate_link_name():
    raises(URDFStructureError, robot(link("a"), link("a")), "link 'a'", "already used")


def test_duplicate_joint_name():
    text = robot(link("a"), link("b"), link("c"), joint("j", "a", "b"), joint("j", "a", "c"))
    raises(URDFStructureError, text, "joint 'j'", "already used")


def test_mimic_unknown_joint():
    text = robot(link("a"), link("b"), link("c"), joint("j1", "a", "b"),
                 joint("j2", "b", "c", body='<mimic joint="j0"/>'))
    raises(URDFStructureError, text, "joint 'j2'", '<mimic joint="j0">', "no joint named 'j0'")


# --------------------------------------------------------------------------- values


@pytest.mark.parametrize("body, words", [
    ('<origin xyz="nan 0 0"/>', ['joint \'j\' <origin> xyz="nan 0 0"', "not finite"]),
    ('<origin rpy="0 inf 0"/>', ['rpy="0 inf 0"', "not finite"]),
    ('<origin xyz="1 a 0"/>', ['xyz="1 a 0"', "'a' is not a number"]),
    ('<origin xyz="1,0,0"/>', ['xyz="1,0,0"', "not a number"]),
    ('<origin xyz="1 0"/>', ['xyz="1 0"', "expected 3 numbers, found 2"]),
    ('<axis xyz="0 -inf 1"/>', ["<axis>", "not finite"]),
    ('<limit lower="x" upper="1" effort="1" velocity="1"/>', ['<limit> lower="x"', "not a number"]),
    ('<limit lower="0" upper="nan" effort="1" velocity="1"/>', ['upper="nan"', "not finite"]),
    ('<limit effort="${e}" velocity="1"/>', ['effort="${e}"', "xacro"]),
    ('<mimic joint="j" multiplier="two"/>', ['multiplier="two"', "not a number"]),
])
def test_bad_joint_numbers(body, words):
    raises(URDFValueError, two_links(body), *words)


@pytest.mark.parametrize("body, words", [
    (f'<inertial><mass value="abc"/>{INERTIA}</inertial>', ["link 'a' <inertial> <mass>", 'value="abc"']),
    (f'<inertial><mass value="inf"/>{INERTIA}</inertial>', ['value="inf"', "not finite"]),
    ('<inertial><mass value="1"/><inertia ixx="nan" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>',
     ["<inertia> ixx=\"nan\"", "not finite"]),
    ('<inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1"/></inertial>', ["ixy", "missing"]),
    ('<inertial><mass value="1"/></inertial>', ["link 'a' <inertial>", "no <inertia>"]),
    (f'<inertial><origin xyz="0 0 nan"/><mass value="1"/>{INERTIA}</inertial>', ["<inertial> <origin>", "nan"]),
    ('<visual><geometry><box size="1 1 nan"/></geometry></visual>', ["<visual> <geometry><box>", "not finite"]),
    ('<collision><geometry><cylinder radius="r" length="1"/></geometry></collision>', ['radius="r"']),
    ('<collision><geometry><sphere radius="-1"/></geometry></collision>', ['radius="-1"', "negative"]),
    ('<visual><geometry><mesh filename="m.stl" scale="1 nan 1"/></geometry></visual>', ['scale="1 nan 1"']),
    ('<visual><geometry><capsule radius="1" length="1"/></geometry></visual>', ["<capsule>", "box, cylinder"]),
    ('<visual><geometry/></visual>', ["<geometry> holds 0 shapes"]),
    ('<visual><geometry><box size="1 1 1"/><sphere radius="1"/></geometry></visual>', ["2 shapes"]),
    ('<visual><origin xyz="0 0 0"/></visual>', ["no <geometry>"]),
])
def test_bad_link_values(body, words):
    raises(URDFValueError, two_links(abody=body), *words)


def test_negative_mass():
    body = f'<inertial><mass value="-2.5"/>{INERTIA}</inertial>'
    raises(URDFValueError, two_links(abody=body), "link 'a'", 'value="-2.5"', "negative", ">= 0")


def test_unknown_joint_type_lists_valid_ones():
    msg = raises(URDFValueError, two_links(jtype="hinge"), "joint 'j'", "type 'hinge' is unknown")
    for t in ("revolute", "continuous", "prismatic", "fixed", "floating", "planar"):
        assert t in msg


@pytest.mark.parametrize("jtype", ["revolute", "prismatic", "continuous"])
def test_zero_axis(jtype):
    raises(URDFValueError, two_links('<axis xyz="0 0 0"/>', jtype), "joint 'j'",
           'xyz="0 0 0"', f"{jtype} joint needs a nonzero axis")


def test_zero_axis_of_fixed_joint_is_fine():
    assert parse_urdf(two_links('<axis xyz="0 0 0"/>', "fixed")).joints[0].type == "fixed"


@pytest.mark.parametrize("text", [
    robot(link("a"), '<link/>'),
    robot(link("a"), link("b"), '<joint name="j" type="fixed"><child link="b"/></joint>'),
    robot(link("a"), link("b"), '<joint name="j" type="fixed"><parent/><child link="b"/></joint>'),
    robot(link("a"), link("b"), '<joint type="fixed"><parent link="a"/><child link="b"/></joint>'),
    robot(link("a"), link("b"), joint("j", "a", "b", body="<mimic/>")),
    robot(link("a", '<visual><geometry><mesh/></geometry></visual>')),
    two_links(jtype=""),
    "<robot name='r'>\n" + link("a") + "&bogus;</robot>",
    "  <",
    "",
    "x" * 5000,
])
def test_odd_inputs_raise_urdf_errors_only(text):
    with pytest.raises(URDFError):
        parse_urdf(text, strict=True)


def test_robot_without_name_uses_file_stem(tmp_path):
    f = tmp_path / "my_arm.urdf"
    f.write_text('<robot>' + link("a") + '</robot>')
    assert parse_urdf(f).name == "my_arm"
    assert parse_urdf('<robot>' + link("a") + '</robot>').name == "robot"


# --------------------------------------------------------------------------- round trip

VALID = """<?xml version="1.0" encoding="utf-8"?>
<!-- a comment -->
<robot name="demo" xmlns:xacro="http://wiki.ros.org/xacro">
  <material name="grey"><color rgba="0.5 0.5 0.5 1"/></material>
  <joint name="wrist" type="prismatic">
    <parent link="upper"/><child link="hand"/>
    <origin xyz="0 0 0.5"/>
    <axis xyz="0 0.6 0.8"/>
    <limit lower="-0.1" upper="0.2" effort="10" velocity="1"/>
    <mimic joint="shoulder" multiplier="-2" offset="0.25"/>
  </joint>
  <link name="base">
    <inertial>
      <origin xyz="0.1 0.2 0.3" rpy="0.1 1.5707963267948966 -0.3"/>
      <mass value="2.5"/>
      <inertia ixx="0.1" ixy="-0.01" ixz="0.02" iyy="0.2" iyz="-0.03" izz="0.3"/>
    </inertial>
    <visual>
      <origin xyz="1 2 3" rpy="0.5 -0.25 3"/>
      <geometry><mesh filename="meshes/base.stl" scale="0.001 0.002 0.003"/></geometry>
      <material name="grey"/>
    </visual>
    <collision><geometry><box size="0.1 0.2 0.3"/></geometry></collision>
    <collision><geometry><cylinder radius="0.05" length="0.4"/></geometry></collision>
    <collision><geometry><sphere radius="0.07"/></geometry></collision>
    <collision><geometry><mesh filename="meshes/missing.dae" scale="2"/></geometry></collision>
  </link>
  <link name="hand"/>
  <joint name="shoulder" type="revolute">
    <parent link="base"/><child link="upper"/>
    <origin xyz="0.1 -0.2 0.3" rpy="3.0 -0.5 1e-3"/>
    <limit effort="5" velocity="2"/>
  </joint>
  <link name="upper"><inertial><mass value="0"/>""" + INERTIA + """</inertial></link>
  <gazebo reference="base"><mu1>0.5</mu1></gazebo>
  <transmission name="t"><type>x</type></transmission>
</robot>
"""


def test_round_trip(tmp_path):
    (tmp_path / "meshes").mkdir()
    (tmp_path / "meshes" / "base.stl").write_text("solid x\nendsolid x\n")
    f = tmp_path / "demo.urdf"
    f.write_text(VALID)
    for d in (parse_urdf(f), parse_urdf(VALID)):
        assert d.name == "demo" and d.root == "base"
        assert list(d.links) == ["base", "upper", "hand"]
        assert [j.name for j in d.joints] == ["shoulder", "wrist"]
        sh, wr = d.joints
        assert (sh.type, sh.parent, sh.child) == ("revolute", "base", "upper")
        np.testing.assert_array_equal(sh.origin.xyz, [0.1, -0.2, 0.3])
        np.testing.assert_array_equal(sh.origin.rpy, [3.0, -0.5, 1e-3])
        np.testing.assert_array_equal(sh.axis, [1.0, 0.0, 0.0])  # default
        assert sh.limit_lower is None and sh.limit_upper is None and sh.mimic is None
        np.testing.assert_array_equal(wr.axis, [0.0, 0.6, 0.8])
        assert (wr.limit_lower, wr.limit_upper) == (-0.1, 0.2)
        assert (wr.mimic.joint, wr.mimic.multiplier, wr.mimic.offset) == ("shoulder", -2.0, 0.25)
        np.testing.assert_array_equal(wr.origin.rpy, [0, 0, 0])
        base = d.links["base"]
        inn = base.inertial
        assert inn.mass == 2.5 and isinstance(inn.mass, float)
        np.testing.assert_array_equal(inn.origin.xyz, [0.1, 0.2, 0.3])
        np.testing.assert_array_equal(inn.origin.rpy, [0.1, np.pi / 2, -0.3])
        np.testing.assert_array_equal(inn.inertia, [[0.1, -0.01, 0.02], [-0.01, 0.2, -0.03],
                                                   [0.02, -0.03, 0.3]])
        assert d.links["upper"].inertial.mass == 0.0 and d.links["hand"].inertial is None
        (vis,) = base.visuals
        assert vis.kind == "mesh" and vis.filename == "meshes/base.stl"
        np.testing.assert_array_equal(vis.scale, [0.001, 0.002, 0.003])
        np.testing.assert_array_equal(vis.origin.rpy, [0.5, -0.25, 3])
        box, cyl, sph, mesh = base.collisions
        assert box.kind == "box" and cyl.kind == "cylinder" and sph.kind == "sphere"
        np.testing.assert_array_equal(box.size, [0.1, 0.2, 0.3])
        assert (cyl.radius, cyl.length, sph.radius) == (0.05, 0.4, 0.07)
        np.testing.assert_array_equal(mesh.scale, [2.0, 2.0, 2.0])
        assert mesh.path is None
        assert d.joint_of_child("hand") is wr and d.child_joints("base") == (sh,)
    from_file = parse_urdf(f)
    assert from_file.source == str(f) and from_file.directory == tmp_path.resolve()
    assert from_file.links["base"].visuals[0].path == (tmp_path / "meshes" / "base.stl").resolve()
    assert parse_urdf(VALID).source == "<string>"


def test_joints_are_topologically_ordered():
    text = robot(joint("j3", "c", "d"), joint("j2", "b", "c"), link("d"), link("c"),
                 joint("j1", "a", "b"), joint("k", "a", "e"), link("e"), link("b"), link("a"))
    d = parse_urdf(text)
    assert d.root == "a"
    seen = {d.root}
    for j in d.joints:
        assert j.parent in seen
        seen.add(j.child)
    assert list(d.links)[0] == "a" and set(d.links) == set("abcde")


# --------------------------------------------------------------------------- meshes


@pytest.fixture
def workspace(tmp_path):
    """tmp/ws/src/my_pkg/{urdf/r.urdf, meshes/a.stl} and tmp/other/ext_pkg/meshes/b.stl."""
    pkg = tmp_path / "ws" / "src" / "my_pkg"
    (pkg / "urdf").mkdir(parents=True)
    (pkg / "meshes").mkdir()
    (pkg / "meshes" / "a.stl").write_text("a")
    ext = tmp_path / "other" / "ext_pkg" / "meshes"
    ext.mkdir(parents=True)
    (ext / "b.stl").write_text("b")
    return tmp_path


def test_package_path_found_from_urdf_ancestors(workspace):
    d = workspace / "ws" / "src" / "my_pkg" / "urdf"
    got = resolve_mesh_path("package://my_pkg/meshes/a.stl", directory=d, package_dirs=())
    assert got == (workspace / "ws/src/my_pkg/meshes/a.stl").resolve()


def test_package_path_found_in_package_dirs(workspace):
    d = workspace / "ws" / "src" / "my_pkg" / "urdf"
    url = "package://ext_pkg/meshes/b.stl"
    assert resolve_mesh_path(url, directory=d, package_dirs=()) is None
    want = (workspace / "other/ext_pkg/meshes/b.stl").resolve()
    assert resolve_mesh_path(url, directory=d, package_dirs=[workspace / "other"]) == want
    # a package_dirs entry that is the package folder itself
    assert resolve_mesh_path(url, directory=None, package_dirs=[workspace / "other/ext_pkg"]) == want


def test_package_path_fallback_without_package_folder(workspace):
    # the package is not named my_robot anywhere: fall back to <dir>/rest
    d = workspace / "ws" / "src" / "my_pkg"
    got = resolve_mesh_path("package://my_robot/meshes/a.stl", directory=d / "urdf", package_dirs=())
    assert got == (d / "meshes" / "a.stl").resolve()


def test_file_and_relative_paths(workspace):
    d = workspace / "ws" / "src" / "my_pkg" / "urdf"
    a = (workspace / "ws/src/my_pkg/meshes/a.stl").resolve()
    assert resolve_mesh_path(f"file://{a}", directory=d) == a
    assert resolve_mesh_path(str(a), directory=None) == a
    assert resolve_mesh_path("../meshes/a.stl", directory=d) == a
    assert resolve_mesh_path("../meshes/zzz.stl", directory=d) is None
    assert resolve_mesh_path("file:///no/such/file.stl", directory=d) is None


def test_parse_resolves_package_meshes_and_require_mesh(workspace):
    f = workspace / "ws" / "src" / "my_pkg" / "urdf" / "r.urdf"
    f.write_text(robot(
        link("a", '<visual><geometry><mesh filename="package://my_pkg/meshes/a.stl"/></geometry></visual>'),
        link("b", '<visual><geometry><mesh filename="package://ext_pkg/meshes/b.stl"/></geometry></visual>'
                  '<collision><geometry><sphere radius="1"/></geometry></collision>'),
        joint("j", "a", "b")))
    d = parse_urdf(f)
    a, b = d.links["a"].visuals[0], d.links["b"].visuals[0]
    assert require_mesh(a, link="a", source=d.source) == (workspace / "ws/src/my_pkg/meshes/a.stl").resolve()
    assert b.path is None
    with pytest.raises(MeshError) as info:
        require_mesh(b, link="b", source=d.source)
    msg = str(info.value)
    assert str(f) in msg and "link 'b'" in msg and "package://ext_pkg/meshes/b.stl" in msg
    assert "package_dirs" in msg and "ext_pkg" in msg
    with pytest.raises(MeshError, match="sphere"):
        require_mesh(d.links["b"].collisions[0], link="b", source=d.source)
    d2 = parse_urdf(f, package_dirs=[workspace / "other"])
    assert d2.links["b"].visuals[0].path == (workspace / "other/ext_pkg/meshes/b.stl").resolve()


# --------------------------------------------------------------------------- corpus


def _corpus_root() -> Path | None:
    return example_robot_data_dir()


CORPUS = _corpus_root()
CORPUS_FILES = sorted(CORPUS.rglob("*.urdf")) if CORPUS else []
# Files of example-robot-data 6.0.0 known to be defective, and the error they give.
KNOWN_BAD = {
    # an empty <robot>, no name: urdfdom (and so Pinocchio) refuses it too
    "ur_description/urdf/ur3.urdf": (URDFStructureError, "no <link>"),
}


def _compare_with_yourdfpy(desc, path):
    """Cross-check against yourdfpy's own parse of the same file (an independent reader)."""
    logging.getLogger("yourdfpy").setLevel(logging.CRITICAL)
    y = yourdfpy.URDF.load(str(path), build_scene_graph=False, load_meshes=False).robot
    ours = {j.name: j for j in desc.joints}
    assert set(ours) == {j.name for j in y.joints}
    for yj in y.joints:
        j = ours[yj.name]
        assert (j.type, j.parent, j.child) == (yj.type, yj.parent, yj.child)
        np.testing.assert_allclose(j.axis, yj.axis, atol=0)
        yo = np.eye(4) if yj.origin is None else yj.origin
        np.testing.assert_allclose(origin_matrix(j.origin), yo, atol=1e-12)
        if yj.limit is not None:
            assert (j.limit_lower, j.limit_upper) == (yj.limit.lower, yj.limit.upper)
        if yj.mimic is not None:
            assert (j.mimic.joint, j.mimic.multiplier, j.mimic.offset) == (
                yj.mimic.joint, yj.mimic.multiplier, yj.mimic.offset)
    assert set(desc.links) == {l.name for l in y.links}
    for yl in y.links:
        li = desc.links[yl.name]
        assert (li.inertial is None) == (yl.inertial is None)
        if yl.inertial is not None:
            assert li.inertial.mass == yl.inertial.mass
            np.testing.assert_array_equal(li.inertial.inertia, yl.inertial.inertia)
            yo = np.eye(4) if yl.inertial.origin is None else yl.inertial.origin
            np.testing.assert_allclose(origin_matrix(li.inertial.origin), yo, atol=1e-12)
        for ours_g, theirs in ((li.visuals, yl.visuals), (li.collisions, yl.collisions)):
            assert len(ours_g) == len(theirs)
            for g, yg in zip(ours_g, theirs):
                if g.kind == "mesh":
                    assert g.filename == yg.geometry.mesh.filename.strip()
                    scale = 1.0 if yg.geometry.mesh.scale is None else yg.geometry.mesh.scale
                    np.testing.assert_array_equal(g.scale, np.broadcast_to(scale, (3,)))
                else:
                    assert getattr(yg.geometry, g.kind) is not None
                yo = np.eye(4) if yg.origin is None else yg.origin
                np.testing.assert_allclose(origin_matrix(g.origin), yo, atol=1e-12)


@pytest.mark.parametrize("path", CORPUS_FILES, ids=lambda p: str(p.relative_to(CORPUS)))
def test_corpus_file_parses_or_raises_urdf_error(path):
    """Every corpus file parses, and agrees with yourdfpy's reading; the files known to be defective
    (KNOWN_BAD) raise exactly the error they are known for. A file wrongly refused fails here."""
    rel = path.relative_to(CORPUS).as_posix()
    if rel in KNOWN_BAD:
        cls, words = KNOWN_BAD[rel]
        with pytest.raises(URDFError) as info:
            parse_urdf(path)
        assert type(info.value) is cls and words in str(info.value), info.value
        return
    desc = parse_urdf(path)
    assert desc.root in desc.links and len(desc.joints) == len(desc.links) - 1
    _compare_with_yourdfpy(desc, path)


def test_corpus_is_there_and_refused_files_are_the_known_bad_ones():
    """The corpus is installed (the test extra) and has the files these tests were written against;
    the set of files parse_urdf refuses is exactly KNOWN_BAD."""
    assert CORPUS is not None, "example-robot-data is missing: pip install -e '.[test]' installs it"
    assert len(CORPUS_FILES) >= 60, f"only {len(CORPUS_FILES)} URDF files under {CORPUS}"
    refused = {}
    for path in CORPUS_FILES:
        try:
            parse_urdf(path)
        except URDFError as err:
            refused[path.relative_to(CORPUS).as_posix()] = f"{type(err).__name__}: {err}"
    assert set(refused) == set(KNOWN_BAD), refused

"""xacro input (issue 12): expansion with arguments, $(find pkg) and package:// resolved as for URDF,
the CLI's --xacro-arg, and clear errors without the extra or with a broken file. The xacro package is
in the test extra, so these run the real expander."""

from __future__ import annotations

import subprocess
import sys

import pytest

from urdf2links import load_urdf
from urdf2links.errors import URDFError

import xacro  # noqa: F401,E402 -- the xacro extra, in the test extra: a broken install fails the suite

MACRO = """<?xml version="1.0"?>
<robot xmlns:xacro="http://www.ros.org/wiki/xacro">
  <xacro:macro name="arm_link" params="name mass">
    <link name="${name}">
      <inertial><origin xyz="0 0 -0.25"/><mass value="${mass}"/>
        <inertia ixx="0.02" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.001"/></inertial>
      <visual><geometry><mesh filename="package://armpkg/meshes/link.stl"/></geometry></visual>
    </link>
  </xacro:macro>
</robot>
"""

ROBOT = """<?xml version="1.0"?>
<robot name="arm" xmlns:xacro="http://www.ros.org/wiki/xacro">
  <xacro:arg name="prefix" default=""/>
  <xacro:property name="prefix" value="$(arg prefix)"/>
  <xacro:include filename="$(find armpkg)/urdf/macros.xacro"/>
  <link name="${prefix}base"/>
  <xacro:arm_link name="${prefix}upper" mass="1.5"/>
  <joint name="${prefix}shoulder" type="revolute">
    <parent link="${prefix}base"/><child link="${prefix}upper"/><axis xyz="0 1 0"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/><dynamics damping="0.4"/>
  </joint>
</robot>
"""


@pytest.fixture
def workspace(tmp_path):
    """A ROS-like package folder ``ws/armpkg`` with ``urdf/`` and ``meshes/``, outside any ROS install."""
    pkg = tmp_path / "ws" / "armpkg"
    (pkg / "urdf").mkdir(parents=True)
    (pkg / "meshes").mkdir()
    (pkg / "meshes" / "link.stl").write_text("solid x\nendsolid x\n")
    (pkg / "urdf" / "macros.xacro").write_text(MACRO)
    (pkg / "urdf" / "arm.urdf.xacro").write_text(ROBOT)
    return pkg


def test_xacro_expands_with_arguments_and_finds_packages(workspace):
    m = load_urdf(workspace / "urdf" / "arm.urdf.xacro", xacro_args={"prefix": "left_"})
    assert m.coordinate_names == ("left_shoulder",)
    assert m.name == "arm"
    assert any("expanded by xacro (prefix:=left_)" in n for n in m.info["notes"]), m.info["notes"]
    assert m.info["joints"][0]["damping"] == 0.4
    default = load_urdf(workspace / "urdf" / "arm.urdf.xacro")  # the argument's default: no prefix
    assert default.coordinate_names == ("shoulder",)


def test_include_by_package_url(workspace):
    f = workspace / "urdf" / "by_url.urdf.xacro"
    f.write_text(ROBOT.replace("$(find armpkg)/urdf/macros.xacro", "package://armpkg/urdf/macros.xacro"))
    assert load_urdf(f).coordinate_names == ("shoulder",)
    macros_only = workspace / "urdf" / "macros.xacro"
    with pytest.raises(URDFError, match="only defines macros"):
        load_urdf(macros_only)


def test_package_meshes_of_an_expanded_xacro_resolve(workspace):
    from urdf2links.parsers.urdf import parse_urdf

    desc = parse_urdf(workspace / "urdf" / "arm.urdf.xacro")
    mesh = desc.links["upper"].visuals[0]
    assert mesh.path == (workspace / "meshes" / "link.stl").resolve()


def test_cli_xacro_arg(workspace):
    out = subprocess.run([sys.executable, "-m", "urdf2links.cli", "inspect", str(workspace / "urdf" / "arm.urdf.xacro"),
                          "--xacro-arg", "prefix:=right_"], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert "[right_shoulder]" in out.stdout and "expanded by xacro (prefix:=right_)" in out.stdout
    bad = subprocess.run([sys.executable, "-m", "urdf2links.cli", "inspect", str(workspace / "urdf" / "arm.urdf.xacro"),
                          "--xacro-arg", "prefix=right_"], capture_output=True, text=True)
    assert bad.returncode == 2 and "name:=value" in bad.stderr and "Traceback" not in bad.stderr


def test_broken_xacro_is_a_urdf_error_naming_the_file(workspace):
    f = workspace / "urdf" / "broken.urdf.xacro"
    f.write_text(ROBOT.replace("${prefix}base", "${undefined_property}base"))
    with pytest.raises(URDFError, match=r"broken\.urdf\.xacro: xacro could not expand the file"):
        load_urdf(f)


def test_unknown_package_is_named(tmp_path):
    f = tmp_path / "r.urdf.xacro"
    f.write_text(ROBOT.replace("$(find armpkg)", "$(find nowhere_pkg)"))
    with pytest.raises(URDFError, match="find nowhere_pkg.*package_dirs"):
        load_urdf(f)


def test_without_the_extra_the_error_says_what_to_install(workspace, monkeypatch):
    monkeypatch.setitem(sys.modules, "xacro", None)  # as if the package were not installed
    with pytest.raises(URDFError, match=r'pip install "urdf2links\[xacro\]"'):
        load_urdf(workspace / "urdf" / "arm.urdf.xacro")


def test_xacro_args_for_a_plain_urdf_are_refused(tmp_path):
    f = tmp_path / "r.urdf"
    f.write_text('<robot name="r"><link name="a"/></robot>')
    with pytest.raises(URDFError, match="not a .xacro file"):
        load_urdf(f, xacro_args={"prefix": "x"})

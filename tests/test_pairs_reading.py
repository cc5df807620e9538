"""Pairs that read (issue 43): a coupling is one difference naming both files' joints, effort through a tendon
actuator, each difference named as its part is called and said to be at rounding or not, one stated order
everywhere the list is printed, a pair's own summary.md and headline.

The second files are MuJoCo's import of the shipped ur5_like arm (``wrist_3_joint`` mimicking ``wrist_2_joint``:
multiplier 2, offset 0.1), edited through MjSpec the way hand-written MJCFs differ: joints renamed, the coupling's
roles swapped, a tendon actuator holding two joints.
"""

from __future__ import annotations

import json
import math
import re
import warnings

import mujoco
import numpy as np
import pytest

from urdf2links.cli import main
from urdf2links.compare.pairs.effects import EFFECT_ROUNDING, ORDER_WORDS, effect_size
from urdf2links.compare.pairs.mujoco_import import save_mujoco_import
from urdf2links.compare.pairs.pair import compare_descriptions_of
from urdf2links.locations import shipped_robots_dir


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    return tmp_path_factory.mktemp("reading")


@pytest.fixture(scope="module")
def mimic_arm(folder):
    """ur5_like with wrist_3 mimicking wrist_2 (q3 = 2 q2 + 0.1), and MuJoCo's import of it (a joint equality)."""
    text = (shipped_robots_dir() / "ur5_like.urdf").read_text()
    head, tail = text.split('<joint name="wrist_3_joint"', 1)
    limit_end = tail.index("/>", tail.index("<limit")) + 2
    tail = tail[:limit_end] + '\n    <mimic joint="wrist_2_joint" multiplier="2" offset="0.1"/>' + tail[limit_end:]
    urdf = folder / "ur5_mimic.urdf"
    urdf.write_text(head + '<joint name="wrist_3_joint"' + tail)
    return urdf, save_mujoco_import(urdf, folder / "ur5_mimic.xml", keep_geometry=False, keep_frames=True).path


def _compare(urdf, mjcf):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return compare_descriptions_of(urdf, mjcf)


def _edited(pair, folder, name, edit):
    spec = mujoco.MjSpec.from_file(str(pair[1]))
    edit(spec)
    spec.compile()
    out = folder / f"{name}.xml"
    out.write_text(spec.to_xml())
    return out


def _renamed_and_swapped(spec, polycoef):
    """Joints wrist_2/wrist_3 named j5/j6 (the file's own names) and the equality written j5 = f(j6)."""
    spec.joint("wrist_2_joint").name = "j5"
    spec.joint("wrist_3_joint").name = "j6"
    eq = next(iter(spec.equalities))
    eq.name1, eq.name2 = "j5", "j6"
    eq.data = np.r_[polycoef, np.zeros(eq.data.size - 2)]


# -- 2. a coupling is one difference that names both files' joints ---------------------------------------------
def test_a_coupling_with_its_roles_swapped_is_the_same_coupling(mimic_arm, folder):
    """q3 = 2 q2 + 0.1 written as q2 = 0.5 q3 - 0.05 under other names: no coupling difference (the old reading
    listed it twice, 'first description only' and 'second description only')."""
    same = _edited(mimic_arm, folder, "swapped", lambda s: _renamed_and_swapped(s, [-0.05, 0.5]))
    c = _compare(mimic_arm[0], same)
    assert {(m.urdf, m.mjcf) for m in c.mapping.matches} >= {("wrist_2_joint", "j5"), ("wrist_3_joint", "j6")}
    assert [d.label() for d in c.differences if d.kind == "coupling"] == []


def test_a_different_coupling_with_its_roles_swapped_is_one_difference_naming_both(mimic_arm, folder):
    """q2 = 0.6 q3 - 0.05, i.e. q3 = 1.667 q2 + 0.0833: one difference of 2 - 1/0.6 = 0.333, at wrist_3 / j6."""
    other = _edited(mimic_arm, folder, "swapped_other", lambda s: _renamed_and_swapped(s, [-0.05, 0.6]))
    cs = [d for d in _compare(mimic_arm[0], other).differences if d.kind == "coupling"]
    assert len(cs) == 1, [d.what for d in cs]
    d = cs[0]
    assert (d.urdf, d.mjcf, d.part) == ("wrist_3_joint", "j6", "joint")
    assert d.difference == pytest.approx(2 - 1 / 0.6, rel=1e-9)
    assert d.mjcf_value == pytest.approx([1 / 0.6, 0.05 / 0.6], rel=1e-9)       # in the first file's form
    for name in ("wrist_2_joint", "wrist_3_joint", "j5", "j6"):                   # both files' joints named
        assert name in d.what, (name, d.what)


# -- 3. effort through a tendon actuator ---------------------------------------------------------------------
def _tendon_actuator(spec, force):
    """A fixed tendon of wrist_2 and wrist_3 (coefficient 0.5 each), its actuator limited to +-``force`` (gear 1),
    and the joints' own actuatorfrcrange removed (as in Menagerie's gripper: the force is limited on the tendon)."""
    t = spec.add_tendon(name="wrists")
    for j in ("wrist_2_joint", "wrist_3_joint"):
        t.wrap_joint(j, 0.5)
        spec.joint(j).actfrclimited = 0
    a = spec.add_actuator(name="wrists_act", target="wrists", trntype=mujoco.mjtTrn.mjTRN_TENDON)
    a.gear = [1, 0, 0, 0, 0, 0]
    a.forcelimited, a.forcerange = 1, [-force, force]


def test_effort_through_a_tendon_actuator(folder):
    """The URDF's 28 N m at each wrist against a tendon actuator's forcerange x gear x coefficient: +-56 N gives
    28 N m (no difference; the old reading said '28 against None' at both), +-40 N gives 20 N m (8/28 each)."""
    urdf = shipped_robots_dir() / "ur5_like.urdf"
    arm = (urdf, save_mujoco_import(urdf, folder / "arm.xml", keep_geometry=False, keep_frames=True).path)
    same = _compare(urdf, _edited(arm, folder, "tendon56", lambda s: _tendon_actuator(s, 56.0)))
    assert [d.label() for d in same.differences if d.kind == "effort"] == []
    weaker = _compare(urdf, _edited(arm, folder, "tendon40", lambda s: _tendon_actuator(s, 40.0)))
    eff = {d.urdf: d for d in weaker.differences if d.kind == "effort"}
    assert set(eff) == {"wrist_2_joint", "wrist_3_joint"}
    for d in eff.values():
        assert d.mjcf_value == pytest.approx(20.0) and d.difference == pytest.approx(8 / 28)
        assert "wrists_act" in d.what and "tendon wrists" in d.what and d.effect["at_rounding"] is True

"""The pairs flow computed once (issue 44): one :class:`PairContext` holds both sides' parts, home poses, joint mapping,
matched bodies and the roots' alignment, and the differences, collisions, effects and motion read from it.

``home_poses`` used to be recomputed on every visit (46 calls for ``compare ur5_like --against ur5_like_mujoco``, on
two pose sets). The counter below wraps it in every module that calls it, so that a stage that computes the home
poses again makes the count grow; and a side whose undo moved a body must get its own poses, never the cached ones.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from urdf2links.compare.pairs import context as context_module
from urdf2links.compare.pairs import mapping as mapping_module
from urdf2links.compare.pairs import roots as roots_module
from urdf2links.compare.pairs.context import pair_context
from urdf2links.compare.pairs.pair import compare_descriptions_of
from urdf2links.locations import shipped_robots_dir
from urdf2links.parsers import parts as parts_module
from urdf2links.parsers.parts import home_poses, robot_parts

URDF = shipped_robots_dir() / "ur5_like.urdf"
MJCF = shipped_robots_dir() / "ur5_like_mujoco.xml"     # MuJoCo's import of it, armature added (6 differences)


@pytest.fixture
def home_calls(monkeypatch):
    """How many times ``home_poses`` runs from here on, whichever module calls it."""
    n = {"calls": 0}
    real = parts_module.home_poses

    def counted(parts):
        n["calls"] += 1
        return real(parts)

    for module in (parts_module, context_module, mapping_module, roots_module):
        monkeypatch.setattr(module, "home_poses", counted)
    return n


def _pair(urdf=URDF, mjcf=MJCF):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return compare_descriptions_of(urdf, mjcf)


def test_a_pair_computes_its_home_poses_once_per_side(home_calls):
    c = _pair()
    assert [d.kind for d in c.differences] == ["armature"] * 6
    assert home_calls["calls"] == 2          # the context's two; the armature undos move no body
    # and undoing them all still removes A's difference (2.5e-2 with the armature) down to MuJoCo's 6 written digits
    # (EFFECT_ROUNDING 1e-5; 3.3e-9 measured)
    assert c.effects["mapped"]["A"]["max_rel_difference"] > 1e-2
    assert c.effects["after_undoing_all"]["A"] < 1e-5


def test_an_undo_that_moves_a_body_gets_its_own_home_poses(tmp_path, home_calls):
    """The planted case: the second file with a body moved 2 cm. Its origin's undo moves the body back; had the
    cached poses served the moved side, the undo would change nothing and A's difference would stay."""
    text = MJCF.read_text()
    moved = text.replace('<body name="forearm_link" pos="0 -0.1197 0.425"', '<body name="forearm_link" pos="0.02 -0.1197 0.425"')
    assert moved != text, "ur5_like_mujoco.xml's forearm_link is no longer where this test moves it from"
    (tmp_path / "moved.xml").write_text(moved)
    c = _pair(MJCF, tmp_path / "moved.xml")
    origin = [d for d in c.differences if d.kind == "origin"]
    assert len(origin) == 1 and origin[0].difference == pytest.approx(0.02, abs=1e-9)
    assert home_calls["calls"] > 2           # the moved side's poses computed, not taken from the cache
    # the move changes A by far more than rounding; undoing it takes A back to the unmoved file's (the same digits
    # on both sides: exact up to the floating point of the undo, 1e-9 is a generous bound)
    assert c.effects["mapped"]["A"]["max_rel_difference"] > 1e-3
    assert c.effects["after_undoing_all"]["A"] < 1e-9


def test_home_of_reuses_only_a_side_whose_bodies_stay_in_place():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ctx = pair_context(robot_parts(URDF), robot_parts(MJCF))
    assert ctx.home_of(ctx.mjcf) is ctx.home_mjcf and ctx.home_of(ctx.urdf) is ctx.home_urdf
    armature = ctx.mjcf.with_joint("elbow_joint", armature=0.5)
    assert ctx.home_of(armature) is ctx.home_mjcf
    body = ctx.mjcf.body("forearm_link")
    pose = np.array(body.pose, float)
    pose[0, 3] += 0.02
    moved = ctx.mjcf.replaced("forearm_link", pose=pose)
    W = ctx.home_of(moved)
    assert W is not ctx.home_mjcf
    for name, F in home_poses(moved).items():
        assert np.array_equal(W[name], F), name
    assert not np.allclose(W["forearm_link"], ctx.home_mjcf["forearm_link"])

"""Constraints and fixed tendons in MuJoCo (issue 36): the same equalities on both engines, the terms at
identical states (Phi_q against efc_J, lambda against efc_force), MuJoCo converging as solref shrinks, an MJCF
file's equalities and tendons read and run as written (route 2), gymnasium's tendons."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import mujoco
import numpy as np
import pytest

import urdf2links
from urdf2links.compare.agreement.constraint_agreement import constraint_terms, solref_study
from urdf2links.compare.mujoco_side.mjcf import mjcf_from_scene
from urdf2links.compare.mujoco_side.mujoco_constraints import equality_rows, shifted_polycoef, with_constraints
from urdf2links.dynamics.constraints import Constraint, ConstraintSet
from urdf2links.integration import simulate
from urdf2links.integration.constrained import ConstrainedRHS
from urdf2links.locations import shipped_robots_dir
from urdf2links.scenes import as_plan
from urdf2links.scenes.constraints import SceneConstraints
from urdf2links.scenes.tendons import FixedTendon

LOOPS = shipped_robots_dir() / "loops"


@pytest.fixture(scope="module")
def leg():
    plan = as_plan(LOOPS / "closed_leg_swing.toml")
    return plan, simulate(plan, progress=False, t_end=0.2, samples=21)


@pytest.fixture(scope="module")
def four_bar():
    plan = as_plan(LOOPS / "four_bar_crank.toml")
    return plan, simulate(plan, progress=False, t_end=0.2, samples=21)


def test_mujoco_approaches_ours_as_solref_shrinks(four_bar, record_figure):
    """MuJoCo's soft constraint (route 1) against the exact one: max |q_MuJoCo - q| over 0.2 s for solref
    tau = 1e-2, 1e-3, 1e-4 s. The issue asks at least 5x per 10x; measured about 300x (rate 2.5)."""
    plan, tr = four_bar
    st = solref_study(plan, tr)
    for r in st["runs"]:
        record_figure("solref study (four bar, route 1)", f"tau {r['tau']:g} s: max |dq|", r["max_error"], "{:.2e}")
    assert st["holds"] and min(st["ratios"]) > 50
    assert st["runs"][-1]["max_error"] < 1e-8


def test_route2_runs_the_file_equalities_and_tendon(leg):
    """The MJCF file itself in MuJoCo (route 2), its connect, joint equality and tendon spring on: it converges
    to our run of what we read from it; the smallest tau within 1e-8 rad (measured 3e-9 over 1 s)."""
    plan, tr = leg
    st = solref_study(plan, tr, route=2, taus=(1e-3, 1e-4))
    assert st["ratios"][0] > 20 and st["runs"][-1]["max_error"] < 1e-8


def test_terms_at_identical_states(leg, four_bar):
    """Phi_q against efc_J rows (to rounding) and lambda against efc_force, J^T lambda against qfrc_constraint,
    relative to MuJoCo's regularizer at solimp 0.9999 (measured 5e-5 on the four bar, 1.7e-3 on the leg, whose
    connect and joint rows share coordinates)."""
    for plan, tr in (leg, four_bar):
        mj = with_constraints(mjcf_from_scene(plan.scene, plan.model), plan.constraints, solref=(1e-3, 1.0))
        t = constraint_terms(plan, mj, [(tr.q[i], tr.qd[i]) for i in (5, 15)])
        assert t["jacobian"]["max_abs"] < 1e-12 * max(1.0, t["jacobian"]["scale"])
        assert t["force"]["max_abs"] < 5e-3 * t["force"]["scale"]
        assert t["generalized_force"]["max_abs"] < 5e-3 * t["generalized_force"]["scale"]


def test_weld_rows_against_mujoco():
    """A weld (E69) of the UR5's last link to the world, at a state where it holds: our rows mapped (rotation
    rows by 0.5 R_2^T) equal efc_J; the six rows lock the arm, so J^T lambda = G, and qfrc_constraint is that
    to MuJoCo's regularizer (1e-4)."""
    model = urdf2links.load_urdf(shipped_robots_dir() / "ur5_like.urdf")
    from urdf2links.scenes.scene_read import scene_from_dict

    scene = scene_from_dict({"robot": {"urdf": str(shipped_robots_dir() / "ur5_like.urdf")}, "gravity": {"magnitude": 9.81},
                             "constraint": [{"name": "w", "kind": "weld", "links": ["wrist_3_link"],
                                             "points": [[0.0, 0.02, 0.1], [0.0, 0.0, 0.0]]}]}, where="w.toml")
    q = np.array([0.3, -0.8, 1.1, -0.4, 0.7, 0.2])
    plan = as_plan(dataclasses.replace(scene, q0=dict(zip(model.coordinate_names, q))), model=model)
    c = plan.constraints.cset.constraints[0]
    T = model.link_poses(q)
    p = T[c.link1]
    c = dataclasses.replace(c, point2=(p @ np.r_[c.point1, 1.0])[:3], frame2=p[:3, :3] @ c.frame1)
    plan.constraints = SceneConstraints(ConstraintSet(model, [c]))
    mj = with_constraints(mjcf_from_scene(plan.scene, model), plan.constraints, solref=(1e-3, 1.0))
    t = constraint_terms(plan, mj, [(q, np.zeros(6))])
    assert t["jacobian"]["max_abs"] < 1e-12
    assert t["generalized_force"]["max_abs"] < 3e-2 * t["generalized_force"]["scale"]
    rhs = ConstrainedRHS(plan, q0=q)
    _, lam, J = rhs.solve(0.0, np.r_[q, np.zeros(6), 0.0])
    assert np.allclose(J.J.T @ lam, model.gravity(q), atol=1e-9)


def test_shifted_polycoef():
    c, ra, rb = np.array([0.1, -0.7, 0.3, 0.2, -0.05]), 0.2, -0.4
    x = np.linspace(-1, 1, 7)
    assert np.allclose(np.polynomial.polynomial.polyval(x, shifted_polycoef(c, ra, rb)),
                       ra + np.polynomial.polynomial.polyval(x - rb, c), atol=1e-14)


def test_tendon_law_against_mujoco():
    """A fixed tendon (E76) with stiffness, damping, a dead-band spring length and a position actuator on it
    (gear 2): our generalized forces against MuJoCo's qfrc_passive and qfrc_actuator at one state (rounding)."""
    from urdf2links.scenes.actuators import Actuator
    from urdf2links.scenes.functions import Constant

    plan = as_plan(LOOPS / "four_bar_crank.toml")
    model = plan.model
    act = Actuator("pull", "t", -1, "position", 30.0, (0.0, -30.0, -2.0), 2.0, Constant(0.4), None, (-5.0, 5.0),
                   "file", "t", 30.0, 2.0)
    td = FixedTendon("t", np.array([1.0, -0.5, 0.25]), 7.0, 0.3, (0.05, 0.15), (act,))
    mj = with_constraints(mjcf_from_scene(plan.scene, model), SceneConstraints(ConstraintSet(model, []), (td,)))
    q, qd = np.array([0.9, -0.2, 0.4]), np.array([0.5, 1.0, -2.0])
    d = mj.data(q, qd)
    d.ctrl[:] = 0.4
    mujoco.mj_forward(mj.model, d)
    f, _ = td.force(0.0, q, qd)
    got = np.asarray(d.qfrc_passive)[mj.dof_index] + np.asarray(d.qfrc_actuator)[mj.dof_index]
    assert np.allclose(got, f, rtol=1e-12, atol=1e-12)
    assert abs(td.length(q) - float(d.ten_length[0])) < 1e-14


def test_mjcf_equalities_and_tendons_are_read():
    """The file's connect (anchors in both bodies), joint equality (polycoef, qpos0) and fixed tendon are in
    model.info; the notes say how they act; the plan lists them."""
    model = urdf2links.load_mjcf(LOOPS / "closed_leg.xml")
    eq = {r["name"]: r for r in model.info["equalities"]}
    assert eq["knee_loop"]["kind"] == "connect" and np.allclose(eq["knee_loop"]["anchor2"], [0.08, 0, 0])
    assert eq["ankle_follows_hip"]["polycoef"][:2] == [0.0, -0.5]
    (t,) = model.info["tendons"]
    assert t["fixed"] and t["joints"] == [("hip", 1.0), ("rod_hip", 1.0)] and t["stiffness"] == 4.0
    assert any("connect, weld and joint are read" in n for n in model.info["notes"])
    from urdf2links.cli import format_tree

    table = format_tree(model)
    assert "knee_loop          connect  rod / shank" in table and "hip_spring  fixed  1 hip + 1 rod_hip" in table
    text = as_plan(LOOPS / "closed_leg_swing.toml").describe()
    assert "constraint 'knee_loop' (connect, MJCF <connect>" in text and "tendon 'hip_spring'" in text


def test_gymnasium_humanoid_tendons():
    """Gymnasium's MJCF models with equalities or fixed tendons: humanoid and humanoidstandup have two fixed
    tendons each and no equality. Read with from_file, they carry no force (no stiffness, damping, limit or
    actuator): the run with them on equals the run without, on both engines."""
    import gymnasium

    path = Path(gymnasium.__file__).parent / "envs/mujoco/assets/humanoid.xml"
    model = urdf2links.load_mjcf(path)
    names = [t["name"] for t in model.info["tendons"]]
    assert names == ["left_hipknee", "right_hipknee"]
    assert all(t["fixed"] and not t["stiffness"] and not t["damping"] and not t["limited"] and not t["actuators"]
               for t in model.info["tendons"])
    from urdf2links.scenes.scene_read import scene_from_dict

    scene = scene_from_dict({"robot": {"mjcf": str(path)}, "constraints": {"from_file": True}}, where="h.toml")
    plan = as_plan(scene, model=model)
    assert plan.constraints is None     # nothing acts: the plan says so by not listing them


def test_pairs_report_a_loop_closed_on_one_side(tmp_path):
    """Kind ``constraint`` of a pair: the leg without its <connect> is another mechanism (3 rows), and a
    moved anchor is a difference in m; the parts themselves are the same."""
    import re

    from urdf2links.compare.pairs.pair import compare_descriptions_of

    src = (LOOPS / "closed_leg.xml").read_text()
    (tmp_path / "open.xml").write_text(re.sub(r"<connect[^>]*/>", "", src))
    (tmp_path / "moved.xml").write_text(src.replace('anchor="0 0 -0.4"', 'anchor="0 0 -0.39"'))
    (d,) = compare_descriptions_of(LOOPS / "closed_leg.xml", tmp_path / "open.xml", states=2).differences
    assert (d.kind, d.urdf, d.mjcf, d.difference) == ("constraint", "knee_loop", None, 3.0)
    (d,) = compare_descriptions_of(LOOPS / "closed_leg.xml", tmp_path / "moved.xml", states=2).differences
    assert d.kind == "constraint" and abs(d.difference - 0.01) < 1e-12 and d.unit == "m"


def test_verdict_scope_counts_what_the_plan_models():
    """The verdict's scope (issue 35's cut_scope) no longer calls a run 'the open tree of a closed mechanism'
    when the scene's constraints model the file's equalities and tendons, or the URDF's mimic."""
    from urdf2links.compare.agreement.verdict import FULL_SCOPE, cut_scope
    from urdf2links.scenes import load_scene

    plan = as_plan(LOOPS / "closed_leg_swing.toml")
    assert cut_scope(plan.model, {}, plan)["text"] == FULL_SCOPE
    assert "2 constraints, 1 tendon dropped" in cut_scope(plan.model, {})["text"]
    g = as_plan(LOOPS / "mimic_gripper_swing.toml")
    scene = load_scene(LOOPS / "mimic_gripper_swing.toml")
    assert cut_scope(g.model, scene.load_options, g)["text"] == FULL_SCOPE
    assert "mimic" in cut_scope(g.model, scene.load_options)["text"]

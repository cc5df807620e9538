"""Actuators as scene effects (issue 26): reading ``[[actuator]]``, MuJoCo's law (E55) against MuJoCo itself,
the compiled right-hand side against its numpy twin, an MJCF file's own actuators, gravcomp, ``--hold``.

Tolerances: the law is a handful of products, so the project's forces equal MuJoCo's ``qfrc_actuator``
to rounding (1e-12 relative to max(|force|, 1 N): measured 0 to 5e-16); the compiled right-hand side and
its numpy twin differ by the recursive terms' rounding (1e-11 relative: measured ~6e-14, as for every
other term in tests/test_scenes.py).
"""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from test_mjcf import GYM
from urdf2links.compare.agreement.actuator_terms import file_actuators, route1_actuators, route2_actuators
from urdf2links.compare.mujoco_side.mjcf import mjcf_from_scene
from urdf2links.compare.mujoco_side.mujoco_mjcf import mujoco_from_mjcf
from urdf2links.errors import SceneError
from urdf2links.locations import shipped_robots_dir
from urdf2links.scenes.actuators import hold_actuators
from urdf2links.scenes.plan import as_plan, compile_plan
from urdf2links.scenes.python_plan import PythonPlan
from urdf2links.scenes.default_scenes import default_scene
from urdf2links.scenes.scene_read import scene_from_dict
from urdf2links.scenes.scene_toml import scene_toml

UR5 = str(shipped_robots_dir() / "ur5_like.urdf")
CART = str(shipped_robots_dir() / "cart_arm.xml")

#: one actuator of every kind and clamp, on the UR5-like arm
ACTUATORS = [
    {"coordinate": "elbow_joint", "kind": "position", "kp": 300.0, "kv": 30.0, "ctrl": {"sines": [[0.8, 1.0]]},
     "forcerange": [-20, 20]},
    {"coordinate": "shoulder_lift_joint", "kind": "velocity", "kv": 5.0, "ctrl": 0.3, "gear": 2.0,
     "ctrlrange": [-0.1, 0.1]},
    {"coordinate": "wrist_1_joint", "kind": "general", "gainprm": [2.0], "biasprm": [0.1, -3.0, -0.5], "ctrl": 1.0,
     "gear": -1.5, "forcerange": [-0.4, 0.7], "ctrlrange": [-2, 0.5]},
    {"coordinate": "wrist_3_joint", "kind": "motor", "gear": 10.0, "ctrl": {"sines": [[0.02, 1.0]]}},
]


def _scene(**more):
    d = {"robot": {"urdf": UR5}, "gravity": {}, "actuator": ACTUATORS, "run": {"t_end": 1.0}}
    d.update(more)
    return scene_from_dict(d)


def _fail(data, match):
    with pytest.raises(SceneError, match=match):
        plan = as_plan(scene_from_dict(data, where="s.toml"))
        return plan


def test_reading_names_the_block_and_key():
    base = {"robot": {"urdf": UR5}}
    _fail({**base, "actuator": [{"coordinate": "elbow_joint", "kind": "servo", "ctrl": 0}]}, r"actuator\[0\].kind")
    _fail({**base, "actuator": [{"coordinate": "elbow_joint", "kind": "position", "ctrl": 0}]}, r"actuator\[0\].kp")
    _fail({**base, "actuator": [{"coordinate": "elbow_joint", "kind": "velocity", "ctrl": 0}]}, r"actuator\[0\].kv")
    _fail({**base, "actuator": [{"coordinate": "elbow_joint", "kind": "motor"}]}, r"actuator\[0\].ctrl")
    _fail({**base, "actuator": [{"coordinate": "elbow_joint", "ctrl": 0, "ctrlrange": [1, -1]}]}, "low 1 must be below")
    _fail({**base, "actuator": [{"coordinate": "elbow_joint", "ctrl": 0, "gear": 0}]}, "gear.*must not be 0")
    _fail({**base, "actuator": [{"coordinate": "elbow_joint", "kind": "motor", "kp": 3, "ctrl": 0}]},
          r"actuator\[0\].kp.*unknown key")
    _fail({**base, "actuator": [{"coordinate": "elbow_joint", "kind": "general", "gainprm": [1, 2], "ctrl": 0}]},
          "only the first 1 entries act")
    _fail({**base, "actuator": [{"coordinate": "elbow", "ctrl": 0}]}, "'elbow' is not a coordinate")
    _fail({**base, "actuator": [{"name": "push", "ctrl": 0}]}, "not an actuator of 'ur5_like'")
    _fail({**base, "actuator": [{"coordinate": "elbow_joint", "ctrl": 0, "name": "a"},
                                {"coordinate": "wrist_1_joint", "ctrl": 0, "name": "a"}]}, "named twice")
    _fail({**base, "actuator": [{"ctrl": 0}]}, "name the coordinate it drives")


def test_shortcuts_expand_as_mujocos_compiler():
    """position: gain kp, bias (0, -kp, -kv); velocity: gain kv, bias (0, 0, -kv); motor: gain 1 (MuJoCo's own
    expansion of <position>, <velocity>, <motor>, read back from a compiled model)."""
    m = mujoco.MjModel.from_xml_string("""<mujoco><worldbody><body><joint name="j"/><geom size="0.1"/></body>
      </worldbody><actuator><position joint="j" kp="7" kv="3"/><velocity joint="j" kv="4"/><motor joint="j"/>
      </actuator></mujoco>""")
    plan = as_plan(scene_from_dict({"robot": {"urdf": UR5}, "actuator": [
        {"coordinate": "elbow_joint", "kind": "position", "kp": 7.0, "kv": 3.0, "ctrl": 0},
        {"coordinate": "elbow_joint", "kind": "velocity", "kv": 4.0, "ctrl": 0},
        {"coordinate": "elbow_joint", "kind": "motor", "ctrl": 0}]}))
    for k, a in enumerate(plan.actuator_set.actuators):
        assert a.gain == m.actuator_gainprm[k, 0]
        assert list(a.bias) == list(m.actuator_biasprm[k, :3])


def test_the_law_equals_mujocos_on_both_routes():
    """At seeded states crossing both clamps, the project's forces against MuJoCo's qfrc_actuator: route 1
    (its MJCF) and route 2 (MuJoCo's own URDF import with the actuators added)."""
    scene = _scene()
    plan = as_plan(scene)
    mj = mjcf_from_scene(scene, plan.model)
    for result in (route1_actuators(plan, mj, states=40, seed=3), route2_actuators(plan, scene.robot, states=40, seed=3)):
        assert result["max_rel_error_actuator"] < 1e-12, result


def test_clamps_engage_in_that_check():
    """The states of the check above reach both clamps (else the check would not test them)."""
    plan = as_plan(_scene())
    rng = np.random.default_rng(3)
    hit = set()
    for _ in range(40):
        t = float(rng.uniform(0.0, 1.0))
        q, qd = rng.uniform(-1.0, 1.0, plan.n), rng.standard_normal(plan.n)
        for a in plan.actuator_set.actuators:
            c = float(a.ctrl(t))
            if a.ctrlrange is not None and not a.ctrlrange[0] <= c <= a.ctrlrange[1]:
                hit.add(("ctrl", a.name))
            f = a.gain * min(max(c, *(a.ctrlrange or (-np.inf,))), *(a.ctrlrange[1:] if a.ctrlrange else (np.inf,)))
            f += a.bias[0] + a.bias[1] * a.gear * q[a.index] + a.bias[2] * a.gear * qd[a.index]
            if a.forcerange is not None and not a.forcerange[0] <= f <= a.forcerange[1]:
                hit.add(("force", a.name))
    assert {k for k, _ in hit} == {"ctrl", "force"}, hit


def test_compiled_right_hand_side_equals_the_numpy_twin():
    """Actuators, a computed torque, gravcomp, loads, springs and dampers together; also a moving base and
    coupled (mimic) coordinates."""
    rng = np.random.default_rng(4)
    scenes = [
        _scene(computed_torque=[{"coordinate": "shoulder_pan_joint", "reference": {"sines": [[0.5, 0.5]]}}],
               gravcomp={"factor": 0.5}, spring=[{"coordinate": "wrist_2_joint", "stiffness": 3.0, "damping": 0.2}],
               force=[{"link": "forearm_link", "value": [1.0, 0.0, {"sines": [[2.0, 0.5]]}], "point": [0.1, 0, 0]}]),
        _scene(base={"z": {"sines": [[0.05, 1.0]]}, "phi_x": {"sines": [[0.1, 0.5]]}},
               computed_torque=[{"coordinate": "elbow_joint", "reference": {"sines": [[0.4, 0.7]], "offset": 0.3}}]),
    ]
    for scene in scenes:
        plan = as_plan(scene)
        twin = PythonPlan(plan)
        for k in range(4):
            t, y = 0.31 * k, np.r_[rng.normal(size=2 * plan.n), 0.0]
            a, b = plan.rhs(t, y), twin.rhs(t, y)
            assert np.abs(a - b).max() < 1e-11 * max(1.0, np.abs(b).max()), (k, np.abs(a - b).max())


def test_coupled_coordinates_take_actuators_and_computed_torque(tmp_path):
    from test_importer import MIMIC

    path = tmp_path / "gripper.urdf"
    path.write_text(MIMIC)
    scene = scene_from_dict({"robot": {"urdf": str(path), "mimic": "coupled"}, "gravity": {},
                             "actuator": [{"coordinate": "left", "kind": "velocity", "kv": 2.0, "ctrl": 0.1}],
                             "computed_torque": [{"coordinate": "left", "reference": {"sines": [[0.01, 1.0]], "offset": 0.02}}]})
    plan = as_plan(scene)
    twin = PythonPlan(plan)
    y = np.array([0.02, 0.05, 0.0])
    assert np.abs(plan.rhs(0.2, y) - twin.rhs(0.2, y)).max() < 1e-11 * np.abs(twin.rhs(0.2, y)).max()


def test_only_scenes_that_name_actuators_compute_them():
    plan = as_plan(scene_from_dict({"robot": {"urdf": UR5}, "gravity": {}}))
    assert "actuator" not in plan.terms and "computed_torque" not in plan.terms
    assert "not computed" in plan.describe() and "actuator" in plan.describe().split("not computed")[1]
    plan = as_plan(_scene())
    assert "actuator" in plan.terms
    text = plan.describe()
    assert "actuator 'position:elbow_joint' on elbow_joint (scene): position kp 300, kv 30, gear 1, forcerange [-20, 20]" \
        in text


# -- an MJCF file's own actuators ----------------------------------------------------------------------
def test_file_actuators_are_read_as_mujoco_compiled_them():
    """Every gymnasium model: each actuator the law covers (joint transmissions on hinges and slides),
    named in a scene, gives MuJoCo's own qfrc_actuator through the state map (tau = J^T qfrc_actuator)."""
    from urdf2links import load_mjcf

    checked = 0
    for path in GYM:
        model = load_mjcf(path)
        rows = [r for r in model.info["actuators"] if r["name"]]
        usable = [r for r in rows if r["joint_type"] in ("hinge", "slide") and r["trntype"] == "joint"
                  and r["dyntype"] == "none"]
        if not usable:
            continue
        scene = scene_from_dict({"robot": {"mjcf": str(path)},
                                 "actuator": [{"name": r["name"], "ctrl": {"sines": [[1.5, 0.7, k]]}}
                                              for k, r in enumerate(usable)]})
        plan = as_plan(scene, model=model)
        mf = mujoco_from_mjcf(plan)
        result = file_actuators(plan, mf, states=6, seed=5)
        assert result["max_rel_error_actuator"] < 1e-12, (path.name, result)
        checked += len(usable)
    assert checked >= 20, checked      # reacher, hopper, walker2d, half_cheetah, ... carry motors with gears


def test_file_actuators_that_cannot_be_scene_effects_are_refused_by_name(tmp_path):
    xml = tmp_path / "ball.xml"
    xml.write_text("""<mujoco><worldbody><body pos="0 0 1"><joint name="b" type="ball"/><geom size="0.1"/>
      <body pos="0 0 -0.3"><joint name="h" axis="1 0 0"/><geom size="0.05"/></body></body></worldbody>
      <actuator><motor name="ball_motor" joint="b" gear="1 0 0 0 0 0"/>
      <general name="filtered" joint="h" dyntype="filter" dynprm="0.1"/></actuator></mujoco>""")
    with pytest.raises(SceneError, match="'ball_motor'.*ball joint.*out of scope"):
        as_plan(scene_from_dict({"robot": {"mjcf": str(xml)}, "actuator": [{"name": "ball_motor", "ctrl": 1.0}]}))
    with pytest.raises(SceneError, match="'filtered'.*activation dynamics"):
        as_plan(scene_from_dict({"robot": {"mjcf": str(xml)}, "actuator": [{"name": "filtered", "ctrl": 1.0}]}))
    with pytest.raises(SceneError, match="only the file's actuator|unknown key"):
        as_plan(scene_from_dict({"robot": {"mjcf": str(xml)}, "actuator": [{"name": "filtered", "ctrl": 1.0, "kp": 3}]}))
    # a scene actuator on the ball's coordinates is fine: MuJoCo's run of the file applies the project's law
    # through the control callback (no MuJoCo joint actuator acts on ZYX angles)
    plan = as_plan(scene_from_dict({"robot": {"mjcf": str(xml)}, "actuator": [
        {"coordinate": "b.phi_x", "kind": "position", "kp": 3.0, "ctrl": 0.1}]}))
    mf = mujoco_from_mjcf(plan)
    assert mf.actuator_ids == (-1,) and any("qfrc_applied from the control callback" in n for n in mf.notes)


def test_the_files_other_actuators_are_switched_off():
    plan = as_plan(scene_from_dict({"robot": {"mjcf": CART}, "actuator": [
        {"coordinate": "elbow", "kind": "position", "kp": 20.0, "ctrl": 0.2}]}))
    mf = mujoco_from_mjcf(plan)
    m = mf.model
    push = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, "push")
    assert m.actuator_gainprm[push, 0] == 0.0 and not (m.opt.disableflags & int(mujoco.mjtDisableBit.mjDSBL_ACTUATION))
    assert any("push" in n for n in mf.notes)
    assert any("push" in n for n in plan.actuator_set.notes)


# -- gravcomp as a scene key ---------------------------------------------------------------------------
def test_gravcomp_of_urdf_links_equals_mujocos_body_gravcomp():
    """``[gravcomp] factor`` on every link and ``bodies`` on one, for a URDF robot: the project's generalized
    force against route 1's qfrc_passive (MuJoCo's body gravcomp, written into the bodies)."""
    scene = scene_from_dict({"robot": {"urdf": UR5}, "gravity": {},
                             "gravcomp": {"factor": 0.7, "bodies": {"forearm_link": 0.2, "wrist_3_link": 0.0}}})
    plan = as_plan(scene)
    mj = mjcf_from_scene(scene, plan.model)
    assert mj.gravcomp_in_bodies
    twin = PythonPlan(plan)
    rng = np.random.default_rng(6)
    for _ in range(4):
        q = rng.uniform(-1, 1, plan.n)
        d = mj.data(q, np.zeros(plan.n))
        ours = twin.generalized_forces(0.0, q, np.zeros(plan.n))
        theirs = d.qfrc_passive[mj.dof_index]
        assert np.abs(ours - theirs).max() < 1e-12 * np.abs(theirs).max()
    table = scene.gravcomp_table(plan.model)
    assert table["forearm_link"] == 0.2 and "wrist_3_link" not in table and table["upper_arm_link"] == 0.7


def test_gravcomp_with_different_factors_in_one_route1_body_falls_back_to_loads(tmp_path):
    urdf = tmp_path / "two.urdf"
    urdf.write_text("""<robot name="two"><link name="world"/>
      <joint name="j" type="revolute"><parent link="world"/><child link="a"/><axis xyz="1 0 0"/>
        <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
      <link name="a"><inertial><origin xyz="0 0 -0.2"/><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
      <joint name="f" type="fixed"><parent link="a"/><child link="b"/><origin xyz="0 0.1 -0.4"/></joint>
      <link name="b"><inertial><mass value="0.5"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
    </robot>""")
    scene = scene_from_dict({"robot": {"urdf": str(urdf)}, "gravity": {}, "gravcomp": {"bodies": {"a": 1.0}},
                             "initial": {"q": {"j": 0.4}}, "run": {"t_end": 0.3}})
    mj = mjcf_from_scene(scene, scene.model())
    assert not mj.gravcomp_in_bodies and any("different factors" in n for n in mj.notes)
    from urdf2links.compare.agreement.trajectory import compare_scene

    c = compare_scene(scene, mujoco_dt=1e-4)
    assert c.summary()["trajectory"]["max_abs_error"] < 1e-9      # the loads through the callback: RK4's error


# -- --hold ---------------------------------------------------------------------------------------------
def test_hold_gains_come_from_the_mass_matrix():
    """kp_i = A_ii (2 pi f)^2, kv_i = 2 A_ii (2 pi f) at q0 (E56): each coordinate alone is critically damped."""
    scene = default_scene(UR5, hold=3.0, q0="random", seed=2)
    model = scene.model()
    q0, _ = scene.initial_state(model)
    A = model.mass_matrix(q0)
    w = 2 * np.pi * 3.0
    for i, a in enumerate(as_plan(scene, model=model).actuator_set.actuators):
        assert a.kind == "position" and a.source == "hold" and a.ctrl(0.0) == q0[i]
        assert a.kp == pytest.approx(A[i, i] * w * w, rel=1e-15) and a.kv == pytest.approx(2 * A[i, i] * w, rel=1e-15)
        assert a.kv ** 2 == pytest.approx(4 * A[i, i] * a.kp, rel=1e-12)    # critical damping: c^2 = 4 m k
    assert scene.name == "default-random-seed2-hold3hz"
    with pytest.raises(SceneError, match="bandwidth"):
        hold_actuators(model, q0, bandwidth=-1.0)


def test_a_held_scene_is_written_and_read_back(tmp_path):
    scene = default_scene(UR5, hold=2.0)
    text = scene_toml(scene)
    assert "[[actuator]]" in text and 'kind = "position"' in text
    path = tmp_path / "held.toml"
    path.write_text(text.replace(f'"{UR5}"', f'"{UR5}"'))
    from urdf2links.scenes.scene_read import load_scene

    back = load_scene(path)
    plan_a, plan_b = as_plan(scene), as_plan(back)
    y = np.r_[np.linspace(-0.5, 0.5, 6), np.linspace(1, -1, 6), 0.0]
    assert np.array_equal(plan_a.rhs(0.1, y), plan_b.rhs(0.1, y))


def test_scene_file_refuses_hold(tmp_path):
    from urdf2links.scenes.scene_toml import scene_or_robot

    with pytest.raises(SceneError, match="--hold apply to a robot file"):
        scene_or_robot(shipped_robots_dir() / "ur5_servo.toml", hold=2.0)


def test_compile_plan_checks_names_of_gravcomp_bodies():
    scene = scene_from_dict({"robot": {"urdf": UR5}, "gravity": {}, "gravcomp": {"bodies": {"forarm_link": 1.0}}})
    model = as_plan(scene_from_dict({"robot": {"urdf": UR5}})).model
    with pytest.raises(SceneError, match="did you mean 'forearm_link'"):
        compile_plan(scene, model)

"""Servo scenes against MuJoCo (issue 26): both engines run the same actuators and computed torque.

- the shipped ``ur5_servo`` (position servos tracking sines, the elbow's saturating at its forcerange, a
  velocity servo, a geared motor with a ctrlrange): below 1e-6 with MuJoCo's RK4 at 1e-4 s, and converging
  as MuJoCo's step shrinks against a tight project reference;
- a gripper on velocity servos (its fingers) and a position servo (its camera tilt);
- a 32-coordinate humanoid (example-robot-data's Talos) held by ``--hold``: held (it sags, it does not fall);
- a computed-torque scene: the UR5-like arm follows its reference exactly (no servo), and with position
  servos it converges onto the reference from an offset start; both engines;
- an MJCF file's own actuator and a scene actuator run by MuJoCo from the file itself (route 2);
- the compiled control callback equals the Python one (ctrl, computed torque) to 1e-12.

Why 1e-6 (the issue's bound): with RK4 at 1e-4 s MuJoCo's own error on these smooth scenes is ~1e-11;
the clamps make the right-hand side non-smooth where they engage, and both integrators lose order there
(measured 2.8e-7 on ur5_servo at the project's rtol 1e-10, most of it the project's own step control at
the kinks: 1.4e-7 against rtol 1e-13). The convergence test takes the project at rtol 1e-13.
"""

from __future__ import annotations

import subprocess
import sys
import warnings

import numpy as np
import pytest

import corpus
from test_importer import MIMIC
from urdf2links.compare.agreement.trajectory import compare_scene
from urdf2links.compare.mujoco_side.mjcf import mjcf_from_scene
from urdf2links.compare.mujoco_side.mujoco_run import run_mujoco
from urdf2links.integration.simulate import simulate
from urdf2links.locations import shipped_robots_dir
from urdf2links.scenes.plan import as_plan
from urdf2links.scenes.default_scenes import default_scene
from urdf2links.scenes.scene_read import scene_from_dict

ROBOTS = shipped_robots_dir()
FIGURE_BOUNDS = {"servo scenes": "1e-6 rad or m: max |q_urdf2links - q_MuJoCo| (MuJoCo RK4 at 1e-4 s)"}
UR5 = str(ROBOTS / "ur5_like.urdf")


def test_ur5_servo_agrees_with_mujoco(record_figure):
    c = compare_scene(ROBOTS / "ur5_servo.toml")
    s = c.summary()
    err = s["trajectory"]["max_abs_error"]
    record_figure("servo scenes", "ur5_servo, MuJoCo RK4 1e-4 s", err, "{:.1e}")
    assert err < 1e-6, err
    assert s["terms"]["route1"]["max_rel_error_actuator"] < 1e-12
    assert s["terms"]["route2"]["max_rel_error_actuator"] < 1e-12
    assert "actuator" in s["effects"] and len(s["actuators"]) == 6
    # the elbow saturates: its force sits on the forcerange for part of the run
    plan = as_plan(c.scene, model=c.model)
    elbow = [a for a in plan.actuator_set.actuators if a.name == "elbow_servo"][0]
    f = np.array([elbow.force(t, q[elbow.index], qd[elbow.index]) for t, q, qd in zip(c.traj.t, c.traj.q, c.traj.qd)])
    assert np.mean(np.abs(f) == 25.0) > 0.03


def test_ur5_servo_converges_as_mujocos_step_shrinks():
    errs = []
    for dt in (4e-4, 1e-4):
        c = compare_scene(ROBOTS / "ur5_servo.toml", mujoco_dt=dt, rtol=1e-13, atol=1e-14, t_end=2.0)
        errs.append(c.summary()["trajectory"]["max_abs_error"])
    assert errs[1] < errs[0] / 8, errs       # at least second order across the clamps' kinks (4x the step)
    assert errs[1] < 5e-7, errs               # measured 1.2e-7 (5.2e-6 at 4e-4 s)


def test_gripper_on_velocity_servos(tmp_path, record_figure):
    path = tmp_path / "gripper.urdf"
    path.write_text(MIMIC)
    scene = scene_from_dict({
        "robot": {"urdf": str(path)}, "gravity": {},
        "actuator": [{"coordinate": "left", "kind": "velocity", "kv": 5.0, "ctrl": {"sines": [[0.05, 1.0]]}},
                     {"coordinate": "right", "kind": "velocity", "kv": 5.0, "ctrl": {"sines": [[-0.05, 1.0]]},
                      "forcerange": [-0.2, 0.2]},
                     {"coordinate": "tilt", "kind": "position", "kp": 2.0, "kv": 0.2, "ctrl": 0.3}],
        # issue 45: a <mimic> is a joint constraint by default; each finger has its own servo here
        "constraints": {"mimic": False},
        "run": {"t_end": 2.0}}, name="gripper_velocity")
    c = compare_scene(scene)
    err = c.summary()["trajectory"]["max_abs_error"]
    record_figure("servo scenes", "gripper, velocity servos", err, "{:.1e}")
    assert err < 1e-6, err
    # the finger follows the commanded velocity: a velocity servo on a 0.1 kg finger has the time constant
    # m / kv = 20 ms, so at 1 Hz it lags by 7 degrees: |q' - ctrl| <= 0.05 |1 - 1/(1 + 2 pi i 0.02)| ~ 6e-3
    i = c.model.coordinate_names.index("left")
    late = c.traj.t > 0.2
    assert np.abs(c.traj.qd[late, i] - 0.05 * np.sin(2 * np.pi * c.traj.t[late])).max() < 1e-2


@corpus.needs_corpus
def test_humanoid_held_by_hold(record_figure):
    """Talos (32 coordinates, fixed base) in its default scene with --hold: both engines agree, and the robot
    is held (it sags under gravity by a fraction of a radian) where without servos it falls."""
    path = corpus.path(corpus.NAMED["talos"])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        held = default_scene(path, hold=2.0, t_end=0.5, q0="rest")      # held at rest: the sag is gravity's
        free = default_scene(path, t_end=0.5, q0="rest")
    c = compare_scene(held)
    assert c.model.n >= 30
    err = c.summary()["trajectory"]["max_abs_error"]
    record_figure("servo scenes", "Talos held by --hold", err, "{:.1e}")
    assert err < 1e-6, err
    sag = np.abs(c.traj.q - c.traj.q[0]).max()
    fall = np.abs(simulate(free, model=c.model, progress=False).q[-1]).max()
    assert sag < 0.25 and fall > 4 * sag, (sag, fall)


@pytest.mark.parametrize("name", ["humanoid", "cart_arm"])
def test_mjcf_robots_held_by_hold_run_by_mujoco_from_the_file(name, record_figure):
    """gymnasium's humanoid (a free root and 21 hinges, 27 coordinates) and the shipped cart_arm (a ball joint)
    held by --hold, MuJoCo running the file itself: the servos on the hinges and slides are MuJoCo actuators
    added to the file, those on the free root's and the ball's ZYX angles the project's law through the
    control callback (f = E^-T tau); both engines agree (the armature of the ball stays in both models)."""
    from test_mjcf import GYM

    path = {p.stem: p for p in GYM}.get(name, ROBOTS / f"{name}.xml")
    c = compare_scene(default_scene(path, hold=2.0, t_end=0.5))
    s = c.summary()
    assert s["route"].startswith("route 2"), s["route"]
    err = s["trajectory"]["max_abs_error"]
    record_figure("servo scenes", f"{name} (MJCF) held by --hold, MuJoCo running the file", err, "{:.1e}")
    assert err < 1e-6, err
    assert np.abs(c.traj.q - c.traj.q[0]).max() < 0.3       # held: it sags, it does not fall


def test_servos_on_a_ball_joints_angles_away_from_zero(record_figure):
    """Position servos driving the three ZYX angles of cart_arm's ball joint through large rotations (the map
    f = E^-T tau is the identity only at zero angles), MuJoCo running the file."""
    act = [{"coordinate": f"wrist.{a}", "kind": "position", "kp": 2.0, "kv": 0.2,
            "ctrl": {"sines": [[0.5, 0.5 + 0.2 * k, k]], "offset": 0.3}} for k, a in enumerate(("phi_x", "phi_y", "phi_z"))]
    act += [{"coordinate": c, "kind": "position", "kp": 200.0, "kv": 20.0, "ctrl": 0.0} for c in ("shoulder", "elbow")]
    scene = scene_from_dict({"robot": {"mjcf": str(ROBOTS / "cart_arm.xml")}, "gravity": {}, "actuator": act,
                             "run": {"t_end": 2.0}}, name="ball_servos")
    c = compare_scene(scene)
    s = c.summary()
    assert s["route"].startswith("route 2")
    i = c.model.coordinate_names.index("wrist.phi_z")
    assert np.abs(c.traj.q[:, i]).max() > 0.5                   # the angles do go far from zero
    record_figure("servo scenes", "ball joint servos (cart_arm), MuJoCo running the file", s["trajectory"]["max_abs_error"],
                  "{:.1e}")
    assert s["trajectory"]["max_abs_error"] < 1e-6


def test_computed_torque_follows_the_reference_on_both_engines(record_figure):
    refs = [{"coordinate": "shoulder_pan_joint", "reference": {"sines": [[0.5, 0.5]]}},
            {"coordinate": "shoulder_lift_joint", "reference": {"sines": [[0.3, 0.4]], "offset": -1.0}},
            {"coordinate": "elbow_joint", "reference": {"sines": [[0.6, 0.8, 0.3]], "offset": 1.0}}]
    scene = scene_from_dict({"robot": {"urdf": UR5}, "gravity": {}, "computed_torque": refs,
                             "dampers": {"from_urdf": True}, "run": {"t_end": 2.0}}, name="computed_torque")
    c = compare_scene(scene)
    plan = as_plan(scene, model=c.model)
    ref = np.array([plan.reference(t) for t in c.t])
    ours, theirs = np.abs(c.q_ours - ref).max(), np.abs(c.q_mujoco - ref).max()
    record_figure("servo scenes", "computed torque: tracking error, urdf2links / MuJoCo",
                  f"{ours:.1e} / {theirs:.1e}")
    # exact when the model matches: what is left is rounding and integration error, grown along a reference that is
    # open-loop unstable (the wrists held at 0 by torque alone: measured 1e-8 to 5e-8 whatever the project's rtol)
    assert ours < 1e-6 and theirs < 1e-6, (ours, theirs)
    assert c.summary()["trajectory"]["max_abs_error"] < 1e-6
    # with servos on the same reference and an offset start, both converge onto it
    servo = [{"coordinate": r["coordinate"], "kind": "position", "kp": 400.0, "kv": 40.0, "ctrl": r["reference"]}
             for r in refs] + [{"coordinate": w, "kind": "position", "kp": 10.0, "kv": 1.0, "ctrl": 0.0}
                               for w in ("wrist_1_joint", "wrist_2_joint", "wrist_3_joint")]
    scene = scene_from_dict({"robot": {"urdf": UR5}, "gravity": {}, "computed_torque": refs, "actuator": servo,
                             "initial": {"q": {"elbow_joint": 1.1}}, "run": {"t_end": 2.0}}, name="ct_servo")
    c = compare_scene(scene)
    ref = np.array([plan.reference(t) for t in c.t])
    i = c.model.coordinate_names.index("elbow_joint")
    assert abs(c.q_ours[0, i] - ref[0, i]) > 0.05 and np.abs(c.q_ours[-1] - ref[-1]).max() < 1e-3
    assert c.summary()["trajectory"]["max_abs_error"] < 1e-6


def test_mjcf_file_runs_its_own_actuator(record_figure):
    scene = scene_from_dict({"robot": {"mjcf": str(ROBOTS / "cart_arm.xml")}, "gravity": {}, "dampers": {"from_file": True},
                             "actuator": [{"name": "push", "ctrl": {"sines": [[1.5, 0.7]]}},
                                          {"coordinate": "elbow", "kind": "position", "kp": 20.0, "kv": 1.0,
                                           "ctrl": {"sines": [[0.5, 1.0]]}}],
                             "gravcomp": {"bodies": {"bob": 1.0}}, "run": {"t_end": 1.0}}, name="cart_arm_servo")
    c = compare_scene(scene)
    s = c.summary()
    assert s["route"].startswith("route 2")
    assert s["wall_time"]["mujoco_inputs"] == "compiled" and s["wall_time"]["mujoco_callback_calls"] > 0
    record_figure("servo scenes", "cart_arm (MJCF, run by MuJoCo from the file)", s["trajectory"]["max_abs_error"],
                  "{:.1e}")
    assert s["trajectory"]["max_abs_error"] < 1e-6
    assert s["terms"]["route2"]["max_rel_error_actuator"] < 1e-12


def test_compiled_callback_equals_the_python_callback():
    scene = scene_from_dict({"robot": {"urdf": UR5}, "gravity": {},
                             "actuator": [{"coordinate": "elbow_joint", "kind": "position", "kp": 300.0, "kv": 30.0,
                                           "ctrl": {"sines": [[0.8, 1.0]]}, "forcerange": [-20, 20]},
                                          {"coordinate": "wrist_1_joint", "kind": "motor", "gear": 3.0, "ctrl": 0.2}],
                             "computed_torque": [{"coordinate": "shoulder_pan_joint", "reference": {"sines": [[0.4, 0.5]]}}],
                             "base": {"z": {"sines": [[0.05, 1.0]]}}, "run": {"t_end": 0.3}})
    plan = as_plan(scene)
    mj = mjcf_from_scene(scene, plan.model, timestep=1e-3)
    a = run_mujoco(mj, plan, inputs="compiled")
    b = run_mujoco(mj, plan, inputs="python")
    assert a.inputs == "compiled" and b.inputs == "python"
    assert np.abs(a.q - b.q).max() < 1e-12 and np.abs(a.qd - b.qd).max() < 1e-11


def test_euler_and_implicit_say_what_they_treat_implicitly():
    scene = default_scene(UR5, hold=2.0, t_end=0.2)
    for integ, words in (("implicitfast", "velocity feedback"), ("RK4", None)):
        c = compare_scene(scene, mujoco_integrator=integ, mujoco_dt=1e-3)
        notes = " ".join(c.summary()["mujoco"]["notes"])
        assert (words in notes) if words else ("implicitly" not in notes), notes
    c = compare_scene(ROBOTS / "spring_arm_torques.toml", mujoco_integrator="Euler", mujoco_dt=1e-3, t_end=0.2)
    assert "Euler integrates joint damping implicitly" in " ".join(c.summary()["mujoco"]["notes"])


def test_cli_compare_with_hold(tmp_path):
    run = subprocess.run([sys.executable, "-m", "urdf2links.cli", "compare", "ur5_like", "--hold", "--t-end", "0.2",
                          "--out", str(tmp_path / "r"), "--animation-fps", "0"], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    assert "default-hold" in run.stdout + run.stderr
    bad = subprocess.run([sys.executable, "-m", "urdf2links.cli", "simulate", "ur5_like", "--hold-bandwidth", "5"],
                         capture_output=True, text=True)
    assert bad.returncode == 2 and "give --hold too" in bad.stderr and "Traceback" not in bad.stderr

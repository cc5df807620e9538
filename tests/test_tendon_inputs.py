"""Issue 43: both engines get the same inputs. A scene that names an MJCF file's own actuator drives it in
the project's run and in MuJoCo's, whatever its transmission: a joint (a file actuator of the plan), a fixed
tendon (through the tendon, E76, with ``[constraints] from_file``); a site transmission (and a spatial
tendon) is refused by name on both, never dropped on one side.

The shipped parallel gripper (robots/loops/gripper2f.xml, the Robotiq 2F-85's pattern: two fingers, a fixed
tendon 'split', a general actuator 'fingers_actuator' on it, a joint equality coupling the fingers) agrees
with MuJoCo to the verdict's threshold; before issue 43 MuJoCo's run of the file never got the actuator's
control and the comparison said "DIVERGE at t = 0.002 s" (0.30 rad over 0.3 s; planted below: the same run
without the control).
"""

from __future__ import annotations

import dataclasses
import importlib.resources
from pathlib import Path

import numpy as np
import pytest

from urdf2links.compare.agreement.actuator_terms import file_actuators, route1_actuators
from urdf2links.compare.agreement.trajectory import DIVERGENCE_THRESHOLD, compare_scene
from urdf2links.compare.mujoco_side.mjcf import mjcf_from_scene
from urdf2links.compare.mujoco_side.mujoco_constraints import with_constraints
from urdf2links.compare.mujoco_side.mujoco_mjcf import mujoco_from_mjcf, run_file
from urdf2links.compare.mujoco_side.mujoco_run import run_mujoco
from urdf2links.compare.mujoco_side.tendon_controls import tendon_actuators
from urdf2links.errors import SceneError
from urdf2links.scenes.plan import as_plan

LOOPS = Path(__file__).resolve().parent.parent / "robots" / "loops"
GRIPPER = LOOPS / "gripper2f.xml"
#: Forces at identical states: the same law evaluated on both sides, a handful of products and two clamps
#: each; relative to max(|MuJoCo's force|, 1 N), rounding is ~1e-16, 1e-12 leaves room for the tendon's sums.
ROUNDING = 1e-12


def _scene(tmp_path, body: str, name: str = "s") -> Path:
    path = tmp_path / f"{name}.toml"
    path.write_text(f'[robot]\nmjcf = "{GRIPPER.as_posix()}"\n\n[gravity]\nmagnitude = 9.81\n\n{body}\n'
                    '[initial]\nq = { wrist_joint = 0.4, left_driver_joint = 0.1, right_driver_joint = 0.1 }\n\n'
                    "[run]\nt_end = 0.3\n")
    return path


TENDON = '[constraints]\nfrom_file = true\n\n[[actuator]]\nname = "fingers_actuator"\nctrl = { sines = [[60.0, 2.0, 0.0]], offset = 100.0 }\n'
JOINT = '[[actuator]]\nname = "wrist_motor"\nctrl = { sines = [[1.5, 1.0, 0.3]] }\n'


def test_joint_transmission_forces_at_identical_states(tmp_path):
    """A file actuator on a joint: MuJoCo's actuator_force and qfrc_actuator (J^T, E50) equal ours at 8
    seeded states, ctrl clamped at ctrlrange on some (amplitude 1.5 against [-2, 2]: not; the states' t)."""
    plan = as_plan(_scene(tmp_path, JOINT))
    mf = mujoco_from_mjcf(plan)
    r = file_actuators(plan, mf, states=8, seed=3)
    assert r["actuators"] == 1 and r["tendon_actuators"] == 0
    assert r["max_rel_error_actuator_force"] < ROUNDING and r["max_rel_error_qfrc_actuator"] < ROUNDING
    m = mf.model                                    # planted: MuJoCo's gain off by 1 %: caught
    m.actuator_gainprm[mf.actuator_ids[0], 0] *= 1.01
    assert file_actuators(plan, mf, states=8, seed=3)["max_rel_error_actuator_force"] > 1e-3


def test_fixed_tendon_transmission_forces_at_identical_states(tmp_path):
    """The file's actuator on the fixed tendon 'split' (E76 on l = 0.5 q_l + 0.5 q_r): MuJoCo's
    actuator_force and qfrc_actuator equal ours at 8 seeded states, on route 2 (the file) and route 1 (the
    tree with the tendon written by with_constraints), forcerange +-1 N crossed at some of them."""
    plan = as_plan(_scene(tmp_path, TENDON + "\n" + JOINT))
    (ta,) = tendon_actuators(plan)
    assert ta.name == "fingers_actuator" and ta.tendon.name == "split"
    mf = mujoco_from_mjcf(plan)
    assert len(mf.tendon_actuator_ids) == 1 and not any("actuation" in n and "disabled" in n for n in mf.notes)
    r2 = file_actuators(plan, mf, states=8, seed=1)
    assert r2["tendon_actuators"] == 1 and r2["actuators"] == 2
    assert r2["max_rel_error_actuator_force"] < ROUNDING and r2["max_rel_error_qfrc_actuator"] < ROUNDING
    mj = with_constraints(mjcf_from_scene(plan.scene, plan.model), plan.constraints)
    r1 = route1_actuators(plan, mj, states=8, seed=1)
    assert r1["tendon_actuators"] == 1 and r1["max_rel_error_actuator"] < ROUNDING
    k = mf.tendon_actuator_ids[0]                   # planted: MuJoCo's tendon actuator not fed (gain 0): caught
    mf.model.actuator_gainprm[k, 0] = 0.0
    assert file_actuators(plan, mf, states=8, seed=1)["max_rel_error_actuator"] > 1e-2


def test_site_transmission_and_tendon_without_from_file_are_refused(tmp_path):
    """Site transmissions and spatial tendons are not modelled: a scene naming such an actuator is refused by
    name (both engines would otherwise differ); so is a fixed tendon's actuator in a scene whose tendons do not
    act (no from_file)."""
    xml = tmp_path / "site_arm.xml"
    xml.write_text("""<mujoco model="site_arm"><compiler angle="radian"/><worldbody><body name="arm">
      <joint name="j" type="hinge" axis="0 1 0"/><inertial pos="0 0 -0.2" mass="1" diaginertia="0.01 0.01 0.01"/>
      <site name="tip" pos="0 0 -0.4"/></body></worldbody>
      <actuator><general name="push" site="tip" gear="1 0 0 0 0 0"/></actuator></mujoco>""")
    scene = tmp_path / "push.toml"
    scene.write_text(f'[robot]\nmjcf = "{xml.as_posix()}"\n\n[[actuator]]\nname = "push"\nctrl = 1.0\n')
    with pytest.raises(SceneError, match=r"'push'.*transmission is a site"):
        as_plan(scene)
    spatial = tmp_path / "spatial_arm.xml"      # an actuator on a spatial tendon: refused too
    spatial.write_text(xml.read_text().replace('<site name="tip" pos="0 0 -0.4"/>', '<site name="tip" pos="0 0 -0.4"/>'
                       '<site name="mid" pos="0 0 -0.2"/>').replace("<actuator>", '<tendon><spatial name="rope">'
                       '<site site="mid"/><site site="tip"/></spatial></tendon><actuator>').replace(
                       'site="tip" gear="1 0 0 0 0 0"', 'tendon="rope"'))
    scene.write_text(f'[robot]\nmjcf = "{spatial.as_posix()}"\n\n[[actuator]]\nname = "push"\nctrl = 1.0\n')
    with pytest.raises(SceneError, match=r"'push'.*transmission is a spatial tendon"):
        as_plan(scene)
    no_file = _scene(tmp_path, TENDON.replace("from_file = true", "from_file = false"), "nofile")
    with pytest.raises(SceneError, match=r"'fingers_actuator' drives the file's fixed tendon 'split'.*from_file = true"):
        as_plan(no_file)


def test_parallel_gripper_with_tendon_actuator_agrees(tmp_path):
    """The shipped gripper scene (route 2: MuJoCo runs the file, the control callback feeds the tendon
    actuator's ctrl): the engines agree below the verdict's threshold. Planted: MuJoCo's run of the same file
    without that control (the behaviour before issue 43) lies beyond the threshold, so the comparison would
    have said DIVERGE."""
    c = compare_scene(LOOPS / "gripper2f_close.toml", t_end=0.3)
    s = c.summary()
    err = float(np.max(c.error))
    assert err < DIVERGENCE_THRESHOLD, s["trajectory"]["verdict"]
    assert "agree" in s["trajectory"]["verdict"] and "DIVERGE" not in s["trajectory"]["verdict"]
    assert [(a["name"], a["coordinate"]) for a in s["actuators"]] == [("fingers_actuator", "split")]   # reported
    assert c.summary_route() == "route 2" and c.run.inputs == "compiled" and c.run.callback_calls > 0
    moved = float(np.ptp(c.q_ours[:, 1]))           # the fingers moved: the actuator acted (not weak evidence)
    assert moved > 0.05
    plan = as_plan(LOOPS / "gripper2f_close.toml")
    mf = mujoco_from_mjcf(plan)
    unfed = run_file(dataclasses.replace(mf, tendon_actuator_ids=()), plan, t_end=0.3, samples=len(c.t))
    m = mf.model
    m.actuator_gainprm[:] = 0.0                      # and with the control never reaching its law either
    m.actuator_biasprm[:] = 0.0
    off = run_file(mf, plan, t_end=0.3, samples=len(c.t))
    for run in (unfed, off):
        assert float(np.max(np.abs(run.q - c.q_ours))) > 10 * DIVERGENCE_THRESHOLD
    mj = with_constraints(mjcf_from_scene(plan.scene, plan.model), plan.constraints)    # route 1 gets it too
    r1 = run_mujoco(mj, plan, t_end=0.3, samples=len(c.t))
    assert r1.inputs == "compiled" and float(np.max(np.abs(r1.q - c.q_ours))) < DIVERGENCE_THRESHOLD
    py = run_mujoco(mj, plan, t_end=0.3, samples=len(c.t), inputs="python")     # its oracle: the Python callback
    assert float(np.max(np.abs(py.q - r1.q))) < 1e-12     # the same controls at the same stages: rounding only


DM = importlib.resources.files("dm_control")
#: dm_control's planar manipulator: its hand's thumb and finger pulled by the motor 'grasp' (gear 2, ctrlrange
#: [-1, 1]) on the fixed tendon 'grasp' (0.5 thumb + 0.5 finger), held together by a tendon equality 'coupling'.
#: Its fingers are light: a control of 0.02 turns them ~6 rad in 0.1 s (with the arm and hand moving from the
#: start, as in tests/test_constraints_models.py).
MANIPULATOR = DM / "suite/manipulator.xml"
_HAND = {"arm_shoulder": 1.0, "arm_elbow": -1.5, "thumb": 2.0, "finger": 2.0}


def _manipulator(amplitude: float):
    from urdf2links.scenes.scene_read import scene_from_dict

    data = {"robot": {"mjcf": str(MANIPULATOR)}, "gravity": {"magnitude": 9.81}, "constraints": {"from_file": True},
            "actuator": [{"name": "grasp", "ctrl": {"sines": [[amplitude, 3.0, 0.0]]}}],
            "initial": {"qd": dict(_HAND)}, "run": {"t_end": 0.1, "samples": 21}}
    return scene_from_dict(data, where="manipulator_grasp.toml")


def test_dm_control_manipulator_grasp_on_its_tendon():
    """A public MJCF with a tendon actuator (dm_control's manipulator.xml, 'grasp'): MuJoCo's actuator_force and
    qfrc_actuator equal ours at identical states, the control clamped by its ctrlrange over most of the run
    (amplitude 1.5 against [-1, 1]); the engines agree over 0.1 s with the scene's control, and MuJoCo's run of the file without that
    control (planted: the behaviour before issue 43) does not."""
    import warnings

    import urdf2links

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")     # the import's audit findings on this file (its notes)
        model = urdf2links.load_mjcf(MANIPULATOR)
    wide = as_plan(_manipulator(1.5), model=model)
    assert [ta.name for ta in tendon_actuators(wide)] == ["grasp"]
    r = file_actuators(wide, mujoco_from_mjcf(wide), states=16, seed=2)
    assert r["tendon_actuators"] == 1 and r["max_rel_error_actuator"] < ROUNDING
    c = compare_scene(_manipulator(0.02), model=model, progress=False, mujoco_fallback=False)
    err = float(np.max(c.error))
    assert err < DIVERGENCE_THRESHOLD and c.summary_route() == "route 2" and c.run.callback_calls > 0
    plan = as_plan(c.scene, model=model)
    mf = mujoco_from_mjcf(plan)
    unfed = run_file(dataclasses.replace(mf, tendon_actuator_ids=()), plan, t_end=0.1, samples=len(c.t))
    assert float(np.max(np.abs(unfed.q - c.q_ours))) > 10 * DIVERGENCE_THRESHOLD

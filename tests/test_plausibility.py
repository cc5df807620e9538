"""The plausibility gate before any verdict (issue 43, compare/agreement/plausibility.py).

Planted runs that are not the robot, each run by both engines for real (urdf2links and MuJoCo):

- a free-floating body with a floor in its MJCF file and no contact in the scene falls through the floor;
- the shipped quadruped on a ground far too soft for its weight sinks its feet past their radius;
- a huge constant torque on the UR5-like arm's elbow (limits +-pi in the file, left out of both engines)
  spins it far past its limit;
- a free box driven by a large force and moment passes the linear and angular speed bounds;
- a passive pendulum on a stiff spring integrated by RK4 with a step past its stability bound gains energy
  (urdf2links' run), and by MuJoCo's Euler at a coarse step (MuJoCo's run).

Each gets "implausible run: ..." naming the engine, the part, the value and the bound, never "agree" or
"DIVERGE", and ``urdf2links check`` fails it. A sound shipped scene still gets "agree" (the control), and
its scope names what both engines switch off.
"""

from __future__ import annotations

import re
import warnings

import pytest

from urdf2links.compare.agreement import plausibility as P
from urdf2links.compare.agreement.trajectory import compare_scene
from urdf2links.compare.check.cases import Case, RunContext, run_case
from urdf2links.compare.check.config import SceneEntry
from urdf2links.locations import shipped_robots_dir
from urdf2links.scenes.default_scenes import default_scene

FLOOR_MJCF = """<mujoco model="boxfloor">
  <worldbody>
    <geom name="floor" type="plane" size="5 5 0.1"/>
    <body name="box" pos="0 0 0.3">
      <freejoint name="root"/>
      <geom type="box" size="0.1 0.1 0.1" mass="1"/>
      <body name="arm" pos="0 0 0.2">
        <joint name="hinge" type="hinge" axis="0 1 0" range="-1 1"/>
        <geom type="capsule" fromto="0 0 0 0 0 0.3" size="0.02" mass="0.2"/>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


def _compare(scene, t_end):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return compare_scene(scene, t_end=t_end, states=1, progress=False).summary()


def _implausible(s: dict, check: str) -> list[dict]:
    """The summary says "implausible run", never agree/DIVERGE; the findings of ``check``."""
    v = s["verdict"]
    assert v["text"].startswith("implausible run: ") and not v["plausible"], v["text"]
    assert "agree" not in v["text"] and "DIVERGE" not in v["text"], v["text"]
    assert s["trajectory"]["verdict"] == v["text"] and not s["plausibility"]["plausible"]
    found = [f for f in s["plausibility"]["findings"] if f["check"] == check]
    assert found, s["plausibility"]["findings"]
    for f in found:
        assert f["value"] > f["bound"] and f["engine"] in ("urdf2links", "MuJoCo")
    return found


def test_a_fall_through_the_files_floor_is_implausible(tmp_path):
    """A floating box with a floor in its file, contact not in the scene: gravity takes it through the floor
    on both engines (0.5 s of free fall from 0.2 m above it: 1.0 m below, far past the 0.02 m margin); the
    scope names the file's floor and its contact as switched off."""
    f = tmp_path / "boxfloor.xml"
    f.write_text(FLOOR_MJCF)
    s = _compare(default_scene(f, t_end=0.5, q0="rest"), 0.5)
    found = _implausible(s, "base_below_ground")
    assert {x["engine"] for x in found} == {"urdf2links", "MuJoCo"}
    assert all(x["part"] == "box" for x in found)
    assert "floating base box falls below the file's floor 'floor'" in s["verdict"]["text"]
    depth = max(x["value"] for x in found)
    assert depth > 0.5, depth           # free fall: 0.5 g t^2 = 1.2 m, less the 0.2 m start above the floor
    off = {x["effect"]: x for x in s["verdict"]["switched_off"]}
    assert "floor" in off["contact"]["names"] and "hinge" in off["limits"]["names"]
    assert "contact and the file's floor 'floor'" in s["verdict"]["scope"]


def test_a_ground_too_soft_to_hold_the_robot_is_implausible(tmp_path):
    """The shipped quadruped's drop on a ground 1e4 times softer than the scene's (stiffness 6.24): its feet
    sink past their 2 cm radius (the bound is the radius, PENETRATION_FRACTION = 1) on both engines."""
    text = (shipped_robots_dir() / "quad12_drop.toml").read_text()
    soft = re.sub(r"stiffness = 6.24e4\ndamping = 3.45e5", "stiffness = 6.24\ndamping = 0.0", text)
    assert soft != text
    path = tmp_path / "quad12_soft.toml"
    path.write_text(soft)
    s = _compare(path, 0.5)
    found = _implausible(s, "penetration")
    assert {x["engine"] for x in found} == {"urdf2links", "MuJoCo"}
    assert {x["part"] for x in found} <= {"FL_calf", "FR_calf", "RL_calf", "RR_calf"}
    assert all(abs(x["bound"] - P.PENETRATION_FRACTION * 0.02) < 1e-12 for x in found)
    assert "sinks into the ground by" in s["verdict"]["text"]


RUNAWAY = """description = "planted: a huge constant torque on the elbow, limits left out"
[robot]
shipped = "ur5_like"
inertia = "strict"
[[torque]]
coordinate = "elbow_joint"
value = 500.0
[run]
t_end = 0.5
method = "DOP853"
rtol = 1e-9
atol = 1e-11
samples = 101
"""


def test_a_joint_runaway_past_its_limits_is_implausible(tmp_path):
    """500 N m on the elbow without gravity: it passes its +pi limit by far more than a quarter of its 2 pi
    range, on both engines (the gate speaks before the trajectories' agreement)."""
    path = tmp_path / "runaway.toml"
    path.write_text(RUNAWAY)
    s = _compare(path, 0.5)
    found = _implausible(s, "joint_limit")
    elbow = [x for x in found if x["part"] == "elbow_joint"]
    assert {x["engine"] for x in elbow} == {"urdf2links", "MuJoCo"}
    for x in elbow:
        assert abs(x["bound"] - P.LIMIT_MARGIN * 2 * 3.141592653589793) < 1e-9 and x["value"] > 2 * x["bound"]
    # whatever the trajectories' sentence says (here they part at the run-away's speeds), the verdict does not
    assert s["verdict"]["agreement"] not in s["verdict"]["text"]
    assert "joint 'elbow_joint' passes its upper limit" in s["verdict"]["text"]
    speeds = {x["part"] for x in s["plausibility"]["findings"] if x["check"] == "speed" and x["engine"] == "MuJoCo"}
    assert "elbow_joint" in speeds          # measured ~1e3 rad/s against the 100 rad/s bound


ENERGY_GAIN = """description = "planted: a passive stiff spring, RK4 past its stability bound"
[robot]
shipped = "pendulum"
[[spring]]
coordinate = "hinge"
stiffness = 57800.0
[initial]
q = { hinge = 0.1 }
[run]
t_end = 0.3
method = "RK4"
dt = 0.01
samples = 31
"""


def test_an_energy_gain_in_a_passive_scene_is_implausible(tmp_path):
    """The pendulum (a = 0.05 + 1.3 * 0.7^2 = 0.687 kg m^2) on a 57800 N m/rad spring: omega = 290 rad/s, so
    RK4 at dt 0.01 s has omega dt = 2.9, past its 2.83 bound (|R| = 1.19 per step): urdf2links' run gains
    energy, MuJoCo's (RK4, dt 1e-4) does not. The gate names urdf2links' energy growth, not a divergence."""
    path = tmp_path / "gain.toml"
    path.write_text(ENERGY_GAIN)
    s = _compare(path, 0.3)
    found = _implausible(s, "energy_growth")
    assert [x["engine"] for x in found] == ["urdf2links"]
    assert found[0]["value"] > 1.0      # amplitude x 1.19^30 = 190: the energy is not a rounding away
    assert s["plausibility"]["bounds"]["passive"]
    assert "energy grows in a passive scene" in s["verdict"]["text"]


def test_an_energy_gain_of_mujocos_run_is_implausible(tmp_path):
    """The same spring integrated well by urdf2links (DOP853, rtol 1e-10) and by MuJoCo's semi-implicit Euler
    at dt 0.003 s (omega dt = 0.87: its energy swings by tens of percent, measured 0.77 of the spring's 289 J):
    the gate names MuJoCo's energy growth (h - h(0): its dissipated work is not measured) and only MuJoCo's."""
    path = tmp_path / "gain.toml"
    path.write_text(ENERGY_GAIN.replace('method = "RK4"\ndt = 0.01', 'method = "DOP853"\nrtol = 1e-10\natol = 1e-12'))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        s = compare_scene(path, states=1, progress=False, mujoco_integrator="Euler", mujoco_dt=0.003).summary()
    assert not s["mujoco"]["blow_ups"] and s["project"]["method"] == "DOP853"
    found = _implausible(s, "energy_growth")
    assert [x["engine"] for x in found] == ["MuJoCo"] and found[0]["value"] > 0.1, found
    assert "MuJoCo: the energy grows in a passive scene: max (h - h(0))" in s["verdict"]["text"]


SPIN = """description = "planted: a free box driven by a large moment and force, no gravity"
[robot]
shipped = "free_body"
floating_base = true
[[moment]]
link = "body"
frame = "world"
value = [0.0, 0.0, 200.0]
[[force]]
link = "body"
point = [0, 0, 0]
frame = "world"
value = [300.0, 0.0, 0.0]
[run]
t_end = 0.5
method = "DOP853"
rtol = 1e-10
atol = 1e-12
samples = 101
"""


def test_a_base_twist_past_the_speed_bounds_is_implausible(tmp_path):
    """The free box (3 kg, I_zz = 0.5 kg m^2, at rest, no gravity) under 300 N and 200 N m for 0.5 s: 50 m/s
    and 200 rad/s, past the 10 m/s and 100 rad/s bounds; the engines agree to ~1e-12 and the verdict is
    still not "agree"."""
    path = tmp_path / "spin.toml"
    path.write_text(SPIN)
    s = _compare(path, 0.5)
    found = _implausible(s, "speed")
    got = {(x["engine"], x["units"]): x for x in found}
    assert set(got) == {(e, u) for e in ("urdf2links", "MuJoCo") for u in ("m/s", "rad/s")}
    for e in ("urdf2links", "MuJoCo"):
        assert abs(got[(e, "m/s")]["value"] - 50.0) < 1e-6 and got[(e, "m/s")]["bound"] == P.LINEAR_SPEED_BOUND
        assert abs(got[(e, "rad/s")]["value"] - 200.0) < 1e-6 and got[(e, "rad/s")]["bound"] == P.ANGULAR_SPEED_BOUND
    assert s["trajectory"]["divergence_time"] is None
    assert "the floating base body spins at 200 rad/s" in s["verdict"]["text"]


def test_check_fails_an_implausible_scene(tmp_path):
    """``urdf2links check``'s scene case fails with the gate's reasons, even when it writes the baselines."""
    path = tmp_path / "runaway.toml"
    path.write_text(RUNAWAY)
    entry = SceneEntry(id="runaway.toml", path=path)
    res = run_case(Case("scene", entry.id, entry.id, entry), RunContext(writing=True))
    assert res.status == "fail", res.message()
    assert "implausible run: " in res.message() and "elbow_joint" in res.message()


def test_a_sound_shipped_scene_still_agrees():
    """The control: the shipped spring arm (torques, springs, dampers, gravity) passes the gate and agrees;
    its scope names the joint limits both engines leave out, and not its springs (the scene's own replace the
    file's damping)."""
    s = _compare(shipped_robots_dir() / "spring_arm_torques.toml", 1.0)
    assert s["plausibility"]["plausible"] and not s["plausibility"]["findings"], s["plausibility"]["text"]
    assert s["verdict"]["plausible"] and s["verdict"]["text"].startswith("the engines agree to ")
    assert "implausible" not in s["verdict"]["text"]
    # its joints' limits are left out of both engines; its springs and dampers are the scene's own (not "off")
    off = {x["effect"]: x for x in s["verdict"]["switched_off"]}
    assert set(off) == {"limits"} and off["limits"]["names"] == ["j1", "j2", "j3"], off
    assert s["verdict"]["scope"] == ("the model without its joint limits (3 joints: j1, j2, j3) (switched off on both "
                                     "engines)")
    assert "without its joint limits (3 joints: j1, j2, j3) (switched off on both engines)" in s["verdict"]["text"]


@pytest.mark.parametrize("bound", ["PENETRATION_FRACTION", "BASE_MARGIN", "LIMIT_MARGIN", "ANGULAR_SPEED_BOUND",
                                   "LINEAR_SPEED_BOUND", "SPEED_FACTOR", "ENERGY_GROWTH_BOUND"])
def test_every_bound_is_documented(bound):
    """Each threshold of the gate is named in docs/reports.md with its value."""
    from urdf2links.locations import checkout_root

    doc = (checkout_root() / "docs" / "reports.md").read_text()
    assert f"`{bound}`" in doc, bound


def test_the_scope_names_what_a_real_mjcf_file_loses(tmp_path):
    """gymnasium's ant.xml (a floor, 8 joints with limits, 8 motors) under gravity for 0.2 s, in a scene that
    names no contact and no actuator: the verdict's scope, in the JSON and in the sentence, names the floor and
    its contact, the limits and the motors as switched off on both engines, never "the whole model"."""
    import importlib.resources

    ant = importlib.resources.files("gymnasium").joinpath("envs", "mujoco", "assets", "ant.xml")
    path = tmp_path / "ant_fall.toml"
    path.write_text(f'description = "the ant under gravity"\n[robot]\nmjcf = "{ant}"\n[gravity]\nmagnitude = 9.81\n'
                    '[run]\nt_end = 0.2\nsamples = 41\n')
    s = _compare(path, 0.2)
    v = s["verdict"]
    off = {x["effect"]: x for x in v["switched_off"]}
    assert v["scope"].startswith("the model without its ") and v["scope"].removeprefix("the model ") in v["text"]
    assert off["limits"]["count"] == 8 and off["actuators"]["count"] == 8, off
    # ant.xml's motors have no names: each is named by its index and its joint, never by an empty string
    assert all(n.startswith("#") and " on " in n for n in off["actuators"]["names"]), off["actuators"]
    if "contact" not in s["effects"]:       # the scene applies no contact: the file's is switched off
        assert off["contact"]["names"][0] == "floor" and "the file's floor 'floor'" in v["scope"]
    for effect in off:
        assert off[effect]["text"] in v["text"]

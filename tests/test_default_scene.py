"""A robot without a scene (issue 12): the default scene, its TOML, URDF damping on both MuJoCo routes,
joint-limit excursions, and the CLI forms ``simulate|compare ROBOT.urdf`` and ``inspect ROBOT.urdf --scene``."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

from cli_runner import run_cli

from urdf2links import load_urdf
from urdf2links.errors import SceneError
from urdf2links.locations import shipped_robots_dir
from urdf2links.scenes.limits import limit_excursions
from urdf2links.scenes.default_scenes import default_scene
from urdf2links.scenes.scene_read import load_scene
from urdf2links.scenes.scene_toml import scene_or_robot, scene_toml, write_scene
from urdf2links.integration.simulate import simulate

DAMPED_ARM = """<?xml version="1.0"?>
<robot name="damped_arm">
  <link name="base"/>
  <joint name="shoulder" type="revolute">
    <parent link="base"/><child link="upper"/><origin xyz="0 0 0.5"/><axis xyz="0 1 0"/>
    <limit lower="-0.5" upper="0.5" effort="10" velocity="2"/><dynamics damping="0.8" friction="0.2"/>
  </joint>
  <link name="upper"><inertial><origin xyz="0.25 0 0"/><mass value="1.5"/>
    <inertia ixx="0.002" iyy="0.03" izz="0.03" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="elbow" type="revolute">
    <parent link="upper"/><child link="fore"/><origin xyz="0.5 0 0" rpy="0.2 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-2" upper="2" effort="10" velocity="2"/><dynamics damping="0.3"/>
  </joint>
  <link name="fore"><inertial><origin xyz="0.2 0 0"/><mass value="0.8"/>
    <inertia ixx="0.001" iyy="0.011" izz="0.011" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="slide" type="prismatic">
    <parent link="fore"/><child link="tip"/><origin xyz="0.4 0 0"/><axis xyz="1 0 0"/>
    <limit lower="-0.1" upper="0.1" effort="10" velocity="1"/><dynamics damping="2.0"/>
  </joint>
  <link name="tip"><inertial><origin xyz="0.05 0 0"/><mass value="0.3"/>
    <inertia ixx="0.0002" iyy="0.0003" izz="0.0003" ixy="0" ixz="0" iyz="0"/></inertial></link>
</robot>
"""


@pytest.fixture
def arm(tmp_path):
    f = tmp_path / "damped_arm.urdf"
    f.write_text(DAMPED_ARM)
    return f


def cli(*args, cwd=None):
    return run_cli(*args, cwd=cwd)  # in this process, as a subprocess would show it (tests/cli_runner.py)


def test_default_scene_contents(arm):
    s = default_scene(arm, q0="rest")
    assert s.name == "default-rest" and s.path is None and s.urdf_damping
    np.testing.assert_array_equal(s.gravity, [0.0, 0.0, -9.81])
    assert s.base is None and not s.loads and not s.torques and s.q0 == {} and s.qd0 == {}
    assert s.run.t_end == 1.0 and s.run.method == "auto"
    assert default_scene(arm, q0="zero").q0 == {} and default_scene(arm, q0="zero").name == "default-rest"
    assert s.load_options["floating_base"] is False
    floating = default_scene(arm, floating=True, t_end=0.5)
    assert floating.load_options["floating_base"] and floating.run.t_end == 0.5


def test_random_q0_is_seeded_and_within_limits(arm):
    a, b, c = (default_scene(arm, q0="random", seed=s) for s in (0, 0, 1))
    assert a.q0 == b.q0 != c.q0
    assert -0.5 <= a.q0["shoulder"] <= 0.5 and -2 <= a.q0["elbow"] <= 2 and -0.1 <= a.q0["slide"] <= 0.1
    with pytest.raises(SceneError, match="q0"):
        default_scene(arm, q0="up")


def test_random_q0_reads_huge_limits_as_none(tmp_path):
    """Gazebo-style files write +-1e16 for joints that turn freely (example-robot-data's iris rotors):
    drawn within them, q0 would be ~1e15 rad, where sin and cos have no digits left. They count as no
    limit, so q0 falls in [-1, 1] like an unlimited joint's."""
    f = tmp_path / "rotor.urdf"
    f.write_text(DAMPED_ARM.replace('lower="-2" upper="2"', 'lower="-1e16" upper="1e16"'))
    for seed in range(5):
        q0 = default_scene(f, q0="random", seed=seed).q0
        assert -1.0 <= q0["elbow"] <= 1.0 and -0.5 <= q0["shoulder"] <= 0.5


def test_urdf_dampers_and_friction_note(arm):
    s = default_scene(arm)
    model = load_urdf(arm)
    springs = s.springs_for(model)
    assert {sp.coordinate: sp.damping for sp in springs.springs} == {"shoulder": 0.8, "elbow": 0.3, "slide": 2.0}
    assert any("friction" in n and "not modelled" in n and "shoulder" in n for n in springs.notes)
    off = scene_or_robot(arm)  # same scene through the CLI's door
    assert off.urdf_damping


def test_scene_toml_round_trip(arm, tmp_path):
    s = default_scene(arm, q0="random", seed=3, t_end=0.7)
    f = write_scene(s, tmp_path / "scenes" / "mine.toml")
    back = load_scene(f)
    assert back.robot.resolve() == arm.resolve() and back.urdf_damping
    assert back.q0 == pytest.approx(s.q0, abs=0) and back.run == s.run
    ex = default_scene(arm, seed=3, t_end=0.7)         # the excited default: qd0 and its damper torques too
    again = load_scene(write_scene(ex, tmp_path / "excited.toml"))
    assert again.qd0 == ex.qd0 and again.q0 == ex.q0 and again.torques == ex.torques and len(ex.torques) == 3
    np.testing.assert_array_equal(back.gravity, s.gravity)
    assert back.load_options == {**s.load_options}
    with pytest.raises(SceneError, match="functions of time"):
        scene_toml(load_scene(shipped_robots_dir() / "ship_crane.toml"))


def test_limit_excursions_say_when_which_and_how_far(arm):
    model = load_urdf(arm)
    t = np.linspace(0, 1, 11)
    q = np.zeros((11, model.n))
    q[:, model.coordinate_names.index("shoulder")] = np.linspace(0, 1, 11)  # leaves +0.5 at t = 0.6
    (e,) = limit_excursions(model, t, q)
    assert (e.joint, e.side, e.t_worst) == ("shoulder", "upper", 1.0) and e.t_first == pytest.approx(0.6)
    said = re.search(r"t = (\S+) s.*?(\S+) rad past the upper", e.text())      # parsed, not matched as printed
    assert e.worst == pytest.approx(0.5) and said, e.text()
    assert float(said.group(1)) == pytest.approx(0.6, abs=1e-9) and float(said.group(2)) == pytest.approx(0.5, rel=1e-3)


def test_simulate_robot_file_without_scene(arm, tmp_path):
    out = cli("simulate", str(arm), "--q0", "random", "--out", str(tmp_path / "out"),
              "--write-scene", str(tmp_path / "arm.toml"), "--quiet")
    assert out.returncode == 0, out.stderr
    assert "default-random-seed0: damped_arm" in out.stdout and "damper" in out.stdout
    assert "note: joint 'shoulder' left its limits [-0.5, 0.5] rad at t =" in out.stdout
    assert "Coulomb friction" in out.stdout
    assert (tmp_path / "out" / "damped_arm_default-random-seed0.npz").is_file() and (tmp_path / "arm.toml").is_file()
    again = cli("simulate", str(tmp_path / "arm.toml"), "--out", str(tmp_path / "out2"), "--quiet")
    assert again.returncode == 0, again.stderr
    bad = cli("simulate", str(tmp_path / "arm.toml"), "--floating")
    assert bad.returncode == 2 and "--floating" in bad.stderr and "Traceback" not in bad.stderr


def test_inspect_scene_prints_the_default_scene(arm):
    out = cli("inspect", str(arm), "--scene")
    assert out.returncode == 0, out.stderr
    assert "[dampers]" in out.stdout and "from_urdf = true" in out.stdout and "terms computed: A, e, G, tau, damper" in out.stdout
    table = cli("inspect", str(arm))
    assert "damping" in table.stdout and "0.8" in table.stdout and "-0.5" in table.stdout


def test_compare_damped_urdf_without_scene(arm, tmp_path):
    """Both engines damped (route 1 writes the dampers, route 2 keeps MuJoCo's own reading of
    <dynamics damping>); terms and trajectories agree as for the shipped scenes (tests/test_reports.py:
    terms < 1e-10, trajectory < 1e-6, no divergence)."""
    out = cli("compare", str(arm), "--q0", "random", "--out", str(tmp_path / "rep"), "--quiet")
    assert out.returncode == 0, out.stderr
    s = json.loads((tmp_path / "rep" / "summary.json").read_text())
    assert s["key"] == "damped_arm/default-random-seed0" and "damper" in s["effects"]
    assert s["terms"]["route1"]["max_rel_error"] < 1e-10 and s["terms"]["route2"]["max_rel_error"] < 1e-10
    assert s["terms"]["route2"]["max_rel_error_damping"] < 1e-12  # -c qd: one product each side
    assert s["trajectory"]["max_abs_error"] < 1e-6 and s["trajectory"]["divergence_time"] is None
    assert s["energy"]["work_terms"] and s["energy"]["project_drift_rel"] < 1e-8
    r2 = " ".join(s["terms"]["route2"]["notes"])
    assert "dof_damping from the URDF's <dynamics damping> kept" in r2
    assert any(n.startswith("limits: joint 'shoulder' left its limits") for n in s["notes"])
    assert any("no scene file" in n for n in s["notes"])


def test_route2_damping_check_can_fail(arm):
    """The damper comparison of route 2 is MuJoCo's own reading of the file: a wrong value shows."""
    from urdf2links.compare.agreement.terms import compare_terms_urdf

    model = load_urdf(arm)
    good = compare_terms_urdf(arm, model, dampers={"shoulder": 0.8, "elbow": 0.3, "slide": 2.0})
    bad = compare_terms_urdf(arm, model, dampers={"shoulder": 0.8, "elbow": 0.3, "slide": 1.0})
    assert good.max_rel_error_damping < 1e-12 and bad.max_rel_error_damping > 0.1

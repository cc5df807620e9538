"""Issue 43's smaller findings, as a new user meets them: what the commands print must be usable as it is.

- ``urdf2links inspect ROBOT --scene > f.toml`` writes a scene file that parses (the plan as TOML comments);
- a negative mass's "mass matrix not positive definite" names the link, its mass and the CLI's
  ``--inertia repair``;
- a misspelt attribute (``<mass valeu="0.5"/>``) is named with a did-you-mean;
- ``inspect`` of an MJCF file with a ``home`` keyframe says how the default scene uses it.
"""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

import numpy as np
import pytest

from cli_runner import run_cli
from urdf2links.errors import DynamicsError, URDFValueError
from urdf2links.parsers.urdf import parse_urdf

ROBOTS = Path(__file__).resolve().parent.parent / "robots"


def test_inspect_scene_output_is_a_scene_file(tmp_path):
    """The printed default scene parses as TOML and loads as a scene; the plan is there, as comments.
    Planted: the same text with the plan's lines uncommented (the output before issue 43) does not parse."""
    from urdf2links.scenes.scene_read import load_scene

    out = run_cli("inspect", str(ROBOTS / "double_pendulum.urdf"), "--scene")
    assert out.returncode == 0, out.stderr
    data = tomllib.loads(out.stdout)
    assert "robot" in data and "initial" in data
    assert re.search(r"^# terms computed: A, e, G", out.stdout, re.M)
    path = tmp_path / "f.toml"
    path.write_text(out.stdout)
    scene = load_scene(path)
    assert scene.model().n == 2
    uncommented = re.sub(r"^# ?", "", out.stdout, flags=re.M)
    with pytest.raises(tomllib.TOMLDecodeError):
        tomllib.loads(uncommented)
    shipped = run_cli("inspect", str(ROBOTS / "ship_crane.toml"))     # a scene file: its plan alone, as before
    assert shipped.returncode == 0 and shipped.stdout.startswith("scene 'ship_crane'")


NEGATIVE = """<robot name="neg">
  <link name="base"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="arm"/><axis xyz="0 1 0"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <link name="arm"><inertial><origin xyz="0 0 -0.2"/><mass value="-0.5"/>
    <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
</robot>"""


def test_negative_mass_names_the_link_and_the_cli_option(tmp_path):
    """The run's error names the link 'arm', its mass -0.5 kg and ``--inertia repair``; the CLI shows it.
    Planted: the same robot with a positive mass runs (the message is about the mass, not the robot)."""
    from urdf2links.parsers.robot_file import load_robot

    path = tmp_path / "neg.urdf"
    path.write_text(NEGATIVE)
    with pytest.warns(UserWarning):
        model = load_robot(path)
    with pytest.raises(DynamicsError) as err:
        model.forward_dynamics(np.zeros(1), np.zeros(1))
    text = str(err.value)
    assert "'arm' (mass -0.5 kg)" in text and "--inertia repair" in text
    mass = float(re.search(r"'arm' \(mass (-?[0-9.e+-]+) kg\)", text).group(1))
    assert mass == pytest.approx(-0.5, abs=1e-12)
    out = run_cli("simulate", str(path), "--t-end", "0.01", "--out", str(tmp_path / "o"), "--quiet")
    assert out.returncode != 0 and "'arm' (mass -0.5 kg)" in out.stderr and "--inertia repair" in out.stderr
    good = tmp_path / "pos.urdf"
    good.write_text(NEGATIVE.replace('value="-0.5"', 'value="0.5"'))
    assert np.all(np.isfinite(load_robot(good).forward_dynamics(np.zeros(1), np.zeros(1))))


def test_misspelt_attribute_is_named_with_a_did_you_mean():
    """``<mass valeu="0.5"/>``: "valeu: did you mean value?"; an attribute spelt nothing like it gets the plain
    "missing" (planted: no guess where there is nothing close)."""
    text = NEGATIVE.replace('value="-0.5"', 'valeu="0.5"')
    with pytest.raises(URDFValueError, match=r"valeu: did you mean value\?.*rename valeu to value"):
        parse_urdf(text)
    with pytest.raises(URDFValueError) as err:
        parse_urdf(NEGATIVE.replace('value="-0.5"', 'kilograms="0.5"'))
    assert "did you mean" not in str(err.value) and "the attribute is missing" in str(err.value)


KEYED = """<mujoco model="keyed"><compiler angle="radian"/><worldbody><body name="arm">
  <joint name="j" type="hinge" axis="0 1 0" range="-1 1"/><inertial pos="0 0 -0.2" mass="1" diaginertia="0.01 0.01 0.01"/>
  </body></worldbody><keyframe><key name="KEY" qpos="0.6"/></keyframe></mujoco>"""


def test_inspect_says_how_the_default_scene_uses_the_home_keyframe(tmp_path):
    """With a keyframe named home: the default scene starts around it (and it does: q0 within a quarter of
    the range of home's 0.6); with another name: not used, and why."""
    from urdf2links.scenes.default_scenes import default_scene

    home = tmp_path / "home.xml"
    home.write_text(KEYED.replace("KEY", "home"))
    out = run_cli("inspect", str(home))
    assert out.returncode == 0, out.stderr
    (line,) = [x for x in out.stdout.splitlines() if "keyframe(s)" in x]
    assert "keyframe 'home' centres the default scene's start" in line and "not used" not in line
    scene = default_scene(home, seed=0)
    q0 = float(scene.initial_state(scene.model())[0][0])
    assert abs(q0 - 0.6) <= 0.5 + 1e-12          # a quarter of the range [-1, 1] around home
    other = tmp_path / "other.xml"
    other.write_text(KEYED.replace("KEY", "stand"))
    out = run_cli("inspect", str(other))
    assert "not used: none is named 'home'" in out.stdout

"""A floating robot on the ground stands on its feet (issue 43, urdf2links/scenes/stance.py, docs/contact.md):
the example-robot-data quadrupeds with --floating --ground in the default scene, and an MJCF file's own floor.

The margin past a joint limit is 0.1 rad: the stance keeps every joint a tenth of its range inside its limits
and its sway at most half of that distance, so a held leg stays inside (measured over 1 s: the closest, a1's,
0.088 rad short of its limit); a leg that folds under the weight goes past by a radian or more (go1's calf 1.5
rad in issue 43's run), which the planted run without servos shows."""

from __future__ import annotations

import dataclasses
import re
import warnings
from pathlib import Path

import numpy as np
import pytest

from urdf2links.integration.simulate import simulate
from urdf2links.scenes.contact import SETTLE
from urdf2links.scenes.plan import compile_plan
from urdf2links.scenes.default_scenes import default_scene
from urdf2links.scenes.stance import ground_for, stance_figures, with_ground

#: joints may pass a limit by this much (rad): see the module doc.
LIMIT_MARGIN = 0.1
#: the quadrupeds of example-robot-data (6.0.0), the robot files issue 43 names and the rest that exist
QUADRUPEDS = {
    "go1": "go1_description/urdf/go1.urdf", "go2": "go2_description/urdf/go2.urdf",
    "solo12": "solo_description/robots/solo12.urdf", "anymal_b": "anymal_b_simple_description/robots/anymal.urdf",
    "anymal_c": "anymal_c_simple_description/urdf/anymal.urdf", "a1": "a1_description/urdf/a1.urdf",
    "hyq": "hyq_description/robots/hyq_no_sensors.urdf", "laikago": "laikago_description/urdf/laikago.urdf",
    "b1": "b1_description/urdf/b1.urdf", "quadruped": "quadruped_description/urdf/quadruped.urdf",
}
T_END = 0.5


def _ground_scene(name, *, q0="excite", t_end=T_END):
    from corpus import ROOT

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")         # base inertia findings of go1 and others: audited, not the point
        scene = default_scene(ROOT / QUADRUPEDS[name], floating=True, q0=q0, t_end=t_end)
        model = scene.model()
    return with_ground(scene, model, q0=q0), model


@pytest.mark.usefixtures("corpus_installed")
@pytest.mark.parametrize("name", sorted(QUADRUPEDS))
def test_quadruped_stands_on_four_feet(name):
    """--floating --ground in the excited default scene: four feet chosen (every quadruped's, by name), the
    base above half its starting height, tilted less than 0.5 rad, no joint past a limit by LIMIT_MARGIN."""
    scene, model = _ground_scene(name)
    (spec,) = scene.contacts
    assert len(spec.spheres) == 4, [s.link for s in spec.spheres]
    assert all(re.search("foot|contact", s.link, re.I) for s in spec.spheres), [s.link for s in spec.spheres]
    assert "feet: 4" in " ".join(scene.notes)
    traj = simulate(compile_plan(scene, model), progress=False)
    fig = stance_figures(model, traj.q, ground=0.0)
    assert fig.standing(margin=LIMIT_MARGIN), fig
    # measured over 1 s: the base sinks at most 1 cm (hyq) and tilts at most 0.05 rad (anymal_b)
    assert fig.min_height > fig.start_height - 0.05, fig


@pytest.mark.usefixtures("corpus_installed")
def test_without_the_servos_the_check_sees_the_robot_fold():
    """Planted: go1's standing scene with its stance servos removed. The legs fold under the weight, and the
    stance check says so (a joint far past its limit, the base low): the check can fail."""
    scene, model = _ground_scene("go1")
    folded = dataclasses.replace(scene, actuators=())
    fig = stance_figures(model, simulate(compile_plan(folded, model), progress=False).q, ground=0.0)
    assert not fig.standing(margin=LIMIT_MARGIN), fig
    # measured: the calves fold 4 rad past their limits and the trunk (no contact sphere) ends 0.42 m below
    assert fig.max_past_limit > 1.0 and fig.min_height < 0.0, fig


@pytest.mark.usefixtures("corpus_installed")
def test_feet_are_found_from_any_start():
    """Issue 43's case: the excited start leaves one foot lowest (the old --ground took RL_foot alone); the
    stance's feet are the four, the same from the excited, random and rest starts (planted: the excited q0's
    lowest sphere alone)."""
    from urdf2links.scenes.contact import resolve_contacts

    feet = {}
    for q0 in ("excite", "random", "rest"):
        scene, model = _ground_scene("go1", q0=q0)
        feet[q0] = sorted(s.link for s in scene.contacts[0].spheres)
    assert feet["excite"] == feet["random"] == feet["rest"] == ["FL_foot", "FR_foot", "RL_foot", "RR_foot"]
    excited = default_scene(Path(scene.robot), floating=True, t_end=T_END, model=model)
    lowest = dataclasses.replace(scene.contacts[0], spheres=(), lowest=True, height="touching")
    planted = resolve_contacts((lowest,), model, excited.initial_state(model)[0])
    assert len(planted.spheres) < 4


@pytest.mark.usefixtures("corpus_installed")
@pytest.mark.parametrize("name", ["go1", "solo12"])
def test_engines_agree_on_the_standing_quadruped(name):
    """Both engines run the standing quadruped (the same law in MuJoCo's callback): they agree to the
    divergence threshold, MuJoCo's run stands as well, and the stdout line prints each engine's base height."""
    from urdf2links.compare.agreement.trajectory import compare_scene

    scene, model = _ground_scene(name)
    c = compare_scene(scene, model=model, states=1, progress=False)
    s = c.summary()
    # measured 3e-10 (go1, 1 s) and 1e-11 (solo12); the divergence threshold is 1e-3
    assert s["trajectory"]["max_abs_error"] < 1e-6
    assert stance_figures(model, c.q_mujoco, ground=0.0).standing(margin=LIMIT_MARGIN)
    b = s["contact"]["native"]["base_height"]
    assert b["ground"] == 0.0 and b["ours_min"] > 0.5 * b["ours_final"] > 0.0


# --------------------------------------------------------------------------- an MJCF file's own floor


def _ant(tmp_path, floor="0 0 0", friction=None) -> Path:
    import gymnasium

    text = (Path(gymnasium.__file__).parent / "envs/mujoco/assets/ant.xml").read_text()
    head = '<geom conaffinity="1" condim="3" material="MatPlane" name="floor" pos="0 0 0"'
    assert head in text
    text = text.replace(head, head.replace('pos="0 0 0"', f'pos="{floor}"')
                        + (f' friction="{friction} 0.005 0.0001"' if friction else ""))
    path = tmp_path / "ant.xml"
    path.write_text(text)
    return path


def test_mjcf_floor_is_the_ground(tmp_path):
    """gymnasium's ant.xml has a floor: its default scene stands on it, at the floor's height and with its
    friction (planted: the floor moved up 0.3 m and its friction 0.4 move the ground and mu with it)."""
    import gymnasium

    for path, height, mu in ((Path(gymnasium.__file__).parent / "envs/mujoco/assets/ant.xml", 0.0, 1.0),
                             (_ant(tmp_path, floor="0 0 0.3", friction=0.4), 0.3, 0.4)):
        scene = default_scene(path, t_end=T_END)
        model = scene.model()
        ground = ground_for(scene, model)
        (spec,) = ground.contacts
        assert spec.height == pytest.approx(height) and spec.friction == pytest.approx(mu)
        assert "the file's floor 'floor'" in ground.description and "--no-floor" in ground.description
        assert len(spec.spheres) == 4
        traj = simulate(compile_plan(ground, model), progress=False)
        fig = stance_figures(model, traj.q, ground=height)
        assert fig.standing(margin=LIMIT_MARGIN), fig
        # the lowest foot starts SETTLE into the floor (placed by the stance)
        assert fig.start_height > 0.1
    dropped = ground_for(scene, model, floor=False)
    assert not dropped.contacts and "--no-floor" in " ".join(dropped.notes)


def test_compare_keeps_the_floor_and_prints_each_engines_base_height():
    """`urdf2links compare ant.xml`: the floor kept (stderr names the feet), the engines agree, and the contact
    line prints each engine's real base height, the difference labelled as one (issue 43: it printed native
    minus law as "base height")."""
    import json
    import tempfile

    import gymnasium
    from cli_runner import run_cli

    ant = Path(gymnasium.__file__).parent / "envs/mujoco/assets/ant.xml"
    with tempfile.TemporaryDirectory() as out:
        r = run_cli("compare", str(ant), "--t-end", "0.3", "--out", out)
        assert r.returncode == 0, r.stderr
        s = json.loads((Path(out) / "summary.json").read_text())
    assert "feet: 4" in r.stderr
    line = next(x for x in r.stdout.splitlines() if x.strip().startswith("contact"))
    m = re.search(r"urdf2links (\S+) m .*MuJoCo's native contact \(a reference\) (\S+) m; difference native - "
                  r"urdf2links (\S+) m", line)
    assert m, line
    ours, native, diff = (float(x) for x in m.groups())
    b = s["contact"]["native"]["base_height"]
    assert ours == pytest.approx(b["ours_final"], rel=1e-3) and native == pytest.approx(b["native_final"], rel=1e-3)
    assert diff == pytest.approx(native - ours, abs=1e-4) and ours > 0.1
    # measured 2e-12 rad; the divergence threshold is 1e-3
    assert s["trajectory"]["max_abs_error"] < 1e-6


def test_two_feet_fall_onto_every_candidate_and_no_gravity_is_refused(tmp_path):
    """gymnasium's humanoid stands on two ball feet, which cannot carry it unaided: every collision sphere and
    capsule end then touches its floor, and the notes say why. Without gravity a file's floor is not used (noted),
    and --ground is refused by name."""
    import gymnasium

    from urdf2links.errors import SceneError

    path = Path(gymnasium.__file__).parent / "envs/mujoco/assets/humanoid.xml"
    scene = default_scene(path, t_end=T_END)
    model = scene.model()
    ground = ground_for(scene, model)
    assert len(ground.contacts[0].spheres) > 20
    assert "2 feet cannot carry the robot unaided" in " ".join(ground.notes)
    weightless = _ant(tmp_path).read_text().replace("<option ", '<option gravity="0 0 0" ', 1)
    assert 'gravity="0 0 0"' in weightless
    (tmp_path / "ant0.xml").write_text(weightless)
    scene = default_scene(tmp_path / "ant0.xml", t_end=T_END)
    kept = ground_for(scene, scene.model())
    assert not kept.contacts and "without gravity nothing holds the robot" in " ".join(kept.notes)
    with pytest.raises(SceneError, match="ant0.xml.*no gravity"):
        ground_for(scene, scene.model(), ground=True)


@pytest.mark.usefixtures("corpus_installed")
def test_a_collision_sphere_elsewhere_does_not_hide_the_named_feet(tmp_path):
    """Planted: solo12 (meshes only) with a collision sphere added under its base. The feet are still its four
    links named FOOT (spheres at their origins), not the base's sphere, which cannot reach the ground."""
    from corpus import ROOT

    src = ROOT / "solo_description/robots/solo12.urdf"
    text = src.read_text()
    anchor = "    <!-- BASE LINK VISUAL -->"
    assert text.count(anchor) == 1
    text = text.replace(anchor, '    <collision><origin xyz="0 0 -0.05"/><geometry><sphere radius="0.03"/></geometry>'
                                "</collision>\n" + anchor)
    path = tmp_path / "solo12_sphere.urdf"
    path.write_text(text)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = default_scene(path, floating=True, t_end=T_END)
        model = scene.model()
    assert [s[0] for s in model.info["collision_spheres"]] == ["base_link"]
    ground = with_ground(scene, model)
    assert sorted(s.link for s in ground.contacts[0].spheres) == ["FL_FOOT", "FR_FOOT", "HL_FOOT", "HR_FOOT"]


def test_no_floor_drops_the_files_floor_and_says_so(tmp_path):
    """`compare ant.xml --no-floor`: no ground (no contact line), stderr names the dropped floor, and the
    report's command to regenerate it keeps --no-floor (planted: the run without it has a contact line)."""
    import gymnasium
    from cli_runner import run_cli

    ant = Path(gymnasium.__file__).parent / "envs/mujoco/assets/ant.xml"
    r = run_cli("compare", str(ant), "--no-floor", "--t-end", "0.05", "--out", str(tmp_path))
    assert r.returncode == 0, r.stderr
    assert "--no-floor: the file's floor 'floor' dropped" in r.stderr
    assert not any(x.strip().startswith("contact") for x in r.stdout.splitlines())
    assert "--no-floor" in (tmp_path / "report.html").read_text()

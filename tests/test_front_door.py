"""The front door (issue 22): what a new user meets, tried as they would, with the messages checked.

Shipped robots and scenes by name from any folder, the same loading options on every command,
files other readers read (a NUL byte, blank lines before the XML declaration), a model one engine
cannot represent, never a traceback, outputs named by the robot, runs that say which scenes and
baselines they use, and tolerances that keep rounding out of the notes.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest

from cli_runner import run_cli

from urdf2links import load_urdf, load_urdf_string
from urdf2links.cli import build_parser, main
from urdf2links.errors import URDFSyntaxError
from urdf2links.locations import InputNotFound, find_input, shipped, shipped_robots_dir

ROOT = Path(__file__).resolve().parents[1]

#: A fixed-base arm whose root link has zero mass but an inertia (as pybullet's kuka_iiwa/model.urdf):
#: nothing moves the root, so it has no effect on the equations.
KUKA_LIKE = """<robot name="lbr_like">
  <link name="link_0"><inertial><origin xyz="-0.1 0 0.07"/><mass value="0.0"/>
    <inertia ixx="0.05" ixy="0" ixz="0" iyy="0.06" iyz="0" izz="0.03"/></inertial></link>
  <joint name="j1" type="revolute"><parent link="link_0"/><child link="link_1"/><origin xyz="0 0 0.1575"/>
    <axis xyz="0 1 0"/><limit lower="-2" upper="2" effort="300" velocity="10"/><dynamics damping="0.5"/></joint>
  <link name="link_1"><inertial><origin xyz="0 -0.03 0.12"/><mass value="4"/>
    <inertia ixx="0.1" ixy="0" ixz="0" iyy="0.09" iyz="0" izz="0.02"/></inertial></link>
</robot>
"""


def run(*args, cwd, env=None):
    """The command line as a user types it (stdout, stderr, exit status), in this process (tests/cli_runner.py)."""
    return run_cli(*args, cwd=cwd, env=env)


# -- 2. shipped robots and scenes by name ---------------------------------------------------------
def test_shipped_names_resolve_from_any_folder(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    path, note = find_input("ship_crane")
    assert path == shipped_robots_dir() / "ship_crane.toml" and note is None
    path, note = find_input("ur5_like.urdf")
    assert path == shipped_robots_dir() / "ur5_like.urdf" and note is None
    path, note = find_input("robots/hard/chain32_swing.toml")       # the layout of a checkout, outside one
    assert path == shipped_robots_dir() / "hard" / "chain32_swing.toml"
    assert "not a file here; using the shipped scene 'chain32_swing'" in note
    (tmp_path / "ship_crane.toml").write_text("x")                  # a file of the user's wins
    assert find_input("ship_crane.toml") == (Path("ship_crane.toml"), None)
    with pytest.raises(InputNotFound) as err:
        find_input("robots/nothing.toml")
    text = str(err.value)
    assert "no such file: 'robots/nothing.toml'" in text and str(tmp_path) in text
    assert "`urdf2links list`" in text and str(shipped_robots_dir()) in text


def test_list_shows_every_shipped_file_with_a_line(tmp_path):
    out = run("list", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    files = sorted(p.stem for p in shipped_robots_dir().rglob("*") if p.suffix in (".urdf", ".toml", ".xml"))
    assert sorted(s.name for s in shipped()) == files
    for s in shipped():
        line = next(ln for ln in out.stdout.splitlines() if ln.split()[:1] == [s.name])
        assert s.kind.split()[0] in line
    robots = [s for s in shipped() if s.kind == "robot"]
    assert all(s.summary for s in robots), [s.name for s in robots if not s.summary]     # README sections


def test_a_missing_file_says_where_the_shipped_ones_are(tmp_path):
    out = run("simulate", "robots/no_such_scene.toml", cwd=tmp_path)
    assert out.returncode == 2 and "Traceback" not in out.stderr
    assert "no such file" in out.stderr and "urdf2links list" in out.stderr


# -- 3. the same loading options everywhere; a model one engine cannot represent ---------------------
LOADING = ["--floating", "--inertia", "repair", "--mimic", "coupled", "--strict", "--package-dir", "d",
           "--xacro-arg", "a:=1"]


@pytest.mark.parametrize("command", ["inspect", "simulate", "compare", "sweep", "tradeoff", "report"])
def test_every_command_that_loads_a_robot_takes_the_loading_options(command):
    args = build_parser().parse_args([command, *([] if command == "report" else ["x.urdf"]), *LOADING])
    assert (args.floating, args.inertia, args.mimic, args.strict, args.package_dir, args.xacro_arg) == \
        (True, "repair", "coupled", True, ["d"], ["a:=1"])


def test_a_massless_root_with_inertia_compares(tmp_path):
    """Route 1 writes the root (nothing moves it) without inertia, and says so; was a traceback."""
    f = tmp_path / "model.urdf"
    f.write_text(KUKA_LIKE)
    out = run("compare", str(f), "--t-end", "0.05", "--animation-fps", "0", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    summary = json.loads((tmp_path / "out/reports/lbr_like/default/summary.json").read_text())     # the robot's name
    assert any("link_0" in n and "written without inertia" in n for n in summary["mujoco"]["notes"] + summary["notes"])
    assert summary["terms"]["max_rel_error_route1"] < 1e-12


def test_a_moving_massless_link_with_inertia_names_the_link_and_the_fix(tmp_path):
    f = tmp_path / "model.urdf"
    text = KUKA_LIKE.replace('<mass value="4"/>', '<mass value="0"/>')
    f.write_text(text)
    out = run("compare", str(f), "--t-end", "0.05", cwd=tmp_path)
    assert out.returncode == 2 and "Traceback" not in out.stderr
    assert "link 'link_1' has zero mass but non-zero second moments" in out.stderr
    assert "--inertia repair" in out.stderr
    fixed = run("compare", str(f), "--t-end", "0.05", "--inertia", "repair", "--animation-fps", "0", cwd=tmp_path)
    assert fixed.returncode == 0, fixed.stderr
    assert (tmp_path / "out/reports/lbr_like/default-repair/summary.json").is_file()


def test_loading_options_on_a_scene_file_are_noted(tmp_path):
    out = run("inspect", "ur5_falling", "--inertia", "repair", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    assert "note: inertia = 'repair' from the command line" in out.stdout
    refused = run("simulate", "ur5_falling", "--floating", cwd=tmp_path)
    assert refused.returncode == 2 and "--floating apply to a robot file" in refused.stderr


def test_never_a_traceback(tmp_path, monkeypatch, capsys):
    """An internal error ends in one message naming it, exit 2; URDF2LINKS_DEBUG shows the traceback."""
    import urdf2links.cli as cli

    def broken(args):
        raise KeyError("boom")

    monkeypatch.setitem(cli.COMMANDS, "list", cli.COMMANDS["list"]._replace(run=broken))
    monkeypatch.delenv("URDF2LINKS_DEBUG", raising=False)
    assert main(["list"]) == 2
    err = capsys.readouterr().err
    assert "urdf2links list: error: KeyError: 'boom' (an internal error" in err and "URDF2LINKS_DEBUG" in err
    monkeypatch.setenv("URDF2LINKS_DEBUG", "1")
    with pytest.raises(KeyError):
        main(["list"])


# -- 4. files other readers read ---------------------------------------------------------------------
ROBOT = '<robot name="r"><link name="a"/><joint name="j" type="revolute"><parent link="a"/><child link="b"/>' \
        '<axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint><link name="b"><inertial>' \
        '<mass value="1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link></robot>'


def test_a_nul_byte_after_the_robot_is_read_like_urdfdom(tmp_path):
    """pybullet's humanoid.urdf ends in a NUL after </robot>; urdfdom's reader stops at a NUL."""
    f = tmp_path / "humanoid.urdf"
    f.write_bytes((ROBOT + "\r\n").encode() + b"\x00")
    m = load_urdf(f)
    assert m.n == 1
    assert any("byte 0x00 (NUL) at line 2, column 1" in n and "as urdfdom does" in n for n in m.info["notes"])
    with pytest.raises(URDFSyntaxError, match=r"byte 0x00 \(NUL\) at line 2, column 1, followed by nothing"):
        load_urdf(f, strict=True)
    f.write_bytes(ROBOT.encode() + b"\n\x00garbage<<")
    assert any("and the 9 more byte(s) after it" in n for n in load_urdf(f).info["notes"])


def test_an_xml_declaration_after_blank_lines_is_read_like_urdfdom(tmp_path):
    f = tmp_path / "late.urdf"
    f.write_text('\n\n<?xml version="1.0"?>\n' + ROBOT.replace("<link name=\"a\"/>", "<link name=\"a\"/>\n"))
    m = load_urdf(f)
    assert any("XML declaration on line 3 after 2 blank line(s)" in n for n in m.info["notes"])
    with pytest.raises(URDFSyntaxError, match="line 3: the XML declaration"):
        load_urdf(f, strict=True)
    # the lines keep their numbers: an error on the robot's second line is reported there
    f.write_text('\n\n<?xml version="1.0"?>\n<robot name="r">\n<link name="a"><bad></link></robot>')
    with pytest.raises(URDFSyntaxError, match=r"late.urdf, line 5"):
        load_urdf(f)


def test_a_refusal_names_the_byte_not_an_empty_line():
    with pytest.raises(URDFSyntaxError, match=r"byte 0x1b, a control character, at line 1"):
        load_urdf_string(ROBOT.replace("<link name=\"a\"/>", "<link name=\"a\"/>\x1b"))


# -- 5., 7. the API as the README shows it; sweeps say what compilation cost -----------------------------
def test_write_trajectory_page_takes_a_fixed_base_scenes_base_state(tmp_path):
    from urdf2links.integration import simulate
    from urdf2links.scenes import load_scene
    from urdf2links.view import write_trajectory_page

    scene = load_scene(shipped_robots_dir() / "ur5_falling.toml")
    traj = simulate(scene, t_end=0.02, progress=False)
    page = write_trajectory_page(tmp_path / "run.html", traj, scene.model(), base=scene.base_state)
    assert page.stat().st_size > 10_000
    with pytest.raises(TypeError, match="base must be None, a BaseState or a callable"):
        write_trajectory_page(tmp_path / "bad.html", traj, scene.model(), base=3.0)


def test_a_sweep_times_no_compilation():
    """The warm-up call compiles (or loads) what the sweep calls; the timed call then compiles nothing."""
    from urdf2links.integration.batch import simulate_batch, sweep_states
    from urdf2links.integration.simulate import Compilation, record_compilation
    from urdf2links.scenes.plan import as_plan

    plan = as_plan(shipped_robots_dir() / "ur5_falling.toml")
    q0, qd0 = sweep_states(plan.scene, plan.model, 3, seed=1)
    with record_compilation() as whole:
        res = simulate_batch(plan, q0, qd0, t_end=0.01, samples=3)
    assert isinstance(res.compilation, Compilation)
    assert set(whole.functions) == set(res.compilation.functions)      # all of it in the warm-up, none timed
    assert res.success


# -- 8. runs that say what they use ----------------------------------------------------------------------
def test_report_says_which_scenes_and_baselines_and_writes_out_of_the_checkout(tmp_path):
    out = run("report", "ur5_falling", "--t-end", "0.05", "--animation-fps", "0", "--quiet", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    assert "scenes: 1 from the scene files given" in out.stderr
    assert "baselines: none found (looked for out/reports/baselines.json)" in out.stderr
    assert (tmp_path / "out/reports/index.html").is_file()


def test_report_in_a_checkout_runs_its_scenes_and_checks_its_baselines(tmp_path):
    """A checkout's robots/*.toml (an edited scene counts without reinstalling) and reports/baselines.json."""
    (tmp_path / "pyproject.toml").write_text('[project]\nname = "urdf2links"\n')
    (tmp_path / "robots").mkdir()
    scene = (shipped_robots_dir() / "ur5_falling.toml").read_text().replace('shipped = "ur5_like"',
                                                                           f'urdf = "{shipped_robots_dir()}/ur5_like.urdf"')
    (tmp_path / "robots" / "edited.toml").write_text(scene.replace("The UR5-like arm", "An edited arm"))
    first = run("report", "--t-end", "0.05", "--animation-fps", "0", "--quiet", "--out", "reports",
                "--write-baselines", cwd=tmp_path)
    assert first.returncode == 0, first.stderr
    assert f"scenes: 1 from robots/*.toml and robots/loops/*.toml of the checkout {tmp_path}" in first.stderr
    assert "this run's figures are accepted into reports/baselines.json" in first.stderr
    again = run("report", "--t-end", "0.05", "--animation-fps", "0", "--quiet", cwd=tmp_path)
    assert again.returncode == 0, again.stderr
    assert "baselines: reports/baselines.json" in again.stderr and (tmp_path / "out/reports/index.html").is_file()


# -- 9. tolerances relative to the motion and the energy scale ------------------------------------------
def test_rounding_at_a_limit_is_no_excursion():
    from urdf2links.scenes.limits import LIMIT_TOLERANCE, limit_excursions

    model = load_urdf_string(ROBOT)
    t = np.array([0.0, 1.0])
    assert limit_excursions(model, t, np.array([[1.0], [1.0 + 1.24e-35]])) == []
    assert limit_excursions(model, t, np.array([[1.0], [1.0 + 1e-12]])) == []      # under 1e-9 of the range
    (e,) = limit_excursions(model, t, np.array([[1.0], [1.0 + 1e-6]]))
    assert e.tolerance == pytest.approx(2 * LIMIT_TOLERANCE) and "by more than 2e-09 rad" in e.text()


def test_energy_drift_of_a_robot_at_rest_is_measured_against_the_rounding_level():
    """A pendulum hanging at rest does not move: the drifts are rounding, and read as such."""
    from urdf2links.compare.agreement.side_by_side import ENERGY_ROUNDING_EPS
    from urdf2links.compare.agreement.trajectory import compare_scene
    from urdf2links.scenes.default_scenes import default_scene

    c = compare_scene(default_scene(shipped_robots_dir() / "pendulum.urdf", t_end=0.05, q0="rest"))
    en = c.summary()["energy"]
    assert "rounding level" in en["scale_note"] and "barely moves" in en["scale_note"]
    assert en["scale"] >= ENERGY_ROUNDING_EPS * np.finfo(float).eps * np.abs(c.energy["ours_EV"]).max()
    assert en["mujoco_drift_rel"] < 1e-2 and en["project_drift_rel"] < 1e-2


# -- 10. names ----------------------------------------------------------------------------------------
def test_reports_of_other_settings_do_not_replace_each_other(tmp_path):
    f = tmp_path / "model.urdf"
    f.write_text(KUKA_LIKE)
    a = run("compare", str(f), "--t-end", "0.02", "--animation-fps", "0", cwd=tmp_path)
    b = run("compare", str(f), "--t-end", "0.02", "--q0", "random", "--animation-fps", "0", cwd=tmp_path)
    assert a.returncode == 0 and b.returncode == 0, a.stderr + b.stderr
    assert {p.name for p in (tmp_path / "out/reports/lbr_like").iterdir()} == {"default", "default-random-seed0"}
    c = run("compare", str(f), "--t-end", "0.02", "--animation-fps", "0", cwd=tmp_path)
    assert "replacing the report written there before" in c.stderr

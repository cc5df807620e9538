"""The MuJoCo cross-validation reports: urdf2links.compare.agreement.trajectory, urdf2links.compare.reports.report, `urdf2links compare`.

Short runs (1 s) of the double pendulum and the ship crane, MuJoCo RK4 dt 1e-4 against the
project's DOP853 rtol 1e-10; the committed baselines (reports/baselines.json) must accept them.
"""

from __future__ import annotations

import copy
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from cli_runner import run_cli

import mujoco  # noqa: F401,E402 -- a declared dependency: a broken MuJoCo fails the suite

from urdf2links.compare.reports.baselines import check_baseline, load_baselines  # noqa: E402
from urdf2links.compare.formatting import json_ready  # noqa: E402
from urdf2links.compare.reports.report import write_index, write_report  # noqa: E402
from urdf2links.compare.agreement.trajectory import compare_scene, divergence_time, growth_fit  # noqa: E402
from pages import assert_offline, poses_4x4  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
ROBOTS = ROOT / "robots"
BASELINES = ROOT / "reports" / "baselines.json"
CONTRACT = ("terms.max_rel_error", "trajectory.max_abs_error", "trajectory.divergence_time", "energy.project_drift",
            "energy.mujoco_drift", "wall_time.project_s", "wall_time.mujoco_s", "mujoco.integrator",
            "mujoco.timestep")


def run_short(name):
    c = compare_scene(ROBOTS / f"{name}.toml", t_end=1.0, method="DOP853", rtol=1e-10, atol=1e-12,
                      mujoco_integrator="RK4", mujoco_dt=1e-4, progress=False)
    return c, json_ready(c.summary())


@pytest.fixture(scope="module")
def pendulum():
    return run_short("double_pendulum_chaos")


@pytest.fixture(scope="module")
def crane():
    return run_short("ship_crane")


def dig(d, dotted):
    for part in dotted.split("."):
        assert isinstance(d, dict) and part in d, f"missing key {dotted!r}"
        d = d[part]
    return d


# --------------------------------------------------------------------------- figures


@pytest.mark.parametrize("which", ["pendulum", "crane"])
def test_terms_agree_route1_and_route2(which, request):
    _, s = request.getfixturevalue(which)
    assert s["terms"]["route1"]["max_rel_error"] < 1e-10
    assert s["terms"]["route1"]["states"] == 8
    assert s["terms"]["route2"]["max_rel_error"] < 1e-10
    assert s["terms"]["max_rel_error"] < 1e-10


def test_route2_refusal_is_stated_and_repair_labelled(pendulum, crane):
    assert pendulum[1]["terms"]["route2"]["route"] == "mujoco-urdf"
    r2 = crane[1]["terms"]["route2"]
    # MuJoCo refuses the crane's massless moving link sway_gimbal: the reason is kept, the figures
    # come from the project's repair (a 1 g sphere on both sides), and the label says so
    assert r2["route"] == "mujoco-urdf-repaired" and "REPAIRED" in r2["label"]
    assert "mjMINVAL" in r2["refusal"] and "sway_gimbal" in r2["refusal"]
    assert r2["refusals"] and all(x["by"] == "MuJoCo" for x in r2["refusals"])


@pytest.mark.parametrize("which", ["pendulum", "crane"])
def test_trajectories_agree(which, request):
    c, s = request.getfixturevalue(which)
    assert s["trajectory"]["max_abs_error"] < 1e-6
    assert s["trajectory"]["divergence_time"] is None
    assert c.error.shape == c.q_ours.shape == c.q_mujoco.shape
    assert np.array_equal(c.t, c.run.t)


def test_ship_deck_agrees_as_well_as_fixed_base(pendulum, crane):
    fixed, ship = pendulum[1], crane[1]
    assert ship["base"]["moving"] and not fixed["base"]["moving"]
    assert ship["base"]["tracking_error"] < 1e-9
    assert ship["trajectory"]["max_abs_error"] <= max(10 * fixed["trajectory"]["max_abs_error"], 1e-9)
    for s in (fixed, ship):  # both engines keep the energy balance (h - h(0) - W) at rounding level
        assert s["energy"]["project_drift_rel"] < 1e-8 and s["energy"]["mujoco_drift_rel"] < 1e-8
    assert ship["energy"]["work_terms"] and "W" in ship["energy"]["note"]
    assert not fixed["energy"]["work_terms"]


def test_json_contract_and_files(pendulum, tmp_path):
    c, s = pendulum
    for key in CONTRACT:
        dig(s, key)
    assert isinstance(s["route"], str) and s["route"]
    assert s["mujoco"]["integrator"] == "RK4" and s["mujoco"]["timestep"] == 1e-4
    paths = write_report(c, tmp_path / "r", json_path=tmp_path / "copy.json")
    on_disk = json.loads((tmp_path / "r" / "summary.json").read_text())
    assert json.loads((tmp_path / "copy.json").read_text()) == on_disk
    for key in CONTRACT:
        dig(on_disk, key)
    page = paths["html"].read_text()
    assert page.count("src='data:image/png;base64,") == 4  # terms, coordinates, error, energy
    assert_offline(page)  # self-contained: the viewer and the data inline
    assert "chaotic" in page and "double_pendulum_chaos" in (tmp_path / "r" / "summary.md").read_text()
    idx = write_index([{"summary": s, "link": "r/report.html"}], tmp_path)
    assert "r/report.html" in idx["html"].read_text() and "double_pendulum_chaos" in idx["md"].read_text()


@pytest.mark.parametrize("which", ["pendulum", "crane"])
def test_report_animates_both_engines(which, request, tmp_path):
    """The report's Motion section: urdf2links solid and MuJoCo as a ghost, each drawn from its own q
    at the frame times (at most 30 per simulated second), the difference plotted beside them."""
    from urdf2links import urdf_link_poses
    from urdf2links.view.animation import read_animation_data

    c, s = request.getfixturevalue(which)
    page = write_report(c, tmp_path / "r")["html"].read_text()
    assert "<h2>Motion</h2>" in page and "largest coordinate" in page and "u2l-cursor" in page
    data = read_animation_data(page)
    assert [(r["name"], r["ghost"]) for r in data["runs"]] == [("urdf2links", False), ("MuJoCo", True)]
    t = np.array(data["t"])
    assert t[-1] == pytest.approx(s["t_end"]) and len(t) <= 30 * s["t_end"] + 2
    assert set(data["links"]) == set(c.model.info["frame_of"])
    k = np.searchsorted(c.t, t)
    base = c.scene.base_state if c.scene.base is not None else None
    for run, q in zip(data["runs"], (c.q_ours, c.q_mujoco)):
        for i in (1, len(t) - 1):
            want = urdf_link_poses(c.model, q[k[i]], t=float(t[i]), base=base)
            got = poses_4x4(run["poses"][i])
            assert all(np.allclose(P, want[nm], atol=1e-5) for nm, P in zip(data["links"], got))  # float32
    assert (data["base"] is not None) == s["base"]["moving"]
    readout = data["readout"][0]
    assert readout["label"] == "max |dq|" and max(readout["values"]) <= s["trajectory"]["max_abs_error"]
    assert "u2l-motion" not in write_report(c, tmp_path / "none", animation_fps=0)["html"].read_text()


def test_chaos_is_reported_as_chaos(pendulum):
    s = pendulum[1]
    assert s["chaotic"] and "chaos, not a failure" in s["trajectory"]["verdict"]


def test_growth_fit_and_divergence_time():
    t = np.linspace(0.0, 10.0, 2001)
    rng = np.random.default_rng(0)
    err = np.abs(1e-13 * np.exp(2.5 * t) * (1 + 0.3 * np.sin(7 * t))) + 1e-14 * rng.random(t.size)
    err = np.minimum(err, 0.5)  # saturates once the trajectories have separated
    div = divergence_time(t, err, 1e-3)
    assert div == pytest.approx(np.log(1e-3 / 1e-13) / 2.5, abs=0.2)
    fit = growth_fit(t, err, end_time=div)
    assert fit["rate"] == pytest.approx(2.5, rel=0.05) and fit["window"][1] <= div
    assert growth_fit(t, 1e-12 * np.ones_like(t)) is None  # no growth out of the noise
    assert divergence_time(t, 1e-6 * np.ones_like(t)) is None


# --------------------------------------------------------------------------- baselines


def test_committed_baselines_cover_every_shipped_scene():
    from urdf2links.compare.commands import report_t_end
    from urdf2links.scenes.scene_read import load_scene

    from urdf2links.locations import report_scene_files

    scenes = load_baselines(BASELINES)["scenes"]
    for toml in report_scene_files(ROBOTS):       # robots/*.toml and the closed loops of robots/loops/ (issue 42)
        sc = load_scene(toml)
        if sc.expected_stop is not None:          # a hard case that stops by design: no figures to accept
            continue
        runs = scenes[f"{Path(sc.robot).stem}/{sc.name}"]["runs"]
        lengths = {r["settings"]["t_end"] for r in runs}
        # the report's (capped) run and the whole scene (urdf2links compare) are both accepted
        assert report_t_end(sc, t_end=None, cap=5.0)[0] in lengths and sc.run.t_end in lengths


def test_baseline_run_selection_and_merge(pendulum, tmp_path):
    from urdf2links.compare.reports.baselines import select_run, write_baselines

    s = pendulum[1]  # a 1 s run
    path = tmp_path / "b.json"
    write_baselines([s], path)
    longer = copy.deepcopy(s)
    longer["t_end"] = 5.0
    longer["trajectory"]["max_abs_error"] = 1.0
    write_baselines([longer], path)  # added next to the 1 s run, not replacing it
    entry = load_baselines(path)["scenes"][s["key"]]
    assert [r["settings"]["t_end"] for r in entry["runs"]] == [1.0, 5.0]
    assert select_run(s, entry)[0]["settings"]["t_end"] == 1.0
    mid = dict(s, t_end=3.0)
    assert select_run(mid, entry)[0]["settings"]["t_end"] == 5.0  # the shortest run at least as long
    run, warn = select_run(dict(s, t_end=9.0), entry)
    assert run["settings"]["t_end"] == 5.0 and "longer than every accepted run" in warn[0]


@pytest.mark.parametrize("which", ["pendulum", "crane"])
def test_check_passes_against_committed_baselines(which, request):
    _, s = request.getfixturevalue(which)
    res = check_baseline(s, load_baselines(BASELINES), source="reports/baselines.json")
    assert res.ok, res.text()
    assert any(line.startswith("ok    trajectory.max_abs_error") for line in res.lines)
    assert res.warnings  # 1 s here, not the baseline's t_end: said, figures still compared


def test_check_fails_naming_the_figure(pendulum, crane):
    s = pendulum[1]
    base = copy.deepcopy(load_baselines(BASELINES))
    (accepted,) = base["scenes"][s["key"]]["runs"]  # the pendulum runs in full in the report: one run
    figs = accepted["figures"]
    figs["trajectory.max_abs_error"] = 1e-13  # allowed 10 x max(1e-13, floor 1e-12) = 1e-11 < 3.6e-10
    figs["terms.max_rel_error"] = 1e-30  # rounding level: the floor (1e-14) keeps it from jittering into a failure
    res = check_baseline(s, base)
    assert not res.ok and res.failures == ["trajectory.max_abs_error"]
    assert "FAIL  trajectory.max_abs_error" in res.text()
    ship = crane[1]
    for run in base["scenes"][ship["key"]]["runs"]:
        run["figures"]["energy.mujoco_drift"] = 1e-12  # floor: 1e-13 x energy scale
    assert check_baseline(ship, base).failures == ["energy.mujoco_drift"]
    s2 = copy.deepcopy(s)  # a divergence much earlier than the baseline's fails too
    s2["trajectory"]["divergence_time"] = 0.5
    accepted["trajectory.divergence_time"] = 4.0
    accepted["trajectory.growth_rate"] = 2.0
    assert "trajectory.divergence_time" in check_baseline(s2, base).failures
    s2["trajectory"]["divergence_time"] = 3.0  # within ln(10)/2 = 1.15 s of it: accepted
    assert "trajectory.divergence_time" not in check_baseline(s2, base).failures
    with pytest.raises(KeyError, match="no baseline"):
        check_baseline(dict(s, key="nobody/nothing"), base)


# --------------------------------------------------------------------------- command line


def cli(*args, cwd=ROOT):
    return run_cli(*args, cwd=cwd)  # in this process, as a subprocess would show it (tests/cli_runner.py)


def test_compare_cli_runs_and_checks(tmp_path):
    scene = str(ROBOTS / "double_pendulum_chaos.toml")
    common = ["compare", scene, "--t-end", "0.5", "--rtol", "1e-10", "--mujoco-dt", "1e-4", "--quiet"]
    out = cli(*common, "--out", str(tmp_path / "ok"), "--json", str(tmp_path / "s.json"), "--check", str(BASELINES))
    assert out.returncode == 0, out.stderr
    assert "baseline check passed" in out.stdout
    s = json.loads((tmp_path / "s.json").read_text())
    for key in CONTRACT:
        dig(s, key)
    assert (tmp_path / "ok" / "report.html").is_file() and (tmp_path / "ok" / "summary.md").is_file()

    shrunk = load_baselines(BASELINES)
    shrunk["scenes"]["double_pendulum/double_pendulum_chaos"]["runs"][0]["figures"]["trajectory.max_abs_error"] = 1e-13
    bad = tmp_path / "shrunk.json"
    bad.write_text(json.dumps(shrunk))
    out = cli(*common, "--out", str(tmp_path / "bad"), "--check", str(bad))
    assert out.returncode == 1
    assert "trajectory.max_abs_error" in out.stderr and "Traceback" not in out.stderr
    assert "FAIL  trajectory.max_abs_error" in out.stdout


def test_cli_does_not_import_mujoco_until_needed():
    code = "import sys, urdf2links.cli; sys.exit(1 if 'mujoco' in sys.modules or 'urdf2links.compare' in sys.modules else 0)"
    assert subprocess.run([sys.executable, "-c", code], cwd=ROOT).returncode == 0


def test_report_caps_driven_scenes():
    from urdf2links.compare.commands import report_t_end
    from urdf2links.scenes.scene_read import load_scene

    crane = load_scene(ROBOTS / "ship_crane.toml")
    T, note = report_t_end(crane, t_end=None, cap=5.0)
    assert T == 5.0 and "capped" in note and "20" in note
    pend = load_scene(ROBOTS / "double_pendulum_chaos.toml")
    assert report_t_end(pend, t_end=None, cap=5.0) == (10.0, None)  # undriven: the whole run
    assert report_t_end(crane, t_end=None, cap=0) == (20.0, None)


# --------------------------------------------------------------------------- real robots

import corpus  # noqa: E402


@corpus.needs_corpus
@pytest.mark.parametrize("name", ["ur5", "panda", "talos", "g1"])
def test_real_robot_reports(name, tmp_path):
    """UR5, Panda, Talos, G1 of example-robot-data falling for 0.2 s: a report is written and the
    terms agree with MuJoCo to 1e-9 on both routes (route 2 repaired where MuJoCo refuses); the
    report animates the robot's meshes in both engines within the 5 MB budget."""
    scene = tmp_path / f"{name}_falling.toml"
    scene.write_text(f'[robot]\nexample_robot_data = "{corpus.NAMED[name]}"\ninertia = "repair"\n'
                     f'[gravity]\nmagnitude = 9.81\n[run]\nt_end = 0.2\nrtol = 1e-10\nsamples = 21\n')
    c = compare_scene(scene, mujoco_integrator="RK4", mujoco_dt=1e-4, states=4, progress=False)
    summary = json_ready(c.summary())
    assert dig(summary, "terms.max_rel_error") < 1e-9
    # 0.2 s from rest: both integrators are far below 1e-6 rad apart
    assert dig(summary, "trajectory.max_abs_error") < 1e-6
    write_report(c, tmp_path / "report")
    page_path = tmp_path / "report" / "report.html"
    assert 10_000 < page_path.stat().st_size < 5_000_000  # the budget: 5 MB with the animation and its meshes
    assert json.loads((tmp_path / "report" / "summary.json").read_text())["terms"]["max_rel_error"] < 1e-9
    from urdf2links.view.animation import read_animation_data

    page = page_path.read_text()
    assert_offline(page)
    data = read_animation_data(page)  # the robot's meshes, both engines
    assert [r["name"] for r in data["runs"]] == ["urdf2links", "MuJoCo"]
    assert set(data["links"]) == set(c.model.info["frame_of"])
    assert sum(sh["kind"] == "mesh" for sh in data["shapes"]) >= 6

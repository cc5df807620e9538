"""The commands of two descriptions (issue 25): ``compare A --against B`` writes the usual report with the two
descriptions first and both robots animated; ``report --pairs`` writes a page per pair and an index, and exits 1
when a pair differs past its tolerances; the motion of a faithful pair does not diverge."""

from __future__ import annotations

import json
import re

import mujoco
import numpy as np
import pytest

from urdf2links.cli import main
from urdf2links.compare.pairs.motion import run_pair_motion
from urdf2links.compare.pairs.mujoco_import import save_mujoco_import
from urdf2links.compare.pairs.pair import compare_descriptions_of
from urdf2links.locations import shipped_robots_dir
from urdf2links.view.animation import read_animation_data

ROBOTS = shipped_robots_dir()


@pytest.fixture(scope="module")
def faithful(tmp_path_factory):
    folder = tmp_path_factory.mktemp("pairs_cmd")
    return save_mujoco_import(ROBOTS / "ur5_like.urdf", folder / "ur5_mujoco.xml", keep_frames=True).path


@pytest.fixture(scope="module")
def heavier(faithful):
    spec = mujoco.MjSpec.from_file(str(faithful))
    spec.body("forearm_link").mass *= 1.5
    out = faithful.parent / "ur5_heavier.xml"
    out.write_text(spec.to_xml())
    return out


def test_compare_against_writes_the_usual_report_with_the_descriptions_first(tmp_path, capsys):
    out = tmp_path / "r"
    code = main(["compare", "ur5_like", "--against", "ur5_like_mujoco", "--t-end", "0.1", "--out", str(out),
                 "--animation-fps", "20", "--quiet"])
    assert code == 0
    s = json.loads((out / "summary.json").read_text())
    for key in ("joint_mapping", "description_differences", "description_effects", "description_motion", "terms",
                "trajectory"):
        assert key in s, key
    assert s["joint_mapping"]["mapped_fraction"] == 1.0
    assert {d["kind"] for d in s["description_differences"]} == {"armature"}
    page = (out / "report.html").read_text()
    # the two descriptions come before the usual sections (terms, trajectories)
    assert page.index("Two descriptions") < page.index("The two descriptions in motion") < page.index("1. Terms")
    data = read_animation_data(page)         # the first animation on the page: both robots
    assert len(data["runs"]) == 2 and any(link.startswith("1:") for link in data["links"])
    runs_of = {tuple(s_["runs"]) for s_ in data["shapes"]}
    assert runs_of == {(0,), (1,)}           # each robot drawn by its own run only
    assert "armature" in capsys.readouterr().out


def test_compare_against_refuses_what_it_cannot_do(tmp_path, capsys):
    assert main(["compare", "ur5_like", "--against", "ur5_like_mujoco", "--map", "elbow_joint=nope", "--t-end",
                 "0.05", "--out", str(tmp_path), "--quiet"]) == 2
    assert "no moving joint 'nope'" in capsys.readouterr().err
    assert main(["compare", "ur5_like", "--map", "a=b", "--t-end", "0.05", "--out", str(tmp_path)]) == 2
    assert "--against" in capsys.readouterr().err


def _pairs_file(tmp_path, faithful, heavier, *, extra="") -> str:
    p = tmp_path / "pairs.toml"
    p.write_text(f'''
[defaults]
t_end = 0.05
tolerances = {{ armature = 0.1 }}

[[pair]]
name = "faithful"
urdf = "{ROBOTS / 'ur5_like.urdf'}"
mjcf = "{faithful}"

[[pair]]
name = "heavier"
urdf = "{ROBOTS / 'ur5_like.urdf'}"
mjcf = "{heavier}"
tolerances = {{ mass = 0.1 }}
{extra}''')
    return str(p)


def test_report_pairs_exits_1_on_a_pair_past_its_tolerance(tmp_path, faithful, heavier, capsys):
    out = tmp_path / "out"
    code = main(["report", "--pairs", _pairs_file(tmp_path, faithful, heavier), "--out", str(out),
                 "--animation-fps", "0", "--quiet"])
    assert code == 1
    index = (out / "index.md").read_text()
    assert re.search(r"\| \[faithful\].*\| pass \|", index) and re.search(r"\| \[heavier\].*FAIL: mass", index)
    for name in ("faithful", "heavier"):
        assert (out / name / "report.html").is_file() and (out / name / "summary.json").is_file()
    assert "pair heavier differs past its tolerances" in capsys.readouterr().err


def test_report_pairs_passes_when_the_tolerances_allow_it(tmp_path, faithful, heavier):
    path = _pairs_file(tmp_path, faithful, heavier)
    text = open(path).read().replace("mass = 0.1", "mass = 0.5")
    open(path, "w").write(text)
    assert main(["report", "--pairs", path, "--out", str(tmp_path / "o"), "--animation-fps", "0", "--quiet"]) == 0


def test_report_pairs_refuses_a_bad_file_by_name(tmp_path, faithful, heavier, capsys):
    path = _pairs_file(tmp_path, faithful, heavier, extra='wobble = 3\n')
    assert main(["report", "--pairs", path, "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "[[pair]] #2" in err and "wobble" in err
    bad = tmp_path / "bad.toml"
    bad.write_text('[[pair]]\nurdf = "x.urdf"\nmjcf = "y.xml"\n')
    assert main(["report", "--pairs", str(bad)]) == 2
    assert "urdf = 'x.urdf': no such file" in capsys.readouterr().err


def test_the_motion_of_a_faithful_pair_does_not_diverge_and_a_heavier_one_does(faithful, heavier):
    """Both engines run both files: a faithful conversion stays together (its 6 written digits aside), each file's
    two engines agree, and a 50 % heavier forearm moves the descriptions apart."""
    urdf = ROBOTS / "ur5_like.urdf"
    pm = run_pair_motion(compare_descriptions_of(urdf, faithful), t_end=0.2)
    s = pm.summary()
    # 6 significant digits in the written file: the two differ by ~1e-6 relative, the arm falls for 0.2 s
    assert s["project"]["max_divergence"] < 1e-4 and s["mujoco"]["max_divergence"] < 1e-4
    assert max(s["engines_max_abs_difference"].values()) < 1e-6
    pm = run_pair_motion(compare_descriptions_of(urdf, heavier), t_end=0.2)
    s = pm.summary()
    assert s["project"]["max_divergence"] > 1e-2 and s["project"]["divergence_time"] is not None
    assert s["mujoco"]["max_divergence"] == pytest.approx(s["project"]["max_divergence"], rel=1e-3)
    assert np.all(np.isfinite(pm.div_project))


def test_the_motion_of_a_pair_with_a_negated_axis_is_mapped(faithful):
    """The elbow's axis negated in the MJCF: from a random state mapped with the sign, both files move alike in
    mapped coordinates (the initial state, the divergence and MuJoCo's run all go through the map)."""
    spec = mujoco.MjSpec.from_file(str(faithful))
    spec.joint("elbow_joint").axis = -np.asarray(spec.joint("elbow_joint").axis)
    out = faithful.parent / "ur5_negated.xml"
    out.write_text(spec.to_xml())
    pm = run_pair_motion(compare_descriptions_of(ROBOTS / "ur5_like.urdf", out), q0="random", seed=3, t_end=0.2)
    s = pm.summary()
    assert abs(s["initial_q"]["elbow_joint"]) > 0.05          # a state where the sign matters
    assert s["project"]["max_divergence"] < 1e-4 and s["mujoco"]["max_divergence"] < 1e-4
    assert np.allclose(pm.q_mjcf[:, 2], -pm.q_urdf[:, 2], atol=1e-4)

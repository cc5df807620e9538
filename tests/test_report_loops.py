"""The constrained scenes in ``urdf2links report`` (issue 42): robots/loops/*.toml is run by default, the hard case
that stops by design (its ``[expect]``, urdf2links/scenes/expect.py) is listed in the index as such, with its
message, and is not a failure; a stop with another message, or a run that no longer stops, is one."""

from __future__ import annotations

import re

import pytest
from cli_runner import run_cli

from urdf2links.errors import SceneError
from urdf2links.locations import report_scene_files, report_scenes, shipped_robots_dir
from urdf2links.scenes.scene_read import load_scene, scene_from_dict
from urdf2links.scenes.scene_toml import write_scene

LOOPS = shipped_robots_dir() / "loops"
CHANGE_POINT = LOOPS / "closed_leg_change_point.toml"


def test_report_runs_the_loops_by_default():
    """``report``'s scenes (in this checkout, and installed) hold every robots/loops/*.toml."""
    files, where = report_scenes()
    loops = sorted(LOOPS.glob("*.toml"))
    assert len(loops) >= 5 and all(p.resolve() in {f.resolve() for f in files} for p in loops), where
    assert {p.name for p in loops} <= {p.name for p in report_scene_files(shipped_robots_dir())}


def _planted(tmp_path, name, text):
    """A copy of the change point's scene (its robot by absolute path) with ``text`` edited in."""
    src = CHANGE_POINT.read_text().replace('mjcf = "closed_leg.xml"', f'mjcf = "{LOOPS / "closed_leg.xml"}"')
    path = tmp_path / f"{name}.toml"
    path.write_text(text(src))
    return path


def test_a_hard_case_that_stops_by_design_is_listed_and_does_not_fail(tmp_path):
    """The shipped change point: exit 0, the index lists it under its own heading with the error and its message
    (the row that lost its independence). Beside it two planted copies, each of which must fail the run: one whose
    [expect] names other words (another stop is not this one), one thrown slower (5 rad/s: it passes near the
    change point, test_change_point_hard_case) over its own t_end of 0.15 s, so that it no longer stops."""
    ok = run_cli("report", CHANGE_POINT, "--out", tmp_path / "ok", "--states", "1", "--animation-fps", "0",
                 "--quiet", cwd=tmp_path)
    assert ok.returncode == 0, ok.stderr
    assert "1 hard case(s) stopped by design" in ok.stdout
    md = (tmp_path / "ok" / "index.md").read_text()
    section = md.split("## Hard cases that stop by design", 1)[1]
    row = next(line for line in section.splitlines() if "closed_leg_change_point" in line)
    assert "DynamicsError" in row and "knee_loop.x are not independent" in row
    t = float(re.search(r"t = ([0-9.e+-]+) s", row).group(1))      # the stop's time, parsed: before the 1 s asked
    assert 0.0 < t < 1.0
    assert "Hard cases that stop by design" in (tmp_path / "ok" / "index.html").read_text()

    other = _planted(tmp_path, "other_words", lambda s: s.replace('message = "knee_loop.x are not independent"',
                                                                  'message = "a stop of another kind"'))
    slower = _planted(tmp_path, "slower", lambda s: s.replace("qd = { hip = 6.0, rod_hip = 6.0, knee = -6.0, ankle = -3.0 }",
                                                              "qd = { hip = 5.0, rod_hip = 5.0, knee = -5.0, ankle = -2.5 }")
                      .replace("t_end = 1.0", "t_end = 0.15"))
    bad = run_cli("report", other, slower, "--out", tmp_path / "bad", "--states", "1", "--animation-fps", "0",
                  "--quiet", cwd=tmp_path)
    assert bad.returncode == 1
    failed = [line for line in bad.stderr.splitlines() if line.startswith("urdf2links report: scene failed")]
    assert len(failed) == 2, bad.stderr
    assert "other_words.toml" in failed[0] and "knee_loop.x are not independent" in failed[0]
    assert "slower.toml" in failed[1] and "without stopping" in failed[1]
    assert "Hard cases that stop by design" not in (tmp_path / "bad" / "index.md").read_text()


def test_expect_is_checked_and_written_back(tmp_path):
    """[expect] names an error of urdf2links.errors and non-empty words (a SceneError naming the key otherwise);
    --write-scene keeps it."""
    scene = load_scene(CHANGE_POINT)
    again = load_scene(write_scene(scene, tmp_path / "again.toml"))
    assert again.expected_stop == scene.expected_stop and scene.expected_stop.error == "DynamicsError"
    base = {"robot": {"mjcf": str(LOOPS / "closed_leg.xml")}}
    with pytest.raises(SceneError, match=r"expect\.stop.*DynamicsError.*got 'ValueError'"):
        scene_from_dict({**base, "expect": {"stop": "ValueError", "message": "x"}})
    with pytest.raises(SceneError, match=r"expect\.message.*non-empty"):
        scene_from_dict({**base, "expect": {"stop": "DynamicsError", "message": " "}})
    with pytest.raises(SceneError, match=r"expect.*unknown key"):
        scene_from_dict({**base, "expect": {"stop": "DynamicsError", "message": "x", "at": 0.07}})

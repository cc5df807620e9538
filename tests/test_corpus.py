"""A corpus against MuJoCo (issue 16): which files, each robot's row, the same figures whichever way it
ran (one process, worker processes, a Dask cluster), failures and baselines per robot, the report files.

A subset of example-robot-data, chosen to cover every kind of row: a file urdf2links refuses
(``ur3.urdf``: an empty ``<robot>``), robots MuJoCo reads as written on route 2 (the double pendulum,
the UR5), one it refuses on route 2 (``finger_edu``: route 2 compares the repaired text), and one whose
inertias MuJoCo refuses on route 1 (``romeo_laas_small``: both engines run the project's repair). Runs
are 0.1 s with terms at 2 states to keep the suite quick; the committed report (reports/corpus/) runs
every file for 0.5 s.
"""

from __future__ import annotations

import io
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest


from corpus import ROOT as CORPUS_ROOT, needs_corpus  # noqa: E402
from urdf2links.compare.reports.baselines import load_baselines, write_baselines  # noqa: E402
from urdf2links.compare.corpus.rows import (
    ROW_KEYS, RUN_DEPENDENT_KEYS, STATUSES, TERMS_TOLERANCE, CorpusSettings, evaluate_robot, find_robots,
)
from urdf2links.compare.corpus.command import regressions  # noqa: E402
from urdf2links.compare.corpus.report import worst_first, write_corpus  # noqa: E402
from urdf2links.compare.corpus.runner import run_corpus  # noqa: E402
from urdf2links.console import TaskBar  # noqa: E402
from urdf2links.locations import shipped_robots_dir  # noqa: E402

SUBSET = UR3, PENDULUM, UR5, FINGER, ROMEO = (
    "ur_description/urdf/ur3.urdf", "double_pendulum_description/urdf/double_pendulum.urdf",
    "ur_description/urdf/ur5_robot.urdf", "finger_edu_description/robots/finger_edu.urdf",
    "romeo_description/urdf/romeo_laas_small.urdf")
SETTINGS = CorpusSettings(t_end=0.1, states=2, thumbnails=False)


def subset_args() -> list[str]:
    return [str(CORPUS_ROOT / f) for f in SUBSET]


def figures(corpus_json: Path) -> list[dict]:
    """corpus.json's rows without what depends on the run (wall times, the worker)."""
    data = json.loads(corpus_json.read_text())
    return [{k: v for k, v in row.items() if k not in RUN_DEPENDENT_KEYS} for row in data["robots"]]


@pytest.fixture(scope="module")
def serial(tmp_path_factory):
    """The subset run one robot after the other in this process, and its report."""
    robots = find_robots(subset_args())
    results = run_corpus(robots, SETTINGS, jobs=1)
    out = tmp_path_factory.mktemp("serial")
    paths = write_corpus(results, out, settings=SETTINGS.describe(), run={"how": "in this process", "wall_s": 0.0})
    return {"robots": robots, "results": results, "rows": {r.row["file"]: r.row for r in results}, "paths": paths}


# --------------------------------------------------------------------------- which files


def _robot(folder: Path, name: str) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    shutil.copy(shipped_robots_dir() / "double_pendulum.urdf", folder / name)
    return folder / name


def test_find_robots_folders_files_and_patterns(tmp_path):
    a = _robot(tmp_path / "fleet" / "arms", "left.urdf")
    _robot(tmp_path / "fleet" / "arms", "right.urdf.xacro")
    _robot(tmp_path / "fleet", "notes.txt")
    other = _robot(tmp_path / "other" / "arms", "left.urdf")
    ids = [r.id for r in find_robots([tmp_path / "fleet"])]
    assert ids == ["arms/left.urdf", "arms/right.urdf.xacro"]          # .urdf and .xacro, sorted, relative
    # two folders: paths relative to the folder that holds both
    assert [r.id for r in find_robots([tmp_path / "fleet", tmp_path / "other"])] == [
        "fleet/arms/left.urdf", "fleet/arms/right.urdf.xacro", "other/arms/left.urdf"]
    assert [r.id for r in find_robots([str(tmp_path / "*" / "arms" / "left.urdf")])] == [
        "fleet/arms/left.urdf", "other/arms/left.urdf"]
    assert [r.id for r in find_robots([a, a])] == ["left.urdf"]           # a file by itself: its name, once
    assert find_robots([other])[0].path == str(other.resolve())
    with pytest.raises(FileNotFoundError, match="no such folder or file"):
        find_robots([tmp_path / "nowhere"])
    (tmp_path / "empty").mkdir()
    with pytest.raises(ValueError, match="no .urdf, .xacro or MJCF .xml"):
        find_robots([tmp_path / "empty"])


@needs_corpus
def test_example_robot_data_by_name(monkeypatch, tmp_path):
    """`--corpus example-robot-data` is the installed corpus, ids relative to its robots folder."""
    monkeypatch.chdir(tmp_path)
    robots = find_robots(["example-robot-data"])
    assert len(robots) >= 69 and set(SUBSET) <= {r.id for r in robots}


# --------------------------------------------------------------------------- rows


@needs_corpus
def test_rows_say_what_happened(serial):
    rows = serial["rows"]
    assert set(rows) == set(SUBSET)       # files given one by one: named relative to the folder holding them all
    for row in rows.values():
        for key in ROW_KEYS:
            head, _, tail = key.partition(".")
            assert head in row and (not tail or tail in row[head]), f"{row['file']}: no {key}"
        assert row["status"] in STATUSES
    refused = rows[UR3]
    assert refused["status"] == "refused" and "no <link> elements" in refused["reason"]
    assert refused["stage"] == "import" and refused["report"] is None
    assert refused["reason"].startswith(UR3)   # the file named by its id, not by a machine's path
    for name in (PENDULUM, UR5, FINGER, ROMEO):
        row = rows[name]
        assert row["status"] == "compared", row["reason"]
        # route 1 is the project's tree through MuJoCo: rounding only (done-when: 1e-9)
        assert row["terms"]["route1"] <= TERMS_TOLERANCE
        assert row["terms"]["route2"] <= TERMS_TOLERANCE
        # 0.1 s of a non-chaotic start from rest: both integrators' errors, far below the threshold
        assert row["trajectory"]["max_abs_error"] < 1e-6 and row["trajectory"]["divergence_time"] is None
        assert row["n"] > 0 and row["report"] == f"{name}/report.html"
    assert rows[UR5]["terms"]["route2_status"] == "as written"
    assert rows[FINGER]["terms"]["route2_status"] == "repaired"
    assert rows[FINGER]["terms"]["route2_reason"]
    romeo = rows[ROMEO]
    assert romeo["inertia"] == "repair" and "MuJoCo refuses the file's inertias on route 1" in romeo["reason"]
    assert romeo["import"]["audit"] and romeo["import"]["repairs"]


@needs_corpus
def test_a_robot_that_fails_does_not_stop_the_others(monkeypatch, tmp_path, capsys):
    """A fault of ours (here injected into the comparison of one robot) is a failed row naming the
    stage and the exception; the other robots are compared; the command exits 1 naming the robot."""
    import urdf2links.compare.agreement.trajectory as trajectory
    from urdf2links.cli import main

    real = trajectory.compare_scene

    def broken_for_ur5(scene, **kw):
        if Path(scene.robot).name == "ur5_robot.urdf":
            raise RuntimeError("injected fault")
        return real(scene, **kw)

    monkeypatch.setattr(trajectory, "compare_scene", broken_for_ur5)
    args = [str(CORPUS_ROOT / SUBSET[1]), str(CORPUS_ROOT / SUBSET[2])]
    code = main(["report", "--corpus", *args, "--jobs", "1", "--t-end", "0.05", "--states", "1", "--out",
                 str(tmp_path), "--quiet", "--no-thumbnails"])
    assert code == 1
    assert f"{UR5} failed at comparison: comparison: RuntimeError: injected fault" in capsys.readouterr().err
    rows = {r["file"]: r for r in json.loads((tmp_path / "corpus.json").read_text())["robots"]}
    assert rows[UR5]["status"] == "failed" and "Traceback" in rows[UR5]["traceback"]
    assert rows[PENDULUM]["status"] == "compared"


# --------------------------------------------------------------------------- same figures, three ways


@needs_corpus
def test_processes_and_dask_give_the_serial_figures(serial, dask_client, tmp_path):
    """The done-when test: corpus.json's figures are the same whether the robots ran here one by one,
    in two worker processes (`--jobs 2`, through the command line) or on a two-worker LocalCluster
    (timings and the worker's name aside). Equality is exact: every robot's run is seeded and
    deterministic, only where it runs changes."""
    jobs = subprocess.run([sys.executable, "-m", "urdf2links.cli", "report", "--corpus", *subset_args(), "--jobs", "2",
                           "--t-end", "0.1", "--states", "2", "--no-thumbnails", "--out", str(tmp_path / "jobs")],
                          capture_output=True, text=True)
    assert jobs.returncode == 0, jobs.stderr[-3000:]
    assert jobs.stderr.count("[") >= len(SUBSET) and "[5/5]" in jobs.stderr       # one line per robot
    results = run_corpus(serial["robots"], SETTINGS, client=dask_client)
    dask_paths = write_corpus(results, tmp_path / "dask", settings=SETTINGS.describe(), run={"how": "dask"})
    reference = figures(serial["paths"]["json"])
    assert figures(tmp_path / "jobs" / "corpus.json") == reference
    assert figures(dask_paths["json"]) == reference
    here = f":{os.getpid()}"
    assert not any(r.row["worker"].endswith(here) for r in results)   # they did run on the cluster's workers


@needs_corpus
def test_kernels_are_not_compiled_again_for_each_robot(serial):
    """Every robot runs the same compiled functions: after the subset, evaluating other robots (of
    other sizes and shapes) adds no numba specialization, so a worker loads the kernels once and
    never compiles per robot."""
    from numba.core.registry import CPUDispatcher

    def signatures():
        return {f"{m}.{k}": len(v.signatures) for m, mod in list(sys.modules.items()) if m.startswith("urdf2links")
                for k, v in vars(mod).items() if isinstance(v, CPUDispatcher)}

    before = signatures()
    for f in ("ur_description/urdf/ur3_robot.urdf", "z1_description/urdf/z1.urdf"):
        row = evaluate_robot(find_robots([CORPUS_ROOT / f])[0], CorpusSettings(t_end=0.05, states=1, pages=False)).row
        assert row["status"] == "compared"
    after = signatures()
    assert {k: v for k, v in after.items() if before.get(k) != v} == {}


# --------------------------------------------------------------------------- baselines


@needs_corpus
def test_baselines_per_robot(serial, tmp_path):
    """Accepted figures per robot (key: its file); a figure that grows, or an accepted robot that is
    no longer compared, is a regression naming the robot."""
    accepted = [r.summary for r in serial["results"] if r.summary is not None]
    path = write_baselines(accepted, tmp_path / "baselines.json")
    base = load_baselines(path)
    assert set(base["scenes"]) == {PENDULUM, UR5, FINGER, ROMEO}
    ur5 = next(r for r in serial["robots"] if r.id == UR5)
    ok = evaluate_robot(ur5, CorpusSettings(t_end=0.1, states=2, pages=False, baselines=base))
    assert ok.row["check"]["ok"] is True and regressions([ok], base) == []
    shrunk = json.loads(json.dumps(base))
    for run in shrunk["scenes"][UR5]["runs"]:
        run["figures"]["trajectory.max_abs_error"] = 1e-20   # the accepted difference made 1e8 times smaller
    bad = evaluate_robot(ur5, CorpusSettings(t_end=0.1, states=2, pages=False, baselines=shrunk))
    assert bad.row["check"]["ok"] is False and "trajectory.max_abs_error" in bad.row["check"]["failures"]
    assert regressions([bad], shrunk) == [f"{UR5}: trajectory.max_abs_error grew past the baseline"]
    shrunk["scenes"][UR3] = shrunk["scenes"][UR5]   # as if ur3 had once been compared
    refused = next(r for r in serial["results"] if r.row["file"] == UR3)
    assert regressions([refused], shrunk)[0].startswith(f"{UR3}: accepted as compared, now refused")


# --------------------------------------------------------------------------- the report


@needs_corpus
def test_report_files(serial):
    paths, rows = serial["paths"], serial["rows"]
    data = json.loads(paths["json"].read_text())
    assert data["counts"] == {"robots": 5, "failed": 0, "compared": 4, "refused": 1}
    assert data["route1_within_tolerance"] and data["settings"]["t_end"] == 0.1
    page = paths["dir"] / UR5 / "report.html"
    text = page.read_text()
    assert "href='../../../index.html'" in text and "Inertia audit" in text and "data:image/png;base64," in text
    assert len(text) < 150_000          # the light page: one small figure instead of four
    assert (paths["dir"] / UR5 / "summary.json").is_file() and paths["png"].is_file()
    index = paths["html"].read_text()
    for name, row in rows.items():
        assert (f"href='{row['report']}'" in index) == (row["report"] is not None)
    assert "<script>" in index and "sortBy" in index and "http" not in index.split("<script>")[1]  # offline
    order = [r["file"] for r in worst_first(list(rows.values()))]
    assert order[-1] == UR3      # refused rows last; failed first; compared by their worst ratio
    worst = [rows[f]["worst"] for f in order[:-1]]
    assert worst == sorted(worst, reverse=True)
    md = paths["md"].read_text()
    assert all(name in md for name in rows) and "| robot | status |" in md


def test_task_bar_prints_lines_without_a_terminal():
    stream = io.StringIO()
    bar = TaskBar(2, label="corpus", stream=stream)
    bar.line("[1/2] a: compared")
    bar.line("warming", advance=False)
    bar.line("[2/2] b: refused")
    bar.close()
    assert stream.getvalue() == "[1/2] a: compared\nwarming\n[2/2] b: refused\n" and bar.done == 2


def test_urdf2links_imports_neither_dask_nor_mujoco():
    code = ("import sys, urdf2links, urdf2links.integration.batch, urdf2links.integration.distributed, urdf2links.cli; "
            "bad = {'dask', 'distributed', 'mujoco'} & set(sys.modules); assert not bad, bad")
    subprocess.run([sys.executable, "-c", code], check=True)


@needs_corpus
def test_thumbnail_beside_each_robot(tmp_path):
    """Each compared robot's picture (urdf2links.view.thumbnail) is in its folder, on its page and in the
    index, linked to the page."""
    robot = find_robots([CORPUS_ROOT / PENDULUM])[0]
    res = evaluate_robot(robot, CorpusSettings(t_end=0.05, states=1))
    assert res.files["thumbnail.png"][:8] == b"\x89PNG\r\n\x1a\n" and res.row["thumbnail"] == "double_pendulum.urdf/thumbnail.png"
    assert "src='thumbnail.png'" in res.files["report.html"]
    paths = write_corpus([res], tmp_path, settings={**SETTINGS.describe(), "t_end": 0.05}, run={"how": "here"})
    index = paths["html"].read_text()
    assert ("<a href='double_pendulum.urdf/report.html'><img class='thumb' alt='' "
            "src='double_pendulum.urdf/thumbnail.png'></a>") in index
    assert (tmp_path / "double_pendulum.urdf" / "thumbnail.png").is_file()


# --------------------------------------------------------------------------- a worker dies

KILLER = Path(__file__).resolve().parent / "worker_killer.py"
FLEET_ARGS = ["--t-end", "0.05", "--states", "1", "--no-thumbnails"]


def _fleet(folder: Path, *names: str) -> Path:
    """Copies of the shipped double pendulum named ``names`` (tests/worker_killer.py acts on the names)."""
    for name in names:
        _robot(folder, f"{name}.urdf")
    return folder


def _rows(out: Path) -> dict:
    return {r["file"]: r for r in json.loads((out / "corpus.json").read_text())["robots"]}


def test_a_robot_whose_worker_process_dies_is_a_failed_row(tmp_path):
    """docs/corpus.md: a robot whose worker dies is reported as failed and the report completes. Two
    worker processes (`--jobs 2`); ``die_once`` kills its worker the first time it runs, ``kill_me``
    every time (SIGKILL, tests/worker_killer.py). The robots the dead pool had not finished run again
    one at a time: ``die_once`` is then compared, ``kill_me`` kills its lone worker again and is a
    failed row saying so; the others are compared, the report is written, the exit status is 1."""
    fleet = _fleet(tmp_path / "fleet", "a", "die_once", "kill_me", "z")
    out = tmp_path / "out"
    run = subprocess.run([sys.executable, str(KILLER), "report", "--corpus", str(fleet), "--jobs", "2", *FLEET_ARGS,
                          "--out", str(out)], capture_output=True, text=True, timeout=900)
    assert run.returncode == 1, run.stderr[-3000:]
    assert "a worker process died; running its" in run.stderr
    rows = _rows(out)
    assert {f: r["status"] for f, r in rows.items()} == {
        "a.urdf": "compared", "die_once.urdf": "compared", "kill_me.urdf": "failed", "z.urdf": "compared"}
    assert rows["kill_me.urdf"]["stage"] == "worker"
    assert "worker process died while running this robot, alone" in rows["kill_me.urdf"]["reason"]
    assert (tmp_path / "fleet" / "die_once.urdf.died").is_file()     # it did kill a worker once
    assert (out / "index.html").is_file() and "kill_me.urdf" in (out / "corpus.md").read_text()
    assert "kill_me.urdf failed at worker" in run.stderr


def test_a_robot_whose_dask_worker_dies_is_a_failed_row(tmp_path):
    """The same on a Dask cluster (`--scheduler ADDRESS`): a two-worker LocalCluster whose workers run
    tests/worker_killer.py at start (its nanny restarts a killed worker, which runs it again). Dask
    retries a task whose worker died (here once: ``allowed-failures`` 1, to keep the test short);
    ``kill_me`` kills both tries and is a failed row naming KilledWorker; the others are compared, the
    report is written, the exit status is 1. ``worker-saturation`` 1.0 sends each worker one task at a
    time, so that a death blames only the robot that was running (Dask counts a death against every
    task the worker held)."""
    import logging

    import dask
    from dask.distributed import LocalCluster

    fleet = _fleet(tmp_path / "fleet", "a", "kill_me", "z")
    out = tmp_path / "out"
    logging.getLogger("distributed").setLevel(logging.CRITICAL)       # the deaths' tracebacks
    with dask.config.set({"distributed.scheduler.allowed-failures": 1, "distributed.scheduler.worker-saturation": 1.0}):
        # its HTTP server on a free port: the session's other cluster (conftest.dask_client) may hold 8787
        with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0",
                          preload=[str(KILLER)]) as cluster:
            run = subprocess.run([sys.executable, "-m", "urdf2links.cli", "report", "--corpus", str(fleet), "--scheduler",
                                  cluster.scheduler_address, *FLEET_ARGS, "--out", str(out)],
                                 capture_output=True, text=True, timeout=900)
    assert run.returncode == 1, run.stderr[-3000:]
    rows = _rows(out)
    assert {f: r["status"] for f, r in rows.items()} == {"a.urdf": "compared", "kill_me.urdf": "failed",
                                                         "z.urdf": "compared"}
    assert rows["kill_me.urdf"]["stage"] == "worker" and "KilledWorker" in rows["kill_me.urdf"]["reason"]
    assert (out / "index.html").is_file() and "kill_me.urdf failed at worker" in run.stderr

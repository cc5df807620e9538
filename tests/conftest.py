"""Figures measured by the tests, written as generated tables.

A test that measures a figure worth showing (a drift, a count of evaluations, a wall time) hands it to
the ``record_figure`` fixture instead of leaving it in a print or in prose::

    def test_something(record_figure):
        err = ...
        record_figure("1. long chains", "chain32 energy drift", err, "{:.1e}")
        assert err < 1e-8

``record_figure(case, name, value, fmt="{:.2g}")`` groups the figures by case; ``value`` may be a number
(formatted with ``fmt``) or a string. The bound of a case is taken from the test module's
``FIGURE_BOUNDS`` dict (case -> the bound as text), so that the table states what the figures are
checked against; its ``FIGURE_NOTE`` string, if any, is printed under the table.

Without ``--figures`` the fixture does nothing. With ``--figures DIR`` every test module that recorded
figures gets ``DIR/<module without test_>.json`` and ``.md`` (one row per case: case, bound,
measured, tests) at the end of the session, e.g.::

    python -m pytest tests/test_hard_cases.py --figures reports/hard_cases -m "slow or not slow"

writes reports/hard_cases/hard_cases.{json,md}. The files are rewritten from this session alone: run
the whole module. A case one of whose tests failed is marked so in the table.
"""

from __future__ import annotations

import json
import os
import platform
from pathlib import Path

# One BLAS thread per test process: the suite already runs one worker per core (pytest-xdist), and OpenBLAS's own
# threads on top of that made the numpy-heavy tests (the identification fits) twice as slow (measured: the 50-seed
# coverage test 130 s with the default, 65 s with one thread, beside a second worker). Set before the workers start,
# which inherit it, like every subprocess a test starts; a value the user chose stays.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import pytest
from hypothesis import settings

# Hypothesis profiles of the fuzz tests (tests/test_fuzz.py): "ci" (the default) is derandomized -- a
# fixed seed, the same examples on every run -- with a small budget; "slow" is the long run of issue 15
# (5000 URDF mutants, 1000 scene mutants, 1000 valid trees). Choose with HYPOTHESIS_PROFILE=slow or
# `pytest --hypothesis-profile slow`. No example database: a failure is replayed from its printed blob.
settings.register_profile("ci", max_examples=200, derandomize=True, database=None, deadline=None, print_blob=True)
settings.register_profile("slow", max_examples=5000, database=None, deadline=None, print_blob=True)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))

_FIGURES: dict[str, dict] = {}       # module stem -> {"bounds": {...}, "cases": {case: [...]}}
_FAILED: set[str] = set()            # node ids of tests that failed


def pytest_addoption(parser):
    parser.addoption("--figures", metavar="DIR", default=None,
                     help="write the figures the tests record (record_figure) to DIR/<module>.json and .md")


@pytest.fixture
def record_figure(request):
    """``record_figure(case, name, value, fmt="{:.2g}")``: keep a measured figure for --figures."""
    if request.config.getoption("--figures") is None:
        return lambda case, name, value, fmt="{:.2g}": None
    module = request.module
    stem = Path(module.__file__).stem.removeprefix("test_")
    entry = _FIGURES.setdefault(stem, {"bounds": dict(getattr(module, "FIGURE_BOUNDS", {})),
                                       "note": getattr(module, "FIGURE_NOTE", ""), "cases": {}})
    nodeid = request.node.nodeid

    def record(case: str, name: str, value, fmt: str = "{:.2g}"):
        text = value if isinstance(value, str) else fmt.format(value)
        raw = value if isinstance(value, str) else float(value)
        entry["cases"].setdefault(case, []).append({"name": name, "value": raw, "text": text, "test": nodeid})

    return record


#: What a skipped test or module says instead: the suite never skips (docs/testing.md, issue 42).
NEVER_SKIP = ("the suite never skips: a missing test dependency is a broken install (pip install -e \".[test]\" "
              "installs every one); fix the install, or make the test fail naming what it needs")


def _refuse_skip(report) -> None:
    """A skip (pytest.skip, importorskip, skipif, an xfail that ran) turned into a failure that says why."""
    if report.skipped:
        reason = report.longrepr[2] if isinstance(report.longrepr, tuple) else str(report.longrepr)
        report.outcome, report.longrepr = "failed", f"skipped or xfailed ({reason}): {NEVER_SKIP}"
        if hasattr(report, "wasxfail"):
            del report.wasxfail


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    outcome = yield
    report = outcome.get_result()
    _refuse_skip(report)
    if report.failed:
        _FAILED.add(item.nodeid)


@pytest.hookimpl(hookwrapper=True)
def pytest_make_collect_report(collector):
    """A module that skips at import (``pytest.importorskip`` at its top) fails its collection instead."""
    outcome = yield
    _refuse_skip(outcome.get_result())


def _command(config, stem):
    marks = config.getoption("markexpr")
    return (f"python -m pytest tests/test_{stem}.py --figures {config.getoption('--figures')}"
            + (f' -m "{marks}"' if marks else ""))


def pytest_sessionfinish(session, exitstatus):
    folder = session.config.getoption("--figures")
    if folder is None or not _FIGURES:
        return
    import numpy as np

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    for stem, entry in _FIGURES.items():
        rows = []
        for case in sorted(entry["cases"]):
            figures = entry["cases"][case]
            tests = sorted({f["test"] for f in figures})
            rows.append({"case": case, "bound": entry["bounds"].get(case, ""),
                         "failed": sorted(t for t in tests if t in _FAILED), "tests": tests,
                         "figures": [{k: f[k] for k in ("name", "value", "text", "test")} for f in figures]})
        command = _command(session.config, stem)
        meta = {"command": command, "machine": platform.platform(), "python": platform.python_version(),
                "numpy": np.__version__}
        try:
            import numba
            meta["numba"] = numba.__version__
        except ImportError:
            pass
        (folder / f"{stem}.json").write_text(json.dumps({**meta, "rows": rows}, indent=2) + "\n")
        lines = [f"# Figures measured by tests/test_{stem}.py", "",
                 f"Generated by `{command}` (the tests' own measurements, recorded with `record_figure`; "
                 "the bounds are the tests' constants). Machine: " + ", ".join(
                     f"{k} {v}" if k != "machine" else v for k, v in meta.items() if k != "command") + ".", "",
                 "| case | bound | measured | tests |", "|---|---|---|---|"]
        for row in rows:
            measured = "; ".join(f"{f['name']} {f['text']}" for f in row["figures"])
            if row["failed"]:
                measured = "**FAILED** (" + ", ".join(t.split("::")[-1] for t in row["failed"]) + "): " + measured
            names = dict.fromkeys(t.split("::")[-1].split("[")[0] for t in row["tests"])   # parametrizations once
            tests = ", ".join(f"`{t}`" for t in names)
            lines.append("| " + " | ".join(c.replace("|", "\\|") for c in (row["case"], row["bound"], measured))
                         + f" | {tests} |")
        if entry["note"]:
            lines += ["", entry["note"]]
        (folder / f"{stem}.md").write_text("\n".join(lines) + "\n")


@pytest.fixture(scope="module")
def mimic_arm(tmp_path_factory):
    """``(URDF, MJCF)``: ur5_like with wrist_3 mimicking wrist_2 (q3 = 2 q2 + 0.1), and MuJoCo's import of it (a
    joint equality); the pairs tests' coupled arm (tests/test_pairs_drifts.py, tests/test_pairs_reading.py)."""
    from urdf2links.compare.pairs.mujoco_import import save_mujoco_import
    from urdf2links.locations import shipped_robots_dir

    folder = tmp_path_factory.mktemp("mimic_arm")
    text = (shipped_robots_dir() / "ur5_like.urdf").read_text()
    head, tail = text.split('<joint name="wrist_3_joint"', 1)
    limit_end = tail.index("/>", tail.index("<limit")) + 2
    tail = tail[:limit_end] + '\n    <mimic joint="wrist_2_joint" multiplier="2" offset="0.1"/>' + tail[limit_end:]
    urdf = folder / "ur5_mimic.urdf"
    urdf.write_text(head + '<joint name="wrist_3_joint"' + tail)
    return urdf, save_mujoco_import(urdf, folder / "ur5_mimic.xml", keep_geometry=False, keep_frames=True).path


@pytest.fixture(scope="session")
def corpus_installed():
    """The example-robot-data corpus's folder; fails the test (tests/corpus.py ``needs_corpus``) when it
    is not installed: it is a test dependency, so missing means a broken install, never a skip."""
    import corpus

    if corpus.ROOT is None:
        pytest.fail(corpus.MISSING)
    return corpus.ROOT


@pytest.fixture(scope="session")
def dask_client():
    """A Dask client of a two-worker ``LocalCluster`` (one thread and one process each, as
    docs/corpus.md recommends), shared by the tests that compare a distributed run with the serial
    one (the test extra installs the distributed extra)."""
    import logging

    import dask.distributed as distributed

    logging.getLogger("distributed").setLevel(logging.ERROR)  # the nanny's shutdown chatter
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        with distributed.Client(cluster) as client:
            yield client

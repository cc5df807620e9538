"""The work-precision study (urdf2links.compare.tradeoff.study, `urdf2links tradeoff`).

One short study of the double pendulum (t_end 0.5 s, the --quick ladders, one timing round) is shared
by the module: reference and check, convergence orders of RK4 (both engines) and Euler, monotone
errors, the JSON contract, the files, the report section. The crossover is tested on synthetic rows.
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import mujoco  # noqa: F401,E402 -- a declared dependency: a broken MuJoCo fails the suite

from urdf2links.compare.tradeoff.study import MUJOCO_DTS, ROUNDING_BAND, _rounding_floor, crossover, run_study
from urdf2links.compare.tradeoff.report import write_study  # noqa: E402
from urdf2links.compare.tradeoff.report import BEGIN, END, insert_section, render_section  # noqa: E402
from urdf2links.cli import main  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
SCENE = ROOT / "robots" / "double_pendulum_chaos.toml"
ROW_KEYS = ("engine", "method", "param", "value", "status", "reason", "error_final", "error_max",
            "energy_drift_rel", "wall_time_s", "wall_time_min_s", "wall_time_max_s", "wall_times_s", "nfev", "nsteps")


@pytest.fixture(scope="module")
def study():
    return run_study(SCENE, t_end=0.5, quick=True, repeats=1, methods=("RK4", "DOP853", "midpoint"),
                     mujoco_integrators=("Euler", "RK4"))


def series(data, engine, method):
    rows = [r for r in data["rows"] if r["engine"] == engine and r["method"] == method]
    assert rows, f"no rows for {engine} {method}"
    return rows


def slope(rows, floor):
    """Least-squares slope of log(final error) against log(dt), over the runs whose error is well
    above the reference's error estimate (10x: below that the reference's own error matters)."""
    pts = [(r["value"], r["error_final"]) for r in rows if r["status"] == "ok" and r["error_final"] > 10 * floor]
    assert len(pts) >= 3, f"too few resolved points for a slope: {pts}"
    x, y = np.log([p[0] for p in pts]), np.log([p[1] for p in pts])
    return float(np.polyfit(x, y, 1)[0])


def test_reference_error_estimate_is_small(study):
    ref = study["reference"]
    assert ref["method"] == "DOP853" and ref["rtol"] == 1e-13
    assert ref["check"]["method"] == "DOP853" and ref["check"]["rtol"] == 1e-12  # --quick's check run
    # DOP853 at rtol 1e-12 / 1e-13 over 0.5 s: differences ~1e-12; 1e-9 leaves room for a slower
    # machine's different step sequence, and fails if the check or the reference went wrong
    assert 0.0 <= ref["error_estimate"] < 1e-9
    assert ref["error_estimate_final"] <= ref["error_estimate"]
    assert study["error"]["floor"] == ref["error_estimate"]


def test_errors_decrease_as_tolerances_tighten(study):
    floor = study["reference"]["error_estimate"]
    for (engine, method) in {(r["engine"], r["method"]) for r in study["rows"]}:
        rows = [r for r in series(study, engine, method) if r["status"] == "ok"]
        assert len(rows) >= 3, f"{engine} {method}: runs failed or were skipped: {series(study, engine, method)}"
        errs = [max(r["error_max"], floor) for r in rows]
        # adaptive error control is not strictly monotone; each rung tightens by 100x (rtol) or
        # 2x (dt), so a factor 3 of slack only forgives jitter, and the ladder must gain 3x overall
        for a, b in zip(errs, errs[1:]):
            assert b <= 3.0 * a, f"{engine} {method}: error grew from {a:.2e} to {b:.2e}: {errs}"
        assert errs[-1] < errs[0] / 3.0, f"{engine} {method}: no convergence {errs}"


def test_rk4_is_fourth_order_in_both_engines(study):
    floor = study["reference"]["error_estimate"]
    for engine in ("urdf2links", "MuJoCo"):
        p = slope(series(study, engine, "RK4"), floor)
        # classic RK4: global error ~ dt^4; 3.5..4.5 allows for pre-asymptotic terms at the coarsest step
        assert 3.5 <= p <= 4.5, f"{engine} RK4: error ~ dt^{p:.2f}"


def test_euler_is_first_order_and_midpoint_second(study):
    floor = study["reference"]["error_estimate"]
    p = slope(series(study, "MuJoCo", "Euler"), floor)
    assert 0.8 <= p <= 1.2, f"MuJoCo Euler: error ~ dt^{p:.2f}"  # first order, +-0.2 as for RK4
    p = slope(series(study, "urdf2links", "midpoint"), floor)
    assert 1.7 <= p <= 2.3, f"implicit midpoint: error ~ dt^{p:.2f}"  # second order


def test_rows_have_costs_and_timing(study):
    assert study["timing"]["repeats"] == 1 and study["timing"]["statistic"] == "median"
    for r in study["rows"]:
        assert set(ROW_KEYS) <= set(r)
        assert r["status"] == "ok", r
        assert r["wall_time_s"] > 0 and len(r["wall_times_s"]) == 1
        assert r["wall_time_min_s"] == r["wall_time_s"] == r["wall_time_max_s"]  # one round: no spread
        assert r["nfev"] >= r["nsteps"] > 0
        if r["engine"] == "MuJoCo":
            stages = {"Euler": 1, "RK4": 4}[r["method"]]
            assert r["nfev"] == stages * r["nsteps"] == stages * round(0.5 / r["value"])
        assert 0.0 <= r["energy_drift_rel"] < 1.0
        assert r["error_final"] <= r["error_max"] + 1e-15


def test_files_json_contract_and_report_section(study, tmp_path):
    report = tmp_path / "report.html"
    report.write_text("<html><body><h1>x</h1><p class='small'>Figures: ...</p></body></html>")
    paths = write_study(study, tmp_path, command="urdf2links tradeoff x --quick")
    data = json.loads(paths["json"].read_text())
    for key in ("reference", "rows", "crossover", "timing", "machine", "error", "energy", "t_end", "key", "budget_s"):
        assert key in data
    assert "statement" in data["crossover"] and "error_level" in data["crossover"]
    assert {"platform", "python", "numpy", "mujoco", "cpu_count"} <= set(data["machine"])
    for name in ("work_precision.png", "energy_drift.png"):
        assert (tmp_path / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    md = paths["md"].read_text()
    assert "Crossover" in md and md.count("\n| ") >= len(study["rows"]) + 1
    # the section went in before the footer, once; writing again replaces it
    assert paths["report"] == report
    write_study(study, tmp_path)
    text = report.read_text()
    assert text.count(BEGIN) == 1 and text.count(END) == 1
    assert text.index(END) < text.index("<p class='small'>Figures: ...")
    assert "data:image/png;base64," in text and "Crossover" in text


def synthetic(project, mujoco):
    """Rows from ((error, seconds), ...) per engine."""
    rows = []
    for engine, pts in (("urdf2links", project), ("MuJoCo", mujoco)):
        for i, (err, s) in enumerate(pts):
            rows.append({"engine": engine, "method": "RK4", "param": "dt", "value": 10.0 ** -i, "status": "ok",
                         "error_max": err, "wall_time_s": s})
    return rows


def test_crossover_where_the_project_wins_tight_accuracy():
    # MuJoCo: cheap and coarse; urdf2links: dearer at 1e-4, cheaper from 1e-8 down
    rows = synthetic([(1e-4, 1.0), (1e-8, 2.0), (1e-11, 3.0)], [(1e-4, 0.1), (1e-8, 5.0), (1e-10, 50.0)])
    c = crossover(rows)
    # grid of 4 levels per decade from 1e-10 (the tightest both reach): the project is faster up to
    # 10**-4.25 (its 1e-8 run, 2 s, against MuJoCo's 5 s); at 1e-4 MuJoCo's 0.1 s run wins
    assert c["error_level"] == pytest.approx(10 ** -4.25)
    assert c["region"][0] == pytest.approx(1e-10)
    assert ("faster than MuJoCo (beyond the timing spread) for errors below 5.6e-05; MuJoCo is faster above it"
            in c["statement"])
    assert c["ratio_at_crossover"] == pytest.approx(5.0 / 2.0)
    assert c["largest_speedup"]["ratio"] == pytest.approx(50.0 / 3.0)
    assert "only urdf2links reached errors below 1.0e-10" in c["statement"]


def test_crossover_when_mujoco_wins_the_tightest_level():
    # the project wins from 1e-10 to 1e-4 but loses at the tightest level (timing jitter, or a
    # fixed-step rung against an adaptive one) and at the loose levels
    rows = synthetic([(1e-2, 1e-3), (1e-3, 1.0), (1e-6, 0.01), (1e-8, 0.02), (1e-10, 0.03), (1e-11, 10.0)],
                     [(1e-2, 1e-4), (1e-3, 5e-3), (1e-6, 1.0), (1e-8, 2.0), (1e-10, 3.0), (1e-11, 5.0)])
    c = crossover(rows)
    assert c["error_level"] == pytest.approx(10 ** -3.25)
    assert c["region"][0] == pytest.approx(1e-10)
    assert "for errors between 1.0e-10 and 5.6e-04 (not below: at 1.0e-11" in c["statement"]
    assert c["largest_speedup"]["ratio"] == pytest.approx(100.0)
    winners = "".join("P" if x["project_faster"] else "M" for x in c["levels"])
    assert winners == "MMMM" + "P" * 28 + "MMMMM"  # 1e-11..10**-10.25, 1e-10..10**-3.25, 1e-3..1e-2


def with_spread(rows, spread):
    """The rows with timing rounds spread by the factor ``spread`` around their median."""
    return [dict(r, wall_time_min_s=r["wall_time_s"] / spread, wall_time_max_s=r["wall_time_s"] * spread) for r in rows]


def test_crossover_needs_more_than_the_spread():
    # the project's median is 2.5x faster at 1e-8 (2 s against 5 s)
    rows = synthetic([(1e-4, 1.0), (1e-8, 2.0), (1e-11, 3.0)], [(1e-4, 0.1), (1e-8, 5.0), (1e-10, 50.0)])
    # spreads of +-1.2x: 2.4 < 4.17, still a win; crossover and statement as without spread
    c = crossover(with_spread(rows, 1.2))
    assert c["error_level"] == pytest.approx(10 ** -4.25) and c["ties"] == 0
    assert "takes 2 s (1.67-2.4) and MuJoCo (RK4 dt 0.1) 5 s (4.17-6)" in c["statement"]
    # spreads of +-1.6x: 3.2 > 3.125, the levels where 2 s meets 5 s become ties, 3 s against 50 s still wins
    c = crossover(with_spread(rows, 1.6))
    winners = {round(math.log10(x["error"]) * 4): x["winner"] for x in c["levels"]}
    assert winners[-40] == "urdf2links" and winners[-32] == "tie" and winners[-16] == "MuJoCo"
    assert c["error_level"] == pytest.approx(10 ** -8.25) and c["ties"] > 0
    assert "levels are ties" in c["statement"] and "the engines tie (within the timing spread) at" in c["statement"]
    # spreads of +-10x: nothing is called
    c = crossover(with_spread(rows, 10.0))
    assert c["error_level"] is None and c["ties"] == len(c["levels"])
    assert "not (yet) faster than MuJoCo beyond the timing spread" in c["statement"] and "a tie" in c["statement"]


def test_rounding_floor_stops_a_ladder():
    est = 1e-11
    row = lambda v, e, status="ok": {"status": status, "value": v, "param": "dt", "error_max": e}  # noqa: E731
    # truncation error falling, then MuJoCo-RK4-like rounding: 3e-10 is no better than 2.7e-10
    done = [row(1e-3, 3e-5), row(5e-4, 2e-6), row(1e-4, 2.7e-10), row(5e-5, 3e-10)]
    stalled, best = _rounding_floor(done, est)
    assert stalled is done[3] and best == 2.7e-10
    # a non-monotone error far above the band (adaptive jitter, Euler's plateau) does not stop a ladder
    assert _rounding_floor([row(1e-3, 0.09), row(1e-4, 0.091), row(1e-5, 1e-4)], est) == (None, math.inf)
    assert _rounding_floor([row(1e-3, 1e-8), row(1e-4, 2e-8)], est)[0] is None      # 2e-8 > 100 x 1e-11
    assert _rounding_floor([row(1e-3, 1e-9), row(1e-4, 1e-9, "failed")], est)[0] is None  # a failure is no floor
    assert ROUNDING_BAND * est == pytest.approx(1e-9)
    # MuJoCo's step ladder: 0.01 s / j, about 1.25x apart from j = 4 on, every step dividing 0.01 s
    ratios = np.array(MUJOCO_DTS[2:-1]) / np.array(MUJOCO_DTS[3:])
    assert np.all(ratios <= 1.6 + 1e-12) and np.median(ratios) == pytest.approx(1.25, abs=0.03)
    assert all(abs(0.01 / dt - round(0.01 / dt)) < 1e-9 for dt in MUJOCO_DTS) and min(MUJOCO_DTS) == pytest.approx(1e-6)


def test_crossover_not_yet_and_floor():
    rows = synthetic([(1e-6, 1.0), (1e-9, 10.0)], [(1e-6, 0.01), (1e-12, 0.1)])
    c = crossover(rows)
    assert c["error_level"] is None and "not (yet) faster" in c["statement"]
    assert "only MuJoCo reached errors below 1.0e-09" in c["statement"]
    # with a reference floor of 1e-9 the tightest errors are indistinguishable: MuJoCo still wins there
    c = crossover(rows, floor=1e-9)
    assert c["tightest_error"] == {"urdf2links": 1e-9, "MuJoCo": 1e-9}
    assert c["error_level"] is None and "MuJoCo 100x faster" in c["statement"]
    failed = [dict(r, status="failed") if r["engine"] == "MuJoCo" else r for r in rows]
    assert "no successful run" in crossover(failed)["statement"]


def test_budget_skips_are_recorded_not_dropped():
    data = run_study(SCENE, t_end=0.2, quick=True, budget=1e-9, methods=("RK4",), mujoco_integrators=("Euler",))
    rows = data["rows"]
    assert len(rows) == 3 + 4 and all(r["status"] == "skipped" for r in rows)
    assert "> budget" in rows[0]["reason"] and "looser rung" in rows[1]["reason"]
    assert "no successful run" in data["crossover"]["statement"]
    section = render_section(data)  # a study with nothing to draw still renders
    assert section.startswith(BEGIN) and "skipped" in section


def test_insert_section_without_footer(tmp_path):
    page = tmp_path / "p.html"
    page.write_text("<html><body>no footer</body></html>")
    data = run_study(SCENE, t_end=0.2, quick=True, budget=1e-9, methods=("RK4",), mujoco_integrators=("RK4",))
    assert insert_section(page, data) and page.read_text().index(END) < page.read_text().index("</body>")
    page.write_text("no html at all")
    assert not insert_section(page, data)


def test_report_includes_the_section_when_the_scene_has_a_study(tmp_path):
    from urdf2links.compare.reports.report import write_report
    from urdf2links.compare.agreement.trajectory import compare_scene

    data = run_study(SCENE, t_end=0.2, quick=True, methods=("RK4",), mujoco_integrators=("RK4",))
    write_study(data, tmp_path)
    c = compare_scene(SCENE, t_end=0.2, states=2, progress=False)
    page = write_report(c, tmp_path)["html"].read_text()
    assert page.count(BEGIN) == 1 and "Accuracy against wall time" in page
    assert page.index("<h2>3. Energy</h2>") < page.index(BEGIN)


def test_cli_writes_the_files(tmp_path, capsys):
    rc = main(["tradeoff", str(SCENE), "--quick", "--t-end", "0.2", "--methods", "RK4,DOP853",
               "--mujoco-integrators", "RK4", "--out", str(tmp_path), "--quiet"])
    assert rc == 0
    out = capsys.readouterr().out
    assert "crossover:" in out and "error estimate" in out
    for name in ("tradeoff.json", "tradeoff.md", "work_precision.png", "energy_drift.png"):
        assert (tmp_path / name).is_file()
    assert json.loads((tmp_path / "tradeoff.json").read_text())["command"].startswith("urdf2links tradeoff")


@pytest.mark.parametrize("argv, named", [
    (["--methods", "RK4,Verlet"], "--methods='RK4,Verlet'"),
    (["--mujoco-integrators", "semi"], "--mujoco-integrators='semi'"),
    (["--t-end", "-1"], "--t-end=-1.0"),
    (["--repeats", "0"], "--repeats=0"),
])
def test_cli_errors_name_the_argument(argv, named, tmp_path, capsys):
    rc = main(["tradeoff", str(SCENE), "--out", str(tmp_path), *argv])
    assert rc == 2
    assert named in capsys.readouterr().err


def test_urdf2links_cli_does_not_import_mujoco():
    code = "import sys, urdf2links.cli; sys.exit('mujoco' in sys.modules or 'urdf2links.compare.tradeoff.study' in sys.modules)"
    assert subprocess.run([sys.executable, "-c", code], cwd=ROOT).returncode == 0

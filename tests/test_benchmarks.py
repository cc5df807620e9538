"""The benchmark scripts render their committed JSON (no timing here: speed is measured by the
scripts themselves, on a quiet machine): every table and plot in reports/benchmarks/ can be
rebuilt from its JSON with ``--render-only``, and the figures the docs state are in it."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest


ROOT = Path(__file__).resolve().parent.parent
BENCHMARKS = ("eval_cost", "solver_cost", "sweeps", "mujoco_harness", "corpus_wall", "loop_cost", "batch_cost")


@pytest.mark.parametrize("name", BENCHMARKS)
def test_render_only_rebuilds_the_table_and_plot(name, tmp_path):
    committed = ROOT / "reports" / "benchmarks" / f"{name}.json"
    data = json.loads(committed.read_text())
    assert data["benchmark"] == name and data["command"].startswith(f"python benchmarks/{name}.py")
    assert {"platform", "cpu_count", "python", "numpy", "numba", "mujoco", "git_commit"} <= set(data["machine"])
    out = tmp_path / f"{name}.json"
    shutil.copy(committed, out)
    subprocess.run([sys.executable, str(ROOT / "benchmarks" / f"{name}.py"), "--render-only", "--out", str(out)],
                   check=True, cwd=tmp_path, capture_output=True, timeout=600)
    md = out.with_suffix(".md").read_text()
    assert md == (ROOT / "reports" / "benchmarks" / f"{name}.md").read_text()  # the committed table is this JSON's
    assert out.with_suffix(".png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "median (min-max)" in md and data["command"] in md


def test_tables_state_what_the_issue_asks():
    """The harness criterion, the sweep's equal outputs and both engines' growth with n are stated."""
    bench = ROOT / "reports" / "benchmarks"
    harness = json.loads((bench / "mujoco_harness.json").read_text())
    crane = next(r for r in harness["rows"] if r["scene"] == "ship_crane")
    assert crane["inputs"] == "compiled" and crane["steps"] == 20000
    assert "MuJoCo's engine time is" in (bench / "mujoco_harness.md").read_text()
    sweeps = json.loads((bench / "sweeps.json").read_text())
    assert {r["scene"] for r in sweeps["rows"]} == {"double_pendulum_chaos", "ur5_falling"}
    corpus = json.loads((bench / "corpus_wall.json").read_text())
    assert corpus["same_figures"] and [r["way"] for r in corpus["rows"]] == ["serial", "jobs 2", "LocalCluster 2"]
    growth = json.loads((bench / "eval_cost.json").read_text())["growth"]
    for key in ("forward_dynamics", "mj_forward"):
        assert len(growth[key]["local"]) >= 5 and len(growth[key]["large_n"]["n"]) >= 3


def test_loop_and_batch_tables_state_issue_14s_ratios():
    """Per evaluation against one MuJoCo Euler step on every model the issue names, and the batch
    at B = 1000 and 10000 on 1 thread and all threads, with equal q'' on both engines."""
    bench = ROOT / "reports" / "benchmarks"
    loop = json.loads((bench / "loop_cost.json").read_text())
    names = {r["robot"] for r in loop["rows"]}
    assert {"double_pendulum", "ur5_like", "chain64"} <= names
    assert all(r["ratio_rhs"] > 0 and r["evals"] >= 2000 for r in loop["rows"])
    assert "rhs / mj_step" in (bench / "loop_cost.md").read_text()
    assert len(loop["slopes"]["rhs"]) >= 3
    batch = json.loads((bench / "batch_cost.json").read_text())
    assert {1000, 10000} <= set(batch["batches"])
    for r in batch["rows"]:
        for k in sorted({1, batch["threads"]}):
            t = r[f"threads_{k}"]
            # q'' against MuJoCo's (q'_1 - q'_0) / dt: the Euler update's rounding / dt (1e-4 s) is
            # ~1e-12 of |q''|; a different q'' (another model, a wrong row) is O(1)
            assert t["ratio"] > 0 and t["max_rel_difference"] < 1e-9, (r["robot"], r["B"], k)

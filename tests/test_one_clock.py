"""One clock (issue 42): every time ``urdf2links check`` shows leaves numba's compilation out, cold or warm.

``check`` on a tiny configuration (the shipped pendulum, MuJoCo's import of it as the pair's MJCF, its default
scene for 0.5 s) runs in a subprocess with an empty numba cache (``URDF2LINKS_CACHE_DIR`` a fresh folder: every
kernel compiled), then three times warm (the same folder), each with ``--jobs 2`` as the written workflow runs it
(the cases in worker processes). Each case's seconds, parsed from its line, its JUnit ``time=`` and its Markdown
row, must stay within the warm runs' spread; the compilation is shown apart, in one line, and is far larger than
that spread, so a time that included it would fail.

Measured on the 2-core machine shared with other work (issue 42), three warm runs each time:

| load | pair warm | pair cold | scene warm | scene cold | compilation (cold) |
|---|---|---|---|---|---|
| heavy, --jobs 1 | 1.5-1.6 s | 1.4-1.9 s | 0.4-0.6 s | 0.3-0.5 s | 77-122 s (pair 36 s, scene 41 s) |
| heavy, --jobs 2 | 1.02-1.17 s | 0.35 s | 0.51-1.37 s | 1.37 s | 88 s |
| light, --jobs 2 | 0.171-0.182 s | 0.203 s | 0.223-0.234 s | 0.292 s | 26 s |

A warm run's case also loads the compiled code from the cache (no compilation, but time), a cold one does not:
either may be the slower. The bound, 2 x the slowest warm run + 1 s, leaves room for a loaded machine's
spread (a cold case read up to 0.3 s above the slowest warm one; the warm runs of one case spread over up to
0.86 s, one 2.7 x another) and is still 5 x smaller than the compilation it must keep out (asserted: the test
can fail).
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from lxml import etree

from urdf2links.compare.pairs.mujoco_import import save_mujoco_import
from urdf2links.locations import shipped_robots_dir

CONFIG = """\
[[robots]]
files = ["robots/pendulum.urdf", "robots/pendulum.xml"]

[[pairs]]
urdf = "robots/pendulum.urdf"
mjcf = "robots/pendulum.xml"

[[scenes]]
robot = "robots/pendulum.urdf"
t_end = 0.5
"""
WARM_RUNS = 3
_CASE_BOUND = "cold <= 2 x slowest warm + 1 s"
FIGURE_BOUNDS = {"compilation": "> 5 x every case's bound (a time that held it would fail)",
                 "robot robots/pendulum.urdf": _CASE_BOUND, "robot robots/pendulum.xml": _CASE_BOUND,
                 "pair robots/pendulum.urdf against robots/pendulum.xml": _CASE_BOUND,
                 "scene robots/pendulum.urdf (default scene)": _CASE_BOUND}
LINE = re.compile(r"^(?:ok|FAIL|ERROR)\s+(robot|pair|scene)\s+(.+) \(([0-9.]+) s\)$", re.M)
COMPILED = re.compile(r": ([0-9.]+) s \((\d+) compiled functions")


def _bound(warm: list[float]) -> float:
    """The largest time a case may show: the module doc's bound."""
    return 2 * max(warm) + 1.0


def _run(repo: Path, cache: Path, n: int, *extra: str) -> dict:
    """``check`` in a subprocess with the numba cache ``cache``: each case's seconds from its line, its JUnit
    ``time=`` and its Markdown row, and the seconds of the compilation line(s)."""
    junit, md = repo / f"run{n}.xml", repo / f"run{n}.md"
    env = {**os.environ, "URDF2LINKS_CACHE_DIR": str(cache)}
    out = subprocess.run([sys.executable, "-m", "urdf2links", "check", str(repo), "--jobs", "2", "--junit", str(junit),
                          "--markdown", str(md), *extra], capture_output=True, text=True, env=env, timeout=1800)
    assert out.returncode == 0, out.stdout + out.stderr
    lines = {f"{kind} {name}": float(s) for kind, name, s in LINE.findall(out.stdout)}
    cases = etree.parse(str(junit)).getroot().iter("testcase")
    xml = {f"{c.get('classname').split('.')[-1]} {c.get('name')}": float(c.get("time")) for c in cases}
    rows = re.findall(r"^\| (robot|pair|scene) \| `(.+?)` \| .*? \| ([0-9.]+) \|$", md.read_text(), re.M)
    table = {f"{kind} {name}": float(s) for kind, name, s in rows}
    return {"lines": lines, "junit": xml, "markdown": table,
            "compiled": [float(s) for s, _ in COMPILED.findall(out.stderr)], "stderr": out.stderr}


@pytest.mark.slow
def test_cold_times_stay_within_the_warm_spread(tmp_path, record_figure):
    repo = tmp_path / "repo"
    (repo / "robots").mkdir(parents=True)
    shutil.copy(shipped_robots_dir() / "pendulum.urdf", repo / "robots" / "pendulum.urdf")
    save_mujoco_import(repo / "robots" / "pendulum.urdf", repo / "robots" / "pendulum.xml", keep_geometry=False)
    (repo / "urdf2links.toml").write_text(CONFIG)
    cache = tmp_path / "numba_cache"                 # empty: the first run compiles every kernel it calls
    cold = _run(repo, cache, 0, "--write-baselines")
    warm = [_run(repo, cache, k) for k in range(1, WARM_RUNS + 1)]
    names = set(cold["lines"])
    assert len(names) == 4 and {n.split()[0] for n in names} == {"robot", "pair", "scene"}, cold["lines"]
    # compilation shown apart, once, and large against every bound below (a time that held it would fail)
    assert len(cold["compiled"]) == 1, cold["stderr"]
    compiled = cold["compiled"][0]
    assert "in worker processes" in cold["stderr"] and "no reported time includes it" in cold["stderr"]
    for run in [cold, *warm]:
        assert set(run["lines"]) == set(run["junit"]) == set(run["markdown"]) == names, run
        for name in names:      # the three outputs show one time: the line (0.1 s), JUnit (1 ms), Markdown (0.1 s)
            assert abs(run["junit"][name] - run["lines"][name]) <= 0.05 + 1e-9
            assert abs(run["markdown"][name] - run["lines"][name]) <= 1e-9
    for name in sorted(names):
        spread = [run["junit"][name] for run in warm]
        bound = _bound(spread)
        record_figure(name, "warm (s)", f"{min(spread):.3f}-{max(spread):.3f}")
        record_figure(name, "cold (s)", cold["junit"][name], "{:.3f}")
        assert compiled > 5 * bound, (compiled, name, bound)
        assert cold["junit"][name] <= bound, (f"{name}: {cold['junit'][name]:.3f} s cold, warm "
                                              f"{min(spread):.3f}-{max(spread):.3f} s: compilation counted?")
    record_figure("compilation", "cold (s)", compiled, "{:.1f}")


def test_the_constrained_path_times_on_the_same_clock():
    """A constrained run (issue 45: the scene's method, auto, in the compiled loops with the projection) reports its
    wall time and its compilation apart, as simulate does: ``wall_time`` within ``run_s``, ``compile_s`` what the
    run compiled."""
    from urdf2links import compilation
    from urdf2links.integration import simulate

    before = compilation.seconds()
    tr = simulate(shipped_robots_dir() / "loops" / "four_bar_crank.toml", t_end=0.05, samples=5, progress=False)
    stats = tr.stats
    assert stats["integrator"] == "auto+projection"
    assert 0 < stats["wall_time"] <= stats["run_s"]
    assert 0 <= stats["compile_s"] <= compilation.seconds() - before + 1e-9    # the plan compiles before the run

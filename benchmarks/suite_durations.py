"""Where the test suite's time goes: the README's test command timed, its slowest tests listed.

Runs ``python -m pytest -q --durations=N`` (the project's pytest settings: two worker processes per
core count, a file per worker at a time) once, as CI runs it: with an EMPTY numba cache (a fresh
folder in ``URDF2LINKS_CACHE_DIR``, so numba compiles everything once, as on a clean machine), or
with the user's cache (``--warm``). It writes ``reports/benchmarks/suite_durations.json`` and the
table between the markers of ``docs/testing.md``: the total wall time, the machine (cores, load
average before the run), and the slowest tests (each figure is one test's own duration in its worker:
with two workers, their sum exceeds the wall time). Usage::

    python benchmarks/suite_durations.py [--warm] [--top 30] [--out reports/benchmarks/suite_durations.json]
    python benchmarks/suite_durations.py --render-only     # the table again from the JSON
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DOC = ROOT / "docs" / "testing.md"
BEGIN, END = "<!-- BEGIN suite_durations (benchmarks/suite_durations.py) -->", "<!-- END suite_durations -->"
_DURATION = re.compile(r"^\s*([0-9.]+)s (call|setup|teardown)\s+(.+?)\s*$")
_TOTAL = re.compile(r"^=*\s*(\d+ (?:passed|failed).*?) in ([0-9.]+)s")


def run_suite(*, warm: bool, top: int) -> dict:
    """One run of the suite: ``{"wall_s", "outcome", "slowest": [{"s", "when", "test"}], ...}``."""
    env = dict(os.environ)
    with tempfile.TemporaryDirectory() as cache:
        if not warm:
            env.pop("NUMBA_CACHE_DIR", None)
            env["URDF2LINKS_CACHE_DIR"] = cache
        load = os.getloadavg()[0]
        start = time.perf_counter()
        out = subprocess.run([sys.executable, "-m", "pytest", "-q", f"--durations={top}", "-p", "no:cacheprovider"],
                             cwd=ROOT, env=env, capture_output=True, text=True)
        wall = time.perf_counter() - start
    lines = out.stdout.splitlines()
    slowest = [{"s": float(m[1]), "when": m[2], "test": m[3]} for m in map(_DURATION.match, lines) if m]
    totals = [m for m in map(_TOTAL.match, lines) if m]
    return {"wall_s": wall, "pytest_s": float(totals[-1][2]) if totals else None,
            "outcome": totals[-1][1] if totals else out.stdout[-500:], "returncode": out.returncode,
            "numba_cache": "warm (the user's)" if warm else "empty (compiled during the run)",
            "cores": os.cpu_count(), "load_before": load, "machine": platform.platform(),
            "python": platform.python_version(), "slowest": slowest[:top]}


def render(data: dict) -> str:
    rows = [f"Measured by `python benchmarks/suite_durations.py` on {data['machine']}, {data['cores']} cores "
            f"(load average {data['load_before']:.1f} before the run), Python {data['python']}, numba cache "
            f"{data['numba_cache']}: **{data['wall_s'] / 60:.1f} minutes** of wall time for "
            f"`python -m pytest -q` ({data['outcome']}; pip's install of the test extra not included).", "",
            f"The {len(data['slowest'])} slowest tests (each in its own worker; numba's compilation lands in "
            "whichever test first needs a function):", "", "| s | phase | test |", "|---:|---|---|"]
    rows += [f"| {r['s']:.1f} | {r['when']} | `{r['test']}` |" for r in data["slowest"]]
    return "\n".join(rows)


def write_doc(data: dict) -> None:
    text = DOC.read_text()
    head, rest = text.split(BEGIN, 1)
    _, tail = rest.split(END, 1)
    DOC.write_text(head + BEGIN + "\n" + render(data) + "\n" + END + tail)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--warm", action="store_true", help="use the user's numba cache instead of an empty one")
    ap.add_argument("--top", type=int, default=30, help="how many of the slowest tests to list (default 30)")
    ap.add_argument("--out", type=Path, default=ROOT / "reports" / "benchmarks" / "suite_durations.json")
    ap.add_argument("--render-only", action="store_true", help="write the table again from --out")
    args = ap.parse_args(argv)
    if args.render_only:
        data = json.loads(args.out.read_text())
    else:
        data = run_suite(warm=args.warm, top=args.top)
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(json.dumps(data, indent=2) + "\n")
    write_doc(data)
    print(render(data))
    return 0 if data["returncode"] == 0 else 1


if __name__ == "__main__":
    sys.exit(main())

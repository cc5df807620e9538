"""Cold start: the process wall time of a user's first commands, with an empty cache folder and a warm one.

Each command runs as a user runs it, in a process of its own (``python -m urdf2links ...``), its wall
time measured around the process: ``import urdf2links``, ``urdf2links --help``, ``simulate pendulum``,
``simulate ur5_falling``, ``compare ur5_falling`` and ``report`` (every shipped scene against MuJoCo).
**Cold**: numba's cache folder (``URDF2LINKS_CACHE_DIR``) is a new, empty folder, so everything the
command calls is compiled; **warm**: the same command again, with the folder the cold run filled.
Every round runs every command cold then warm, the order of the commands reversed every other round.
Each row gives the median (min-max) over the rounds, the compilation the command reported on its own
line, and for ``simulate`` the wall time the command itself reports (which leaves compilation out).

The targets (issue 32, a 2-core machine) are checked with the tie rule: *met* when the slowest round
is within the target, *missed* when the fastest round is not, else *tie* (the spread straddles it).
The machine's load average is recorded with every run: on a shared machine the spread is wide.

    python benchmarks/cold_start.py               # 3 rounds (about 15 minutes on 2 cores)
    python benchmarks/cold_start.py --only "simulate pendulum" --rounds 2
"""

from __future__ import annotations

import json
import os
import re
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from benchmarking import ROOT, fmt_spread, markdown_table, run_benchmark, spread

#: The commands timed, as typed after ``python``.
COMMANDS = {
    "import urdf2links": ["-c", "import urdf2links"],
    "urdf2links --help": ["-m", "urdf2links", "--help"],
    "simulate pendulum": ["-m", "urdf2links", "simulate", "pendulum", "--out", "{out}", "--quiet"],
    "simulate ur5_falling": ["-m", "urdf2links", "simulate", "ur5_falling", "--out", "{out}", "--quiet"],
    "compare ur5_falling": ["-m", "urdf2links", "compare", "ur5_falling", "--out", "{out}", "--quiet"],
    "report": ["-m", "urdf2links", "report", "--out", "{out}"],
}
#: Issue 32's targets (seconds of process wall time, and of the wall time the command reports).
TARGETS = {("simulate pendulum", "cold"): 20.0, ("simulate pendulum", "warm"): 1.5, ("report", "cold"): 90.0,
           ("import urdf2links", "warm"): 0.5, ("import urdf2links", "cold"): 0.5,
           ("urdf2links --help", "warm"): 0.5}
REPORTED_TARGET = ("simulate pendulum", 0.05)
_COMPILED = re.compile(r"compiling the solver for this machine, first run only: ([0-9.]+) s")
_WALL = re.compile(r"evaluations, ([0-9.]+) s wall")


def _run(name: str, cache: str, out: str) -> dict:
    log_file = os.path.join(out, "compile_log.json")
    if os.path.exists(log_file):
        os.remove(log_file)
    env = dict(os.environ, URDF2LINKS_CACHE_DIR=cache, URDF2LINKS_COMPILE_LOG=log_file)
    env.pop("NUMBA_CACHE_DIR", None)
    argv = [sys.executable, *[a.replace("{out}", out) for a in COMMANDS[name]]]
    load = os.getloadavg()[0]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    res = subprocess.run(argv, env=env, cwd=out, capture_output=True, text=True, timeout=3600)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    if res.returncode not in (0, 1):      # report exits 1 when a scene misses its baseline: still timed
        raise SystemExit(f"{name}: exit {res.returncode}\n{res.stderr[-3000:]}")
    text = res.stdout + res.stderr
    compiled = _COMPILED.search(text)
    reported = _WALL.search(res.stdout)
    functions = json.loads(Path(log_file).read_text())["functions"] if os.path.exists(log_file) else {}
    return {"wall": wall, "cpu": cpu, "load": load, "compile_s": float(compiled.group(1)) if compiled else 0.0,
            "reported_wall": float(reported.group(1)) if reported else None,
            "functions": {k.replace("urdf2links.", ""): round(v["own_s"], 4) for k, v in functions.items()}}


def _measure(args, log):
    names = [n for n in COMMANDS if not args.only or n in args.only]
    runs = {n: {"cold": [], "warm": []} for n in names}
    base = tempfile.mkdtemp(prefix="urdf2links-cold-start-")
    try:
        for r in range(args.rounds):
            for name in (names if r % 2 == 0 else names[::-1]):
                cache, out = os.path.join(base, f"cache-{r}-{len(runs[name]['cold'])}-{abs(hash(name))}"), \
                    os.path.join(base, f"out-{r}")
                os.makedirs(out, exist_ok=True)
                for kind in ("cold", "warm"):
                    got = _run(name, cache, out)
                    runs[name][kind].append(got)
                    log(f"  round {r + 1}/{args.rounds} {name} {kind}: {got['wall']:.2f} s (cpu {got['cpu']:.2f} s, "
                        f"load {got['load']:.1f}, "
                        f"compiled {got['compile_s']:.1f} s"
                        + (f", reported {got['reported_wall']:.3f} s" if got["reported_wall"] is not None else "")
                        + ")")
                shutil.rmtree(cache, ignore_errors=True)
    finally:
        shutil.rmtree(base, ignore_errors=True)
    rows = {}
    for name in names:
        rows[name] = {}
        for kind in ("cold", "warm"):
            xs = runs[name][kind]
            rows[name][kind] = {"wall": spread([x["wall"] for x in xs]), "cpu": spread([x["cpu"] for x in xs]),
                                "runs": xs,
                                "compile_s": spread([x["compile_s"] for x in xs]),
                                "load": spread([x["load"] for x in xs])}
            rep = [x["reported_wall"] for x in xs if x["reported_wall"] is not None]
            if rep:
                rows[name][kind]["reported_wall"] = spread(rep)
    return {"rows": rows, "rounds": args.rounds, "targets": {f"{k[0]} ({k[1]})": v for k, v in TARGETS.items()},
            "cpu_count": os.cpu_count(), "python": sys.version.split()[0]}


def verdict(s: dict, target: float) -> str:
    """The tie rule against a target: met (slowest round within), missed (fastest round beyond), else tie."""
    return "met" if s["max"] <= target else "missed" if s["min"] > target else "tie"


def _render(data):
    rows, table = data["rows"], []
    for name, r in rows.items():
        for kind in ("cold", "warm"):
            x = r[kind]
            target = data["targets"].get(f"{name} ({kind})")
            rep = x.get("reported_wall")
            table.append([f"`{name}`", kind, fmt_spread(x["wall"], digits=3), fmt_spread(x["cpu"], digits=3),
                          fmt_spread(x["compile_s"], digits=3),
                          fmt_spread(rep, digits=2) if rep else "-",
                          f"{target:g} s: {verdict(x['wall'], target)}" if target else "-",
                          fmt_spread(x["load"], digits=2)])
    md = ["Process wall time (s) of each command in a process of its own; **cold**: an empty numba cache folder "
          "(`URDF2LINKS_CACHE_DIR`), **warm**: the folder the cold run filled. Median (min-max) over "
          f"{data['rounds']} rounds; *compiled*: the seconds the command reported on its line 'compiling the solver "
          "for this machine, first run only'; *reported*: the wall time `simulate` prints (compilation left out). "
          "Targets (issue 32) under the tie rule: met when the slowest round is within, missed when the fastest is "
          f"not. The load average (1 min) of the machine ({data['cpu_count']} cores, shared) at each start; *process CPU*: "
          "the user + system seconds of the process and its threads (numba compiles on one thread: on an idle "
          "machine the wall time of a cold run is close to its CPU time; on a loaded one it is longer).", "",
          markdown_table(["command", "cache", "process wall (s)", "process CPU (s)", "compiled (s)", "reported wall (s)", "target",
                          "load"], table)]
    rep = rows.get(REPORTED_TARGET[0], {}).get("cold", {}).get("reported_wall")
    if rep:
        md += ["", f"`{REPORTED_TARGET[0]}`'s reported wall time, cold: {fmt_spread(rep, digits=2)} s against "
               f"{REPORTED_TARGET[1]:g} s: {verdict(rep, REPORTED_TARGET[1])}."]
    md += ["", _kernel_table(rows)]
    return "\n".join(md), None


#: The commands whose cold runs give the table of compile times per function.
KERNEL_COMMANDS = ("simulate pendulum", "report")


def _kernel_table(rows) -> str:
    """Seconds numba spent compiling each function itself (its callees' compilation left out: each
    callee has its row), median over the cold rounds, in the cold runs of :data:`KERNEL_COMMANDS`."""
    import statistics

    cols = [c for c in KERNEL_COMMANDS if c in rows]
    own = {}
    for c in cols:
        for run in rows[c]["cold"]["runs"]:
            for f, secs in run.get("functions", {}).items():
                own.setdefault(f, {}).setdefault(c, []).append(secs)
    med = {f: {c: statistics.median(v[c]) for c in v} for f, v in own.items()}
    order = sorted(med, key=lambda f: -max(med[f].values()))
    table = [[f"`{f}`", *(f"{med[f][c]:.2f}" if c in med[f] else "-" for c in cols)] for f in order[:40]]
    rest = order[40:]
    if rest:
        table.append([f"{len(rest)} others", *(f"{sum(med[f].get(c, 0.0) for f in rest):.2f}" for c in cols)])
    table.append(["**all**", *(f"{sum(med[f].get(c, 0.0) for f in med):.2f}" for c in cols)])
    return ("Compile time per function (s), cold: numba's own time for each (its callees' compilation, nested "
            "in it, is on their rows), median over the rounds; `-`: not compiled by that command. From "
            "`URDF2LINKS_COMPILE_LOG` (`urdf2links.compilation.per_function`).\n\n"
            + markdown_table(["function", *(f"`{c}`" for c in cols)], table))


def _options(p):
    p.add_argument("--only", action="append", choices=list(COMMANDS), help="time only this command (repeat)")


if __name__ == "__main__":
    os.chdir(ROOT)
    run_benchmark("cold_start", __doc__, _measure, _render, options=_options, rounds_default=3)

"""What every benchmark script here shares: interleaved rounds in one process, min/median/max,
the machine and versions, and the three files (JSON, Markdown table, PNG plot) in reports/benchmarks/.

A benchmark is one command (``python benchmarks/<name>.py``). It writes
``reports/benchmarks/<name>.json`` (figures, settings, the machine and versions, the command),
``<name>.md`` (the table the docs link to) and ``<name>.png``, or beside the JSON that ``--out``
names; ``--render-only`` rewrites the table and the plot from an existing JSON without timing
anything. Timings are taken in rounds: each round runs every variant once, the order reversed
every other round, so that a slow spell of the machine hits all variants alike; a figure is the
median of its rounds with their min and max.
"""

from __future__ import annotations

import argparse
import json
import shlex
import statistics
import sys
import time
from pathlib import Path
from typing import Callable

ROOT = Path(__file__).resolve().parent.parent
REPORTS = ROOT / "reports" / "benchmarks"

__all__ = ["ROOT", "REPORTS", "run_benchmark", "rounds", "spread", "fmt_spread", "markdown_table", "machine",
           "load_models"]


def rounds(variants: dict[str, Callable[[], float | None]], n: int, *, log=None) -> dict[str, list[float]]:
    """Run every variant ``n`` times, interleaved, the order reversed every other round. A variant
    returns the seconds it measured itself (e.g. an engine's own timed region), or None: then the
    call's duration counts. Returns the seconds of every round per variant."""
    out: dict[str, list[float]] = {k: [] for k in variants}
    names = list(variants)
    for r in range(n):
        for k in (names if r % 2 == 0 else names[::-1]):
            t0 = time.perf_counter()
            own = variants[k]()
            out[k].append(float(own) if own is not None else time.perf_counter() - t0)
        if log:
            log(f"  round {r + 1}/{n}: " + ", ".join(f"{k} {out[k][-1]:.4g} s" for k in names))
    return out


def spread(xs: list[float]) -> dict:
    """``{"median", "min", "max", "rounds"}`` of a variant's seconds."""
    return {"median": float(statistics.median(xs)), "min": float(min(xs)), "max": float(max(xs)), "rounds": len(xs)}


def fmt_spread(s: dict, scale: float = 1.0, digits: int = 3) -> str:
    """``median (min-max)``, scaled (e.g. 1e6 for microseconds)."""
    med, lo, hi = s["median"] * scale, s["min"] * scale, s["max"] * scale
    return f"{med:.{digits}g}" + (f" ({lo:.{digits}g}-{hi:.{digits}g})" if hi > lo else "")


def markdown_table(header: list[str], rows: list[list]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(lines)


def load_models(shipped=(), real=()) -> list:
    """The shipped robots named in ``shipped`` (file names under robots/), then the example-robot-data
    robots at the paths ``real`` (with ``inertia="repair"``; none when the corpus is not installed),
    loaded with the importer's audit warnings silenced."""
    import warnings

    import urdf2links
    from urdf2links.locations import example_robot_data_dir, shipped_robots_dir

    root = example_robot_data_dir()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        out = [urdf2links.load_urdf(shipped_robots_dir() / name) for name in shipped]
        if root is not None:
            out += [urdf2links.load_urdf(root / rel, inertia="repair") for rel in real]
    return out

def machine() -> dict:
    from urdf2links.compare.formatting import machine_info

    return machine_info()


def _command(argv) -> str:
    script = Path(sys.argv[0]).resolve()
    shown = str(script.relative_to(ROOT)) if script.is_relative_to(ROOT) else sys.argv[0]
    return "python " + " ".join([shown, *map(shlex.quote, argv)])


def run_benchmark(name: str, doc: str, measure: Callable, render: Callable, *, options: Callable | None = None,
                  rounds_default: int = 5, argv=None) -> dict:
    """The command line of a benchmark: ``--out`` (default ``reports/benchmarks/<name>.json``),
    ``--rounds``, ``--render-only`` and the script's own ``options(parser)``. ``measure(args, log)``
    returns the JSON-ready figures; ``render(data)`` returns ``(markdown, figure or None)`` from them
    alone. Writes the JSON (with ``machine`` and ``command``), the Markdown (headed by the command
    and ended by the machine line) and the PNG; returns the data."""
    from urdf2links.compare.figures import save_png
    from urdf2links.compare.formatting import json_ready

    p = argparse.ArgumentParser(description=doc.strip().splitlines()[0])
    p.add_argument("--out", default=str(REPORTS.relative_to(ROOT) / f"{name}.json"),
                   help=f"the JSON (default reports/benchmarks/{name}.json, from the repository root); the .md and "
                        ".png go beside it")
    p.add_argument("--rounds", type=int, default=rounds_default, help=f"interleaved rounds (default {rounds_default})")
    p.add_argument("--render-only", action="store_true", help="rewrite the .md and .png from the JSON at --out; "
                   "time nothing")
    if options is not None:
        options(p)
    args = p.parse_args(sys.argv[1:] if argv is None else argv)
    out = Path(args.out)
    if not out.is_absolute():
        out = ROOT / out
    if args.render_only:
        data = json.loads(out.read_text())
    else:
        data = json_ready(dict(measure(args, print), benchmark=name, machine=machine(),
                               command=_command(sys.argv[1:] if argv is None else argv)))
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(json.dumps(data, indent=2) + "\n")
    markdown, fig = render(data)
    m = data["machine"]
    out.with_suffix(".md").write_text(
        markdown.rstrip() + "\n\n"
        + (f"![{name}]({out.with_suffix('.png').name})\n\n" if fig is not None else "")
        + f"Generated by `{data['command']}` (`--render-only` rewrites this table and the plot from the JSON). "
          f"Machine: {m['platform']}, {m['processor']}, {m['cpu_count']} CPUs; Python {m['python']}, numpy "
          f"{m['numpy']}, numba {m['numba']}, MuJoCo {m['mujoco']}; commit {m['git_commit']}.\n")
    if fig is not None:
        save_png(fig, out.with_suffix(".png"))
    print(markdown)
    print(f"wrote {out}, {out.with_suffix('.md').name}" + (f", {out.with_suffix('.png').name}" if fig is not None else ""))
    return data

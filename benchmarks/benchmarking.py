"""What every benchmark script here shares: interleaved rounds in one process, min/median/max,
the machine and versions, and the three files (JSON, Markdown table, PNG plot) in reports/benchmarks/.

A benchmark is one command (``python benchmarks/<name>.py``); it writes
``reports/benchmarks/<name>.json`` (figures, settings, machine), ``<name>.md`` (the table the docs
link to) and ``<name>.png`` unless ``--out`` names another JSON path. Timings are taken in rounds:
each round runs every variant once, the order reversed every other round, so that a slow spell of
the machine hits all variants alike; a variant's figure is its median with the min and max.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from pathlib import Path
from typing import Callable

ROOT = Path(__file__).resolve().parent.parent
REPORTS = ROOT / "reports" / "benchmarks"

__all__ = ["ROOT", "REPORTS", "parser", "rounds", "spread", "fmt_spread", "markdown_table", "write_outputs",
           "machine"]


def parser(name: str, doc: str) -> argparse.ArgumentParser:
    """The script's argument parser with ``--out`` (default ``reports/benchmarks/<name>.json``) and
    ``--rounds``."""
    p = argparse.ArgumentParser(description=doc.strip().splitlines()[0])
    p.add_argument("--out", default=str(REPORTS / f"{name}.json"), help="JSON path; the .md and .png go beside it")
    p.add_argument("--rounds", type=int, default=5, help="interleaved rounds (default 5)")
    return p


def rounds(variants: dict[str, Callable[[], float]], n: int, *, log=None) -> dict[str, list[float]]:
    """Run every variant ``n`` times, interleaved, the order reversed every other round. A variant
    returns the seconds it measured itself (e.g. an engine's own timed region) or None, in which
    case the call's duration counts. Returns the seconds of every round per variant."""
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
    """``median (min-max)`` scaled (e.g. 1e6 for microseconds)."""
    med, lo, hi = s["median"] * scale, s["min"] * scale, s["max"] * scale
    return f"{med:.{digits}g}" + (f" ({lo:.{digits}g}-{hi:.{digits}g})" if hi > lo else "")


def markdown_table(header: list[str], rows: list[list]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(lines)


def machine() -> dict:
    from urdf2links.compare.formatting import machine_info

    return machine_info()


def write_outputs(out: str | Path, data: dict, markdown: str, fig=None, *, command: str | None = None) -> list[Path]:
    """Write the JSON (with ``machine`` and ``command``), the Markdown (with the machine line and the
    command that regenerates it) and the figure (PNG) beside it; returns the paths."""
    from urdf2links.compare.figures import save_png
    from urdf2links.compare.formatting import json_ready

    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    command = command or "python " + " ".join([str(Path(sys.argv[0]).relative_to(ROOT))
                                                if Path(sys.argv[0]).resolve().is_relative_to(ROOT) else sys.argv[0],
                                                *sys.argv[1:]])
    data = dict(data, machine=data.get("machine") or machine(), command=command)
    out.write_text(json.dumps(json_ready(data), indent=2) + "\n")
    m = data["machine"]
    md = out.with_suffix(".md")
    md.write_text(markdown.rstrip() + "\n\n"
                  + f"Machine: {m['platform']}, {m['processor']}, {m['cpu_count']} CPUs; Python {m['python']}, numpy "
                    f"{m['numpy']}, numba {m['numba']}, MuJoCo {m['mujoco']}; commit {m['git_commit']}. "
                    f"Regenerate: `{command}`.\n")
    paths = [out, md]
    if fig is not None:
        paths.append(save_png(fig, out.with_suffix(".png")))
    return paths

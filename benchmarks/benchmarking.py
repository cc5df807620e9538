"""What every benchmark script here shares: interleaved rounds in one process, min/median/max,
the machine and versions, the three files (JSON, Markdown table, PNG plot) in reports/benchmarks/, the
tie rule, and the models and compiled loops more than one benchmark times. Scripts share through this
module only: none imports another script.

A benchmark is one command (``python benchmarks/<name>.py``). It writes
``reports/benchmarks/<name>.json`` (figures, settings, the machine and versions, the command),
``<name>.md`` (the table the docs link to) and ``<name>.png``, or beside the JSON that ``--out``
names; ``--render-only`` rewrites the table and the plot from an existing JSON without timing
anything. Timings are taken in rounds: each round runs every variant once, the order reversed
every other round, so that a slow spell of the machine hits all variants alike; a figure is the
median of its rounds with their min and max.

Two figures compare when their spreads do not overlap (:func:`compare`): a ratio whose spreads
overlap is a **tie**, whatever its medians say; tables show the ratio of the medians beside the
ratio of the minima. A row whose spread is wide (max / min above :data:`WIDE`) is measured again
(:func:`measured`), keeping the attempt with the narrowest spread.
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

import numpy as np
from numba import njit

from urdf2links.scenes.scene_kernels import scene_rhs

ROOT = Path(__file__).resolve().parent.parent
REPORTS = ROOT / "reports" / "benchmarks"
#: The JSON's format: 2 since issue 23 (ties, the fastest MuJoCo call, every Model call). A JSON of
#: another format is not rendered by today's scripts: regenerate it.
FORMAT = 2
#: A variant whose max / min over the rounds exceeds this is a wide spread: its row is measured again.
WIDE = 1.5
#: example-robot-data robots the benchmarks time (paths under its robots folder), by short name.
REAL_ROBOTS = {"ur5": "ur_description/urdf/ur5_robot.urdf", "panda": "panda_description/urdf/panda.urdf",
               "talos": "talos_data/robots/talos_reduced.urdf", "g1": "g1_description/urdf/g1_29dof_rev_1_0.urdf"}

__all__ = ["ROOT", "REPORTS", "FORMAT", "WIDE", "REAL_ROBOTS", "run_benchmark", "rounds", "measured", "spread",
           "is_wide", "compare", "fastest", "fmt_spread", "fmt_ratio", "markdown_table", "machine", "load_models",
           "real", "chain", "eval_loop"]


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


def is_wide(s: dict, wide: float = WIDE) -> bool:
    """A spread whose max is more than ``wide`` times its min (a slow spell of the machine)."""
    return s["max"] > wide * s["min"]


def _widest(times: dict[str, list[float]]) -> float:
    return max(max(v) / min(v) for v in times.values())


def measured(variants: dict[str, Callable[[], float | None]], n: int, *, wide: float = WIDE, retries: int = 2,
             log=None) -> tuple[dict[str, list[float]], int]:
    """:func:`rounds` of ``variants``; while one of them has a wide spread (max / min above ``wide``),
    all of them again, interleaved as before, at most ``retries`` more times. Returns the attempt
    whose widest spread is the narrowest (every variant from that same attempt: the engines keep
    sharing the machine's spells) and the number of attempts made."""
    best = rounds(variants, n, log=log)
    attempts = 1
    while attempts <= retries and _widest(best) > wide:
        if log:
            log(f"  wide spread (max/min {_widest(best):.2f} > {wide:g}): measured again")
        again = rounds(variants, n, log=log)
        attempts += 1
        if _widest(again) < _widest(best):
            best = again
    return best, attempts


def compare(ours: dict, peer: dict) -> dict:
    """``ours`` against ``peer`` (two :func:`spread` s, in seconds): the ratio of the medians and the
    ratio of the minima (ours / peer: below 1 is faster), and the verdict of the tie rule:
    ``"faster"`` when ours' slowest round beats the peer's fastest, ``"slower"`` the other way round,
    else ``"tie"`` (the spreads overlap: the difference is inside the noise)."""
    verdict = "faster" if ours["max"] < peer["min"] else "slower" if ours["min"] > peer["max"] else "tie"
    return {"median": ours["median"] / peer["median"], "min": ours["min"] / peer["min"], "verdict": verdict}


def fastest(spreads: dict[str, dict]) -> str:
    """The name of the fastest of several ways to do the same work (smallest median)."""
    return min(spreads, key=lambda k: spreads[k]["median"])


def fmt_ratio(c: dict, digits: int = 2) -> str:
    """A :func:`compare` as a table cell: ``median-ratio (min min-ratio) verdict``, e.g. ``0.40 (min 0.97) tie``."""
    return f"{c['median']:.{digits}f} (min {c['min']:.{digits}f}) {c['verdict']}"


def fmt_spread(s: dict, scale: float = 1.0, digits: int = 3) -> str:
    """``median (min-max)``, scaled (e.g. 1e6 for microseconds)."""
    med, lo, hi = s["median"] * scale, s["min"] * scale, s["max"] * scale
    return f"{med:.{digits}g}" + (f" ({lo:.{digits}g}-{hi:.{digits}g})" if hi > lo else "")


def markdown_table(header: list[str], rows: list[list]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(lines)


def real(*names: str) -> tuple[str, ...]:
    """Paths of :data:`REAL_ROBOTS` by short name (``real("ur5", "g1")``), for :func:`load_models`."""
    return tuple(REAL_ROBOTS[k] for k in names)


def chain(n: int):
    """A spatial pendulum of ``n`` rods (0.5 m, 1 kg, COM 0.25 m below the joint), hinge axes
    alternating x / y: the benchmarks' model of growth with n."""
    from urdf2links import LinkSpec, Model, build_tree

    specs = []
    for i in range(n):
        H = np.zeros((4, 4))
        m, c = 1.0, np.array([0.0, 0.0, -0.25])
        S = np.diag([0.02, 0.02, 0.002]) * 0.5 + m * np.outer(c, c)
        H[:3, :3], H[:3, 3], H[3, :3], H[3, 3] = S, m * c, m * c, m
        specs.append(LinkSpec(f"l{i}", None if i == 0 else f"l{i - 1}", params=(0, 0, 0 if i == 0 else -0.5, 0, 0, 0),
                              coordinates={"phi_x" if i % 2 == 0 else "phi_y": f"q{i}"}, H=H))
    return Model(build_tree(specs), name=f"chain{n}")


@njit(cache=True)
def eval_loop(y, out, reps, I, F, W, SI, SF, X, rhs):
    """``reps`` evaluations of the compiled right-hand side at ``y`` (t moving), inside a compiled loop:
    ``eval_loop(y, out, reps, *plan.rhs.args)`` (``rhs``: the scene's C function, called as the
    integration loops call it)."""
    for r in range(reps):
        scene_rhs(0.01 * r, y, out, I, F, W, SI, SF, X, rhs)


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
                  rounds_default: int = 5, argv=None, accepts: tuple[int, ...] = (FORMAT,)) -> dict:
    """The command line of a benchmark: ``--out`` (default ``reports/benchmarks/<name>.json``),
    ``--rounds``, ``--render-only`` and the script's own ``options(parser)``. ``measure(args, log)``
    returns the JSON-ready figures; ``render(data)`` returns ``(markdown, figure or None)`` from them
    alone. Writes the JSON (with ``machine`` and ``command``), the Markdown (headed by the command
    and ended by the machine line) and the PNG; returns the data. ``--render-only`` refuses a JSON
    whose format (:data:`FORMAT`; 1 when absent) is not in ``accepts``."""
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
        if data.get("format", 1) not in accepts:
            raise SystemExit(f"{out}: format {data.get('format', 1)}, this script renders format {FORMAT}: "
                             f"regenerate it with {data.get('command', f'python benchmarks/{name}.py')}")
    else:
        data = json_ready(dict(measure(args, print), benchmark=name, format=FORMAT, machine=machine(),
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

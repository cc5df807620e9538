"""Wall time of `urdf2links report --corpus` on example-robot-data three ways: one process, two worker
processes (``--jobs 2``), a two-worker Dask ``LocalCluster`` (one thread each); and whether the three
gave the same figures (they must: only where a robot runs changes).

Each way runs :func:`urdf2links.compare.corpus.runner.run_corpus` over the same robots with the
command's defaults (default scene, 0.5 s, seed 0, light pages and thumbnails), then writes the same
report (timed apart: the one collecting process writes it in every way). Figures, each the median
(min-max) of ``--rounds`` interleaved rounds: the run (start of the worker processes, their
warm-up and every robot; a Dask cluster's own start is timed apart, as a user starts a cluster once
and runs against it many times), the report, and the sum over robots of each robot's own wall
time (the work there is to share; a run is never shorter than its slowest robot). Usage::

    python benchmarks/corpus_wall.py [--subset N] [--rounds 1] [--out reports/benchmarks/corpus_wall.json]
    python benchmarks/corpus_wall.py --render-only
"""

from __future__ import annotations

import tempfile
import time

from benchmarking import compare, fmt_ratio, fmt_spread, markdown_table, run_benchmark, spread
from urdf2links.compare.corpus.rows import RUN_DEPENDENT_KEYS, CorpusSettings, find_robots
from urdf2links.compare.corpus.report import write_corpus
from urdf2links.compare.corpus.runner import run_corpus

WAYS = ("serial", "jobs 2", "LocalCluster 2")


def _figures(results) -> list[dict]:
    return [{k: v for k, v in r.row.items() if k not in RUN_DEPENDENT_KEYS} for r in results]


def _dask_run(robots, settings) -> tuple[float, float, list]:
    import logging

    from dask.distributed import Client, LocalCluster

    logging.getLogger("distributed").setLevel(logging.CRITICAL)   # the workers' shutdown chatter
    t0 = time.perf_counter()
    cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None)
    client = Client(cluster)
    start = time.perf_counter() - t0
    try:
        t0 = time.perf_counter()
        results = run_corpus(robots, settings, client=client)
        return start, time.perf_counter() - t0, results
    finally:
        client.close()
        cluster.close()


def one_way(way: str, robots, settings) -> tuple[dict, list]:
    """Run the corpus ``way`` once: its seconds and results."""
    start = None
    if way == "LocalCluster 2":
        start, run_s, results = _dask_run(robots, settings)
    else:
        t0 = time.perf_counter()
        results = run_corpus(robots, settings, jobs=1 if way == "serial" else 2)
        run_s = time.perf_counter() - t0
    with tempfile.TemporaryDirectory() as out:
        t0 = time.perf_counter()
        write_corpus(results, out, settings=settings.describe(), run={"how": way, "wall_s": run_s})
        report_s = time.perf_counter() - t0
    slowest = max(results, key=lambda r: r.row["wall_time"]["total_s"]).row
    return ({"run_s": run_s, "cluster_start_s": start, "report_s": report_s,
             "robots_sum_s": sum(r.row["wall_time"]["total_s"] for r in results),
             "slowest": slowest["file"], "slowest_s": slowest["wall_time"]["total_s"]}, results)


def measure(args, log) -> dict:
    robots = find_robots(["example-robot-data"])[: args.subset]
    settings = CorpusSettings()
    runs: dict[str, list[dict]] = {w: [] for w in WAYS}
    reference, same = None, True
    for r in range(args.rounds):
        for way in (WAYS if r % 2 == 0 else WAYS[::-1]):
            row, results = one_way(way, robots, settings)
            runs[way].append(row)
            reference = reference or _figures(results)
            same = same and _figures(results) == reference
            log(f"round {r + 1}/{args.rounds} {way:15s} run {row['run_s']:7.1f} s, report {row['report_s']:5.1f} s, "
                f"sum over robots {row['robots_sum_s']:7.1f} s")
    rows = []
    for way, rs in runs.items():
        starts = [x["cluster_start_s"] for x in rs if x["cluster_start_s"] is not None]
        slow = max(rs, key=lambda x: x["slowest_s"])
        rows.append({"way": way, "run": spread([x["run_s"] for x in rs]), "report": spread([x["report_s"] for x in rs]),
                     "robots_sum": spread([x["robots_sum_s"] for x in rs]),
                     "cluster_start": spread(starts) if starts else None,
                     "slowest": slow["slowest"], "slowest_s": slow["slowest_s"]})
    return {"corpus": "example-robot-data", "robots": len(robots), "t_end": settings.t_end, "rounds": args.rounds,
            "rows": rows, "same_figures": same}


def render(data: dict):
    from urdf2links.compare.figures import figure

    serial = next(r for r in data["rows"] if r["way"] == "serial")["run"]
    table = [[r["way"], fmt_spread(r["run"]), "-" if r["way"] == "serial" else fmt_ratio(compare(r["run"], serial)),
              "-" if r["cluster_start"] is None else fmt_spread(r["cluster_start"]), fmt_spread(r["report"]),
              fmt_spread(r["robots_sum"]), f"{r['slowest']} ({r['slowest_s']:.1f} s)"] for r in data["rows"]]
    md = "\n".join([
        "# Corpus wall time: one process, two processes, a two-worker Dask cluster", "",
        f"`run_corpus` over {data['robots']} robot files of {data['corpus']}, each in its default scene for "
        f"{data['t_end']:g} s with its light page and thumbnail, {data['rounds']} interleaved round(s); seconds, "
        "median (min-max).", "",
        markdown_table(["way", "run (s)", "run / serial", "cluster start (s)", "report (s)", "sum over robots (s)",
                        "slowest robot"], table), "",
        "Same figures whichever way: " + ("yes" if data["same_figures"] else "**NO**") + " (corpus.json rows "
        "compared exactly, wall times and the worker's name aside). Run: the worker processes' start and warm-up "
        "(kernels loaded from numba's cache, MuJoCo, matplotlib) and every robot; a Dask cluster's own start is the "
        "column beside it. A run is never shorter than its slowest robot. run / serial: ratio of the medians, "
        "(min: of the minima), and the tie rule's verdict (faster or slower only when the spreads over the rounds "
        "do not overlap; with one round a spread is a point)."])
    fig = figure(8.2, 2.6)
    ax = fig.subplots()
    ways = [r["way"] for r in data["rows"]]
    runs = [r["run"]["median"] for r in data["rows"]]
    starts = [0.0 if r["cluster_start"] is None else r["cluster_start"]["median"] for r in data["rows"]]
    ax.barh(ways, runs, color="C0", label="run")
    ax.barh(ways, starts, left=runs, color="C7", label="cluster start")
    ax.axvline(max(r["slowest_s"] for r in data["rows"]), color="C3", ls="--", lw=1, label="slowest robot")
    ax.invert_yaxis()
    ax.set_xlabel(f"wall time (s), {data['robots']} robots")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
    ax.grid(alpha=0.3, axis="x")
    return md, fig


def options(p) -> None:
    p.add_argument("--subset", type=int, help="only the first N robot files (a quick check of the script)")


if __name__ == "__main__":
    # format 1 JSON renders as well: its figures are the same, the tie rule is applied here
    run_benchmark("corpus_wall", __doc__, measure, render, options=options, rounds_default=1, accepts=(1, 2))

"""``urdf2links report --corpus DIR [DIR ...]``: every robot of a corpus against MuJoCo, in parallel.

Finds the robots (:func:`urdf2links.compare.corpus.rows.find_robots`), runs them
(:func:`urdf2links.compare.corpus.runner.run_corpus`: ``--jobs N`` processes here, default every core,
or ``--scheduler ADDRESS`` a Dask cluster), prints one line per finished robot above an overall bar,
and writes the report (:func:`urdf2links.compare.corpus.report.write_corpus`) into ``--out`` (default
``reports/corpus``). With ``<out>/baselines.json`` present (or ``--check FILE``) every compared robot
is checked against its accepted figures (key: its file in the corpus); ``--write-baselines [FILE]``
accepts this run's. Exit 0; 1 when a robot failed or regressed (each named on stderr: a worse
figure, or a robot with a baseline that is no longer compared); 2 on bad arguments.
"""

from __future__ import annotations

from pathlib import Path

from urdf2links.compilation import clock  # durations without numba's compilation
from urdf2links.console import TaskBar, err, shown_path
from urdf2links.locations import DEFAULT_OUT, default_baselines
from urdf2links.scenes.scene_toml import xacro_args_of

from ..reports.baselines import load_baselines, write_baselines
from .report import write_corpus
from .rows import CorpusSettings, RobotResult, find_robots
from .runner import run_corpus

__all__ = ["corpus_command", "regressions", "DEFAULT_CORPUS_OUT", "CORPUS_T_END"]

DEFAULT_CORPUS_OUT = DEFAULT_OUT / "corpus"
#: Length (s) of each robot's default-scene run unless ``--t-end`` says otherwise.
CORPUS_T_END = 0.5
_BASELINES_ABOUT = (
    "Accepted figures of `urdf2links report --corpus` per robot file (its path in the corpus) and run length: "
    "`urdf2links report --corpus DIR --check THIS_FILE` fails, naming the robot and the figure, when a figure grows "
    "past factor x max(baseline, floor) or a robot accepted here is no longer compared. Wall times are recorded, "
    "not checked.")


def _line(res: RobotResult, k: int, total: int) -> str:
    """The progress line of one finished robot."""
    r = res.row
    head = f"[{k}/{total}] {r['file']}: {r['status']}"
    secs = f" ({(r.get('wall_time') or {}).get('total_s', 0.0):.1f} s)"
    if r["status"] == "refused":
        return head + f": {(r['reason'] or '').splitlines()[0][:140]}" + secs
    if r["status"] == "failed":
        return head + f" at {r['stage']}: {(r['reason'] or '').splitlines()[0][:160]}" + secs
    te, tr, en = r["terms"], r["trajectory"], r["energy"]
    r2 = "-" if te["route2"] is None else f"{te['route2']:.1e}"
    text = (f"{head}, n = {r['n']}, terms {te['route1']:.1e} / {r2}"
            + (f" ({te['route2_status']})" if te["route2_status"] not in ("as written", None) else "")
            + f", max |dq| {float(tr['max_abs_error']):.1e}"
            + ("" if tr["divergence_time"] is None else f", diverges at {tr['divergence_time']:.3g} s")
            + f", drift {float(en['project_drift_rel']):.1e} / {float(en['mujoco_drift_rel']):.1e}" + secs)
    if r.get("inertia") == "repair":
        text += " [inertia repaired]"
    chk = r.get("check")
    if chk and chk.get("ok") is False:
        text += f" BASELINE FAILED: {', '.join(chk['failures'])}"
    return text


def regressions(results, baselines: dict | None) -> list[str]:
    """One line per robot that regressed against ``baselines``: a checked figure grew past its
    baseline, or a robot with an accepted entry is not compared any more."""
    if baselines is None:
        return []
    accepted = baselines.get("scenes", {})
    out = []
    for res in results:
        r = res.row
        chk = r.get("check")
        if r["status"] == "compared" and chk and chk.get("ok") is False:
            out.append(f"{r['file']}: {', '.join(chk['failures'])} grew past the baseline")
        elif r["status"] != "compared" and r["file"] in accepted:
            out.append(f"{r['file']}: accepted as compared, now {r['status']}: {(r['reason'] or '').splitlines()[0][:160]}")
    return out


def _baselines(args, out: Path, log):
    """``(baselines or None, path)`` as ``report`` reads them, said on ``log``; OSError/ValueError when
    unreadable."""
    if args.write_baselines:
        return None, None
    path, looked = (Path(args.check), [Path(args.check)]) if args.check else default_baselines(out, sub="corpus")
    if path is None:
        log(f"baselines: none found (looked for {', '.join(shown_path(p) for p in looked)}): the rows are reported, "
            "not checked")
        return None, None
    log(f"baselines: {shown_path(path)} (exit 1 when a robot regresses)")
    return load_baselines(path), path


def _settings(args, baselines, path) -> CorpusSettings:
    return CorpusSettings(t_end=float(args.t_end if args.t_end is not None else CORPUS_T_END), seed=int(args.seed),
                          states=int(args.states), mujoco_integrator=args.mujoco_integrator,
                          mujoco_dt=float(args.mujoco_dt), package_dirs=tuple(str(p) for p in args.package_dir),
                          inertia=args.inertia or "audit", mimic=args.mimic or "independent", strict=bool(args.strict),
                          floating_base=bool(args.floating), xacro_args=xacro_args_of(args),
                          thumbnails=not args.no_thumbnails,
                          baselines=baselines, factor=args.factor,
                          baselines_source=shown_path(path) if baselines is not None else "")


def _command(args) -> str:
    parts = ["urdf2links report --corpus", *(shown_path(p) if Path(p).exists() else p for p in args.corpus)]
    for flag, value, default in (("--out", args.out, None), ("--t-end", args.t_end, None), ("--seed", args.seed, 0),
                                 ("--states", args.states, 8), ("--mujoco-integrator", args.mujoco_integrator, "RK4"),
                                 ("--mujoco-dt", args.mujoco_dt, 1e-4)):
        if value is not None and value != default:
            parts.append(f"{flag} {value:g}" if isinstance(value, float) else f"{flag} {value}")
    return " ".join(parts)


def _run(args, robots, settings, bar) -> tuple[list[RobotResult], dict]:
    """Run the robots where the arguments say; the results and what ``corpus.json`` records of the run."""
    count = {"k": 0}

    def done(res):
        count["k"] += 1
        bar.line(_line(res, count["k"], len(robots)))

    log = (lambda m: bar.line(m, advance=False))
    start, timing = clock(), {}
    if args.scheduler:
        from urdf2links.integration.distributed import connect, worker_count

        if args.jobs is not None:
            log(f"--jobs {args.jobs} ignored: with --scheduler the cluster's workers run the robots")
        client = connect(args.scheduler)
        try:
            how = f"on the Dask cluster at {args.scheduler} ({worker_count(client)} workers)"
            log(f"running {len(robots)} robots {how}")
            results = run_corpus(robots, settings, client=client, on_result=done, log=log, timing=timing)
        finally:
            client.close()
    else:
        from urdf2links.integration.distributed import cores

        jobs = args.jobs or cores()
        how = "in this process" if jobs == 1 else f"in {jobs} processes"
        log(f"running {len(robots)} robots {how}")
        results = run_corpus(robots, settings, jobs=jobs, on_result=done, log=log, timing=timing)
    # the workers' warm-up (numba's compilation in a fresh installation) is left out, as every other time
    return results, {"how": how, "wall_s": clock() - start - timing.get("warm_s", 0.0),
                     "warm_up_s": timing.get("warm_s", 0.0)}


def corpus_command(args) -> int:
    if args.scenes:
        err("urdf2links report: error: give scene files or --corpus, not both")
        return 2
    out = Path(args.out) if args.out else DEFAULT_CORPUS_OUT
    try:
        robots = find_robots(args.corpus)
        baselines, bpath = _baselines(args, out, err)
    except (OSError, ValueError) as exc:
        err(f"urdf2links report: error: {exc}")
        return 2
    settings = _settings(args, baselines, bpath)
    bar = TaskBar(len(robots), label="corpus", enabled=not args.quiet)
    try:
        results, run = _run(args, robots, settings, bar)
    except (ImportError, OSError) as exc:
        bar.close()
        err(f"urdf2links report: error: {exc}")
        return 2
    bar.close()
    paths = write_corpus(results, out, settings=settings.describe(), run=run, command=_command(args),
                         nested=(out.parent / "index.html").is_file())
    if args.write_baselines:
        target = out / "baselines.json" if args.write_baselines is True else Path(args.write_baselines)
        accepted = [r.summary for r in results if r.summary is not None]
        err(f"wrote {shown_path(write_baselines(accepted, target, factor=args.factor, about=_BASELINES_ABOUT))} "
            f"({len(accepted)} robots)")
    c = paths["data"]["counts"]
    print(f"{shown_path(paths['html'])}: {c['robots']} robots, {c['compared']} compared, {c['refused']} refused, "
          f"{c['failed']} failed, {run['how']} in {run['wall_s']:.0f} s (warm-up before it: {run['warm_up_s']:.0f} s; "
          "corpus.json, corpus.md)")
    failed = [r.row for r in results if r.row["status"] == "failed"]
    for r in failed:
        err(f"urdf2links report: {r['file']} failed at {r['stage']}: {(r['reason'] or '').splitlines()[0][:200]}")
    regressed = regressions(results, baselines)
    for line in regressed:
        err(f"urdf2links report: regression: {line}")
    return 1 if (failed or regressed) else 0

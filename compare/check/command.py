"""``urdf2links check [PATH]``: the robots, pairs and scenes of a repository's configuration, checked.

:func:`run_check` reads the configuration (:func:`~urdf2links.compare.check.config.read_config`), keeps the
cases that depend on files changed since a git commit (``changed_since``,
:func:`~urdf2links.compare.check.depends.changed_files`), runs them here or in ``jobs`` processes
(:func:`run_cases`), writes the scenes' baselines when asked and returns a :class:`CheckRun`.
:func:`check_command` is the command: ``--init`` (:mod:`~urdf2links.compare.check.init`), ``--write-workflow``
(:mod:`~urdf2links.compare.check.workflow`), then the check, ``--junit``, ``--markdown``; exit 0 when every
check holds, 1 when one falls short, 2 when the configuration or a file cannot be used.
"""

from __future__ import annotations

import multiprocessing
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

from urdf2links import compilation
from urdf2links.console import err, shown_path

from ..reports.baselines import load_baselines, write_baselines
from .cases import Case, CaseResult, RunContext, cases_of, run_case
from .config import CheckConfig, ConfigError, read_config
from .depends import changed_files
from .fingerprint import write_fingerprints
from .init import leave_out_scenes, no_evidence
from .outputs import exit_status, ordered, verdict, write_junit, write_markdown

__all__ = ["CheckRun", "run_check", "run_cases", "check_command"]

_BASELINES_ABOUT = (
    "Accepted figures of the scenes of `urdf2links check` (key: the scene file, or the robot file of a default "
    "scene): a scene fails when a figure grows past factor x max(baseline, floor) or its divergence comes earlier "
    "than the baseline's by more than ln(factor) / growth rate. fingerprints: each robot file's dynamic parameters "
    "by name (compare/check/fingerprint.py); a robot fails when one changed. `urdf2links check --write-baselines` "
    "accepts a run's.")


@dataclass
class CheckRun:
    """One run: the ``config``, its ``results`` (one per case run), ``skipped`` (cases left out by
    ``--changed-since``), ``note`` (what was run and why), the ``baselines`` file written (or None)."""

    config: CheckConfig
    results: list[CaseResult] = field(default_factory=list)
    skipped: list[Case] = field(default_factory=list)
    note: str = ""
    baselines: Path | None = None

    @property
    def status(self) -> int:
        return exit_status(self.results)


def run_cases(cases: list[Case], ctx: RunContext, *, jobs: int = 1,
              on_result: Callable[[CaseResult], None] | None = None) -> list[CaseResult]:
    """Every case, in this process (``jobs`` 1) or in ``jobs`` fresh processes; results in the cases' order.
    A worker process's compilation is counted with this process's (:func:`urdf2links.compilation.elsewhere`),
    so that the command shows it once; each case's seconds leave it out."""
    done = on_result or (lambda r: None)
    if jobs <= 1 or len(cases) <= 1:
        out = []
        for c in cases:
            out.append(run_case(c, ctx))
            done(out[-1])
        return out
    with ProcessPoolExecutor(max_workers=min(jobs, len(cases)), mp_context=multiprocessing.get_context("spawn")) as ex:
        futures = [ex.submit(run_case, c, ctx) for c in cases]
        out = []
        for f in futures:
            out.append(f.result())
            compilation.elsewhere(*out[-1].compiled)
            done(out[-1])
        return out


def _context(config: CheckConfig, write: bool, open_loops: bool = False) -> RunContext:
    baselines = None
    if config.baselines.is_file():
        baselines = load_baselines(config.baselines)
    return RunContext(baselines, shown_path(config.baselines), config.factor, write, open_loops)


def run_check(path=".", *, changed_since: str | None = None, jobs: int = 1, write: bool = False,
              open_loops: bool = False,
              on_result: Callable[[CaseResult], None] | None = None) -> CheckRun:
    """The check of the configuration that holds for ``path`` (module doc); ``write``: accept the scenes' figures
    as their baselines. ConfigError, ValueError (a git reference), OSError: cannot be used (exit 2)."""
    config = read_config(path)
    every = cases_of(config)
    cases, note = every, f"{len(every)} checks from {shown_path(config.source)}"
    if changed_since:
        changed = changed_files(changed_since, config.root)
        cases = cases_of(config, only=changed)
        note = (f"{len(cases)} of {len(every)} checks from {shown_path(config.source)}: those that depend on the "
                f"{len(changed)} file(s) changed since {changed_since}")
    run = CheckRun(config, skipped=[c for c in every if c not in cases], note=note)
    run.results = run_cases(cases, _context(config, write, open_loops), jobs=jobs, on_result=on_result)
    if write:
        accepted = [r.summary for r in run.results if r.summary is not None and no_evidence(r.summary) is None]
        run.baselines = write_baselines(accepted, config.baselines, factor=config.factor, about=_BASELINES_ABOUT)
        write_fingerprints(run.baselines, {r.case.entry.id: r.fingerprint for r in run.results
                                           if r.fingerprint is not None})
    return run


def _line(r: CaseResult) -> str:
    mark = {"pass": "ok   ", "fail": "FAIL ", "error": "ERROR"}[r.status]
    head = f"{mark} {r.case.kind:<5} {r.case.name} ({r.seconds:.1f} s)"
    return head + "".join(f"\n        {p.text}" for p in sorted(r.problems, key=lambda p: -p.ratio))


def _leave_out_no_evidence(run: CheckRun) -> None:
    """After --init: the default scenes whose runs are no evidence (:func:`~.init.no_evidence`) are left out of
    the configuration just written, said, and not counted in this run's verdict."""
    why = {r.case.entry.robot.id: no_evidence(r.summary) for r in run.results
           if r.case.kind == "scene" and r.case.entry.robot is not None and no_evidence(r.summary)}
    if why:
        leave_out_scenes(run.config.source, why, log=err)
        run.results = [r for r in run.results if not (r.case.kind == "scene" and r.case.entry.robot is not None
                                                      and r.case.entry.robot.id in why)]
        run.note += f"; {len(why)} default scene(s) left out (no evidence to accept)"


def check_command(args) -> int:
    """``urdf2links check`` (module doc)."""
    folder = Path(args.path)
    if getattr(args, "source", None) and not args.write_workflow:
        err("urdf2links check: error: --from goes with --write-workflow (where the workflow installs urdf2links)")
        return 2
    if args.write_workflow:
        from .workflow import write_workflow

        try:
            target, src = write_workflow(folder, None if args.write_workflow is True else args.write_workflow,
                                         source=getattr(args, "source", None))
        except ValueError as exc:
            err(f"urdf2links check: error: {exc}")
            return 2
        print(f"wrote {shown_path(target)}: commit it; the check runs on every push and pull request (docs/ci.md)")
        if src.placeholder:
            err(f"urdf2links check: {shown_path(target)} installs urdf2links from URDF2LINKS_SOURCE, which is a "
                "placeholder (SET-ME): set it to urdf2links' repository at a commit, or remove the file and write it "
                "again with --from GIT_URL@COMMIT or --from PATH (docs/ci.md)")
        else:
            print(f"it installs {src.requirement} (from {src.how})")
        if not args.init:
            return 0
    write = bool(args.write_baselines)
    if args.init:
        from .init import init_config

        init_config(folder, log=err)
        write = True
    try:
        run = run_check(folder, changed_since=args.changed_since, jobs=args.jobs or 1, write=write,
                        open_loops=bool(getattr(args, "open_loops", False)),
                        on_result=None if args.quiet else (lambda r: print(_line(r), flush=True)))
    except ConfigError as exc:
        err(f"urdf2links check: error: {exc}")
        return 2
    if args.init:
        _leave_out_no_evidence(run)
    err(f"urdf2links check: {run.note}")
    if run.baselines is not None:
        err(f"wrote {shown_path(run.baselines)}: the accepted figures of "
            f"{sum(r.summary is not None for r in run.results)} scene(s), the fingerprints of "
            f"{sum(r.fingerprint is not None for r in run.results)} robot file(s)")
    if args.junit:
        err(f"wrote {shown_path(write_junit(run.results, args.junit))}")
    if args.markdown:
        err(f"wrote {shown_path(write_markdown(run.results, args.markdown, note=run.note))}")
    print(verdict(run.results))
    for r in ordered(run.results):
        print(f"  {r.case.kind} {r.case.name}: {r.message().splitlines()[0]}")
    return run.status

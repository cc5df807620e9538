"""The cases of ``urdf2links check``: one per robot, pair and scene, each run alone into a :class:`CaseResult`.

* a **robot** (:func:`check_robot`): loaded with its options (:func:`urdf2links.parsers.robot_file.load_robot`);
  an error if it cannot be, a failure for each inertia finding of the audit its entry does not allow, and for
  each dynamic parameter that changed since its fingerprint was accepted
  (:mod:`~urdf2links.compare.check.fingerprint`, the baselines' ``fingerprints``);
* a **pair** (:func:`check_pair`): both files compared part by part
  (:func:`~urdf2links.compare.pairs.pair.compare_descriptions_of`); a failure for each difference its
  ``accepted`` table does not accept by name, each accepted one that moved past its own tolerance, each accepted
  one that is gone (:func:`~urdf2links.compare.check.accepted.judge`), and the mapped terms A, G past theirs;
* a **scene** (:func:`check_scene`): a scene file, or a robot's default scene
  (:func:`urdf2links.scenes.default_scenes.default_scene`, ``q0 = "excite"`` unless the entry says), run by both engines
  (:func:`~urdf2links.compare.agreement.trajectory.compare_scene`) and checked against its accepted figures
  (:func:`~urdf2links.compare.reports.baselines.check_baseline`, key: the case's file); a scene without one
  fails, unless the run writes the baselines; a run with weak evidence (E67: most coordinates barely moved) fails.

A case never raises: a file that cannot be used is an ``error`` (exit 2), a check that falls short a ``fail``
(exit 1). Every problem carries its ``ratio`` (value over tolerance), the order of the summaries.
"""

from __future__ import annotations

import math
import traceback
import warnings
from dataclasses import dataclass, field
from pathlib import Path

from urdf2links import compilation
from urdf2links.errors import DescriptionError, DynamicsError, IntegrationError, SceneError, URDFError

from ..formatting import get, json_ready
from .config import PairEntry, RobotEntry, SceneEntry

__all__ = ["Case", "CaseResult", "Problem", "RunContext", "run_case", "cases_of", "pair_summary", "check_robot",
           "check_pair", "check_scene", "STATUSES"]

#: What a case's ``status`` can be, worst last.
STATUSES = ("pass", "fail", "error")
#: Errors that say a file cannot be used (the rest are faults of urdf2links or MuJoCo, reported as such).
_FILE_ERRORS = (DescriptionError, SceneError, DynamicsError, IntegrationError, ValueError, OSError)


@dataclass(frozen=True)
class Case:
    """One check: ``kind`` (``robot``, ``pair``, ``scene``), ``name`` (its file; a pair: both), ``file`` (the
    file it is named after: the robot, the pair's second description, the scene file or robot) and ``entry``."""

    kind: str
    name: str
    file: str
    entry: RobotEntry | PairEntry | SceneEntry


@dataclass
class Problem:
    """One thing that falls short: ``text`` (names the file, link or joint, the value and the tolerance),
    ``ratio`` (value over tolerance; inf when there is no measure, e.g. an inertia finding or an error)."""

    text: str
    ratio: float = math.inf


@dataclass
class CaseResult:
    """A case's outcome: ``status`` (:data:`STATUSES`), its ``problems``, ``lines`` (what was checked),
    ``seconds`` (numba's compilation left out: :func:`urdf2links.compilation.clock`), ``compiled`` (the
    seconds and functions numba compiled during the case, shown apart, once), for a scene its comparison
    ``summary`` (the baselines' entry), for a robot its ``fingerprint``."""

    case: Case
    status: str = "pass"
    problems: list[Problem] = field(default_factory=list)
    lines: list[str] = field(default_factory=list)
    seconds: float = 0.0
    summary: dict | None = None
    fingerprint: dict | None = None
    compiled: tuple = (0.0, [])

    @property
    def worst(self) -> float:
        """The largest problem's ratio (0 when it passed)."""
        return max((p.ratio for p in self.problems), default=0.0)

    def message(self) -> str:
        """The problems, largest first, one per line (what a failing test says)."""
        return "\n".join(p.text for p in sorted(self.problems, key=lambda p: -p.ratio))


@dataclass(frozen=True)
class RunContext:
    """What every case of one run shares: the parsed ``baselines`` (or None), their ``source``, ``factor``
    and ``writing`` (``--write-baselines``: a scene without an accepted entry passes)."""

    baselines: dict | None = None
    source: str = ""
    factor: float | None = None
    writing: bool = False
    open_loops: bool = False
    """``--open-loops`` (issue 45): every scene's file equalities, fixed tendons and mimic constraints dropped."""


def _load(robot: RobotEntry, **extra):
    from urdf2links.parsers.robot_file import is_mjcf_path, load_robot

    load = dict(robot.load)
    if is_mjcf_path(robot.path):   # an MJCF file says itself how its bodies move; only these options are its own
        load = {k: v for k, v in load.items() if k in ("inertia", "strict")}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")   # the findings are the case's
        return load_robot(robot.path, **load, **extra)


def check_robot(res: CaseResult, robot: RobotEntry, ctx: RunContext = RunContext()) -> None:
    """A robot loads, its inertia audit finds nothing its entry does not allow, and its dynamic parameters are
    those of its accepted fingerprint."""
    model = _load(robot)
    res.lines.append(f"{robot.id}: robot {model.name!r}, {model.tree.n_links} links, {model.n} coordinates, "
                     f"{len(model.audit)} inertia finding(s)")
    for text in model.info.get("missing_files", ()):      # issue 42: a mesh the file names that is not there
        res.problems.append(Problem(text))
    for r in model.audit:
        allowed = robot.allow is True or r.link in (robot.allow or ())
        line = f"{robot.id}: link {r.link}: inertia {r.kind}: {r.message}" + (f" ({r.fix})" if r.fix else "")
        if allowed:
            res.lines.append(f"allowed: {line}")
        else:
            res.problems.append(Problem(line + " (allow it with allow_inertia_findings)"))
    _check_fingerprint(res, robot, ctx)


def _check_fingerprint(res: CaseResult, robot: RobotEntry, ctx: RunContext) -> None:
    from .fingerprint import ACCEPT, changes, fingerprint

    res.fingerprint = now = fingerprint(robot.path, load=robot.load)
    if ctx.writing:
        res.lines.append(f"{robot.id}: its fingerprint accepted (--write-baselines)")
        return
    old = ((ctx.baselines or {}).get("fingerprints") or {}).get(robot.id)
    if old is None:
        res.problems.append(Problem(f"{robot.id}: no accepted fingerprint of its dynamic parameters in "
                                    f"{ctx.source or 'the baselines'}: {ACCEPT}"))
        return
    found = changes(old, now)
    res.lines.append(f"{robot.id}: {len(found)} change(s) since its fingerprint was accepted")
    res.problems += [Problem(c.text(robot.id), c.ratio) for c in found]


def _value(v, unit: str) -> str:
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_value(x, "") for x in v) + "]" + (f" {unit}" if unit else "")
    if isinstance(v, (int, float)) and not isinstance(v, bool):
        return f"{v:.6g}"
    return str(v)


def _row(row) -> str:
    from .accepted import rows_toml

    return rows_toml([row], indent="")[1].rstrip(",")


def _row_text(p, pair: PairEntry) -> str:
    """A pair's problem (:class:`~urdf2links.compare.check.accepted.RowProblem`) in words: the kind, the part,
    both values and their files, what moved, and the row that accepts it now."""
    u, m = pair.urdf.id, pair.mjcf.id
    if p.what == "gone":
        r = p.row
        return (f"{m}: the accepted {r.kind} of {r.part} ({_value(r.urdf, '')} in {u}, {_value(r.mjcf, '')} in {m}) "
                f"is gone: the files agree there now; remove its row from the pair's accepted table")
    d, now = p.difference, p.replacement
    head = f"{m}: {d['kind']} of {now.part}: {_value(now.urdf, '')} in {u}, {_value(now.mjcf, '')} in {m} ({d['what']})"
    if p.what == "new":
        text = (f"{head}; difference {_value(now.difference, '')} {now.unit}, not accepted; to accept it, add to "
                f"the pair's accepted table: {_row(now)}")
    else:
        r = p.row
        text = (f"{head}; accepted {_value(r.urdf, '')} and {_value(r.mjcf, '')}, difference "
                f"{_value(r.difference, '')} {r.unit}: {p.detail} moved by {p.moved:.4g} > its tolerance "
                f"{p.allowed:g}; to accept it, replace its row with: {_row(now)}")
    return text + (f"; known cause: {d['explanation']}" if d.get("explanation") else "")


def pair_summary(pair: PairEntry) -> dict:
    """Both descriptions of ``pair`` compared part by part: the summary (JSON-ready,
    :meth:`~urdf2links.compare.pairs.pair.PairComparison.summary`)."""
    from ..pairs.pair import compare_descriptions_of

    load = {k: v for k, v in pair.urdf.load.items() if k in ("floating_base", "package_dirs", "strict", "xacro_args")}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        p = compare_descriptions_of(pair.urdf.path, pair.mjcf.path, explicit_map=pair.map, load=load,
                                    states=pair.states, seed=pair.seed)
    return json_ready(p.summary())


def check_pair(res: CaseResult, pair: PairEntry) -> None:
    """Both descriptions compared part by part, against the accepted differences and the terms' tolerances."""
    from ..pairs.differences import ROUNDING
    from .accepted import judge

    summary = pair_summary(pair)
    jm = summary["joint_mapping"]
    res.lines.append(f"{pair.urdf.id} against {pair.mjcf.id}: {len(jm['matched'])} joints matched, "
                     f"{len(summary['description_differences'])} difference(s) above rounding, "
                     f"{len(pair.accepted)} accepted")
    for p in judge(summary, pair.accepted):
        if p.what == "new":
            tol, diff = ROUNDING.get(p.replacement.kind, 0.0), p.replacement.difference
            ratio = diff / tol if tol > 0 and math.isfinite(diff) else math.inf
        else:
            ratio = p.ratio
        res.problems.append(Problem(_row_text(p, pair), ratio))
    eff = summary["description_effects"]["mapped"]
    for term, limit in pair.tolerances.items():
        value = eff[term]["max_rel_difference"]
        value = math.inf if value in ("inf", "nan") else float(value)
        if not value <= limit:
            res.problems.append(Problem(f"{pair.mjcf.id}: {term} (mapped, against {pair.urdf.id}): max relative "
                                        f"difference {value:.4g} > tolerance {limit:g}",
                                        math.inf if limit == 0 else value / limit))


def _scene(entry: SceneEntry, open_loops: bool = False):
    from urdf2links.scenes.default_scenes import default_scene
    from urdf2links.scenes.file_constraints import open_loops as opened
    from urdf2links.scenes.scene_read import load_scene

    if entry.path is not None:
        return opened(load_scene(entry.path)) if open_loops else load_scene(entry.path)
    load = dict(entry.robot.load)
    return default_scene(entry.robot.path, t_end=entry.t_end, q0=entry.q0, seed=entry.seed,
                         floating=load.pop("floating_base", False), open_loops=open_loops, **load)


def check_scene(res: CaseResult, entry: SceneEntry, ctx: RunContext) -> None:
    """The scene run by both engines and checked against its accepted figures."""
    from ..agreement.trajectory import compare_scene
    from ..reports.baselines import check_baseline

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        c = compare_scene(_scene(entry, ctx.open_loops), progress=False, log=lambda m: None)
    summary = json_ready(c.summary())
    summary["key"] = entry.id
    res.summary = summary
    res.lines.append(f"{entry.id}: t = 0..{summary['t_end']:g} s, terms {get(summary, 'terms.max_rel_error'):.2e}, "
                     f"max |dq| {float(get(summary, 'trajectory.max_abs_error')):.2e}")
    gate = summary.get("plausibility") or {}
    if not gate.get("plausible", True):     # issue 43: no figure of an implausible run is evidence
        res.problems.append(Problem(f"{entry.id}: {gate['text']}"))
    cov = summary.get("coverage") or {}
    if cov.get("weak_evidence"):
        res.problems.append(Problem(f"{entry.id}: weak evidence: {cov.get('text', '')}; start the run where every "
                                    "coordinate moves (q0 = \"excite\", the default) or run it longer (t_end)"))
    if ctx.writing:
        res.lines.append("accepted as its baseline (--write-baselines)")
        return
    if ctx.baselines is None or entry.id not in ctx.baselines.get("scenes", {}):
        res.problems.append(Problem(f"{entry.id}: no accepted figures in {ctx.source or 'the baselines'}: run "
                                    "`urdf2links check --write-baselines` to accept this run's"))
        return
    chk = check_baseline(summary, ctx.baselines, factor=ctx.factor, source=ctx.source)
    res.lines += chk.lines
    for name in chk.failures:
        line = next((x for x in chk.lines if x.startswith(f"FAIL  {name}")), name)
        res.problems.append(Problem(f"{entry.id}: {line.removeprefix('FAIL  ')}", chk.ratios.get(name, math.inf)))


def run_case(case: Case, ctx: RunContext = RunContext()) -> CaseResult:
    """Run one case (module doc); never raises."""
    res = CaseResult(case)
    start, before = compilation.clock(), compilation.snapshot()     # the user's seconds leave compilation out
    try:
        if case.kind == "robot":
            check_robot(res, case.entry, ctx)
        elif case.kind == "pair":
            check_pair(res, case.entry)
        else:
            check_scene(res, case.entry, ctx)
        res.status = "fail" if res.problems else "pass"
    except _FILE_ERRORS as exc:
        res.status = "error"
        res.problems.append(Problem(f"{_blamed(case, exc)}: cannot be used: {type(exc).__name__}: {exc}"))
    except Exception as exc:  # noqa: BLE001 -- one case's fault must not hide the others
        res.status = "error"
        tb = "".join(traceback.format_exception(exc)[-4:])
        res.problems.append(Problem(f"{case.file}: internal error of urdf2links ({type(exc).__name__}: {exc})\n{tb}"))
    res.seconds = compilation.clock() - start
    res.compiled = before.since()
    return res


def _blamed(case: Case, exc: BaseException) -> str:
    """The file an error of ``case`` belongs to: for a pair, the description its message names (a URDF's missing
    mesh is the URDF's, issue 42), the URDF for an error of the URDF reader; else the case's file."""
    if case.kind != "pair":
        return case.file
    text = str(exc)
    for r in (case.entry.urdf, case.entry.mjcf):
        if str(r.path) in text or r.id in text:
            return r.id
    return case.entry.urdf.id if isinstance(exc, URDFError) else case.file


def cases_of(config, *, only=None) -> list[Case]:
    """Every case of ``config`` (a :class:`~urdf2links.compare.check.config.CheckConfig`): robots, pairs,
    scenes, in the configuration's order; ``only`` (a set of absolute paths, ``--changed-since``): only the
    cases that depend on one of them (:func:`~urdf2links.compare.check.depends.robot_files`)."""
    from .depends import robot_files

    out = [Case("robot", r.id, r.id, r) for r in config.robots]
    out += [Case("pair", f"{p.urdf.id} against {p.mjcf.id}", p.mjcf.id, p) for p in config.pairs]
    out += [Case("scene", s.id if s.path is not None else f"{s.id} (default scene)", s.id, s) for s in config.scenes]
    if only is None:
        return out
    if Path(config.source).resolve() in only:
        return out
    memo: dict[Path, set] = {}

    def files(robot: RobotEntry) -> set:
        if robot.path not in memo:
            memo[robot.path] = robot_files(robot.path, robot.load)
        return memo[robot.path]

    def depends(case: Case) -> set:
        e = case.entry
        if case.kind == "robot":
            return files(e)
        if case.kind == "pair":
            return files(e.urdf) | files(e.mjcf)
        if e.robot is not None:
            return files(e.robot)
        return {e.path} | _scene_robot_files(e.path, config)

    baselines = Path(config.baselines).resolve() in only   # a changed baselines file: every scene and robot again
    return [c for c in out if (baselines and c.kind in ("scene", "robot")) or depends(c) & only]


def _scene_robot_files(path: Path, config) -> set:
    from urdf2links.scenes.scene_read import load_scene

    from .depends import robot_files

    try:
        scene = load_scene(path)
    except Exception:  # noqa: BLE001 -- the case itself will say why the scene cannot be read
        return set()
    robot = next((r for r in config.robots if r.path == Path(scene.robot).resolve()), None)
    return robot_files(scene.robot, robot.load if robot else scene.load_options)

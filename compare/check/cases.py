"""The cases of ``urdf2links check``: one per robot, pair and scene, each run alone into a :class:`CaseResult`.

* a **robot** (:func:`check_robot`): loaded with its options (:func:`urdf2links.parsers.robot_file.load_robot`);
  an error if it cannot be, a failure for each inertia finding of the audit its entry does not allow;
* a **pair** (:func:`check_pair`): both files compared part by part
  (:func:`~urdf2links.compare.pairs.pair.compare_descriptions_of`); a failure for each difference past its
  tolerance (:func:`~urdf2links.compare.pairs.pair.exceedances`: every kind the comparison reports, the
  difference kinds of the pair comparison as they are, and A, G), naming the link or joint and both values;
* a **scene** (:func:`check_scene`): a scene file, or a robot's default scene
  (:func:`urdf2links.scenes.scene.default_scene`), run by both engines
  (:func:`~urdf2links.compare.agreement.trajectory.compare_scene`) and checked against its accepted figures
  (:func:`~urdf2links.compare.reports.baselines.check_baseline`, key: the case's file); a scene without one
  fails, unless the run writes the baselines.

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
from urdf2links.errors import DescriptionError, DynamicsError, IntegrationError, SceneError

from ..formatting import get, json_ready
from .config import PairEntry, RobotEntry, SceneEntry

__all__ = ["Case", "CaseResult", "Problem", "RunContext", "run_case", "cases_of", "pair_exceedances", "check_robot", "check_pair",
           "check_scene", "STATUSES"]

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
    seconds and functions numba compiled during the case, shown apart, once) and, for a scene, its comparison
    ``summary`` (the baselines' entry)."""

    case: Case
    status: str = "pass"
    problems: list[Problem] = field(default_factory=list)
    lines: list[str] = field(default_factory=list)
    seconds: float = 0.0
    summary: dict | None = None
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


def _load(robot: RobotEntry, **extra):
    from urdf2links.parsers.robot_file import is_mjcf_path, load_robot

    load = dict(robot.load)
    if is_mjcf_path(robot.path):   # an MJCF file says itself how its bodies move; only these options are its own
        load = {k: v for k, v in load.items() if k in ("inertia", "strict")}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")   # the findings are the case's
        return load_robot(robot.path, **load, **extra)


def check_robot(res: CaseResult, robot: RobotEntry) -> None:
    """A robot loads, and its inertia audit finds nothing its entry does not allow."""
    model = _load(robot)
    res.lines.append(f"{robot.id}: robot {model.name!r}, {model.tree.n_links} links, {model.n} coordinates, "
                     f"{len(model.audit)} inertia finding(s)")
    for r in model.audit:
        allowed = robot.allow is True or r.link in (robot.allow or ())
        line = f"{robot.id}: link {r.link}: inertia {r.kind}: {r.message}" + (f" ({r.fix})" if r.fix else "")
        if allowed:
            res.lines.append(f"allowed: {line}")
        else:
            res.problems.append(Problem(line + " (allow it with allow_inertia_findings)"))


def _value(v, unit: str) -> str:
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_value(x, "") for x in v) + "]" + (f" {unit}" if unit else "")
    if isinstance(v, (int, float)) and not isinstance(v, bool):
        return f"{v:.6g}"
    return str(v)


def _where(d: dict) -> str:
    links = [n for n in dict.fromkeys(d.get("links") or ()) if n]
    joints = [n for n in dict.fromkeys((d.get("urdf"), d.get("mjcf"))) if n]
    out = f"link {' / '.join(links)}" if links else ""
    if joints and joints != links:
        out += (" (joint " if out else "joint ") + " / ".join(joints) + (")" if out else "")
    return out or "-"


def _difference_text(e: dict, pair: PairEntry) -> str:
    """A difference past its tolerance in words: the kind, where, both values and their files, the tolerance."""
    d = e["difference"]
    unit = d.get("unit", "")
    text = (f"{pair.mjcf.id}: {d['kind']} of {_where(d)}: {_value(d.get('urdf_value'), '')} in {pair.urdf.id}, "
            f"{_value(d.get('mjcf_value'), '')} in {pair.mjcf.id} ({d.get('what', '')}); difference "
            f"{e['value']:.4g} {unit} > tolerance {e['limit']:g}")
    return text + (f"; known cause: {d['explanation']}" if d.get("explanation") else "")


def pair_exceedances(pair: PairEntry) -> tuple[dict, list[dict]]:
    """Both descriptions of ``pair`` compared part by part: the summary (JSON-ready) and what exceeds the pair's
    tolerances (:func:`~urdf2links.compare.pairs.pair.exceedances`)."""
    from ..pairs.pair import compare_descriptions_of, exceedances

    load = {k: v for k, v in pair.urdf.load.items() if k in ("floating_base", "package_dirs", "strict", "xacro_args")}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        p = compare_descriptions_of(pair.urdf.path, pair.mjcf.path, explicit_map=pair.map, load=load,
                                    states=pair.states, seed=pair.seed)
    summary = json_ready(p.summary())
    return summary, exceedances(summary, pair.tolerances)


def check_pair(res: CaseResult, pair: PairEntry) -> None:
    """Both descriptions compared part by part; every difference past its tolerance is a problem."""
    summary, past = pair_exceedances(pair)
    jm = summary["joint_mapping"]
    res.lines.append(f"{pair.urdf.id} against {pair.mjcf.id}: {len(jm['matched'])} joints matched, "
                     f"{len(summary['description_differences'])} difference(s) above rounding")
    for e in past:
        limit = e["limit"]
        ratio = math.inf if limit == 0 else e["value"] / limit
        text = (_difference_text(e, pair) if "difference" in e
                else f"{pair.mjcf.id}: {e['text']} (against {pair.urdf.id})")
        res.problems.append(Problem(text, ratio))


def _scene(entry: SceneEntry):
    from urdf2links.scenes.scene import default_scene, load_scene

    if entry.path is not None:
        return load_scene(entry.path)
    load = dict(entry.robot.load)
    return default_scene(entry.robot.path, t_end=entry.t_end, q0=entry.q0, seed=entry.seed,
                         floating=load.pop("floating_base", False), **load)


def check_scene(res: CaseResult, entry: SceneEntry, ctx: RunContext) -> None:
    """The scene run by both engines and checked against its accepted figures."""
    from ..agreement.trajectory import compare_scene
    from ..reports.baselines import check_baseline

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        c = compare_scene(_scene(entry), progress=False, log=lambda m: None)
    summary = json_ready(c.summary())
    summary["key"] = entry.id
    res.summary = summary
    res.lines.append(f"{entry.id}: t = 0..{summary['t_end']:g} s, terms {get(summary, 'terms.max_rel_error'):.2e}, "
                     f"max |dq| {float(get(summary, 'trajectory.max_abs_error')):.2e}")
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
            check_robot(res, case.entry)
        elif case.kind == "pair":
            check_pair(res, case.entry)
        else:
            check_scene(res, case.entry, ctx)
        res.status = "fail" if res.problems else "pass"
    except _FILE_ERRORS as exc:
        res.status = "error"
        res.problems.append(Problem(f"{case.file}: cannot be used: {type(exc).__name__}: {exc}"))
    except Exception as exc:  # noqa: BLE001 -- one case's fault must not hide the others
        res.status = "error"
        tb = "".join(traceback.format_exception(exc)[-4:])
        res.problems.append(Problem(f"{case.file}: internal error of urdf2links ({type(exc).__name__}: {exc})\n{tb}"))
    res.seconds = compilation.clock() - start
    res.compiled = before.since()
    return res


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

    baselines = Path(config.baselines).resolve() in only   # a changed baselines file: every scene again
    return [c for c in out if (baselines and c.kind == "scene") or depends(c) & only]


def _scene_robot_files(path: Path, config) -> set:
    from urdf2links.scenes.scene import load_scene

    from .depends import robot_files

    try:
        scene = load_scene(path)
    except Exception:  # noqa: BLE001 -- the case itself will say why the scene cannot be read
        return set()
    robot = next((r for r in config.robots if r.path == Path(scene.robot).resolve()), None)
    return robot_files(scene.robot, robot.load if robot else scene.load_options)

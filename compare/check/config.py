"""The configuration of ``urdf2links check``: ``[tool.urdf2links]`` in ``pyproject.toml``, or ``urdf2links.toml``.

:func:`find_config` looks in the folder given and its ancestors (up to the repository's root, the folder
holding ``.git``) for ``urdf2links.toml`` or a ``pyproject.toml`` with a ``[tool.urdf2links]`` table;
:func:`read_config` checks every key (a :class:`ConfigError` names the file, the table and the key) and
expands the globs into a :class:`CheckConfig`. Schema (``urdf2links.toml`` holds the same keys at its top
level; every path is relative to the configuration's folder, docs/ci.md)::

    [tool.urdf2links]
    baselines = "urdf2links-baselines.json"   # the scenes' accepted figures (check --write-baselines)
    factor = 10                               # allowed growth of a scene's figure over its baseline
    tolerances = { A = 1e-3 }                 # every pair's bounds on the mapped terms A and G (pairs add theirs)

    [[tool.urdf2links.robots]]
    files = ["robots/*.urdf", "robots/**/*.xml"]   # globs of .urdf, .xacro and MJCF .xml files
    floating_base = false                          # loading options, as on the command line
    package_dirs = ["robots"]
    xacro_args = { prefix = "left_" }
    inertia = "audit"                              # audit | strict | repair
    mimic = "independent"                          # independent | coupled
    strict = false
    allow_inertia_findings = false                 # true, or the links whose findings are accepted

    [[tool.urdf2links.pairs]]
    urdf = "robots/arm.urdf"                  # the first description
    mjcf = "robots/arm.xml"                   # the second
    map = { shoulder = "joint1" }             # joints whose names differ
    tolerances = { A = 1e-3 }                 # A and G: the mapped terms' largest relative difference
    states = 8                                # seeded states of the A and G comparison
    seed = 0
    accepted = [                              # each difference accepted by name (compare/check/accepted.py)
      { kind = "damping", part = "joint j1", urdf = 0, mjcf = 1, difference = 1, unit = "N m s/rad", tolerance = 1e-5 },
    ]

    [[tool.urdf2links.scenes]]
    files = ["scenes/*.toml"]                 # scene files, or:
    robot = "robots/arm.urdf"                 # a robot file's default scene (its loading options from robots)
    t_end = 0.5
    q0 = "excite"                             # excite (every coordinate travels its range) | random | rest
    seed = 0
"""

from __future__ import annotations

import glob
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

from urdf2links.parsers.importer import INERTIA_POLICIES, MIMIC_POLICIES

from ..corpus.rows import is_mujoco_document
from ..pairs.differences import KINDS
from ..pairs.pair import TERM_KEYS
from ..reports.baselines import DEFAULT_FACTOR
from .accepted import AcceptedRow, read_rows

__all__ = ["ConfigError", "CheckConfig", "RobotEntry", "PairEntry", "SceneEntry", "find_config", "read_config",
           "CONFIG_NAME", "DEFAULT_BASELINES", "ROBOT_SUFFIXES", "SCENE_T_END"]

#: The configuration file of its own (the other place is ``[tool.urdf2links]`` of ``pyproject.toml``).
CONFIG_NAME = "urdf2links.toml"
#: The baselines file when the configuration names none.
DEFAULT_BASELINES = "urdf2links-baselines.json"
#: The files a robots glob keeps (an ``.xml`` one only when its root element is ``<mujoco>``).
ROBOT_SUFFIXES = (".urdf", ".xacro", ".xml")
#: Run length (s) of a robot's default scene unless the entry says.
SCENE_T_END = 0.5
#: The initial states a robot's default scene may start from (urdf2links.ranges.Q0_CHOICES).
SCENE_Q0 = ("excite", "random", "rest", "zero")
_LOAD_KEYS = ("floating_base", "package_dirs", "xacro_args", "inertia", "mimic", "strict")
_TOP_KEYS = ("baselines", "factor", "tolerances", "robots", "pairs", "scenes")


class ConfigError(ValueError):
    """The configuration cannot be used (exit 2): the message names the file, the table and the key."""


@dataclass(frozen=True)
class RobotEntry:
    """One robot file: ``id`` (its path relative to the configuration's folder), ``path`` (absolute), ``load``
    (:func:`urdf2links.parsers.robot_file.load_robot` options) and ``allow`` (``True``, or the links whose
    inertia findings are accepted)."""

    id: str
    path: Path
    load: dict = field(default_factory=dict)
    allow: bool | tuple = False


@dataclass(frozen=True)
class PairEntry:
    """One pair: the two robots, the joint ``map``, ``tolerances`` of the terms A and G (the configuration's, then
    the pair's), ``states`` and ``seed`` of the A and G comparison, the ``accepted`` differences by name
    (:class:`~urdf2links.compare.check.accepted.AcceptedRow`)."""

    urdf: RobotEntry
    mjcf: RobotEntry
    map: dict = field(default_factory=dict)
    tolerances: dict = field(default_factory=dict)
    states: int = 8
    seed: int = 0
    accepted: tuple[AcceptedRow, ...] = ()


@dataclass(frozen=True)
class SceneEntry:
    """One scene: a scene file (``robot`` None) or a robot's default scene (``path`` None); ``id`` is the
    baselines' key (the scene file, or the robot file)."""

    id: str
    path: Path | None = None
    robot: RobotEntry | None = None
    t_end: float = SCENE_T_END
    q0: str = "excite"
    seed: int = 0


@dataclass(frozen=True)
class CheckConfig:
    """The configuration read: its ``source`` file, ``root`` folder, robots, pairs, scenes, the baselines'
    ``baselines`` path and ``factor``."""

    source: Path
    root: Path
    robots: tuple[RobotEntry, ...]
    pairs: tuple[PairEntry, ...]
    scenes: tuple[SceneEntry, ...]
    baselines: Path
    factor: float = DEFAULT_FACTOR
    tolerances: dict = field(default_factory=dict)


def _table_of(path: Path) -> dict | None:
    """The configuration table of ``path`` (None: a pyproject.toml without ``[tool.urdf2links]``)."""
    try:
        data = tomllib.loads(path.read_text())
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{path}: not valid TOML: {exc}") from None
    if path.name == "pyproject.toml":
        return data.get("tool", {}).get("urdf2links")
    return data


def find_config(start=".") -> tuple[Path, dict] | None:
    """``(file, its table)`` of the configuration that holds for ``start`` (a folder, or a configuration file),
    or None when there is none up to the repository's root (module doc)."""
    start = Path(start).resolve()
    if start.is_file():
        table = _table_of(start)
        if table is None:
            raise ConfigError(f"{start}: has no [tool.urdf2links] table")
        return start, table
    for folder in (start, *start.parents):
        found = [(p, _table_of(p)) for p in (folder / CONFIG_NAME, folder / "pyproject.toml") if p.is_file()]
        found = [(p, t) for p, t in found if t is not None]
        if len(found) == 2:
            raise ConfigError(f"{folder}: both {CONFIG_NAME} and pyproject.toml's [tool.urdf2links] configure "
                              "urdf2links check; keep one")
        if found:
            return found[0]
        if (folder / ".git").exists():
            return None
    return None


def _where(source: Path, table: str) -> str:
    prefix = "tool.urdf2links." if source.name == "pyproject.toml" else ""
    return f"{source} [{prefix}{table}]" if table else str(source)


def _fail(where: str, msg: str):
    raise ConfigError(f"{where}: {msg}")


def _number(where: str, key: str, v, *, low: float = 0.0) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)) or math.isnan(v) or v < low:
        _fail(where, f"{key} = {v!r}: give a number >= {low:g}")
    return float(v)


def _tolerances(where: str, value) -> dict:
    """A ``{A | G: number}`` table: the mapped terms' bounds. A difference kind is refused: differences are
    accepted by name (``accepted``), never a whole kind at once."""
    if not isinstance(value, dict):
        _fail(where, f"tolerances must be a table {{A = number, G = number}}, got {value!r}")
    for k in value:
        if k in KINDS:
            _fail(where, f"tolerances.{k}: a whole kind of difference cannot be accepted at once; accept each "
                         "difference by name in the pair's accepted table (a failing `urdf2links check` prints the "
                         "row to add; `urdf2links check --init` in a folder without a configuration writes them all)")
        if k not in TERM_KEYS:
            _fail(where, f"tolerances: unknown key {k!r}; give A and G, the mapped terms' largest relative "
                         f"difference (differences of kind {', '.join(KINDS)} are accepted by name: accepted)")
    return {k: _number(where, f"tolerances.{k}", v) for k, v in value.items()}


def _globs(where: str, value) -> list[str]:
    value = [value] if isinstance(value, str) else value
    if not isinstance(value, list) or not value or not all(isinstance(v, str) for v in value):
        _fail(where, f"files = {value!r}: give a glob or a list of globs (e.g. \"robots/**/*.urdf\")")
    return value


def _expand(root: Path, where: str, pattern: str, suffixes) -> list[Path]:
    hits = sorted(Path(p).resolve() for p in glob.glob(str(root / pattern), recursive=True))
    files = [p for p in hits if p.is_file() and p.name.endswith(suffixes)
             and (not p.name.endswith(".xml") or is_mujoco_document(p) or not glob.has_magic(pattern))]
    if not files:
        _fail(where, f"files: {pattern!r} matches no {' or '.join(suffixes)} file under {root}")
    return files


def _load_options(where: str, entry: dict, root: Path) -> dict:
    load = {}
    for k in _LOAD_KEYS:
        if k not in entry:
            continue
        v = entry[k]
        if k in ("floating_base", "strict") and not isinstance(v, bool):
            _fail(where, f"{k} = {v!r}: give true or false")
        if k == "inertia" and v not in INERTIA_POLICIES or k == "mimic" and v not in MIMIC_POLICIES:
            _fail(where, f"{k} = {v!r}: give one of {INERTIA_POLICIES if k == 'inertia' else MIMIC_POLICIES}")
        if k == "package_dirs":
            if not isinstance(v, list) or not all(isinstance(d, str) for d in v):
                _fail(where, f"package_dirs = {v!r}: give a list of folders")
            v = tuple(str((root / d).resolve()) for d in v)
        if k == "xacro_args":
            if not isinstance(v, dict):
                _fail(where, f"xacro_args = {v!r}: give a table {{name = \"value\"}}")
            v = {str(a): str(b) for a, b in v.items()}
        load[k] = v
    return load


def _robots(source: Path, root: Path, entries) -> dict[Path, RobotEntry]:
    out: dict[Path, RobotEntry] = {}
    for i, e in enumerate(entries):
        where = _where(source, f"robots {i + 1}")
        bad = [k for k in e if k not in ("files", "allow_inertia_findings", *_LOAD_KEYS)]
        if bad:
            _fail(where, f"unknown key(s) {bad}; allowed: files, allow_inertia_findings, {', '.join(_LOAD_KEYS)}")
        allow = e.get("allow_inertia_findings", False)
        if not (isinstance(allow, bool) or isinstance(allow, list) and all(isinstance(a, str) for a in allow)):
            _fail(where, f"allow_inertia_findings = {allow!r}: give true, false or a list of link names")
        load = _load_options(where, e, root)
        for pattern in _globs(where, e.get("files")):
            for p in _expand(root, where, pattern, ROBOT_SUFFIXES):
                out[p] = RobotEntry(_relative(p, root), p, load, allow if isinstance(allow, bool) else tuple(allow))
    return out


def _relative(p: Path, root: Path) -> str:
    try:
        return p.relative_to(root).as_posix()
    except ValueError:
        return str(p)


def _robot(robots: dict, root: Path, where: str, key: str, value) -> RobotEntry:
    """The robot entry of a file a pair or scene names (its loading options; a file no robots glob matched
    loads with the defaults)."""
    if not isinstance(value, str):
        _fail(where, f"{key} = {value!r}: give a robot file")
    p = (root / value).resolve()
    if not p.is_file():
        _fail(where, f"{key} = {value!r}: {p} does not exist")
    return robots.get(p) or RobotEntry(_relative(p, root), p)


def _pairs(source, root, entries, robots, tolerances) -> list[PairEntry]:
    out = []
    for i, e in enumerate(entries):
        where = _where(source, f"pairs {i + 1}")
        bad = [k for k in e if k not in ("urdf", "mjcf", "map", "tolerances", "states", "seed", "accepted")]
        if bad:
            _fail(where, f"unknown key(s) {bad}; allowed: urdf, mjcf, map, tolerances, states, seed, accepted")
        mp = e.get("map", {})
        if not isinstance(mp, dict) or not all(isinstance(v, str) for v in mp.values()):
            _fail(where, "map must be a table {urdf_joint = \"mjcf_joint\"}")
        tol = {**tolerances, **_tolerances(where, e.get("tolerances", {}))}
        out.append(PairEntry(_robot(robots, root, where, "urdf", e.get("urdf")),
                             _robot(robots, root, where, "mjcf", e.get("mjcf")), dict(mp), tol,
                             int(_number(where, "states", e.get("states", 8), low=1)),
                             int(_number(where, "seed", e.get("seed", 0))),
                             read_rows(where, e.get("accepted", []), _fail)))
    return out


def _scenes(source, root, entries, robots) -> list[SceneEntry]:
    out = []
    for i, e in enumerate(entries):
        where = _where(source, f"scenes {i + 1}")
        bad = [k for k in e if k not in ("files", "robot", "t_end", "q0", "seed")]
        if bad or ("files" in e) == ("robot" in e):
            _fail(where, "give files = [scene globs] or robot = \"file\" (its default scene, with t_end, q0, seed)"
                  + (f"; unknown key(s) {bad}" if bad else ""))
        if "files" in e:
            out += [SceneEntry(_relative(p, root), path=p) for pattern in _globs(where, e["files"])
                    for p in _expand(root, where, pattern, (".toml",))]
            continue
        q0 = e.get("q0", "excite")
        if q0 not in SCENE_Q0:
            _fail(where, f"q0 = {q0!r}: give one of {', '.join(SCENE_Q0)} (excite: every coordinate travels a good "
                         "part of its range)")
        robot = _robot(robots, root, where, "robot", e["robot"])
        out.append(SceneEntry(robot.id, robot=robot, t_end=_number(where, "t_end", e.get("t_end", SCENE_T_END)),
                              q0=q0, seed=int(_number(where, "seed", e.get("seed", 0)))))
    return out


def _tables(where: str, table: dict, key: str) -> list[dict]:
    v = table.get(key, [])
    if not isinstance(v, list) or not all(isinstance(e, dict) for e in v):
        _fail(where, f"{key} must be an array of tables ([[{key}]])")
    return v


def read_config(start=".") -> CheckConfig:
    """The configuration that holds for ``start`` (a folder or the file), checked and expanded (module doc)."""
    found = find_config(start)
    if found is None:
        raise ConfigError(f"no configuration for urdf2links check in {Path(start).resolve()} or above: write "
                          f"{CONFIG_NAME} or [tool.urdf2links] in pyproject.toml (`urdf2links check --init` "
                          "writes one; docs/ci.md)")
    source, table = found
    root = source.parent
    where = _where(source, "")
    bad = [k for k in table if k not in _TOP_KEYS]
    if bad:
        _fail(where, f"unknown key(s) {bad}; allowed: {', '.join(_TOP_KEYS)}")
    tolerances = _tolerances(where, table.get("tolerances", {}))
    robots = _robots(source, root, _tables(where, table, "robots"))
    pairs = _pairs(source, root, _tables(where, table, "pairs"), robots, tolerances)
    scenes = _scenes(source, root, _tables(where, table, "scenes"), robots)
    if not (robots or pairs or scenes):
        _fail(where, "names no robots, pairs or scenes")
    baselines = table.get("baselines", DEFAULT_BASELINES)
    if not isinstance(baselines, str):
        _fail(where, f"baselines = {baselines!r}: give a file name")
    return CheckConfig(source, root, tuple(robots.values()), tuple(pairs), tuple(scenes), root / baselines,
                       _number(where, "factor", table.get("factor", DEFAULT_FACTOR), low=1.0), tolerances)

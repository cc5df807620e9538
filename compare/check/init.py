"""``urdf2links check --init``: a starting configuration for a folder, accepting its current state.

:func:`init_config` finds every robot file under the folder (``.urdf``, ``.xacro``, MJCF ``.xml``; hidden
folders and virtual environments skipped) and every scene file (a ``.toml`` with a ``[robot]`` table), loads
each robot (a file that cannot be loaded is left out, and said), and guesses the pairs by robot name: a URDF
or xacro file and an MJCF file whose ``<robot name>`` and ``<mujoco model>`` agree. The current state is
accepted: a robot's inertia findings are allowed by link, each difference a pair has now is accepted by name as
a row of its ``accepted`` table (:mod:`~urdf2links.compare.check.accepted`: kind, part, both values, its own
tolerance; any other difference, or one that moves, fails), and the run that follows writes the baselines: every
robot's fingerprint (:mod:`~urdf2links.compare.check.fingerprint`) and every scene -- each scene file and each
robot's default scene, excited (``q0 = "excite"``) -- run by both engines. The result is ``urdf2links.toml``
(docs/ci.md).
"""

from __future__ import annotations

import os
import tomllib
import warnings
from pathlib import Path

from lxml import etree

from ..corpus.rows import is_mujoco_document
from ..pairs.differences import KINDS
from .accepted import accepted_row, rows_toml, toml_value
from .config import CONFIG_NAME, DEFAULT_BASELINES, SCENE_T_END, ConfigError, RobotEntry, find_config

__all__ = ["find_robot_files", "robot_name", "guess_pairs", "init_config", "toml_value"]

_SKIP = {"node_modules", "__pycache__", "site-packages", "build", "dist"}


def find_robot_files(folder: Path) -> tuple[list[Path], list[Path]]:
    """``(robot files, scene files)`` under ``folder`` (module doc), sorted."""
    robots, scenes = [], []
    for here, dirs, names in os.walk(folder):
        dirs[:] = sorted(d for d in dirs if not d.startswith(".") and d not in _SKIP
                         and not (Path(here) / d / "pyvenv.cfg").exists())
        for n in sorted(names):
            p = Path(here) / n
            if n.endswith((".urdf", ".xacro")) or n.endswith(".xml") and is_mujoco_document(p):
                robots.append(p)
            elif n.endswith(".toml") and n not in (CONFIG_NAME, "pyproject.toml") and _is_scene(p):
                scenes.append(p)
    return robots, scenes


def _is_scene(path: Path) -> bool:
    try:
        return isinstance(tomllib.loads(path.read_text()).get("robot"), dict)
    except (OSError, tomllib.TOMLDecodeError, UnicodeDecodeError):
        return False


def robot_name(path: Path) -> str:
    """The robot's name as its file gives it (``<robot name>``, ``<mujoco model>``), else the file's stem."""
    try:
        root = etree.parse(str(path)).getroot()
        name = root.get("model" if root.tag == "mujoco" else "name") or ""
    except (OSError, etree.XMLSyntaxError):
        name = ""
    return name if name and "$" not in name else path.name.split(".")[0]


def guess_pairs(robots: list[Path]) -> list[tuple[Path, Path]]:
    """``(URDF or xacro, MJCF)`` of the same robot name (module doc)."""
    firsts = [p for p in robots if not p.name.endswith(".xml")]
    return [(u, m) for m in robots if m.name.endswith(".xml") for u in firsts if robot_name(u) == robot_name(m)]


def _pair_rows(urdf: RobotEntry, mjcf: RobotEntry) -> tuple[list[str], list[str]]:
    """The ``accepted`` table that accepts a pair as it is now (its lines), and a comment line per kind."""
    from .cases import pair_summary
    from .config import PairEntry

    summary = pair_summary(PairEntry(urdf, mjcf))
    desc = summary["descriptions"]
    formats = (desc["urdf"]["format"], desc["mjcf"]["format"])
    floating = bool(summary["description_counts"]["root_pose"]["floating"])
    diffs = [d for d in summary["description_differences"] if not (d["kind"] == "root_pose" and floating)]
    rows = sorted((accepted_row(d, formats) for d in diffs), key=lambda r: (KINDS.index(r.kind), r.part))
    kinds = {}
    for d in diffs:
        kinds[d["kind"]] = kinds.get(d["kind"], 0) + 1
    kinds = dict(sorted(kinds.items(), key=lambda kn: KINDS.index(kn[0])))
    why = [f"# accepted at init: {', '.join(f'{n} {k}' for k, n in kinds.items())} difference(s), each by name"
           ] if kinds else []
    return (rows_toml(rows) if rows else []), why


def _lines(table: str, entries: list[tuple[list[str], dict, list[str]]]) -> list[str]:
    out = []
    for comments, e, extra in entries:
        out += ["", *comments, f"[[{table}]]"] + [f"{k} = {toml_value(v)}" for k, v in e.items()] + extra
    return out


def init_config(folder, *, t_end: float = SCENE_T_END, log=print) -> Path:
    """Write ``folder/urdf2links.toml`` (module doc) and return its path; the baselines are written by running
    the check (:func:`urdf2links.compare.check.command.run_check` with ``write_baselines``)."""
    from .cases import _load

    folder = Path(folder).resolve()
    found = find_config(folder)
    if found is not None and found[0].parent == folder:
        raise ConfigError(f"{found[0]} already configures urdf2links check: --init writes a new configuration only "
                          "where there is none")
    robot_paths, scene_paths = find_robot_files(folder)
    if not robot_paths and not scene_paths:
        raise ConfigError(f"--init: no robot file (.urdf, .xacro, MJCF .xml) or scene file under {folder}")
    rel = {p: p.relative_to(folder).as_posix() for p in robot_paths + scene_paths}
    loaded, plain, robots = [], [], []
    for p in robot_paths:
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                model = _load(RobotEntry(rel[p], p))
        except Exception as exc:  # noqa: BLE001 -- a robot that cannot be loaded is left out, and said
            log(f"--init: left out {rel[p]}: it cannot be loaded ({type(exc).__name__}: {str(exc)[:200]})")
            continue
        loaded.append(p)
        links = sorted({r.link for r in model.audit})
        if not links:
            plain.append(rel[p])
            continue
        robots.append(([f"# accepted at init: {len(model.audit)} inertia finding(s) of {rel[p]}"],
                       {"files": [rel[p]], "allow_inertia_findings": links}, []))
    robots = [([], {"files": plain}, [])] * bool(plain) + robots
    pairs = []
    for u, m in guess_pairs(loaded):
        rows, why = _pair_rows(RobotEntry(rel[u], u), RobotEntry(rel[m], m))
        pairs.append(([f"# guessed at init: both files describe robot {robot_name(u)!r}", *why],
                      {"urdf": rel[u], "mjcf": rel[m]}, rows))
    scenes = [([], {"files": [rel[p] for p in scene_paths]}, [])] * bool(scene_paths)
    scenes += [([], {"robot": rel[p], "t_end": t_end, "q0": "excite", "seed": 0}, []) for p in loaded]
    text = ["# urdf2links check: robots, pairs and scenes checked on every change (docs/ci.md).",
            "# Written by `urdf2links check --init`, accepting the current state; edit freely.",
            f"baselines = {toml_value(DEFAULT_BASELINES)}", "factor = 10.0"]
    text += _lines("robots", robots) + _lines("pairs", pairs) + _lines("scenes", scenes)
    path = folder / CONFIG_NAME
    path.write_text("\n".join(text) + "\n")
    log(f"wrote {path}: {len(loaded)} robot(s), {len(pairs)} pair(s), {len(scenes) - bool(scene_paths)} default "
        f"scene(s), {len(scene_paths)} scene file(s)")
    return path


def no_evidence(summary: dict | None) -> str | None:
    """Why a scene's run is no evidence to accept (the plausibility gate failed, or weak evidence, E67), or None."""
    if summary is None:
        return None
    gate = summary.get("plausibility") or {}
    if not gate.get("plausible", True):
        return gate.get("text", "implausible run")
    cov = summary.get("coverage") or {}
    return f"weak evidence: {cov.get('text', '')}" if cov.get("weak_evidence") else None


def leave_out_scenes(path: Path, reasons: dict[str, str], *, log=print) -> None:
    """Comment out, in the configuration ``path`` that --init wrote, the default scene of each robot in ``reasons``
    (robot file -> why its run is no evidence): --init accepts the current state, and a run that is not the robot
    (a joint flying past its limits, a body through its floor) or that moves nothing is no state to accept. The
    block stays in the file as comments under the reason, so that a user who makes the scene plausible (a scene
    file that holds the joints, a shorter run) sees what to bring back."""
    lines, out, i = path.read_text().splitlines(), [], 0
    while i < len(lines):
        block = lines[i:i + 2]
        robot = block[1].split("=", 1)[1].strip().strip('"') if (
            len(block) == 2 and block[0] == "[[scenes]]" and block[1].startswith("robot = ")) else None
        if robot not in reasons:
            out.append(lines[i])
            i += 1
            continue
        end = i + 1
        while end < len(lines) and lines[end].strip() and not lines[end].startswith("["):
            end += 1
        out += [f"# left out at init: the default scene of {robot} is no evidence to accept: "
                f"{reasons[robot][:600]}"] + [f"# {x}" for x in lines[i:end]]
        log(f"--init: left out the default scene of {robot}: {reasons[robot][:300]}")
        i = end
    path.write_text("\n".join(out) + "\n")

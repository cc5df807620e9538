"""A corpus of robot descriptions against MuJoCo: which files, and one robot's row.

:func:`find_robots` turns folders, files and glob patterns into :class:`RobotFile` entries (every
``*.urdf`` and ``*.xacro`` under a folder); :func:`evaluate_robot` runs one of them and returns a
:class:`RobotResult`: its row of ``corpus.json`` (:data:`ROW_KEYS`), the comparison's full summary
and, when asked, its light report page. It never raises for a robot: every outcome is a row whose
``status`` says what happened (:data:`STATUSES`):

* ``compared``: imported, run in its default scene (:func:`urdf2links.scenes.default_scenes.default_scene`: gravity,
  fixed base, every coordinate moving from a seeded random ``q0`` within the joint limits and ``q'``
  (E65), the URDF's damping; ``t_end`` 0.5 s) by both engines and compared (:func:`urdf2links.compare.agreement.trajectory.compare_scene`: terms at
  seeded states on route 1 and route 2, trajectories, energies). MuJoCo refusing the file on route 2
  is part of a comparison, not a failure: ``terms.route2_status`` says ``repaired`` (or ``refused``)
  and ``terms.route2_reason`` gives MuJoCo's reason, as in the scene reports;
* ``refused``: the file is not a robot urdf2links can read, and the importer says why (a
  :class:`~urdf2links.errors.URDFError` or :class:`~urdf2links.errors.SceneError`: an empty
  ``<robot>``, a xacro that only defines macros, ...): a documented refusal, ``reason`` quotes it;
* ``failed``: anything else went wrong -- a fault of urdf2links or of MuJoCo, not of the file.
  ``stage`` says where (import, scene, comparison, page), ``reason`` the exception, ``traceback``
  its last frames.

Everything a row holds is computed from the file and the :class:`CorpusSettings` alone (seeded), so
a robot's row is the same whichever process or machine ran it; only ``wall_time`` and ``worker``
differ (:data:`RUN_DEPENDENT_KEYS`).
"""

from __future__ import annotations

import glob
import math
import os
import socket
import traceback
import warnings
from dataclasses import dataclass, field
from pathlib import Path

from urdf2links.compilation import clock  # durations without numba's compilation
from urdf2links.errors import DescriptionError, SceneError
from urdf2links.scenes.default_scenes import default_scene

from ..formatting import json_ready
from ..mujoco_side.mjcf import MjcfRefused
from ..mujoco_side.mujoco_stepping import instability_note
from ..mujoco_side.stable_run import fallback_note
from ..reports.baselines import check_baseline

__all__ = ["RobotFile", "CorpusSettings", "RobotResult", "find_robots", "evaluate_robot", "failed_result",
           "robot_thumbnail", "worst_ratio",
           "STATUSES", "ROW_KEYS", "RUN_DEPENDENT_KEYS", "TERMS_TOLERANCE", "CORPUS_SUFFIXES", "EXAMPLE_ROBOT_DATA"]

#: What a row's ``status`` can be (module doc).
STATUSES = ("compared", "refused", "failed")
#: The keys of every row of ``corpus.json`` (dotted: nested objects).
ROW_KEYS = ("file", "status", "reason", "n", "terms.route1", "terms.route2", "trajectory.max_abs_error",
            "trajectory.divergence_time", "energy.project_drift", "energy.mujoco_drift", "coverage.moved_fraction",
            "coverage.weak_evidence", "scope", "wall_time")
#: Keys of a row that depend on where and how fast it ran (everything else is the same on every run).
RUN_DEPENDENT_KEYS = ("wall_time", "worker")
#: Route 1 compares the project's own tree written as MJCF with itself through MuJoCo: its terms
#: agree to rounding (~1e-15 relative on every corpus robot), so anything past 1e-9 is a bug.
TERMS_TOLERANCE = 1e-9
#: The name that stands for the installed example-robot-data robots (when no such folder is here).
EXAMPLE_ROBOT_DATA = "example-robot-data"
#: File names a folder is searched for.
CORPUS_SUFFIXES = (".urdf", ".xacro", ".xml")
#: The comparison's timings a row keeps (summary.json's ``wall_time.regions`` says what each holds):
#: each engine's integration timed alike, the whole calls around them, the warm-up, the terms.
_TIMES = ("project_s", "mujoco_s", "project_run_s", "mujoco_harness_s", "project_warmup_s", "terms_s")


@dataclass(frozen=True)
class RobotFile:
    """One robot of a corpus: ``id``, its name in the corpus (the path relative to the folder it was
    found in; the file's path as given for a file argument), and ``path``, the absolute file."""

    id: str
    path: str


#: How each ``q0`` choice of the default scene reads in the corpus' settings.
_STATES = {"excite": "q0 and q' seeded random, every coordinate set to travel a good part of its range in the run "
                     "(E65)", "random": "seeded random q0 within the joint limits, at rest", "rest": "at rest at q = 0",
           "zero": "at rest at q = 0"}


@dataclass(frozen=True)
class CorpusSettings:
    """How every robot of a corpus is run (the same for all; sent to each worker).

    ``t_end`` (s), ``q0`` and ``seed`` of the default scene; ``states`` and ``seed`` of the terms;
    MuJoCo's ``mujoco_integrator`` and ``mujoco_dt``; the import's ``inertia`` policy and
    ``package_dirs``; ``pages``: render each robot's light report page, with ``thumbnails`` a still
    picture of the robot for the index (a few seconds a robot: meshes are read); ``baselines`` (the parsed
    baselines file, or None) with ``factor`` and ``baselines_source`` (its path, for the messages)."""

    t_end: float = 0.5
    q0: str = "excite"
    seed: int = 0
    states: int = 8
    mujoco_integrator: str = "RK4"
    mujoco_dt: float = 1e-4
    inertia: str = "audit"
    package_dirs: tuple[str, ...] = ()
    mimic: str = "independent"
    strict: bool = False
    floating_base: bool = False
    xacro_args: dict | None = None
    pages: bool = True
    thumbnails: bool = True
    baselines: dict | None = None
    factor: float | None = None
    baselines_source: str = ""

    def describe(self) -> dict:
        """The settings as ``corpus.json`` records them (the baselines by their source only)."""
        return {"t_end": self.t_end, "q0": self.q0, "seed": self.seed, "states": self.states,
                "mujoco_integrator": self.mujoco_integrator, "mujoco_dt": self.mujoco_dt, "inertia": self.inertia,
                "package_dirs": list(self.package_dirs), "pages": self.pages, "thumbnails": self.thumbnails,
                **{k: v for k, v in (("mimic", self.mimic), ("strict", self.strict),
                                     ("floating_base", self.floating_base), ("xacro_args", self.xacro_args))
                   if v not in ("independent", False, None, {})},
                "baselines": self.baselines_source or None,
                "scene": "default scene: gravity, fixed base, URDF damping, " + _STATES.get(self.q0, self.q0)}


@dataclass
class RobotResult:
    """What :func:`evaluate_robot` hands back: ``row`` (JSON-ready, :data:`ROW_KEYS` and more),
    ``summary`` (the comparison's full summary, ``key`` set to the robot's id; None unless compared)
    and ``files``: the robot's own files by name (``report.html``, ``summary.json``, ``thumbnail.png``;
    text or bytes), written into ``<out>/<id>/`` by the process that collects the results (a worker
    needs no access to the output folder)."""

    row: dict
    summary: dict | None = None
    files: dict = field(default_factory=dict)


# --------------------------------------------------------------------------- which files


def _matches(folder: Path) -> list[Path]:
    return sorted(p for p in folder.rglob("*") if p.is_file() and p.name.endswith(CORPUS_SUFFIXES)
                  and (not p.name.endswith(".xml") or is_mujoco_document(p)))


def is_mujoco_document(path: Path) -> bool:
    """An ``.xml`` file found in a folder is a robot when its root element is ``<mujoco>`` (a folder of
    robots also holds ROS ``package.xml`` and launch files, which are not); a file named explicitly is
    always taken."""
    try:
        head = path.read_bytes()[:4096].decode("utf-8", "replace")
    except OSError:
        return False
    import re

    head = re.sub(r"<\?.*?\?>|<!--.*?-->|<!DOCTYPE[^>]*>", "", head, flags=re.S)
    return re.match(r"\s*<mujoco[\s>/]", head) is not None


def _expand(arg: str) -> list[tuple[Path, Path]]:
    """``(file, its base folder)`` for one argument: every robot under a folder (the folder is the
    base), a file (its own folder), the files and folders a glob pattern matches."""
    path = Path(arg)
    if arg == EXAMPLE_ROBOT_DATA and not path.exists():
        from urdf2links.locations import example_robot_data_dir

        path = example_robot_data_dir()
        if path is None:
            raise FileNotFoundError(f"--corpus {arg}: the example-robot-data package is not installed (pip install "
                                    "example-robot-data), and there is no such folder here")
    if path.is_dir():
        return [(p, path) for p in _matches(path)]
    if path.is_file():
        return [(path, path.parent)]
    if glob.has_magic(arg):
        out = []
        for hit in sorted(glob.glob(arg, recursive=True)):
            h = Path(hit)
            out += [(p, h) for p in _matches(h)] if h.is_dir() else [(h, h.parent)] if h.name.endswith(CORPUS_SUFFIXES) else []
        return out
    raise FileNotFoundError(f"--corpus {arg}: no such folder or file, and not a glob pattern (give a folder of "
                            "robots, a .urdf/.xacro/.xml file or a pattern such as 'robots/**/*.urdf')")


def find_robots(paths) -> list[RobotFile]:
    """The robots of a corpus, in the order given (sorted within a folder): every ``*.urdf`` and
    ``*.xacro`` under a folder (recursively), a file itself, the files a glob pattern matches; the
    same file reached twice is kept once. :data:`EXAMPLE_ROBOT_DATA` names the installed
    example-robot-data robots (:func:`urdf2links.locations.example_robot_data_dir`). Ids are paths relative to the deepest folder that holds
    every argument's base folder (a folder argument itself, a file's own folder): relative to the
    folder when one folder is given, ``fleet/arm.urdf`` and ``other/arm.urdf`` for two. FileNotFoundError
    names an argument that is nothing; ValueError one where nothing was found."""
    found: list[tuple[Path, Path]] = []
    seen: set[Path] = set()
    for arg in paths:
        hits = _expand(str(arg))
        if not hits:
            raise ValueError(f"--corpus {arg}: no .urdf, .xacro or MJCF .xml file there")
        for p, base in hits:
            real = p.resolve()
            if real not in seen:
                seen.add(real)
                found.append((real, base.resolve()))
    top = Path(os.path.commonpath([str(base) for _, base in found]))
    return [RobotFile(id=real.relative_to(top).as_posix(), path=str(real)) for real, _ in found]


# --------------------------------------------------------------------------- one robot


def robot_thumbnail(model, q, *, package_dirs=()) -> bytes:
    """A still picture of the robot at ``q`` (its initial pose), shown beside its row in the corpus
    index and linked to its page: PNG bytes (:func:`urdf2links.view.thumbnail.render_thumbnail`, 192 x 144
    pixels, meshes decimated to 2000 faces)."""
    from urdf2links.view.thumbnail import render_thumbnail

    return render_thumbnail(model, q, package_dirs=package_dirs, size=(192, 144), max_faces=2000)


def _shorten(x, robot: RobotFile):
    """``x`` (JSON-ready) with the robot's absolute path written as its id and its corpus folder
    dropped from other paths: rows and pages read the same on every machine (and a committed report
    holds no site-packages paths)."""
    if isinstance(x, dict):
        return {k: _shorten(v, robot) for k, v in x.items()}
    if isinstance(x, list):
        return [_shorten(v, robot) for v in x]
    if isinstance(x, str):
        root = _root(robot)
        x = x.replace(robot.path, robot.id)
        return x.replace(root, "") if root else x
    return x


def _root(robot: RobotFile) -> str:
    """The corpus folder of ``robot`` with a trailing slash ('' when its id is not a path tail)."""
    return robot.path[: -len(robot.id)] if robot.path.endswith("/" + robot.id) else ""


def _audit_rows(model) -> list[dict]:
    return [{"link": r.link, "kind": r.kind, "action": r.action, "message": r.message, "fix": r.fix}
            for r in model.audit]


def _route2(r2: dict) -> tuple[str, str | None]:
    """Route 2's status (``as written``, ``repaired``, ``refused``, ``skipped``) and MuJoCo's reason."""
    first = (r2.get("refusals") or [{}])[0].get("reason")
    first = first.strip().splitlines()[0] if first else None
    if r2.get("skipped"):
        return "skipped", r2["skipped"]
    if r2.get("error"):
        return "refused", first or r2["error"]
    return ("repaired" if "REPAIRED" in r2.get("label", "") else "as written"), first


def worst_ratio(terms: dict, trajectory: dict) -> float | None:
    """The largest of a compared robot's figures over its tolerance: route 1 and route 2 terms over
    :data:`TERMS_TOLERANCE`, the trajectory difference over the divergence threshold (infinite when
    one of them is not finite: JSON-ready rows write those as strings). Above 1: out of tolerance
    (the index sorts by it, worst first); None when none was measured."""
    figures = [(terms.get("route1"), TERMS_TOLERANCE), (terms.get("route2"), TERMS_TOLERANCE),
               (trajectory.get("max_abs_error"), trajectory.get("divergence_threshold"))]
    ratios = [math.inf if isinstance(v, str) else v / tol for v, tol in figures if v is not None]
    return max(ratios) if ratios else None


def _compared_row(row: dict, s: dict) -> None:
    """Fill a compared robot's row from its comparison summary ``s`` (JSON-ready)."""
    te, tr, en = s["terms"], s["trajectory"], s["energy"]
    status2, reason2 = _route2(te["route2"])
    row["terms"] = {"route1": te["max_rel_error_route1"], "route2": te["max_rel_error_route2"],
                    "route1_A": te["route1"].get("max_rel_error_A"),
                    "route1_bias": te["route1"].get("max_rel_error_bias"),
                    "route2_status": status2, "route2_reason": reason2, "route2_label": te["route2"].get("label"),
                    "states": te["route1"]["states"]}
    row["trajectory"] = {"max_abs_error": tr["max_abs_error"], "divergence_time": tr["divergence_time"],
                         "divergence_threshold": tr["divergence_threshold"], "final_abs_error": tr["final_abs_error"],
                         "verdict": tr["verdict"]}
    row["energy"] = {"project_drift": en["project_drift"], "mujoco_drift": en["mujoco_drift"],
                     "project_drift_rel": en["project_drift_rel"], "mujoco_drift_rel": en["mujoco_drift_rel"],
                     "scale": en["scale"]}
    cov, verdict = s.get("coverage") or {}, s.get("verdict") or {}
    row["coverage"] = {k: cov.get(k) for k in ("coordinates", "moved", "moved_fraction", "weak_evidence", "text")}
    row["scope"] = verdict.get("scope")
    row["verdict"] = verdict.get("text", tr["verdict"])
    row["plausible"] = verdict.get("plausible", True)      # issue 43: the gate before the verdict
    row["limit_excursions"] = len(s.get("limit_excursions", []))
    row["mujoco_notes"] = list(s["mujoco"].get("notes", []))
    row["mujoco_blow_ups"] = dict(s["mujoco"]["blow_ups"])
    fallback = s["mujoco"].get("fallback")
    if (verdict.get("cut") or {}).get("cut"):     # the note column says what both engines left out
        row["reason"] = verdict["scope"] + (f"; {row['reason']}" if row.get("reason") else "")
    if not row["plausible"]:     # issue 43: the note column opens with the gate's reasons
        row["reason"] = s["plausibility"]["text"] + (f"; {row['reason']}" if row.get("reason") else "")
    if row["mujoco_blow_ups"]:   # the index's note column says it: the difference is MuJoCo's blow-up
        note = instability_note(row["mujoco_blow_ups"], s["mujoco"]["integrator"], s["mujoco"]["timestep"])
        row["reason"] = note + (f"; {row['reason']}" if row.get("reason") else "")
    elif fallback:               # ... or the stable setting the harness chose instead, and its convergence
        row["mujoco_fallback"] = fallback
        row["reason"] = fallback_note(fallback) + (f"; {row['reason']}" if row.get("reason") else "")
    row["project_methods"] = s["project"].get("methods_used")
    row["worst"] = worst_ratio(row["terms"], row["trajectory"])


def _new_row(robot: RobotFile, settings: CorpusSettings) -> dict:
    return {"file": robot.id, "status": None, "reason": None, "stage": None, "name": None, "n": None, "links": None,
            "import": {"audit": [], "repairs": [], "notes": []},
            "terms": {"route1": None, "route2": None, "route2_status": None, "route2_reason": None},
            "trajectory": {"max_abs_error": None, "divergence_time": None},
            "energy": {"project_drift": None, "mujoco_drift": None}, "worst": None, "check": None,
            "coverage": {"coordinates": None, "moved": None, "moved_fraction": None, "weak_evidence": None},
            "scope": None,
            "inertia": settings.inertia, "report": None, "thumbnail": None, "seed": settings.seed,
            "t_end": settings.t_end,
            "wall_time": {}, "worker": f"{socket.gethostname()}:{os.getpid()}"}


def _fail(row: dict, stage: str, exc: BaseException) -> None:
    before = f" (after: {row['reason']})" if row.get("reason") else ""
    row["status"], row["stage"] = "failed", stage
    row["reason"] = f"{stage}: {type(exc).__name__}: {exc}{before}"
    row["traceback"] = "".join(traceback.format_exception(exc)[-6:])


def _refuse(row: dict, stage: str, exc: BaseException) -> None:
    row["status"], row["stage"], row["reason"] = "refused", stage, str(exc)


def _check(row: dict, summary: dict, settings: CorpusSettings) -> object | None:
    """The baseline check of a compared robot (None without baselines or without an entry for it)."""
    if settings.baselines is None:
        return None
    try:
        chk = check_baseline(summary, settings.baselines, factor=settings.factor, source=settings.baselines_source)
    except KeyError:
        row["check"] = {"ok": None, "failures": [], "text": f"no baseline for {row['file']!r}"}
        return None
    row["check"] = {"ok": chk.ok, "failures": list(chk.failures), "text": chk.text()}
    return chk


def _robot_files(robot: RobotFile, c, summary: dict, row: dict, check, settings: CorpusSettings) -> dict:
    """The robot's page, summary and (with ``settings.thumbnails``) thumbnail; their links in ``row``."""
    import json

    from .page import render_robot_page

    depth = robot.id.count("/") + 1
    files = {"summary.json": json.dumps({**summary, "import": row["import"]}, indent=2) + "\n"}
    if settings.thumbnails:
        try:
            files["thumbnail.png"] = robot_thumbnail(c.model, c.q_ours[0], package_dirs=settings.package_dirs)
            row["thumbnail"] = f"{robot.id}/thumbnail.png"
        except Exception as exc:  # noqa: BLE001 - a picture that cannot be drawn is no reason to fail the robot
            row["thumbnail_note"] = f"no thumbnail: {type(exc).__name__}: {exc}"
    row["report"] = f"{robot.id}/report.html"
    files["report.html"] = render_robot_page(c, summary, row, check=check, index_link="../" * depth + "index.html")
    return files


def _load(robot: RobotFile, settings: CorpusSettings, inertia: str):
    from urdf2links.parsers.robot_file import is_mjcf_path, load_robot

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the audit is in model.audit, and in the row
        return load_robot(robot.path, **_load_options(settings, inertia, robot.path))


def _load_options(settings: CorpusSettings, inertia: str, path) -> dict:
    """The options every robot of the corpus is loaded with (``inertia``: the settings' or the repair);
    an MJCF file takes only ``inertia`` and ``strict`` (the others are URDF's)."""
    from urdf2links.parsers.robot_file import is_mjcf_path

    if is_mjcf_path(path):
        return {"inertia": inertia, "strict": settings.strict}
    return {"inertia": inertia, "package_dirs": tuple(settings.package_dirs), "mimic": settings.mimic,
            "strict": settings.strict, "floating_base": settings.floating_base, "xacro_args": settings.xacro_args}


def _import_info(row: dict, robot: RobotFile, model, inertia: str) -> None:
    row.update(name=model.name, n=int(model.n), links=int(model.tree.n_links), inertia=inertia)
    row["import"] = _shorten({"audit": _audit_rows(model), "notes": list(model.info.get("notes", [])),
                              "repairs": [str(r) for r in model.audit if r.action == "repaired"]}, robot)


class _Stage:
    """Where an evaluation is (``failed`` rows name it)."""

    name = "import"


def _compare(robot: RobotFile, model, settings: CorpusSettings, inertia: str, at: _Stage):
    from ..agreement.trajectory import compare_scene

    at.name = "scene"
    opts = _load_options(settings, inertia, robot.path)
    scene = default_scene(robot.path, t_end=settings.t_end, q0=settings.q0, seed=settings.seed, model=model,
                          floating=opts.pop("floating_base", False), **opts)
    at.name = "comparison"
    return compare_scene(scene, mujoco_integrator=settings.mujoco_integrator, mujoco_dt=settings.mujoco_dt,
                         states=settings.states, seed=settings.seed, progress=False, model=model)


def _repair_reason(exc: BaseException, findings: int) -> str:
    what = (f"MuJoCo refuses the file's inertias on route 1 ({exc.reason.splitlines()[0]})" if isinstance(exc, MjcfRefused)
            else f"the file as written cannot be simulated ({type(exc).__name__}: {str(exc).splitlines()[0][:160]})")
    return (f"{what}; its inertia audit has {findings} finding(s): both engines ran the project's repair "
            "(inertia='repair'), as route 2 does when MuJoCo refuses a file")


def _compare_or_repair(robot: RobotFile, model, settings: CorpusSettings, row: dict, at: _Stage):
    """The comparison of the file as loaded; when MuJoCo refuses its inertias on route 1 or the
    equations cannot be solved (A not positive definite, an integration that cannot go on) and the
    audit found inconsistent inertias, the comparison of the project's repair, and ``row`` says why."""
    from urdf2links.errors import DynamicsError, IntegrationError

    try:
        return _compare(robot, model, settings, settings.inertia, at)
    except (MjcfRefused, DynamicsError, IntegrationError) as exc:
        if settings.inertia == "repair" or not model.audit:
            raise
        row["reason"] = _repair_reason(exc, len(model.audit))
    at.name = "import (repair)"
    repaired = _load(robot, settings, "repair")
    _import_info(row, robot, repaired, "repair")
    return _compare(robot, repaired, settings, "repair", at)


def failed_result(robot: RobotFile, settings: CorpusSettings, stage: str, exc: BaseException) -> RobotResult:
    """The result of a robot whose evaluation never returned (its worker died, its result could not
    come back): a ``failed`` row at ``stage``."""
    row = _new_row(robot, settings)
    row["worker"] = None
    _fail(row, stage, exc)
    return RobotResult(row=_finished(row, robot))


def _finished(row: dict, robot: RobotFile) -> dict:
    """The row as ``corpus.json`` holds it: JSON-ready, paths shortened, the import notes counted
    (``import.n_notes``; the robot's page and summary.json list them)."""
    row["import"]["n_notes"] = len(row["import"].pop("notes"))
    return _shorten(json_ready(row), robot)


def evaluate_robot(robot: RobotFile, settings: CorpusSettings = CorpusSettings()) -> RobotResult:
    """Import, compare and (with ``settings.pages``) render one robot; never raises for the robot's
    sake (module doc). The comparison's summary gets ``key = robot.id`` (the baselines' key)."""
    row = _new_row(robot, settings)
    times = row["wall_time"]
    start = clock()
    result = RobotResult(row=row)
    at = _Stage()
    try:
        model = _load(robot, settings, settings.inertia)
        times["import_s"] = clock() - start
        _import_info(row, robot, model, settings.inertia)
        c = _compare_or_repair(robot, model, settings, row, at)
        summary = _shorten(json_ready(c.summary()), robot)
        summary["key"] = robot.id
        _compared_row(row, summary)
        times.update({k: summary["wall_time"][k] for k in _TIMES}, comparison_s=summary["wall_time"]["total_s"])
        row["status"] = "compared"
        result.summary = summary
        check = _check(row, summary, settings)
        at.name = "page"
        if settings.pages:
            t0 = clock()
            result.files = _robot_files(robot, c, summary, row, check, settings)
            times["page_s"] = clock() - t0
    except (DescriptionError, SceneError) as exc:
        (_refuse if at.name in ("import", "scene") else _fail)(row, at.name, exc)
    except Exception as exc:  # noqa: BLE001 - one robot's fault must not stop the corpus: its row says why
        _fail(row, at.name, exc)
    times["total_s"] = clock() - start
    result.row = _finished(row, robot)
    return result

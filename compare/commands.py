"""The ``compare``, ``report`` and ``tradeoff`` commands of ``urdf2links``: their handlers (the arguments are
declared in :mod:`urdf2links.commands.comparisons`, which imports this module only when one of them runs, so that
``import urdf2links`` never imports MuJoCo).

``urdf2links compare SCENE.toml``: one scene against MuJoCo, a report in
``reports/<robot>/<scene>/`` (or ``--out``), the summary also to ``--json``, and with
``--check BASELINES.json`` a non-zero exit naming every figure that grew past its baseline.

``urdf2links report``: every shipped scene (``robots/*.toml``, and the closed loops of ``robots/loops/*.toml``)
and ``reports/index.html``; a hard case that stops by design (its ``[expect]``, :mod:`urdf2links.scenes.expect`)
is listed as such, with its message, and is not a failure.
Every scene runs its whole ``t_end`` (MuJoCo's inputs come from a compiled control callback,
:mod:`urdf2links.compare.mujoco_side.mujoco_inputs`); ``--cap`` seconds caps the scenes with time-dependent
inputs (a moving base, joint torques, loads; default :data:`REPORT_CAP_S`, 0: none) and the
report says so. ``--t-end`` sets every scene's ``t_end`` instead. With ``<out>/baselines.json`` present (or ``--check FILE``) every scene is
checked against it (exit 1 on a failure); ``--write-baselines [FILE]`` adds this run's figures
to it (or to FILE), replacing an accepted run of the same length and MuJoCo setting.
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass, field
from pathlib import Path

from urdf2links.compilation import clock  # durations without numba's compilation
from urdf2links.console import err, shown_path
from urdf2links.integration.integrators import METHODS
from urdf2links.locations import DEFAULT_OUT, default_baselines, report_scenes, shipped_robots_dir
from urdf2links.scenes.scene_read import load_scene
from urdf2links.scenes.scene_toml import load_options_of, override_loading, scene_from_args, write_scene_option

from .agreement.trajectory import compare_scene
from .formatting import json_ready
from .reports.baselines import check_baseline, load_baselines, write_baselines
from .reports.report import write_index, write_report
from .reports.stops import expected_stop, missed_stop
from .tradeoff.report import write_study
from .tradeoff.study import STAGES, run_study

__all__ = ["compare_command", "report_command", "tradeoff_command", "shipped_scenes", "report_t_end", "REPORT_CAP_S"]

#: Default cap (s) of ``urdf2links report`` on scenes with time-dependent inputs (0: none).
REPORT_CAP_S = 0.0


def shipped_scenes() -> list[Path]:
    """The shipped open-tree scene files (``robots/*.toml`` of the installed package; ``urdf2links report`` also
    runs the closed loops, :func:`urdf2links.locations.report_scene_files`)."""
    return sorted(shipped_robots_dir().glob("*.toml"))


def _driven(scene) -> list[str]:
    return [w for w, on in (("the moving base", scene.base is not None), ("joint torques", bool(scene.torques)),
                            ("loads", bool(scene.loads))) if on]


def _words(items: list[str]) -> str:
    return items[0] if len(items) == 1 else ", ".join(items[:-1]) + " and " + items[-1]


def report_t_end(scene, *, t_end: float | None, cap: float) -> tuple[float, str | None]:
    """The ``t_end`` ``urdf2links report`` uses for ``scene`` and the note that says why, if it is
    not the scene's own."""
    if t_end is not None:
        return float(t_end), (f"t_end set to {t_end:g} s by --t-end (the scene's is {scene.run.t_end:g} s)"
                              if t_end != scene.run.t_end else None)
    driven = _driven(scene)
    if cap and cap > 0 and driven and scene.run.t_end > cap:
        return float(cap), (
            f"t_end capped at {cap:g} s (the scene's is {scene.run.t_end:g} s) by `urdf2links report --cap` on "
            f"scenes with {_words(driven)}. `urdf2links compare {shown_path(scene.path)}` runs the whole scene.")
    return float(scene.run.t_end), None


def _print_headline(s: dict, stream=None) -> None:
    stream = stream or sys.stdout       # the stdout of the call, not the one of the first import (a test's capture)
    tr, en, te, wt = s["trajectory"], s["energy"], s["terms"], s["wall_time"]
    r2 = te["route2"]
    print(f"{s['key']}: t = 0..{s['t_end']:g} s, urdf2links {s['project']['method']} vs MuJoCo "
          f"{s['mujoco']['integrator']} dt {s['mujoco']['timestep']:g}", file=stream)
    print(f"  terms      max rel. error {te['max_rel_error']:.2e} (route 1 {te['max_rel_error_route1']:.2e}; "
          + (f"route 2 {te['max_rel_error_route2']:.2e}" if te["max_rel_error_route2"] is not None else "route 2 skipped")
          + (", REPAIRED: MuJoCo refused the file" if "REPAIRED" in r2.get("label", "") else "") + ")", file=stream)
    print(f"  trajectory max |dq| {tr['max_abs_error']:.2e}, divergence "
          + ("none" if tr["divergence_time"] is None else f"at {tr['divergence_time']:.4g} s")
          + (f", growth rate {tr['growth_rate']:.3g} /s (chaotic)" if tr.get("growth_rate") is not None else ""),
          file=stream)
    print(f"  energy     drift urdf2links {en['project_drift']:.2e} J, MuJoCo {en['mujoco_drift']:.2e} J "
          f"(relative {en['project_drift_rel']:.1e}, {en['mujoco_drift_rel']:.1e}, to {en['scale']:.2g} J)",
          file=stream)
    if s["base"]["moving"]:
        print(f"  base       tracking error {s['base']['tracking_error']:.2e}", file=stream)
    if s.get("contact"):        # issue 37: MuJoCo's native contact beside the law
        nat = s["contact"]["native"]
        b, st = nat["base_height"], nat["settle_time"]
        ground = f", the ground at {b['ground']:.4g} m" if b.get("ground") is not None else ""
        print(f"  contact    base height at the end (the root link's z{ground}): urdf2links {b['ours_final']:.4g} m"
              + (f" (lowest {b['ours_min']:.4g} m)" if "ours_min" in b else "")
              + f", MuJoCo's native contact (a reference) {b['native_final']:.4g} m; difference native - urdf2links "
              f"{b['native_final'] - b['ours_final']:+.2e} m (largest {b['max_difference']:.2e} m)", file=stream)
        print(f"             feet {nat['feet']['final_max_distance']:.2e} m apart at the end, settled at "
              f"{st['ours'] if st['ours'] is not None else 'never'} / "
              f"{st['native'] if st['native'] is not None else 'never'} s (law / native)", file=stream)
    if s.get("coverage"):
        print(f"  coverage   {s['coverage']['text']}", file=stream)
    if s.get("constraints") and "error" not in s["constraints"]:        # issue 45: the closed loops (compare/reports/loop_section.py)
        L = s["constraints"]
        st, fa = L["study"], L["forces"].get("generalized") or L["forces"]["at_our_states"]
        print(f"  loops      max |Phi| {L['residual']['max']:.2e}, |Phi'| {L['residual']['rate_max']:.2e}; |J^T efc_force - "
              f"J^T lambda| {fa['max_abs']:.2e} " + (f"({fa['relative']:.1e} of {fa['scale']:.3g})" if fa["max_abs"] >
                                              L["forces"]["floor"] else f"(max |J^T lambda| {fa['scale']:.2g})") + "; solref tau "
              + ", ".join(f"{r['tau']:g}" for r in st["runs"]) + " s: MuJoCo "
              + ", ".join(f"{r['max_error']:.1e}" for r in st["runs"]) + f" from ours over {st['t_end']:g} s", file=stream)
    if s.get("verdict"):
        print(f"  verdict    {s['verdict']['text']}", file=stream)
    print(f"  wall time  urdf2links {wt['project_s']:.3g} s (integrator), MuJoCo {wt['mujoco_s']:.3g} s (engine, "
          f"mj_step nstep); whole calls {wt['project_run_s']:.3g} s / {wt['mujoco_harness_s']:.3g} s", file=stream)
    # compilation is shown apart, once: the command's last line (urdf2links.compilation.summary); the report
    # and summary.json keep this scene's share (project_compiled, mujoco_callback_compiled)


def _compare_cmd(args) -> str:
    parts = ["urdf2links compare", shown_path(args.scene)]
    parts += [f for f, on in (("--floating", args.floating), (f"--q0 {args.q0}", args.q0 != "excite"),
                              (f"--inertia {args.inertia}", args.inertia), (f"--mimic {args.mimic}", args.mimic),
                              ("--strict", args.strict), ("--hold", getattr(args, "hold", False)),
                              ("--ground", getattr(args, "ground", False)),     # issue 43: and the file's floor
                              ("--no-floor", getattr(args, "no_floor", False)),
                              ("--open-loops", getattr(args, "open_loops", False))) if on]
    parts += [f"--package-dir {shown_path(d)}" for d in args.package_dir] + [f"--xacro-arg {a}" for a in args.xacro_arg]
    for flag, value, default in (("--t-end", args.t_end, None), ("--mujoco-integrator", args.mujoco_integrator, "RK4"),
                                 ("--mujoco-dt", args.mujoco_dt, 1e-4), ("--method", args.method, None),
                                 ("--rtol", args.rtol, None), ("--states", args.states, 8), ("--seed", args.seed, 0)):
        if value is not None and value != default:
            parts.append(f"{flag} {value:g}" if isinstance(value, float) else f"{flag} {value}")
    return " ".join(parts)


def _when(path: Path) -> str:
    import datetime

    return datetime.datetime.fromtimestamp(path.stat().st_mtime).strftime("%Y-%m-%d %H:%M")


def compare_command(args) -> int:
    if getattr(args, "against", None):       # two descriptions of one robot
        from .pairs.command import compare_against_command

        return compare_against_command(args)
    if getattr(args, "map", None):
        raise ValueError("--map pairs joints of two descriptions: give the second with --against")
    scene = scene_from_args(args)
    write_scene_option(args, scene)
    quiet = getattr(args, "quiet", False)
    log = (lambda m: None) if quiet else (lambda m: err(f"  {scene.name}: {m}"))
    baselines = None
    if args.check:
        try:
            baselines = load_baselines(args.check)
        except (OSError, ValueError) as exc:
            err(f"urdf2links compare: error: cannot read baselines {args.check}: {exc}")
            return 2
    c = compare_scene(scene, t_end=args.t_end, mujoco_integrator=args.mujoco_integrator, mujoco_dt=args.mujoco_dt,
                      method=args.method, rtol=args.rtol, states=args.states, seed=args.seed,
                      progress=False if quiet else None, log=log, max_wall=args.max_wall)
    summary = json_ready(c.summary())
    check = None
    if baselines is not None:
        try:
            check = check_baseline(summary, baselines, factor=args.factor, source=shown_path(args.check))
        except KeyError as exc:
            err(f"urdf2links compare: error: {exc.args[0]}")
            return 2
    folder = Path(args.out) if args.out else DEFAULT_OUT / summary["robot"] / summary["scene"]
    if (folder / "summary.json").is_file():
        err(f"  {shown_path(folder)}: replacing the report written there before ({_when(folder / 'summary.json')})")
    paths = write_report(c, args.out, json_path=args.json, command=_compare_cmd(args), check=check,
                         animation_fps=args.animation_fps)
    _print_headline(paths["summary"])
    for note in c.model.info.get("missing_files", ()):     # issue 42: a mesh whose file was not found, named
        print(f"  note       {note}")
    print(f"  report     {shown_path(paths['html'])} (summary.json, summary.md)" + (f"; JSON also {args.json}" if args.json else ""))
    if check is not None:
        print(check.text())
        if not check.ok:
            err(f"urdf2links compare: {summary['key']}: figure(s) grew past the baseline: {', '.join(check.failures)}")
            return 1
    return 0


def report_command(args) -> int:
    """``urdf2links report`` (module doc): ``--pairs`` and ``--corpus`` to their own commands, else every scene
    compared, checked against the baselines, written, and the index over them."""
    if getattr(args, "pairs", None):
        from .pairs.command import report_pairs_command

        return report_pairs_command(args)
    if getattr(args, "corpus", None):
        from .corpus.command import corpus_command

        return corpus_command(args)
    out = Path(args.out) if args.out else DEFAULT_OUT
    if args.scenes:
        files, where = [Path(p) for p in args.scenes], "the scene files given"
    else:
        files, where = report_scenes()
    if not files:
        err(f"urdf2links report: error: no scenes found ({where})")
        return 2
    err(f"scenes: {len(files)} from {where}")
    if args.write_baselines is True:
        args.write_baselines = out / "baselines.json"
    load = load_options_of(args)
    baselines = _report_baselines(args, out)
    if baselines.unreadable:
        return 2
    runs = _ReportRuns()
    start = clock()
    for i, f in enumerate(files, 1):
        _report_scene(args, f, label=f"[{i}/{len(files)}]", load=load, out=out, baselines=baselines, runs=runs)
    corpus = out / "corpus" / "index.html"
    idx = write_index(runs.entries, out, note=_report_note(args, baselines),
                      command="urdf2links report" + (f" --out {args.out}" if args.out else ""),
                      corpus_link="corpus/index.html" if corpus.is_file() else None, stopped=runs.stopped)
    if args.write_baselines:
        bp = write_baselines(runs.summaries, args.write_baselines, factor=args.factor)
        err(f"wrote {shown_path(bp)}")
    print(idx["table"])
    print(f"\n{shown_path(idx['html'])}: {len(runs.entries)} scene(s) in {clock() - start:.0f} s"
          + (f"; {len(runs.stopped)} hard case(s) stopped by design, as their [expect] says" if runs.stopped else ""))
    for e in runs.errors:
        err(f"urdf2links report: scene failed: {e}")
    for f in runs.failed:
        err(f"urdf2links report: baseline check FAILED for {f}")
    return 1 if (runs.errors or runs.failed) else 0


@dataclass(frozen=True)
class _ReportBaselines:
    """The baselines ``report`` checks against (``data`` None: not checked), their ``path``, and whether the file
    given could not be read (``unreadable``: the command exits 2)."""

    data: dict | None = None
    path: Path | None = None
    unreadable: bool = False


def _report_baselines(args, out: Path) -> _ReportBaselines:
    """``--write-baselines``: none checked; else ``--check FILE`` or the default ``<out>/baselines.json``."""
    if args.write_baselines:
        err(f"baselines: this run's figures are accepted into {shown_path(args.write_baselines)} (not checked)")
        return _ReportBaselines()
    path, looked = (Path(args.check), [Path(args.check)]) if args.check else default_baselines(out)
    if path is None:
        err(f"baselines: none found (looked for {', '.join(shown_path(p) for p in looked)}): the figures are "
            "reported, not checked")
        return _ReportBaselines()
    try:
        data = load_baselines(path)
    except (OSError, ValueError) as exc:
        err(f"urdf2links report: error: cannot read baselines {path}: {exc}")
        return _ReportBaselines(path=path, unreadable=True)
    err(f"baselines: {shown_path(path)} (exit 1 when a figure grows past its baseline)")
    return _ReportBaselines(data, path)


@dataclass
class _ReportRuns:
    """What ``report``'s scenes gave, filled in scene by scene: the index's entries, the summaries (for
    ``--write-baselines``), the baseline failures, the errors, the hard cases that stopped by design."""

    entries: list = field(default_factory=list)
    summaries: list = field(default_factory=list)
    failed: list = field(default_factory=list)
    errors: list = field(default_factory=list)
    stopped: list = field(default_factory=list)


def _report_scene(args, f: Path, *, label: str, load: dict, out: Path, baselines: _ReportBaselines,
                  runs: _ReportRuns) -> None:
    """One scene of ``report``: compared (a failure, or a hard case's stop by design, noted and the next scene run),
    checked against its baseline, its report written; ``runs`` gets what it gave."""
    t0 = clock()
    scene = override_loading(load_scene(f), load)
    if getattr(args, "open_loops", False):      # issue 45: the file's equalities dropped, noted
        from urdf2links.scenes.file_constraints import open_loops

        scene = open_loops(scene)
    T, note = report_t_end(scene, t_end=args.t_end, cap=args.cap)
    err(f"{label} {Path(scene.robot).stem}/{scene.name}: t = 0..{T:g} s"
        + (f" (capped; scene {scene.run.t_end:g} s)" if note and args.t_end is None else ""))
    try:
        c = compare_scene(scene, t_end=T, mujoco_integrator=args.mujoco_integrator, mujoco_dt=args.mujoco_dt,
                          states=args.states, t_end_note=note, progress=False if args.quiet else None,
                          log=(lambda m: None) if args.quiet else (lambda m: err(f"    {m}")),
                          max_wall=args.max_wall)
    except Exception as exc:  # keep going: one broken scene must not hide the others
        stop = expected_stop(scene, Path(scene.robot).stem, exc, t_end=T)
        if stop is not None:      # a hard case's [expect]: listed as stopping by design, not a failure
            err(f"    stopped by design ({scene.expected_stop.text()}): {type(exc).__name__}: {exc}")
            runs.stopped.append(stop)
            return
        err(f"    FAILED: {type(exc).__name__}: {exc}")
        runs.errors.append(f"{f}: {exc}")
        return
    missed = missed_stop(scene, t_end=T)
    if missed is not None:
        err(f"    FAILED: {missed}")
        runs.errors.append(missed)
    summary = json_ready(c.summary())
    check = None
    if baselines.data is not None:
        try:
            check = check_baseline(summary, baselines.data, factor=args.factor, source=shown_path(baselines.path))
        except KeyError as exc:
            err(f"    no baseline: {exc.args[0]}")
        if check is not None and not check.ok:
            runs.failed.append(f"{summary['key']}: {', '.join(check.failures)}")
    cmd = f"urdf2links compare {shown_path(f)}" + (f" --t-end {T:g}" if T != scene.run.t_end else "")
    write_report(c, out / summary["robot"] / summary["scene"], command=cmd, check=check,
                 index_link="../../index.html", animation_fps=args.animation_fps)
    runs.summaries.append(summary)
    runs.entries.append({"summary": summary, "link": f"{summary['robot']}/{summary['scene']}/report.html",
                         "check": check})
    tr, en = summary["trajectory"], summary["energy"]
    err(f"    done in {clock() - t0:.1f} s: terms {summary['terms']['max_rel_error']:.1e}, "
        f"max |dq| {tr['max_abs_error']:.1e}, drift {en['project_drift_rel']:.1e} / {en['mujoco_drift_rel']:.1e}"
        + ("" if check is None else f", baseline {'ok' if check.ok else 'FAILED: ' + ', '.join(check.failures)}")
        + ("" if summary["verdict"].get("plausible", True) else "; IMPLAUSIBLE RUN (the verdict says why)"))


def _report_note(args, baselines: _ReportBaselines) -> str:
    """The index's note: the run's length (``--t-end``, ``--cap``) and the baseline check."""
    note = ""
    if args.t_end is not None:
        note = f"Every scene run for t_end = {args.t_end:g} s (--t-end)."
    elif args.cap and args.cap > 0:
        note = (f"Scenes with time-dependent inputs (moving base, joint torques, loads) are capped at t_end = "
                f"{args.cap:g} s (--cap); the others run their whole t_end. `urdf2links compare SCENE.toml` runs any "
                "scene in full.")
    if baselines.data is not None:
        note += (f" Baseline check against {shown_path(baselines.path)} (errors may grow "
                 f"{baselines.data.get('factor', 10):g}x).")
    return note.strip()


def tradeoff_command(args) -> int:
    """``urdf2links tradeoff SCENE.toml``: the study, its files, the crossover on stdout."""
    scene = scene_from_args(args)

    def names(text, what, allowed):
        if text is None:
            return None
        items = tuple(x.strip() for x in text.split(",") if x.strip())
        bad = [x for x in items if x not in allowed]
        if bad or not items:
            raise ValueError(f"{what}={text!r}: unknown {bad or 'empty list'}; choose from {', '.join(allowed)}")
        return items

    try:
        methods = names(args.methods, "--methods", METHODS)
        integrators = names(args.mujoco_integrators, "--mujoco-integrators", tuple(STAGES))
        if args.t_end is not None and not (math.isfinite(args.t_end) and args.t_end > 0):
            raise ValueError(f"--t-end={args.t_end!r}: must be a finite number of seconds > 0")
        if args.repeats is not None and args.repeats < 1:
            raise ValueError(f"--repeats={args.repeats!r}: must be at least 1")
        if args.budget is not None and not args.budget > 0:
            raise ValueError(f"--budget={args.budget!r}: must be a number of seconds > 0")
    except ValueError as exc:
        err(f"urdf2links tradeoff: error: {exc}")
        return 2
    log = (lambda m: None) if args.quiet else (lambda m: err(f"  {scene.name}: {m}"))
    data = run_study(scene, t_end=args.t_end, quick=args.quick, repeats=args.repeats, budget=args.budget,
                     methods=methods, mujoco_integrators=integrators, log=log)
    out = Path(args.out) if args.out else DEFAULT_OUT / data["robot"] / data["scene"]
    cmd = " ".join(["urdf2links tradeoff", shown_path(args.scene)] + (["--quick"] if args.quick else [])
                   + ([f"--t-end {args.t_end:g}"] if args.t_end is not None else []))
    paths = write_study(data, out, command=cmd)
    ref = data["reference"]
    print(f"{data['key']}: work-precision, t = 0..{data['t_end']:g} s; reference {ref['method']} rtol {ref['rtol']:g}, "
          f"error estimate {ref['error_estimate']:.1e} (check {ref['check']['method']} rtol {ref['check']['rtol']:g})")
    ok = sum(r["status"] == "ok" for r in data["rows"])
    print(f"  {ok} runs, {sum(r['status'] == 'failed' for r in data['rows'])} failed, "
          f"{sum(r['status'] == 'skipped' for r in data['rows'])} skipped (budget {data['budget_s']:g} s)")
    print(f"  crossover: {data['crossover']['statement']}")
    print(f"  wrote {shown_path(paths['json'])}, tradeoff.md, work_precision.png, energy_drift.png"
          + (f"; section in {shown_path(paths['report'])}" if paths["report"] else ""))
    return 0

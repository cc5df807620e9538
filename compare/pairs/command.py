"""The commands of two descriptions: ``urdf2links compare A --against B`` and ``urdf2links report --pairs PAIRS.toml``.

``compare A --against B [--map a=b ...]``: the two descriptions compared part by part
(:func:`~urdf2links.compare.pairs.pair.compare_descriptions_of`) and in motion
(:func:`~urdf2links.compare.pairs.motion.run_pair_motion`), then the usual comparison of the first file
against MuJoCo in its default scene (:func:`urdf2links.compare.agreement.trajectory.compare_scene`); one
report whose first sections are the two descriptions' (``report.html``, ``summary.json`` with
``joint_mapping``, ``description_differences``, ``description_effects``, ``description_motion``), in
``out/reports/<robot>/<scene>-against-<second>/`` unless ``--out``.

``report --pairs PAIRS.toml`` (:mod:`urdf2links.compare.pairs.pairs_file`; a shipped pairs file by name:
``robots/pairs/<name>.toml``): every pair compared and run (no usual comparison: the pairs are the
subject), a page per pair and ``index.html``/``index.md`` in ``out/reports/pairs/`` unless ``--out``;
exit 1 when a pair differs past its tolerances, 2 when a pair could not be compared (the others still are).
"""

from __future__ import annotations

import warnings
from pathlib import Path

from urdf2links.compilation import clock  # durations without numba's compilation
from urdf2links.console import err, shown_path
from urdf2links.locations import DEFAULT_OUT, find_input, shipped_robots_dir
from urdf2links.scenes.scene_toml import load_options_of, scene_from_args

from ..agreement.trajectory import compare_scene
from ..formatting import json_ready
from ..reports.report import write_report
from .mapping import parse_map
from .motion import pair_animation, run_pair_motion
from .pair import check_tolerances, compare_descriptions_of
from .pairs_file import read_pairs_file
from .effects import ORDER_WORDS
from .report import (description_sections, effect_words, pair_headline, pair_markdown, part_words,
                     write_pair_page, write_pairs_index)

__all__ = ["compare_against_command", "report_pairs_command", "find_pairs_file"]


def _headline(s: dict, label: str) -> None:
    eff = s["description_effects"]["mapped"]
    jm = s["joint_mapping"]
    diffs = s["description_differences"]
    print(f"{label}: {s['descriptions']['urdf']['file']} against {s['descriptions']['mjcf']['file']}")
    print(f"  joints     {len(jm['matched'])} matched ({', '.join(f'{n} by {k}' for k, n in jm['matched_by'].items() if n)}),"
          f" mapped fraction {jm['mapped_fraction']:.3g}" + (f"; negated: {', '.join(jm['negated'])}" if jm["negated"] else ""))
    n = s.get("description_counts")
    if n:
        print(f"  counts     {n['dynamics']['count']} change the dynamics (A {float(n['dynamics']['effect']['A']):.2e}, "
              f"G {float(n['dynamics']['effect']['G']):.2e}), {n['non_dynamic']['count']} do not, root pose "
              f"{n['root_pose']['count']}")
        e = n.get("dynamics_equal") or {}
        if e.get("count"):
            print(f"  equal      {e['count']} values differ, dynamics equal ({', '.join(e['kinds'])}): with the others "
                  f"undone, A and G agree to {float(e['A']):.1e}, {float(e['G']):.1e} at {e['states']} seeded states "
                  "(not seen by the equations of motion of this tree; not counted as dynamic)"
                  + "".join(f"; they carry {float(v):.3g} kg m^2 of {c}'s armature, which its listed armature difference "
                            "accounts for" for c, v in (e.get("carried_armature") or {}).items()))
    print(f"  parts      {len(diffs)} difference(s) above rounding" + (f"; order: {ORDER_WORDS}" if diffs else "")
          + "".join(f"\n    {d['kind']:<10} {part_words(d)}: {float(d['difference']):.3g} {d['unit']}; effect on A, G: "
                    f"{effect_words(d)}" + (" (explained)" if d.get("explanation") else "") for d in diffs[:8])
          + (f"\n    ... {len(diffs) - 8} more (summary.md)" if len(diffs) > 8 else ""))
    for term in ("A", "G"):
        by = eff[term].get("explained_by")
        print(f"  {term:<10} max relative difference {float(eff[term]['max_rel_difference']):.2e}"
              + (f", {100 * by['explains']:.0f}% explained by {by['kind']} of {by['urdf'] or by['mjcf']}" if by else ""))
    m = s.get("description_motion")
    if m:
        for eng in ("project", "mujoco"):
            b = m[eng]
            if b is not None:
                t = b["divergence_time"]
                print(f"  motion     {'urdf2links' if eng == 'project' else 'MuJoCo':<10} the descriptions {b['max_divergence']:.2e} "
                      f"apart at most" + (f", past {m['threshold']:g} at t = {t:.4g} s" if t is not None else ""))


def _pair_parts(urdf, mjcf, *, explicit_map, load, states, seed, q0, t_end, mujoco_dt, mujoco_integrator, fps, log):
    """The description half: summary, animation HTML."""
    pair = compare_descriptions_of(urdf, mjcf, explicit_map=explicit_map, load=load, states=states, seed=seed)
    summary = pair.summary()
    anim = None
    if t_end and t_end > 0:
        pm = run_pair_motion(pair, q0=q0, seed=seed, t_end=t_end, load=load, mujoco_dt=mujoco_dt,
                             mujoco_integrator=mujoco_integrator, log=log)
        summary["description_motion"] = pm.summary()
        if fps:
            anim = pair_animation(pm, fps=fps).html
    return pair, json_ready(summary), anim


def compare_against_command(args) -> int:
    """``urdf2links compare A --against B`` (module doc)."""
    against, note = find_input(args.against, kinds=("robot",))
    if note:
        err(f"urdf2links compare: {note}")
    if str(args.scene).endswith(".toml"):
        raise ValueError(f"--against compares two robot files: {shown_path(args.scene)} is a scene; give the first "
                         "robot file (.urdf, .xacro or .xml)")
    load = load_options_of(args)
    quiet = getattr(args, "quiet", False)
    log = (lambda m: None) if quiet else (lambda m: err(f"  pair: {m}"))
    t_end = 1.0 if args.t_end is None else float(args.t_end)
    log("comparing the descriptions part by part")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        _pair, summary, anim = _pair_parts(args.scene, against, explicit_map=parse_map(args.map), load=load,
                                           states=args.states, seed=args.seed, q0=args.q0, t_end=t_end,
                                           mujoco_dt=args.mujoco_dt, mujoco_integrator=args.mujoco_integrator,
                                           fps=args.animation_fps, log=log)
    scene = scene_from_args(args)
    log(f"the first description against MuJoCo in its default scene ({scene.name})")
    c = compare_scene(scene, t_end=args.t_end, mujoco_integrator=args.mujoco_integrator, mujoco_dt=args.mujoco_dt,
                      method=args.method, rtol=args.rtol, states=args.states, seed=args.seed,
                      progress=False if quiet else None, log=(lambda m: None) if quiet else (lambda m: err(f"  {m}")),
                      max_wall=args.max_wall)
    folder = (Path(args.out) if args.out else
              DEFAULT_OUT / c.summary()["robot"] / f"{scene.name}-against-{Path(against).stem}")
    first = description_sections(summary, animation_html=anim, verdict=False)   # the page's headline is the pair's
    cmd = (f"urdf2links compare {shown_path(args.scene)} --against {shown_path(against)}"
           + "".join(f" --map {m}" for m in args.map or ()))
    extra = {k: summary[k] for k in summary}
    head = pair_headline(summary)
    paths = write_report(c, folder, json_path=args.json, command=cmd, animation_fps=args.animation_fps,
                         first_sections=first, summary_extra=extra, headline=head,
                         first_markdown=pair_markdown(summary, title=head["title"]))
    _headline(summary, "descriptions")
    s = paths["summary"]
    print(f"  usual      the first description against MuJoCo: terms {s['terms']['max_rel_error']:.2e}, trajectory "
          f"max |dq| {s['trajectory']['max_abs_error']:.2e}")
    print(f"  report     {shown_path(paths['html'])} (summary.json, summary.md)")
    return 0


def find_pairs_file(arg) -> Path:
    """A pairs file: the path given, else a shipped one by name (``robots/pairs/<name>.toml``)."""
    p = Path(arg).expanduser()
    if p.is_file():
        return p
    shipped = shipped_robots_dir() / "pairs" / (p.name if p.suffix == ".toml" else f"{p.name}.toml")
    if shipped.is_file():
        return shipped
    names = sorted(f.stem for f in (shipped_robots_dir() / "pairs").glob("*.toml"))
    raise ValueError(f"--pairs {arg}: no such file (looked in {Path.cwd()}), and no shipped pairs file of that name "
                     f"(shipped: {', '.join(names) or 'none'})")


def report_pairs_command(args) -> int:
    """``urdf2links report --pairs PAIRS.toml`` (module doc)."""
    path = find_pairs_file(args.pairs)
    specs = read_pairs_file(path)
    out = Path(args.out) if args.out else DEFAULT_OUT / "pairs"
    err(f"pairs: {len(specs)} from {shown_path(path)} -> {shown_path(out)}")
    entries, failed, broken = [], [], []
    start = clock()
    for i, p in enumerate(specs, 1):
        t0 = clock()
        t_end = p.t_end if args.t_end is None else float(args.t_end)
        err(f"[{i}/{len(specs)}] {p.name}: {shown_path(p.urdf)} against {shown_path(p.mjcf)}")
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                pair, summary, anim = _pair_parts(p.urdf, p.mjcf, explicit_map=p.map, load=p.load, states=p.states,
                                                  seed=p.seed, q0=p.q0, t_end=t_end, mujoco_dt=args.mujoco_dt,
                                                  mujoco_integrator=args.mujoco_integrator, fps=args.animation_fps,
                                                  log=(lambda m: None) if args.quiet else (lambda m: err(f"    {m}")))
                failures = check_tolerances(summary, p.tolerances)
                write_pair_page(summary, out / p.name, title=f"{p.name}: two descriptions", animation_html=anim,
                                failures=failures, index_link="../index.html",
                                command=f"urdf2links report --pairs {shown_path(path)}")
        except Exception as exc:  # noqa: BLE001 -- one broken pair must not hide the others
            err(f"    FAILED: {type(exc).__name__}: {exc}")
            broken.append(p.name)
            entries.append({"name": p.name, "error": f"{type(exc).__name__}: {exc}"})
            continue
        entries.append({"name": p.name, "link": f"{p.name}/report.html", "summary": summary, "failures": failures})
        if failures:
            failed.append(p.name)
        err(f"    {len(summary['description_differences'])} difference(s), "
            + ("pass" if not failures else f"FAIL ({len(failures)}: {failures[0]}" + (" ..." if len(failures) > 1 else "") + ")")
            + f" in {clock() - t0:.1f} s")
    idx = write_pairs_index(entries, out, source=shown_path(path), command=f"urdf2links report --pairs {shown_path(path)}")
    print(idx["table"])
    print(f"\n{shown_path(idx['html'])}: {len(specs)} pair(s) in {clock() - start:.0f} s; "
          f"{len(specs) - len(failed) - len(broken)} pass, {len(failed)} past their tolerances, {len(broken)} not compared")
    for name in failed:
        err(f"urdf2links report: pair {name} differs past its tolerances")
    return 2 if broken else (1 if failed else 0)

"""What a comparison of two descriptions writes: its sections of a report page, a pair's own page, the pairs' index.

* :func:`description_sections`: the HTML of "Two descriptions" (files, joint mapping, the differences
  largest first with what each does to ``A`` and ``G``, the attribution) and "The two descriptions in
  motion" (both robots animated, their divergence): the first sections of ``urdf2links compare A
  --against B``'s report (the usual report of the first file against MuJoCo follows) and the whole of
  a pair's page in ``urdf2links report --pairs``;
* :func:`pair_markdown`: the same as Markdown (``summary.md``; that of ``compare A --against B`` too, before the
  usual report's), :func:`pair_headline`: the pair's own headline on ``compare A --against B``'s page;
* every list of differences says its order (:data:`~urdf2links.compare.pairs.effects.ORDER_WORDS`), and each
  difference what undoing it alone does to A and G, or that this is at rounding (:func:`effect_words`);
* :func:`write_pair_page`: a pair's ``report.html``, ``summary.json`` and ``summary.md``;
* :func:`write_pairs_index`: ``index.html`` and ``index.md`` over the pairs, with each pair's verdict
  against its tolerances.
"""

from __future__ import annotations

import html
import json
from pathlib import Path

import numpy as np

from ..formatting import fmt, fmt_md, fmt_t, json_ready
from ..reports.report import page_css
from .effects import NOT_IN_A_G, ORDER_WORDS

__all__ = ["description_sections", "pair_markdown", "pair_headline", "write_pair_page", "write_pairs_index", "CSS",
           "effect_words", "part_words"]

CSS = page_css(max_width=1180, table_font="0.9em", cell_padding="4px 8px",
               extra=".warn { border-left-color: #d98c3d; background: #fdf7ef; }\n")

_E = html.escape


def _table(rows, header, num_cols=()) -> str:
    out = ["<table>", "<tr>" + "".join(f"<th>{h}</th>" for h in header) + "</tr>"]
    for r in rows:
        out.append("<tr>" + "".join(f"<td class='num'>{v}</td>" if i in num_cols else f"<td>{v}</td>"
                                    for i, v in enumerate(r)) + "</tr>")
    return "\n".join(out + ["</table>"])


def _value(v) -> str:
    if v is None:
        return "&ndash;"
    if isinstance(v, str):
        return _E(v)
    a = np.asarray(v, dtype=object if isinstance(v, list) and any(x is None for x in v) else float)
    if a.dtype == object:
        return _E(str(v))
    if a.ndim == 0:
        return f"{float(a):.6g}"
    if a.ndim == 1:
        return "(" + ", ".join(f"{x:.4g}" for x in a) + ")"
    return "diag (" + ", ".join(f"{x:.3g}" for x in np.diag(a)) + ")" if a.shape == (3, 3) else _E(str(a.shape))


def _share(x) -> str:
    if x is None or (isinstance(x, float) and not np.isfinite(x)):
        return "&ndash;"
    return f"{100 * float(x):.0f}%" if abs(float(x)) >= 0.005 else "0%"


def effect_words(d: dict) -> str:
    """What a difference (its JSON) does to A and G, in words: ``none`` (damping, limits, frames: no term of A or
    G), ``at rounding``, ``A 6.7e-02, G 7.2e-02`` (what undoing it alone changes, relative to the term's largest
    entry), or ``not undoable alone``."""
    e = d.get("effect") or {}
    if d.get("kind") in NOT_IN_A_G:
        return "none: not a term of A or G"
    if e.get("dynamics_equal"):
        return "values differ, dynamics equal (with the others of its group: A and G agree to rounding)"
    if d.get("kind") == "root_pose" and e.get("at_rounding") is True and not e.get("undoable", True):
        return "none: a floating root's pose is a state"
    if e.get("at_rounding") is True:
        return "at rounding"
    if e.get("at_rounding") is None:
        return "not undoable alone (see after undoing all)" if e else "not evaluated"
    changes = [(t, _number(e.get(f"changes_{t}")), _number(e.get(f"as_named_changes_{t}"))) for t in ("A", "G")]
    return ", ".join(f"{t} {fmt_md(a)}" + (f" (as named {fmt_md(n)})" if n is not None and a is not None and n > a
                                           else "") for t, a, n in changes)


def _number(x) -> float | None:
    """A figure of a summary (``"inf"`` as JSON writes it) as a float; None stays None."""
    return None if x is None else float(x)


def part_words(d: dict) -> str:
    """The part a difference names, as each file calls it: ``link forearm_link / forearm_link``."""
    names = " / ".join(str(n) for n in (d.get("urdf"), d.get("mjcf")) if n) or "-"
    return f"{d.get('part', 'part')} {names}"


def pair_headline(s: dict, failures=None) -> dict:
    """The pair's own headline on ``compare A --against B``'s page (``{"title", "html"}``): the two files and the
    verdict on them, before the first file's comparison against MuJoCo."""
    d = s["descriptions"]
    box = _verdict(s, failures)
    m = s.get("description_motion")
    if m and m.get("project"):
        t = m["project"]["divergence_time"]
        box = box[:-len("</div>")] + (f"<br><b>In motion</b> (urdf2links, t = 0..{m['t_end']:g} s): the descriptions "
                                      f"{fmt(m['project']['max_divergence'])} apart at most (rad or m)"
                                      + (f", past {m['threshold']:g} at t = {fmt_t(t)}" if t is not None else "")
                                      + ".</div>")
    return {"title": f"{d['urdf']['file']} against {d['mjcf']['file']}: two descriptions of one robot", "html": box}


def _verdict(s: dict, failures) -> str:
    diffs = s["description_differences"]
    eff = s["description_effects"]["mapped"]
    kinds = sorted({d["kind"] for d in diffs})
    head = ("<b>No difference above rounding</b>: the two describe the same robot (to the 6 significant digits "
            "MuJoCo's XML writer keeps)." if not diffs else
            f"<b>{len(diffs)} difference(s) above rounding</b> ({', '.join(kinds)}); "
            f"{sum(1 for d in diffs if d.get('explanation'))} explained by a known conversion step.")
    terms = []
    for term in ("A", "G"):
        t = eff[term]
        by = t.get("explained_by")
        terms.append(f"{term} differs by {fmt(t['max_rel_difference'])} (relative)"
                     + (f", {_share(by['explains'])} of it from {_E(by['kind'])} of "
                        f"<code>{_E(str(by['urdf'] or by['mjcf']))}</code>" if by else ""))
    n = s.get("description_counts")
    if n:
        head += (f"<br><b>{n['dynamics']['count']}</b> change the dynamics (A {fmt(n['dynamics']['effect']['A'])}, "
                 f"G {fmt(n['dynamics']['effect']['G'])} relative); <b>{n['non_dynamic']['count']}</b> do not "
                 f"({_E(', '.join(n['non_dynamic']['kinds']) or 'limits, frames, collision geometry')}); root pose: <b>{n['root_pose']['count']}</b>"
                 + (" (a floating root's pose at home: a state)" if n['root_pose']['floating'] and
                    n['root_pose']['count'] else "") + ".")
        e = n.get("dynamics_equal") or {}
        if e.get("count"):
            head += (f"<br><b>{e['count']}</b> values differ, dynamics equal ({_E(', '.join(e['kinds']))}): with every "
                     f"other difference undone, A and G agree to {fmt(e['A'])} and {fmt(e['G'])} (relative) at "
                     f"{e['states']} seeded states; these parameters are not seen by the equations of motion of this "
                     "tree (only combinations of them are), and are not counted as dynamic."
                     + "".join(f" They carry {fmt(v)} kg m^2 of <code>{_E(c)}</code>'s armature, which its listed "
                               "armature difference accounts for." for c, v in (e.get("carried_armature") or {}).items()))
    cls = "box" if not diffs else ("box bad" if failures else "box warn")
    check = ""
    if failures is not None:
        check = ("<br><b>Tolerances:</b> <span class='ok'>pass</span>" if not failures else
                 "<br><b>Tolerances:</b> <span class='fail'>FAIL</span>: " + _E("; ".join(failures[:6]))
                 + (f" ... ({len(failures) - 6} more, in summary.md)" if len(failures) > 6 else ""))
    return f"<div class='{cls}'>{head}<br>{'; '.join(terms)}.{check}</div>"


def _mapping_html(jm: dict) -> list[str]:
    by = jm["matched_by"]
    parts = [f"<p><b>Joint mapping</b>: {len(jm['matched'])} matched ({by['name']} by name, {by['structure']} by "
             f"structure, {by['map']} by --map), mapped fraction {jm['mapped_fraction']:.3g}"
             + (f"; unmatched in the first: <code>{_E(', '.join(jm['unmatched_urdf']))}</code>" if jm["unmatched_urdf"]
                else "")
             + (f"; unmatched in the second: <code>{_E(', '.join(jm['unmatched_mjcf']))}</code>" if jm["unmatched_mjcf"]
                else "")
             + (f"; <b>negated axes</b> (q maps with sign -1): <code>{_E(', '.join(jm['negated']))}</code>"
                if jm["negated"] else "") + ".</p>"]
    rows = [[_E(m["urdf"]), _E(m["mjcf"]), m["by"], " / ".join(m["type"]), f"{m['sign']:+g}", f"{m['offset']:.6g}"]
            for m in jm["matched"]]
    parts.append("<details><summary class='small'>every matched joint (q_mjcf = sign q_urdf + offset)</summary>"
                 + _table(rows, ["first", "second", "by", "type", "sign", "offset"], num_cols=(4, 5)) + "</details>")
    return parts


def _differences_html(s: dict) -> list[str]:
    diffs = s["description_differences"]
    counts = s["description_difference_counts"]
    below = sum(counts["below_rounding"].values())
    if not diffs:
        return [f"<p>Compared: {below} quantities (masses, centres of mass, inertias, axes, origins, limits, armature, "
                "damping, stiffness), all within rounding.</p>"]
    rows = []
    for i, d in enumerate(diffs[:200], 1):
        e = d.get("effect") or {}
        rows.append([str(i), _E(d["kind"]) + f" <span class='small'>({_E(d.get('part', ''))})</span>",
                     f"<code>{_E(str(d['urdf'] or '-'))}</code>",
                     f"<code>{_E(str(d['mjcf'] or '-'))}</code>", _value(d["urdf_value"]), _value(d["mjcf_value"]),
                     f"{fmt(d['difference'], 3)} {_E(d['unit'])}", _E(effect_words(d)),
                     _share(e.get("explains_A")), _share(e.get("explains_G")),
                     _E(d["what"]) + (f"<br><span class='small'>through {_E(', '.join(d['through']))}</span>"
                                      if d.get("through") else "")
                     + (f"<br><span class='small'>why: {_E(d['explanation'])}</span>" if d.get("explanation") else "")])
    more = f"<p class='small'>{len(diffs) - 200} more in summary.json.</p>" if len(diffs) > 200 else ""
    return [f"<p>Order: {_E(ORDER_WORDS)}. Each names its part as its file calls it (a link by its link, a joint by "
            "its joint). Values in each kind's unit; inertias shown by their diagonal (the whole tensor in summary.json). "
            f"{below} more quantities were within rounding.</p>",
            _table(rows, ["#", "kind", "first", "second", "first's value", "second's value", "difference",
                          "effect on A, G", "explains A", "explains G", "what"], num_cols=(6, 8, 9)), more]


def _effects_html(s: dict) -> list[str]:
    eff = s["description_effects"]
    parts = [f"<p><b>What they do.</b> A and G of both descriptions by urdf2links' equations at {eff['states']} seeded "
             f"states (seed {eff['seed']}; gravity {eff['gravity']}), in the first description's coordinates "
             "(q_mjcf = sign q_urdf + offset); each difference undone alone in the second description, then all at "
             "once.</p>"]
    rows = []
    for view in ("mapped", "as_named"):
        if view not in eff:
            continue
        for term in ("A", "G"):
            t = eff[view][term]
            big = t.get("largest") or {}
            where = (f"{'/'.join(big.get('entry', []))}" if term == "A" else big.get("coordinate", "")) if big else ""
            by = t.get("explained_by")
            rows.append([_E(view.replace("_", " ")), term, fmt(t["max_rel_difference"]),
                         (f"<code>{_E(where)}</code>: {big['urdf']:.6g} against {big['mjcf']:.6g}" if big else "&ndash;"),
                         (f"{_E(by['kind'])} <code>{_E(str(by['urdf'] or by['mjcf']))}</code>: {_share(by['explains'])}"
                          if by else "&ndash;"),
                         fmt(eff["after_undoing_all"][term]) if view == "mapped" else "&ndash;"])
    parts.append(_table(rows, ["coordinates", "term", "max relative difference", "largest entry (first / second)",
                               "explained most by", "left after undoing all"], num_cols=(2, 5)))
    return parts


def _motion_html(motion: dict, animation_html: str | None) -> list[str]:
    parts = ["<h2>The two descriptions in motion</h2>",
             f"<p>Each file in its default scene ({_E(motion['scene']['urdf'])}; {_E(motion['scene']['mjcf'])}), from the "
             f"same state (the first description's, mapped), t = 0..{motion['t_end']:g} s, by urdf2links and by MuJoCo "
             "running each file as written. The robot drawn solid is the first description, the translucent one the "
             "second.</p>"]
    if animation_html:
        parts.append(animation_html)
    rows = []
    for eng in ("project", "mujoco"):
        b = motion[eng]
        name = "urdf2links" if eng == "project" else (f"MuJoCo ({motion['mujoco_settings']['integrator']}, dt "
                                                      f"{motion['mujoco_settings']['timestep']:g} s)")
        rows.append([name, "&ndash;" if b is None else fmt(b["max_divergence"]),
                     "&ndash;" if b is None else fmt_t(b["divergence_time"]),
                     "&ndash;" if b is None else fmt(b["final_divergence"])])
    parts.append(_table(rows, ["engine", "max divergence (rad/m)", f"divergence time (&gt; {motion['threshold']:g})",
                               "at the end"], num_cols=(1, 2, 3)))
    eng = motion["engines_max_abs_difference"]
    parts.append("<p class='small'>Each file's two engines against each other (max |q urdf2links &minus; q MuJoCo|): "
                 f"first {fmt(eng['urdf'])}, second {fmt(eng['mjcf'])}: the descriptions' divergence above is theirs, "
                 "not the engines'.</p>")
    if motion["notes"]:
        parts.append("<details><summary class='small'>notes on the runs</summary><ul class='notes'>"
                     + "".join(f"<li>{_E(n)}</li>" for n in motion["notes"]) + "</ul></details>")
    return parts


def description_sections(s: dict, *, animation_html: str | None = None, failures=None,
                         verdict: bool = True) -> list[str]:
    """The HTML sections of a pair (module doc) from its summary ``s`` (``joint_mapping``,
    ``description_differences``, ``description_effects``, and ``description_motion`` when run);
    ``failures``: the tolerance check's lines (None: no check); ``verdict``: open with the pair's verdict (False
    when the page's headline already is it, :func:`pair_headline`)."""
    d = s["descriptions"]
    parts = ["<h2>Two descriptions</h2>", _verdict(s, failures) if verdict else "",
             _table([["first", f"<code>{_E(d['urdf']['file'])}</code>", d["urdf"]["format"], _E(d["urdf"]["name"]),
                      str(d["urdf"]["bodies"]), str(d["urdf"]["joints"])],
                     ["second", f"<code>{_E(d['mjcf']['file'])}</code>", d["mjcf"]["format"], _E(d["mjcf"]["name"]),
                      str(d["mjcf"]["bodies"]), str(d["mjcf"]["joints"])]],
                    ["", "file", "format", "robot", "bodies", "moving joints"], num_cols=(4, 5))]
    parts += _mapping_html(s["joint_mapping"]) + _effects_html(s) + ["<h3>Differences</h3>"] + _differences_html(s)
    if s.get("description_notes"):
        parts.append("<ul class='notes'>" + "".join(f"<li>{_E(n)}</li>" for n in s["description_notes"]) + "</ul>")
    if s.get("description_motion"):
        parts += _motion_html(s["description_motion"], animation_html)
    return parts


def pair_markdown(s: dict, *, title: str, failures=None) -> str:
    """A pair's summary as Markdown."""
    eff = s["description_effects"]["mapped"]
    jm = s["joint_mapping"]
    lines = [f"# {title}", "", f"First: `{s['descriptions']['urdf']['file']}`; second: `{s['descriptions']['mjcf']['file']}`.",
             "", f"Joints: {len(jm['matched'])} matched, mapped fraction {jm['mapped_fraction']:.3g}"
             + (f"; negated axes: {', '.join(jm['negated'])}" if jm["negated"] else "") + ".", ""]
    for term in ("A", "G"):
        by = eff[term].get("explained_by")
        lines.append(f"- {term}: max relative difference {fmt_md(eff[term]['max_rel_difference'])}"
                     + (f", {_share(by['explains'])} explained by {by['kind']} of {by['urdf'] or by['mjcf']}" if by else ""))
    e = (s.get("description_counts") or {}).get("dynamics_equal") or {}
    if e.get("count"):
        lines.append(f"- {e['count']} values differ, dynamics equal ({', '.join(e['kinds'])}): with every other "
                     f"difference undone, A and G agree to {fmt_md(e['A'])} and {fmt_md(e['G'])} at {e['states']} "
                     "seeded states (not seen by the equations of motion of this tree; not counted as dynamic)")
    if failures is not None:
        lines += ["", "Tolerances: " + ("pass" if not failures else "FAIL: " + "; ".join(failures))]
    lines += ["", f"Differences above rounding: {len(s['description_differences'])}. Order: {ORDER_WORDS}.", "",
              "| # | kind | part | first | second | difference | effect on A, G | what |",
              "|---|---|---|---|---|---|---|---|"]
    for i, d in enumerate(s["description_differences"][:100], 1):
        lines.append(f"| {i} | {d['kind']} | {d.get('part', '')} | {d['urdf'] or '-'} | {d['mjcf'] or '-'} | "
                     f"{fmt_md(d['difference'], 3)} {d['unit']} | {effect_words(d)} | {d['what']}"
                     + (f" (why: {d['explanation']})" if d.get("explanation") else "") + " |")
    if len(s["description_differences"]) > 100:
        lines.append(f"| ... | {len(s['description_differences']) - 100} more in summary.json | | | | | | |")
    if not s["description_differences"]:
        lines.append("| - | none above rounding | | | | | | |")
    m = s.get("description_motion")
    if m:
        lines += ["", f"Motion, t = 0..{m['t_end']:g} s: divergence urdf2links {fmt_md((m['project'] or {}).get('max_divergence'))}"
                  f" (time {fmt_t((m['project'] or {}).get('divergence_time'))}), MuJoCo "
                  f"{fmt_md((m['mujoco'] or {}).get('max_divergence'))} (time {fmt_t((m['mujoco'] or {}).get('divergence_time'))})."]
    return "\n".join(lines) + "\n"


def write_pair_page(summary: dict, out_dir, *, title: str, animation_html: str | None = None, failures=None,
                    index_link: str | None = None, command: str | None = None) -> dict:
    """A pair's own ``report.html``, ``summary.json``, ``summary.md`` in ``out_dir``."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    s = json_ready(summary)
    (out / "summary.json").write_text(json.dumps(s, indent=2) + "\n")
    (out / "summary.md").write_text(pair_markdown(s, title=title, failures=failures))
    page = ([f"<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'><title>{_E(title)}</title>"
             f"<style>{CSS}</style></head><body>",
             f"<p class='small'><a href='{_E(index_link)}'>&larr; all pairs</a></p>" if index_link else "",
             f"<h1>{_E(title)}</h1>", "<p class='sub'>Two descriptions of one robot compared part by part and in motion "
             "(urdf2links).</p>"]
            + description_sections(s, animation_html=animation_html, failures=failures)
            + [f"<p class='small'>Figures: <a href='summary.json'>summary.json</a>, <a href='summary.md'>summary.md</a>."
               + (f" Regenerate: <code>{_E(command)}</code>" if command else "") + "</p></body></html>"])
    (out / "report.html").write_text("\n".join(page), encoding="utf-8")
    return {"dir": out, "html": out / "report.html", "json": out / "summary.json", "md": out / "summary.md"}


def write_pairs_index(entries, out_root, *, source: str, command: str | None = None) -> dict:
    """``index.html`` and ``index.md`` over ``entries`` (``{"name", "link", "summary", "failures", "error"}``)."""
    root = Path(out_root)
    root.mkdir(parents=True, exist_ok=True)
    rows, md = [], ["| pair | first | second | mapped | differences | A | G | divergence | verdict |",
                    "|---|---|---|---|---|---|---|---|---|"]
    for e in entries:
        if e.get("error"):
            rows.append([_E(e["name"]), "", "", "", "", "", "", "", f"<span class='fail'>ERROR</span>: {_E(e['error'])}"])
            md.append(f"| {e['name']} | | | | | | | | ERROR: {e['error']} |")
            continue
        s = e["summary"]
        eff = s["description_effects"]["mapped"]
        kinds = {}
        for d in s["description_differences"]:
            kinds[d["kind"]] = kinds.get(d["kind"], 0) + 1
        diffs = ", ".join(f"{k} {n}" for k, n in kinds.items()) or "none"
        mot = s.get("description_motion") or {}
        div = (mot.get("project") or {}).get("max_divergence")
        verdict = "pass" if not e["failures"] else "FAIL: " + "; ".join(e["failures"][:3]) + (
            f" (+{len(e['failures']) - 3})" if len(e["failures"]) > 3 else "")
        rows.append([f"<a href='{_E(e['link'])}'>{_E(e['name'])}</a>", f"<code>{_E(s['descriptions']['urdf']['file'])}</code>",
                     f"<code>{_E(s['descriptions']['mjcf']['file'])}</code>", f"{s['joint_mapping']['mapped_fraction']:.3g}",
                     _E(diffs), fmt(eff["A"]["max_rel_difference"]), fmt(eff["G"]["max_rel_difference"]), fmt(div),
                     "<span class='ok'>pass</span>" if not e["failures"] else f"<span class='fail'>FAIL</span><br>"
                     f"<span class='small'>{_E('; '.join(e['failures'][:5]))}</span>"])
        md.append(f"| [{e['name']}]({e['link']}) | {s['descriptions']['urdf']['file']} | {s['descriptions']['mjcf']['file']} | "
                  f"{s['joint_mapping']['mapped_fraction']:.3g} | {diffs} | {fmt_md(eff['A']['max_rel_difference'])} | "
                  f"{fmt_md(eff['G']['max_rel_difference'])} | {fmt_md(div)} | {verdict} |")
    page = (f"<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'><title>Pairs of descriptions</title>"
            f"<style>{CSS}</style></head><body><h1>Pairs of descriptions</h1>"
            f"<p class='sub'>Each pair of robot files ({_E(source)}) compared part by part and in motion; a pair fails "
            "when a difference exceeds its tolerance (a kind without one is held to rounding).</p>"
            + _table(rows, ["pair", "first", "second", "mapped", "differences", "A", "G", "divergence (rad/m)",
                            "verdict"], num_cols=(3, 5, 6, 7))
            + "<p class='small'>A, G: max relative difference of the mass matrix and the gravity term at seeded states, in "
              "mapped coordinates. Divergence: max |q first &minus; q second mapped| of urdf2links' runs.</p>"
            + (f"<p class='small'>Regenerate: <code>{_E(command)}</code></p>" if command else "") + "</body></html>")
    (root / "index.html").write_text(page, encoding="utf-8")
    (root / "index.md").write_text("# Pairs of descriptions\n\n" + "\n".join(md) + "\n")
    return {"html": root / "index.html", "md": root / "index.md", "table": "\n".join(md)}

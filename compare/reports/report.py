"""Reports of the MuJoCo cross-validation: a self-contained HTML page, ``summary.json`` and
``summary.md`` per scene, and an index page over scenes.

* :func:`write_report` writes ``report.html`` (the robot moving in both engines, MuJoCo's run a
  translucent ghost (:mod:`urdf2links.compare.reports.motion`); plots embedded as base64 PNG:
  coordinates of both engines overlaid, error against time (log), energy of both engines,
  agreement of the terms),
  ``summary.json`` (:meth:`urdf2links.compare.agreement.trajectory.SceneComparison.summary`, non-finite numbers
  written as the strings ``"nan"``/``"inf"``) and ``summary.md`` into
  ``<root>/<robot>/<scene>/`` (or a given folder).
  When the folder holds a ``tradeoff.json`` (``urdf2links tradeoff``), the page gets its
  work-precision section (:func:`urdf2links.compare.tradeoff.report.render_section`).
* :func:`write_index` writes ``index.html`` and ``index.md``: one row per robot and scene with the
  headline figures and links.
* The regression check against ``baselines.json`` is :mod:`urdf2links.compare.reports.baselines`.
"""

from __future__ import annotations

import html
import json
import sys
from pathlib import Path

from urdf2links.locations import DEFAULT_OUT
from urdf2links.view.animation import DEFAULT_FPS

from ..agreement.constraint_agreement import loop_figures
from ..agreement.verdict import with_loops
from ..formatting import fmt, fmt_md, fmt_t, json_ready
from ..tradeoff.report import insert_section
from .baselines import CheckResult
from .contact_section import contact_markdown, contact_section
from .loop_section import loop_markdown, loop_section
from .coverage import coverage_cell, coverage_html, coverage_markdown, weak_evidence
from .motion import motion_section
from .plots import plot_coordinates, plot_energy, plot_error, plot_overview, plot_terms
from .stops import stops_html, stops_md

__all__ = ["write_report", "render_html", "render_markdown", "write_index", "page_css", "with_loop_sections"]


# --------------------------------------------------------------------------- HTML


def page_css(*, max_width: int = 1120, table_font: str = "0.92em", cell_padding: str = "4px 9px",
             extra: str = "") -> str:
    """The stylesheet of the report pages (a scene's report, the pairs' pages): the width, the tables' font and
    cells' padding, and a page's ``extra`` rules."""
    return f"""
body {{ font-family: -apple-system, 'Segoe UI', Helvetica, Arial, sans-serif; margin: 0 auto; max-width: {max_width}px;
       padding: 16px 24px 40px; color: #1d2330; line-height: 1.45; }}
h1 {{ font-size: 1.6em; margin-bottom: 0.1em; }} h2 {{ margin-top: 1.6em; border-bottom: 1px solid #d0d5de; padding-bottom: 3px; }}
.sub {{ color: #5a6272; margin-top: 0; }}
table {{ border-collapse: collapse; margin: 8px 0 14px; font-size: {table_font}; }}
th, td {{ border: 1px solid #d0d5de; padding: {cell_padding}; text-align: left; vertical-align: top; }}
th {{ background: #eef1f6; }} td.num {{ text-align: right; font-family: 'DejaVu Sans Mono', Menlo, monospace; white-space: nowrap; }}
.box {{ border-left: 4px solid #3d7bd9; background: #f3f7fd; padding: 8px 14px; margin: 10px 0; }}
.bad {{ border-left-color: #c9302c; background: #fbeeee; }}
.ok {{ color: #1e7b34; font-weight: 600; }} .fail {{ color: #c9302c; font-weight: 600; }}
code {{ background: #f0f2f5; padding: 0 3px; border-radius: 3px; font-size: 0.92em; }}
ul.notes li {{ margin: 2px 0; font-size: 0.9em; }} .small {{ font-size: 0.88em; color: #5a6272; }}
{extra}"""


_CSS = page_css(extra="""img { max-width: 100%; border: 1px solid #e3e6ec; margin: 6px 0; }
.chaos { border-left-color: #d98c3d; background: #fdf7ef; }
""")


def _rows(rows, header=None, num_cols=()) -> str:
    out = ["<table>"]
    if header:
        out.append("<tr>" + "".join(f"<th>{h}</th>" for h in header) + "</tr>")
    for r in rows:
        out.append("<tr>" + "".join(f"<td class='num'>{v}</td>" if i in num_cols else f"<td>{v}</td>"
                                    for i, v in enumerate(r)) + "</tr>")
    out.append("</table>")
    return "\n".join(out)


def _route_rows(r) -> list:
    if "max_rel_error_A" in r:
        return [fmt(r["max_rel_error_A"]), fmt(r["max_rel_error_bias"]), fmt(r["max_rel_error"])]
    return ["&ndash;"] * 3


def _headline(s) -> list:
    tr, en, te, wt, mj, pr = s["trajectory"], s["energy"], s["terms"], s["wall_time"], s["mujoco"], s["project"]
    head = [("terms: max relative error (A, e+G)", fmt(te["max_rel_error"]),
             "largest over both routes and all seeded states"),
            ("trajectory: max |&Delta;q|", fmt(tr["max_abs_error"]) + " rad/m", "largest over coordinates and time"),
            ("trajectory: divergence time", fmt_t(tr["divergence_time"]), f"first time |&Delta;q| &gt; {tr['divergence_threshold']:g}"),
            ]
    if tr.get("growth_rate") is not None:
        head.append(("trajectory: growth rate of |&Delta;q|", fmt(tr["growth_rate"]) + " /s",
                     "least-squares fit of log error over the growth phase (chaos)"))
    head += [("energy drift, urdf2links", fmt(en["project_drift"]) + " J", f"relative {fmt(en['project_drift_rel'])}"),
             ("energy drift, MuJoCo", fmt(en["mujoco_drift"]) + " J", f"relative {fmt(en['mujoco_drift_rel'])}")]
    if s["base"]["moving"]:
        head.append(("base tracking error (MuJoCo)", fmt(s["base"]["tracking_error"]),
                     "max |base_A qpos - prescribed pose| (m, rad)"))
    head += [("wall time, urdf2links", fmt(wt["project_s"], 3, " s"), f"{pr['method']}, {pr['nsteps']} steps, "
              f"{pr['nfev']} evaluations; the integrator (section {_wall_section(s)})"),
             ("wall time, MuJoCo", fmt(wt["mujoco_s"], 3, " s"), f"{mj['integrator']} dt {mj['timestep']:g} s, "
              f"{mj['nsteps']} steps; the engine, mj_step(nstep) (section {_wall_section(s)})")]
    return head


def _gate_line(p: dict) -> str:
    """The plausibility gate in one line: what it checked, and whether both runs passed (docs/reports.md)."""
    return (("passed" if p["plausible"] else "FAILED (the verdict says why)") + " on both engines' runs: "
            + "; ".join(p["checks"]))


def _top(s, check, index_link, index_label="all scenes", headline=None) -> list[str]:
    """Title, verdict, notes on the run length and the baseline check, headline figures, setup. ``headline``
    (``{"title", "html"}``): the page's own title and headline when the comparison is not its subject (a pair of
    descriptions): the comparison against MuJoCo follows under its own heading."""
    e = html.escape
    tr, mj, pr = s["trajectory"], s["mujoco"], s["project"]
    title = headline["title"] if headline else f"{s['robot']} / {s['scene']}: urdf2links against MuJoCo"
    implausible = not (s.get("plausibility") or {}).get("plausible", True)     # issue 43: the gate first
    verdict_cls = ("box bad" if implausible else "box chaos" if s["chaotic"] or weak_evidence(s) else
                   ("box bad" if tr["divergence_time"] is not None else "box"))
    parts = [f"<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'><title>{e(title)}</title>"
             f"<style>{_CSS}</style></head><body>",
             f"<p class='small'><a href='{e(index_link)}'>&larr; {e(index_label)}</a></p>" if index_link else "",
             *([f"<h1>{e(title)}</h1>", headline["html"],
                f"<h2>The first description against MuJoCo: {e(s['robot'])} / {e(s['scene'])}</h2>"] if headline else
               [f"<h1>{e(s['robot'])} / {e(s['scene'])}</h1>"]),
             f"<p class='sub'>{e(s['description'])}</p>",
             f"<div class='{verdict_cls}'><b>Trajectories:</b> {e(tr['verdict'])}</div>"]
    if s.get("coverage"):
        parts.append(f"<p class='sub'><b>Coverage:</b> {e(s['coverage']['text'])} (section 4).</p>")
    if s.get("plausibility"):       # issue 43: what the gate checked, before any verdict
        parts.append(f"<p class='sub'><b>Plausibility:</b> {e(_gate_line(s['plausibility']))}.</p>")
    if s.get("t_end_note"):
        parts.append(f"<div class='box chaos'>{e(s['t_end_note'])}</div>")
    if check is not None:
        parts.append(f"<div class='box{'' if check.ok else ' bad'}'><b>Baseline check:</b> "
                     + ("<span class='ok'>ok</span>" if check.ok else "<span class='fail'>FAILED</span> ("
                        + e(", ".join(check.failures)) + ")") + f" &mdash; {e(check.source)}</div>")
    parts.append("<h2>Headline figures</h2>")
    parts.append(_rows(_headline(s), ["figure", "value", "what"], num_cols=(1,)))
    parts.append("<h2>Setup</h2>")
    setup = [("scene file", f"<code>{e(str(s['scene_file']))}</code>"),
             ("robot", f"{e(s['robot_name'])} ({len(s['coordinates'])} coordinates: {e(', '.join(s['coordinates']))})"),
             ("effects computed", e(", ".join(s["effects"]))),
             ("run", f"t = 0..{s['t_end']:g} s (scene: {s['t_end_scene']:g} s), {s['samples']} samples"),
             ("urdf2links", f"{e(pr['method'])}" + (f", rtol {pr['rtol']:g}, atol {pr['atol']:g}" if pr["method"] not in ("RK4", "midpoint")
                                                     else f", dt {pr['dt']:g} s")),
             ("MuJoCo", f"{e(mj['integrator'])}, timestep {mj['timestep']:g} s, MuJoCo {e(mj['version'])}"),
             ("route", e(s["route_description"])),
             ("initial state", "q = " + e(", ".join(f"{k} {v:g}" for k, v in s["initial"]["q"].items()))
              + "; qd = " + e(", ".join(f"{k} {v:g}" for k, v in s["initial"]["qd"].items())))]
    if s.get("actuators"):
        setup.append(("actuators", "<br>".join(f"<code>{e(a['name'])}</code> on {e(a['coordinate'])} ({e(a['source'])}): "
                                               f"{e(a['law'])}" for a in s["actuators"])))
    parts.append(_rows(setup))
    return parts


def _terms_section(s, light=False) -> list[str]:
    e = html.escape
    r1, r2 = s["terms"]["route1"], s["terms"]["route2"]
    parts = ["<h2>1. Terms at identical states</h2>",
             f"<p>At {r1['states']} seeded random states (seed {r1['seed']}; q uniform within the joints' limits, a "
             "[-1, 1] window where a joint has none; qd standard normal"
             + ("; a random base pose and rate, no base acceleration" if r1.get("moving_base") else "")
             + "): the project's <code>A</code> against MuJoCo's <code>mj_fullM</code> and <code>e + G</code> "
               "against <code>qfrc_bias</code>, as max|ours &minus; MuJoCo| / max|MuJoCo|.</p>"]
    rows = [["route&nbsp;1", e(r1["label"]), *_route_rows(r1)]]
    r2_label = e(r2.get("label", "route 2"))
    if r2.get("skipped"):
        r2_label += f"<br><span class='small'>{e(r2['skipped'])}</span>"
    if r2.get("error"):
        r2_label += f"<br><span class='small'>{e(r2['error'])}</span>"
    rows.append(["route&nbsp;2", r2_label, *_route_rows(r2)])
    parts.append(_rows(rows, ["", "what MuJoCo loaded", "A", "e + G", "max"], num_cols=(2, 3, 4)))
    if r2.get("max_rel_error_damping") is not None:
        parts.append("<p>Route 2 also compared the dampers (the scene asks for the URDF's damping): the project's "
                     "<code>-c qd</code> against MuJoCo's <code>qfrc_damper</code> from its own reading of "
                     f"<code>&lt;dynamics damping&gt;</code>: max relative error "
                     f"<code>{r2['max_rel_error_damping']:.2e}</code> (included in route 2's max).</p>")
    acts = [(tag, r["actuators"]) for tag, r in (("route 1", r1), ("route 2", r2)) if r.get("actuators")]
    if acts:
        parts.append("<p>The actuators' generalized forces too (MuJoCo's law, E55): the project's against MuJoCo's "
                     "<code>qfrc_actuator</code> with <code>d.ctrl</code> at the same time, at seeded states "
                     "(included in each route's max): "
                     + "; ".join(f"{tag} " + (f"<code>{a['max_rel_error_actuator']:.2e}</code>" if "max_rel_error_actuator"
                                              in a else e(a.get("skipped", "not compared"))) for tag, a in acts) + ".</p>")
    if r2.get("refusals"):
        parts.append("<p><b>MuJoCo refused the original file.</b> Attempts, in order:</p><ul class='notes'>")
        for ref in r2["refusals"]:
            parts.append(f"<li>{e(ref['attempt'])}: refused by {e(ref['by'])}: <code>{e(ref['reason'].splitlines()[0])}</code></li>")
        parts.append(f"<li>accepted: {e(r2.get('label', ''))}</li></ul>")
    if not light:
        parts.append(f"<img alt='terms' src='data:image/png;base64,{plot_terms(s)}'>")
    return parts


def _trajectory_section(c, s, light=False) -> list[str]:
    e = html.escape
    tr = s["trajectory"]
    parts = ["<h2>2. Trajectories</h2>"]
    if light:
        parts.append(f"<img alt='difference and energy balance' src='data:image/png;base64,{plot_overview(c, s)}'>")
    else:
        parts += [f"<img alt='coordinates' src='data:image/png;base64,{plot_coordinates(c)}'>",
                  f"<img alt='error' src='data:image/png;base64,{plot_error(c, s)}'>"]
    rows = [[e(k), fmt(v)] for k, v in tr["max_abs_error_by_coordinate"].items()]
    parts.append(_rows(rows, ["coordinate", "max |&Delta;q|"], num_cols=(1,)))
    g = tr.get("growth")
    if s["chaotic"]:
        parts.append("<div class='box chaos'>This scene is <b>chaotic</b>: nearby trajectories separate exponentially, so two "
                     "correct integrators that differ at rounding level must eventually diverge. The report gives the "
                     f"divergence time (first |&Delta;q| &gt; {tr['divergence_threshold']:g}) and the fitted growth rate "
                     "instead of calling the difference an error."
                     + (f" Fit: |&Delta;q| &asymp; 10<sup>{g['log10_intercept']:.2f}</sup> exp({g['rate']:.3g} t) over "
                        f"t = {g['window'][0]:.3g}..{g['window'][1]:.3g} s ({g['decades']:.1f} decades, e-folding time "
                        f"{g['e_folding_time']:.3g} s)." if g and g.get("e_folding_time") else "") + "</div>")
    return parts


def _energy_section(c, s, light=False) -> list[str]:
    e = html.escape
    en = s["energy"]
    parts = ["<h2>3. Energy</h2>",
            f"<p>Quantity balanced: {e(en['quantity'])}. {e(en['note'][0].upper() + en['note'][1:])}. Energy scale of the relative "
            f"drifts: {fmt(en['scale'])} J, {e(en.get('scale_note') or 'the max of |E|, |V - V(0)|, |W|')}; largest difference of E + V between the engines: "
            f"{fmt(en['max_engine_difference'])} J.</p>",
            _rows([["urdf2links", fmt(en["project_drift"]), fmt(en["project_drift_rel"])],
                   ["MuJoCo", fmt(en["mujoco_drift"]), fmt(en["mujoco_drift_rel"])]],
                  ["engine", "drift (J)", "relative to scale"], num_cols=(1, 2))]
    if not light:
        parts.append(f"<img alt='energy' src='data:image/png;base64,{plot_energy(c, s)}'>")
    return parts


def _wall_section(s) -> int:
    return _first_closing(s) + (1 if s["base"]["moving"] else 0)


def _first_closing(s) -> int:
    """The number of the first closing section: after the coverage section (4) when there is one."""
    return 5 if s.get("coverage") else 4


def _inputs_words(wt) -> str:
    return {"none": "none (no control callback)",
            "compiled": f"the compiled control callback ({wt['mujoco_callback_calls']} calls)",
            "python": f"the Python control callback ({wt['mujoco_callback_calls']} calls; its time is in the engine's)",
            }.get(wt["mujoco_inputs"], str(wt["mujoco_inputs"]))


def _compile_words(wt) -> str:
    """Compilation, on its own line when it happened."""
    out = []
    if wt["project_compiled"]:
        out.append(f"urdf2links warm-up: numba compiled {len(wt['project_compiled'])} function(s) in "
                   f"{wt['project_warmup_s']:.1f} s (once; not in the timed run).")
    else:
        out.append(f"urdf2links warm-up {wt['project_warmup_s']:.2f} s (compiled code loaded from numba's cache).")
    if wt["mujoco_callback_compiled"]:
        out.append(f"MuJoCo's control callback compiled in {wt['mujoco_callback_load_s']:.1f} s (once).")
    return " ".join(out)


def _closing_sections(s, command) -> list[str]:
    """Base motion (when it moves), wall time, notes, where the figures are."""
    e = html.escape
    wt, mj, pr, r2 = s["wall_time"], s["mujoco"], s["project"], s["terms"]["route2"]
    parts = []
    n_sec = _first_closing(s)
    if s["base"]["moving"]:
        parts.append(f"<h2>{n_sec}. Base motion</h2>")
        parts.append(f"<p>The base {{A}} moves as prescribed by the scene; MuJoCo's <code>base_A</code> body is driven "
                     f"through <code>qfrc_applied</code> so that its acceleration is the prescribed one. Largest distance "
                     f"from the prescribed pose over the run: <b>{fmt(s['base']['tracking_error'])}</b> (m, rad).</p>")
        n_sec += 1
    parts.append(f"<h2>{n_sec}. Wall time</h2>")
    parts.append(_rows([["urdf2links", e(pr["method"]), str(pr["nsteps"]), fmt(wt["project_s"], 3, " s"),
                         fmt(wt["project_run_s"], 3, " s")],
                        ["MuJoCo", e(f"{mj['integrator']} dt {mj['timestep']:g}"), str(mj["nsteps"]),
                         fmt(wt["mujoco_s"], 3, " s"), fmt(wt["mujoco_harness_s"], 3, " s")]],
                       ["engine", "integrator", "steps", "timed: the integration", "whole call"], num_cols=(2, 3, 4)))
    regions = wt["regions"]
    parts.append("<p class='small'><b>Timed.</b> " + e(regions["project_s"]) + ". " + e(regions["mujoco_s"])
                 + ". <b>Whole call.</b> urdf2links: " + e(regions["project_run_s"]) + "; MuJoCo: "
                 + e(regions["mujoco_harness_s"]) + f". MuJoCo's inputs: {e(_inputs_words(wt))}.</p>")
    parts.append(f"<p class='small'>{e(_compile_words(wt))} Terms: {fmt(wt['terms_s'], 2, ' s')}; whole comparison "
                 f"{fmt(wt['total_s'], 2, ' s')}; {e(wt['note'])}.</p>")
    if s["notes"]:
        parts.append("<h2>Notes</h2><ul class='notes'>" + "".join(f"<li>{e(n)}</li>" for n in s["notes"]) + "</ul>")
    if r2.get("notes"):
        parts.append("<details><summary class='small'>route 2 notes (MuJoCo's URDF import)</summary><ul class='notes'>"
                     + "".join(f"<li>{e(n)}</li>" for n in r2["notes"]) + "</ul></details>")
    parts.append("<p class='small'>Figures: <a href='summary.json'>summary.json</a>, <a href='summary.md'>summary.md</a>."
                 + (f" Regenerate: <code>{e(command)}</code>" if command else "") + "</p>")
    return parts


def render_html(c, summary: dict, *, command: str | None = None, check: "CheckResult | None" = None,
                index_link: str | None = None, animation_fps: float = DEFAULT_FPS, index_label: str = "all scenes",
                light: bool = False, extra_sections=(), first_sections=(), headline=None) -> str:
    """The scene's self-contained report page (plots as base64 PNG, the motion section's viewer
    inlined); ``index_link``: relative address of the index page, if any, shown as ``index_label``;
    ``animation_fps``: frames per second of simulated time of the motion section (0: no motion
    section). ``light``: no motion section and one overview figure
    (:func:`~urdf2links.compare.reports.plots.plot_overview`: the difference and both energy balances)
    instead of the four plots, for pages made by the dozen (a corpus); ``extra_sections``: HTML
    fragments put after the energy section; ``first_sections``: HTML fragments put first, after the headline
    figures (a comparison of two descriptions, :mod:`urdf2links.compare.pairs.report`), whose ``headline``
    (``{"title", "html"}``) is then the page's own."""
    motion = [] if light else motion_section(c, fps=animation_fps)
    parts = (_top(summary, check, index_link, index_label, headline) + list(first_sections) + motion + _terms_section(summary, light)
             + _trajectory_section(c, summary, light) + _energy_section(c, summary, light)
             + coverage_html(summary, 4, _rows) + list(extra_sections)
             + loop_section(summary.get("constraints"), _loop_series(c), summary["verdict"])     # issue 45
             + contact_section(c, summary)      # issue 37
             + _closing_sections(summary, command) + ["</body></html>"])
    return "\n".join(parts)


# --------------------------------------------------------------------------- Markdown


def render_markdown(s: dict) -> str:
    tr, en, te, wt, mj, pr = s["trajectory"], s["energy"], s["terms"], s["wall_time"], s["mujoco"], s["project"]
    lines = [f"# {s['robot']} / {s['scene']}: urdf2links against MuJoCo", "", s["description"], ""]
    if s.get("t_end_note"):
        lines += [f"> {s['t_end_note']}", ""]
    lines += [f"**Trajectories:** {tr['verdict']}", ""]
    if s.get("plausibility"):       # issue 43: what the gate checked, before any verdict
        lines += [f"**Plausibility:** {_gate_line(s['plausibility'])}.", ""]
    lines += [*coverage_markdown(s),
              f"t = 0..{s['t_end']:g} s; urdf2links {pr['method']}"
              + (f" rtol {pr['rtol']:g}" if pr["method"] not in ("RK4", "midpoint") else f" dt {pr['dt']:g}")
              + f"; MuJoCo {mj['integrator']} dt {mj['timestep']:g} s; {s['route_description']}.", "",
              "| figure | value |", "|---|---|",
              f"| terms max relative error (route 1 / route 2) | {fmt_md(te['max_rel_error'])} "
              f"({fmt_md(te['max_rel_error_route1'])} / {fmt_md(te['max_rel_error_route2'])}) |",
              f"| route 2 | {te['route2'].get('label', '-')} |",
              f"| trajectory max abs error | {fmt_md(tr['max_abs_error'])} |",
              f"| divergence time (> {tr['divergence_threshold']:g}) | {fmt_t(tr['divergence_time'])} |"]
    if tr.get("growth_rate") is not None:
        lines.append(f"| growth rate of the difference | {fmt_md(tr['growth_rate'])} /s |")
    lines += [f"| energy drift urdf2links | {fmt_md(en['project_drift'])} J ({fmt_md(en['project_drift_rel'])} relative) |",
              f"| energy drift MuJoCo | {fmt_md(en['mujoco_drift'])} J ({fmt_md(en['mujoco_drift_rel'])} relative) |"]
    if s["base"]["moving"]:
        lines.append(f"| base tracking error | {fmt_md(s['base']['tracking_error'])} |")
    lines += [f"| wall time urdf2links (the integrator) | {wt['project_s']:.3g} s ({pr['nsteps']} steps; whole "
              f"simulate() {wt['project_run_s']:.3g} s) |",
              f"| wall time MuJoCo (the engine) | {wt['mujoco_s']:.3g} s ({mj['nsteps']} steps; whole run "
              f"{wt['mujoco_harness_s']:.3g} s; inputs: {_inputs_words(wt)}) |", "",
              f"Energy: {en['quantity']}; {en['note']}.", "",
              f"Timed regions: urdf2links: {wt['regions']['project_s']}. MuJoCo: {wt['regions']['mujoco_s']}. "
              + _compile_words(wt), ""]
    lines += contact_markdown(s)        # issue 37: a [[contact]] scene's ground and MuJoCo's native contact
    lines += loop_markdown(s.get("constraints"), s["verdict"])      # issue 45: the closed loops
    return "\n".join(lines)


# --------------------------------------------------------------------------- files


def _loop_series(c):
    got = getattr(c, "info", {}).get("loop_figures")
    return None if got is None else got[1]


def with_loop_sections(c, summary: dict) -> dict:
    """``summary`` of a comparison ``c`` with its closed loops (issue 45): ``constraints`` (the residual, the forces
    against MuJoCo's ``efc_force``, the solref study: :func:`~urdf2links.compare.agreement.constraint_agreement.loop_figures`,
    computed once per comparison and kept in ``c.info``) and the loops' agreement stated in the verdict
    (:func:`~urdf2links.compare.agreement.verdict.with_loops`). Unchanged for a run without constraint rows."""
    traj = getattr(c, "traj", None)
    cons = None if traj is None else traj.stats.get("constraints")
    if not cons or not cons.get("rows"):
        return summary
    if "loop_figures" not in c.info:
        try:
            c.info["loop_figures"] = loop_figures(c)
        except Exception as exc:     # a failed section must not lose the report (nor `report`'s other scenes)
            c.info["loop_figures"] = ({"error": f"{type(exc).__name__}: {exc}"}, None)
    loops = json_ready(c.info["loop_figures"][0])
    if "error" in loops:
        verdict = {**summary["verdict"], "text": summary["verdict"]["text"].rstrip(".")
                   + f"; the loops were NOT compared ({loops['error']})."}
        return {**summary, "constraints": loops, "verdict": verdict,
                "trajectory": {**summary["trajectory"], "verdict": verdict["text"]}}
    verdict = json_ready(with_loops(summary["verdict"], loops))
    trajectory = {**summary["trajectory"], "verdict": verdict["text"]}
    return {**summary, "constraints": loops, "verdict": verdict, "trajectory": trajectory}


def write_report(c, out_dir=None, *, root=None, json_path=None, command: str | None = None,
                 check: "CheckResult | None" = None, index_link: str | None = None,
                 animation_fps: float = DEFAULT_FPS, first_sections=(), summary_extra: dict | None = None,
                 headline=None, first_markdown: str | None = None) -> dict:
    """Write ``report.html``, ``summary.json`` and ``summary.md`` for comparison ``c`` into
    ``out_dir`` (default ``<root>/<robot>/<scene>/``, ``root`` default ``out/reports``, whose page then links ``../../index.html``;
    else ``index_link``) and, if given, the summary also to ``json_path``; ``animation_fps`` as
    :func:`render_html`; ``first_sections`` go first on the page and ``summary_extra`` (keys added to the
    summary) into ``summary.json``: a comparison of two descriptions, whose ``headline`` (``{"title", "html"}``)
    is the page's and whose ``first_markdown`` opens ``summary.md`` (the usual Markdown follows, its headings one
    level down). Returns ``{"dir", "html", "json", "md", "summary"}``."""
    summary = with_loop_sections(c, json_ready({**c.summary(), **(summary_extra or {})}))
    if out_dir is None:
        out = Path(DEFAULT_OUT if root is None else root) / summary["robot"] / summary["scene"]
        index_link = index_link or "../../index.html"
    else:
        out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    text = json.dumps(summary, indent=2) + "\n"
    (out / "summary.json").write_text(text)
    if json_path is not None:
        jp = Path(json_path)
        jp.parent.mkdir(parents=True, exist_ok=True)
        jp.write_text(text)
    md = render_markdown(summary)
    if first_markdown:
        md = first_markdown.rstrip("\n") + "\n\n" + "\n".join("#" + x if x.startswith("#") else x for x in md.split("\n"))
    (out / "summary.md").write_text(md)
    (out / "report.html").write_text(render_html(c, summary, command=command, check=check, index_link=index_link,
                                                 animation_fps=animation_fps, first_sections=first_sections,
                                                 headline=headline), encoding="utf-8")
    if (out / "tradeoff.json").is_file():  # a work-precision study of this scene (urdf2links tradeoff): its section
        try:
            insert_section(out / "report.html", json.loads((out / "tradeoff.json").read_text()))
        except (ValueError, KeyError, TypeError) as err:  # an unreadable study must not break the report
            print(f"report: {out / 'tradeoff.json'} not included: {type(err).__name__}: {err}", file=sys.stderr)
    return {"dir": out, "html": out / "report.html", "json": out / "summary.json", "md": out / "summary.md",
            "summary": summary}


def _index_row(s: dict, link: str, chk: "CheckResult | None") -> list[str]:
    """One scene's row of ``index.html`` (:func:`write_index`): its cells, HTML."""
    e = html.escape
    tr, en, te, wt = s["trajectory"], s["energy"], s["terms"], s["wall_time"]
    r2 = te["max_rel_error_route2"]
    check = "&ndash;" if chk is None else ("<span class='ok'>ok</span>" if chk.ok else
                                            "<span class='fail'>FAIL</span><br><span class='small'>"
                                            + e(", ".join(chk.failures)) + "</span>")
    acts = ", ".join({"G": "gravity", "spring": "springs", "damper": "dampers", "tau": "torques",
                      "Q": "loads"}.get(x, x) for x in s["effects"] if x not in ("A", "e")) or "nothing"
    r2cell = "skipped<br><span class='small'>floating base</span>" if r2 is None else (
        fmt(r2, 1) + ("<br><span class='small'>repaired</span>" if "REPAIRED" in te["route2"].get("label", "") else ""))
    divcell = fmt_t(tr["divergence_time"]) + ("<br><span class='small'>chaotic" + (
        f", growth {tr['growth_rate']:.2g}/s" if tr.get("growth_rate") else "") + "</span>" if s["chaotic"] else "")
    tcell = f"{s['t_end']:g} s" + (f"<br><span class='small'>scene {s['t_end_scene']:g} s</span>"
                                  if s["t_end"] != s["t_end_scene"] else "")
    return [f"<a href='{e(link)}'>{e(s['scene'])}</a><br><span class='small'>{e(s['robot'])}</span>", e(acts),
            tcell, fmt(te["max_rel_error_route1"], 1), r2cell, fmt(tr["max_abs_error"], 1), divcell,
            fmt(en["project_drift_rel"], 1), fmt(en["mujoco_drift_rel"], 1),
            fmt(s["base"]["tracking_error"], 1) if s["base"]["moving"] else "&ndash;", coverage_cell(s),
            f"{wt['project_s']:.2f}", f"{wt['mujoco_s']:.2f}", check]


def _index_md_row(s: dict, link: str) -> str:
    """One scene's line of ``index.md`` (:func:`write_index`)."""
    tr, en, te, wt = s["trajectory"], s["energy"], s["terms"], s["wall_time"]
    div = fmt_t(tr["divergence_time"])
    if s["chaotic"]:
        div += " (chaotic" + (f"; growth {tr['growth_rate']:.2g}/s" if tr.get("growth_rate") else "") + ")"
    r2 = te["max_rel_error_route2"]
    r2s = fmt(r2) + (" (repaired)" if "REPAIRED" in te["route2"].get("label", "") else "") if r2 is not None else "skipped"
    t_end = f"{s['t_end']:g} s" + (f" (scene {s['t_end_scene']:g})" if s["t_end"] != s["t_end_scene"] else "")
    return (f"| {s['robot']} | [{s['scene']}]({link}) | {t_end} | {fmt_md(te['max_rel_error_route1'])} / "
            f"{r2s.replace('&ndash;', '-')} | {fmt_md(tr['max_abs_error'])} | {div} | "
            f"{fmt_md(en['project_drift_rel'])} / {fmt_md(en['mujoco_drift_rel'])} | "
            f"{fmt_md(s['base']['tracking_error']) if s['base']['moving'] else '-'} | "
            f"{coverage_cell(s, markdown=True)} | {wt['project_s']:.2f} / {wt['mujoco_s']:.2f} |")


def write_index(entries, out_root, *, note: str = "", command: str | None = None, corpus_link: str | None = None,
                stopped=()) -> dict:
    """``index.html`` and ``index.md`` in ``out_root``: one row per (summary, link, check) entry,
    ``entries`` a list of dicts ``{"summary": ..., "link": relative path of report.html, "check":
    CheckResult or None}``; ``corpus_link``: relative address of a corpus report
    (``urdf2links report --corpus``), linked under the title; ``stopped``: the hard cases that stopped by
    design (:mod:`urdf2links.compare.reports.stops`), in a section of their own."""
    root = Path(out_root)
    root.mkdir(parents=True, exist_ok=True)
    e = html.escape
    header = ["scene<br><span class='small'>robot</span>", "what acts", "t<sub>end</sub>",
              "terms<br>route 1", "terms<br>route 2", "trajectory<br>max |&Delta;q|",
              "divergence<br>|&Delta;q| &gt; 1e-3", "energy drift<br>(rel.) urdf2links", "energy drift<br>(rel.) MuJoCo",
              "base<br>tracking", "coverage", "wall (s)<br>urdf2links", "wall (s)<br>MuJoCo", "baseline<br>check"]
    rows = []
    md = ["| robot | scene | t_end | terms max rel. error (route 1 / route 2) | trajectory max abs error | divergence | "
          "energy drift rel. (urdf2links / MuJoCo) | base tracking | coverage | wall s (urdf2links / MuJoCo) |",
          "|---|---|---|---|---|---|---|---|---|---|"]
    for ent in entries:
        rows.append(_index_row(ent["summary"], ent["link"], ent.get("check")))
        md.append(_index_md_row(ent["summary"], ent["link"]))
    first = entries[0]["summary"] if entries else None
    settings = ""
    if first:
        settings = (f"MuJoCo {e(first['mujoco']['integrator'])} with timestep {first['mujoco']['timestep']:g} s (route 1: the "
                    "project's tree as MJCF, base motion prescribed) against the project's integrator as each scene sets it. ")
    parts = [f"<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'><title>urdf2links against MuJoCo</title>"
             f"<style>{_CSS} body {{ max-width: 1180px; }} table {{ font-size: 0.84em; }} td, th {{ padding: 4px 6px; }}</style></head><body>",
             "<h1>urdf2links against MuJoCo: accuracy reports</h1>",
             "<p class='sub'>Every shipped scene run by both engines from the same initial state with the same loads; "
             "terms at identical states, trajectories, energies, wall time.</p>",
             f"<div class='box'>{settings}{e(note)}</div>",
             (f"<p><b><a href='{e(corpus_link)}'>Corpus report</a></b>: every robot of a corpus of real robot "
              "descriptions against MuJoCo, each in its default scene (<code>urdf2links report --corpus</code>).</p>"
              if corpus_link else ""),
             _rows(rows, header, num_cols=(3, 4, 5, 7, 8, 9, 11, 12)), stops_html(list(stopped)),
             "<p class='small'>terms: max |ours &minus; MuJoCo| / max |MuJoCo| of A (mj_fullM) and e + G (qfrc_bias) at "
             "seeded random states; route 1 = the project's tree as MJCF, route 2 = MuJoCo's own URDF import (fixed base "
             "only; \"repaired\" when MuJoCo refused the file). Trajectory errors in rad (m for translations). Energy drift: "
             "max |h &minus; h(0) &minus; W| over the energy scale (h = E + V for a fixed base). Wall times are the "
             "integration loops. Energy drifts are relative to each scene's energy scale (max of |E|, |V &minus; V(0)|, |W|); "
             "the scene reports give them in J. Coverage: how many coordinates moved by more than 1e-3 (rad or m) in "
             "the run; <b>weak evidence</b> when fewer than half did (E67).</p>"]
    if command:
        parts.append(f"<p class='small'>Regenerate: <code>{e(command)}</code></p>")
    parts.append("</body></html>")
    (root / "index.html").write_text("\n".join(parts))
    md_link = corpus_link.removesuffix("index.html") + "corpus.md" if corpus_link else None
    corpus_md = [f"Corpus report: [{md_link}]({md_link}) and {corpus_link} (every robot of a corpus against MuJoCo, "
                 "each in its default scene).", ""] if corpus_link else []
    md_text = "\n".join(["# urdf2links against MuJoCo", "", (note + "\n") if note else "", *corpus_md, *md,
                         *stops_md(list(stopped)), ""])
    (root / "index.md").write_text(md_text)
    return {"html": root / "index.html", "md": root / "index.md", "table": "\n".join([*md, *stops_md(list(stopped))])}

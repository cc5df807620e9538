"""Reports of the MuJoCo cross-validation: a self-contained HTML page, ``summary.json`` and
``summary.md`` per scene, an index page over scenes, and the regression check against baselines.

* :func:`write_report` writes ``report.html`` (plots embedded as base64 PNG: coordinates of both
  engines overlaid, error against time (log), energy of both engines, agreement of the terms),
  ``summary.json`` (:meth:`compare.trajectory.SceneComparison.summary`, non-finite numbers
  written as the strings ``"nan"``/``"inf"``) and ``summary.md`` into
  ``<root>/<robot>/<scene>/`` (or a given folder).
  When the folder holds a ``tradeoff.json`` (``urdf2links tradeoff``), the page gets its
  work-precision section (:func:`compare.tradeoff_plots.render_section`).
* :func:`write_index` writes ``index.html`` and ``index.md``: one row per robot and scene with the
  headline figures and links.
* :func:`check_baseline` compares a summary with the accepted figures of ``baselines.json``
  (:func:`baseline_entry`, :func:`write_baselines`): a figure fails when it grows past
  ``factor`` (default :data:`DEFAULT_FACTOR`) times its baseline (or times a floor, for figures
  at rounding level that jitter); a divergence time fails when it comes earlier than the
  baseline's by more than the time the error needs to grow by ``factor``. Wall times are not
  checked.
"""

from __future__ import annotations

import base64
import html
import io
import json
import math
import sys
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = [
    "write_report",
    "render_html",
    "render_markdown",
    "write_index",
    "json_ready",
    "baseline_entry",
    "write_baselines",
    "load_baselines",
    "select_run",
    "check_baseline",
    "CheckResult",
    "CHECKED_FIGURES",
    "DEFAULT_FACTOR",
]

#: Allowed growth of an error figure over its baseline before ``--check`` fails.
DEFAULT_FACTOR = 10.0

#: Figures ``--check`` compares, with the floor under which a baseline is treated as the floor
#: (numbers at rounding level jitter between machines). A floor given as ``("energy", x)`` is
#: ``x`` times the scene's energy scale ``energy.scale`` (J).
CHECKED_FIGURES = {
    "terms.max_rel_error": 1e-14,
    "terms.max_rel_error_route1": 1e-14,
    "terms.max_rel_error_route2": 1e-14,
    "trajectory.max_abs_error": 1e-12,
    "energy.project_drift": ("energy", 1e-13),
    "energy.mujoco_drift": ("energy", 1e-13),
    "base.tracking_error": 1e-12,
}


# --------------------------------------------------------------------------- JSON


def json_ready(x):
    """``x`` with numpy scalars/arrays made plain and non-finite floats written as strings."""
    if isinstance(x, dict):
        return {str(k): json_ready(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [json_ready(v) for v in x]
    if isinstance(x, np.ndarray):
        return json_ready(x.tolist())
    if isinstance(x, (np.bool_, bool)):
        return bool(x)
    if isinstance(x, (np.integer, int)):
        return int(x)
    if isinstance(x, (np.floating, float)):
        v = float(x)
        return v if math.isfinite(v) else ("nan" if math.isnan(v) else ("inf" if v > 0 else "-inf"))
    if isinstance(x, Path):
        return str(x)
    return x


def get(summary: dict, dotted: str):
    """``summary["a"]["b"]`` for ``"a.b"``; None when missing."""
    cur = summary
    for part in dotted.split("."):
        if not isinstance(cur, dict) or part not in cur:
            return None
        cur = cur[part]
    return cur


# --------------------------------------------------------------------------- formatting


def fmt(x, digits: int = 2, unit: str = "") -> str:
    if x is None:
        return "&ndash;"
    if isinstance(x, str):
        return html.escape(x)
    if isinstance(x, bool):
        return "yes" if x else "no"
    if isinstance(x, (int, np.integer)):
        return f"{int(x)}{unit}"
    v = float(x)
    if not math.isfinite(v):
        return str(v)
    if v == 0:
        return "0" + unit
    a = abs(v)
    s = f"{v:.{digits}e}" if (a < 1e-2 or a >= 1e5) else f"{v:.{digits + 1}g}"
    return s + unit


def fmt_t(x) -> str:
    return "none" if x is None else f"{float(x):.4g} s"


def _md(x, digits=2, unit="") -> str:
    return fmt(x, digits, unit).replace("&ndash;", "-")


# --------------------------------------------------------------------------- plots


def _figure(w, h):
    from matplotlib.figure import Figure

    return Figure(figsize=(w, h), dpi=90, layout="constrained")


def _png(fig) -> str:
    """The figure as base64 PNG, reduced to a 256-colour palette (a third of the size; the plots
    are line art on white)."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", metadata={"Software": None})
    try:
        from PIL import Image

        img = Image.open(io.BytesIO(buf.getvalue())).convert("RGB").quantize(colors=256, method=Image.Quantize.MEDIANCUT)
        small = io.BytesIO()
        img.save(small, format="PNG", optimize=True)
        if small.tell() < buf.tell():
            buf = small
    except Exception:  # Pillow missing or failing: keep matplotlib's PNG
        pass
    return base64.b64encode(buf.getvalue()).decode("ascii")


def _every(m: int, most: int = 1500) -> slice:
    """A stride that keeps at most ``most`` of ``m`` samples for plotting (the last one included
    when the stride divides evenly; the figures themselves use every sample)."""
    return slice(None, None, max(1, math.ceil(m / most)))


def _unit(name: str, model) -> str:
    """'m' for a translation coordinate, 'rad' otherwise."""
    info = {c.get("name"): c for c in model.info.get("coordinates", []) if isinstance(c, dict)}
    c = info.get(name, {})
    return "m" if c.get("slot") in ("x", "y", "z") or c.get("type") == "prismatic" else "rad"


def plot_coordinates(c) -> str:
    names = c.coordinate_names
    n = max(len(names), 1)
    cols = 1 if n == 1 else 2
    rows = math.ceil(n / cols)
    fig = _figure(11, 1.9 * rows + 0.5)
    axes = fig.subplots(rows, cols, squeeze=False, sharex=True)
    k = _every(len(c.t))
    for j, name in enumerate(names):
        ax = axes[j // cols][j % cols]
        ax.plot(c.t[k], c.q_ours[k, j], color="C0", lw=2.2, label="urdf2links")
        ax.plot(c.t[k], c.q_mujoco[k, j], color="C1", lw=1.2, ls=(0, (4, 3)), label="MuJoCo")
        ax.set_ylabel(f"{name} ({_unit(name, c.model)})", fontsize=9)
        ax.grid(alpha=0.3)
        if j == 0:
            ax.legend(loc="best", fontsize=8)
    for j in range(len(names), rows * cols):
        axes[j // cols][j % cols].set_visible(False)
    for ax in axes[-1]:
        ax.set_xlabel("t (s)")
    fig.suptitle("coordinates: urdf2links (solid) and MuJoCo (dashed) from the same initial state", fontsize=11)
    return _png(fig)


def plot_error(c, summary) -> str:
    fig = _figure(11, 4.2)
    ax = fig.subplots()
    k = _every(len(c.t), 1000)
    for j, name in enumerate(c.coordinate_names):
        e = np.where(c.error[:, j] > 0, c.error[:, j], np.nan)
        ax.semilogy(c.t[k], e[k], lw=0.9, label=name)
    tr = summary["trajectory"]
    if c.error.size:
        env = np.maximum.accumulate(c.error.max(axis=1))
        ax.semilogy(c.t, np.where(env > 0, env, np.nan), color="k", lw=1.6, label="running max (all samples)")
    show_threshold = c.scene.chaotic or tr["divergence_time"] is not None or tr["max_abs_error"] > 1e-3 * c.threshold
    if show_threshold:
        ax.axhline(c.threshold, color="C3", ls="--", lw=1.2, label=f"divergence threshold {c.threshold:g}")
    if tr["divergence_time"] is not None:
        ax.axvline(tr["divergence_time"], color="C3", ls=":", lw=1.5,
                   label=f"divergence t = {tr['divergence_time']:.3g} s")
    g = c.growth
    if g:
        tt = np.linspace(g["window"][0], g["window"][1], 50)
        ax.semilogy(tt, 10 ** (g["log10_intercept"] + g["rate"] * tt / np.log(10.0)), color="C3", lw=2.2, alpha=0.6,
                    label=f"fit exp({g['rate']:.3g} t)")
    ax.set_xlabel("t (s)")
    ax.set_ylabel("|q urdf2links - q MuJoCo| (rad or m)")
    ax.grid(alpha=0.3, which="both")
    ax.legend(loc="lower right", fontsize=8, ncol=2)
    ax.set_title("trajectory difference per coordinate" + (" (chaotic scene: growth is expected)" if c.scene.chaotic else ""),
                 fontsize=11)
    return _png(fig)


def plot_energy(c, summary) -> str:
    en = c.energy
    moving = c.scene.base is not None
    work = summary["energy"]["work_terms"]
    k = _every(len(c.t))
    fig = _figure(11, 8.2 if moving else 6.0)
    axes = fig.subplots(3 if moving else 2, 1, sharex=True, height_ratios=[3, 3, 2] if moving else [3, 2])
    ax = axes[0]
    ax.plot(c.t[k], en["ours_EV"][k], color="C0", lw=2.2, label="urdf2links E + V")
    ax.plot(c.t[k], en["mujoco_EV"][k], color="C1", lw=1.2, ls=(0, (4, 3)), label="MuJoCo E + V (mjENBL_ENERGY)")
    if work and not moving:
        ax.plot(c.t[k], (en["ours_EV"][0] + en["work"])[k], color="0.35", lw=1.0, ls=":",
                label="(E + V)(0) + W (W: work done on the robot)")
    ax.set_ylabel("E + V (J)")
    ax.grid(alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    ax.set_title("energy of both engines" + (" (moving base: E + V in {0}; h is what the base's work balances)"
                                             if moving else ""), fontsize=11)
    if moving:
        ax = axes[1]
        ax.plot(c.t[k], en["ours_h"][k], color="C0", lw=2.2, label="urdf2links h = E2 - E0 + V")
        ax.plot(c.t[k], en["mujoco_h"][k], color="C1", lw=1.2, ls=(0, (4, 3)), label="MuJoCo h (from its energies)")
        ax.plot(c.t[k], (en["ours_h"][0] + en["work"])[k], color="0.35", lw=1.0, ls=":",
                label="h(0) + W (W: work of the base and dampers)")
        ax.set_ylabel("energy function h (J)")
        ax.grid(alpha=0.3)
        ax.legend(loc="best", fontsize=8)
    ax = axes[-1]
    for key, color, label in (("ours_balance", "C0", "urdf2links"), ("mujoco_balance", "C1", "MuJoCo")):
        b = np.abs(en[key])
        ax.semilogy(c.t[k], np.where(b > 0, b, np.nan)[k], color=color, lw=1.0, label=label)
    sym = "h" if moving else "(E + V)"
    ax.set_ylabel(f"|{sym} - {sym}(0)" + (" - W|" if work else "|") + " (J)")
    ax.set_xlabel("t (s)")
    ax.grid(alpha=0.3, which="both")
    ax.legend(loc="lower right", fontsize=8)
    return _png(fig)


def plot_terms(summary) -> str:
    r1, r2 = summary["terms"]["route1"], summary["terms"]["route2"]
    labels, values, colors = [], [], []
    for tag, r, col in (("route 1", r1, "C0"), ("route 2" + (" (repaired)" if "REPAIRED" in r2.get("label", "") else ""),
                                                 r2, "C2")):
        if "max_rel_error_A" not in r:
            continue
        labels += [f"{tag}: A vs mj_fullM", f"{tag}: e+G vs qfrc_bias"]
        values += [r["max_rel_error_A"], r["max_rel_error_bias"]]
        colors += [col, col]
    fig = _figure(11, 0.42 * len(labels) + 1.2)
    ax = fig.subplots()
    y = np.arange(len(labels))[::-1]
    v = np.maximum(np.asarray(values, float), 1e-18)
    ax.barh(y, v, color=colors, height=0.6, left=1e-18)
    ax.set_xscale("log")
    ax.set_xlim(1e-18, 1e-6)
    ax.set_yticks(y, labels, fontsize=9)
    ax.axvline(np.finfo(float).eps, color="0.3", ls=":", lw=1, label="machine epsilon 2.2e-16")
    ax.axvline(1e-10, color="C3", ls="--", lw=1, label="tolerance of the tests 1e-10")
    for yi, vi in zip(y, values):
        ax.text(max(vi, 1e-18) * 1.6, yi, f"{vi:.1e}", va="center", fontsize=8)
    ax.set_xlabel(f"max relative error over {r1['states']} seeded states")
    ax.legend(loc="lower right", fontsize=8)
    ax.grid(alpha=0.3, axis="x", which="both")
    return _png(fig)


# --------------------------------------------------------------------------- HTML


_CSS = """
body { font-family: -apple-system, 'Segoe UI', Helvetica, Arial, sans-serif; margin: 0 auto; max-width: 1120px;
       padding: 16px 24px 40px; color: #1d2330; line-height: 1.45; }
h1 { font-size: 1.6em; margin-bottom: 0.1em; } h2 { margin-top: 1.6em; border-bottom: 1px solid #d0d5de; padding-bottom: 3px; }
.sub { color: #5a6272; margin-top: 0; }
table { border-collapse: collapse; margin: 8px 0 14px; font-size: 0.92em; }
th, td { border: 1px solid #d0d5de; padding: 4px 9px; text-align: left; vertical-align: top; }
th { background: #eef1f6; } td.num { text-align: right; font-family: 'DejaVu Sans Mono', Menlo, monospace; white-space: nowrap; }
img { max-width: 100%; border: 1px solid #e3e6ec; margin: 6px 0; }
.box { border-left: 4px solid #3d7bd9; background: #f3f7fd; padding: 8px 14px; margin: 10px 0; }
.chaos { border-left-color: #d98c3d; background: #fdf7ef; }
.bad { border-left-color: #c9302c; background: #fbeeee; }
.ok { color: #1e7b34; font-weight: 600; } .fail { color: #c9302c; font-weight: 600; }
code { background: #f0f2f5; padding: 0 3px; border-radius: 3px; font-size: 0.92em; }
ul.notes li { margin: 2px 0; font-size: 0.9em; } .small { font-size: 0.88em; color: #5a6272; }
"""


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


def render_html(c, summary: dict, *, command: str | None = None, check: "CheckResult | None" = None,
                index_link: str | None = None) -> str:
    """The scene's self-contained report page (plots as base64 PNG); ``index_link``: relative
    address of the index page, if any."""
    s = summary
    e = html.escape
    tr, en, te, wt, mj, pr = s["trajectory"], s["energy"], s["terms"], s["wall_time"], s["mujoco"], s["project"]
    title = f"{s['robot']} / {s['scene']}: urdf2links against MuJoCo"
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
    head += [("wall time, urdf2links", fmt(wt["project_s"], 2, " s"), f"{pr['method']}, {pr['nsteps']} steps, {pr['nfev']} evaluations"),
             ("wall time, MuJoCo", fmt(wt["mujoco_s"], 2, " s"), f"{mj['integrator']} dt {mj['timestep']:g} s, {mj['nsteps']} steps")]

    verdict_cls = "box chaos" if s["chaotic"] else ("box bad" if tr["divergence_time"] is not None else "box")
    parts = [f"<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'><title>{e(title)}</title>"
             f"<style>{_CSS}</style></head><body>",
             f"<p class='small'><a href='{e(index_link)}'>&larr; all scenes</a></p>" if index_link else "",
             f"<h1>{e(s['robot'])} / {e(s['scene'])}</h1>",
             f"<p class='sub'>{e(s['description'])}</p>",
             f"<div class='{verdict_cls}'><b>Trajectories:</b> {e(tr['verdict'])}</div>"]
    if s.get("t_end_note"):
        parts.append(f"<div class='box chaos'>{e(s['t_end_note'])}</div>")
    if check is not None:
        parts.append(f"<div class='box{'' if check.ok else ' bad'}'><b>Baseline check:</b> "
                     + ("<span class='ok'>ok</span>" if check.ok else "<span class='fail'>FAILED</span> ("
                        + e(", ".join(check.failures)) + ")") + f" &mdash; {e(check.source)}</div>")
    parts.append("<h2>Headline figures</h2>")
    parts.append(_rows(head, ["figure", "value", "what"], num_cols=(1,)))

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
    parts.append(_rows(setup))

    # terms
    r1, r2 = te["route1"], te["route2"]
    parts.append("<h2>1. Terms at identical states</h2>")
    parts.append(f"<p>At {r1['states']} seeded random states (seed {r1['seed']}; q uniform in [-1, 1], qd standard normal"
                 + ("; a random base pose and rate, no base acceleration" if r1.get("moving_base") else "")
                 + "): the project's <code>A</code> against MuJoCo's <code>mj_fullM</code> and <code>e + G</code> "
                   "against <code>qfrc_bias</code>, as max|ours &minus; MuJoCo| / max|MuJoCo|.</p>")
    rows = [["route&nbsp;1", e(r1["label"]), *_route_rows(r1)]]
    r2_label = e(r2.get("label", "route 2"))
    if r2.get("skipped"):
        r2_label += f"<br><span class='small'>{e(r2['skipped'])}</span>"
    if r2.get("error"):
        r2_label += f"<br><span class='small'>{e(r2['error'])}</span>"
    rows.append(["route&nbsp;2", r2_label, *_route_rows(r2)])
    parts.append(_rows(rows, ["", "what MuJoCo loaded", "A", "e + G", "max"], num_cols=(2, 3, 4)))
    if r2.get("refusals"):
        parts.append("<p><b>MuJoCo refused the original file.</b> Attempts, in order:</p><ul class='notes'>")
        for ref in r2["refusals"]:
            parts.append(f"<li>{e(ref['attempt'])}: refused by {e(ref['by'])}: <code>{e(ref['reason'].splitlines()[0])}</code></li>")
        parts.append(f"<li>accepted: {e(r2.get('label', ''))}</li></ul>")
    parts.append(f"<img alt='terms' src='data:image/png;base64,{plot_terms(s)}'>")

    # trajectories
    parts.append("<h2>2. Trajectories</h2>")
    parts.append(f"<img alt='coordinates' src='data:image/png;base64,{plot_coordinates(c)}'>")
    parts.append(f"<img alt='error' src='data:image/png;base64,{plot_error(c, s)}'>")
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

    # energy
    parts.append("<h2>3. Energy</h2>")
    parts.append(f"<p>Quantity balanced: {e(en['quantity'])}. {e(en['note'][0].upper() + en['note'][1:])}. Energy scale (max of |E|, |V &minus; V(0)|, |W|): "
                 f"{fmt(en['scale'])} J; largest difference of E + V between the engines: {fmt(en['max_engine_difference'])} J.</p>")
    parts.append(_rows([["urdf2links", fmt(en["project_drift"]), fmt(en["project_drift_rel"])],
                        ["MuJoCo", fmt(en["mujoco_drift"]), fmt(en["mujoco_drift_rel"])]],
                       ["engine", "drift (J)", "relative to scale"], num_cols=(1, 2)))
    parts.append(f"<img alt='energy' src='data:image/png;base64,{plot_energy(c, s)}'>")

    # base, time
    n_sec = 4
    if s["base"]["moving"]:
        parts.append(f"<h2>{n_sec}. Base motion</h2>")
        parts.append(f"<p>The base {{A}} moves as prescribed by the scene; MuJoCo's <code>base_A</code> body is driven "
                     f"through <code>qfrc_applied</code> so that its acceleration is the prescribed one. Largest distance "
                     f"from the prescribed pose over the run: <b>{fmt(s['base']['tracking_error'])}</b> (m, rad).</p>")
        n_sec += 1
    parts.append(f"<h2>{n_sec}. Wall time</h2>")
    parts.append(_rows([["urdf2links", e(pr["method"]), str(pr["nsteps"]), fmt(wt["project_s"], 2, " s")],
                        ["MuJoCo", e(f"{mj['integrator']} dt {mj['timestep']:g}"), str(mj["nsteps"]), fmt(wt["mujoco_s"], 2, " s")]],
                       ["engine", "integrator", "steps", "wall time"], num_cols=(2, 3)))
    parts.append(f"<p class='small'>{e(wt['note'])}. Terms: {fmt(wt['terms_s'], 2, ' s')}; whole comparison "
                 f"{fmt(wt['total_s'], 2, ' s')}.</p>")
    if s["notes"]:
        parts.append("<h2>Notes</h2><ul class='notes'>" + "".join(f"<li>{e(n)}</li>" for n in s["notes"]) + "</ul>")
    if r2.get("notes"):
        parts.append("<details><summary class='small'>route 2 notes (MuJoCo's URDF import)</summary><ul class='notes'>"
                     + "".join(f"<li>{e(n)}</li>" for n in r2["notes"]) + "</ul></details>")
    parts.append("<p class='small'>Figures: <a href='summary.json'>summary.json</a>, <a href='summary.md'>summary.md</a>."
                 + (f" Regenerate: <code>{e(command)}</code>" if command else "") + "</p>")
    parts.append("</body></html>")
    return "\n".join(parts)


# --------------------------------------------------------------------------- Markdown


def render_markdown(s: dict) -> str:
    tr, en, te, wt, mj, pr = s["trajectory"], s["energy"], s["terms"], s["wall_time"], s["mujoco"], s["project"]
    lines = [f"# {s['robot']} / {s['scene']}: urdf2links against MuJoCo", "", s["description"], ""]
    if s.get("t_end_note"):
        lines += [f"> {s['t_end_note']}", ""]
    lines += [f"**Trajectories:** {tr['verdict']}", "",
              f"t = 0..{s['t_end']:g} s; urdf2links {pr['method']}"
              + (f" rtol {pr['rtol']:g}" if pr["method"] not in ("RK4", "midpoint") else f" dt {pr['dt']:g}")
              + f"; MuJoCo {mj['integrator']} dt {mj['timestep']:g} s; {s['route_description']}.", "",
              "| figure | value |", "|---|---|",
              f"| terms max relative error (route 1 / route 2) | {_md(te['max_rel_error'])} "
              f"({_md(te['max_rel_error_route1'])} / {_md(te['max_rel_error_route2'])}) |",
              f"| route 2 | {te['route2'].get('label', '-')} |",
              f"| trajectory max abs error | {_md(tr['max_abs_error'])} |",
              f"| divergence time (> {tr['divergence_threshold']:g}) | {fmt_t(tr['divergence_time'])} |"]
    if tr.get("growth_rate") is not None:
        lines.append(f"| growth rate of the difference | {_md(tr['growth_rate'])} /s |")
    lines += [f"| energy drift urdf2links | {_md(en['project_drift'])} J ({_md(en['project_drift_rel'])} relative) |",
              f"| energy drift MuJoCo | {_md(en['mujoco_drift'])} J ({_md(en['mujoco_drift_rel'])} relative) |"]
    if s["base"]["moving"]:
        lines.append(f"| base tracking error | {_md(s['base']['tracking_error'])} |")
    lines += [f"| wall time urdf2links | {wt['project_s']:.2f} s ({pr['nsteps']} steps) |",
              f"| wall time MuJoCo | {wt['mujoco_s']:.2f} s ({mj['nsteps']} steps) |", "",
              f"Energy: {en['quantity']}; {en['note']}.", ""]
    return "\n".join(lines)


# --------------------------------------------------------------------------- files


def write_report(c, out_dir=None, *, root="reports", json_path=None, command: str | None = None,
                 check: "CheckResult | None" = None, index_link: str | None = None) -> dict:
    """Write ``report.html``, ``summary.json`` and ``summary.md`` for comparison ``c`` into
    ``out_dir`` (default ``<root>/<robot>/<scene>/``, whose page then links ``../../index.html``;
    else ``index_link``) and, if given, the summary also to ``json_path``. Returns
    ``{"dir", "html", "json", "md", "summary"}``."""
    summary = json_ready(c.summary())
    if out_dir is None:
        out = Path(root) / summary["robot"] / summary["scene"]
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
    (out / "summary.md").write_text(render_markdown(summary))
    (out / "report.html").write_text(render_html(c, summary, command=command, check=check, index_link=index_link))
    if (out / "tradeoff.json").is_file():  # a work-precision study of this scene (urdf2links tradeoff): its section
        from .tradeoff_plots import insert_section

        try:
            insert_section(out / "report.html", json.loads((out / "tradeoff.json").read_text()))
        except (ValueError, KeyError, TypeError) as err:  # an unreadable study must not break the report
            print(f"report: {out / 'tradeoff.json'} not included: {type(err).__name__}: {err}", file=sys.stderr)
    return {"dir": out, "html": out / "report.html", "json": out / "summary.json", "md": out / "summary.md",
            "summary": summary}


def write_index(entries, out_root, *, note: str = "", command: str | None = None) -> dict:
    """``index.html`` and ``index.md`` in ``out_root``: one row per (summary, link, check) entry,
    ``entries`` a list of dicts ``{"summary": ..., "link": relative path of report.html, "check":
    CheckResult or None}``."""
    root = Path(out_root)
    root.mkdir(parents=True, exist_ok=True)
    e = html.escape
    header = ["scene<br><span class='small'>robot</span>", "what acts", "t<sub>end</sub>",
              "terms<br>route 1", "terms<br>route 2", "trajectory<br>max |&Delta;q|",
              "divergence<br>|&Delta;q| &gt; 1e-3", "energy drift<br>(rel.) urdf2links", "energy drift<br>(rel.) MuJoCo",
              "base<br>tracking", "wall (s)<br>urdf2links", "wall (s)<br>MuJoCo", "baseline<br>check"]
    rows = []
    md = ["| robot | scene | t_end | terms max rel. error (route 1 / route 2) | trajectory max abs error | divergence | "
          "energy drift rel. (urdf2links / MuJoCo) | base tracking | wall s (urdf2links / MuJoCo) |",
          "|---|---|---|---|---|---|---|---|---|"]
    for ent in entries:
        s, link, chk = ent["summary"], ent["link"], ent.get("check")
        tr, en, te, wt = s["trajectory"], s["energy"], s["terms"], s["wall_time"]
        div = fmt_t(tr["divergence_time"])
        if s["chaotic"]:
            div += " (chaotic" + (f"; growth {tr['growth_rate']:.2g}/s" if tr.get("growth_rate") else "") + ")"
        r2 = te["max_rel_error_route2"]
        r2s = fmt(r2) + (" (repaired)" if "REPAIRED" in te["route2"].get("label", "") else "") if r2 is not None else "skipped"
        t_end = f"{s['t_end']:g} s" + (f" (scene {s['t_end_scene']:g})" if s["t_end"] != s["t_end_scene"] else "")
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
        rows.append([f"<a href='{e(link)}'>{e(s['scene'])}</a><br><span class='small'>{e(s['robot'])}</span>", e(acts),
                     tcell, fmt(te["max_rel_error_route1"], 1), r2cell, fmt(tr["max_abs_error"], 1), divcell,
                     fmt(en["project_drift_rel"], 1), fmt(en["mujoco_drift_rel"], 1),
                     fmt(s["base"]["tracking_error"], 1) if s["base"]["moving"] else "&ndash;",
                     f"{wt['project_s']:.2f}", f"{wt['mujoco_s']:.2f}", check])
        md.append(f"| {s['robot']} | [{s['scene']}]({link}) | {t_end} | {_md(te['max_rel_error_route1'])} / "
                  f"{r2s.replace('&ndash;', '-')} | {_md(tr['max_abs_error'])} | {div} | "
                  f"{_md(en['project_drift_rel'])} / {_md(en['mujoco_drift_rel'])} | "
                  f"{_md(s['base']['tracking_error']) if s['base']['moving'] else '-'} | "
                  f"{wt['project_s']:.2f} / {wt['mujoco_s']:.2f} |")
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
             _rows(rows, header, num_cols=(3, 4, 5, 7, 8, 9, 10, 11)),
             "<p class='small'>terms: max |ours &minus; MuJoCo| / max |MuJoCo| of A (mj_fullM) and e + G (qfrc_bias) at "
             "seeded random states; route 1 = the project's tree as MJCF, route 2 = MuJoCo's own URDF import (fixed base "
             "only; \"repaired\" when MuJoCo refused the file). Trajectory errors in rad (m for translations). Energy drift: "
             "max |h &minus; h(0) &minus; W| over the energy scale (h = E + V for a fixed base). Wall times are the "
             "integration loops. Energy drifts are relative to each scene's energy scale (max of |E|, |V &minus; V(0)|, |W|); "
             "the scene reports give them in J.</p>"]
    if command:
        parts.append(f"<p class='small'>Regenerate: <code>{e(command)}</code></p>")
    parts.append("</body></html>")
    (root / "index.html").write_text("\n".join(parts))
    md_text = "\n".join(["# urdf2links against MuJoCo", "", (note + "\n") if note else "", *md, ""])
    (root / "index.md").write_text(md_text)
    return {"html": root / "index.html", "md": root / "index.md", "table": "\n".join(md)}


# --------------------------------------------------------------------------- baselines


def baseline_entry(summary: dict) -> dict:
    """The accepted figures of one scene (for ``baselines.json``): the checked figures, the
    divergence time and growth rate, and the run's settings."""
    figs = {k: get(summary, k) for k in CHECKED_FIGURES}
    return {
        "settings": {"t_end": summary["t_end"], "mujoco.integrator": summary["mujoco"]["integrator"],
                     "mujoco.timestep": summary["mujoco"]["timestep"], "project.method": summary["project"]["method"],
                     "project.rtol": summary["project"]["rtol"], "samples": summary["samples"]},
        "figures": {k: v for k, v in figs.items() if v is not None},
        "energy.scale": summary["energy"]["scale"],
        "trajectory.divergence_time": summary["trajectory"]["divergence_time"],
        "trajectory.growth_rate": summary["trajectory"].get("growth_rate"),
        "wall_time (not checked)": {"project_s": round(summary["wall_time"]["project_s"], 3),
                                    "mujoco_s": round(summary["wall_time"]["mujoco_s"], 3)},
    }


def _runs(scene_entry: dict) -> list[dict]:
    """The accepted runs of one scene: ``{"runs": [...]}``, or a single flat entry."""
    return list(scene_entry["runs"]) if "runs" in scene_entry else [scene_entry]


def _run_id(entry: dict) -> tuple:
    st = entry.get("settings", {})
    return (st.get("t_end"), st.get("mujoco.integrator"), st.get("mujoco.timestep"))


def write_baselines(summaries, path, *, factor: float | None = None) -> Path:
    """Write ``baselines.json``: ``{"about", "factor", "floors", "scenes": {"<robot>/<scene>":
    {"runs": [entry, ...]}}}``, one entry (:func:`baseline_entry`) per accepted run length and MuJoCo
    setting. Runs already in an existing file are kept unless this run replaces them (same
    ``t_end``, integrator and timestep): a capped run and a whole-scene run can both be accepted."""
    path = Path(path)
    old = load_baselines(path) if path.is_file() else {"scenes": {}}
    scenes = {k: {"runs": _runs(v)} for k, v in old.get("scenes", {}).items()}
    for summ in summaries:
        entry = baseline_entry(summ)
        runs = [r for r in scenes.get(summ["key"], {"runs": []})["runs"] if _run_id(r) != _run_id(entry)]
        runs.append(entry)
        runs.sort(key=lambda r: (r["settings"].get("t_end") or 0.0))
        scenes[summ["key"]] = {"runs": runs}
    data = {
        "about": ("Accepted figures of the MuJoCo cross-validation per shipped scene and run length (urdf2links "
                  "report --write-baselines). `urdf2links compare SCENE --check THIS_FILE` compares a run with the "
                  "shortest accepted run at least as long (same MuJoCo integrator and timestep preferred) and fails "
                  "when a figure grows past factor x max(baseline, floor) or a divergence comes earlier than the "
                  "baseline's by more than ln(factor) / growth rate. Wall times are recorded, not checked."),
        "factor": float(factor if factor is not None else old.get("factor", DEFAULT_FACTOR)),
        "floors": {k: (f"{v[1]:g} x energy.scale" if isinstance(v, tuple) else v) for k, v in CHECKED_FIGURES.items()},
        "scenes": dict(sorted(scenes.items())),
    }
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(json_ready(data), indent=2) + "\n")
    return path


def select_run(summary: dict, scene_entry: dict) -> tuple[dict, list[str]]:
    """The accepted run to compare ``summary`` with: among the runs with the same MuJoCo integrator
    and timestep (else all), the shortest whose ``t_end`` is at least the summary's (errors and
    drifts grow with time, so it bounds a shorter run); else the longest, with a warning."""
    runs = _runs(scene_entry)
    same = [r for r in runs if _run_id(r)[1:] == (summary["mujoco"]["integrator"], summary["mujoco"]["timestep"])]
    pool = same or runs
    T = float(summary["t_end"])
    longer = [r for r in pool if (r.get("settings", {}).get("t_end") or 0.0) >= T * (1 - 1e-9)]
    if longer:
        return min(longer, key=lambda r: r["settings"]["t_end"]), []
    chosen = max(pool, key=lambda r: r.get("settings", {}).get("t_end") or 0.0)
    return chosen, [f"this run ({T:g} s) is longer than every accepted run: compared with the longest "
                    f"({chosen.get('settings', {}).get('t_end')} s)"]


def load_baselines(path) -> dict:
    path = Path(path)
    data = json.loads(path.read_text())
    if not isinstance(data, dict) or "scenes" not in data:
        raise ValueError(f"{path}: not a baselines file (no 'scenes' table)")
    return data


@dataclass
class CheckResult:
    """Outcome of :func:`check_baseline`: ``ok``, the failing figure names, one line per figure,
    warnings (settings that differ from the baseline's), ``source`` (file and key)."""

    ok: bool
    failures: list[str] = field(default_factory=list)
    lines: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    source: str = ""

    def text(self) -> str:
        head = f"baseline check {'passed' if self.ok else 'FAILED'} ({self.source})"
        return "\n".join([head] + [f"  warning: {w}" for w in self.warnings] + [f"  {x}" for x in self.lines])


def _number(v):
    if isinstance(v, bool) or v is None:
        return None
    if isinstance(v, (int, float)):
        return float(v)
    if isinstance(v, str):
        try:
            return float(v)
        except ValueError:
            return None
    return None


def check_baseline(summary: dict, baselines: dict, *, factor: float | None = None, source: str = "") -> CheckResult:
    """Compare ``summary`` with its entry (key ``summary["key"]``) of ``baselines`` (see module doc).
    The accepted run is chosen by :func:`select_run`. A missing entry raises ``KeyError``."""
    key = summary["key"]
    scenes = baselines.get("scenes", {})
    if key not in scenes:
        raise KeyError(f"no baseline for {key!r} in {source or 'the baselines'} (it has {sorted(scenes)})")
    base, warn = select_run(summary, scenes[key])
    f = float(factor if factor is not None else baselines.get("factor", DEFAULT_FACTOR))
    st = base.get("settings", {})
    what = f"{key} (accepted run of {st.get('t_end', '?')} s), factor {f:g}"
    res = CheckResult(ok=True, source=f"{source}: {what}" if source else what, warnings=warn)
    now = {"t_end": summary["t_end"], "mujoco.integrator": summary["mujoco"]["integrator"],
           "mujoco.timestep": summary["mujoco"]["timestep"], "project.method": summary["project"]["method"],
           "project.rtol": summary["project"]["rtol"]}
    for k, v in now.items():
        if k in st and st[k] != v:
            res.warnings.append(f"{k} is {v!r}, the baseline's is {st[k]!r}: figures compared anyway")
    scale = _number(get(summary, "energy.scale")) or _number(base.get("energy.scale")) or 0.0
    for name, floor in CHECKED_FIGURES.items():
        b = _number(base.get("figures", {}).get(name))
        raw = get(summary, name)
        if b is None:
            continue
        v = _number(raw)
        if raw is None:
            res.lines.append(f"skip  {name}: not measured in this run (baseline {b:.3g})")
            continue
        fl = floor[1] * scale if isinstance(floor, tuple) else floor
        allowed = f * max(b, fl)
        if v is None or not math.isfinite(v) or v > allowed:
            res.ok = False
            res.failures.append(name)
            res.lines.append(f"FAIL  {name} = {raw if v is None else f'{v:.3g}'} grew past its baseline {b:.3g} "
                             f"(allowed {f:g} x max(baseline, floor {fl:.2g}) = {allowed:.3g})")
        else:
            res.lines.append(f"ok    {name} = {v:.3g} (baseline {b:.3g}, allowed {allowed:.3g})")
    d0 = _number(base.get("trajectory.divergence_time"))
    d = _number(get(summary, "trajectory.divergence_time"))
    if d0 is not None and d is not None:
        rate = _number(base.get("trajectory.growth_rate"))
        margin = math.log(f) / rate if rate and rate > 0 else 0.5 * d0
        earliest = d0 - margin
        name = "trajectory.divergence_time"
        if d < earliest:
            res.ok = False
            res.failures.append(name)
            res.lines.append(f"FAIL  {name} = {d:.4g} s is earlier than its baseline {d0:.4g} s by more than "
                             f"{margin:.3g} s (the time the difference needs to grow {f:g}x)")
        else:
            res.lines.append(f"ok    {name} = {d:.4g} s (baseline {d0:.4g} s, earliest allowed {earliest:.4g} s)")
    return res

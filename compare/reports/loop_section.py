"""The report's closed-loop sections (issue 45): the residual, the constraint forces against MuJoCo's, the solref study.

A scene with constraint rows (``[[constraint]]``, ``[constraints] from_file`` or ``mimic``) gets, in ``report.html``,
``summary.md`` and ``summary.json``'s ``constraints`` (from
:func:`urdf2links.compare.agreement.constraint_agreement.loop_figures`):

- **which loops** were closed, on which side (urdf2links: exact constraints with multipliers, E72, projected after
  every step, E74; MuJoCo: soft equality constraints at ``solref`` 1e-3 s, ``solimp`` 0.9999) and which were left
  open (the verdict's scope, :func:`urdf2links.compare.agreement.verdict.loop_scope`);
- **the residual** over the run: the project's max ``|Phi|`` and ``|Phi'|`` at its samples (and before any
  projection), MuJoCo's ``|efc_pos|`` and ``|efc_vel|`` of its equality rows along its own run (its soft
  constraint's violation), and the issue's bound 1e-9;
- **the constraint forces**: the project's ``lambda`` (E72; N on a point row, N m on an orientation or joint row)
  against MuJoCo's ``efc_force`` of the same rows (the same sign: ``J^T lambda = efc_J^T efc_force``), (a) at the
  project's own samples (MuJoCo's ``mj_forward`` at the same state, time and inputs: its ``Phi = Phi' = 0`` there,
  so only its regularizer separates the two) and (b) along MuJoCo's own run (its violation adds ``-k Phi - b Phi'``);
  the bound is on (a), 1e-2 of max ``|lambda|``;
- **the solref study**: three more MuJoCo runs over the first 0.25 s (``solref`` tau 1e-2, 1e-3, 1e-4 s, RK4 at
  ``min(dt, tau / 10)``), MuJoCo's largest distance from the project's run for each, and the rate per decade.

The loops' agreement (residual below 1e-9, forces within the bound, MuJoCo approaching at least 5x per 10x smaller
tau or the trajectories within the divergence threshold) is stated in the verdict
(:func:`urdf2links.compare.agreement.verdict.with_loops`).
"""

from __future__ import annotations

import html

import numpy as np

from ..figures import figure, margins, png_base64
from ..formatting import fmt
from .plots import _log_axis

__all__ = ["loop_section", "loop_markdown", "plot_residual", "plot_forces", "plot_study"]


def _stride(m: int, most: int = 1200) -> slice:
    return slice(None, None, max(1, -(-m // most)))


def _positive(x):
    x = np.abs(np.asarray(x, float))
    return np.where(x > 0, x, np.nan)


def plot_residual(series) -> str:
    """The project's ``|Phi|`` and ``|Phi'|`` at its samples and MuJoCo's ``|efc_pos|`` along its run (log)."""
    fig = figure(11, 3.4)
    ax = fig.subplots()
    k, km = _stride(len(series["t"])), _stride(len(series["t_mj"]))
    ax.semilogy(series["t"][k], _positive(series["residual"])[k], color="C0", lw=1.6, label="urdf2links max |Phi|")
    ax.semilogy(series["t"][k], _positive(series["rate_residual"])[k], color="C0", lw=1.0, ls=":",
                label="urdf2links max |Phi'| (per s)")
    ax.semilogy(series["t_mj"][km], _positive(series["mj_pos"])[km], color="C1", lw=1.2, ls=(0, (4, 3)),
                label="MuJoCo max |efc_pos| (its soft constraint's violation)")
    ax.axhline(1e-9, color="C3", ls="--", lw=1.0, label="bound 1e-9 (urdf2links)")
    ax.set_xlabel("t (s)")
    ax.set_ylabel("residual (m, rad)")
    ax.set_title("constraint residual over the run (zeros not drawn)", fontsize=11)
    ax.grid(alpha=0.3, which="major")
    ax.legend(loc="best", fontsize=8, ncol=2)
    _log_axis(ax, decades=8)
    margins(fig)
    return png_base64(fig)


def plot_forces(series, *, most_rows: int = 6) -> str:
    """Top: ``lambda`` per row (solid) and MuJoCo's ``efc_force`` at the project's states (dashed) and along its own
    run (dotted); bottom: ``|efc_force - lambda|`` at the project's states (log). At most ``most_rows`` rows, the
    largest forces first."""
    lam, at, along, rows = series["lambda"], series["mj_at_ours"], series["mj_along"], series["rows"]
    order = np.argsort(-np.abs(lam).max(axis=0))[:most_rows] if lam.size else []
    fig = figure(11, 5.6)
    ax, bx = fig.subplots(2, 1, sharex=True, height_ratios=[3, 2])
    k, km = _stride(len(series["t"])), _stride(len(series["t_mj"]))
    for c, j in enumerate(order):
        col = f"C{c % 10}"
        unit = series["units"].get(rows[j], "")
        ax.plot(series["t"][k], lam[k, j], color=col, lw=2.0, label=f"{rows[j]} ({unit})")
        ax.plot(series["t"][k], at[k, j], color="k", lw=0.9, ls=(0, (4, 3)))
        ax.plot(series["t_mj"][km], along[km, j], color=col, lw=1.0, ls=":")
        bx.semilogy(series["t"][k], _positive(at[:, j] - lam[:, j])[k], color=col, lw=1.0)
    ax.plot([], [], color="k", lw=0.9, ls=(0, (4, 3)), label="MuJoCo efc_force at urdf2links' states")
    ax.plot([], [], color="0.4", lw=1.0, ls=":", label="MuJoCo efc_force along its own run")
    ax.set_ylabel("lambda (N, N m)")
    ax.set_title("constraint forces: urdf2links' lambda (solid) against MuJoCo's efc_force (same sign)", fontsize=11)
    ax.grid(alpha=0.3)
    ax.legend(loc="best", fontsize=7, ncol=2)
    bx.set_ylabel("|efc_force - lambda|\nat the same states")
    bx.set_xlabel("t (s)")
    bx.grid(alpha=0.3, which="major")
    _log_axis(bx)
    margins(fig, left=1.05, hspace=0.3)
    return png_base64(fig)


def plot_study(study) -> str:
    """Left: MuJoCo's distance from the project's run against time, per tau (log); right: its largest against tau
    (log-log) with the issue's slope (5x per 10x, a rate of 0.7) through the largest tau's point."""
    fig = figure(11, 3.6)
    ax, bx = fig.subplots(1, 2, width_ratios=[3, 2])
    t = study["t"]
    k = _stride(len(t))
    for r in study["runs"]:
        ax.semilogy(t[k], _positive(r["error_t"])[k], lw=1.2, label=f"tau {r['tau']:g} s (dt {r['timestep']:g} s)")
    ax.set_xlabel("t (s)")
    ax.set_ylabel("max |q_MuJoCo - q| (rad, m)")
    ax.set_title("MuJoCo approaching urdf2links as solref's tau shrinks", fontsize=10)
    ax.grid(alpha=0.3, which="major")
    ax.legend(loc="best", fontsize=8)
    _log_axis(ax)
    taus = np.array([r["tau"] for r in study["runs"]])
    errs = np.array([r["max_error"] for r in study["runs"]])
    bx.loglog(taus, np.where(errs > 0, errs, np.nan), "o-", color="C0", label="MuJoCo's largest distance")
    if errs.size and np.isfinite(errs[0]) and errs[0] > 0:
        bx.loglog(taus, errs[0] * (taus / taus[0]) ** 0.7, color="C3", ls="--", lw=1.0,
                  label="5x per 10x (rate 0.7): the least asked")
    bx.axhline(study["floor"], color="0.5", ls=":", lw=1.0, label=f"floor {study['floor']:g}")
    bx.set_xlabel("solref time constant tau (s)")
    bx.set_ylabel("largest distance (rad, m)")
    bx.grid(alpha=0.3, which="major")
    bx.legend(loc="best", fontsize=7)
    _log_axis(bx)
    _log_axis(bx, bx.xaxis, decades=4)
    margins(fig, wspace=1.0)
    return png_base64(fig)


def _rows_html(rows, header) -> str:
    e = html.escape
    head = "<tr>" + "".join(f"<th>{e(h)}</th>" for h in header) + "</tr>"
    body = "".join("<tr>" + "".join(f"<td>{x}</td>" for x in r) + "</tr>" for r in rows)
    return f"<table>{head}{body}</table>"


def _residual_rows(s) -> list[list[str]]:
    r = s["residual"]
    return [["urdf2links max |Phi| at its samples", fmt(r["max"]), f"&le; {r['bound']:g}"],
            ["urdf2links max |Phi'| at its samples (per s)", fmt(r["rate_max"]), ""],
            ["urdf2links largest |Phi| of a step before its projection", fmt(r["max_step_drift"]), ""],
            ["MuJoCo max |efc_pos| along its run (soft: its violation)", fmt(r["mujoco_max"]), "(not bounded)"],
            ["MuJoCo max |efc_vel| along its run (per s)", fmt(r["mujoco_rate_max"]), ""]]


def _force_rows(s) -> list[list[str]]:
    f = s["forces"]
    a, b = f["at_our_states"], f["along_mujoco_run"]
    out = [[html.escape(r), html.escape(f["units"].get(r, "")), fmt(a["by_row"][r]), fmt(b["by_row"][r])] for r in s["rows"]]
    if a["max_abs"] <= f["floor"]:      # a coupling that carries no force: nothing to be relative to
        out.append(["<b>all rows</b>", "", f"{fmt(a['max_abs'])} (&le; {f['floor']:g}; max |&lambda;| {fmt(a['scale'])}: "
                    "no force to compare)", fmt(b["max_abs"])])
    else:
        out.append(["<b>all rows</b>", "", f"{fmt(a['max_abs'])} ({fmt(a['relative'])} of max |&lambda;| "
                    f"{fmt(a['scale'])})", f"{fmt(b['max_abs'])} ({fmt(b['relative'])})"])
    g = f.get("generalized")
    if g is not None:       # the bounded figure: rows a loop makes dependent share their force in any proportion
        out.append(["<b>J<sup>T</sup>&lambda;, every coordinate</b>", "N, N m",
                    f"{fmt(g['max_abs'])} ({fmt(g['relative'])} of max |J<sup>T</sup>&lambda;| {fmt(g['scale'])}; "
                    f"bound {f['bound_relative']:g})", ""])
    return out


def _study_rows(st) -> list[list[str]]:
    out = []
    for k, r in enumerate(st["runs"]):
        ratio = f"{st['ratios'][k]:.3g}x" if k < len(st["ratios"]) else ""
        rate = fmt(st["rates"][k], 3) if k < len(st["rates"]) else ""
        held = ("" if k >= len(st["held"]) else "yes" if st["held"][k] else "<span class='fail'>no</span>")
        out.append([f"{r['tau']:g}", f"{r['timestep']:g}", str(r["steps"]), fmt(r["max_error"]), ratio, rate, held,
                    f"{r['wall_s']:.2f}"])
    return out


def loop_section(s: dict, series: dict | None, verdict: dict) -> list[str]:
    """HTML fragments of the section (none for a scene without constraint rows): ``s`` the summary's
    ``constraints``, ``series`` the figures' arrays (None: no figures), ``verdict`` the summary's verdict."""
    if not s:
        return []
    e = html.escape
    if "error" in s:
        return ["<h2>Closed loops</h2>", f"<div class='box bad'><b>Loops:</b> not compared: {e(s['error'])}.</div>"]
    st, f = s["study"], s["forces"]
    loops = (verdict.get("cut") or {}).get("loops") or {}
    parts = ["<h2>Closed loops</h2>",
             f"<p><b>Scope.</b> {e(loops.get('text', ''))}.</p>",
             f"<div class='box{'' if s['agree'] else ' bad'}'><b>Loops:</b> {e(s['text'])}.</div>",
             "<p class='small'>Constraints: " + e("; ".join(f"{c['name']} ({c['kind']}, {c['joins']}, {c['rows']} row"
                                                           f"{'s' * (c['rows'] != 1)}, {c['source']})" for c in s["closed"]))
             + (f". Redundant rows (E73, left out of the solve): {e('; '.join(s['redundant']))}" if s["redundant"] else "")
             + f". urdf2links' path: {e(str(s.get('method')))}.</p>",
             "<h3>Residual</h3>", _rows_html(_residual_rows(s), ["figure", "value", "bound"])]
    if series is not None:
        parts.append(f"<img alt='constraint residual' src='data:image/png;base64,{plot_residual(series)}'>")
    parts += ["<h3>Constraint forces against MuJoCo's efc_force</h3>",
              f"<p>{e(f['what'])}. Sign: {e(f['sign'])}. Rows mapped one to one (a weld's orientation rows as "
              f"0.5 R<sub>2</sub> MuJoCo's). Bound on the first column: {f['bound_relative']:g} of max |&lambda;| "
              f"(or {f['floor']:g} absolute).</p>",
              _rows_html(_force_rows(s), ["row", "units", "max |efc_force - lambda| at urdf2links' states",
                                          "along MuJoCo's own run"])]
    if series is not None:
        parts.append(f"<img alt='constraint forces' src='data:image/png;base64,{plot_forces(series)}'>")
    parts += ["<h3>How MuJoCo approaches the exact constraints: the solref study</h3>",
              f"<p>{e(st['what'])}. Asked: at least {st['required_ratio']:g}x per 10x smaller tau (a rate of 0.7); an "
              f"error at or below {st['floor']:g} has nothing left to approach. Result: "
              + ("<span class='ok'>converges</span>" if st["holds"] else "<span class='fail'>does NOT converge</span>")
              + (f", slowest measured rate {st['rate']:.2f} decades per decade" if st["rate"] is not None else
                 ", every error at the floor") + ".</p>",
              _rows_html(_study_rows(st), ["tau (s)", "MuJoCo dt (s)", "steps", "max |q_MuJoCo - q|", "ratio to the next",
                                           "rate per decade", "5x held", "wall (s)"])]
    if series is not None:
        parts.append(f"<img alt='solref study' src='data:image/png;base64,{plot_study(series['study'])}'>")
    w = s["wall_s"]
    parts.append(f"<p class='small'>This section cost {w['total_s']:.2f} s: the forces (mj_forward at every sample of "
                 f"both runs) {w['forces_s']:.2f} s, the study {w['study_s']:.2f} s.</p>")
    return parts


def loop_markdown(s: dict, verdict: dict) -> list[str]:
    """The section's lines in summary.md."""
    if not s:
        return []
    if "error" in s:
        return ["", "## Closed loops", "", f"**Loops:** not compared: {s['error']}."]
    r, f, st = s["residual"], s["forces"], s["study"]
    a, b = f["at_our_states"], f["along_mujoco_run"]
    loops = (verdict.get("cut") or {}).get("loops") or {}
    lines = ["", "## Closed loops", "", f"Scope: {loops.get('text', '')}.", "", f"**Loops:** {s['text']}.", "",
             "| figure | value |", "|---|---|",
             f"| urdf2links max \\|Phi\\| / \\|Phi'\\| (bound {r['bound']:g}) | {r['max']:.2e} / {r['rate_max']:.2e} |",
             f"| MuJoCo max \\|efc_pos\\| / \\|efc_vel\\| along its run | {r['mujoco_max']:.2e} / {r['mujoco_rate_max']:.2e} |",
             f"| max \\|efc_force - lambda\\| at urdf2links' states | {a['max_abs']:.2e} ({a['relative']:.2e} of "
             f"{a['scale']:.3g}) |",
             f"| max \\|efc_force - lambda\\| along MuJoCo's run | {b['max_abs']:.2e} ({b['relative']:.2e}) |",
             *([f"| max \\|J^T efc_force - J^T lambda\\| at urdf2links' states (the bounded figure) | "
                f"{f['generalized']['max_abs']:.2e} ({f['generalized']['relative']:.2e} of "
                f"{f['generalized']['scale']:.3g}) |"] if f.get("generalized") else []), "",
             f"Forces: {f['what']}. Sign: {f['sign']}.", "",
             f"Solref study: {st['what']}.", "",
             "| tau (s) | MuJoCo dt (s) | max \\|q_MuJoCo - q\\| | ratio to the next | rate per decade |",
             "|---|---|---|---|---|"]
    for k, run in enumerate(st["runs"]):
        ratio = f"{st['ratios'][k]:.3g}x" if k < len(st["ratios"]) else ""
        rate = f"{st['rates'][k]:.2f}" if k < len(st["rates"]) else ""
        lines.append(f"| {run['tau']:g} | {run['timestep']:g} | {run['max_error']:.3e} | {ratio} | {rate} |")
    lines += ["", "At least 5x per 10x smaller tau: " + ("holds." if st["holds"] else "does NOT hold."),
              f"The section cost {s['wall_s']['total_s']:.2f} s (study {s['wall_s']['study_s']:.2f} s)."]
    return lines

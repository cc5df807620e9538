"""What ``identify`` writes: identify.json, identify.md, report.html and residuals.png in ``--out``.

The parameter table (description value, identified value, standard deviation, identifiable, changed), the
base parameters (each a named combination), the torque residual per joint before and after on the fitted
data and on the held-out seed (numbers and a figure), the changes written, the notes.
"""

from __future__ import annotations

import html
import json
from pathlib import Path

import numpy as np

from ..figures import figure, margins, png_base64, save_png
from ..formatting import json_ready

__all__ = ["summary", "write_outputs", "residual_figure"]


def summary(ident, changes=()) -> dict:
    """The JSON summary of an :class:`~.pipeline.Identification`."""
    f = ident.fit
    return json_ready({
        "description": str(ident.pair.description), "against": str(ident.pair.engine.path),
        "coordinates": list(ident.names),
        "samples": int(sum(r.samples for r in ident.recordings)), "samples_fitted": f.samples,
        "seeds": [r.seed for r in ident.recordings], "held_out_seed": ident.held_out.seed,
        "mj_inverse_consistency": ident.consistency, "friction_band": ident.band,
        "rank": int(f.base.r), "parameters_total": len(f.described), "condition": f.base.condition_number,
        "consistent_fit": f.consistent, "unidentifiable": list(f.base.unidentifiable()),
        "residual_rms": {"before": ident.residual_before.tolist(), "after": ident.residual_after.tolist()},
        "held_out_rms": {"before": ident.heldout_before.tolist(), "after": ident.heldout_after.tolist()},
        "base_parameters": f.base_table(),
        "parameters": f.rows_table(),
        "changes": [c.to_json() for c in changes],
        "validation": [r.to_json() for r in ident.validation],
        "times_s": ident.times, "notes": ident.notes})


def residual_figure(ident):
    """Bars of the torque residual RMS per joint, before and after, fitted data and held-out seed (log scale)."""
    fig = figure(9.5, 3.2)
    ax = fig.add_subplot(111)
    n = len(ident.names)
    x = np.arange(n)
    floor = 1e-16
    for k, (vals, label) in enumerate(((ident.residual_before, "fitted data, description"),
                                       (ident.residual_after, "fitted data, identified"),
                                       (ident.heldout_before, "held-out seed, description"),
                                       (ident.heldout_after, "held-out seed, identified"))):
        ax.bar(x + (k - 1.5) * 0.2, np.maximum(vals, floor), 0.2, label=label)
    ax.set_yscale("log")
    ax.set_xticks(x, [nm.replace("_joint", "\n") for nm in ident.names], fontsize=7)
    ax.set_ylabel("torque residual RMS (N m)")
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    margins(fig, bottom=0.7, right=2.1)
    return fig


def _short(v) -> str:
    """A number or a list of numbers at 6 significant digits (the JSON keeps every digit)."""
    return "[" + ", ".join(f"{x:.6g}" for x in v) + "]" if isinstance(v, (list, tuple)) else f"{v:.6g}"


def _table_md(rows) -> list[str]:
    out = ["| parameter | description | identified | std | identifiable | changed |", "|---|---|---|---|---|---|"]
    for r in rows:
        std = "" if r["std"] is None else f"{r['std']:.2e}"
        out.append(f"| {r['parameter']} | {r['described']:.6g} | {r['identified']:.6g} | {std} | "
                   f"{'yes' if r['identifiable'] else 'no'} | {'**yes**' if r['changed'] else ''} |")
    return out


def _markdown(s: dict) -> str:
    lines = [f"# identify {s['description']} --against {s['against']}", "",
             f"{s['samples']} samples, {s['samples_fitted']} fitted; {s['rank']} base parameters of "
             f"{s['parameters_total']}; condition number {s['condition']:.3g}; mj_inverse consistency "
             f"{s['mj_inverse_consistency']:.1e} N m.", "", "## Torque residual RMS per joint (N m)", "",
             "| joint | fitted, description | fitted, identified | held-out, description | held-out, identified |",
             "|---|---|---|---|---|"]
    for i, nm in enumerate(s["coordinates"]):
        lines.append(f"| {nm} | {s['residual_rms']['before'][i]:.3e} | {s['residual_rms']['after'][i]:.3e} | "
                     f"{s['held_out_rms']['before'][i]:.3e} | {s['held_out_rms']['after'][i]:.3e} |")
    lines += ["", "![residuals](residuals.png)", "", "## Held-out run simulated (max |q - q_OTHER|, rad or m)", "",
              "| model | engine | " + " | ".join(s["coordinates"]) + " |", "|---|---|" + "---|" * len(s["coordinates"])]
    for v in s["validation"]:
        cells = [f"{x:.2e}" for x in v["max_error"]] if v["max_error"] is not None else [v["note"]] + [""] * (
            len(s["coordinates"]) - 1)
        lines.append(f"| {v['model']} | {v['engine']} | " + " | ".join(cells) + " |")
    lines += ["", "## Changes", ""]
    lines += [f"- {c['element']} {c['what']}: {_short(c['before'])} -> {_short(c['after'])}"
              + ("" if c["written"] else f" (not written: {c['note']})") for c in s["changes"]] or ["- none"]
    lines += ["", "## Base parameters (identifiable combinations)", "", "| combination | description | identified | std |",
              "|---|---|---|---|"]
    lines += [f"| {b['combination']} | {b['described']:.6g} | {b['identified']:.6g} | {b['std']:.2e} |"
              for b in s["base_parameters"]]
    lines += ["", "## Parameters", ""] + _table_md(s["parameters"])
    lines += ["", "## Notes", ""] + [f"- {n}" for n in s["notes"]]
    return "\n".join(lines) + "\n"


def _html(s: dict, png: str) -> str:
    def table(head, rows):
        h = "".join(f"<th>{html.escape(x)}</th>" for x in head)
        body = "".join("<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in r) + "</tr>" for r in rows)
        return f"<table><tr>{h}</tr>{body}</table>"
    res = [(nm, f"{s['residual_rms']['before'][i]:.3e}", f"{s['residual_rms']['after'][i]:.3e}",
            f"{s['held_out_rms']['before'][i]:.3e}", f"{s['held_out_rms']['after'][i]:.3e}")
           for i, nm in enumerate(s["coordinates"])]
    params = [(r["parameter"], f"{r['described']:.6g}", f"{r['identified']:.6g}",
               "" if r["std"] is None else f"{r['std']:.2e}", "yes" if r["identifiable"] else "no",
               "yes" if r["changed"] else "") for r in s["parameters"]]
    changes = [(c["element"], c["what"], _short(c["before"]), _short(c["after"]),
                "yes" + (f" ({c['note']})" if c["note"] else "") if c["written"] else "no: " + c["note"])
               for c in s["changes"]]
    base = [(b["combination"], f"{b['described']:.6g}", f"{b['identified']:.6g}", f"{b['std']:.2e}")
            for b in s["base_parameters"]]
    return f"""<!doctype html><html><head><meta charset="utf-8"><title>identify {html.escape(Path(s['description']).name)}</title>
<style>body{{font-family:sans-serif;max-width:1100px;margin:1em auto;font-size:14px}}table{{border-collapse:collapse;font-size:12px}}
td,th{{border:1px solid #ccc;padding:2px 6px;text-align:right}}td:first-child{{text-align:left}}</style></head><body>
<h1>identify {html.escape(s['description'])}<br><small>against {html.escape(s['against'])}</small></h1>
<p>{s['samples']} samples, {s['samples_fitted']} fitted; {s['rank']} base parameters of {s['parameters_total']};
condition number {s['condition']:.3g}; mj_inverse consistency {s['mj_inverse_consistency']:.1e} N m.</p>
<h2>Torque residual RMS per joint (N m)</h2>
{table(("joint", "fitted, description", "fitted, identified", "held-out, description", "held-out, identified"), res)}
<p><img src="data:image/png;base64,{png}" alt="residuals"></p>
<h2>Held-out run simulated: max |q - q_OTHER| (rad or m)</h2>
{table(("model", "engine") + tuple(s["coordinates"]), [(v["model"], v["engine"]) + (tuple(f"{x:.2e}" for x in v["max_error"]) if v["max_error"] is not None else (v["note"],)) for v in s["validation"]])}
<h2>Changes</h2>{table(("element", "what", "before", "after", "written"), changes) if changes else "<p>none</p>"}
<h2>Base parameters</h2>{table(("combination", "description", "identified", "std"), base)}
<h2>Parameters</h2>{table(("parameter", "description", "identified", "std", "identifiable", "changed"), params)}
<h2>Notes</h2><ul>{"".join(f"<li>{html.escape(n)}</li>" for n in s['notes'])}</ul></body></html>
"""


def write_outputs(ident, out, changes=()) -> dict:
    """identify.json, identify.md, report.html and residuals.png into the folder ``out``; the summary."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    s = summary(ident, changes)
    (out / "identify.json").write_text(json.dumps(s, indent=1) + "\n")
    (out / "identify.md").write_text(_markdown(s))
    fig = residual_figure(ident)
    png = png_base64(fig)
    save_png(residual_figure(ident), out / "residuals.png")
    (out / "report.html").write_text(_html(s, png))
    return s

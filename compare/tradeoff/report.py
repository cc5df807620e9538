"""The files of a work-precision study (:mod:`urdf2links.compare.tradeoff.study`): JSON, Markdown, figures, report section.

* :func:`write_study` writes ``tradeoff.json``, ``tradeoff.md`` (:func:`render_markdown`) and the
  two figures, and puts the section into the scene's ``report.html`` when there is one.

* :func:`plot_work_precision`: error (max over the run) against wall time, log-log, every method a
  line through the median times with the rounds' spread (min-max) as horizontal bars, both engines
  on one figure (urdf2links: solid lines, cool colours, round markers; MuJoCo: dashed lines, warm
  colours, square markers); beside it the same errors against dynamics evaluations. The band under the reference's error estimate is shaded: errors there are not
  resolved. The crossover level, if any, is a dotted line.
* :func:`plot_energy_drift`: relative energy drift against wall time, same styles.
* :func:`render_section`: the HTML section of the scene's report (figures embedded as base64 PNG);
  :func:`insert_section` puts it into an existing ``report.html`` (between markers, replacing an
  earlier one).
"""

from __future__ import annotations

import html
import json
from pathlib import Path

import numpy as np

from ..figures import figure, png_base64, save_png
from ..formatting import json_ready

__all__ = ["write_study", "render_markdown", "plot_work_precision", "plot_energy_drift", "render_section",
           "insert_section", "style", "BEGIN", "END"]

BEGIN = "<!-- tradeoff:begin -->"
END = "<!-- tradeoff:end -->"

_PROJECT_COLOURS = {"auto": "#000000", "RK45": "#08306b", "DOP853": "#2171b5", "Radau5": "#00a087",
                    "Radau": "#17becf", "BDF": "#238b45", "LSODA": "#74c476", "RK4": "#6a51a3", "midpoint": "#9e9ac8"}
_MUJOCO_COLOURS = {"Euler": "#cb181d", "implicitfast": "#fd8d3c", "RK4": "#8c2d04", "implicit": "#e7298a"}


def style(engine: str, method: str) -> dict:
    """Line style of one method: urdf2links solid/cool/round, MuJoCo dashed/warm/square."""
    if engine == "MuJoCo":
        return {"color": _MUJOCO_COLOURS.get(method, "#d95f0e"), "ls": (0, (5, 2.5)), "marker": "s", "ms": 5,
                "lw": 1.8, "label": f"MuJoCo {method} (dt ladder)"}
    fixed = method in ("RK4", "midpoint")
    return {"color": _PROJECT_COLOURS.get(method, "#3182bd"), "ls": "-", "marker": "D" if fixed else "o", "ms": 5,
            "lw": 2.6 if method == "auto" else 1.8,    # the default method stands out
            "label": f"urdf2links {method} ({'dt' if fixed else 'rtol'} ladder)" + (" (default)" if method == "auto" else "")}


def _series(data, key):
    """{(engine, method): (rows sorted loosest first)} of the runs that succeeded and were timed."""
    out = {}
    for r in data["rows"]:
        if r["status"] == "ok" and r.get("wall_time_s") is not None and r.get(key) is not None:
            out.setdefault((r["engine"], r["method"]), []).append(r)
    return out


def _figure(w, h):
    return figure(w, h, dpi=100)


def _spread_bars(ax, rows, y, colour):
    """Horizontal bars from each run's fastest to its slowest timing round."""
    med = np.array([r["wall_time_s"] for r in rows])
    lo = np.array([r.get("wall_time_min_s") or r["wall_time_s"] for r in rows])
    hi = np.array([r.get("wall_time_max_s") or r["wall_time_s"] for r in rows])
    if np.any(hi > lo):
        ax.errorbar(med, y, xerr=[med - lo, hi - med], fmt="none", ecolor=colour, elinewidth=1.0, capsize=2.5,
                    alpha=0.85)


def _wall(r) -> str:
    """``median (min-max)`` of a row's timing rounds."""
    if r.get("wall_time_s") is None:
        return "-"
    lo, hi = r.get("wall_time_min_s"), r.get("wall_time_max_s")
    return f"{r['wall_time_s']:.3g}" + (f" ({lo:.3g}-{hi:.3g})" if lo is not None and hi is not None and hi > lo else "")


def _floor(ax, data):
    f = data["reference"]["error_estimate"]
    if f and f > 0:
        ax.axhspan(1e-300, f, color="0.85", alpha=0.6, lw=0,
                   label=f"below the reference's error estimate {f:.1e}")


def _finish(fig, axes, data, title):
    fails = [r for r in data["rows"] if r["status"] == "failed"]
    skips = [r for r in data["rows"] if r["status"] == "skipped"]
    ref = data["reference"]
    sub = (f"t = 0..{data['t_end']:g} s; reference {ref['method']} rtol {ref['rtol']:g}; {len(fails)} failed and "
           f"{len(skips)} skipped runs not drawn (see the table)\nwall time: median of {data['timing']['repeats']} "
           "interleaved rounds (bars: min-max), both engines in one process, compilation excluded")
    fig.suptitle(f"{data['robot']} / {data['scene']}: {title}\n{sub}", fontsize=10)
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside right center", fontsize=8, frameon=False)


def plot_work_precision(data: dict, path=None):
    """Error against wall time (and against evaluations); writes ``path`` (PNG) if given, returns
    the Figure."""
    fig = _figure(13.5, 5.6)
    ax, bx = fig.subplots(1, 2, width_ratios=[1.35, 1])
    series = _series(data, "error_max")
    lo = []
    for (engine, method), rows in series.items():
        st = style(engine, method)
        err = np.array([max(r["error_max"], 1e-17) for r in rows])
        lo.append(err.min())
        ax.loglog([r["wall_time_s"] for r in rows], err, **st)
        _spread_bars(ax, rows, err, st["color"])
        bx.loglog([r["nfev"] for r in rows], err, **{k: v for k, v in st.items() if k != "label"})
    for a in (ax, bx):
        a.grid(alpha=0.3, which="both")
        if lo:
            a.set_ylim(max(min(lo) / 5, 1e-17), None)
        _floor(a, data)
    lvl = data["crossover"].get("error_level")
    if lvl:
        ax.axhline(lvl, color="k", ls=":", lw=1.3,
                   label=f"crossover: urdf2links faster (beyond the spread) below {lvl:.1e}")
    ax.set_xlabel("wall time (s): median, bars min-max over the rounds")
    ax.set_ylabel("error: max over the run of max |q - q_ref| (rad or m)")
    bx.set_xlabel("dynamics evaluations (MuJoCo: steps x stages)")
    bx.set_title("the same errors against evaluations", fontsize=9)
    _finish(fig, [ax], data, "work-precision (error against wall time)")
    if path is not None:
        save_png(fig, path)
    return fig


def plot_energy_drift(data: dict, path=None):
    """Relative energy drift against wall time; writes ``path`` (PNG) if given, returns the Figure."""
    fig = _figure(11.5, 5.2)
    ax = fig.subplots()
    for (engine, method), rows in _series(data, "energy_drift_rel").items():
        y = np.array([max(r["energy_drift_rel"], 1e-17) for r in rows])
        st = style(engine, method)
        ax.loglog([r["wall_time_s"] for r in rows], y, **st)
        _spread_bars(ax, rows, y, st["color"])
    d = data["reference"]["energy_drift_rel"]
    ax.axhline(max(d, 1e-17), color="0.4", ls=":", lw=1.2, label=f"the reference's own drift {d:.1e}")
    ax.grid(alpha=0.3, which="both")
    ax.set_xlabel("wall time (s): median, bars min-max over the rounds")
    ax.set_ylabel("energy drift: max |h - h(0) - W| / energy scale")
    _finish(fig, [ax], data, "energy drift against wall time")
    if path is not None:
        save_png(fig, path)
    return fig




def _num(x, d=2):
    return "&ndash;" if x is None else f"{x:.{d}e}"


def render_section(data: dict) -> str:
    """The report's work-precision section (HTML, between :data:`BEGIN` and :data:`END`)."""
    e = html.escape
    ref, co = data["reference"], data["crossover"]
    rows = []
    for r in data["rows"]:
        cls = "" if r["status"] == "ok" else " class='small'"
        status = "ok" if r["status"] == "ok" else f"<span class='fail'>{e(r['status'])}</span>: {e(str(r['reason']))}"
        wt = "&ndash;" if r.get("wall_time_s") is None else _wall(r)
        rows.append(f"<tr{cls}><td>{e(r['engine'])}</td><td>{e(r['method'])}</td><td class='num'>{e(r['param'])} "
                    f"{r['value']:g}</td><td class='num'>{_num(r.get('error_max'))}</td><td class='num'>"
                    f"{_num(r.get('error_final'))}</td><td class='num'>{_num(r.get('energy_drift_rel'), 1)}</td>"
                    f"<td class='num'>{wt}</td><td class='num'>{'&ndash;' if r.get('nfev') is None else r['nfev']}"
                    f"</td><td>{status}</td></tr>")
    wp = png_base64(plot_work_precision(data))
    ed = png_base64(plot_energy_drift(data))
    m = data["machine"]
    parts = [BEGIN, "<h2>Accuracy against wall time (work-precision)</h2>",
             f"<div class='box'><b>Crossover:</b> {e(co['statement'])}.</div>",
             f"<p>Every method of both engines on this scene from the same initial state, t = 0..{data['t_end']:g} s"
             + (f" ({e(data['t_end_note'])})" if data.get("t_end_note") else "") + ", against a reference: "
             f"{e(ref['method'])} rtol {ref['rtol']:g} ({ref['nsteps']} steps), checked against {e(ref['check']['method'])} "
             f"rtol {ref['check']['rtol']:g}; the reference's <b>error estimate</b> (their largest difference) is "
             f"<b>{ref['error_estimate']:.1e}</b> (final {ref['error_estimate_final']:.1e}): smaller errors are not "
             f"resolved (grey band). Error: {e(data['error']['metric'])}. Wall time: median of "
             f"{data['timing']['repeats']} interleaved rounds in one process, bars from the fastest to the slowest "
             f"round; an engine is faster at an error level only when its slowest round beats the other's fastest. "
             f"urdf2links: {e(data['timing']['project'])}; MuJoCo: {e(data['timing']['mujoco'])}; "
             f"{e(data['timing'].get('compilation', ''))}. Runs predicted to exceed {data['budget_s']:g} s are "
             "skipped.</p>",
             f"<img alt='work-precision diagram' src='data:image/png;base64,{wp}'>",
             f"<img alt='energy drift against wall time' src='data:image/png;base64,{ed}'>",
             "<details><summary>all runs</summary><table><tr><th>engine</th><th>method</th><th>setting</th>"
             "<th>error max</th><th>error final</th><th>energy drift</th><th>wall s, median (min-max)</th><th>evaluations</th>"
             "<th>status</th></tr>" + "\n".join(rows) + "</table></details>",
             f"<p class='small'>Energy drift: {e(data['energy']['metric'])}. Evaluations: {e(data['evaluations'])}. "
             f"Machine: {e(m['platform'])}, {m['cpu_count']} CPUs, Python {e(m['python'])}, numpy {e(m['numpy'])}, "
             f"MuJoCo {e(m['mujoco'])}. Figures: <a href='tradeoff.json'>tradeoff.json</a>, "
             f"<a href='tradeoff.md'>tradeoff.md</a>"
             + (f". Regenerate: <code>{e(data['command'])}</code>" if data.get("command") else "") + ".</p>", END]
    return "\n".join(parts)


def insert_section(report: Path, data: dict) -> bool:
    """Put the section into an existing report page (replacing an earlier one); False when the
    page has no place for it."""
    text = Path(report).read_text()
    if BEGIN in text and END in text:
        text = text[:text.index(BEGIN)] + text[text.index(END) + len(END):]
    section = render_section(data)
    for anchor in ("<h2>Notes</h2>", "<p class='small'>Figures:", "</body>"):
        if anchor in text:
            i = text.index(anchor)
            Path(report).write_text(text[:i] + section + "\n" + text[i:])
            return True
    return False


def _fmt(x, d=2):
    return "-" if x is None else (f"{x:.{d}e}" if isinstance(x, float) else str(x))


def render_markdown(data: dict) -> str:
    ref = data["reference"]
    lines = [f"# {data['robot']} / {data['scene']}: accuracy against wall time", "",
             f"t = 0..{data['t_end']:g} s, {data['samples']} samples"
             + (f" ({data['t_end_note']})" if data.get("t_end_note") else "") + ".", "",
             f"**Crossover:** {data['crossover']['statement']}.", "",
             f"Reference: {ref['method']} rtol {ref['rtol']:g} atol {ref['atol']:g} ({ref['nsteps']} steps, "
             f"{ref['nfev']} evaluations); checked against {ref['check']['method']} rtol {ref['check']['rtol']:g}: "
             f"error estimate {ref['error_estimate']:.2e} (max over the run), {ref['error_estimate_final']:.2e} (final).",
             "", f"Error: {data['error']['metric']}. Energy drift: {data['energy']['metric']}. Wall time: median "
             f"(min-max) of {data['timing']['repeats']} interleaved rounds; urdf2links: {data['timing']['project']}; "
             f"MuJoCo: {data['timing']['mujoco']}; {data['timing'].get('compilation', '')}. Budget "
             f"{data['budget_s']:g} s per run.", "",
             "| engine | method | setting | status | error max | error final | energy drift | wall s, median (min-max) "
             "| evaluations | steps |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for r in data["rows"]:
        st = r["status"] if r["status"] == "ok" else f"{r['status']}: {r['reason']}"
        wt = _wall(r)
        lines.append(f"| {r['engine']} | {r['method']} | {r['param']} {r['value']:g} | {st} | {_fmt(r['error_max'])} | "
                     f"{_fmt(r['error_final'])} | {_fmt(r['energy_drift_rel'], 1)} | {wt} | {_fmt(r['nfev'])} | "
                     f"{_fmt(r['nsteps'])} |")
    m = data["machine"]
    lines += ["", f"Machine: {m['platform']}, {m['cpu_count']} CPUs, Python {m['python']}, numpy {m['numpy']}, "
                  f"scipy {m['scipy']}, MuJoCo {m['mujoco']}; commit {m['git_commit']}.", ""]
    return "\n".join(lines)


def write_study(data: dict, out_dir, *, command: str | None = None) -> dict:
    """Write ``tradeoff.json``, ``tradeoff.md``, ``work_precision.png`` and ``energy_drift.png`` into
    ``out_dir``, and put the section into ``report.html`` there when it exists. Returns the paths."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    if command:
        data = dict(data, command=command)
    paths = {"dir": out, "json": out / "tradeoff.json", "md": out / "tradeoff.md",
             "work_precision": out / "work_precision.png", "energy_drift": out / "energy_drift.png"}
    paths["json"].write_text(json.dumps(json_ready(data), indent=2) + "\n")
    paths["md"].write_text(render_markdown(data))
    plot_work_precision(data, paths["work_precision"])
    plot_energy_drift(data, paths["energy_drift"])
    report = out / "report.html"
    paths["report"] = report if report.is_file() and insert_section(report, data) else None
    return paths

"""The corpus report: ``corpus.json``, ``corpus.md``, ``corpus.png`` and ``index.html`` over every robot.

:func:`write_corpus` writes into ``out``: each robot's own files (its light page, summary and
thumbnail, :mod:`urdf2links.compare.corpus.page`) under ``<out>/<robot id>/``; ``corpus.json`` (one
object per robot, :data:`urdf2links.compare.corpus.rows.ROW_KEYS` and more, under ``"robots"``, with the
settings and the run); ``corpus.md`` (the table, worst first); ``corpus.png`` (every robot's terms,
trajectory difference and energy drifts against their tolerances); ``index.html``: the table,
sortable (click a heading) and filterable (text, status, out of tolerance), worst first by default,
each robot linked to its page, plain inline JavaScript (works offline, from a file).

Worst first: failed rows, then compared rows by :func:`~urdf2links.compare.corpus.rows.worst_ratio` (the
largest figure over its tolerance), then refused rows.
"""

from __future__ import annotations

import html
import json
import math
import platform
from pathlib import Path

from urdf2links.scenes.scene import RunSettings

from ..figures import figure, save_png
from ..formatting import fmt, fmt_md
from .rows import TERMS_TOLERANCE

__all__ = ["write_corpus", "corpus_data", "worst_first", "render_index", "render_markdown_table"]

_RANK = {"failed": 0, "compared": 1, "refused": 2}


def worst_first(rows: list[dict]) -> list[dict]:
    """``rows`` in the index's default order (module doc); ties by file."""
    def key(r):
        w = r.get("worst")
        w = math.inf if isinstance(w, str) else (w if isinstance(w, (int, float)) else -1.0)
        return (_RANK.get(r["status"], 3), -w, r["file"])
    return sorted(rows, key=key)


def coverage_counts(compared: list[dict]) -> dict:
    """Of the compared rows: how many are weak evidence (E67), how many moved at least 90% of their
    coordinates, and the smallest fraction moved (None without coverage)."""
    fr = [r["coverage"]["moved_fraction"] for r in compared if (r.get("coverage") or {}).get("moved_fraction") is not None]
    return {"weak_evidence": sum(bool(r["coverage"].get("weak_evidence")) for r in compared if r.get("coverage")),
            "moved_90_percent": sum(f >= 0.9 for f in fr), "with_coverage": len(fr),
            "least_moved_fraction": min(fr) if fr else None}


def _coverage_sentence(data: dict) -> str:
    cov = data.get("coverage") or {}
    if not cov.get("with_coverage"):
        return ""
    return (f" Coverage: {cov['moved_90_percent']} of {cov['with_coverage']} compared robots moved at least 90% of their "
            f"coordinates by more than 1e-3 (least: {cov['least_moved_fraction']:.0%}); {cov['weak_evidence']} weak "
            "evidence (fewer than half moved).")


def corpus_data(rows: list[dict], *, settings: dict, run: dict, command: str | None) -> dict:
    """The content of ``corpus.json``: rows sorted by file, counts, settings, versions, the run."""
    import mujoco
    import numpy

    import urdf2links

    counts = {s: sum(r["status"] == s for r in rows) for s in _RANK}
    compared = [r for r in rows if r["status"] == "compared"]
    r1 = [r["terms"]["route1"] for r in compared if isinstance(r["terms"]["route1"], (int, float))]
    return {
        "schema": 1,
        "about": "urdf2links against MuJoCo on every robot of a corpus, each in its default scene "
                 "(`urdf2links report --corpus`); one object per robot under 'robots'. 'wall_time' and "
                 "'worker' depend on the machine and the run; every other figure is the same however it ran.",
        "command": command,
        "settings": settings,
        "versions": {"urdf2links": getattr(urdf2links, "__version__", None), "mujoco": mujoco.__version__,
                     "numpy": numpy.__version__, "python": platform.python_version()},
        "counts": {"robots": len(rows), **counts},
        "route1_worst": max(r1) if r1 else None,
        "route1_within_tolerance": all(v <= TERMS_TOLERANCE for v in r1),
        "coverage": coverage_counts(compared),
        "run": run,
        "robots": sorted(rows, key=lambda r: r["file"]),
    }


# --------------------------------------------------------------------------- index.html


_CSS = """
body { font-family: -apple-system, 'Segoe UI', Helvetica, Arial, sans-serif; margin: 0 auto; max-width: 1500px;
       padding: 16px 24px 40px; color: #1d2330; line-height: 1.4; }
h1 { font-size: 1.5em; margin-bottom: 0.1em; } .sub { color: #5a6272; margin-top: 0; }
.box { border-left: 4px solid #3d7bd9; background: #f3f7fd; padding: 8px 14px; margin: 10px 0; font-size: 0.92em; }
table { border-collapse: collapse; font-size: 0.82em; margin-top: 6px; }
th, td { border: 1px solid #d0d5de; padding: 3px 6px; text-align: left; vertical-align: top; }
th { background: #eef1f6; cursor: pointer; user-select: none; white-space: nowrap; }
th.sorted-asc::after { content: ' \\25B2'; } th.sorted-desc::after { content: ' \\25BC'; }
td.num { text-align: right; font-family: 'DejaVu Sans Mono', Menlo, monospace; white-space: nowrap; }
tr.failed td { background: #fbeeee; } tr.refused td { background: #f6f6f6; color: #5a6272; }
td.out { color: #c9302c; font-weight: 600; } .small { font-size: 0.85em; color: #5a6272; }
td.reason { min-width: 200px; max-width: 340px; overflow-wrap: anywhere; }
td.file { max-width: 260px; overflow-wrap: anywhere; }
.ok { color: #1e7b34; font-weight: 600; } .fail { color: #c9302c; font-weight: 600; }
.controls { margin: 10px 0 4px; font-size: 0.9em; } .controls label { margin-right: 12px; }
img.thumb { width: 96px; height: auto; border: 0; } img.fig { max-width: 100%; border: 1px solid #e3e6ec; }
code { background: #f0f2f5; padding: 0 3px; border-radius: 3px; }
"""

_JS = """
(function () {
  const table = document.getElementById('corpus'), body = table.tBodies[0];
  const rows = Array.from(body.rows), heads = Array.from(table.tHead.rows[0].cells);
  function value(row, col) {
    const v = row.cells[col].dataset.v;
    if (v === undefined || v === '') return null;
    const x = Number(v);
    return isNaN(x) ? v.toLowerCase() : x;
  }
  function sortBy(col, dir) {
    const sorted = rows.slice().sort(function (a, b) {
      const x = value(a, col), y = value(b, col);
      if (x === null && y === null) return Number(a.dataset.order) - Number(b.dataset.order);
      if (x === null) return 1;
      if (y === null) return -1;
      if (x < y) return -dir;
      if (x > y) return dir;
      return Number(a.dataset.order) - Number(b.dataset.order);
    });
    sorted.forEach(function (r) { body.appendChild(r); });
    heads.forEach(function (h) { h.classList.remove('sorted-asc', 'sorted-desc'); });
    if (col !== null) heads[col].classList.add(dir > 0 ? 'sorted-asc' : 'sorted-desc');
  }
  heads.forEach(function (h, col) {
    if (h.dataset.sort === 'no') return;
    h.addEventListener('click', function () {
      const dir = h.classList.contains('sorted-desc') ? 1 : (h.classList.contains('sorted-asc') ? -1 : Number(h.dataset.first || 1));
      sortBy(col, dir);
    });
  });
  document.getElementById('worst-first').addEventListener('click', function () {
    rows.slice().sort(function (a, b) { return Number(a.dataset.order) - Number(b.dataset.order); })
        .forEach(function (r) { body.appendChild(r); });
    heads.forEach(function (h) { h.classList.remove('sorted-asc', 'sorted-desc'); });
  });
  const text = document.getElementById('filter'), out = document.getElementById('only-out');
  const weak = document.getElementById('only-weak');
  const boxes = Array.from(document.querySelectorAll('input[data-status]'));
  function filter() {
    const q = text.value.trim().toLowerCase(), show = {};
    boxes.forEach(function (b) { show[b.dataset.status] = b.checked; });
    let n = 0;
    rows.forEach(function (r) {
      const ok = show[r.dataset.status] && (!out.checked || r.dataset.out === '1')
        && (!weak.checked || r.dataset.weak === '1')
        && (q === '' || r.textContent.toLowerCase().indexOf(q) >= 0);
      r.hidden = !ok;
      if (ok) n += 1;
    });
    document.getElementById('shown').textContent = n + ' of ' + rows.length + ' robots shown';
  }
  [text, out, weak].concat(boxes).forEach(function (el) { el.addEventListener('input', filter); });
  // the address may carry a view: #sort=<column>-<asc|desc>&q=<text>&status=<failed,compared>&out=1&weak=1
  const view = new URLSearchParams(location.hash.slice(1));
  if (view.has('q')) text.value = view.get('q');
  if (view.has('status')) {
    const keep = view.get('status').split(',');
    boxes.forEach(function (b) { b.checked = keep.indexOf(b.dataset.status) >= 0; });
  }
  if (view.get('out') === '1') out.checked = true;
  if (view.get('weak') === '1') weak.checked = true;
  if (view.has('sort')) {
    const s = view.get('sort').split('-');
    if (heads[Number(s[0])]) sortBy(Number(s[0]), s[1] === 'desc' ? -1 : 1);
  }
  filter();
})();
"""

#: (heading, sort direction on first click: -1 largest first) of the index table, after the picture.
_HEADINGS = [("robot file<br><span class='small'>robot name</span>", 1), ("status", 1), ("n", -1),
             ("terms<br>route 1", -1), ("terms<br>route 2", -1), ("trajectory<br>max |&Delta;q|", -1),
             ("divergence<br>|&Delta;q| &gt; 1e-3", 1), ("energy drift<br>urdf2links (rel.)", -1),
             ("energy drift<br>MuJoCo (rel.)", -1), ("worst<br>/ tolerance", -1),
             ("coverage<br>moved", 1), ("wall<br>(s)", -1)]


def _num(v) -> str:
    """A sort value: numbers as they are, 'inf'/'nan' strings as very large, None as empty."""
    if v is None:
        return ""
    if isinstance(v, str):
        return "1e308" if v in ("inf", "nan") else ""
    return repr(float(v))


def _cell(v, *, digits: int = 1, out: bool = False, extra: str = "") -> str:
    cls = "num out" if out else "num"
    return f"<td class='{cls}' data-v='{_num(v)}'>{fmt(v, digits)}{extra}</td>"


def _route2_cell(te: dict) -> str:
    st = te.get("route2_status")
    small = {"repaired": "repaired", "refused": "MuJoCo refuses", "skipped": "skipped"}.get(st)
    title = html.escape(te.get("route2_reason") or "", quote=True)
    v = te.get("route2")
    out = isinstance(v, (int, float)) and v > TERMS_TOLERANCE
    return (f"<td class='num{' out' if out else ''}' data-v='{_num(v)}' title='{title}'>{fmt(v, 1)}"
            + (f"<br><span class='small'>{small}</span>" if small else "") + "</td>")


def _row_html(r: dict, order: int, *, thumbs: bool, checks: bool) -> str:
    e = html.escape
    te, tr, en, wt = r["terms"], r["trajectory"], r["energy"], r.get("wall_time") or {}
    link = r.get("report")
    name = f"<a href='{e(link)}'>{e(r['file'])}</a>" if link else e(r["file"])
    robot = f"<br><span class='small'>robot {e(str(r['name']))}</span>" if r.get("name") else ""
    worst = r.get("worst")
    out = r["status"] == "compared" and (isinstance(worst, str) or (worst is not None and worst > 1.0))
    cells = []
    if thumbs:
        img = (f"<a href='{e(link or '')}'><img class='thumb' alt='' src='{e(r['thumbnail'])}'></a>"
               if r.get("thumbnail") else "")
        cells.append(f"<td data-v=''>{img}</td>")
    cells.append(f"<td class='file' data-v='{e(r['file'], quote=True)}'>{name}{robot}</td>")
    stage = f"<br><span class='small'>{e(r['stage'])}</span>" if r["status"] == "failed" and r.get("stage") else ""
    cells.append(f"<td data-v='{_RANK.get(r['status'], 3)}'>{e(r['status'])}{stage}</td>")
    cells.append(f"<td class='num' data-v='{_num(r.get('n'))}'>{'' if r.get('n') is None else r['n']}</td>")
    r1 = te.get("route1")
    cells.append(_cell(r1, out=isinstance(r1, (int, float)) and r1 > TERMS_TOLERANCE))
    cells.append(_route2_cell(te))
    mx = tr.get("max_abs_error")
    cells.append(_cell(mx, out=isinstance(mx, (int, float)) and mx > tr.get("divergence_threshold", math.inf)))
    div = tr.get("divergence_time")
    div_text = ("none" if r["status"] == "compared" else "&ndash;") if div is None else f"{div:.3g} s"
    cells.append(f"<td class='num' data-v='{_num(div)}'>{div_text}</td>")
    cells += [_cell(en.get("project_drift_rel")), _cell(en.get("mujoco_drift_rel")), _cell(worst, out=out)]
    cells.append(_coverage_cell(r))
    cells.append(f"<td class='num' data-v='{_num(wt.get('total_s'))}'>{fmt(wt.get('total_s'), 1)}</td>")
    if checks:
        chk = r.get("check")
        text = "&ndash;" if not chk or chk.get("ok") is None else (
            "<span class='ok'>ok</span>" if chk["ok"] else "<span class='fail'>FAIL</span><br><span class='small'>"
            + e(", ".join(chk["failures"])) + "</span>")
        cells.append(f"<td data-v='{'' if not chk or chk.get('ok') is None else int(bool(chk['ok']))}'>{text}</td>")
    reason = r.get("reason") or ""
    cells.append(f"<td class='small reason' data-v='{e(reason[:60], quote=True)}'>{e(reason[:400])}"
                 + ("..." if len(reason) > 400 else "") + "</td>")
    weak = int(bool((r.get("coverage") or {}).get("weak_evidence")))
    return (f"<tr class='{e(r['status'])}' data-status='{e(r['status'])}' data-out='{int(out)}' data-weak='{weak}' "
            f"data-order='{order}'>" + "".join(cells) + "</tr>")


def _coverage_cell(r: dict) -> str:
    """The coverage column: ``k/n`` coordinates moved (sorted by the fraction), weak evidence in red (E67)."""
    cov = r.get("coverage") or {}
    if cov.get("moved") is None:
        return "<td class='num' data-v=''>&ndash;</td>"
    weak = "<br><span class='fail'>weak evidence</span>" if cov.get("weak_evidence") else ""
    return (f"<td class='num' data-v='{_num(cov.get('moved_fraction'))}' title='{html.escape(cov.get('text') or '', quote=True)}'>"
            f"{cov['moved']}/{cov['coordinates']}{weak}</td>")


#: what the project runs in a default scene: ``auto`` (DOP853, Radau5 while the run is stiff) at the scenes' rtol
_PROJECT_RUN = f"{RunSettings.method} (DOP853, Radau5 while stiff) rtol {RunSettings.rtol:g}"


def render_index(data: dict, *, figure_file: str | None = "corpus.png") -> str:
    """``index.html`` of a corpus (``data`` as :func:`corpus_data` makes it)."""
    e = html.escape
    rows = worst_first(data["robots"])
    thumbs = any(r.get("thumbnail") for r in rows)
    checks = any(r.get("check") for r in rows)
    heads = ([("", 1)] if thumbs else []) + _HEADINGS + ([("baseline", 1)] if checks else []) + [("reason / note", 1)]
    head = "".join(f"<th data-first='{d}'" + (" data-sort='no'" if not h else "") + f">{h}</th>" for h, d in heads)
    body = "\n".join(_row_html(r, i, thumbs=thumbs, checks=checks) for i, r in enumerate(rows))
    c, st, run = data["counts"], data["settings"], data["run"]
    boxes = "".join(f"<label><input type='checkbox' data-status='{s}' checked> {s} ({c[s]})</label>" for s in _RANK)
    summary = (f"<b>{c['robots']} robots</b>: {c['compared']} compared, {c['refused']} refused (the file cannot be "
               f"read; the reason is in the row), {c['failed']} failed (a fault of urdf2links or MuJoCo). Route 1 "
               f"terms: worst {fmt(data['route1_worst'])} ("
               + ("all within" if data["route1_within_tolerance"] else "<span class='fail'>NOT all within</span>")
               + f" {TERMS_TOLERANCE:g}).") + e(_coverage_sentence(data))
    setup = (f"Each robot in its default scene ({e(st['scene'])}), t = 0..{st['t_end']:g} s, seed {st['seed']}; terms "
             f"at {st['states']} seeded states; MuJoCo {e(st['mujoco_integrator'])} dt {st['mujoco_dt']:g} s against "
             f"urdf2links {e(_PROJECT_RUN)} (the methods each robot's run used are in its page). "
             f"Ran {e(run.get('how', ''))} in {run.get('wall_s', 0):.0f} s"
             + (f" (the warm-up before the first robot, {run['warm_up_s']:.0f} s, numba's compilation in a fresh "
                "installation, left out)." if run.get("warm_up_s") else "."))
    parts = [f"<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'><title>urdf2links corpus against MuJoCo"
             f"</title><style>{_CSS}</style></head><body>",
             "<p class='small'><a href='../index.html'>&larr; all reports</a></p>" if data.get("nested") else "",
             "<h1>A corpus of robots against MuJoCo</h1>",
             "<p class='sub'>urdf2links and MuJoCo on every robot description found: import, terms at identical "
             "states (route 1: the project's tree as MJCF; route 2: MuJoCo's own URDF import), a short run of the "
             "default scene (trajectory difference, divergence, each engine's energy drift), wall time.</p>",
             f"<div class='box'>{summary}<br>{setup}</div>"]
    if figure_file:
        parts.append(f"<p><a href='{e(figure_file)}'><img class='fig' alt='every robot against its tolerances' "
                     f"src='{e(figure_file)}'></a></p>")
    parts += [f"<div class='controls'><button id='worst-first'>worst first</button> <input id='filter' size='28' "
              f"placeholder='filter: robot, file, reason...'> {boxes}<label><input type='checkbox' id='only-out'> out "
              f"of tolerance only</label> <label><input type='checkbox' id='only-weak'> weak evidence only "
              f"({sum(bool((r.get('coverage') or {}).get('weak_evidence')) for r in rows)})</label> "
              "<span id='shown' class='small'></span></div>",
              f"<table id='corpus'><thead><tr>{head}</tr></thead><tbody>\n{body}\n</tbody></table>",
              _legend(), f"<p class='small'>Data: <a href='corpus.json'>corpus.json</a>, <a href='corpus.md'>corpus.md</a>."
              + (f" Regenerate: <code>{e(data['command'])}</code>" if data.get("command") else "") + "</p>",
              f"<script>{_JS}</script></body></html>"]
    return "\n".join(parts)


def _legend() -> str:
    return ("<p class='small'>terms: max |ours &minus; MuJoCo| / max |MuJoCo| of A (mj_fullM) and e + G (qfrc_bias) "
            f"at seeded states, tolerance {TERMS_TOLERANCE:g}; route 2 \"repaired\": MuJoCo refused the file, compared on "
            "the project's repaired text (hover for MuJoCo's reason). Trajectory: largest |q urdf2links &minus; q MuJoCo| "
            "over coordinates and time (rad, m); divergence: first time it exceeds 1e-3. Energy drift: max |E + V "
            "&minus; (E + V)(0) &minus; W| of each engine over the robot's energy scale. worst / tolerance: the largest "
            "of route 1 and route 2 over 1e-9 and the trajectory difference over 1e-3 (above 1, in red: out of "
            "tolerance). Coverage: the coordinates that moved by more than 1e-3 (rad or m) in the run, of all; "
            "<b>weak evidence</b> when fewer than half did (E67: the agreement then says little about the joints' "
            "dynamics). Wall: the robot's whole evaluation (import, both engines, terms, page). A reason on a "
            "compared row says what was done to compare it (the project's inertia repair when the file as written "
            "cannot be simulated or MuJoCo refuses its inertias).</p>")


# --------------------------------------------------------------------------- Markdown, figure


def render_markdown_table(data: dict) -> str:
    """``corpus.md``: the counts and settings, then one line per robot, worst first."""
    c, st = data["counts"], data["settings"]
    lines = ["# A corpus of robots against MuJoCo", "",
             f"{c['robots']} robots: {c['compared']} compared, {c['refused']} refused, {c['failed']} failed. Route 1 "
             f"terms: worst {fmt_md(data['route1_worst'])} (tolerance {TERMS_TOLERANCE:g}: "
             + ("all within" if data["route1_within_tolerance"] else "NOT all within") + ")." + _coverage_sentence(data),
             "",
             f"Default scene ({st['scene']}), t = 0..{st['t_end']:g} s, seed {st['seed']}; MuJoCo "
             f"{st['mujoco_integrator']} dt {st['mujoco_dt']:g} s. Generated by `{data.get('command')}`; "
             "pages in index.html, figures in corpus.json.", "",
             "| robot | status | n | terms route 1 | terms route 2 | max abs dq | divergence | energy drift rel. "
             "(urdf2links / MuJoCo) | worst / tol. | coverage | wall s | reason |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in worst_first(data["robots"]):
        te, tr, en = r["terms"], r["trajectory"], r["energy"]
        r2 = fmt_md(te.get("route2")) + (f" ({te['route2_status']})" if te.get("route2_status") not in (None, "as written") else "")
        link = f"[{r['file']}]({r['report']})" if r.get("report") else r["file"]
        div = tr.get("divergence_time")
        div = ("none" if r["status"] == "compared" else "-") if div is None else f"{div:.3g} s"
        reason = (r.get("reason") or "").replace("|", "\\|").replace("\n", " ")
        lines.append(f"| {link} | {r['status']} | {'' if r.get('n') is None else r['n']} | {fmt_md(te.get('route1'))} | "
                     f"{r2} | {fmt_md(tr.get('max_abs_error'))} | {div} | {fmt_md(en.get('project_drift_rel'))} / "
                     f"{fmt_md(en.get('mujoco_drift_rel'))} | {fmt_md(r.get('worst'))} | {_coverage_md(r)} | "
                     f"{fmt_md((r.get('wall_time') or {}).get('total_s'), 1)} | "
                     + (reason[:160] + ("..." if len(reason) > 160 else "")) + " |")
    return "\n".join(lines) + "\n"


def _coverage_md(r: dict) -> str:
    cov = r.get("coverage") or {}
    if cov.get("moved") is None:
        return "-"
    return f"{cov['moved']}/{cov['coordinates']}" + (" **weak evidence**" if cov.get("weak_evidence") else "")


def plot_corpus(data: dict, path) -> Path | None:
    """``corpus.png``: for each compared robot (sorted by name) its route 1 and route 2 terms (top) and
    its trajectory difference and energy drifts (bottom), with the tolerances. None when no robot
    was compared."""
    import numpy as np

    rows = sorted((r for r in data["robots"] if r["status"] == "compared"), key=lambda r: r["file"])
    if not rows:
        return None
    x = np.arange(len(rows))

    def col(f):
        return np.array([v if isinstance(v, (int, float)) else (np.inf if v in ("inf", "nan") else np.nan)
                         for v in map(f, rows)], float)

    fig = figure(max(8.0, 0.16 * len(rows) + 2.0), 7.0, dpi=80)
    ax, bx = fig.subplots(2, 1, sharex=True)
    floor = 1e-18
    for a, series, tol in ((ax, [("route 1", lambda r: r["terms"]["route1"], "C0", "o"),
                                 ("route 2", lambda r: r["terms"]["route2"], "C2", "x")], TERMS_TOLERANCE),
                           (bx, [("trajectory max |dq| (rad, m)", lambda r: r["trajectory"]["max_abs_error"], "k", "s"),
                                 ("energy drift urdf2links (rel.)", lambda r: r["energy"]["project_drift_rel"], "C0", "^"),
                                 ("energy drift MuJoCo (rel.)", lambda r: r["energy"]["mujoco_drift_rel"], "C1", "v")], 1e-3)):
        for label, f, color, marker in series:
            a.scatter(x, np.maximum(col(f), floor), s=18, color=color, marker=marker, label=label, zorder=3)
        a.set_yscale("log")
        a.axhline(tol, color="C3", ls="--", lw=1.0, label=f"tolerance {tol:g}" if a is ax else "divergence threshold 1e-3")
        a.grid(alpha=0.3, which="major")
        a.legend(loc="upper left", fontsize=7, ncol=2, framealpha=0.9)
    ax.set_ylabel("terms: max relative error")
    ax.set_title(f"{len(rows)} robots compared with MuJoCo (zeros drawn at {floor:g})", fontsize=10)
    bx.set_ylabel("run of the default scene")
    bx.set_xticks(x, [r["file"].rsplit("/", 1)[-1].rsplit(".", 1)[0] for r in rows], rotation=90, fontsize=6)
    return save_png(fig, path)


# --------------------------------------------------------------------------- files


def _write_robot_files(results, out: Path) -> int:
    n = 0
    for res in results:
        if not res.files:
            continue
        folder = out / res.row["file"]
        folder.mkdir(parents=True, exist_ok=True)
        for name, content in res.files.items():
            (folder / name).write_bytes(content if isinstance(content, bytes) else content.encode())
            n += 1
    return n


def write_corpus(results, out, *, settings: dict, run: dict, command: str | None = None,
                 nested: bool = False) -> dict:
    """Write the corpus report into ``out`` (module doc); ``results`` as
    :func:`urdf2links.compare.corpus.runner.run_corpus` returns them, ``settings`` and ``run`` what
    ``corpus.json`` records of them; ``nested``: the index links ``../index.html`` (the reports'
    index) at its top. Returns the paths and the data."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    _write_robot_files(results, out)
    data = corpus_data([r.row for r in results], settings=settings, run=run, command=command)
    (out / "corpus.json").write_text(json.dumps(data, indent=1) + "\n")
    (out / "corpus.md").write_text(render_markdown_table(data))
    png = plot_corpus(data, out / "corpus.png")
    (out / "index.html").write_text(render_index({**data, "nested": nested}, figure_file=png.name if png else None))
    return {"dir": out, "html": out / "index.html", "json": out / "corpus.json", "md": out / "corpus.md",
            "png": png, "data": data}

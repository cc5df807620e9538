"""A corpus robot's own page: the scene report in its light form plus what the import found.

:func:`render_robot_page` is :func:`urdf2links.compare.reports.report.render_html` with ``light=True`` (one
overview figure, ~30 KB, instead of the four plots, ~150-350 KB: a corpus has dozens of robots) and
a section on the import: the inertia audit's findings and repairs, the importer's notes (what was
tolerated or folded), MuJoCo's reason when it refused the file on route 2.
"""

from __future__ import annotations

import html

from ..reports.report import render_html

__all__ = ["render_robot_page"]


def _list(items, *, limit: int = 40) -> str:
    e = html.escape
    shown = [f"<li>{e(str(x))}</li>" for x in items[:limit]]
    if len(items) > limit:
        shown.append(f"<li>... and {len(items) - limit} more (summary.json has them all)</li>")
    return "<ul class='notes'>" + "".join(shown) + "</ul>"


def import_section(row: dict) -> str:
    """The import of one corpus robot as an HTML section: audit findings (and repairs), notes,
    route 2's status and MuJoCo's reason."""
    e = html.escape
    imp, te = row["import"], row["terms"]
    parts = ["<h2>Import</h2>"]
    if row.get("thumbnail"):
        parts.append("<img src='thumbnail.png' alt='the robot at its initial pose' style='float: right; border: 0'>")
    parts.append(f"<p><code>{e(row['file'])}</code>: robot <b>{e(str(row['name']))}</b>, {row['links']} links, "
                 f"{row['n']} coordinates (fixed base).</p>")
    audit = imp["audit"]
    parts.append(f"<p><b>Inertia audit</b>: {len(audit)} finding(s)"
                 + (f", {len(imp['repairs'])} repaired" if imp["repairs"] else "") + ".</p>")
    if audit:
        parts.append(_list([f"{a['link']}: {a['kind']}: {a['message']}"
                            + (f" -> repaired: {a['fix']}" if a["action"] == "repaired" else "") for a in audit]))
    route2 = {"as written": "MuJoCo's own URDF import loaded the file as written.",
              "repaired": "MuJoCo refused the file as written; route 2 compared the project's repaired text.",
              "refused": "MuJoCo refused the file in every form tried: route 2 has no figures.",
              "skipped": "route 2 was not run."}.get(te["route2_status"], "")
    parts.append(f"<p><b>Route 2</b>: {e(route2)}"
                 + (f" MuJoCo's reason: <code>{e(te['route2_reason'])}</code>" if te.get("route2_reason") else "")
                 + "</p>")
    if imp["notes"]:
        parts.append(f"<details><summary class='small'>import notes ({len(imp['notes'])}): what the reader "
                     "tolerated, folded or ignored</summary>" + _list(imp["notes"]) + "</details>")
    return "\n".join(parts)


def render_robot_page(c, summary: dict, row: dict, *, check=None, index_link: str | None = None) -> str:
    """The page of a compared corpus robot (``c`` its :class:`~urdf2links.compare.agreement.trajectory.SceneComparison`,
    ``summary`` its JSON-ready summary, ``row`` its corpus row); ``index_link`` back to the corpus
    index. The command shown regenerates the robot's full report."""
    command = (f"urdf2links compare {row['file']} --q0 random --seed {row['seed']} --t-end {row['t_end']:g}"
               + f" (from the corpus folder; `--out DIR` for the full report with all plots)")
    return render_html(c, summary, command=command, check=check, index_link=index_link, index_label="all robots",
                       light=True, extra_sections=[import_section(row)])

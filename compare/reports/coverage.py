"""A report's coverage section: what the run exercised (E66, E67), as HTML, Markdown and an index cell.

Reads ``summary["coverage"]`` (:meth:`urdf2links.scenes.coverage.Coverage.summary`); a summary written
before coverage was measured has none, and every function here then says so instead of failing.
"""

from __future__ import annotations

import html

from ..formatting import fmt, fmt_md

__all__ = ["coverage_html", "coverage_markdown", "coverage_cell", "weak_evidence"]


def weak_evidence(s: dict) -> bool:
    """Whether the summary ``s`` is marked weak evidence (E67); False when it has no coverage."""
    return bool((s.get("coverage") or {}).get("weak_evidence"))


def coverage_cell(s: dict, *, markdown: bool = False) -> str:
    """The index's coverage cell: ``k/n moved`` and the WEAK EVIDENCE mark; ``-`` without coverage."""
    cov = s.get("coverage")
    if not cov:
        return "-" if markdown else "&ndash;"
    text = f"{cov['moved']}/{cov['coordinates']} moved"
    if markdown:
        return text + (" **weak evidence**" if cov["weak_evidence"] else "")
    return text + ("<br><span class='fail'>weak evidence</span>" if cov["weak_evidence"] else "")


def coverage_html(s: dict, number: int, table) -> list[str]:
    """The section ``number`` of a report page: the coverage line and, per coordinate, the range
    traversed, its fraction of the range, the largest |q'| and the energy swing (``table(rows, header,
    num_cols)`` renders the table)."""
    e = html.escape
    cov = s.get("coverage")
    if not cov:
        return []
    box = "box chaos" if cov["weak_evidence"] else "box"
    total = cov.get("energy_swing_total")
    parts = [f"<h2>{number}. Coverage: what the run exercised</h2>",
             f"<div class='{box}'>{e(cov['text'])}.</div>",
             "<p>Per coordinate, from urdf2links' run: the range traversed (max q &minus; min q, rad or m) and its "
             "fraction of the joint's range (its limits, else a &plusmn;1 window), the largest |q'|, and the energy "
             "the coordinate exchanged with the others: the swing (max &minus; min) of its share "
             "E<sub>k</sub> = &frac12; q'<sub>k</sub> (A q')<sub>k</sub> of the kinetic energy (E66)"
             + (f"; largest kinetic energy {fmt(cov['kinetic_max'])} J, swings summed {fmt(total)} J"
                if cov.get("kinetic_max") is not None else "") + ".</p>"]
    rows = [[e(name), fmt(c["traversed"]), f"{c['fraction_of_range']:.0%}", fmt(c["max_rate"]),
             fmt(c["energy_swing"]) if c["energy_swing"] is not None else "&ndash;"]
            for name, c in cov["by_coordinate"].items()]
    parts.append(table(rows, ["coordinate", "traversed", "of range", "max |q'|", "energy swing (J)"],
                       num_cols=(1, 2, 3, 4)))
    return parts


def coverage_markdown(s: dict) -> list[str]:
    """The coverage lines of ``summary.md``."""
    cov = s.get("coverage")
    if not cov:
        return []
    lines = [f"**Coverage:** {cov['text']}.", "", "| coordinate | traversed | of range | max abs q' | energy swing (J) |",
             "|---|---|---|---|---|"]
    lines += [f"| {name} | {fmt_md(c['traversed'])} | {c['fraction_of_range']:.0%} | {fmt_md(c['max_rate'])} | "
              f"{fmt_md(c['energy_swing']) if c['energy_swing'] is not None else '-'} |"
              for name, c in cov["by_coordinate"].items()]
    return lines + [""]

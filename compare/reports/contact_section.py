"""The report's ground-contact section (issue 37): the law, the same law in MuJoCo, MuJoCo's native contact.

A ``[[contact]]`` scene's trajectory section already compares the two engines running the same law
(docs/equations.md (E83)); this section says what the law is, where its spheres are, and how far MuJoCo's own
contact (E84) lands from it: base height, feet positions and slip, time to settle, with a figure of the base
height and the deepest sphere's depth in both.
"""

from __future__ import annotations

import html

from ..figures import figure, png_base64
from ..formatting import fmt

__all__ = ["contact_section", "contact_markdown"]


def _settle(x) -> str:
    return "not within the run" if x is None else f"{x:.3g} s"


def _rows(nat: dict) -> list[list[str]]:
    b, f, s = nat["base_height"], nat["feet"], nat["settle_time"]
    return [["base height at the end (m, the root link's z" + (f"; ground at {b['ground']:g} m" if b.get("ground")
                                                                   is not None else "") + ")", fmt(b["ours_final"]), fmt(b["native_final"]),
             fmt(b["native_final"] - b["ours_final"])],
            *([["lowest base height (m)", fmt(b["ours_min"]), fmt(b["native_min"]),
                fmt(b["native_min"] - b["ours_min"])]] if "ours_min" in b else []),
            ["largest base height difference (m)", "", "", fmt(b["max_difference"])],
            ["feet: largest distance at the end (m)", "", "", fmt(f["final_max_distance"])],
            ["largest slip of a sphere while touching (m)", fmt(f["slip_ours_max"]), fmt(f["slip_native_max"]),
             fmt(f["slip_native_max"] - f["slip_ours_max"])],
            ["time to settle (kinetic energy < 1e-3 of its largest)", _settle(s["ours"]), _settle(s["native"]), ""],
            ["largest coordinate difference (m or rad)", "", "", fmt(nat["max_abs_q_difference"])]]


def _plot(series) -> str:
    fig = figure(8.0, 3.2)
    ax1, ax2 = fig.subplots(1, 2)
    t = series["t"]
    ax1.plot(t, series["base_ours"], label="urdf2links (the law)", lw=1.4)
    ax1.plot(t, series["base_native"], label="MuJoCo native contact", lw=1.0, ls="--")
    ax1.set(xlabel="t (s)", ylabel="root link height (m)", title="base height")
    ax2.plot(t, 1e3 * series["depth_ours"], lw=1.4)
    ax2.plot(t, 1e3 * series["depth_native"], lw=1.0, ls="--")
    ax2.set(xlabel="t (s)", ylabel="depth (mm)", title="deepest sphere's depth")
    ax1.legend(fontsize=8)
    return png_base64(fig)


def contact_section(c, summary: dict) -> list[str]:
    """HTML fragments of the section (none for a scene without contact)."""
    con = summary.get("contact")
    if not con:
        return []
    e = html.escape
    nat = con["native"]
    links = sorted({s["link"] for s in con["spheres"]})
    header = "<tr><th>figure</th><th>urdf2links (the law)</th><th>MuJoCo native</th><th>native - law</th></tr>"
    body = "".join("<tr>" + "".join(f"<td>{e(x)}</td>" for x in row) + "</tr>" for row in _rows(nat))
    parts = ["<h2>Ground contact</h2>",
             "<p>The ground is a compliant law (docs/equations.md (E77)-(E80)): " + "; ".join(e(x) for x in con["law"])
             + f". {len(con['spheres'])} contact sphere(s) on {e(', '.join(links))}"
             + (". " + e("; ".join(con["notes"])) if con["notes"] else "") + ".</p>",
             "<p>MuJoCo runs the same law in its compiled control callback, its own contacts off (E83): the "
             "trajectory and energy sections above compare the two engines on the same physics.</p>",
             "<h3>MuJoCo's native contact, as a reference (not an error)</h3>",
             f"<p>The same scene with MuJoCo's own contacts ({e(nat['integrator'])}, dt {nat['timestep']:g} s): "
             + e("; ".join(nat["parameters"])) + ". MuJoCo's friction is hard Coulomb and its normal force a soft "
             "constraint (E84): how far it lands from the law is what moving a policy between the engines "
             "changes.</p>",
             f"<table>{header}{body}</table>"]
    if nat.get("native_blow_ups"):
        parts.append(f"<p>MuJoCo's native run became unstable: {e(str(nat['native_blow_ups']))}.</p>")
    series = getattr(c, "info", {}).get("contact_series")
    if series is not None:
        parts.append(f"<img alt='ground contact' src='data:image/png;base64,{_plot(series)}'>")
    return parts


def contact_markdown(summary: dict) -> list[str]:
    """The section's lines in summary.md."""
    con = summary.get("contact")
    if not con:
        return []
    nat = con["native"]
    lines = ["", "## Ground contact", "", "Law: " + "; ".join(con["law"]) + ".", "",
             "MuJoCo's native contact (a reference, not an error): " + "; ".join(nat["parameters"]), "",
             "| figure | urdf2links (the law) | MuJoCo native | native - law |", "|---|---|---|---|"]
    lines += ["| " + " | ".join(row) + " |" for row in _rows(nat)]
    return lines

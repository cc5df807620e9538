"""The plots of a scene's comparison report: coordinates of both engines, error, energy, terms."""

from __future__ import annotations

import math

import numpy as np

from ..figures import figure, margins, png_base64

__all__ = ["plot_coordinates", "plot_error", "plot_energy", "plot_terms", "plot_overview"]


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
    fig = figure(11, 1.9 * rows + 0.5)
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
    margins(fig, top=0.75, wspace=1.0, hspace=0.3)     # top: the title, and an axes' offset text (1e-16) under it
    return png_base64(fig)


def plot_error(c, summary) -> str:
    fig = figure(11, 4.2)
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
    _log_axis(ax)
    margins(fig)
    return png_base64(fig)


def plot_energy(c, summary) -> str:
    en = c.energy
    moving = c.scene.base is not None
    work = summary["energy"]["work_terms"]
    k = _every(len(c.t))
    fig = figure(11, 8.2 if moving else 6.0)
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
    _log_axis(ax)
    margins(fig, hspace=0.3)
    return png_base64(fig)


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
        if r.get("max_rel_error_actuator") is not None:
            labels.append(f"{tag}: actuators vs qfrc_actuator")
            values.append(r["max_rel_error_actuator"])
            colors.append(col)
    fig = figure(11, 0.42 * len(labels) + 1.2)
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
    _log_axis(ax, ax.xaxis, decades=7)
    margins(fig, left=2.9, top=0.2)         # left: the bars' labels ("route 2 (repaired): e+G vs qfrc_bias")
    return png_base64(fig)


def _log_axis(ax, axis=None, *, decades: int = 6) -> None:
    """A log axis (default: y) with a handful of labelled decades and no minor labels (drawing hundreds
    of tick labels is what made a small figure cost seconds), labelled ``1e-12`` in plain text (the
    default ``10^-12`` is typeset by mathtext: a third of a small figure's time)."""
    from matplotlib.ticker import LogFormatter, LogLocator, NullFormatter

    axis = ax.yaxis if axis is None else axis
    axis.set_major_locator(LogLocator(numticks=decades))
    axis.set_major_formatter(LogFormatter())
    axis.set_minor_locator(LogLocator(subs=(), numticks=decades))
    axis.set_minor_formatter(NullFormatter())


def plot_overview(c, summary) -> str:
    """One small figure for a light page (a corpus robot): left, the largest difference over the
    coordinates ``max_j |q_ours - q_MuJoCo|`` against time with the divergence threshold; right, each
    engine's energy balance ``|h - h(0) - W|`` (``h = E + V`` for a fixed base). Zeros (identical
    results) are not drawn on the log axes."""
    fig = figure(11, 3.0, dpi=72)
    fig.set_layout_engine(None)
    fig.subplots_adjust(left=0.07, right=0.99, bottom=0.16, top=0.9, wspace=0.22)
    ax, bx = fig.subplots(1, 2)
    k = _every(len(c.t), 600)
    if c.error.size and np.any(c.error > 0):
        e = c.error.max(axis=1)
        ax.plot(c.t[k], np.where(e > 0, e, np.nan)[k], color="k", lw=1.2, label="max over coordinates")
    ax.axhline(c.threshold, color="C3", ls="--", lw=1.0, label=f"divergence threshold {c.threshold:g}")
    div = summary["trajectory"]["divergence_time"]
    if div is not None:
        ax.axvline(div, color="C3", ls=":", lw=1.3, label=f"divergence t = {div:.3g} s")
    ax.set_yscale("log")
    ax.set_xlabel("t (s)")
    ax.set_ylabel("|q urdf2links - q MuJoCo| (rad, m)")
    ax.set_title("trajectory difference", fontsize=10)
    work = summary["energy"]["work_terms"]
    for key, color, label in (("ours_balance", "C0", "urdf2links"), ("mujoco_balance", "C1", "MuJoCo")):
        b = np.abs(c.energy[key])
        if np.any(b > 0):
            bx.plot(c.t[k], np.where(b > 0, b, np.nan)[k], color=color, lw=1.0, label=label)
    bx.set_yscale("log")
    sym = "h" if c.scene.base is not None else "(E + V)"
    bx.set_xlabel("t (s)")
    bx.set_ylabel(f"|{sym} - {sym}(0)" + (" - W|" if work else "|") + " (J)")
    bx.set_title("energy balance of each engine (zero: not drawn)", fontsize=10)
    for a in (ax, bx):
        _log_axis(a)
        a.grid(alpha=0.3, which="major")
        if a.get_legend_handles_labels()[0]:
            a.legend(loc="lower right", fontsize=7)
    return png_base64(fig)

"""The figure of a derivative filter: its gains against the logged positions' spectrum (PNG)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from scipy.signal import welch

__all__ = ["plot_filter"]


def plot_filter(d, path) -> Path:
    """Top: each joint's position spectrum (Welch, one-sided, detrended), the white-noise floor
    ``2 sigma^2 / fs`` of the estimated noise (E95) and the bandwidth. Bottom: the filter's gains
    ``G_0, G_1, G_2`` (E93, E94), 1 for an ideal smoother and differentiators. ``d``: a Derivatives."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    filt, log = d.filter, d.log
    fs = filt.fs
    # segments long enough to resolve a twentieth of the bandwidth (as far as the log's length allows)
    nper = int(min(len(log.times), 2 ** int(np.ceil(np.log2(max(16.0, 20 * fs / filt.bandwidth_hz))))))
    fig, (top, bottom) = plt.subplots(2, 1, sharex=True, figsize=(8, 6.5), height_ratios=(3, 2))
    f = None
    for j, name in enumerate(log.names):
        if not log.logged("position")[j]:
            continue
        f, p = welch(log.positions[:, j], fs=fs, nperseg=nper, detrend="linear")
        top.loglog(f[1:], p[1:], lw=0.9, label=name)
    floor = 2 * float(np.mean(d.noise ** 2)) / fs
    top.axhline(floor, color="k", ls=":", lw=1, label=f"noise floor (sigma {np.sqrt(np.mean(d.noise ** 2)):.2g})")
    for ax in (top, bottom):
        ax.axvline(filt.bandwidth_hz, color="crimson", ls="--", lw=1)
        ax.grid(True, which="both", alpha=0.25)
    top.set_ylabel("position PSD (unit$^2$/Hz)")
    how, _, band = filt.describe().partition(": bandwidth")
    top.set_title(f"{log.source}\n{how}\nbandwidth{band}", fontsize=8.5)
    top.legend(fontsize=7, ncol=2, loc="lower left")
    ff = np.geomspace(f[1] if f is not None else fs / len(log.times), fs / 2, 600)
    g = filt.gains(ff)
    for k, lab in enumerate(("smoother $G_0$", "velocity $G_1$", "acceleration $G_2$")):
        bottom.semilogx(ff, g[k], lw=1.3, ls=("-", "--", ":")[k], label=lab)
    bottom.axhline(1 / np.sqrt(2), color="grey", lw=0.8)
    bottom.text(filt.bandwidth_hz, 1.05, f" {filt.bandwidth_hz:.3g} Hz", color="crimson", fontsize=8)
    bottom.set_ylim(-0.05, 1.2)
    bottom.set_xlabel("frequency (Hz)")
    bottom.set_ylabel("gain / ideal")
    bottom.legend(fontsize=8, loc="lower left")
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path

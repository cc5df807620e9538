"""Plots of trajectories (matplotlib, written to PNG; no display needed)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["plot_trajectory"]


def plot_trajectory(traj, path) -> Path:
    """Coordinates against time (top), energies (middle) and the power-balance error (bottom)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(3, 1, figsize=(9, 9), sharex=True, gridspec_kw={"height_ratios": [3, 2, 1.5]})
    ax = axes[0]
    for j, name in enumerate(traj.coordinate_names):
        ax.plot(traj.t, traj.q[:, j], lw=1.2, label=name)
    ax.set_ylabel("coordinate (rad or m)")
    ax.legend(loc="upper right", fontsize=8, ncol=max(1, len(traj.coordinate_names) // 8))
    s = traj.stats
    ax.set_title(f"{traj.scene}: {traj.robot}, {s['method']} rtol {s['rtol']:g}"
                 + (f" dt {s['dt']:g}" if s.get("dt") else "") + f" - {s['nsteps']} steps, {s['wall_time']:.2f} s wall")
    ax.grid(alpha=0.3)
    e = traj.energy
    ax = axes[1]
    ax.plot(traj.t, e["kinetic"], label="kinetic E")
    ax.plot(traj.t, e["potential"], label="potential V")
    ax.plot(traj.t, e["function"], label="E + V (energy function h)", color="k")
    if np.abs(e["work"]).max() > 0:
        ax.plot(traj.t, e["work"] + e["function"][0], "--", label="h(0) + work W")
    ax.set_ylabel("energy (J)")
    ax.legend(loc="upper right", fontsize=8)
    ax.grid(alpha=0.3)
    ax = axes[2]
    err = np.abs(e["error"])
    positive = err[err > 0]
    floor = positive.min() / 10 if positive.size else 1e-16
    ax.semilogy(traj.t[1:], np.maximum(err[1:], floor), color="tab:red")  # h - h(0) - W is 0 at t = 0
    ax.set_ylim(bottom=floor)
    ax.set_ylabel("|h - h(0) - W| (J)")
    ax.set_xlabel("time (s)")
    ax.grid(alpha=0.3, which="both")
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path

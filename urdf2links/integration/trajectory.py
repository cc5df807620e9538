"""What a run returns: :class:`Trajectory` (states, energies, poses, the run's figures), its files (NPZ, CSV),
and what its wall time measures (:data:`TIMED_REGION`). :func:`~urdf2links.integration.simulate.simulate` and
the constrained path (:mod:`~urdf2links.integration.constrained`) both return one.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = ["Trajectory", "TIMED_REGION"]

#: What ``Trajectory.stats["wall_time"]`` contains.
TIMED_REGION = ("urdf2links' integrator: the integration loop from the first evaluation of the compiled right-hand "
                "side to the last step, with the dense output's coefficients the samples are read from (re-charting "
                "switches included); not the plan's compilation, the evaluation at the samples, the energies, the "
                "poses, nor numba's compilation (done before the clock starts, or the clock stopped while it runs)")


@dataclass(frozen=True, eq=False)
class Trajectory:
    """Result of :func:`simulate`.

    ``t`` (m,), ``q`` and ``qd`` (m, n) with columns ``coordinate_names``; ``energy`` dict of (m,)
    arrays: ``kinetic`` E, ``potential`` V (gravity and springs), ``work`` W (non-potential forces
    and base), ``function`` h (E + V for a fixed base), ``error`` ``h - h(0) - W``;
    ``poses`` dict link -> (m, 4, 4); ``stats`` (method, rtol, atol, dt, nfev, nsteps, njev, ``wall_time`` the
    integration (:data:`TIMED_REGION`), ``run_s`` the whole :func:`simulate` call, ``stretches``
    (``auto``: which method ran when, and why; :func:`describe_stretches`), ``methods_used``,
    ``limit_excursions``: :class:`~urdf2links.scenes.limits.LimitExcursion` dicts, ``spring_notes``);
    ``sol`` the integrator's dense interpolant ``t -> (q, qd, W)`` or None; ``charts`` the
    :class:`~urdf2links.integration.charts.ChartedRun` (segments, states in each chart) when floating links were
    re-charted, else None.
    """

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    coordinate_names: tuple[str, ...]
    energy: dict
    poses: dict = field(default_factory=dict)
    stats: dict = field(default_factory=dict)
    scene: str = ""
    robot: str = ""
    sol: object = None
    charts: object = None

    @property
    def energy_error(self) -> float:
        """max |h - h(0) - W| over the run, relative to the energy scale max(|E|, |V - V(0)|, |W|)."""
        e = self.energy
        scale = max(np.abs(e["kinetic"]).max(), np.abs(e["potential"] - e["potential"][0]).max(),
                    np.abs(e["work"]).max(), 1e-300)
        return float(np.abs(e["error"]).max() / scale)

    def save_npz(self, path) -> Path:
        path = Path(path)
        arrays = {"t": self.t, "q": self.q, "qd": self.qd, "coordinate_names": np.array(self.coordinate_names)}
        arrays.update({f"energy_{k}": v for k, v in self.energy.items()})
        arrays.update({f"pose_{k}": v for k, v in self.poses.items()})
        np.savez_compressed(path, **arrays, stats=np.array(repr(self.stats)))
        return path

    def save_csv(self, path) -> Path:
        path = Path(path)
        with path.open("w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(["t", *self.coordinate_names, *(f"d_{c}" for c in self.coordinate_names),
                        *(f"energy_{k}" for k in self.energy)])
            for i in range(len(self.t)):
                w.writerow([repr(float(self.t[i])), *map(repr, self.q[i].tolist()), *map(repr, self.qd[i].tolist()),
                            *(repr(float(v[i])) for v in self.energy.values())])
        return path

"""How much of a robot's dynamics a run exercised: the coverage of a trajectory (E66, E67).

Two engines that agree on a run where nothing moves have checked little. :func:`coverage` measures,
per coordinate ``k`` of a trajectory sampled at times ``t`` (m,):

* ``traversed_k = max q_k - min q_k`` (rad or m), and the fraction of the coordinate's range that is
  (:func:`~urdf2links.scenes.excitation.coordinate_ranges`: its limits, else a +-1 window);
* ``max_rate_k = max |q'_k|``;
* the energy it exchanged with the other coordinates (E66): the kinetic energy splits into shares
  ``E_k = 1/2 q'_k (A(q) q')_k`` with ``sum_k E_k = E``; the swing ``max E_k - min E_k`` (J) of a
  share is the energy that flowed into and out of that coordinate, through the coupling of ``A`` and
  the forces, over the run.

A run is **weak evidence** (E67) when fewer than half of its coordinates moved by more than
:data:`MOVED` (``traversed_k > 1e-3`` rad or m): whatever the engines' agreement, it says little about
the joints' dynamics. ``Coverage.summary()`` is the JSON a report carries; ``Coverage.text()`` one line.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .excitation import coordinate_ranges

__all__ = ["coverage", "Coverage", "MOVED", "WEAK_FRACTION", "MAX_ENERGY_STATES"]

#: A coordinate has moved when it traversed more than this (rad or m) in the run.
MOVED = 1e-3
#: A run whose fraction of moved coordinates is below this is weak evidence (E67).
WEAK_FRACTION = 0.5
#: The kinetic-energy shares are evaluated at this many samples at most (evenly spread).
MAX_ENERGY_STATES = 200


@dataclass(frozen=True)
class Coverage:
    """What :func:`coverage` measured: per coordinate (n,) ``traversed`` (rad or m), ``range_width``
    (the coordinate's range), ``max_rate`` (rad/s or m/s), ``energy_swing`` (J, E66; None without a
    model); ``kinetic_max`` (J, the largest E in the run, or None)."""

    names: tuple[str, ...]
    traversed: np.ndarray
    range_width: np.ndarray
    max_rate: np.ndarray
    energy_swing: np.ndarray | None
    kinetic_max: float | None
    threshold: float = MOVED

    @property
    def moved(self) -> np.ndarray:
        """(n,) bool: the coordinates that traversed more than the threshold."""
        return self.traversed > self.threshold

    @property
    def moved_fraction(self) -> float:
        """The fraction of the coordinates that moved (1.0 for a model without coordinates)."""
        return float(np.mean(self.moved)) if self.moved.size else 1.0

    @property
    def weak(self) -> bool:
        """Weak evidence (E67): fewer than half of the coordinates moved."""
        return self.moved_fraction < WEAK_FRACTION

    def text(self) -> str:
        """One line: how many coordinates moved, and the weak-evidence mark when it applies."""
        n, k = len(self.names), int(np.sum(self.moved))
        head = f"{k} of {n} coordinates moved by more than {self.threshold:g} (rad or m)"
        if n:
            head += f", median {np.median(self.traversed / self.range_width):.0%} of their range"
        return head + (": WEAK EVIDENCE (fewer than half moved: the run says little about the joints' dynamics)"
                       if self.weak else "")

    def summary(self) -> dict:
        """The JSON-ready coverage section of a report (per coordinate and overall)."""
        per = {}
        for i, name in enumerate(self.names):
            per[name] = {"traversed": float(self.traversed[i]),
                         "fraction_of_range": float(self.traversed[i] / self.range_width[i]),
                         "max_rate": float(self.max_rate[i]),
                         "energy_swing": None if self.energy_swing is None else float(self.energy_swing[i])}
        swing = None if self.energy_swing is None else float(np.sum(self.energy_swing))
        return {"coordinates": len(self.names), "moved": int(np.sum(self.moved)),
                "moved_fraction": self.moved_fraction, "threshold": self.threshold, "weak_evidence": self.weak,
                "kinetic_max": self.kinetic_max, "energy_swing_total": swing, "text": self.text(),
                "by_coordinate": per,
                "definitions": "traversed = max q - min q (rad or m); fraction_of_range over the joint's limits, else "
                               "a +-1 window; max_rate = max |q'|; energy_swing = max - min of the coordinate's share "
                               "E_k = 1/2 q'_k (A q')_k of the kinetic energy (E66), J; weak evidence when fewer than "
                               f"{WEAK_FRACTION:.0%} of the coordinates traversed more than {self.threshold:g} (E67)"}


def coverage(q, qd, *, model=None, names=None, threshold: float = MOVED) -> Coverage:
    """The coverage of a run sampled as ``q``, ``qd`` (m, n) (module doc). ``model`` (a
    :class:`~urdf2links.dynamics.model.Model` of the run's coordinates) gives the ranges and the
    energy shares (E66, ``A(q)`` at up to :data:`MAX_ENERGY_STATES` samples); without it the ranges are
    +-1 windows and the energy is not measured. ``names`` default to the model's coordinates."""
    q, qd = np.atleast_2d(np.asarray(q, float)), np.atleast_2d(np.asarray(qd, float))
    if q.shape != qd.shape:
        raise ValueError(f"coverage: q and qd must have one shape (m, n), got {q.shape} and {qd.shape}")
    n = q.shape[1]
    if model is not None and model.n != n:
        raise ValueError(f"coverage: the model has {model.n} coordinates, the run {n}")
    names = tuple(names if names is not None else model.coordinate_names if model is not None
                  else (f"q{i}" for i in range(n)))
    finite = np.all(np.isfinite(q), axis=1) & np.all(np.isfinite(qd), axis=1)
    q, qd = q[finite], qd[finite]
    if not len(q):
        zero = np.zeros(n)
        return Coverage(names, zero, np.ones(n), zero, None, None, threshold)
    traversed = q.max(axis=0) - q.min(axis=0)
    width = coordinate_ranges(model).width if model is not None else np.full(n, 2.0)
    swing, kmax = None, None
    if model is not None and n:
        pick = np.unique(np.linspace(0, len(q) - 1, min(len(q), MAX_ENERGY_STATES)).round().astype(int))
        # one state per call: the batch call's parallel kernel would be compiled for this alone (seconds of
        # a first report, issue 32), and each state's A is the same to the bit (Model's batch contract)
        A = np.array([model.mass_matrix(row) for row in q[pick]])
        share = 0.5 * qd[pick] * np.einsum("bij,bj->bi", A, qd[pick])
        swing = share.max(axis=0) - share.min(axis=0)
        kmax = float(share.sum(axis=1).max())
    return Coverage(names, traversed, np.where(width > 0, width, 1.0), np.abs(qd).max(axis=0), swing, kmax, threshold)

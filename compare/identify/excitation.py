"""Excitation trajectories: periodic Fourier series within the joint limits (docs/identify.md, "The command").

Each coordinate ``i`` follows ``q_i(t) = c_i + sum_k a_ik sin(k w t) + b_ik cos(k w t)``, ``k = 1..K``, period
``2 pi / w``. A seeded draw (:func:`random_trajectory`) takes ``a, b ~ N(0, 1) / k`` and scales each coordinate so
that it stays within ``SAFETY`` of its half range around the range's middle and, when the file states one, within
``SAFETY`` of its velocity limit; :func:`fit_within` applies the same bounds to any coefficients (the ``--design``
search, :mod:`.design`). The velocities and accelerations are the series' exact derivatives.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["JointBounds", "FourierTrajectory", "random_trajectory", "fit_within", "bounds_of_parts", "SAFETY"]

#: Fraction of each bound (half range, velocity limit) a trajectory may use.
SAFETY = 0.8
#: The window (rad or m) either side of 0 of a coordinate without finite limits.
FREE_WINDOW = 1.5


@dataclass(frozen=True)
class JointBounds:
    """Per coordinate (n,): ``lower``, ``upper`` (rad or m), ``velocity`` (rad/s or m/s; inf: none stated),
    ``effort`` (N m or N; inf: none stated), in DESCRIPTION's coordinates ``names``."""

    names: tuple[str, ...]
    lower: np.ndarray
    upper: np.ndarray
    velocity: np.ndarray
    effort: np.ndarray


def bounds_of_parts(parts, names) -> JointBounds:
    """The bounds of the one-coordinate joints ``names`` of a description's parts
    (:class:`urdf2links.parsers.parts.RobotParts`): the file's limits, else ``+-FREE_WINDOW`` around home."""
    joints = {j.name: j for j, _b in parts.joints}
    lo, hi, vel, eff = [], [], [], []
    for name in names:
        j = joints[name]
        if j.lower is not None and j.upper is not None and j.lower < j.upper and max(abs(j.lower), abs(j.upper)) < 1e6:
            lo.append(j.lower), hi.append(j.upper)
        else:
            lo.append(j.ref - FREE_WINDOW), hi.append(j.ref + FREE_WINDOW)
        vel.append(j.velocity if j.velocity else np.inf)
        eff.append(j.effort if j.effort else np.inf)
    return JointBounds(tuple(names), np.array(lo), np.array(hi), np.array(vel, float), np.array(eff, float))


@dataclass(frozen=True)
class FourierTrajectory:
    """``q(t) = c + sum_k a[:, k-1] sin(k w t) + b[:, k-1] cos(k w t)`` (module doc): ``c`` (n,), ``a``, ``b``
    (n, K), ``w`` the base frequency (rad/s)."""

    names: tuple[str, ...]
    w: float
    c: np.ndarray
    a: np.ndarray
    b: np.ndarray

    @property
    def period(self) -> float:
        return 2 * np.pi / self.w

    def _phases(self, t):
        t = np.atleast_1d(np.asarray(t, float))
        k = np.arange(1, self.a.shape[1] + 1)
        kw = k * self.w
        return np.sin(np.outer(t, kw)), np.cos(np.outer(t, kw)), kw

    def evaluate(self, t) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``q``, ``q'``, ``q''`` at the times ``t`` (T,), each (T, n)."""
        s, co, kw = self._phases(t)
        q = self.c + s @ self.a.T + co @ self.b.T
        qd = (co * kw) @ self.a.T - (s * kw) @ self.b.T
        qdd = -(s * kw**2) @ self.a.T - (co * kw**2) @ self.b.T
        return q, qd, qdd

    def to_json(self) -> dict:
        return {"names": list(self.names), "w": self.w, "period": self.period, "c": self.c.tolist(),
                "a": self.a.tolist(), "b": self.b.tolist()}


def fit_within(names, w: float, a, b, bounds: JointBounds, *, grid: int = 2000) -> FourierTrajectory:
    """The series ``a``, ``b`` (n, K) centred in ``bounds`` and scaled per coordinate to use at most ``SAFETY`` of
    its half range and of its velocity limit (checked on ``grid`` points of one period)."""
    a, b = np.array(a, float), np.array(b, float)
    c = 0.5 * (bounds.lower + bounds.upper)
    half = 0.5 * (bounds.upper - bounds.lower)
    probe = FourierTrajectory(tuple(names), float(w), np.zeros_like(c), a, b)
    q, qd, _ = probe.evaluate(np.linspace(0.0, probe.period, grid, endpoint=False))
    reach = np.max(np.abs(q), axis=0)
    speed = np.max(np.abs(qd), axis=0)
    scale = np.minimum(SAFETY * half / np.maximum(reach, 1e-300), SAFETY * bounds.velocity / np.maximum(speed, 1e-300))
    return FourierTrajectory(tuple(names), float(w), c, a * scale[:, None], b * scale[:, None])


def random_trajectory(bounds: JointBounds, *, seed: int, harmonics: int = 5, period: float = 10.0) -> FourierTrajectory:
    """A seeded random Fourier trajectory within ``bounds`` (module doc)."""
    rng = np.random.default_rng(seed)
    n = len(bounds.names)
    k = np.arange(1, harmonics + 1)
    a = rng.standard_normal((n, harmonics)) / k
    b = rng.standard_normal((n, harmonics)) / k
    return fit_within(bounds.names, 2 * np.pi / period, a, b, bounds)

"""Dense output: the continuous solution ``t -> y`` between the steps of an integration.

:class:`DenseOutput` evaluates, on ``[t_min, t_max]``, one of four interpolants: a cubic Hermite
on states and slopes at the steps (RK4, the implicit midpoint), the compiled loops' polynomial
rows (DOP853's seventh-degree form, RK45's quartic, as scipy computes them; Radau5's cubic
collocation polynomial), a wrapped scipy ``OdeSolution``, or pieces of those joined end to end (the
stretches of ``auto``). Shapes: scalar ``t`` -> ``(dim,)``, times ``(k,)`` -> ``(k, dim)``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from scipy.integrate import OdeSolution

__all__ = ["DenseOutput", "midpoint_dense"]


class DenseOutput:
    """Continuous solution ``t -> y`` on ``[t_min, t_max]``: scalar ``t`` -> ``(dim,)``,
    times of shape ``(k,)`` -> ``(k, dim)``. Cubic Hermite from ``(ts, ys, fs)``, the compiled
    loops' polynomial rows ``poly = (method, coefficients (m, r, dim))``, a wrapped scipy
    ``OdeSolution``, or ``pieces``: DenseOutputs of consecutive intervals (each ``t`` is read from
    the last piece that starts at or before it)."""

    __slots__ = ("t_min", "t_max", "_ts", "_ys", "_fs", "_ode", "_poly", "_pieces", "_starts")

    def __init__(self, ts, ys=None, fs=None, ode: OdeSolution | None = None, poly=None, pieces=None):
        self._ts, self._ys, self._fs, self._ode, self._poly = ts, ys, fs, ode, poly
        self._pieces = list(pieces) if pieces else None
        self._starts = np.array([p.t_min for p in self._pieces]) if self._pieces else None
        self.t_min, self.t_max = float(ts[0]), float(ts[-1])

    def __call__(self, t):
        tt = np.asarray(t, dtype=float)
        scalar = tt.ndim == 0
        tt = np.atleast_1d(tt)
        if tt.ndim != 1:
            raise ValueError(f"t must be a scalar or a 1-D array, got shape {tt.shape}")
        slack = 1e-12 * max(1.0, abs(self.t_min), abs(self.t_max))
        if tt.size and (not np.all(np.isfinite(tt)) or tt.min() < self.t_min - slack
                        or tt.max() > self.t_max + slack):
            raise ValueError(f"t={t!r} outside the interpolated interval "
                             f"[{self.t_min!r}, {self.t_max!r}]")
        tt = np.clip(tt, self.t_min, self.t_max)
        if self._pieces is not None:
            out = self._joined(tt)
        elif self._ode is not None:
            out = self._ode(tt).T
        elif self._poly is not None:
            out = self._poly_eval(tt)
        else:
            out = self._hermite(tt)
        return out[0] if scalar else out

    def _joined(self, tt):
        k = np.clip(np.searchsorted(self._starts, tt, side="right") - 1, 0, len(self._pieces) - 1)
        out = np.empty((tt.size, self._ys.shape[1]))
        for j in np.unique(k):
            piece = self._pieces[j]
            at = k == j
            out[at] = piece(np.clip(tt[at], piece.t_min, piece.t_max)).reshape(-1, out.shape[1])
        return out

    def _hermite(self, tt):
        ts = self._ts
        i = np.clip(np.searchsorted(ts, tt, side="right") - 1, 0, ts.size - 2)
        h = ts[i + 1] - ts[i]
        s = ((tt - ts[i]) / h)[:, None]
        s2, r = s * s, 1.0 - s
        r2 = r * r
        return ((1.0 + 2.0 * s) * r2 * self._ys[i] + s2 * (3.0 - 2.0 * s) * self._ys[i + 1]
                + h[:, None] * (s * r2 * self._fs[i] - s2 * r * self._fs[i + 1]))

    def _poly_eval(self, tt):
        """Row ``i + 1`` of the coefficients belongs to the step from ``ts[i]``: DOP853's
        seventh-degree form, RK45's quartic (scipy's) or Radau5's cubic ``y_i + sum_k Q_k x^k``."""
        method, C = self._poly
        ts, ys = self._ts, self._ys
        i = np.clip(np.searchsorted(ts, tt, side="right") - 1, 0, ts.size - 2)
        h = (ts[i + 1] - ts[i])[:, None]
        x = (tt - ts[i])[:, None] / h
        rows = C[i + 1]                                   # (k, r, dim)
        if method == "DOP853":
            y = np.zeros((tt.size, ys.shape[1]))
            for j, r in enumerate(range(rows.shape[1] - 1, -1, -1)):
                y += rows[:, r]
                y *= x if j % 2 == 0 else (1.0 - x)
            return y + ys[i]
        y = np.zeros((tt.size, ys.shape[1]))
        p = np.ones_like(x)
        for r in range(rows.shape[1]):
            p = p * x
            y += rows[:, r] * p
        return ys[i] + (y if method == "Radau5" else h * y)


def midpoint_dense(ts, ys, ks, f0, f_end) -> DenseOutput:
    """The midpoint rule's interpolant: cubic Hermite on the steps ``ts`` (n + 1,), ``ys``, with
    the exact slopes ``f0``, ``f_end`` at the ends and, inside, the second-order weighted mean of
    the two adjacent stage slopes ``ks`` (n, dim)."""
    n = ts.size - 1
    fs = np.empty_like(ys)
    fs[0] = f0
    fs[n] = f_end
    if n > 1:
        h = np.diff(ts)[:, None]
        fs[1:n] = (h[1:] * ks[:-1] + h[:-1] * ks[1:]) / (h[1:] + h[:-1])
    return DenseOutput(ts, ys, fs)

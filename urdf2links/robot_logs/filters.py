"""The zero-phase filters that turn logged positions into velocities and accelerations, and their
frequency responses (the bandwidth that is printed and plotted).

- ``savgol``: Savitzky-Golay (scipy.signal): a least-squares polynomial of degree ``order`` over a centred
  window of ``window`` samples, differentiated; symmetric coefficients, so zero phase. Needs one sampling
  rate. Its gains ``G_k(f) = |H_k(f)| / (2 pi f)^k`` (E94) come from the coefficients (scipy.signal.freqz).
- ``spline``: a smoothing spline (scipy.interpolate.make_smoothing_spline, any spacing), differentiated
  exactly. Its penalty ``lam`` is set from the cutoff: the spline minimises ``sum (y - g)^2 + lam int g''^2``,
  whose response on samples ``dt`` apart is ``H(f) = 1 / (1 + lam dt (2 pi f)^4)`` (E93), the same for every
  derivative order, so ``lam = (sqrt 2 - 1) / (dt (2 pi f_c)^4)`` puts its -3 dB point at ``f_c``.

The bandwidth is the -3 dB frequency of the position smoother ``G_0``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import make_smoothing_spline
from scipy.signal import freqz, savgol_coeffs, savgol_filter

__all__ = ["Filter", "savgol", "spline", "METHODS"]

METHODS = ("savgol", "spline")
_HALF = 1.0 / np.sqrt(2.0)


@dataclass(frozen=True)
class Filter:
    """A stated filter: ``method``, its parameters (``window`` and ``order`` for savgol, ``lam`` for
    spline), the sampling step ``dt`` (s), and ``bandwidth_hz``, the -3 dB frequency of the smoother."""

    method: str
    dt: float
    bandwidth_hz: float
    window: int | None = None
    order: int | None = None
    lam: float | None = None

    @property
    def fs(self) -> float:
        return 1.0 / self.dt

    def gains(self, f: np.ndarray, orders=(0, 1, 2)) -> np.ndarray:
        """(K, F) gains ``G_k(f) = |H_k(f)| / (2 pi f)^k`` (E93, E94) of the smoother (k = 0), the
        differentiator (1) and the second derivative (2), for k in ``orders`` (K,), at frequencies ``f`` (F,)
        Hz; an ideal filter has 1 everywhere."""
        f = np.asarray(f, dtype=float)
        w = 2 * np.pi * np.maximum(f, 1e-12)
        if self.method == "spline":
            g = 1.0 / (1.0 + self.lam * self.dt * w**4)
            return np.vstack([g for _ in orders])
        out = []
        for k in orders:
            h = savgol_coeffs(self.window, self.order, deriv=k, delta=self.dt, use="conv")
            _, H = freqz(h, worN=f, fs=self.fs)
            out.append(np.abs(H) / w**k)
        return np.vstack(out)

    def derivative_bandwidths_hz(self) -> tuple[float, float]:
        """The -3 dB frequencies of the velocity and acceleration gains ``G_1``, ``G_2``."""
        return _bandwidth(self, 1), _bandwidth(self, 2)

    def describe(self) -> str:
        """The filter in one line, as the identify command prints it."""
        if self.method == "savgol":
            how = (f"Savitzky-Golay, window {self.window} samples ({self.window * self.dt:.4g} s), "
                   f"polynomial order {self.order}")
        else:
            how = f"smoothing spline, lam {self.lam:.4g}"
        v, a = self.derivative_bandwidths_hz()
        return (f"{how}, zero phase, at {self.fs:.6g} Hz: bandwidth (-3 dB) {self.bandwidth_hz:.4g} Hz "
                f"(velocity {v:.4g} Hz, acceleration {a:.4g} Hz)")


def _bandwidth(filt: Filter, k: int = 0) -> float:
    """The first frequency where the gain ``G_k`` (E93, E94) falls to 1/sqrt 2, on a grid of fs/8192."""
    f = np.linspace(0.0, 0.5 * filt.fs, 4097)[1:]
    g = filt.gains(f, orders=(k,))[0]
    below = np.flatnonzero(g < _HALF)
    if not below.size:
        return 0.5 * filt.fs
    i = below[0]
    if i == 0:
        return float(f[0])
    return float(np.interp(_HALF, [g[i], g[i - 1]], [f[i], f[i - 1]]))     # g falls from f[i-1] to f[i]


def savgol(dt: float, *, window: int | None = None, order: int = 3, cutoff_hz: float | None = None,
           n_samples: int) -> Filter:
    """The Savitzky-Golay filter of ``window`` samples, or the odd window whose bandwidth is nearest
    ``cutoff_hz`` (bisection: the bandwidth falls as the window grows), at most ``n_samples``."""
    if order < 2:
        raise ValueError(f"savgol: order {order} cannot give accelerations; use order >= 2")
    if window is not None:
        if window % 2 == 0 or window <= order:
            raise ValueError(f"savgol: window {window} must be odd and larger than the order {order}")
        filt = Filter("savgol", dt, 0.0, window=int(window), order=order)
        return Filter("savgol", dt, _bandwidth(filt), window=int(window), order=order)
    lo, hi = (order + 2) // 2, (n_samples - 1) // 2          # half-widths: window = 2 h + 1
    bw = {}

    def at(h):
        if h not in bw:
            bw[h] = _bandwidth(Filter("savgol", dt, 0.0, window=2 * h + 1, order=order))
        return bw[h]
    if hi < lo:
        raise ValueError(f"savgol: {n_samples} samples are too few for a window larger than the order {order}")
    # the bandwidth is near (order + 1) fs / (3.2 N): a window of 2 (order + 1) fs / cutoff is past it,
    # which keeps the search off windows of thousands of samples (each a costly response)
    guess = int(2 * (order + 1) / (dt * cutoff_hz)) + lo
    if guess < hi and at(guess) < cutoff_hz:
        hi = guess
    while hi - lo > 1:
        mid = (lo + hi) // 2
        lo, hi = (mid, hi) if at(mid) > cutoff_hz else (lo, mid)
    h = min((lo, hi), key=lambda x: abs(at(x) - cutoff_hz))
    return Filter("savgol", dt, at(h), window=2 * h + 1, order=order)


def spline(dt: float, *, cutoff_hz: float) -> Filter:
    """The smoothing spline whose -3 dB point (E93) is ``cutoff_hz``."""
    lam = (np.sqrt(2.0) - 1.0) / (dt * (2 * np.pi * cutoff_hz) ** 4)
    return Filter("spline", dt, float(cutoff_hz), lam=float(lam))


def apply(filt: Filter, t: np.ndarray, y: np.ndarray) -> np.ndarray:
    """(3, S, m): ``y`` (S, m) smoothed, its first and its second derivative, by ``filt``."""
    if filt.method == "savgol":
        return np.stack([savgol_filter(y, filt.window, filt.order, deriv=k, delta=filt.dt, axis=0, mode="interp")
                         for k in range(3)])
    try:        # every column in one fit (scipy >= 1.15 takes y (S, m)); else column by column
        s = make_smoothing_spline(t, y, lam=filt.lam)
        return np.stack([s(t), s.derivative(1)(t), s.derivative(2)(t)])
    except ValueError:
        out = np.empty((3,) + y.shape)
        for j in range(y.shape[1]):
            s = make_smoothing_spline(t, y[:, j], lam=filt.lam)
            out[0, :, j], out[1, :, j], out[2, :, j] = s(t), s.derivative(1)(t), s.derivative(2)(t)
        return out

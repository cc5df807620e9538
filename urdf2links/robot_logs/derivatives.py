"""Velocities and accelerations of a log from a stated zero-phase filter, its bandwidth, the noise level.

:func:`derivatives` is what ``identify --data`` calls: it filters the positions (and, with the same
filter, the efforts, so that both sides of ``Q = Y pi`` see one bandwidth) and differentiates them
(:mod:`urdf2links.robot_logs.filters`), estimates each joint's position noise from third differences
(E95), and returns a :class:`Derivatives` that prints its filter and plots it against the spectrum.

Near the ends a centred window does not fit: the first and last ``edge`` samples come from a one-sided
fit (savgol ``mode="interp"``) or the spline's free ends, and are less filtered; :attr:`Derivatives.interior`
selects the samples away from them, and identification should use those.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import filters
from .base import base_coordinates
from .errors import NonUniformError, TooFewSamplesError
from .filters import Filter
from .log import RobotLog

__all__ = ["Derivatives", "derivatives", "noise_level", "DEFAULT_CUTOFF_HZ", "JITTER"]

#: The default bandwidth: robot motions excited for identification lie below a few hertz (Fourier
#: trajectories of 0.05-0.5 Hz fundamentals, a handful of harmonics); 10 Hz passes them and cuts the
#: sensor noise above. It is stated in the result and printed, never silent.
DEFAULT_CUTOFF_HZ = 10.0
#: Savitzky-Golay assumes one sampling rate: steps may differ from the median step by this fraction.
JITTER = 0.01


def noise_level(x: np.ndarray) -> np.ndarray:
    """(m,) standard deviation of white noise on ``x`` (S, m), from its third differences (E95):
    ``Delta^3 e`` has variance ``20 sigma^2`` (1 + 9 + 9 + 1), and a smooth signal sampled fast leaves
    ``Delta^3 x ~ x''' dt^3``, far below the noise; robust (median absolute deviation, 1.4826)."""
    d3 = np.diff(x, n=3, axis=0)
    mad = np.median(np.abs(d3 - np.median(d3, axis=0)), axis=0)
    return 1.4826 * mad / np.sqrt(20.0)


@dataclass(frozen=True)
class Derivatives:
    """The filtered log. Shapes: (S,) ``times``; (S, n) ``positions`` (smoothed), ``velocities``,
    ``accelerations``, ``efforts`` (smoothed by the same filter; NaN where not logged). ``filter``: the
    stated filter and its bandwidth; ``noise`` (n,): each joint's position noise (E95), in the
    positions' unit; ``edge``: samples at each end less filtered (``interior`` leaves them out);
    ``log``: the log filtered (its raw samples, for the spectrum); ``wrenches`` (S, 6): the log's contact
    wrenches interpolated at ``times`` and smoothed by the same filter, or None; ``base`` (3, S, 6): a
    floating base's coordinates ``x, y, z, phi_x, phi_y, phi_z`` (base.BASE_SLOTS) at ``times``, filtered,
    their first and second derivatives, or None; ``notes``: what was done."""

    times: np.ndarray
    names: tuple[str, ...]
    positions: np.ndarray
    velocities: np.ndarray
    accelerations: np.ndarray
    efforts: np.ndarray
    filter: Filter
    noise: np.ndarray
    edge: int
    log: RobotLog
    notes: tuple[str, ...] = ()
    wrenches: np.ndarray | None = None
    base: np.ndarray | None = None

    @property
    def bandwidth_hz(self) -> float:
        return self.filter.bandwidth_hz

    @property
    def interior(self) -> slice:
        """The samples away from the ends (module doc)."""
        return slice(self.edge, len(self.times) - self.edge)

    def describe(self) -> str:
        """The filter and the noise, in lines, as the identify command prints them."""
        noise = ", ".join(f"{n} {s:.2g}" for n, s in zip(self.names, self.noise))
        return "\n".join([f"derivatives: {self.filter.describe()}",
                          f"  position noise (third differences): {noise}",
                          f"  {self.edge} samples at each end less filtered (left out by .interior)"])

    def plot(self, path) -> Path:
        """A PNG of the filter's gains against the positions' spectrum (spectrum_plot)."""
        from .spectrum_plot import plot_filter      # matplotlib, loaded only when a figure is asked for
        return plot_filter(self, path)


def _step(log: RobotLog) -> tuple[float, float, int]:
    """(median step, largest relative deviation of a step from it, the sample after that step)."""
    d = np.diff(log.times)
    dt = float(np.median(d))
    dev = np.abs(d - dt) / dt
    k = int(np.argmax(dev))
    return dt, float(dev[k]), k + 1


def derivatives(log: RobotLog, *, method: str = "savgol", cutoff_hz: float | None = None,
                window: int | None = None, order: int = 3) -> Derivatives:
    """Velocities and accelerations of ``log``'s positions (module doc). ``method``: "savgol" (one
    sampling rate, within :data:`JITTER`) or "spline" (any spacing). The filter: ``window`` (savgol,
    samples, odd) and ``order``, or ``cutoff_hz`` (default :data:`DEFAULT_CUTOFF_HZ`), from which the
    window (or the spline's penalty) is chosen; the bandwidth is in the result."""
    if method not in filters.METHODS:
        raise ValueError(f"derivatives: method {method!r} is not one of {filters.METHODS}")
    if window is not None and (method != "savgol" or cutoff_hz is not None):
        raise ValueError("derivatives: window= is savgol's, and excludes cutoff_hz=")
    S = log.n_samples
    if S < 2 * order + 3:
        raise TooFewSamplesError(f"{log.source}: {S} samples cannot be filtered and differentiated twice; a "
                                 f"polynomial of order {order} needs at least {2 * order + 3}",
                                 equations=S, needed=2 * order + 3, source=log.source, topic=log.topic)
    dt, jitter, k = _step(log)
    cutoff = DEFAULT_CUTOFF_HZ if cutoff_hz is None and window is None else cutoff_hz
    if cutoff is not None and not 0 < cutoff < 0.5 / dt:
        raise ValueError(f"derivatives: cutoff {cutoff} Hz must lie between 0 and the Nyquist frequency "
                         f"{0.5 / dt:.6g} Hz of {log.source}")
    notes = [] if cutoff_hz is not None or window is not None else [
        f"bandwidth: the default {DEFAULT_CUTOFF_HZ:g} Hz (cutoff_hz= or window= to choose)"]
    if method == "savgol":
        if jitter > JITTER:
            raise NonUniformError(
                f"{log.source}: time step {log.at(k - 1)} to {log.at(k)} is {log.times[k] - log.times[k - 1]:.6g} s, "
                f"{100 * jitter:.3g}% off the median step {dt:.6g} s; Savitzky-Golay needs one sampling rate "
                f"(within {100 * JITTER:g}%): use method='spline' (any spacing)", jitter=jitter, column="t",
                **log.where(k))
        filt = filters.savgol(dt, window=window, order=order, cutoff_hz=cutoff, n_samples=S)
        edge = filt.window // 2
    else:
        filt = filters.spline(dt, cutoff_hz=cutoff)
        edge = int(np.ceil(1.0 / (filt.bandwidth_hz * dt)))      # about one period of the cutoff
    P = log.positions
    out = np.full((3,) + P.shape, np.nan)          # a joint without positions stays NaN
    has = np.array(log.logged("position"), dtype=bool)
    if has.any():
        out[:, :, has] = filters.apply(filt, log.times, P[:, has])
    efforts = np.full_like(P, np.nan)
    on = np.array(log.logged("effort"), dtype=bool)
    if on.any():
        efforts[:, on] = filters.apply(filt, log.times, log.efforts[:, on])[0]
    notes.append(f"velocities and accelerations from the positions: {filt.describe()}")
    if on.any():
        notes.append("efforts smoothed by the same filter")
    wrenches = None
    if log.wrenches is not None:
        wrenches = filters.apply(filt, log.times, log.wrenches.at(log.times, source=log.source))[0]
        notes.append(f"wrenches of {log.wrenches.topic} interpolated (linearly) at the joint samples' times and "
                     "smoothed by the same filter")
    base = None
    if log.base is not None:
        base = filters.apply(filt, log.times, base_coordinates(log.base, log.times, source=log.source))
        notes.append("the base's pose as x, y, z and ZYX angles (unwrapped) at the joint samples' times, "
                     "differentiated by the same filter")
    return Derivatives(times=log.times, names=log.names, positions=out[0], velocities=out[1],
                       accelerations=out[2], efforts=efforts, filter=filt, noise=noise_level(P),
                       edge=min(edge, S // 2), log=log, notes=tuple(notes), wrenches=wrenches, base=base)

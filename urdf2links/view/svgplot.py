"""Small SVG line plots against time for the animation's side panels (:mod:`urdf2links.view.animation`).

Drawn in Python (so the page shows them without scripts) with a vertical cursor line that the
player moves: the ``<svg>`` carries ``data-t0``, ``data-t1`` (the time axis) and ``data-x0``,
``data-x1`` (where those times are, in the ``viewBox``'s units); the cursor is the element of class
``u2l-cursor``. A log-scaled panel plots ``log10`` of the values, values at or below zero drawn at
the bottom of the axis.
"""

from __future__ import annotations

import html
import math
from dataclasses import dataclass, field

import numpy as np

__all__ = ["Panel", "panel_svg", "PALETTE"]

#: Line colours (matplotlib's tab10 order).
PALETTE = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f",
           "#bcbd22", "#17becf")
_W, _H = 420, 230
_L, _R, _T, _B = 58, 10, 26, 34  # margins
_MAX_DECADES = 14  # a log axis spans at most this many decades below its top
_MAX_POINTS = 800  # per line: longer series are reduced to a min/max envelope per bin


@dataclass(frozen=True)
class Panel:
    """A plot beside the viewer: ``series`` label -> values (m,) at times ``t`` (m,), ``log`` for a
    log10 axis, ``unit`` of the values, ``lines`` horizontal reference lines label -> value
    (dashed), ``legend`` False to leave the labels out (many coordinates)."""

    title: str
    t: np.ndarray
    series: dict
    log: bool = False
    unit: str = ""
    lines: dict = field(default_factory=dict)
    legend: bool = True

    def at(self, times) -> dict:
        """Each series at ``times`` (the nearest earlier sample): label -> list of floats."""
        t = np.asarray(self.t, float)
        k = np.clip(np.searchsorted(t, np.asarray(times, float), side="right") - 1, 0, len(t) - 1)
        return {label: [float(v) for v in np.asarray(y, float)[k]] for label, y in self.series.items()}


def _envelope(t: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """At most ~``_MAX_POINTS`` points: the min and the max of each bin, in time order."""
    if len(t) <= _MAX_POINTS:
        return t, y
    bins = np.array_split(np.arange(len(t)), _MAX_POINTS // 2)
    tt, yy = [], []
    for b in bins:
        i, j = b[np.argmin(y[b])], b[np.argmax(y[b])]
        for k in sorted({int(i), int(j)}):
            tt.append(t[k])
            yy.append(y[k])
    return np.array(tt), np.array(yy)


def _nice_ticks(lo: float, hi: float, n: int = 5) -> list[float]:
    if not hi > lo:
        return [lo]
    raw = (hi - lo) / n
    mag = 10.0 ** math.floor(math.log10(raw))
    step = min((m * mag for m in (1, 2, 2.5, 5, 10) if m * mag >= raw), default=10 * mag)
    first = math.ceil(lo / step) * step
    return [first + k * step for k in range(int((hi - first) / step + 1e-9) + 1)]


def _fmt(v: float) -> str:
    return f"{v:.3g}" if v != 0 else "0"


def _y_range(panel: Panel, ys: list[np.ndarray]) -> tuple[float, float]:
    vals = np.concatenate([y[np.isfinite(y)] for y in ys] + [np.array(list(panel.lines.values()), float)])
    if panel.log:
        vals = vals[vals > 0]
        if not vals.size:
            return -16.0, 0.0
        lo, hi = math.floor(math.log10(vals.min())), math.ceil(math.log10(vals.max()))
        lo = max(lo, hi - _MAX_DECADES)  # values at rounding level below this sit on the axis
        return float(lo), float(max(hi, lo + 1))
    if not vals.size:
        return -1.0, 1.0
    lo, hi = float(vals.min()), float(vals.max())
    pad = 0.05 * (hi - lo) if hi > lo else max(abs(hi), 1.0) * 0.1
    return lo - pad, hi + pad


def panel_svg(panel: Panel) -> str:
    """The panel as an inline ``<svg>`` (module doc)."""
    e = html.escape
    t = np.asarray(panel.t, float)
    t0, t1 = float(t[0]), float(t[-1]) if t[-1] > t[0] else float(t[0]) + 1.0
    raw = {k: np.asarray(v, float) for k, v in panel.series.items()}
    lo, hi = _y_range(panel, list(raw.values()))  # log10 units on a log axis
    if panel.log:
        ys = {k: np.log10(np.maximum(v, 10.0 ** lo)) for k, v in raw.items()}
        lines = {k: math.log10(v) for k, v in panel.lines.items() if v > 0}
    else:
        ys, lines = raw, dict(panel.lines)
    x = lambda tv: _L + (tv - t0) / (t1 - t0) * (_W - _L - _R)  # noqa: E731
    y = lambda v: _T + (hi - v) / (hi - lo) * (_H - _T - _B)  # noqa: E731
    out = [f"<svg class='u2l-panel' viewBox='0 0 {_W} {_H}' "
           f"data-t0='{t0!r}' data-t1='{t1!r}' data-x0='{x(t0):.2f}' data-x1='{x(t1):.2f}' role='img' "
           f"aria-label='{e(panel.title)}'>",
           f"<text x='{_L}' y='16' class='u2l-title'>{e(panel.title)}</text>",
           f"<rect x='{_L}' y='{_T}' width='{_W - _L - _R}' height='{_H - _T - _B}' class='u2l-frame'/>"]
    yticks = list(range(int(lo), int(hi) + 1)) if panel.log else _nice_ticks(lo, hi)
    if panel.log and len(yticks) > 7:
        yticks = yticks[::math.ceil(len(yticks) / 6)]
    for v in yticks:
        label = f"1e{v}" if panel.log else _fmt(v)
        out.append(f"<line x1='{_L}' x2='{_W - _R}' y1='{y(v):.1f}' y2='{y(v):.1f}' class='u2l-grid'/>"
                   f"<text x='{_L - 4}' y='{y(v) + 4:.1f}' class='u2l-tick' text-anchor='end'>{label}</text>")
    for v in _nice_ticks(t0, t1):
        out.append(f"<text x='{x(v):.1f}' y='{_H - _B + 14}' class='u2l-tick' text-anchor='middle'>{_fmt(v)}</text>")
    out.append(f"<text x='{(_L + _W - _R) / 2:.0f}' y='{_H - 4}' class='u2l-tick' text-anchor='middle'>t (s)"
               + (f"; values in {e(panel.unit)}" if panel.unit else "") + "</text>")
    for label, v in lines.items():
        out.append(f"<line x1='{_L}' x2='{_W - _R}' y1='{y(v):.1f}' y2='{y(v):.1f}' class='u2l-ref'/>"
                   f"<text x='{_W - _R - 3}' y='{y(v) + 11:.1f}' class='u2l-tick' text-anchor='end'>{e(label)}</text>")
    for k, (label, v) in enumerate(ys.items()):
        tt, vv = _envelope(t, v)
        ok = np.isfinite(vv)
        pts = " ".join(f"{x(a):.1f},{y(b):.1f}" for a, b in zip(tt[ok], vv[ok]))
        color = PALETTE[k % len(PALETTE)]
        out.append(f"<polyline points='{pts}' fill='none' stroke='{color}' stroke-width='1.3'>"
                   f"<title>{e(label)}</title></polyline>")
    if panel.legend and len(ys) > 1:
        for k, label in enumerate(ys):
            out.append(f"<text x='{_L + 6 + 116 * (k % 3)}' y='{_T + 12 + 12 * (k // 3)}' class='u2l-tick' "
                       f"fill='{PALETTE[k % len(PALETTE)]}'>{e(label[:20])}</text>")
    out.append(f"<line class='u2l-cursor' x1='{x(t0):.1f}' x2='{x(t0):.1f}' y1='{_T}' y2='{_H - _B}'/></svg>")
    return "".join(out)

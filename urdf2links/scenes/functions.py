"""Prescribed functions of time for scenes: base motions, loads, set points.

A scene chooses each function from a few fixed forms (never ``eval`` of text). Every form gives
its value and its *exact* first and second derivatives, which a prescribed base motion needs::

    Constant(value)                      value
    Sines(offset, terms, rate)           offset + rate*t + sum a*sin(2*pi*f*t + phase)
    Table(times, values, kind="cubic")   an interpolating spline through sampled data

All three are frozen dataclasses; ``f(t)``, ``f.derivative(t)``, ``f.second_derivative(t)``
take a float (and return a float) or an ndarray of times (and return an array of its shape).

TOML schema read by :func:`parse_function` (one of)::

    heave = 0.5                                          # a number: Constant
    heave = { constant = 0.5 }                           # Constant
    heave = { sines = [[0.5, 0.1, 0.0], [0.1, 0.3]] }    # [amplitude, frequency_hz, phase_rad]
    heave = { sines = [[0.5, 0.1]], offset = 1.0, rate = 0.02 }   # phase, offset, rate optional
    surge = { rate = 0.5 }                               # offset/rate alone: a straight line
    pitch = { times = [0, 1, 2, 3], values = [0, 0.1, 0.05, 0], kind = "cubic" }   # Table

:func:`vector_function` reads a list of ``length`` such specs (e.g. x, y, z of a deck) into a
:class:`VectorFunction`. Bad specs raise :class:`SceneValueError` (a ``ValueError``) naming the
place (``where``), the key and the valid choices.
"""

from __future__ import annotations

import difflib
import math
import numbers
from abc import ABC, abstractmethod
from dataclasses import dataclass, field

import numpy as np

from ..errors import SceneError
from ..ranges import MAX_TABLE_SAMPLES, out_of_range

__all__ = ["SceneValueError", "TimeFunction", "Constant", "Sines", "Table", "VectorFunction",
           "parse_function", "vector_function"]

TABLE_KINDS = ("cubic", "quintic")
#: Smallest spacing of a table's times (s): closer samples make the spline's derivatives overflow.
MIN_TABLE_SPACING = 1e-6
_MIN_SAMPLES = {"cubic": 2, "quintic": 6}


class SceneValueError(SceneError):
    """A scene (TOML) value cannot be turned into what it describes; the message says where."""


def _finite(x, name: str, quantity: str | None = None) -> float:
    """``x`` as a float; ValueError naming ``name`` unless it is a finite real number (not a bool),
    within the physical range of ``quantity`` when given (:data:`urdf2links.ranges.RANGES`)."""
    if isinstance(x, bool) or not isinstance(x, numbers.Real) or not math.isfinite(x):
        raise ValueError(f"{name} must be a finite number, got {x!r}")
    problem = out_of_range(float(x), quantity) if quantity else None
    if problem:
        raise ValueError(f"{name}: {problem}")
    return float(x)


class TimeFunction(ABC):
    """A scalar function of time f(t) with exact first and second derivatives."""

    @abstractmethod
    def _evaluate(self, t: np.ndarray, order: int) -> np.ndarray:
        """d^order f / dt^order at the times ``t`` (an ndarray, any shape), same shape."""

    @abstractmethod
    def describe(self) -> str:
        """A one-line human-readable formula."""

    def _at(self, t, order: int):
        ta = np.asarray(t, dtype=float)
        out = np.broadcast_to(self._evaluate(ta, order), ta.shape).astype(float)
        return float(out) if out.ndim == 0 else out

    def __call__(self, t):
        """f(t): a float for a float ``t``, an array of ``t``'s shape for an array."""
        return self._at(t, 0)

    def derivative(self, t):
        """df/dt at ``t`` (exact)."""
        return self._at(t, 1)

    def second_derivative(self, t):
        """d2f/dt2 at ``t`` (exact)."""
        return self._at(t, 2)


@dataclass(frozen=True)
class Constant(TimeFunction):
    """f(t) = value."""

    value: float

    def __post_init__(self):
        object.__setattr__(self, "value", _finite(self.value, "value", "value"))

    def _evaluate(self, t, order):
        return np.full(t.shape, self.value if order == 0 else 0.0)

    def describe(self) -> str:
        return f"constant {self.value:g}"


@dataclass(frozen=True)
class Sines(TimeFunction):
    """f(t) = offset + rate*t + sum_k a_k sin(2 pi f_k t + phase_k).

    ``terms`` holds ``(amplitude, frequency_hz, phase_rad)`` triples (phase may be left out);
    frequencies are >= 0. The derivatives are the analytic ones."""

    offset: float = 0.0
    terms: tuple = ()
    rate: float = 0.0

    def __post_init__(self):
        object.__setattr__(self, "offset", _finite(self.offset, "offset", "value"))
        object.__setattr__(self, "rate", _finite(self.rate, "rate", "value"))
        if isinstance(self.terms, (str, bytes)) or not hasattr(self.terms, "__iter__"):
            raise ValueError(f"terms must be a list of [amplitude, frequency_hz, phase_rad], got {self.terms!r}")
        terms = []
        for k, term in enumerate(self.terms):
            if isinstance(term, (str, bytes)) or not hasattr(term, "__len__") or len(term) not in (2, 3):
                raise ValueError(f"terms[{k}] must be [amplitude, frequency_hz] or "
                                 f"[amplitude, frequency_hz, phase_rad], got {term!r}")
            a = _finite(term[0], f"terms[{k}] amplitude", "value")
            f = _finite(term[1], f"terms[{k}] frequency_hz", "frequency")
            p = _finite(term[2], f"terms[{k}] phase_rad", "value") if len(term) == 3 else 0.0
            if f < 0:
                raise ValueError(f"terms[{k}] frequency_hz must be >= 0, got {f!r}")
            terms.append((a, f, p))
        object.__setattr__(self, "terms", tuple(terms))

    def _evaluate(self, t, order):
        if order == 0:
            out = self.offset + self.rate * t
        else:
            out = np.full(t.shape, self.rate if order == 1 else 0.0)
        for a, f, p in self.terms:
            w = 2.0 * math.pi * f
            # d^n/dt^n sin(w t + p) = w^n sin(w t + p + n pi/2)
            out = out + a * w**order * np.sin(w * t + p + order * math.pi / 2)
        return out

    def describe(self) -> str:
        parts = [f"{self.offset:g}"] if self.offset or not (self.rate or self.terms) else []
        if self.rate:
            parts.append(f"{self.rate:g}*t")
        parts += [f"{a:g}*sin(2*pi*{f:g}*t + {p:g})" for a, f, p in self.terms]
        return " + ".join(parts)


@dataclass(frozen=True)
class Table(TimeFunction):
    """A sampled table ``values`` at ``times`` (s), interpolated by a smooth spline.

    ``kind="cubic"``: :class:`scipy.interpolate.CubicSpline` (not-a-knot ends), C2 - continuous
    value, first and second derivative - at least 2 samples. ``kind="quintic"``: a degree-5
    interpolating B-spline (:func:`scipy.interpolate.make_interp_spline`, k=5), C4, at least 6
    samples. Both pass exactly through the samples.

    Outside ``[times[0], times[-1]]`` the function *holds* the end value with zero derivatives
    (so the derivatives jump at the ends unless the data starts and ends at rest)."""

    times: tuple
    values: tuple
    kind: str = field(default="cubic", kw_only=True)
    _spline: object = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        if self.kind not in TABLE_KINDS:
            raise ValueError(f"kind must be one of {TABLE_KINDS}, got {self.kind!r}")
        seqs = {}
        for name in ("times", "values"):
            seq = getattr(self, name)
            if isinstance(seq, (str, bytes)) or not hasattr(seq, "__len__"):
                raise ValueError(f"{name} must be a list of numbers, got {seq!r}")
            if len(seq) > MAX_TABLE_SAMPLES:
                raise ValueError(f"{name}: {len(seq)} samples, more than the {MAX_TABLE_SAMPLES} a table may hold")
            seqs[name] = tuple(_finite(x, f"{name}[{i}]", "time" if name == "times" else "value")
                               for i, x in enumerate(seq))
        t, v = seqs["times"], seqs["values"]
        if len(t) != len(v):
            raise ValueError(f"times and values must have the same length, got {len(t)} times and {len(v)} values")
        need = _MIN_SAMPLES[self.kind]
        if len(t) < need:
            raise ValueError(f"times: a {self.kind} table needs at least {need} samples, got {len(t)}: {list(t)!r}")
        for i in range(1, len(t)):
            if not t[i] > t[i - 1]:
                raise ValueError(f"times must be strictly increasing, got times[{i - 1}]={t[i - 1]!r} "
                                 f"then times[{i}]={t[i]!r}")
            if t[i] - t[i - 1] < MIN_TABLE_SPACING:
                raise ValueError(f"times[{i - 1}]={t[i - 1]!r} and times[{i}]={t[i]!r} are closer than "
                                 f"{MIN_TABLE_SPACING:g} s: the spline's derivatives would overflow")
        object.__setattr__(self, "times", t)
        object.__setattr__(self, "values", v)
        ta, va = np.array(t), np.array(v)
        from scipy.interpolate import CubicSpline, make_interp_spline    # here: scipy costs an import of 0.3-0.7 s

        spline = CubicSpline(ta, va) if self.kind == "cubic" else make_interp_spline(ta, va, k=5)
        object.__setattr__(self, "_spline", spline)

    def _evaluate(self, t, order):
        t0, t1 = self.times[0], self.times[-1]
        out = np.asarray(self._spline(np.clip(t, t0, t1), order), dtype=float)
        if order > 0:
            out = np.where((t < t0) | (t > t1), 0.0, out)
        return out

    def describe(self) -> str:
        return (f"{self.kind} spline through {len(self.times)} samples on "
                f"[{self.times[0]:g}, {self.times[-1]:g}] s, held at the end values "
                f"with zero derivatives outside")


@dataclass(frozen=True)
class VectorFunction:
    """Several :class:`TimeFunction` components; results have shape (n,) for a float ``t`` and
    (n, *t.shape) for an array ``t``."""

    components: tuple

    def __post_init__(self):
        comps = tuple(self.components)
        for i, c in enumerate(comps):
            if not isinstance(c, TimeFunction):
                raise ValueError(f"components[{i}] must be a TimeFunction, got {c!r}")
        object.__setattr__(self, "components", comps)

    def __len__(self) -> int:
        return len(self.components)

    def _stack(self, t, order):
        return np.stack([np.asarray(c._at(t, order), dtype=float) for c in self.components])

    def __call__(self, t) -> np.ndarray:
        return self._stack(t, 0)

    def derivative(self, t) -> np.ndarray:
        return self._stack(t, 1)

    def second_derivative(self, t) -> np.ndarray:
        return self._stack(t, 2)

    def describe(self) -> str:
        return "[" + "; ".join(c.describe() for c in self.components) + "]"


_FORMS = {  # form key -> keys allowed with it
    "constant": ("constant",),
    "sines": ("sines", "offset", "rate"),
    "times": ("times", "values", "kind"),
}
_ALL_KEYS = tuple(k for keys in _FORMS.values() for k in keys)
_CHOICES = "a number, {constant = ...}, {sines = [[a, f_hz, phase], ...], offset = ..., rate = ...} " \
           "or {times = [...], values = [...], kind = \"cubic\"|\"quintic\"}"


def _did_you_mean(key: str) -> str:
    close = difflib.get_close_matches(str(key), _ALL_KEYS, n=1, cutoff=0.6)
    return f" (did you mean {close[0]!r}?)" if close else ""


def parse_function(spec, *, where: str) -> TimeFunction:
    """A :class:`TimeFunction` from a TOML value ``spec`` (schema in the module docstring).

    ``where`` names the place for messages, e.g. ``"scene.toml: [base] heave"``. Raises
    :class:`SceneValueError` naming ``where``, the bad key or value and the valid choices."""
    if isinstance(spec, numbers.Real) and not isinstance(spec, bool):
        try:
            return Constant(spec)
        except ValueError as e:
            raise SceneValueError(f"{where}: {e}") from e
    if not isinstance(spec, dict):
        raise SceneValueError(f"{where}: expected {_CHOICES}; got {spec!r}")
    for key in spec:
        if key not in _ALL_KEYS:
            raise SceneValueError(f"{where}: unknown key {key!r}{_did_you_mean(key)}; "
                                  f"valid keys are {', '.join(repr(k) for k in _ALL_KEYS)}")
    forms = [f for f, keys in _FORMS.items() if any(k in spec for k in keys)]
    if len(forms) != 1:
        what = "no" if not forms else "more than one"
        raise SceneValueError(f"{where}: {what} function form in keys {sorted(spec)}; expected {_CHOICES}")
    form = forms[0]
    try:
        if form == "constant":
            return Constant(spec["constant"])
        if form == "sines":
            try:
                return Sines(offset=spec.get("offset", 0.0), terms=spec.get("sines", ()), rate=spec.get("rate", 0.0))
            except ValueError as e:  # the TOML key of Sines.terms is 'sines'
                raise ValueError(str(e).replace("terms", "sines", 1)) from e
        missing = [k for k in ("times", "values") if k not in spec]
        if missing:
            raise ValueError(f"a table needs both 'times' and 'values'; missing {missing[0]!r}")
        return Table(spec["times"], spec["values"], kind=spec.get("kind", "cubic"))
    except ValueError as e:
        raise SceneValueError(f"{where}: {e}") from e


def vector_function(spec, *, where: str, length: int = 3) -> VectorFunction:
    """A :class:`VectorFunction` from a TOML list of ``length`` function specs (each as for
    :func:`parse_function`); component ``i`` is reported as ``f"{where}[{i}]"``."""
    if isinstance(spec, (str, bytes, dict)) or not isinstance(spec, (list, tuple)) or len(spec) != length:
        raise SceneValueError(f"{where}: expected a list of {length} functions of time "
                              f"(each {_CHOICES}); got {spec!r}")
    return VectorFunction(tuple(parse_function(s, where=f"{where}[{i}]") for i, s in enumerate(spec)))

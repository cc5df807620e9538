"""A scene's values checked where they are read: :class:`SceneReader` (a table's keys, a number within its
physical range (:data:`urdf2links.ranges.RANGES`), a choice, a function of time; every SceneError names the file, the
key, the value and what would fix it) and :func:`check_run` (a run's settings: length, tolerances, step, samples,
method)."""

from __future__ import annotations

import math

import numpy as np

from ..errors import SceneError
from ..ranges import MAX_SAMPLES, MAX_STEPS, METHODS, MIN_ATOL, MIN_T_END, RANGES, RTOL_FLOOR
from .functions import SceneValueError, TimeFunction, VectorFunction, parse_function, vector_function
from .scene import RunSettings, did_you_mean

__all__ = ["SceneReader", "check_run"]


class SceneReader:
    """Reads the values of one scene (``where`` names it in every error), checking each as it is read."""

    def __init__(self, where: str):
        self.where = where

    def fail(self, key: str, problem: str):
        raise SceneError(f"{self.where}: {key}: {problem}")

    def keys(self, table, allowed, key):
        if not isinstance(table, dict):
            self.fail(key, f"must be a table, got {type(table).__name__} {table!r}")
        for k in table:
            if k not in allowed:
                self.fail(f"{key}.{k}" if key else k, f"unknown key{did_you_mean(k, allowed)}; valid keys are {list(allowed)}")

    def number(self, value, key, *, positive=False, nonnegative=False, quantity: str | None = None,
               low: float | None = None, high: float | None = None):
        """A finite number (not a bool), checked where it is read: ``positive``/``nonnegative``, within
        the physical range of ``quantity`` (:data:`urdf2links.ranges.RANGES`) and within ``[low, high]``;
        the SceneError names the key, the value and the valid range."""
        bound = RANGES[quantity][0] if quantity else math.inf
        lo = 0.0 if (positive or nonnegative) else -bound
        lo = lo if low is None else max(lo, low)
        hi = bound if high is None else min(bound, high)
        unit = f" {RANGES[quantity][1]}" if quantity and RANGES[quantity][1] else ""
        valid = (f"{'(' if positive and low is None else '['}{lo:g}, {hi:g}]{unit}")
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            self.fail(key, f"must be a finite number in {valid}, got {value!r}")
        if lo == 0 and (value < 0 or (positive and value == 0)):
            self.fail(key, f"must {'be positive' if positive else 'not be negative'}, got {value!r}: valid range {valid}")
        if value < lo or value > hi:
            self.fail(key, f"{value!r} is outside the valid range {valid}")
        return float(value)

    def vector(self, value, key, *, quantity: str | None = None):
        if not isinstance(value, list) or len(value) != 3:
            self.fail(key, f"must be a list of 3 numbers, got {value!r}")
        return np.array([self.number(v, f"{key}[{i}]", quantity=quantity) for i, v in enumerate(value)])

    def items(self, data, kind: str) -> list:
        """The ``[[kind]]`` blocks of ``data`` (an array of tables)."""
        items = data.get(kind, [])
        if not isinstance(items, list):
            self.fail(f"[[{kind}]]", f"must be an array of tables ([[{kind}]] blocks), got {items!r}")
        return items

    def strings(self, value, key) -> tuple:
        if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
            self.fail(key, f"must be a list of strings, got {value!r}")
        return tuple(value)

    def choice(self, value, key, choices):
        if value not in choices:
            self.fail(key, f"{value!r} is not one of {list(choices)}{did_you_mean(value, choices)}")
        return value

    def function(self, spec, key) -> TimeFunction:
        try:
            return parse_function(spec, where=f"{self.where}: {key}")
        except SceneValueError as err:
            raise SceneError(str(err)) from None

    def vector_function(self, spec, key) -> VectorFunction:
        try:
            return vector_function(spec, where=f"{self.where}: {key}", length=3)
        except SceneValueError as err:
            raise SceneError(str(err)) from None


def check_run(run: RunSettings, where: str, *, prefix: str = "run.") -> RunSettings:
    """``run`` with every setting checked where it is given (a scene's ``[run]``, or the overrides of
    :func:`urdf2links.integration.simulate.simulate`): a SceneError names ``where``, the key, the value and its
    valid range. ``t_end`` in [1e-9, 1e6] s (:data:`~urdf2links.ranges.MIN_T_END`); ``rtol`` in [100 eps, 1) (float64 delivers no more);
    ``atol`` in [1e-30, 1e3] (:data:`~urdf2links.ranges.MIN_ATOL`); ``dt`` in (0, 1e6] s with at most :data:`~urdf2links.ranges.MAX_STEPS`
    steps; ``samples`` in [1, :data:`~urdf2links.ranges.MAX_SAMPLES`]."""
    r = SceneReader(where)
    t_end = r.number(run.t_end, f"{prefix}t_end", positive=True, quantity="time", low=MIN_T_END)
    rtol = r.number(run.rtol, f"{prefix}rtol", low=RTOL_FLOOR, high=0.999)
    atol = r.number(run.atol, f"{prefix}atol", positive=True, low=MIN_ATOL, high=1e3)
    dt = None
    if run.dt is not None:
        dt = r.number(run.dt, f"{prefix}dt", positive=True, quantity="time")
        if t_end / dt > MAX_STEPS:
            r.fail(f"{prefix}dt", f"{run.dt!r} makes {t_end / dt:.3g} steps over t_end = {t_end:g} s, more than the "
                                  f"{MAX_STEPS:g} a run may take: valid range [{t_end / MAX_STEPS:g}, 1e+06] s")
    samples = run.samples
    if isinstance(samples, bool) or not isinstance(samples, (int, np.integer)) or not 1 <= samples <= MAX_SAMPLES:
        r.fail(f"{prefix}samples", f"must be a whole number in [1, {MAX_SAMPLES}], got {samples!r}")
    if not isinstance(run.recharting, bool):
        r.fail(f"{prefix}recharting", f"must be true or false, got {run.recharting!r}")
    method = r.choice(run.method, f"{prefix}method", METHODS)
    if method in ("RK4", "midpoint") and dt is None:
        r.fail(f"{prefix}dt", f"method {method!r} takes a fixed step: give dt (seconds)")
    return RunSettings(t_end=t_end, method=method, rtol=rtol, atol=atol, dt=dt, samples=int(samples),
                       recharting=run.recharting)

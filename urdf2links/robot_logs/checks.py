"""A log checked before it is used: bad data is an error that names the column (or topic) and the row
(or time stamp), and what is repaired (an angle wrapped at +-pi) is said in the notes. Nothing is guessed.

- :func:`check_times`: finite, strictly increasing time stamps (unsorted and duplicate are errors).
- :func:`check_log`: the joints' names against the description's (did you mean), NaN and infinite values
  (and a floating base's unit quaternions),
  wrapped angles (unwrapped, noted) and real jumps (an error), values that look like degrees, and with
  ``n_base`` the number of samples (:func:`check_samples`). It returns the log in the description's joint
  order.
"""

from __future__ import annotations

import difflib
from collections.abc import Mapping, Sequence

import numpy as np
from scipy.ndimage import median_filter

from .errors import (DegreesError, JumpError, LogError, NonFiniteError, TimeOrderError, TooFewSamplesError,
                     UnknownJointError)
from .log import QUANTITIES, RobotLog

__all__ = ["angular_limits", "check_times", "check_log", "check_names", "check_finite", "check_jumps", "check_units",
           "check_samples", "JUMP_SIGMAS", "JUMP_FRACTION", "WRAP_TOLERANCE"]

#: A step is a jump when it departs from its neighbours' median step by more than JUMP_SIGMAS robust
#: standard deviations of that departure (MAD * 1.4826) and by more than JUMP_FRACTION of the column's range.
#: 30 sigma: Gaussian noise reaches it with probability ~1e-197 a sample; the range floor keeps a noiseless
#: simulated log (MAD near 0) from calling its own accelerations jumps.
JUMP_SIGMAS = 30.0
JUMP_FRACTION = 0.02
#: A step is an angle wrapped at +-pi when it is within this of +-2 pi and both samples lie within it of +-pi.
WRAP_TOLERANCE = 0.25
DEG = 180.0 / np.pi


def angular_limits(model) -> dict[str, tuple[float, float]]:
    """The ``limits`` argument of :func:`check_log` from a loaded model (its ``info["joints"]``): each
    revolute (or MJCF hinge) joint with one coordinate and finite limits ``lower < upper``, by coordinate
    name. (A URDF joint's coordinate is its joint position: same zero, same sign, docs/equations.md (E9).)"""
    out = {}
    for j in model.info.get("joints", []):
        lo, hi = j.get("lower"), j.get("upper")
        if (j.get("type") in ("revolute", "hinge") and len(j.get("coordinates", ())) == 1 and lo is not None
                and hi is not None and np.isfinite(lo) and np.isfinite(hi) and lo < hi):
            out[j["coordinates"][0]] = (float(lo), float(hi))
    return out


def check_times(log: RobotLog) -> None:
    """Finite and strictly increasing times; the first offending sample named (row and time)."""
    t = log.times
    bad = np.flatnonzero(~np.isfinite(t))
    if bad.size:
        k = bad[0]
        raise NonFiniteError(f"{log.source}: time column, {log.row_word} {log.rows[k]}: {t[k]} is not a finite "
                             "time", column="t", source=log.source, row=int(log.rows[k]), topic=log.topic)
    d = np.diff(t)
    for kind, mask, what in (("unsorted", d < 0, "goes back from"), ("duplicate", d == 0, "repeats")):
        idx = np.flatnonzero(mask)
        if idx.size:
            k = idx[0] + 1
            raise TimeOrderError(
                f"{log.source}: time column, {log.at(k)} {what} {log.at(k - 1)} ({idx.size} such "
                f"step{'s' if idx.size > 1 else ''}); the log must be sorted by time with one sample per time "
                "stamp: sort it, and drop or average repeated stamps", kind=kind, column="t", **log.where(k))


def check_names(log: RobotLog, joints: Sequence[str]) -> RobotLog:
    """The log's joints in the description's order (``joints``: the description's joint names); a name
    that matches none is an :class:`UnknownJointError` with the closest names. Joints of the description
    that the log lacks are noted."""
    known = list(joints)
    unknown = [j for j in log.names if j not in known]
    if unknown:
        sugg = {u: tuple(difflib.get_close_matches(u, known, n=3, cutoff=0.5)) for u in unknown}
        said = "; ".join(f"{u!r}" + (f" (did you mean {' or '.join(map(repr, s))}?)" if s else "")
                         for u, s in sugg.items())
        cols = [log.column("position", log.names.index(u)) for u in unknown]
        raise UnknownJointError(f"{log.source}: joint names that match nothing in the description: {said}; "
                                f"the description's joints are {known}. Rename the columns (or the topic's "
                                "names) to the description's", unknown=tuple(unknown), suggestions=sugg,
                                source=log.source, column=cols[0], topic=log.topic)
    order = [log.names.index(j) for j in known if j in log.names]
    missing = [j for j in known if j not in log.names]
    note = None if not missing else f"joints of the description not in the log: {', '.join(missing)}"
    if order == list(range(len(order))) and note is None:
        return log
    note = "; ".join(x for x in (note, None if order == sorted(order) else "joints put in the description's order")
                     if x)
    return log.with_changes(note, names=tuple(log.names[i] for i in order), positions=log.positions[:, order],
                            velocities=log.velocities[:, order], efforts=log.efforts[:, order])


def check_finite(log: RobotLog) -> None:
    """No NaN inside a logged column (a column entirely NaN is absent, not bad) and no infinite value."""
    for q in QUANTITIES:
        a = log.values(q)
        for j in range(a.shape[1]):
            col = a[:, j]
            nan = np.isnan(col)
            if nan.all():
                continue
            bad = np.flatnonzero(nan | np.isinf(col))
            if bad.size:
                k = bad[0]
                raise NonFiniteError(
                    f"{log.source}: column {log.column(q, j)!r}, {log.at(k)}: {col[k]} ({bad.size} non-finite "
                    f"value{'s' if bad.size > 1 else ''} in the column); drop those samples with a segment "
                    "(--from/--to) or fill them in the file", column=log.column(q, j), **log.where(k))


def _unwrap(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(q with steps at +-pi unwrapped, indices of those steps)."""
    d = np.diff(q)
    near = np.abs(np.abs(q) - np.pi) < WRAP_TOLERANCE
    wrap = (np.abs(np.abs(d) - 2 * np.pi) < WRAP_TOLERANCE) & near[:-1] & near[1:]
    if not wrap.any():
        return q, np.empty(0, dtype=int)
    turns = np.where(wrap, np.round(d / (2 * np.pi)), 0.0)
    return q - 2 * np.pi * np.concatenate([[0.0], np.cumsum(turns)]), np.flatnonzero(wrap)


def check_jumps(log: RobotLog) -> RobotLog:
    """Angles wrapped at +-pi unwrapped (noted); any other step that departs from the steps around it by
    more than the threshold (:data:`JUMP_SIGMAS`, :data:`JUMP_FRACTION`) is a :class:`JumpError`."""
    P = log.positions.copy()
    notes = []
    for j, on in enumerate(log.logged("position")):
        if not on or len(P) < 8:
            continue
        P[:, j], wraps = _unwrap(P[:, j])
        if wraps.size:
            notes.append(f"{log.column('position', j)}: {wraps.size} step(s) of 2 pi unwrapped (an angle wrapped "
                         f"at +-pi), the first after {log.at(wraps[0])}")
        d = np.diff(P[:, j])
        typical = median_filter(d, size=7, mode="nearest")
        r = d - typical
        sigma = 1.4826 * np.median(np.abs(r - np.median(r)))
        span = np.ptp(P[:, j])
        tau = max(JUMP_SIGMAS * sigma, JUMP_FRACTION * span, 1e-12)
        bad = np.flatnonzero(np.abs(r) > tau)
        if bad.size:
            k = bad[0] + 1
            raise JumpError(
                f"{log.source}: column {log.column('position', j)!r} jumps by {d[k - 1]:.6g} from {log.at(k - 1)} "
                f"to {log.at(k)}, against a typical step of {typical[k - 1]:.3g} (threshold {tau:.3g}); not "
                "an angle wrapped at +-pi. Cut the log around it (--from/--to) or repair the encoder's data",
                step=float(d[k - 1]), column=log.column("position", j), **log.where(k))
    return log.with_changes("; ".join(notes), positions=P) if notes else log


def _degrees_by_limits(log: RobotLog, j: int, lo: float, hi: float) -> None:
    q = log.positions[:, j]
    margin = 0.1 * (hi - lo) + 0.05
    k = int(np.argmax(np.maximum(q - hi, lo - q)))
    outside = q[k] > hi + margin or q[k] < lo - margin
    if outside and np.all(q / DEG >= lo - margin) and np.all(q / DEG <= hi + margin):
        raise DegreesError(
            f"{log.source}: column {log.column('position', j)!r} reaches {q[k]:.6g} at {log.at(k)}, outside the "
            f"joint's limits [{lo:.4g}, {hi:.4g}] rad, while every value divided by 180/pi lies within them: "
            "the column looks like degrees; convert it to radians", factor=DEG,
            column=log.column("position", j), **log.where(k))


def _degrees_by_rates(log: RobotLog, j: int) -> None:
    """The logged velocity against the position's derivative: a ratio near 180/pi (or pi/180) is degrees."""
    q, v = np.ascontiguousarray(log.positions[:, j]), np.ascontiguousarray(log.velocities[:, j])
    g = np.gradient(q, log.times)
    vg, gg, vv = float(np.sum(v * g)), float(np.sum(g * g)), float(np.sum(v * v))
    if gg == 0.0 or vv == 0.0:
        return
    c = vg / gg
    corr = vg / np.sqrt(vv * gg)
    if corr < 0.9:
        return
    for ratio, q_, unit in ((DEG, "velocity", "degrees per second"), (1 / DEG, "position", "degrees")):
        if abs(c / ratio - 1.0) < 0.2:
            raise DegreesError(
                f"{log.source}: column {log.column(q_, j)!r} looks like {unit}: the logged velocity is {c:.4g} "
                f"times the derivative of the logged position (180/pi = {DEG:.4g}); convert it to radians",
                factor=float(c if ratio > 1 else 1 / c), column=log.column(q_, j), source=log.source,
                topic=log.topic)


def check_units(log: RobotLog, limits: Mapping[str, tuple[float, float]] | None = None) -> None:
    """Degrees where radians are meant: positions beyond a revolute joint's ``limits`` (name -> (lower,
    upper) rad) that fit within them once divided by 180/pi, and velocities 180/pi times (or positions
    180/pi times less than) the position's derivative."""
    for j, name in enumerate(log.names):
        lim = (limits or {}).get(name)
        if log.logged("position")[j] and lim is not None and np.all(np.isfinite(lim)):
            _degrees_by_limits(log, j, float(lim[0]), float(lim[1]))
        if log.logged("position")[j] and log.logged("velocity")[j] and log.n_samples > 2:
            _degrees_by_rates(log, j)


def check_samples(log: RobotLog, *, n_base: int, equations_per_sample: int | None = None) -> None:
    """Enough equations for ``n_base`` base parameters and a noise estimate: ``S * m >= n_base + 1``, where
    ``m`` is ``equations_per_sample`` (default: the joints whose effort is logged; a floating base's
    unactuated rows are 6)."""
    m = sum(log.logged("effort")) if equations_per_sample is None else int(equations_per_sample)
    eq, need = log.n_samples * m, int(n_base) + 1
    if eq < need:
        raise TooFewSamplesError(
            f"{log.source}: {log.n_samples} samples x {m} equations each = {eq} equations, fewer than the "
            f"{need} that {n_base} base parameters and a noise estimate need; log a longer segment (many times "
            "more samples than that is what gives usable standard deviations)", equations=eq, needed=need,
            source=log.source, topic=log.topic)


def check_log(log: RobotLog, *, joints: Sequence[str], limits: Mapping[str, tuple[float, float]] | None = None,
              n_base: int | None = None, equations_per_sample: int | None = None) -> RobotLog:
    """Every check of the module doc, in order: names, finite values, wraps and jumps, units, samples.
    Returns the log in the description's joint order, angles unwrapped, each change in its notes."""
    check_times(log)
    log = check_names(log, joints)
    if not any(log.logged("position")):
        raise LogError(f"{log.source}: no joint position is logged; identification needs them",
                       source=log.source, topic=log.topic)
    check_finite(log)
    if log.base is not None:
        log.base.check(log.source)
    log = check_jumps(log)
    check_units(log, limits)
    if n_base is not None:
        check_samples(log, n_base=n_base, equations_per_sample=equations_per_sample)
    return log

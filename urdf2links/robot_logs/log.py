"""A robot's log as read: the samples' times, the joints' positions, velocities and efforts, where they
came from, and the notes of everything done to them.

Shapes: ``S`` samples, ``n`` joints, ``W`` wrench samples. Batch axis (samples) first.
A quantity that is not in the file is all NaN; a NaN inside a logged column is an error
(:func:`urdf2links.robot_logs.checks.check_log`), never an absent value.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from .errors import LogFormatError, TimeOrderError

__all__ = ["QUANTITIES", "RobotLog", "Wrenches", "segment", "require_increasing"]

#: The per-joint quantities of a ROS ``sensor_msgs/msg/JointState``, in its field order.
QUANTITIES = ("position", "velocity", "effort")
_FIELD = {"position": "positions", "velocity": "velocities", "effort": "efforts"}


def require_increasing(times: np.ndarray, *, what: str, source: str, topic: str | None = None) -> None:
    """A side topic's (wrenches', base poses') times strictly increasing, else a TimeOrderError naming
    the message (interpolation on unsorted times would be silently wrong)."""
    d = np.diff(times)
    for kind, mask in (("unsorted", d < 0), ("duplicate", d == 0)):
        idx = np.flatnonzero(mask)
        if idx.size:
            k = int(idx[0]) + 1
            raise TimeOrderError(f"{source}: {what}: message {k + 1} (t = {times[k]:.9g} s) is {kind} after message "
                                 f"{k} (t = {times[k - 1]:.9g} s); its stamps must increase", kind=kind,
                                 source=source, topic=topic, row=k + 1, time=float(times[k]))


@dataclass(frozen=True)
class Wrenches:
    """Contact forces from a ``geometry_msgs/msg/WrenchStamped`` topic.

    ``times`` (W,) in the log's seconds (same origin as :attr:`RobotLog.times`); ``values`` (W, 6):
    force x, y, z (N), then torque x, y, z (N m), in the axes of ``frame`` (the messages' frame_id)."""

    topic: str
    frame: str
    times: np.ndarray
    values: np.ndarray

    def at(self, times: np.ndarray, *, source: str = "") -> np.ndarray:
        """(S, 6) the wrenches linearly interpolated at ``times`` (S,); a time outside the topic's own
        range is an error naming it (nothing is extrapolated)."""
        t = np.asarray(times, dtype=float)
        require_increasing(self.times, what=f"the wrench topic {self.topic}", source=source, topic=self.topic)
        outside = np.flatnonzero((t < self.times[0]) | (t > self.times[-1])) if len(self.times) else np.arange(len(t))
        if outside.size:
            k = int(outside[0])
            raise LogFormatError(
                f"{source}: the wrench topic {self.topic} runs from {self.times[0] if len(self.times) else 'nothing'} "
                f"to {self.times[-1] if len(self.times) else ''} s; sample {k + 1} at t = {t[k]:.9g} s lies outside "
                "it: choose a segment (--from/--to) that both topics cover", source=source, topic=self.topic,
                time=float(t[k]))
        return np.column_stack([np.interp(t, self.times, self.values[:, i]) for i in range(6)])


@dataclass(frozen=True)
class RobotLog:
    """The samples of a log (module doc for shapes).

    ``times`` (S,) seconds; ``names`` (n,) joint names in the log's order; ``positions``,
    ``velocities``, ``efforts`` (S, n), NaN where the file has no such column.
    ``source``: the file (and topic). ``notes``: everything done to the data, in order.
    ``rows`` (S,): each sample's row in the file (a CSV data row counted from 1, a bag message's index on
    its topic counted from 1), kept through segments so that errors name the file's own row.
    ``columns``: ``(quantity, joint) -> the column's name in the file`` (the CSV header as written,
    ``"<topic> position[<joint>]"`` for a bag). ``row_word``: "row" (tables) or "message" (bags).
    ``t0_ns``: a bag's first stamp (ns since the epoch); its ``times`` count from it. ``topic``: a bag's
    JointState topic. ``wrenches``: the contact-force topic, when one was read. ``base``: a floating
    base's poses (:class:`~urdf2links.robot_logs.base.BasePoses`), when the log has them."""

    times: np.ndarray
    names: tuple[str, ...]
    positions: np.ndarray
    velocities: np.ndarray
    efforts: np.ndarray
    source: str
    notes: tuple[str, ...] = ()
    rows: np.ndarray | None = None
    columns: dict = field(default_factory=dict)
    row_word: str = "row"
    t0_ns: int | None = None
    topic: str | None = None
    wrenches: Wrenches | None = None
    base: object = None         # BasePoses (urdf2links.robot_logs.base), when the log has the base's pose

    def __post_init__(self):
        S, n = len(self.times), len(self.names)
        for q in QUANTITIES:
            a = getattr(self, _FIELD[q])
            if a.shape != (S, n):
                raise ValueError(f"{self.source}: {q}s must have shape ({S}, {n}); got {a.shape}")
        if self.rows is None:
            object.__setattr__(self, "rows", np.arange(1, S + 1))

    @property
    def n_samples(self) -> int:
        return len(self.times)

    def describe(self) -> str:
        """What was read, in lines, as the identify command prints it: source, samples, duration and rate,
        the joints and the quantities logged, the side topics, then every note."""
        S = self.n_samples
        span = float(self.times[-1] - self.times[0]) if S else 0.0
        rate = (S - 1) / span if span > 0 else float("nan")
        logged = {q: sum(self.logged(q)) for q in QUANTITIES}
        lines = [f"log: {self.source}: {S} samples over {span:.6g} s ({rate:.6g} Hz), {len(self.names)} joints "
                 f"({', '.join(f'{v} with {q}' for q, v in logged.items())})"]
        if self.wrenches is not None:
            lines.append(f"  wrenches: {self.wrenches.topic}, {len(self.wrenches.times)} messages, frame "
                         f"{self.wrenches.frame!r}")
        if self.base is not None:
            lines.append(f"  base pose: {self.base.source}, {len(self.base.times)} poses")
        return "\n".join(lines + [f"  note: {n}" for n in self.notes])

    def values(self, quantity: str) -> np.ndarray:
        """(S, n) array of ``quantity`` (one of :data:`QUANTITIES`)."""
        return getattr(self, _FIELD[quantity])

    def logged(self, quantity: str) -> tuple[bool, ...]:
        """Per joint: whether the file has this quantity (a column not entirely NaN)."""
        return tuple(bool(x) for x in ~np.all(np.isnan(self.values(quantity)), axis=0))

    def column(self, quantity: str, j: int) -> str:
        """The file's own name of joint ``j``'s ``quantity`` column."""
        return self.columns.get((quantity, self.names[j]), f"{self.names[j]}.{quantity}")

    def where(self, k: int) -> dict:
        """Sample ``k`` as error attributes: ``source``, ``row``, ``time``, ``topic``."""
        return dict(source=self.source, row=int(self.rows[k]), time=float(self.times[k]), topic=self.topic)

    def at(self, k: int) -> str:
        """Sample ``k`` in words: ``row 12 (t = 0.011 s)`` or ``message 12 (t = 0.011 s after the first stamp)``."""
        if self.t0_ns is None:
            return f"{self.row_word} {int(self.rows[k])} (t = {self.times[k]:.9g} s)"
        stamp = self.t0_ns + int(round(self.times[k] * 1e9))
        return (f"{self.row_word} {int(self.rows[k])} (t = {self.times[k]:.9g} s after the first stamp, "
                f"stamp {stamp // 10**9}.{stamp % 10**9:09d})")

    def with_changes(self, note: str | None = None, **changes) -> RobotLog:
        """A copy with ``changes`` applied and ``note`` appended to the notes."""
        notes = self.notes + ((note,) if note else ())
        return replace(self, notes=notes, **changes)

    def take(self, keep: np.ndarray, note: str | None = None) -> RobotLog:
        """The samples selected by the boolean mask or index array ``keep`` (S,)."""
        w, b, t = self.wrenches, self.base, self.times[keep]
        if w is not None and len(t):
            inside = (w.times >= t[0]) & (w.times <= t[-1])
            w = replace(w, times=w.times[inside], values=w.values[inside])
        if b is not None and len(t) and b.source == "columns":      # a table's poses are the samples' own
            b = replace(b, times=b.times[keep], positions=b.positions[keep], quaternions=b.quaternions[keep],
                        rows=b.rows[keep])
        return self.with_changes(note, times=t, positions=self.positions[keep], velocities=self.velocities[keep],
                                 efforts=self.efforts[keep], rows=self.rows[keep], wrenches=w, base=b)


def segment(log: RobotLog, *, t_from: float | None = None, t_to: float | None = None) -> RobotLog:
    """The samples with ``t_from <= t <= t_to`` (either bound may be None), noted; an empty segment is
    an error naming the log's time range. Times are the log's own (a bag's count from its first stamp)."""
    if t_from is None and t_to is None:
        return log
    lo = -np.inf if t_from is None else float(t_from)
    hi = np.inf if t_to is None else float(t_to)
    if lo > hi:
        raise LogFormatError(f"{log.source}: the segment's start {lo} s is after its end {hi} s; swap "
                             "--from and --to", source=log.source, topic=log.topic)
    keep = (log.times >= lo) & (log.times <= hi)
    if not keep.any():
        raise LogFormatError(
            f"{log.source}: no sample between {lo} s and {hi} s; the log runs from {log.times[0]:.9g} s to "
            f"{log.times[-1]:.9g} s" + (" (seconds after its first stamp)" if log.t0_ns is not None else ""),
            source=log.source, topic=log.topic)
    idx = np.flatnonzero(keep)
    return log.take(keep, f"segment {lo:g} s to {hi:g} s: {len(idx)} of {log.n_samples} samples kept "
                          f"({log.at(idx[0])} to {log.at(idx[-1])})")

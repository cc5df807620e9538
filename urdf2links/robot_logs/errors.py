"""The errors of a robot log: each names the file, the column (or topic) and the row (or time stamp).

Every one is a :class:`LogError`, a ``ValueError``. The attributes say where, for a program (and for the
tests, which assert on them rather than on the words): ``source`` (the file), ``column`` (a CSV column
as written in its header, or ``"<topic> <field>[<joint>]"`` for a bag), ``row`` (the data row of a CSV
file counted from 1, or the message's index on its topic counted from 1; None when the whole column is
meant), ``time`` (the sample's time in the log's seconds, or None) and ``topic`` (a bag's topic, or
None). The message says what would fix the file.
"""

from __future__ import annotations

__all__ = [
    "LogError", "LogFormatError", "NonFiniteError", "TimeOrderError", "JumpError", "UnknownJointError",
    "DegreesError", "TooFewSamplesError", "NonUniformError",
]


class LogError(ValueError):
    """A robot log that cannot be used as it is (module doc: the attributes say where)."""

    def __init__(self, message: str, *, source: str = "", column: str | None = None, row: int | None = None,
                 time: float | None = None, topic: str | None = None):
        super().__init__(message)
        self.source = source
        self.column = column
        self.row = row
        self.time = time
        self.topic = topic


class LogFormatError(LogError):
    """The file cannot be read as a log: no time column, no joint column, an unknown suffix, a topic
    that is not in the bag or has another message type, joints that change between messages."""


class NonFiniteError(LogError):
    """A NaN (an empty cell) or an infinite value in a column that is otherwise logged."""


class TimeOrderError(LogError):
    """Time stamps that go backwards (``kind == "unsorted"``) or repeat (``kind == "duplicate"``)."""

    def __init__(self, message: str, *, kind: str, **where):
        super().__init__(message, **where)
        self.kind = kind


class JumpError(LogError):
    """A position that jumps between two samples by more than the motion around it allows, and is not
    an angle wrapped at +-pi (those are unwrapped, and said so in the notes). ``step`` is the jump."""

    def __init__(self, message: str, *, step: float, **where):
        super().__init__(message, **where)
        self.step = step


class UnknownJointError(LogError):
    """Joint names of the log that match no joint of the description. ``unknown`` lists them and
    ``suggestions`` maps each to the description's closest names (did you mean)."""

    def __init__(self, message: str, *, unknown: tuple[str, ...], suggestions: dict[str, tuple[str, ...]],
                 **where):
        super().__init__(message, **where)
        self.unknown = tuple(unknown)
        self.suggestions = dict(suggestions)


class DegreesError(LogError):
    """A column whose values look like degrees (or degrees per second) where radians are meant.
    ``factor`` is the evidence: the ratio that is close to 180/pi."""

    def __init__(self, message: str, *, factor: float, **where):
        super().__init__(message, **where)
        self.factor = factor


class TooFewSamplesError(LogError):
    """Fewer equations than the base parameters need (``equations`` against ``needed``)."""

    def __init__(self, message: str, *, equations: int, needed: int, **where):
        super().__init__(message, **where)
        self.equations = equations
        self.needed = needed


class NonUniformError(LogError):
    """Time steps too uneven for a filter that assumes one sampling rate (Savitzky-Golay). ``jitter``
    is the largest relative deviation of a step from the median step."""

    def __init__(self, message: str, *, jitter: float, **where):
        super().__init__(message, **where)
        self.jitter = jitter

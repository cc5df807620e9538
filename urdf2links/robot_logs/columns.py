"""Column names of a tabular log (CSV, NPZ): the time column and each joint's position, velocity, effort.

The project's own naming (what :func:`urdf2links.robot_logs.tables.write_csv` writes) is ROS JointState's:
``t`` (seconds), then ``<joint>.position``, ``<joint>.velocity``, ``<joint>.effort`` per joint.
Accepted variants (case-insensitive), tried in this order:

- time: ``t``, ``time``, ``timestamp``, ``stamp``, ``t_s``, ``time_s`` (seconds); ``t_ns``, ``time_ns``,
  ``stamp_ns``, ``timestamp_ns`` (integer nanoseconds, converted and noted);
- ``<joint><sep><quantity>`` with ``sep`` one of ``.``, ``/``, ``:``;
- ``<quantity><sep><joint>`` or ``<quantity>[<joint>]`` (``position[panda_joint1]``, ROS's array style);
- ``<joint>_<quantity>``, then ``<quantity>_<joint>``;

where ``quantity`` is a word of :data:`WORDS`: position ``position``, ``pos``, ``q``; velocity
``velocity``, ``vel``, ``qd``, ``dq``, ``qdot``, ``v``; effort ``effort``, ``eff``, ``tau``, ``torque``,
``force``. A column that matches none of these is left out and named in the log's notes. A floating
base's pose has its own seven columns (:data:`urdf2links.robot_logs.base.BASE_COLUMNS`).
"""

from __future__ import annotations

import re

__all__ = ["TIME_SECONDS", "TIME_NANOSECONDS", "WORDS", "parse_column", "time_column"]

TIME_SECONDS = ("t", "time", "timestamp", "stamp", "t_s", "time_s")
TIME_NANOSECONDS = ("t_ns", "time_ns", "stamp_ns", "timestamp_ns")
WORDS = {
    "position": ("position", "pos", "q"),
    "velocity": ("velocity", "vel", "qd", "dq", "qdot", "v"),
    "effort": ("effort", "eff", "tau", "torque", "force"),
}
_QUANTITY = {w: q for q, words in WORDS.items() for w in words}
_SEPS = ".:/"
_BRACKET = re.compile(r"^(\w+)\[([^\]]+)\]$")


def time_column(header: list[str]) -> tuple[int, float] | None:
    """``(index, seconds per unit)`` of the time column in ``header``, or None."""
    lower = [h.strip().lower() for h in header]
    for names, scale in ((TIME_SECONDS, 1.0), (TIME_NANOSECONDS, 1e-9)):
        for name in names:
            if name in lower:
                return lower.index(name), scale
    return None


def parse_column(name: str) -> tuple[str, str] | None:
    """``(joint, quantity)`` of a column name, or None when it names no joint quantity (module doc)."""
    s = name.strip()
    m = _BRACKET.match(s)
    if m and m.group(1).lower() in _QUANTITY:
        return m.group(2), _QUANTITY[m.group(1).lower()]
    for sep in _SEPS:
        if sep in s:
            head, tail = s.rsplit(sep, 1)
            if tail.lower() in _QUANTITY and head:
                return head, _QUANTITY[tail.lower()]
            head, tail = s.split(sep, 1)
            if head.lower() in _QUANTITY and tail:
                return tail, _QUANTITY[head.lower()]
    if "_" in s:
        head, tail = s.rsplit("_", 1)
        if tail.lower() in _QUANTITY and head:
            return head, _QUANTITY[tail.lower()]
        head, tail = s.split("_", 1)
        if head.lower() in _QUANTITY and tail:
            return tail, _QUANTITY[head.lower()]
    return None

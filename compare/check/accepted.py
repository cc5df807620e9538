"""A pair's accepted differences, by name: the ``accepted`` table of a ``[[pairs]]`` entry (docs/ci.md).

Each row accepts one difference the pair comparison reports
(:func:`~urdf2links.compare.pairs.pair.compare_descriptions_of`): its ``kind``, its ``part`` (the joint, link,
body, frame or constraint by its own name, :func:`part_of`), the value each file gives (``urdf``, ``mjcf``),
their ``difference`` in ``unit`` (metres and radians apart: an origin that turned is in rad, one that moved in m)
and its own ``tolerance``, in that unit. :func:`judge` holds a pair's differences now against the rows:

* a difference no row accepts fails (whatever its kind: no kind is accepted as a whole);
* a row whose difference moved fails: its difference by more than its tolerance, a file's value by more than its
  tolerance (or, where the values are in another unit than the difference, by more than :data:`VALUE_ROUNDING` in
  theirs: a frame's pose -- an origin's, a root's -- is ``[x, y, z, roll, pitch, yaw]``, its position held in m
  and its rotation in rad, each to the row's tolerance when that is the row's unit), or its unit changed;
* a row whose difference is gone fails too (the pair changed: remove the row).

:func:`accepted_row` writes a row from a difference with the tolerance :func:`row_tolerance` gives: the kind's
rounding level (:data:`~urdf2links.compare.pairs.differences.ROUNDING`), or :data:`REL` of the row's magnitude
when that is larger (MuJoCo's XML writer keeps 6 significant digits: a file saved again moves a value by at most
5e-6 of it). A 1 cm move, a halved damping or a mass x 1.1 are 1e3 to 1e5 times that.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from urdf2links.dynamics.rotations import matrix_to_rpy, rpy_to_matrix

from ..pairs.differences import KINDS, ROUNDING

__all__ = ["AcceptedRow", "RowProblem", "part_of", "accepted_row", "row_tolerance", "rows_toml", "read_rows",
           "judge", "toml_value", "REL", "VALUE_ROUNDING"]

#: A row's tolerance relative to its magnitude: twice the relative rounding of 6 significant digits (5e-6).
REL = 1e-5
#: How far a file's value may move where it is in another unit than the difference (m, or relative).
VALUE_ROUNDING = 1e-5
#: The kinds of a joint, of a body's frame or inertia (named by body), the rest named apart.
_JOINT_KINDS = {"axis", "type", "limits", "effort", "velocity", "armature", "damping", "stiffness", "friction",
                "joint_missing", "coupling"}
#: The unit of the two values where it is not the difference's own.
_VALUE_UNITS = {"mass": "relative", "inertia": "relative", "effort": "relative", "velocity": "relative",
                "collision": "relative", "com": "m", "origin": "pose", "root_pose": "pose", "frame_missing": "m",
                "link_missing": "kg", "axis": "rad"}
_WORD = {"urdf": "link", "mjcf": "body"}
_KEYS = ("kind", "part", "urdf", "mjcf", "difference", "unit", "tolerance")


@dataclass(frozen=True)
class AcceptedRow:
    """One accepted difference (module doc); values as :func:`row_value` writes them."""

    kind: str
    part: str
    urdf: object
    mjcf: object
    difference: float
    unit: str
    tolerance: float

    def as_dict(self) -> dict:
        return {k: getattr(self, k) for k in _KEYS}


@dataclass(frozen=True)
class RowProblem:
    """What :func:`judge` found: ``what`` (``new``, ``moved``, ``gone``), the ``difference`` (the summary's JSON,
    None when gone), the ``row`` (None when new), the row that would accept it now (``replacement``), ``moved`` and
    ``allowed`` (how far it moved, and how far it may), ``detail`` (which value moved)."""

    what: str
    difference: dict | None
    row: AcceptedRow | None
    replacement: AcceptedRow | None
    moved: float = math.inf
    allowed: float = 0.0
    detail: str = ""

    @property
    def ratio(self) -> float:
        return math.inf if self.allowed <= 0 else self.moved / self.allowed


def _name(n) -> str | None:
    return None if n in (None, "") else str(n)


def part_of(d: dict, formats=("urdf", "mjcf")) -> str:
    """The part a difference (its JSON) belongs to, by its own name: ``joint panda_joint1``, ``link panda_link3``
    (``link a / body b`` where the two files name it apart), ``frame panda_hand_tcp``, ``constraint c``."""
    kind, links = d["kind"], [_name(x) for x in d.get("links") or ()]
    if kind == "frame_missing":
        return f"frame {links[0] if links else _name(d['urdf'])}"
    if kind in _JOINT_KINDS:
        words, names = ("joint", "joint"), (_name(d["urdf"]), _name(d["mjcf"]))
    elif kind == "constraint":
        words, names = ("constraint", "constraint"), (_name(d["urdf"]), _name(d["mjcf"]))
        if not any(names):
            return "constraint between " + " and ".join(n for n in links if n)
    else:
        words = tuple(_WORD.get(f, "body") for f in formats)
        two = kind in ("mass", "com", "inertia", "origin", "root_pose") and len(links) == 2
        names = (links[0], links[1]) if two else (_name(d["urdf"]), _name(d["mjcf"]))
    (w1, w2), (n1, n2) = words, names
    if n1 and n2:
        return f"{w1} {n1}" if n1 == n2 else f"{w1} {n1} / {w2} {n2}"
    return f"{w1} {n1}" if n1 else f"{w2} {n2}"


def _num(x):
    if isinstance(x, str) and x in ("inf", "-inf", "nan"):
        return float(x)
    return x


def _round(x: float) -> float:
    return float(f"{x:.8g}") if math.isfinite(x) else x


def _array(v) -> np.ndarray:
    def plain(x):
        return [plain(y) for y in x] if isinstance(x, (list, tuple)) else float(_num(x))
    return np.asarray(plain(v), float)


def row_value(kind: str, v):
    """A file's value of a difference as a row keeps it: a number or a flat list (8 significant digits), a name;
    ``"none"`` where the file has none, ``"unlimited"`` for a joint without limits; an inertia tensor as
    ``[ixx, iyy, izz, ixy, ixz, iyz]`` (kg m^2), a frame (an origin's, from the difference's ``frames``; a root's)
    as ``[x, y, z, roll, pitch, yaw]`` (m, rad)."""
    if v is None:
        return "none"
    if isinstance(v, str) and _num(v) is v:
        return v
    a = _array(v)
    if a.size and np.all(np.isnan(a)):
        return "unlimited" if kind == "limits" else "none"
    if a.shape == (3, 3):
        a = np.array([a[0, 0], a[1, 1], a[2, 2], a[0, 1], a[0, 2], a[1, 2]])
    elif a.shape == (4, 4):
        a = np.r_[a[:3, 3], matrix_to_rpy(a[:3, :3])]
    if a.ndim == 0:
        return _round(float(a))
    return [_round(float(x)) for x in a.ravel()]


def _difference(d: dict) -> float:
    return float(_num(d["difference"]))


def _values_distance(a, b, unit: str) -> float:
    """How far a file's value moved: 0 or inf for names, else the largest change (over the larger value's size
    when ``unit`` is relative); inf when the shape changed."""
    if isinstance(a, str) or isinstance(b, str):
        return 0.0 if a == b else math.inf
    x, y = np.atleast_1d(np.asarray(a, float)), np.atleast_1d(np.asarray(b, float))
    if x.shape != y.shape:
        return math.inf
    same = (x == y) | (np.isnan(x) & np.isnan(y))
    if same.all():
        return 0.0
    delta = float(np.max(np.abs(np.where(same, 0.0, x - y))))
    if unit == "relative":
        finite = np.r_[x[np.isfinite(x)], y[np.isfinite(y)]]
        delta /= max(float(np.max(np.abs(finite))) if finite.size else 0.0, 1e-300)
    return delta


def row_tolerance(kind: str, unit: str, difference: float, values=()) -> float:
    """A new row's tolerance (module doc): the kind's rounding, or :data:`REL` of the difference and of the values
    (those in the difference's unit), whichever is larger."""
    sizes = [abs(difference)] if math.isfinite(difference) else []
    vunit = _VALUE_UNITS.get(kind, unit)
    if (vunit == unit or vunit == "pose" and unit == "m") and unit != "relative":
        for v in values:
            if not isinstance(v, str):
                a = np.abs(np.atleast_1d(np.asarray(v, float)))[:3 if vunit == "pose" else None]
                sizes += [float(x) for x in a if math.isfinite(x)]
    scale = 1.0 if unit == "relative" else max(sizes, default=0.0)
    return float(f"{max(ROUNDING.get(kind, 0.0), REL * scale):.2g}")


def accepted_row(d: dict, formats=("urdf", "mjcf"), *, tolerance: float | None = None) -> AcceptedRow:
    """The row that accepts the difference ``d`` (its summary JSON) as it is now (module doc)."""
    frames = d.get("frames") or {}
    u, m = (row_value(d["kind"], frames[s] if s in frames else d.get(f"{s}_value")) for s in ("urdf", "mjcf"))
    diff = _difference(d)
    tol = row_tolerance(d["kind"], d["unit"], diff, (u, m)) if tolerance is None else tolerance
    return AcceptedRow(d["kind"], part_of(d, formats), u, m, _round(diff), d["unit"], tol)


def _pose_moves(a, b) -> tuple[float, float]:
    """How far a pose ``[x, y, z, roll, pitch, yaw]`` moved (m) and turned (rad); inf when it is not one now."""
    if isinstance(a, str) or isinstance(b, str) or np.shape(a) != (6,) or np.shape(b) != (6,):
        return (0.0, 0.0) if a == b else (math.inf, math.inf)
    x, y = np.asarray(a, float), np.asarray(b, float)
    R = rpy_to_matrix(x[3:]).T @ rpy_to_matrix(y[3:])
    return float(np.linalg.norm(x[:3] - y[:3])), float(np.arccos(np.clip((np.trace(R) - 1.0) / 2.0, -1.0, 1.0)))


def _moved(row: AcceptedRow, now: AcceptedRow) -> tuple[float, float, str]:
    """``(moved, allowed, which)``: the largest move of the row's difference or a file's value over what it may."""
    if now.unit != row.unit:
        return math.inf, row.tolerance, f"its unit changed from {row.unit} to {now.unit}"
    a, b = row.difference, now.difference
    checks = [(0.0 if a == b else abs(a - b), row.tolerance, "the difference")]
    vunit = _VALUE_UNITS.get(row.kind, row.unit)
    allowed = row.tolerance if vunit == row.unit else VALUE_ROUNDING
    for side in ("urdf", "mjcf"):
        old, new = getattr(row, side), getattr(now, side)
        if vunit == "pose":
            for unit, moved in zip(("m", "rad"), _pose_moves(old, new)):
                checks.append((moved, row.tolerance if unit == row.unit else VALUE_ROUNDING,
                               f"the {side} frame's {'position' if unit == 'm' else 'rotation'}"))
        else:
            checks.append((_values_distance(old, new, vunit), allowed, f"the {side} value"))
    return max(checks, key=lambda c: c[0] / c[1] if c[1] > 0 else (math.inf if c[0] > 0 else 0.0))


def judge(summary: dict, rows) -> list[RowProblem]:
    """A pair's differences now (its summary JSON) against its accepted ``rows`` (module doc): one problem per
    difference not accepted, per row that moved and per row whose difference is gone. A floating root's pose at
    home is a state, not a difference (as :func:`~urdf2links.compare.pairs.pair.exceedances` holds it)."""
    desc = summary.get("descriptions", {})
    formats = (desc.get("urdf", {}).get("format", "urdf"), desc.get("mjcf", {}).get("format", "mjcf"))
    floating = bool(summary.get("description_counts", {}).get("root_pose", {}).get("floating"))
    left: dict[tuple, list[AcceptedRow]] = {}
    for r in rows:
        left.setdefault((r.kind, r.part), []).append(r)
    out = []
    for d in summary["description_differences"]:
        if d["kind"] == "root_pose" and floating:
            continue
        now = accepted_row(d, formats)
        found = left.get((now.kind, now.part))
        if not found:
            out.append(RowProblem("new", d, None, now))
            continue
        row = found.pop(0)
        moved, allowed, which = _moved(row, now)
        if moved > allowed:
            out.append(RowProblem("moved", d, row, accepted_row(d, formats, tolerance=row.tolerance), moved, allowed,
                                  which))
    out += [RowProblem("gone", None, r, None, 1.0, 1.0) for rs in left.values() for r in rs]
    return out


def toml_value(v) -> str:
    """A TOML value: strings, booleans, numbers (``inf``, ``-inf``, ``nan``), lists, inline tables."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(v) if math.isfinite(v) else ("nan" if math.isnan(v) else ("inf" if v > 0 else "-inf"))
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{k} = {toml_value(x)}" for k, x in v.items()) + " }" if v else "{}"
    return "[" + ", ".join(toml_value(x) for x in v) + "]"


def rows_toml(rows, *, indent: str = "  ") -> list[str]:
    """``accepted = [ ... ]``: one inline table per row, its columns aligned (the lines of a configuration)."""
    if not rows:
        return ["accepted = []"]
    cells = [[f"{k} = {toml_value(getattr(r, k))}," for k in _KEYS] for r in rows]
    widths = [max(len(c[i]) for c in cells) for i in range(len(_KEYS))]
    lines = ["accepted = [   # each difference accepted by name, and how far it may move (docs/ci.md)"]
    for c in cells:
        c[-1] = c[-1].rstrip(",")
        lines.append(indent + "{ " + " ".join(x.ljust(w) for x, w in zip(c, widths)).rstrip() + " },")
    return lines + ["]"]


def read_rows(where: str, value, fail) -> tuple[AcceptedRow, ...]:
    """The ``accepted`` rows of a pair, every key checked (``fail(where, message)`` raises)."""
    if not isinstance(value, list) or not all(isinstance(r, dict) for r in value):
        fail(where, f"accepted must be an array of tables {{ {', '.join(_KEYS)} }}, got {value!r}")
    out = []
    for i, r in enumerate(value):
        at = f"accepted[{i}]"
        missing, bad = [k for k in _KEYS if k not in r], [k for k in r if k not in _KEYS]
        if missing or bad:
            fail(where, f"{at}: " + (f"missing {missing}" if missing else "") + ("; " if missing and bad else "")
                 + (f"unknown key(s) {bad}" if bad else "") + f"; a row has {', '.join(_KEYS)}")
        if r["kind"] not in KINDS:
            fail(where, f"{at}: unknown kind {r['kind']!r}; the kinds are {', '.join(KINDS)}")
        tol, diff = r["tolerance"], r["difference"]
        if isinstance(tol, bool) or not isinstance(tol, (int, float)) or not 0 <= tol < math.inf:
            fail(where, f"{at} ({r['kind']} of {r['part']}): tolerance = {tol!r}: give a finite number >= 0 (a row "
                        "accepts one difference as it is; inf would accept any)")
        if isinstance(diff, bool) or not isinstance(diff, (int, float)):
            fail(where, f"{at}: difference = {diff!r}: give a number")
        for k in ("part", "unit"):
            if not isinstance(r[k], str):
                fail(where, f"{at}: {k} = {r[k]!r}: give a string")
        out.append(AcceptedRow(r["kind"], r["part"], r["urdf"], r["mjcf"], float(diff), r["unit"], float(tol)))
    return tuple(out)

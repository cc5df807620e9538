"""Tabular logs: CSV and NPZ with ROS JointState naming (:mod:`urdf2links.robot_logs.columns`), read and written.

CSV: one header line, then one sample per line; an empty cell is NaN (an absent column is one that is
empty throughout). NPZ: either the CSV's columns as arrays (``t``, ``<joint>.position``, ...), or
JointState's layout: ``t`` (S,), ``name`` (n,) strings, and ``position``, ``velocity``, ``effort`` (S, n),
each optional but one.
"""

from __future__ import annotations

import csv
import warnings
from pathlib import Path

import numpy as np

from .base import BASE_COLUMNS, BasePoses
from .columns import parse_column, time_column
from .errors import LogFormatError
from .log import QUANTITIES, RobotLog

__all__ = ["read_csv", "read_npz", "write_csv", "write_npz", "log_from_columns"]

_FORMS = ("t, then <joint>.position, <joint>.velocity, <joint>.effort (docs/logs.md lists the variants "
          "accepted)")


def log_from_columns(source: str, header: list[str], data: np.ndarray) -> RobotLog:
    """A log from named columns: ``header`` (C,) and ``data`` (S, C) floats (NaN for empty cells)."""
    found = time_column(header)
    if found is None:
        raise LogFormatError(f"{source}: no time column among {header[:8]}{' ...' if len(header) > 8 else ''}; "
                             f"name it 't' (seconds) or 't_ns' (nanoseconds)", source=source)
    it, scale = found
    notes, names, columns, ignored = [], [], {}, []
    base_cols = {h.lower(): c for c, h in enumerate(header) if h.lower() in BASE_COLUMNS}
    for c, h in enumerate(header):
        if c == it or h.lower() in BASE_COLUMNS:
            continue
        parsed = parse_column(h)
        if parsed is None:
            ignored.append(h)
            continue
        joint, q = parsed
        if (q, joint) in columns:
            raise LogFormatError(f"{source}: columns {columns[(q, joint)][0]!r} and {h!r} both hold joint "
                                 f"{joint!r}'s {q}; keep one", source=source, column=h)
        columns[(q, joint)] = (h, c)
        if joint not in names:
            names.append(joint)
    if not names:
        raise LogFormatError(f"{source}: no joint column in {header}; expected {_FORMS}", source=source)
    S, n = data.shape[0], len(names)
    arrays = {q: np.full((S, n), np.nan) for q in QUANTITIES}
    for (q, joint), (_h, c) in columns.items():
        arrays[q][:, names.index(joint)] = data[:, c]
    times = data[:, it] * scale
    if scale != 1.0:
        notes.append(f"time column {header[it]!r} read as nanoseconds and divided by 1e9")
    if ignored:
        notes.append(f"columns left out (no joint quantity in their names): {', '.join(ignored)}")
    for q in QUANTITIES:
        absent = [j for j in names if (q, j) not in columns]
        if absent:
            notes.append(f"no {q} column for {', '.join(absent)}: NaN")
    base = _base_columns(source, base_cols, data, times, notes)
    return RobotLog(times=times, names=tuple(names), positions=arrays["position"],
                    velocities=arrays["velocity"], efforts=arrays["effort"], source=source,
                    notes=tuple(notes), columns={k: v[0] for k, v in columns.items()}, base=base)


def _base_columns(source: str, cols: dict, data: np.ndarray, times: np.ndarray, notes: list) -> BasePoses | None:
    """The base's poses from the columns BASE_COLUMNS (all seven, or none)."""
    if not cols:
        return None
    missing = [c for c in BASE_COLUMNS if c not in cols]
    if missing:
        raise LogFormatError(f"{source}: base pose columns {sorted(cols)} without {missing}; a base pose needs "
                             f"all of {list(BASE_COLUMNS)}", source=source, column=missing[0])
    v = data[:, [cols[c] for c in BASE_COLUMNS]]
    notes.append("the base's pose read from the columns " + ", ".join(BASE_COLUMNS))
    return BasePoses(source="columns", frame="", times=times, positions=v[:, :3], quaternions=v[:, 3:],
                     rows=np.arange(1, len(times) + 1))


def read_csv(path) -> RobotLog:
    """A CSV log (module doc). A cell that is not a number is an error naming its column and row."""
    source = str(path)
    with open(path, newline="") as f:
        try:
            header = [h.strip() for h in next(csv.reader(f))]
        except StopIteration:
            raise LogFormatError(f"{source}: the file is empty; expected a header line {_FORMS}",
                                 source=source) from None
    found = time_column(header)
    used = [c for c, h in enumerate(header) if parse_column(h) is not None or (found and c == found[0])
            or h.lower() in BASE_COLUMNS]
    try:        # the fast path: every used cell a number; else cell by cell, naming the bad one
        with warnings.catch_warnings():
            warnings.simplefilter("error")          # "input contained no data" too
            block = np.loadtxt(path, delimiter=",", skiprows=1, usecols=used, ndmin=2, dtype=float)
        data = np.full((block.shape[0], len(header)), np.nan)    # a column left out is not read (it is noted)
        data[:, used] = block
    except (ValueError, UserWarning):
        data = _cells(path, source, header, used)
    return log_from_columns(source, header, data)


def _cells(path, source: str, header: list[str], used: list[int]) -> np.ndarray:
    """(S, C) the used columns read cell by cell: an empty cell is NaN, any other that is not a number,
    or a row of another length, an error naming it."""
    with open(path, newline="") as f:
        reader = csv.reader(f)
        next(reader)
        rows = []
        for r, line in enumerate(reader, start=1):
            if not line:
                continue
            if len(line) != len(header):
                raise LogFormatError(f"{source}: row {r} has {len(line)} cells, the header {len(header)}",
                                     source=source, row=r)
            rows.append(line)
    data = np.full((len(rows), len(header)), np.nan)
    for r, line in enumerate(rows):
        for c in used:
            cell = line[c].strip()
            try:
                data[r, c] = float(cell) if cell else np.nan
            except ValueError:
                raise LogFormatError(f"{source}: column {header[c]!r}, row {r + 1}: {cell!r} is not a number",
                                     source=source, column=header[c], row=r + 1) from None
    return data


def read_npz(path) -> RobotLog:
    """An NPZ log in either layout (module doc)."""
    source = str(path)
    with np.load(path, allow_pickle=False) as z:
        arrays = {k: z[k] for k in z.files}
    if "name" in arrays:
        return _jointstate_layout(source, arrays)
    header = list(arrays)
    lengths = {k: a.shape for k, a in arrays.items()}
    S = {a.shape[0] for a in arrays.values() if a.ndim == 1}
    if len(S) != 1 or any(a.ndim != 1 for a in arrays.values()):
        raise LogFormatError(f"{source}: the arrays must all be one column of one length (S,); got {lengths}",
                             source=source)
    data = np.column_stack([arrays[k].astype(float) for k in header])
    return log_from_columns(source, header, data)


def _jointstate_layout(source: str, arrays: dict) -> RobotLog:
    names = tuple(str(x) for x in arrays["name"])
    if "t" not in arrays:
        raise LogFormatError(f"{source}: an NPZ with 'name' needs 't' (S,) seconds", source=source)
    times = arrays["t"].astype(float)
    S, n = len(times), len(names)
    out, notes = {}, []
    for q in QUANTITIES:
        a = arrays.get(q)
        if a is None:
            out[q] = np.full((S, n), np.nan)
            notes.append(f"no '{q}' array: NaN for every joint")
        elif a.shape != (S, n):
            raise LogFormatError(f"{source}: '{q}' has shape {a.shape}; expected ({S}, {n}) for {S} times and "
                                 f"{n} names", source=source, column=q)
        else:
            out[q] = a.astype(float)
    return RobotLog(times=times, names=names, positions=out["position"], velocities=out["velocity"],
                    efforts=out["effort"], source=source, notes=tuple(notes),
                    columns={(q, j): f"{q}[{j}]" for q in QUANTITIES for j in names})


def write_csv(log: RobotLog, path) -> Path:
    """``log`` as CSV in the project's naming (``t``, ``<joint>.position``, ..., the base's pose columns
    when it has them at its samples' times), every float written exactly (17 significant digits); a
    quantity absent for a joint is left out."""
    cols = [(q, j) for j in range(len(log.names)) for q in QUANTITIES if log.logged(q)[j]]
    header = ["t"] + [f"{log.names[j]}.{q}" for q, j in cols]
    data = np.column_stack([log.times] + [log.values(q)[:, j] for q, j in cols])
    if log.base is not None and np.array_equal(log.base.times, log.times):
        header += list(BASE_COLUMNS)
        data = np.column_stack([data, log.base.positions, log.base.quaternions])
    path = Path(path)
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(header)
        w.writerows([["" if np.isnan(x) else repr(float(x)) for x in row] for row in data])
    return path


def write_npz(log: RobotLog, path) -> Path:
    """``log`` as NPZ in JointState's layout (``t``, ``name``, ``position``, ``velocity``, ``effort``)."""
    path = Path(path)
    np.savez(path, t=log.times, name=np.array(log.names), position=log.positions, velocity=log.velocities,
             effort=log.efforts)
    return path

"""A model's inputs as rows for the compiled calls (:mod:`urdf2links.dynamics.model_kernels`): one state or a batch.

A state argument is ``(n,)`` (one state) or ``(B, n)`` (a batch of B states); the others given with
it must have the same shape. The base {A} of a batch (:func:`base_rows`) is one
:class:`~urdf2links.dynamics.transforms.BaseState` for every row, a BaseState whose ``pose``, ``rate``,
``accel`` are ``(B, 6)`` (one per row), or a callable ``t -> BaseState`` evaluated at ``t`` (a float:
one base for every row; an array ``(B,)``: each row at its own time).
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from .loads import Wrench
from .transforms import BaseState, base_state_at

__all__ = ["Rows", "kernel_array", "state_rows", "base_rows", "load_rows", "NO_BASE", "NO_LOADS"]

NO_BASE = np.zeros((1, 18))
"""Base rows of a fixed base (never read by the kernels)."""
NO_LOADS = np.zeros((0, 11))

Rows = namedtuple("Rows", ["batched", "arrays"])
"""``batched``: the arguments had a batch axis; ``arrays``: each (B, n) float C-contiguous, or None."""


def kernel_array(a) -> np.ndarray:
    """``a`` as a float64, C-contiguous, writable array (a copy only when it is not one): every
    compiled call sees one array type, so a read-only or strided input (a row of a memory map, a
    frozen array) does not compile another variant of the kernels."""
    return np.require(a, dtype=float, requirements=["C", "W"])


def state_rows(n: int, names, named) -> Rows:
    """``named``: ``[(argument name, value or None), ...]``, the first one the state that sets the
    shape, ``(n,)`` or ``(B, n)``; a ValueError names the argument, the shape received and the
    shape expected."""
    first, value = named[0]
    a = np.asarray(value, dtype=float)
    if a.ndim not in (1, 2) or a.shape[-1] != n:
        raise ValueError(f"{first} must have shape ({n},) for one state or (B, {n}) for a batch, for coordinates "
                         f"{tuple(names)}; got shape {a.shape}")
    B = a.shape[0] if a.ndim == 2 else 1      # not reshape(-1, n): a model without coordinates has n = 0
    out = [kernel_array(a.reshape(B, n))]
    for name, v in named[1:]:
        if v is None:
            out.append(None)
            continue
        b = np.asarray(v, dtype=float)
        if b.shape != a.shape:
            raise ValueError(f"{name} must have the shape of {first}, {a.shape}, for coordinates {tuple(names)}; "
                             f"got shape {b.shape}")
        out.append(kernel_array(b.reshape(B, n)))
    return Rows(a.ndim == 2, out)


def _as_rows(state: BaseState, B: int, batched: bool) -> np.ndarray:
    parts = [np.asarray(x, dtype=float) for x in (state.pose, state.rate, state.accel)]
    shapes = {p.shape for p in parts}
    if shapes == {(6,)}:
        return np.concatenate(parts)[None, :]
    if batched and shapes == {(B, 6)}:
        return np.concatenate(parts, axis=1)
    want = f"(6,) or ({B}, 6)" if batched else "(6,)"
    raise ValueError(f"base: pose, rate and accel must have shape {want}; got shapes "
                     f"{[p.shape for p in parts]}")


def base_rows(base, t, B: int, *, batched: bool, still: bool = False) -> tuple[np.ndarray, bool]:
    """``(rows (1 or B, 18), has_base)``: pose, rate and acceleration of {A} per row (see the module
    doc); ``still`` keeps the pose and zeroes the rates (a base at rest there)."""
    if base is None:
        return NO_BASE, False
    ts = np.asarray(t, dtype=float)
    if ts.ndim == 0:
        rows = _as_rows(base_state_at(base, float(ts)), B, batched)
    elif not batched or ts.shape != (B,):
        raise ValueError(f"t must be a number, or an array of shape ({B},) (one time per row of a batch); "
                         f"got shape {ts.shape}" + ("" if batched else " for one state"))
    elif callable(base):
        rows = np.concatenate([_as_rows(base_state_at(base, float(x)), 1, False) for x in ts])
    else:
        rows = _as_rows(base_state_at(base, 0.0), B, batched)
    if still:
        rows = rows.copy()
        rows[:, 6:] = 0.0
    return rows, True


def load_rows(tree, loads) -> np.ndarray:
    """(k, 11) ``(link index, force (3), moment (3), point (3), local)`` of
    :class:`~urdf2links.dynamics.loads.Wrench` loads, the same for every row."""
    loads = loads if isinstance(loads, (list, tuple)) else list(loads)
    if not loads:
        return NO_LOADS
    out = np.empty((len(loads), 11))
    for k, w in enumerate(loads):
        if not isinstance(w, Wrench):
            raise TypeError(f"loads must be Wrench objects, got {type(w).__name__}")
        out[k, 0] = tree.link_index(w.link)
        out[k, 1:] = w.row
    return out

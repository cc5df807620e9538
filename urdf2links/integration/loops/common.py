"""What every integration loop shares: the evaluation of a compiled scene, norms, the angle guard.

:func:`evaluate` is the one call into the compiled right-hand side
(the scene's :func:`urdf2links.scenes.scene_kernels.rhs_function`, the last of its ``args``) that every
compiled loop makes; it counts the call and keeps the state where it failed for the driver's error
message. The right-hand side is a C function typed by its signature alone, so every loop is compiled
once, whatever effects the scene has.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ...compilation import one_signature

__all__ = ["AngleGuard", "evaluate", "rms", "finite", "guard_fires", "EPS"]

EPS = 2.220446049250313e-16


class AngleGuard:
    """A ``stop`` test: True once ``|cos(y[j])| < cos_min`` for any ``j`` in ``indices``, i.e. an
    angle (a ZYX ``phi_y``) came within ``arccos(cos_min)`` of ``+-pi/2``, where its chart is
    singular. ``cos_min`` is one threshold or one per index. The compiled loops test it without
    calling Python."""

    __slots__ = ("indices", "thresholds")

    def __init__(self, indices, cos_min):
        self.indices = np.asarray(indices, dtype=np.int64).ravel()
        c = np.asarray(cos_min, dtype=float)
        if c.ndim > 1 or (c.ndim == 1 and c.size != self.indices.size) or not np.all((c > 0.0) & (c < 1.0)):
            raise ValueError(f"cos_min must be in (0, 1), one value or one per index, got {cos_min!r}")
        self.thresholds = np.array(np.broadcast_to(c, self.indices.shape), dtype=float)   # writable: a read-only array is a type of its own to numba

    def __call__(self, t, y) -> bool:
        return bool(self.indices.size) and bool(np.any(np.abs(np.cos(y[self.indices])) < self.thresholds))

    def __or__(self, other: "AngleGuard") -> "AngleGuard":
        """Both guards as one (either fires)."""
        return AngleGuard(np.r_[self.indices, other.indices], np.r_[self.thresholds, other.thresholds])


# -- small pieces -----------------------------------------------------------------------------------
@one_signature
@njit(cache=True)
def rms(x, scale):
    s = 0.0
    for i in range(x.size):
        v = x[i] / scale[i]
        s += v * v
    return np.sqrt(s / x.size)


@one_signature
@njit(cache=True)
def finite(x):
    for i in range(x.size):
        if not np.isfinite(x[i]):
            return False
    return True


@one_signature
@njit(cache=True)
def guard_fires(y, guard):
    """The angle guard ``guard = (indices, thresholds)``: some ``|cos y[i]| < threshold``."""
    idx, cos_min = guard
    for j in range(idx.size):
        if abs(np.cos(y[idx[j]])) < cos_min[j]:
            return True
    return False


@one_signature
@njit(cache=True)
def evaluate(t, y, out, args, counters):
    """One evaluation of the compiled scene ``args`` into ``out``; counts it in ``cnt[0]``. On
    failure the state goes to ``fail = [t, y]`` for the driver's error, and it returns False."""
    cnt, fail = counters
    cnt[0] += 1
    I, F, W, SI, SF, X, rhs = args
    pivot = rhs(t, y, out, I, F, W, SI, SF, X)
    if pivot < 0 and finite(out):
        return True
    fail[0] = t
    for i in range(y.size):
        fail[1 + i] = y[i]
    return False

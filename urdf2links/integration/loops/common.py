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
from ...scenes.constraint_arrays import CM, CX, x_layout
from ...scenes.constraint_kernels import schur_correction
from ...dynamics.tree_arrays import Tree
from ...scenes.scene_arrays import S_CON, Scene

__all__ = ["AngleGuard", "evaluate", "rms", "finite", "guard_fires", "EPS", "has_rows", "project", "settle",
           "PROJECTION_TOL", "PROJECTION_MAXITER"]

PROJECTION_TOL = 1e-13      # the Gauss-Newton projection stops at max |Phi| <= this (E74)
PROJECTION_MAXITER = 30

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


# -- issue 45: the projection onto the constraints (E74), after every accepted step --------------------
@one_signature
@njit(cache=True)
def has_rows(args):
    """The compiled scene ``args`` has constraint rows (fixed tendons alone need no projection)."""
    SI = args[3]
    return SI[S_CON] > 0 and SI[SI[S_CON] + CM] > 0


@one_signature
@njit(cache=True)
def project(t, y, f, args, counters):
    """``y = (q, q', W)`` projected in place onto ``Phi = 0`` (Gauss-Newton ``q <- q - A^-1 J^T S^-1 Phi``
    until ``max |Phi| <= PROJECTION_TOL`` or it stops decreasing) and ``Phi' = 0`` (``q' <- q' - A^-1 J^T S^-1
    J q'``, the nearest in the metric of A) (E74), every term from the compiled right-hand side's own
    evaluation (A's factor and the pivoted factor of S, over the rows it solved); ``f`` left as ``y'`` at the projected state. Records
    the largest ``max |Phi|`` before a projection. False when an evaluation failed (``evaluate``)."""
    SI, X = args[3], args[5]
    tree, scene = Tree(args[0], args[1], args[2]), Scene(SI, args[4], X)
    n, nt = SI[0], SI[1]
    c0 = SI[S_CON]
    m = SI[c0 + CM]
    xc = SI[c0 + CX]
    lay = x_layout(m, n, nt)
    xphi, xj, xact, xst = xc + lay[0], xc + lay[2], xc + lay[8], xc + lay[11]
    v = np.empty(m)
    dq = np.empty(n)
    last = np.inf
    for it in range(PROJECTION_MAXITER + 1):
        X[xst + 6] = 1.0 if it == 0 else 0.0      # the change-point events of accepted steps only
        ok = evaluate(t, y, f, args, counters)
        X[xst + 6] = 0.0
        if not ok:
            return False
        res = 0.0
        for k in range(m):
            res = max(res, abs(X[xphi + k]))
        if it == 0:
            X[xst + 4] = max(X[xst + 4], res)
            X[xst + 5] += 1.0
        if res <= PROJECTION_TOL or res >= last or it == PROJECTION_MAXITER:
            break
        last = res
        for k in range(m):
            v[k] = X[xphi + k] if X[xact + k] != 0.0 else 0.0
        schur_correction(tree, scene, v, 0, dq)
        for i in range(n):
            y[i] -= dq[i]
    rate = 0.0
    for k in range(m):
        s = 0.0
        if X[xact + k] != 0.0:
            for i in range(n):
                s += X[xj + k * n + i] * y[n + i]
        v[k] = s
        rate = max(rate, abs(s))
    if rate > 0.0:
        schur_correction(tree, scene, v, 0, dq)
        for i in range(n):
            y[n + i] -= dq[i]
        if not evaluate(t, y, f, args, counters):
            return False
    return True


@one_signature
@njit(cache=True)
def settle(t, y, f, args, counters):
    """``f = y'(t, y)`` after a step; with constraint rows, ``y`` projected first (:func:`project`)."""
    if has_rows(args):
        return project(t, y, f, args, counters)
    return evaluate(t, y, f, args, counters)

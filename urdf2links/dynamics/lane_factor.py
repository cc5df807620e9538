"""The tree-sparse ``A = L^T D L`` (docs/equations.md (E47)) and its solve in SIMD lanes: :mod:`urdf2links.dynamics.factor`'s
:func:`~urdf2links.dynamics.factor.ltdl` and :func:`~urdf2links.dynamics.factor.ltdl_solve` for a block of ``LW``
states, the packed matrices in the rows ``W_A`` of the lane scratch ``WL`` (W_SIZE, LW)
(:mod:`urdf2links.dynamics.lane_kernels`).

The sparsity (which rows and columns an elimination touches) is the tree's, the same in every lane, so
the loops over it stay scalar and only the innermost loop runs over the lanes. The pivot test is per
lane: a lane whose pivot ``D[k]`` is at or below the rounding level of its own ``A``
(:func:`~urdf2links.dynamics.factor.pivot_floor`) records the first such ``k`` (from the leaves) in its
status, as the scalar factorization returns it; the lane's elimination goes on (its numbers are then
meaningless, and the caller raises for that row), so the other lanes never wait on a branch.
"""

from __future__ import annotations

from ..compilation import kernel, one_signature

from .factor import EPS
from .lane_kernels import rows, small
from .tree_arrays import I_ANCIDX, I_ANCPTR, I_ANCROW, I_RUNPTR, I_RUNS, W_A

__all__ = ["lane_ltdl", "lane_solve"]


def ieee(fn):
    """A kernel whose divisions follow IEEE (a zero pivot of a failing lane gives inf or nan, as the lane goes on,
    where numba's default raises ZeroDivisionError): its check of every divisor also stops the vectorizer."""
    return kernel(fn, error_model="numpy")


# The small lane loops below take ``LW`` as a plain integer (one_signature): with a constant trip count LLVM
# unrolls a loop this small before its loop vectorizer runs, and the unrolled code is not vectorized
# (the rows are distinct arguments that may overlap for all it knows); a loop of unknown count is
# vectorized behind one overlap check.
@one_signature
@kernel
def _pivots(WL, rd, k, T, ST, LW):
    """Lane by lane: the pivot at row ``rd`` into ``T[3]``, against the lane's floor ``T[0]``; a first
    failure records ``k`` in the lane's status."""
    rd = small(rd)
    for l in range(LW):
        D = WL[rd * LW + l]
        T[3 * LW + l] = D
        ST[l] = k if (ST[l] < 0 and not D > T[l]) else ST[l]


@kernel
def _floors(TI, WL, T, lanes):
    """``T[0]``: every lane's :func:`~urdf2links.dynamics.factor.pivot_floor`, ``10 eps n max|A_kk|``."""
    LW = len(lanes)
    n = TI[1]
    ap, wa = small(TI[I_ANCPTR]), small(TI[W_A])
    for l in range(LW):
        T[LW + l] = 0.0
    for k in range(n):
        r = wa + small(TI[ap + k + 1] - 1)
        for l in range(LW):
            a = abs(WL[r * LW + l])
            T[LW + l] = a if a > T[LW + l] else T[LW + l]
    for l in range(LW):
        T[l] = 10.0 * EPS * max(T[LW + l], 1e-300) * n


@ieee
def _eliminate(K, A1, A2, t, T, lanes):
    """Eliminate the pivot of row ``K`` (its slots ``0..t``) from its ancestor rows ``A1`` (slot ``t``) and
    ``A2`` (slot ``t - 1``), every lane, the pivots in ``T[3]``: the row kernel's two-at-a-time update (E47)."""
    LW = len(lanes)
    t = small(t)
    for l in range(LW):
        D = T[3 * LW + l]
        T[LW + l] = K[t * LW + l] / D
        T[2 * LW + l] = K[(t - 1) * LW + l] / D
    for u in range(t):
        for l in range(LW):
            w = K[u * LW + l]
            A1[u * LW + l] = A1[u * LW + l] - T[LW + l] * w
            A2[u * LW + l] = A2[u * LW + l] - T[2 * LW + l] * w
    for l in range(LW):
        A1[t * LW + l] = A1[t * LW + l] - T[LW + l] * K[t * LW + l]
        K[t * LW + l] = T[LW + l]
        K[(t - 1) * LW + l] = T[2 * LW + l]


@one_signature
@ieee
def _eliminate_one(K, A1, T, LW):
    """The last single ancestor (slot 0) of :func:`_eliminate`."""
    for l in range(LW):
        x1 = K[l] / T[3 * LW + l]
        A1[l] = A1[l] - x1 * K[l]
        K[l] = x1


@kernel
def lane_ltdl(TI, WL, T, ST, lanes):
    """``A = L^T D L`` in place of every lane's packed ``A`` (E47), the operations of
    :func:`~urdf2links.dynamics.factor.ltdl` in its order. ``T`` (4, LW) scratch; ``ST`` (LW,) int64 the
    lanes' status: -1 in, the first failing coordinate (from the leaves) of a lane out."""
    LW = len(lanes)
    n = TI[1]
    ap, ar, wa = small(TI[I_ANCPTR]), small(TI[I_ANCROW]), small(TI[W_A])
    _floors(TI, WL, T, lanes)
    for kk in range(n):
        k = small(n - 1 - kk)
        r0 = small(TI[ap + k])
        rk = wa + r0
        last = small(TI[ap + k + 1] - r0 - 1)
        _pivots(WL, rk + last, k, T, ST, LW)
        t = last - 1
        while t >= 1:
            _eliminate(rows(WL, rk, t + 1, LW), rows(WL, wa + small(TI[ar + r0 + t]), t + 1, LW),
                       rows(WL, wa + small(TI[ar + r0 + t - 1]), t, LW), t, T, lanes)
            t -= 2
        if t == 0:
            _eliminate_one(rows(WL, rk, 1, LW), rows(WL, wa + small(TI[ar + r0]), 1, LW), T, LW)


@one_signature
@kernel
def _update(y, a, x, LW):
    """``y -= a x``, lane by lane (one row each)."""
    for l in range(LW):
        y[l] = y[l] - a[l] * x[l]


@one_signature
@ieee
def _divide(y, a, LW):
    for l in range(LW):
        y[l] = y[l] / a[l]


@kernel
def lane_solve(TI, WL, XL, lanes):
    """Solve ``L^T D L y = x`` in place in every lane after :func:`lane_ltdl`; ``XL`` (n, LW)
    (:func:`~urdf2links.dynamics.factor.ltdl_solve`'s operations in its order)."""
    LW = len(lanes)
    n = TI[1]
    ap, ai, rp, rs = small(TI[I_ANCPTR]), small(TI[I_ANCIDX]), small(TI[I_RUNPTR]), small(TI[I_RUNS])
    wa = small(TI[W_A])
    for kk in range(n):                     # L^T z = x: from the leaves
        k = small(n - 1 - kk)
        r0 = small(TI[ap + k])
        run = TI[rp + k + 1] - TI[rp + k] == 1
        c0 = small(TI[rs + 2 * small(TI[rp + k])])
        xk = rows(XL, k, 1, LW)
        for u in range(small(TI[ap + k + 1] - 1 - r0)):
            c = c0 + u if run else small(TI[ai + r0 + u])
            _update(rows(XL, c, 1, LW), rows(WL, wa + r0 + u, 1, LW), xk, LW)
    for k in range(n):                      # D, then L y = z: from the root
        r0 = small(TI[ap + k])
        m = small(TI[ap + k + 1] - 1 - r0)
        run = TI[rp + k + 1] - TI[rp + k] == 1
        c0 = small(TI[rs + 2 * small(TI[rp + k])])
        xk = rows(XL, k, 1, LW)
        _divide(xk, rows(WL, wa + r0 + m, 1, LW), LW)
        for u in range(m):
            c = c0 + u if run else small(TI[ai + r0 + u])
            _update(xk, rows(WL, wa + r0 + u, 1, LW), rows(XL, c, 1, LW), LW)

"""Solving ``A q'' = rhs`` (docs/equations.md (E46), (E47)): the tree-sparse factorization and the dense Cholesky.

:func:`ltdl` factorizes the mass matrix as packed by :func:`urdf2links.dynamics.kernels.dynamics` (row ``i``
holds the coordinates ``anc_idx[anc_ptr[i]:anc_ptr[i + 1]]``: the ancestors of ``i`` and ``i``
itself) into ``A = L^T D L``, eliminating from the leaves to the root. Eliminating a coordinate
updates only pairs of its ancestors, which are already stored, so there is no fill-in: the cost
is the sum over coordinates of (depth)^2 / 2 instead of n^3 / 6 (a chain is dense either way;
a humanoid's limbs are not). This is MuJoCo's ``mj_factorM``. The ancestors of an ancestor of
``k`` are a prefix of ``k``'s own row, so the inner update runs over two contiguous runs.

:func:`cholesky` / :func:`cholesky_solve` are the dense ``A = L L^T`` for a matrix that is not
tree-sparse (coupled coordinates, ``C^T A C``). Both flag a pivot at or below the rounding level
of ``A`` (``10 eps n max|A_ii|``) as a zero eigenvalue and return its index (else -1).
"""

from __future__ import annotations

import numpy as np

from ..compilation import kernel, one_signature

from .tree_arrays import I_ANCIDX, I_ANCPTR, I_ANCROW, I_RUNPTR, I_RUNS, W_A, nonneg

__all__ = ["ltdl", "ltdl_solve", "unpack", "cholesky", "cholesky_solve", "pivot_floor"]

EPS = 2.220446049250313e-16


@one_signature
@kernel
def pivot_floor(scale, n):
    """The rounding level of a matrix whose largest diagonal entry is ``scale``: ``10 eps n scale``."""
    return 10.0 * EPS * max(scale, 1e-300) * n


@one_signature
@kernel
def ltdl(TI, W):
    """``A = L^T D L`` in place of the packed ``A`` (E47): ``D[k]`` on the diagonal slot of row ``k``,
    ``L[k, i]`` (unit lower triangular) on its other slots. Returns -1, or the first coordinate (from
    the leaves) whose pivot ``D[k]`` is at or below :func:`pivot_floor`."""
    n = TI[1]
    ap, ar, wa = nonneg(TI[I_ANCPTR]), nonneg(TI[I_ANCROW]), nonneg(TI[W_A])
    scale = 0.0
    for k in range(n):
        a = abs(W[wa + nonneg(TI[ap + k + 1] - 1)])
        if a > scale:
            scale = a
    tiny = pivot_floor(scale, n)
    for kk in range(n):
        k = nonneg(n - 1 - kk)
        r0 = nonneg(TI[ap + k])
        rk = wa + r0
        last = nonneg(TI[ap + k + 1] - r0 - 1)     # the diagonal's slot in row k
        D = W[rk + last]
        if not D > tiny:
            return k
        # eliminate k from its ancestors i = anc(k)[t], t descending; row i is anc(k)[0..t], so the
        # update of row i is W[row(i) + u] -= L[k, i] W[rk + u], u <= t. Two ancestors at a time
        # (rows i and i' do not overlap: the same operations as one at a time, in fewer loops).
        t = last - 1
        while t >= 1:
            r1 = wa + nonneg(TI[ar + r0 + t])
            r2 = wa + nonneg(TI[ar + r0 + t - 1])
            x1 = W[rk + t] / D
            x2 = W[rk + t - 1] / D
            for u in range(t):
                w = W[rk + u]
                W[r1 + u] -= x1 * w
                W[r2 + u] -= x2 * w
            W[r1 + t] -= x1 * W[rk + t]
            W[rk + t] = x1
            W[rk + t - 1] = x2
            t -= 2
        if t == 0:
            r1 = wa + nonneg(TI[ar + r0])
            x1 = W[rk] / D
            W[r1] -= x1 * W[rk]
            W[rk] = x1
    return -1


@one_signature
@kernel
def ltdl_solve(TI, W, x, ix):
    """Solve ``L^T D L y = x[ix:ix + n]`` in place after :func:`ltdl`. A row whose coordinates are
    one run of consecutive ones (``runs`` of :mod:`urdf2links.dynamics.tree_arrays`: every row of a chain)
    is indexed directly, the others through ``anc_idx``."""
    n = TI[1]
    ap, ai, rp, rs = nonneg(TI[I_ANCPTR]), nonneg(TI[I_ANCIDX]), nonneg(TI[I_RUNPTR]), nonneg(TI[I_RUNS])
    wa, ix = nonneg(TI[W_A]), nonneg(ix)
    for kk in range(n):                     # L^T z = x: from the leaves
        k = nonneg(n - 1 - kk)
        r0 = nonneg(TI[ap + k])
        m = nonneg(TI[ap + k + 1] - 1 - r0)     # the row without its diagonal
        j = wa + r0
        xk = x[ix + k]
        if TI[rp + k + 1] - TI[rp + k] == 1:
            c0 = ix + nonneg(TI[rs + 2 * nonneg(TI[rp + k])])
            for u in range(m):
                x[c0 + u] -= W[j + u] * xk
        else:
            for u in range(m):
                x[ix + nonneg(TI[ai + r0 + u])] -= W[j + u] * xk
    for k in range(n):                      # D, then L y = z: from the root
        r0 = nonneg(TI[ap + k])
        m = nonneg(TI[ap + k + 1] - 1 - r0)
        j = wa + r0
        v = x[ix + k] / W[j + m]
        if TI[rp + k + 1] - TI[rp + k] == 1:
            c0 = ix + nonneg(TI[rs + 2 * nonneg(TI[rp + k])])
            for u in range(m):
                v -= W[j + u] * x[c0 + u]
        else:
            for u in range(m):
                v -= W[j + u] * x[ix + nonneg(TI[ai + r0 + u])]
        x[ix + k] = v


@one_signature
@kernel
def unpack(TI, W, A):
    """The packed ``A`` (before :func:`ltdl`) as a dense symmetric matrix into ``A`` (n, n); pairs
    that are not ancestor pairs are zero (E25)."""
    n = TI[1]
    ap, ai, wa = nonneg(TI[I_ANCPTR]), nonneg(TI[I_ANCIDX]), nonneg(TI[W_A])
    for i in range(n):
        for l in range(n):
            A[i, l] = 0.0
    for i in range(n):
        j0 = nonneg(TI[ap + i])
        for u in range(TI[ap + i + 1] - j0):
            j = j0 + u
            l = nonneg(TI[ai + j])
            A[i, l] = W[wa + j]
            A[l, i] = W[wa + j]


@one_signature
@kernel
def cholesky(A, a0, n, Lf, l0):
    """Dense ``A = L L^T`` of the (n, n) row-major ``A[a0:]`` into ``Lf[l0:]`` (lower triangle).
    Returns -1, or the index of the first pivot at or below :func:`pivot_floor` (E46)."""
    a0, l0 = nonneg(a0), nonneg(l0)
    scale = 0.0
    for i in range(n):
        if abs(A[a0 + i * n + i]) > scale:
            scale = abs(A[a0 + i * n + i])
    tiny = pivot_floor(scale, n)
    for j in range(n):
        rj = l0 + j * n
        d = A[a0 + j * n + j]
        for k in range(j):
            d -= Lf[rj + k] * Lf[rj + k]
        if not d > tiny:
            return j
        d = np.sqrt(d)
        Lf[rj + j] = d
        for i in range(j + 1, n):
            ri = l0 + i * n
            v = A[a0 + i * n + j]
            for k in range(j):
                v -= Lf[ri + k] * Lf[rj + k]
            Lf[ri + j] = v / d
    return -1


@one_signature
@kernel
def cholesky_solve(Lf, l0, n, x, x0):
    """Solve ``L L^T y = x[x0:x0 + n]`` in place after :func:`cholesky`."""
    l0, x0 = nonneg(l0), nonneg(x0)
    for i in range(n):
        v = x[x0 + i]
        for k in range(i):
            v -= Lf[l0 + i * n + k] * x[x0 + k]
        x[x0 + i] = v / Lf[l0 + i * n + i]
    for i in range(n - 1, -1, -1):
        v = x[x0 + i]
        for k in range(i + 1, n):
            v -= Lf[l0 + k * n + i] * x[x0 + k]
        x[x0 + i] = v / Lf[l0 + i * n + i]

"""Dense LU factorisation with partial pivoting, real or complex, compiled with numba.

The implicit loop (:mod:`urdf2links.integration.loops.radau`) factors its two iteration matrices
once and solves with them over many Newton iterations and steps; numba has no ``lu_factor``, so the
factorisation is kept here in place (the ``L`` multipliers below the diagonal, ``U`` on and above
it, row interchanges in ``piv``), in the order LAPACK's ``getrf`` applies them. One source serves
``float64`` and ``complex128`` matrices (numba compiles one version for each); the interpreter runs
the same functions on numpy arrays (the loops' interpreted twin).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ...compilation import one_signature

__all__ = ["lu_factor", "lu_solve"]


@one_signature
@njit(cache=True)
def lu_factor(A, piv):
    """``A`` (m, m) <- its LU factors with partial pivoting, ``piv`` (m,) int64 the row swapped
    with row ``k`` at step ``k``. Returns -1, or the step ``k`` whose pivot is zero or not finite
    (``A`` is then singular or broken and must not be solved with)."""
    m = A.shape[0]
    for k in range(m):
        p = k
        big = abs(A[k, k])
        for i in range(k + 1, m):
            v = abs(A[i, k])
            if v > big:
                big, p = v, i
        piv[k] = p
        if big == 0.0 or not np.isfinite(big):
            return k
        if p != k:
            for j in range(m):
                a = A[k, j]
                A[k, j] = A[p, j]
                A[p, j] = a
        inv = 1.0 / A[k, k]
        for i in range(k + 1, m):
            lik = A[i, k] * inv
            A[i, k] = lik
            if lik != 0.0:
                for j in range(k + 1, m):
                    A[i, j] -= lik * A[k, j]
    return -1


@one_signature
@njit(cache=True)
def lu_solve(A, piv, b):
    """``b`` (m,) <- ``M^-1 b`` for the factors ``A``, ``piv`` of :func:`lu_factor` (same kind:
    a complex ``b`` for complex factors)."""
    m = A.shape[0]
    for k in range(m):
        p = piv[k]
        if p != k:
            v = b[k]
            b[k] = b[p]
            b[p] = v
    for i in range(m):
        s = b[i]
        for j in range(i):
            s -= A[i, j] * b[j]
        b[i] = s
    for i in range(m - 1, -1, -1):
        s = b[i]
        for j in range(i + 1, m):
            s -= A[i, j] * b[j]
        b[i] = s / A[i, i]

"""Lagrange's equations with multipliers: the KKT solve, redundant rows, projection onto the constraints.

docs/equations.md (E72)-(E74). With ``Phi_q`` = ``J`` (m, n) and ``gamma = Phi_q' q'`` from
:class:`~urdf2links.dynamics.constraints.ConstraintSet`, and ``f = Q - e - G`` the unconstrained
right-hand side of (E24) (every force a scene names):

- (E72) ``[A J^T; J 0] [q''; -lambda] = [f; -gamma]``, so ``A q'' = f + J^T lambda`` and
  ``Phi'' = J q'' + gamma = 0``; ``J^T lambda`` is the constraint's generalized force, ``lambda`` its
  force (N, or N m on a ``weld``'s orientation rows; a ``joint`` row's in the units of ``q_a``'s
  generalized force). Solved by block elimination, which is that system's exact solution: ``A = L L^T``,
  ``Y = L^-1 J^T``, the Schur complement ``S = J A^-1 J^T = Y^T Y`` by Cholesky, ``lambda = S^-1 (-gamma -
  J A^-1 f)``, ``q'' = A^-1 (f + J^T lambda)``. A pivot of ``S`` below ``1e-12`` of its largest diagonal
  means the rows are no longer independent (a singular configuration of the loop): a
  :class:`~urdf2links.errors.DynamicsError` names the rows, the pivot and the state.
- (E73) redundant rows: a pivoted QR of ``J^T`` at the initial state, rank by ``|R_kk| > 1e-9
  |R_00|``; the rows past the rank are combinations of the others (a planar loop closed by a
  ``connect`` has one: the out-of-plane row is identically zero), named, and left out of the solve
  (their residual is still reported).
- (E74) projection onto ``Phi = 0``, ``Phi' = 0`` (the mass-weighted least change):
  ``q <- q - A^-1 J^T S^-1 Phi`` repeated (Gauss-Newton) until ``|Phi| <= tol``, then
  ``q' <- q' - A^-1 J^T S^-1 J q'``. The velocity projection removes only the part of ``q'``
  that violates the constraint in the metric of ``A``, so it never increases the kinetic energy.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import DynamicsError

__all__ = ["RowSelection", "independent_rows", "kkt_solve", "kkt_matrix", "project_position", "project_velocity",
           "Projection", "SCHUR_PIVOT", "RANK_TOL"]

SCHUR_PIVOT = 1e-12     # a Schur pivot below this fraction of max diag(S): the rows are dependent there
RANK_TOL = 1e-9         # |R_kk| <= RANK_TOL |R_00| in the pivoted QR of J^T: a redundant row (E73)


@dataclass(frozen=True)
class RowSelection:
    """``keep``: indices of the independent rows; ``redundant``: the others; ``rank``; ``notes`` one
    sentence per redundant row."""

    keep: np.ndarray
    redundant: np.ndarray
    rank: int
    notes: tuple[str, ...]


def independent_rows(J: np.ndarray, rows) -> RowSelection:
    """Which rows of ``J`` (m, n) are independent (E73): pivoted QR of ``J^T``."""
    m = J.shape[0]
    if m == 0:
        return RowSelection(np.zeros(0, int), np.zeros(0, int), 0, ())
    import scipy.linalg as sla      # here: 0.16 s of import that only constrained scenes need

    _, R, piv = sla.qr(J.T, mode="economic", pivoting=True)
    d = np.abs(np.diag(R))
    scale = d[0] if d.size else 0.0
    rank = int(np.sum(d > RANK_TOL * scale)) if scale > 0 else 0
    keep, red = np.sort(piv[:rank]), np.sort(piv[rank:])
    notes = tuple(f"constraint row {rows[k]!r} is redundant: a combination of the other rows at the initial state "
                  f"(Phi_q has rank {rank} of {m} rows); left out of the solve, its residual still reported"
                  for k in red)
    return RowSelection(keep, red, rank, notes)


def kkt_matrix(A, J):
    """``[A J^T; J 0]`` (n + m, n + m) (E72), for checks."""
    n, m = A.shape[0], J.shape[0]
    K = np.zeros((n + m, n + m))
    K[:n, :n], K[:n, n:], K[n:, :n] = A, J.T, J
    return K


def _schur(A, J, rows, where):
    """Cholesky factors of ``A`` and of ``S = J A^-1 J^T``, and ``Y = L^-1 J^T`` (E72)."""
    L = np.linalg.cholesky(A)
    Y = np.linalg.solve(L, J.T)       # small systems: numpy's solve (scipy's triangular one costs ~1 ms a call here)
    S = Y.T @ Y
    scale = max(float(np.max(np.diag(S))), 1e-300) if S.size else 1.0
    try:
        Ls = np.linalg.cholesky(S)
        bad = np.nonzero(np.diag(Ls) ** 2 <= SCHUR_PIVOT * scale)[0]
    except np.linalg.LinAlgError:
        Ls, bad = None, np.array([0])
    if Ls is None or bad.size:
        w, V = np.linalg.eigh(S)
        involved = [rows[k] for k in np.nonzero(np.abs(V[:, 0]) > 0.1 * np.abs(V[:, 0]).max())[0]]
        raise DynamicsError(f"{where}: the constraint rows {', '.join(involved)} are not independent here "
                            f"(smallest eigenvalue of J A^-1 J^T {w[0]:.3g}, {w[0] / scale:.2g} of its largest "
                            f"diagonal): a singular configuration of the loop, where the multipliers are not "
                            f"determined; start away from it, or remove one of those rows")
    return L, Y, Ls


def kkt_solve(A, f, J, gamma, *, rows=(), where="constrained solve"):
    """``(q'', lambda, S)`` of (E72) by block elimination; ``S`` the Schur complement's Cholesky factor."""
    if J.shape[0] == 0:
        return np.linalg.solve(A, f), np.zeros(0), None
    L, Y, Ls = _schur(A, J, rows or [str(k) for k in range(J.shape[0])], where)
    z = np.linalg.solve(L, f)                                   # L^-1 f
    lam = _cho(Ls, -gamma - Y.T @ z)                            # S lambda = -gamma - J A^-1 f
    qdd = np.linalg.solve(L.T, z + Y @ lam)                     # A q'' = f + J^T lambda
    return qdd, lam, Ls


@dataclass(frozen=True)
class Projection:
    """A state projected (E74): ``q``, ``qd``, ``iterations`` of Gauss-Newton, ``residual`` max |Phi| after,
    ``moved`` |dq| and ``velocity_change`` |dqd| (max norms)."""

    q: np.ndarray
    qd: np.ndarray
    iterations: int
    residual: float
    moved: float
    velocity_change: float


def _correction(A, J, x, rows, where):
    """``A^-1 J^T S^-1 x``."""
    L, Y, Ls = _schur(A, J, rows, where)
    return _cho(L, J.T @ _cho(Ls, x))


def _cho(L, b):
    """``(L L^T)^-1 b``."""
    return np.linalg.solve(L.T, np.linalg.solve(L, b))


def project_position(q, terms_of, mass_of, keep, *, tol=1e-13, max_iter=30, rows=(), where="projection"):
    """Gauss-Newton onto ``Phi = 0`` (E74); ``terms_of(q)`` gives :class:`ConstraintTerms`, ``mass_of(q)`` A.
    Returns ``(q, iterations, residual)``; stops when ``max |Phi|`` (all rows) is at most ``tol``, or
    stops decreasing."""
    q = np.array(q, float)
    A = mass_of(q)
    last = np.inf
    for it in range(max_iter + 1):
        T = terms_of(q)
        res = float(np.max(np.abs(T.phi))) if T.phi.size else 0.0
        if res <= tol or res >= last or it == max_iter:
            return q, it, res
        last = res
        q = q - _correction(A, T.J[keep], T.phi[keep], [rows[k] for k in keep] if rows else (), where)
    return q, max_iter, res


def project_velocity(qd, J, A, *, rows=(), where="projection"):
    """``q' - A^-1 J^T S^-1 J q'`` (E74): the constrained velocity nearest in the metric of A."""
    if J.shape[0] == 0:
        return np.array(qd, float)
    return qd - _correction(A, J, J @ qd, rows, where)

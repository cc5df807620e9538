"""DESCRIPTION's parameters fitted to OTHER's recorded motion: base parameters, the fit, the parameter table.

The equations (docs/identify.md, "The command"): every recorded sample ``s`` and coordinate ``j`` gives one
row ``tau_sj = Y_sj pi``. Rows where ``|q'_sj| < band`` are left out: there MuJoCo's frictionloss (a soft
constraint, linear in ``q'`` near 0) and the regularised Coulomb law of the fit differ; everywhere else
both are ``f sign(q')`` (to ``exp(-2 band / eps)``).

Base parameters by pivoted QR of the column-scaled ``Y`` (a column of rounding only, :data:`ZERO_COLUMN`, is zero:
scaled, it would look independent) (numerical rank at :data:`RANK_TOL`): the
independent columns ``B`` and the rest ``D`` with ``Y_D = Y_B K``, so ``Y pi = Y_B beta``, ``beta = pi_B +
K pi_D``: each base parameter is one named combination. ``beta`` by least squares; the identified ``pi``
is the description's moved so that it has the fitted ``beta`` with the fewest, smallest moves (least sum of
``|column scale x move|``, masses, damping, friction and armature kept >= 0: a linear program): what the data
cannot identify stays at the description's unless a fitted combination asks for it; a move below :data:`CHANGED` (relative) or :data:`NEGLIGIBLE` (absolute) is rounding, and
the description's value stays. Standard deviations from ``sigma^2 (Y_B^T Y_B)^-1``, ``sigma^2`` the residual
variance (0 for noise-free data: then they say the rounding).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg import qr, solve_triangular


__all__ = ["Fit", "BaseParameters", "base_parameters", "fit", "FRICTION_BAND", "RANK_TOL", "rows_of"]

#: Rows with ``|q'| <`` this (rad/s or m/s) left out (module doc).
FRICTION_BAND = 0.05
#: Numerical rank: ``|R_ii| / |R_00|`` of the column-scaled QR below this is dependent.
RANK_TOL = 1e-9
#: A column whose norm is below this fraction of the largest is zero (rounding of a term that vanishes exactly).
ZERO_COLUMN = 1e-10
#: A parameter "changed" when it moved more than this relative to its size and more than :data:`NEGLIGIBLE`
#: (SI units: kg, kg m, kg m^2, N m s, N m); a smaller move is the fit's rounding, and the description's value stays.
CHANGED = 1e-6
NEGLIGIBLE = 1e-9


@dataclass(frozen=True)
class BaseParameters:
    """``independent`` (r,) and ``dependent`` (P - r,) column indices, ``K`` (r, P - r), ``names`` (r,) the
    combinations in words, ``condition`` the condition number of the column-scaled base regressor."""

    independent: np.ndarray
    dependent: np.ndarray
    K: np.ndarray
    names: tuple[str, ...]
    condition: float

    def of(self, pi) -> np.ndarray:
        """``beta = pi_B + K pi_D`` (r,)."""
        pi = np.asarray(pi, float)
        return pi[self.independent] + self.K @ pi[self.dependent]


def rows_of(Y, tau, qd, *, band: float = FRICTION_BAND) -> tuple[np.ndarray, np.ndarray]:
    """The rows ``(S n, P)``, ``(S n,)`` of the samples kept (module doc)."""
    keep = (np.abs(qd) >= band).reshape(-1)
    return Y.reshape(-1, Y.shape[-1])[keep], np.asarray(tau).reshape(-1)[keep]


def _name(labels, i: int, dependent, k_row) -> str:
    words = [labels[i]]
    for d, k in zip(dependent, k_row):
        if abs(k) > 1e-10:
            words.append(f"{'+' if k > 0 else '-'} {abs(k):.4g} {labels[d]}" if abs(abs(k) - 1) > 1e-10
                         else f"{'+' if k > 0 else '-'} {labels[d]}")
    return " ".join(words)


def base_parameters(labels, A) -> BaseParameters:
    """The base parameters of the rows ``A`` (R, P) (module doc)."""
    scale = np.linalg.norm(A, axis=0)
    used = scale > ZERO_COLUMN * np.max(scale)      # a column of rounding only (a mass on both axes of a shoulder)
    scale = np.where(used, scale, 0.0)
    As = np.where(used, A / np.where(used, scale, 1.0), 0.0)
    R0 = np.linalg.qr(As, mode="r")                              # (P, P): the same column geometry, cheaper
    _Q, R, perm = qr(R0, mode="economic", pivoting=True)
    diag = np.abs(np.diag(R))
    r = int(np.sum(diag > RANK_TOL * diag[0]))
    B, D = perm[:r], perm[r:]
    Ks = solve_triangular(R[:r, :r], R[:r, r:])                  # scaled: As_D = As_B Ks
    K = Ks * scale[D][None, :] / scale[B][:, None] if len(D) else np.zeros((r, 0))
    K[np.abs(K) < 1e-12 * max(1.0, np.max(np.abs(K), initial=0.0))] = 0.0
    cond = float(np.linalg.cond(R0[:, B]))
    order = np.argsort(B)
    B, K = B[order], K[order]
    names = tuple(_name(labels, int(i), D, K[k]) for k, i in enumerate(B))
    return BaseParameters(B, D, K, names, cond)


@dataclass(frozen=True, eq=False)
class Fit:
    """The fit's result: ``parameters`` (:class:`urdf2links.identification.ParameterSet`), ``described`` and ``identified`` pi (P,), ``std`` (P,) (NaN where
    not identifiable), ``identifiable`` (P,) bool (an independent column), ``changed`` (P,) bool, ``base``
    (:class:`BaseParameters`), ``beta`` (r,) and ``beta_std``, ``rows`` used, ``residual_rms``."""

    parameters: object
    described: np.ndarray
    identified: np.ndarray
    std: np.ndarray
    identifiable: np.ndarray
    changed: np.ndarray
    base: BaseParameters
    beta: np.ndarray
    beta_std: np.ndarray
    rows: int
    residual_rms: float

    def link_H(self, which: str = "identified") -> np.ndarray:
        """(L, 4, 4) the links' H of ``described`` or ``identified`` pi."""
        return self.parameters.H(getattr(self, which))

    def min_eigenvalues(self, which: str = "identified") -> np.ndarray:
        """(L,) the smallest eigenvalue of each tree link's H (> 0: physically consistent; massless links: 0)."""
        return np.array([np.linalg.eigvalsh(H)[0] for H in self.link_H(which)])

    def rows_table(self) -> list[dict]:
        """The parameter table, one dict per parameter."""
        out = []
        for i, label in enumerate(self.parameters.names):
            out.append({"parameter": label, "described": float(self.described[i]),
                        "identified": float(self.identified[i]),
                        "std": None if not np.isfinite(self.std[i]) else float(self.std[i]),
                        "identifiable": bool(self.identifiable[i]), "changed": bool(self.changed[i])})
        return out


def _lower_bounds(params) -> np.ndarray:
    """(P,) 0 for masses and the joints' damping, friction and armature; -inf for the rest."""
    names = params.names
    return np.array([0.0 if (k in ("damping", "friction", "armature") or (k == "link" and nm.startswith("m_")))
                     else -np.inf for k, nm in zip(params.kind, names)])


def _fewest_moves(base: BaseParameters, dbeta, scale, described, lower) -> np.ndarray:
    """The move ``d`` (P,) of least ``sum |scale_i d_i|`` (a linear program: few parameters move, each weighed by
    what it does to the torques) with ``beta(pi + d) = beta(pi) + dbeta`` and ``pi + d >= lower`` (masses,
    damping, friction, armature not negative). Along what the data cannot identify nothing moves unless the
    fitted combinations ask for it. Falls back to ``pi_B = beta - K pi_D`` when the program finds no solution."""
    from scipy.optimize import linprog

    P = len(scale)
    M = np.zeros((len(dbeta), P))
    M[:, base.independent] = np.eye(len(dbeta))
    M[:, base.dependent] = base.K
    s = np.where(scale > ZERO_COLUMN * np.max(scale), scale, 1.0)
    lo = np.where(np.isfinite(lower), lower - described, -np.inf)
    # d = (u - v) / s with u, v >= 0: minimise sum(u + v)
    bounds = [(0, None)] * (2 * P)
    A_ub = np.hstack([-np.eye(P) / s[:, None], np.eye(P) / s[:, None]])       # -(u - v)/s <= -lo
    keep = np.isfinite(lo)
    res = linprog(np.ones(2 * P), A_ub=A_ub[keep], b_ub=-lo[keep], A_eq=np.hstack([M / s, -M / s]), b_eq=dbeta,
                  bounds=bounds, method="highs")
    if res.status != 0:
        d = np.zeros(P)
        d[base.independent] = dbeta
        return d
    return (res.x[:P] - res.x[P:]) / s


def fit(params, A, b) -> Fit:
    """The fit of the rows ``A`` (R, P), ``b`` (R,) (module doc), from the description's pi (``params.values``)."""
    described = np.asarray(params.values, float)
    p = params.names
    base = base_parameters(p, A)
    YB = A[:, base.independent]
    scale = np.linalg.norm(YB, axis=0)
    x, *_ = np.linalg.lstsq(YB / scale, b, rcond=None)
    beta = x / scale
    res = b - YB @ beta
    dof = max(len(b) - len(beta), 1)
    sigma2 = float(res @ res) / dof
    cov = sigma2 * np.linalg.inv((YB / scale).T @ (YB / scale)) / np.outer(scale, scale)
    beta_std = np.sqrt(np.maximum(np.diag(cov), 0.0))
    identified = described + _fewest_moves(base, beta - base.of(described), np.linalg.norm(A, axis=0), described,
                                           _lower_bounds(params))
    std = np.full(len(p), np.nan)
    std[base.independent] = beta_std
    identifiable = np.zeros(len(p), bool)
    identifiable[base.independent] = True
    size = np.maximum(np.abs(described), np.abs(identified))
    changed = np.abs(identified - described) > np.maximum(CHANGED * size, NEGLIGIBLE)
    identified = np.where(changed, identified, described)
    return Fit(params, described, identified, std, identifiable, changed, base, beta, beta_std, len(b),
               float(np.sqrt(np.mean(res**2))))

"""Weighted least squares of base parameters with the noise estimated from the residual (docs/equations.md (E96)).

A robot's log has noise whose level nobody states: each joint's torque sensor has its own. The fit
(:func:`weighted_fit`) is iterated: ordinary least squares, then each row kind's noise ``sigma_j`` (a
joint's torque row, or a floating base's row) from its residual, then least squares weighted by
``1 / sigma_j``, the noise estimated again from the new residual. The covariance of the base parameters is
``C = G^-1`` with ``G = sum_t Y_t^T W Y_t`` (``W = diag(1 / sigma_j^2)``), or, when the residual is
correlated over ``lags`` samples (the positions' filter correlates the regressor's own noise over its
window), the sandwich ``G^-1 B G^-1`` with Newey-West's ``B = sum_{|l| <= L} (1 - |l| / (L + 1)) sum_t u_t
u_(t+l)^T``, ``u_t = Y_t^T W e_t`` (E96). Standard deviations are the square roots of C's diagonal and the
95% intervals ``beta +- 1.96 std``.

The intervals assume the regressor exact. It is not: the velocities and accelerations carry the filtered
position noise. Perturbation theory bounds the relative error of the solution by the condition number
times the regressor's relative error; :func:`weighted_fit` states that product (``error_bound``) and warns
when it passes 1 (the bound allows an error as large as the parameters) or the condition number passes 1e6: the intervals are then meaningless.

Shapes: ``Y`` (S, m, r) the base columns per sample and row kind, ``y`` (S, m), batch axis first.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["WeightedFit", "weighted_fit", "Z95", "COND_WARN", "BOUND_WARN"]

#: the normal distribution's two-sided 95% quantile
Z95 = 1.959963984540054
#: the condition number past which the intervals are called meaningless whatever the noise
COND_WARN = 1e6
#: the bound (condition number x the regressor's relative error) past which they are
BOUND_WARN = 1.0


@dataclass(frozen=True, eq=False)
class WeightedFit:
    """``beta`` (r,) the base parameters, ``covariance`` (r, r), ``std`` (r,), ``intervals`` (r, 2) 95%;
    ``sigma`` (m,) each row kind's noise estimated from the residual; ``rms`` (m,) the residual's root mean
    square per row kind; ``condition_number`` of the weighted base regressor (columns scaled to unit norm);
    ``error_bound`` the condition number times the regressor's relative error (or None when not given);
    ``lags`` the sandwich's correlation length (0: white residual); ``warnings``; ``samples`` S."""

    beta: np.ndarray
    covariance: np.ndarray
    std: np.ndarray
    intervals: np.ndarray
    sigma: np.ndarray
    rms: np.ndarray
    condition_number: float
    error_bound: float | None
    lags: int
    warnings: tuple
    samples: int

    def covers(self, beta_true) -> np.ndarray:
        """(r,) bool: the 95% interval holds ``beta_true``."""
        b = np.asarray(beta_true, float)
        return (self.intervals[:, 0] <= b) & (b <= self.intervals[:, 1])

    def summary(self) -> dict:
        return {"samples": self.samples, "sigma": self.sigma.tolist(), "rms": self.rms.tolist(),
                "condition_number": self.condition_number, "error_bound": self.error_bound, "lags": self.lags,
                "warnings": list(self.warnings)}


def _solve(Yw, yw):
    """Least squares of the stacked weighted rows by the normal equations, columns scaled to unit norm (the
    units differ by decades): (beta, G^-1, cond). The condition number is the square root of the scaled
    normal matrix's; rank deficiency raises ValueError."""
    d = np.linalg.norm(Yw, axis=0)
    d[d == 0] = 1.0
    Ys = Yw / d
    lam, V = np.linalg.eigh(Ys.T @ Ys)
    if lam[0] <= 1e-14 * lam[-1]:
        raise ValueError("the base regressor is rank deficient on these rows: the base parameters come from other "
                         "data; recompute them on this log")
    Ginv = (V / lam) @ V.T
    x = Ginv @ (Ys.T @ yw)
    return x / d, Ginv / np.outer(d, d), float(np.sqrt(lam[-1] / lam[0]))


def _newey_west(Yw, ew, lags: int) -> np.ndarray:
    """``B`` of the module doc from the weighted rows ``Yw`` (S, m, r) and residuals ``ew`` (S, m). Bartlett's
    weights ``1 - |l| / (L + 1)`` are the autocorrelation of a box of ``L + 1`` samples, so ``B`` is
    ``V^T V / (L + 1)`` with ``V`` the moving sums of ``u`` over ``L + 1`` samples (to the run's ends): one
    product instead of ``L``."""
    u = np.einsum("smr,sm->sr", Yw, ew)
    c = np.concatenate([np.zeros((1, u.shape[1])), np.cumsum(u, axis=0)])
    k = lags + 1
    V = c[k:] - c[:-k]
    return V.T @ V / k


def weighted_fit(Y, y, *, iterations: int = 2, lags: int = 0, relative_error: float | None = None,
                 fixed_sigma=None) -> WeightedFit:
    """The base parameters of ``y = Y beta + e`` (module doc, E96). ``Y`` (S, m, r), ``y`` (S, m);
    ``iterations`` re-weightings after the unweighted start; ``lags`` the residual's correlation length in
    samples (0: white); ``relative_error`` the regressor's relative error from the derivatives' noise (for
    ``error_bound``); ``fixed_sigma`` (m,) with NaN where the noise is estimated, a number where it is known.
    Raises ValueError on shapes that do not agree or a rank-deficient regressor."""
    Y, y = np.asarray(Y, float), np.asarray(y, float)
    if Y.ndim != 3 or y.shape != Y.shape[:2]:
        raise ValueError(f"Y must be (S, m, r) and y (S, m) with the same S, m; got {Y.shape} and {y.shape}")
    S, m, r = Y.shape
    if S * m <= r:
        raise ValueError(f"{S * m} equations for {r} base parameters: more samples are needed")
    fixed = np.full(m, np.nan) if fixed_sigma is None else np.asarray(fixed_sigma, float)
    sigma = np.where(np.isnan(fixed), 1.0, fixed)
    for _ in range(iterations + 1):
        w = 1.0 / sigma
        beta, Ginv, cond = _solve((Y * w[None, :, None]).reshape(S * m, r), (y * w).reshape(-1))
        e = y - np.einsum("smr,r->sm", Y, beta)
        dof = max(S - r / m, 1.0)
        est = np.sqrt(np.sum(e ** 2, axis=0) / dof)
        sigma = np.where(np.isnan(fixed), np.maximum(est, np.finfo(float).tiny), fixed)
    w = 1.0 / sigma
    if lags > 0:
        cov = Ginv @ _newey_west(Y * w[None, :, None], e * w, lags) @ Ginv
    else:
        cov = Ginv * float(np.sum((e * w) ** 2) / max(S * m - r, 1))
    std = np.sqrt(np.maximum(np.diag(cov), 0.0))
    warnings = []
    bound = None if relative_error is None else float(cond * relative_error)
    if cond > COND_WARN:
        warnings.append(f"condition number {cond:.3g} > {COND_WARN:.0e}: the standard deviations and intervals "
                        "are meaningless (the data hardly separate some base parameters); excite the robot more")
    if bound is not None and bound > BOUND_WARN:
        warnings.append(f"condition number {cond:.3g} times the regressor's relative error {relative_error:.2g} "
                        f"(from the derivatives' noise) is {bound:.2g} > {BOUND_WARN}: the intervals, which assume an "
                        "exact regressor, are meaningless; a lower filter cutoff or more excitation would help")
    return WeightedFit(beta=beta, covariance=cov, std=std, intervals=np.stack([beta - Z95 * std, beta + Z95 * std], 1),
                       sigma=sigma, rms=np.sqrt(np.mean(e ** 2, axis=0)), condition_number=cond, error_bound=bound,
                       lags=int(lags), warnings=tuple(warnings), samples=S)

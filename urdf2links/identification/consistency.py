"""Physical consistency: every link's H positive definite, regularised toward the description (docs/equations.md (E92)).

A link is physically consistent exactly when its H is positive definite (E12). The least-squares fit
(:mod:`urdf2links.identification.fit`) does not know that: noise, or a weakly excited link, gives a
negative mass or moments that break the triangle inequalities. The consistent fit solves the
semidefinite program

    minimize   (beta(pi) - beta_ls)^T G (beta(pi) - beta_ls) / (S n)
               + rho * mean(tau^2) * sum_k ((pi_k - pi_desc,k) / s_k)^2
    subject to H_p(pi) >= eps_p 1 (every link),   damping, friction, armature >= 0,

with ``beta(pi) = pi_I + K pi_D`` (E91) and ``G`` the normal equations' matrix, so the first term is the
increase of the torque residual's mean square over the least-squares fit. The second pulls every
parameter, the unidentifiable ones too, toward the description's value with a small weight ``rho``
(``s_k`` the scale of the parameter: the link's mass for ``m``, ``m * 0.1 m`` for a first moment, ``m * 0.01 m^2``
for a planar moment, 1 for a joint's). Here the unidentifiable parameters may move: the data do not see them
and consistency may need them (a mass that must grow for the moments to fit).

Why a semidefinite program through cvxpy (with Clarabel, an interior-point conic solver) rather than a
log-Cholesky parametrisation with scipy: the problem is convex as stated (a quadratic objective, linear
matrix inequalities), so the interior-point solver returns the global optimum with a certificate and
needs no starting point; the log-Cholesky form ``H = U U^T`` with ``U``'s diagonal ``exp(.)`` makes it
non-convex, needs a start inside the cone and cannot reach a semidefinite boundary (a point mass), and
scipy's least squares then converges to a local optimum without a certificate. The program's size does not
grow with the samples (the normal equations hold them): a 7-joint arm (146 parameters, 11 links) solves in
tens of milliseconds. cvxpy and clarabel are the optional extra ``identify`` (pyproject.toml).

:func:`consistent_fit` returns the fit with :class:`Consistency` attached: the consistent values, each
link's smallest eigenvalue of H in the least-squares fit, in the same program solved without its
constraints (a linear solve: what the regularisation alone gives) and in the consistent fit; a link the
constraint moved (it differs from that free solution) gets a sentence saying what moved and why, and so
does a joint term held at zero.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass

import numpy as np

from .parameters import link_matrix

__all__ = ["Consistency", "consistent_fit", "min_eigenvalues"]


@dataclass(frozen=True)
class Consistency:
    """``values`` (p,) the consistent parameters; ``free`` (p,) the same program's solution without the
    constraints (a linear solve: what the regularisation alone does); ``links`` the moving links;
    ``eig_before``, ``eig_free``, ``eig_after`` (links,) each link's smallest eigenvalue of H in the
    least-squares fit, the free solution and the consistent one; ``moved`` the links the constraint moved
    (a parameter differs from the free solution by more than ``tolerance`` of its scale: the constraint was
    active there), with ``notes`` (one sentence each); ``rms_increase`` the torque residual's root mean square
    added over the least-squares fit; ``status`` the solver's; ``seconds`` its time."""

    values: np.ndarray
    links: tuple
    eig_before: np.ndarray
    eig_free: np.ndarray
    eig_after: np.ndarray
    free: np.ndarray
    moved: tuple
    notes: tuple
    rms_increase: float
    status: str
    seconds: float

    def summary(self) -> dict:
        return {"status": self.status, "moved": list(self.moved), "notes": list(self.notes),
                "rms_increase": self.rms_increase, "seconds": self.seconds,
                "all_positive_definite": bool(np.all(self.eig_after > 0))}


def min_eigenvalues(params, values) -> tuple[tuple, np.ndarray]:
    """``(links, smallest eigenvalue of H)`` of every link with parameters, at ``values`` (p,)."""
    v = params.vector(values)
    names = params.model.tree.link_names
    links = tuple(names[p] for p, c in enumerate(params.link_col) if c >= 0)
    eig = np.array([np.linalg.eigvalsh(link_matrix(v[c:c + 10]))[0] for c in params.link_col if c >= 0])
    return links, eig


def _scales(params) -> np.ndarray:
    """``s_k`` (module doc): the link's mass for m, m 0.1 m for first moments, m 0.01 m^2 for planar ones (a
    massless link: 1 kg), 1 for a joint's parameter."""
    s = np.ones(params.p)
    for c in params.link_col:
        if c < 0:
            continue
        m = max(abs(params.values[c + 9]), 1e-3) if params.values[c + 9] > 0 else 1.0
        s[c:c + 6] = 0.01 * m
        s[c + 6:c + 9] = 0.1 * m
        s[c + 9] = m
    return s


def _beta_map(params, base) -> np.ndarray:
    """M (r, p) with ``beta = M pi`` (E91)."""
    M = np.zeros((base.r, params.p))
    M[np.arange(base.r), base.independent] = 1.0
    if base.dependent.size:
        M[:, base.dependent] = base.K
    return M


def _free_solution(params, base, L, beta_ls, lam, s):
    """The program of the module doc without its constraints, in the scaled unknowns ``z`` (``pi = pi_desc +
    s z``): ``(B^T B + lam 1) z = B^T L (beta_ls - M pi_desc)``, ``B = L M diag(s)``."""
    M = _beta_map(params, base)
    B = L @ M * s[None, :]
    z = np.linalg.solve(B.T @ B + lam * np.eye(params.p), B.T @ (L @ (beta_ls - M @ params.values)))
    return params.values + s * z


def consistent_fit(fit, *, regularization: float = 1e-4, margin: float = 1e-9, tolerance: float = 1e-3,
                   solver: str = "CLARABEL"):
    """``fit`` (an :class:`~urdf2links.identification.fit.Identification` with its normal equations) with
    every H positive definite (module doc, E92): the fit returned with ``consistency`` set.
    ``regularization`` rho; ``margin``: ``eps_p = margin * s_m`` (the link's mass scale); ``tolerance``: a
    link is said to be moved when a parameter moved by more than this fraction of its scale. Raises
    ImportError naming the extra when cvxpy is missing, RuntimeError naming the solver's status when it fails."""
    try:
        import cvxpy as cp
    except ImportError as err:     # the optional extra
        raise ImportError("the consistent fit needs cvxpy and clarabel: pip install 'urdf2links[identify]'") from err
    params, base, ne = fit.params, fit.base, fit.normal
    if ne is None:
        raise ValueError("consistent_fit needs the fit's normal equations (an Identification from identify())")
    t0 = time.perf_counter()
    G, _ = ne.weighted(fit.weights)
    Sn = max(ne.samples * params.n, 1)
    d = np.sqrt(np.maximum(np.diag(G), np.finfo(float).tiny))
    L = np.linalg.cholesky(G / np.outer(d, d) + 1e-12 * np.eye(len(d))).T * d[None, :] / np.sqrt(Sn)
    s = _scales(params)
    mean_t2 = float(np.sum(fit.weights ** 2 * ne.t) / Sn)
    # the unknowns scaled: x = pi_desc + s z, z of order 1 (the parameters' units differ by decades)
    M = _beta_map(params, base)
    z = cp.Variable(params.p)
    x = params.values + cp.multiply(s, z)
    objective = cp.sum_squares(L @ (M @ params.values - fit.beta) + (L @ M * s[None, :]) @ z) \
        + regularization * mean_t2 * cp.sum_squares(z)
    E = [link_matrix(np.eye(10)[k]) for k in range(10)]
    cons = []
    for c in params.link_col:
        if c >= 0:
            H = sum(x[c + k] * E[k] for k in range(10))
            cons.append(H >> margin * s[c + 9] * np.eye(4))
    nonneg = [k for k, kd in enumerate(params.kind) if kd in ("damping", "friction", "armature") or
              kd.startswith("tendon_")]
    if nonneg:
        cons.append(x[nonneg] >= 0)
    prob = cp.Problem(cp.Minimize(objective), cons)
    prob.solve(solver=solver)
    if prob.status not in ("optimal", "optimal_inaccurate") or z.value is None:
        raise RuntimeError(f"the consistent fit's semidefinite program ended {prob.status!r} (solver {solver}); "
                           "more excitation, or a larger regularization, would help")
    v = params.values + s * np.asarray(z.value, float)
    free = _free_solution(params, base, L, fit.beta, regularization * mean_t2, s)
    links, before = min_eigenvalues(params, fit.values)
    _, eig_free = min_eigenvalues(params, free)
    _, after = min_eigenvalues(params, v)
    moved, notes = [], []
    for ln, e, a in zip(links, eig_free, after):
        sl = params.link_parameters(ln)
        dv = (v[sl] - free[sl]) / s[sl]
        k = int(np.argmax(np.abs(dv)))
        if abs(dv[k]) > tolerance:
            moved.append(ln)
            notes.append(f"link {ln!r}: moved to stay physically consistent; the largest change is "
                         f"{params.names[sl.start + k]} from {free[sl.start + k]:.6g} to {v[sl.start + k]:.6g} "
                         f"({dv[k]:+.3g} of its scale); the smallest eigenvalue of H was {e:.3g} without the "
                         f"constraint, {a:.3g} with it")
    for k in nonneg:
        if free[k] < 0.0:
            notes.append(f"{params.names[k]}: {free[k]:.6g} without the constraint, held at {v[k]:.3g} (>= 0)")
    db = base.beta(v) - fit.beta
    rms_inc = float(np.sqrt(max(db @ G @ db, 0.0) / Sn))
    cons_obj = Consistency(values=v, links=links, eig_before=before, eig_free=eig_free, eig_after=after,
                           free=free, moved=tuple(moved),
                           notes=tuple(notes), rms_increase=rms_inc, status=str(prob.status),
                           seconds=time.perf_counter() - t0)
    return dataclasses.replace(fit, consistency=cons_obj)

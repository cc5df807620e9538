"""The least-squares fit of the base parameters, with standard deviations: :func:`identify`.

With the base parameters of :mod:`urdf2links.identification.base` (E91), ``tau = Y_I beta`` over every
sample. The samples are taken in blocks (``block`` rows): each block's regressor is computed (compiled,
:func:`~urdf2links.identification.regression.regressor_block`), its independent columns ``Y_I`` are kept
and only the normal equations are accumulated, per coordinate ``j`` (``W_j`` its weight):

    G_j = sum Y_I[:, j]^T Y_I[:, j],   b_j = sum Y_I[:, j]^T tau_j,   t_j = sum tau_j^2
    G = sum W_j^2 G_j,   beta = G^{-1} sum W_j^2 b_j

so that nothing of size (S, n, p) is formed twice, and never whole. The residual's sum of squares per
coordinate follows from the same sums, ``t_j - 2 beta . b_j + beta^T G_j beta`` (for the description's
``beta`` too: the residual before and after). The noise variance is ``sigma^2 = RSS_w / (S n - r)`` and the
covariance of ``beta`` is ``sigma^2 G^{-1}``. The parameters: ``pi_D`` at the description's values, ``pi_I =
beta - K pi_D`` (so ``pi_I`` has ``beta``'s covariance and ``pi_D`` none).

:func:`identify` returns an :class:`Identification`; with ``consistent=True`` it then runs
:func:`~urdf2links.identification.consistency.consistent_fit` (E92) on the same normal equations.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .base import BaseParameters, base_parameters
from .regression import regressor_columns
from ..dynamics.rows import kernel_array

__all__ = ["Identification", "NormalEquations", "identify", "normal_equations", "fit_rows", "solve_normal_equations",
           "project_constraints"]


@dataclass(frozen=True, eq=False)
class NormalEquations:
    """The sums of the module doc over the samples: ``G`` (n, r, r) per coordinate, ``b`` (n, r), ``t`` (n,),
    ``samples`` S; the columns are ``base.independent``."""

    base: BaseParameters
    G: np.ndarray
    b: np.ndarray
    t: np.ndarray
    samples: int

    def weighted(self, weights) -> tuple[np.ndarray, np.ndarray]:
        w2 = np.asarray(weights, float) ** 2
        return np.einsum("j,jab->ab", w2, self.G), np.einsum("j,ja->a", w2, self.b)

    def rss(self, beta) -> np.ndarray:
        """(n,): the residual's sum of squares per coordinate at ``beta`` (r,)."""
        return np.maximum(self.t - 2.0 * self.b @ beta + np.einsum("a,jab,b->j", beta, self.G, beta), 0.0)


def normal_equations(base: BaseParameters, q, qd, qdd, tau, *, block: int = 512, base_motion=None,
                     t=0.0) -> NormalEquations:
    """The per-coordinate sums (module doc) over the samples ``q, q', q'', tau`` (S, n), in blocks of
    ``block`` samples. ``base_motion``, ``t``: a moving base, as for :meth:`Model.inverse_dynamics`."""
    params = base.params
    n, p = params.n, params.p
    arrs = [np.atleast_2d(np.asarray(a, float)) for a in (q, qd, qdd, tau)]
    for name, a in zip(("q", "qd", "qdd", "tau"), arrs):
        if a.ndim != 2 or a.shape[1] != n or a.shape[0] != arrs[0].shape[0]:
            raise ValueError(f"{name} must have shape (S, {n}) like q (coordinates {params.model.coordinate_names}); "
                             f"got {a.shape}")
    S = arrs[0].shape[0]
    ind = base.independent
    r = ind.size
    own = base.row_columns()                   # per coordinate: its structurally non-zero base columns (positions in ind)
    ptr = np.concatenate(([0], np.cumsum([o.size for o in own]))).astype(np.int64)
    cols = ind[np.concatenate(own)] if ptr[-1] else np.zeros(0, np.int64)
    Gc = [np.zeros((o.size, o.size)) for o in own]
    bc = [np.zeros(o.size) for o in own]
    tt = np.zeros(n)
    buf = np.empty(min(block, S) * ptr[-1])
    for s0 in range(0, S, block):
        s1 = min(S, s0 + block)
        B = s1 - s0
        Q, QD, QDD = (kernel_array(a[s0:s1]) for a in arrs[:3])
        out = buf if B * ptr[-1] == buf.size else np.empty(B * ptr[-1])
        regressor_columns(params, Q, QD, QDD, ptr, cols, out, base=base_motion, t=t)
        T = arrs[3][s0:s1]
        for j in range(n):
            Yj = out[B * ptr[j]:B * ptr[j + 1]].reshape(B, -1)     # (B, r_j), contiguous: BLAS
            Tj = np.ascontiguousarray(T[:, j])
            Gc[j] += Yj.T @ Yj
            bc[j] += Yj.T @ Tj
            tt[j] += Tj @ Tj
    G, b = np.zeros((n, r, r)), np.zeros((n, r))
    for j, o in enumerate(own):
        G[j][np.ix_(o, o)] = Gc[j]
        b[j][o] = bc[j]
    return NormalEquations(base=base, G=G, b=b, t=tt, samples=S)


@dataclass(frozen=True, eq=False)
class Identification:
    """A fit's result.

    ``params`` (:class:`~urdf2links.identification.parameters.ParameterSet`), ``base``
    (:class:`~urdf2links.identification.base.BaseParameters`); ``values`` (p,) the identified parameters
    (the unidentifiable ones at the description's values), ``std`` (p,) their standard deviations (0 for
    those kept), ``covariance`` (p, p); ``identifiable`` (p,) bool: in an identifiable combination (not
    kept at the description's value); ``alone`` (p,) bool: identified by itself; ``beta``, ``beta_std``
    (r,) the base parameters and theirs; ``condition_number`` of the base regressor; ``sigma`` the residual's
    standard deviation (weighted); ``rms_before``, ``rms_after`` (n,) the torque residual per coordinate with
    the description's and the identified values; ``samples``; ``weights`` (n,); ``consistency`` the
    :class:`~urdf2links.identification.consistency.Consistency` when asked for (else None)."""

    params: object
    base: BaseParameters
    values: np.ndarray
    std: np.ndarray
    covariance: np.ndarray
    identifiable: np.ndarray
    alone: np.ndarray
    beta: np.ndarray
    beta_std: np.ndarray
    condition_number: float
    sigma: float
    rms_before: np.ndarray
    rms_after: np.ndarray
    samples: int
    weights: np.ndarray
    consistency: object = None
    normal: NormalEquations | None = field(default=None, repr=False)

    @property
    def description(self) -> np.ndarray:
        return self.params.values

    def model(self):
        """The identified Model (links' H, armature): :meth:`ParameterSet.to_model` of the values (the
        consistent ones when the fit was asked to be consistent)."""
        v = self.values if self.consistency is None else self.consistency.values
        return self.params.to_model(v)

    def table(self) -> list[dict]:
        """One row per parameter: name, kind, owner, description, identified, std, identifiable, alone."""
        v = self.values if self.consistency is None else self.consistency.values
        return [{"name": nm, "kind": kd, "owner": ow, "description": float(d), "identified": float(x),
                 "std": float(s), "identifiable": bool(i), "alone": bool(a)}
                for nm, kd, ow, d, x, s, i, a in zip(self.params.names, self.params.kind, self.params.owner,
                                                     self.params.values, v, self.std, self.identifiable, self.alone)]

    def combinations(self) -> list[dict]:
        """One row per identifiable combination (E91): its name in link terms, the description's value, the
        identified value and its standard deviation, and whether it is a parameter alone."""
        alone = ~np.any(self.base.K != 0.0, axis=1)
        desc = self.base.beta(self.params.values)
        return [{"name": nm, "description": float(d), "identified": float(b), "std": float(s), "alone": bool(a)}
                for nm, d, b, s, a in zip(self.base.names, desc, self.beta, self.beta_std, alone)]

    def summary(self) -> dict:
        out = {"samples": self.samples, "parameters": self.params.p, "identifiable_combinations": self.base.r,
               "unidentifiable": list(self.base.unidentifiable()), "condition_number": self.condition_number,
               "sigma": self.sigma, "rms_before": self.rms_before.tolist(), "rms_after": self.rms_after.tolist()}
        if self.consistency is not None:
            out["consistency"] = self.consistency.summary()
        return out


def identify(params, q, qd, qdd, tau, *, base: BaseParameters | None = None, weights=None, samples: int | None = 200,
             rtol: float = 1e-9, block: int = 512, consistent: bool = False, base_motion=None, t=0.0,
             consistency_options: dict | None = None) -> Identification:
    """Fit ``params`` to the samples ``q, q', q'', tau`` (S, n) (module doc): the base parameters from
    ``samples`` rows spread over the run (or ``base`` given), then every sample in blocks. ``weights``
    (n,) per coordinate (default 1; e.g. the inverse of each joint's noise). ``consistent=True``: every
    link's H positive definite (E92, :func:`~urdf2links.identification.consistency.consistent_fit`,
    options ``consistency_options``). ``tau``: the joints' generalized forces, applied loads already
    subtracted (:func:`~urdf2links.identification.regression.regressor`)."""
    if base is None:
        base = base_parameters(params, q, qd, qdd, samples=samples, rtol=rtol, base=base_motion, t=t)
    ne = normal_equations(base, q, qd, qdd, tau, block=block, base_motion=base_motion, t=t)
    return solve_normal_equations(ne, weights=weights, consistent=consistent, consistency_options=consistency_options)


def fit_rows(params, Y, y, *, base: BaseParameters | None = None, rtol: float = 1e-9, consistent: bool = False,
             consistency_options: dict | None = None) -> Identification:
    """The same fit from given rows: ``Y`` (K, p) with ``Y pi = y`` (K,), e.g. the power balance's rows of
    :func:`~urdf2links.identification.energy.energy_rows` (E90), or the regressor's rows projected onto a
    constraint's null space (``N^T Y``, ``N^T tau`` remove the unknown forces ``J^T lambda`` of joint or tendon
    equalities, E70). One group of rows: ``rms_before``, ``rms_after`` are (1,)."""
    Y = np.asarray(Y, float)
    y = np.asarray(y, float)
    if Y.ndim != 2 or Y.shape[1] != params.p or y.shape != (Y.shape[0],):
        raise ValueError(f"fit_rows needs Y (K, {params.p}) and y (K,); got {Y.shape}, {y.shape}")
    if base is None:
        base = base_parameters(params, Y=Y[:, None, :], rtol=rtol)
    YI = Y[:, base.independent]
    ne = NormalEquations(base=base, G=(YI.T @ YI)[None], b=(YI.T @ y)[None], t=np.array([y @ y]), samples=Y.shape[0])
    return solve_normal_equations(ne, weights=np.ones(1), consistent=consistent,
                                  consistency_options=consistency_options)


def project_constraints(Y, tau, J) -> tuple[np.ndarray, np.ndarray]:
    """Rows free of the constraint forces of constant linear equalities ``J q = c`` (J (k, n): a joint
    coupling, or a tendon equality on fixed tendons' lengths, E70, E76): with ``N`` (n, n - k) an orthonormal
    basis of ``J``'s null space, ``N^T tau = N^T Y pi`` holds whatever the multipliers (``N^T J^T = 0``).
    Returns ``(N^T Y`` stacked (S (n - k), p), ``N^T tau`` (S (n - k),)) for :func:`fit_rows`."""
    import scipy.linalg

    Y, tau, J = (np.asarray(a, float) for a in (Y, tau, J))
    J = np.atleast_2d(J)
    if Y.ndim != 3 or tau.shape != Y.shape[:2] or J.shape[1] != Y.shape[1]:
        raise ValueError(f"project_constraints needs Y (S, n, p), tau (S, n), J (k, n); got {Y.shape}, {tau.shape}, "
                         f"{J.shape}")
    N = scipy.linalg.null_space(J)
    return np.einsum("jm,sjp->smp", N, Y).reshape(-1, Y.shape[2]), (tau @ N).reshape(-1)


def solve_normal_equations(ne: NormalEquations, *, weights=None, consistent: bool = False,
                           consistency_options: dict | None = None) -> Identification:
    """The fit (module doc) from accumulated normal equations: ``weights`` (one per group of rows, the
    coordinates), ``consistent`` as for :func:`identify`."""
    base = ne.base
    params = base.params
    groups = ne.t.size
    w = np.ones(groups) if weights is None else np.asarray(weights, float)
    if w.shape != (groups,) or np.any(w <= 0):
        raise ValueError(f"weights must be {groups} positive numbers (one per coordinate), got {weights!r}")
    G, b = ne.weighted(w)
    beta, Ginv = _solve(G, b)
    dof = max(ne.samples * groups - base.r, 1)
    sigma2 = float(np.sum(w ** 2 * ne.rss(beta)) / dof)
    cov_beta = sigma2 * Ginv
    ind, dep = base.independent, base.dependent
    values = params.values.copy()
    values[ind] = beta - base.K @ params.values[dep]
    cov = np.zeros((params.p, params.p))
    cov[np.ix_(ind, ind)] = cov_beta
    std = np.sqrt(np.maximum(np.diag(cov), 0.0))
    identifiable = np.zeros(params.p, bool)
    identifiable[ind] = True
    S = max(ne.samples, 1)
    fit = Identification(
        params=params, base=base, values=values, std=std, covariance=cov, identifiable=identifiable,
        alone=base.alone(), beta=beta, beta_std=np.sqrt(np.maximum(np.diag(cov_beta), 0.0)),
        condition_number=base.condition_number, sigma=float(np.sqrt(sigma2)),
        rms_before=np.sqrt(ne.rss(base.beta(params.values)) / S), rms_after=np.sqrt(ne.rss(beta) / S),
        samples=ne.samples, weights=w, normal=ne)
    if consistent:
        from .consistency import consistent_fit

        return consistent_fit(fit, **(consistency_options or {}))
    return fit


def _solve(G, b):
    """``G^{-1} b`` and ``G^{-1}`` of a symmetric positive definite ``G``, scaled to a unit diagonal first
    (the columns' units differ by decades)."""
    d = np.sqrt(np.maximum(np.diag(G), np.finfo(float).tiny))
    Gs = G / d[:, None] / d[None, :]
    import scipy.linalg

    try:
        c = scipy.linalg.cho_factor(Gs, lower=True)
        Ginv_s = scipy.linalg.cho_solve(c, np.eye(len(d)))
    except np.linalg.LinAlgError:
        Ginv_s = np.linalg.pinv(Gs)
    Ginv = Ginv_s / d[:, None] / d[None, :]
    return Ginv @ b, Ginv

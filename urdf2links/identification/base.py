"""Base parameters: what a motion can identify, named in link terms (docs/equations.md (E91)).

``tau = Y pi`` holds for every sample, but ``Y`` (the stack over the samples, (S n, p)) has a null space:
directions of ``pi`` no motion of the data changes a torque with (a link fixed to its parent's rotation
axis, a mass at a point three joint axes meet in, ...). With an orthonormal basis ``N`` (p, k) of that
null space (the right singular vectors of the stacked ``Y`` below ``rtol`` times the largest singular value),
a pivoted QR of ``N^T`` picks ``k`` parameters ``D`` whose block ``N_D`` is invertible -- masses first,
then first moments, then the rest (the pivot's column weights), so that an unidentifiable direction through
a link's mass keeps that mass. The other ``r = p - k`` parameters ``I`` carry the identifiable
combinations:

    Y_D = Y_I K,   K = -N_I N_D^{-1},   so   Y pi = Y_I beta,   beta = pi_I + K pi_D     (E91)

``beta`` (r,) are the base parameters, each named ``name_I + K_Ik name_Dk + ...`` (``m_link3 + m_link4``,
``mx_link3 - 0.333*m_link4``); ``pi_D`` stays at the description's values. The condition number is the one
of ``Y_I`` (the base regressor) on the samples. The samples may be a subsample of a long run (spread over
it: ``samples=``): the null space of a motion that excites every joint is the structure's, reached long
before 20,000 samples; :mod:`urdf2links.identification.fit` then uses every sample for the fit.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .regression import regressor

__all__ = ["BaseParameters", "base_parameters", "combination_name", "PREFERENCE"]

#: the pivot's column weight by kind of parameter: an unidentifiable direction is fixed by its heaviest-weighted
#: parameter (an armature, which the first joint's link's moment about its axis always hides, before a mass
#: before a first moment before a planar moment before a joint's damping, friction or offset)
PREFERENCE = {"armature": 16.0, "m": 8.0, "mx": 4.0, "my": 4.0, "mz": 4.0}


@dataclass(frozen=True, eq=False)
class BaseParameters:
    """The identifiable combinations of one motion (module doc, E91).

    ``independent`` (r,) and ``dependent`` (k,) column indices of ``pi``; ``K`` (r, k); ``names`` (r,) each
    combination in link terms; ``null_space`` (p, k) the unidentifiable directions, as columns
    ``e_D - sum K e_I`` (one per dependent parameter, with a coefficient 1 on it); ``directions`` (k,) their
    names; ``singular_values`` of the stacked regressor; ``condition_number`` of the base regressor ``Y_I``;
    ``rows`` how many rows (samples times coordinates) decided it; ``rtol`` the rank's tolerance; ``pattern``
    (n, p) bool: the regressor's entries non-zero on the samples, by coordinate."""

    params: object
    independent: np.ndarray
    dependent: np.ndarray
    K: np.ndarray
    names: tuple
    null_space: np.ndarray
    directions: tuple
    singular_values: np.ndarray
    condition_number: float
    rows: int
    rtol: float
    pattern: np.ndarray

    @property
    def r(self) -> int:
        return len(self.independent)

    def beta(self, values) -> np.ndarray:
        """The base parameters (r,) of a parameter vector (p,): ``pi_I + K pi_D``."""
        v = self.params.vector(values)
        return v[self.independent] + self.K @ v[self.dependent]

    def row_columns(self) -> list:
        """Per coordinate ``j``, the positions in ``independent`` of the base columns that are non-zero in
        ``j``'s rows of the regressor on the samples (``pattern``): a leg's torques never see an arm's
        links, so the fit's normal equations per coordinate keep only these (the sums' cost drops from
        ``n r^2`` to ``sum r_j^2`` per sample)."""
        return [np.flatnonzero(self.pattern[j][self.independent]) for j in range(self.pattern.shape[0])]

    def alone(self) -> np.ndarray:
        """(p,) bool: identified by itself (independent, with no other parameter in its combination)."""
        out = np.zeros(self.params.p, bool)
        out[self.independent[~np.any(self.K != 0.0, axis=1)]] = True
        return out

    def unidentifiable(self) -> tuple:
        """The names of the parameters kept at the description's value (the dependent ones)."""
        return tuple(self.params.names[k] for k in self.dependent)

    def summary(self) -> dict:
        return {"parameters": self.params.p, "identifiable_combinations": self.r, "unidentifiable": len(self.dependent),
                "condition_number": self.condition_number, "rows": self.rows, "rtol": self.rtol}


def combination_name(names, head: int, terms, *, digits: int = 4) -> str:
    """``names[head] + c names[k] - ...`` of ``terms`` ((k, coefficient), ...), coefficients to ``digits``."""
    out = names[head]
    for k, c in terms:
        if abs(abs(c) - 1.0) < 1e-9:
            c = float(np.sign(c))
        if c == 1.0:
            out += f" + {names[k]}"
        elif c == -1.0:
            out += f" - {names[k]}"
        else:
            out += f" {'+' if c > 0 else '-'} {abs(c):.{digits}g}*{names[k]}"
    return out


def _weights(params) -> np.ndarray:
    return np.array([PREFERENCE.get(nm.split("_", 1)[0], 1.0) if kd == "link" else PREFERENCE.get(kd, 0.5)
                     for nm, kd in zip(params.names, params.kind)])


def spread(S: int, samples: int | None) -> np.ndarray:
    """Indices of ``samples`` rows spread evenly over ``S`` (all when ``samples`` is None or >= S)."""
    if samples is None or samples >= S:
        return np.arange(S)
    return np.unique(np.linspace(0, S - 1, samples).round().astype(np.int64))


def base_parameters(params, q=None, qd=None, qdd=None, *, Y=None, samples: int | None = 200, rtol: float = 1e-9,
                    base=None, t=0.0, clean: float = 1e-10) -> BaseParameters:
    """The base parameters of the motion ``q, q', q''`` (S, n) (module doc, E91), from ``samples`` rows
    spread over it (None: all), or from a given regressor ``Y`` (S, n, p). ``rtol``: the rank's tolerance
    on the singular values relative to the largest; ``clean``: entries of ``K`` below it are zero.
    Raises ValueError when no data is given."""
    if Y is None:
        if q is None or qd is None or qdd is None:
            raise ValueError("base_parameters needs q, qd, qdd (S, n) or a regressor Y (S, n, p)")
        q, qd, qdd = (np.atleast_2d(np.asarray(a, float)) for a in (q, qd, qdd))
        idx = spread(q.shape[0], samples)
        Y = regressor(params, q[idx], qd[idx], qdd[idx], base=base, t=t)
    Y = np.asarray(Y, float)
    pattern = np.any(Y != 0.0, axis=0) if Y.ndim == 3 else np.ones((1, params.p), bool)
    Ys = Y.reshape(-1, params.p)
    import scipy.linalg

    Rs = scipy.linalg.qr(Ys, mode="r", check_finite=False)[0][:params.p]     # Y = Q R: R's singular values are Y's
    s, Vt = np.linalg.svd(Rs, full_matrices=False)[1:]
    rank = int(np.sum(s > rtol * s[0])) if s.size and s[0] > 0 else 0
    N = Vt[rank:].T
    p, k = params.p, N.shape[1]
    if k:
        piv = scipy.linalg.qr(N.T * _weights(params)[None, :], pivoting=True, mode="r")[1]
        dep = np.sort(piv[:k])
    else:
        dep = np.zeros(0, np.int64)
    ind = np.setdiff1d(np.arange(p), dep)
    K = -np.linalg.solve(N[dep].T, N[ind].T).T if k else np.zeros((p, 0))
    K[np.abs(K) < clean] = 0.0
    names = params.names
    combos = tuple(combination_name(names, i, [(dep[j], K[a, j]) for j in np.flatnonzero(K[a])])
                   for a, i in enumerate(ind))
    null = np.zeros((p, k))
    null[dep, np.arange(k)] = 1.0
    null[ind] = -K
    directions = tuple(combination_name(names, dep[j], [(ind[a], -K[a, j]) for a in np.flatnonzero(K[:, j])])
                       for j in range(k))
    sI = np.linalg.svd(Rs[:, ind], compute_uv=False) if ind.size else np.zeros(1)
    cond = float(sI[0] / sI[-1]) if sI[-1] > 0 else float("inf")
    return BaseParameters(params=params, independent=ind, dependent=dep, K=K, names=combos, null_space=null,
                          directions=directions, singular_values=s, condition_number=cond, rows=Ys.shape[0],
                          rtol=rtol, pattern=pattern)

"""DESCRIPTION's parameters fitted to OTHER's recorded motion: the library's fit, the samples it is given, the
parameter table (docs/identify.md, "The command").

The fit is :func:`urdf2links.identification.identify` (base parameters by a pivoted QR of the null space,
E91, masses kept first; least squares with standard deviations; with ``consistent=True`` every link's H
positive definite, E92, when the library has it, then :func:`polished` onto the fitted base parameters). What this
module adds:

- the samples: those where some coordinate has ``|q'| < band`` are left out (:func:`kept_samples`); there
  MuJoCo's frictionloss (a soft constraint, linear in ``q'`` near 0) and the regularised Coulomb law of the
  fit differ; everywhere else both are ``f sign(q')`` (to ``v_s^2 / (2 band^2)``);
- "changed": a parameter moved more than :data:`CHANGED` relative to its size and more than
  :data:`NEGLIGIBLE` (SI units); a smaller move is the fit's rounding, and the description's value stays.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from urdf2links.identification import identify as library_identify

__all__ = ["Fit", "fit", "kept_samples", "FRICTION_BAND", "CHANGED", "NEGLIGIBLE"]

#: Samples with some ``|q'| <`` this (rad/s or m/s) left out (module doc).
FRICTION_BAND = 0.05
CHANGED = 1e-6
NEGLIGIBLE = 1e-9
#: The consistent fit's pull toward the description (E92's rho): MuJoCo's samples are noise free, so the torques
#: alone decide wherever they can (the library's default, 1e-4, moved a planted frictionloss by 19%).
REGULARIZATION = 1e-10


def kept_samples(qd, *, band: float = FRICTION_BAND) -> np.ndarray:
    """(S,) bool: the samples where every coordinate moves at ``|q'| >= band`` (module doc)."""
    return np.all(np.abs(qd) >= band, axis=1)


@dataclass(frozen=True, eq=False)
class Fit:
    """The fit: ``result`` (the library's :class:`~urdf2links.identification.Identification`), ``described`` and
    ``identified`` pi (p,) (the consistent values when the fit was consistent), ``changed`` (p,) bool,
    ``samples`` fitted, ``consistent`` (None: the library has no consistent fit yet)."""

    result: object
    described: np.ndarray
    identified: np.ndarray
    changed: np.ndarray
    samples: int
    consistent: bool | None

    @property
    def parameters(self):
        return self.result.params

    @property
    def base(self):
        return self.result.base

    def link_H(self, which: str = "identified") -> np.ndarray:
        """(L, 4, 4) the tree links' H of ``described`` or ``identified`` pi."""
        return self.parameters.H(getattr(self, which))

    def min_eigenvalues(self, which: str = "identified") -> np.ndarray:
        """(L,) the smallest eigenvalue of each tree link's H (> 0: physically consistent)."""
        return np.array([np.linalg.eigvalsh(H)[0] for H in self.link_H(which)])

    def rows_table(self) -> list[dict]:
        """The parameter table, one dict per parameter."""
        r = self.result
        return [{"parameter": nm, "described": float(self.described[i]), "identified": float(self.identified[i]),
                 "std": float(r.std[i]) if r.identifiable[i] else None, "identifiable": bool(r.identifiable[i]),
                 "changed": bool(self.changed[i])} for i, nm in enumerate(self.parameters.names)]

    def base_table(self) -> list[dict]:
        """The base parameters: each combination, its terms, described and identified values, std."""
        b, r = self.base, self.result
        names = self.parameters.names
        out = []
        for k, i in enumerate(b.independent):
            terms = [[names[i], 1.0]] + [[names[d], float(c)] for d, c in zip(b.dependent, b.K[k]) if c != 0.0]
            out.append({"combination": b.names[k], "terms": terms, "described": float(b.beta(self.described)[k]),
                        "identified": float(r.beta[k]), "std": float(r.beta_std[k])})
        return out


def polished(params, base, beta, values) -> np.ndarray:
    """``values`` (p,) moved by the least scaled step onto the fitted base parameters, ``M x = beta`` (E91), when
    every link's H stays positive definite and no damping, friction or armature goes below 0 (else ``values``). The consistent fit (E92) trades the torques'
    residual against a pull toward the description and solves to its solver's tolerance (~1e-4 relative on
    noise-free data); on data that the fitted ``beta`` explains to rounding the step is that small, and it
    gives back the fit's own combinations exactly."""
    M = np.zeros((base.r, params.p))
    M[np.arange(base.r), base.independent] = 1.0
    if base.dependent.size:
        M[:, base.dependent] = base.K
    scale = np.ones(params.p)
    for c in params.link_col:
        if c >= 0:
            m = max(abs(params.values[c + 9]), 1e-3)
            scale[c:c + 6], scale[c + 6:c + 9], scale[c + 9] = 0.01 * m, 0.1 * m, m
    w, *_ = np.linalg.lstsq(M * scale, beta - M @ values, rcond=None)
    x = values + scale * w
    joint = np.array([k in ("damping", "friction", "armature") for k in params.kind])
    if (all(np.linalg.eigvalsh(H)[0] > 0 for H in params.H(x)[params.link_col >= 0])
            and not np.any(joint & (x < -NEGLIGIBLE) & (values >= 0))):
        return x
    return values


def fit(params, q, qd, qdd, tau) -> Fit:
    """The library's fit of the samples (S, n) each (module doc), consistent when the library can."""
    try:
        result = library_identify(params, q, qd, qdd, tau, consistent=True,
                                  consistency_options={"regularization": REGULARIZATION})
        consistent = True
        values = polished(params, result.base, result.beta, result.consistency.values)
    except ImportError:          # urdf2links.identification.consistency (E92) not there yet
        result = library_identify(params, q, qd, qdd, tau)
        consistent, values = None, result.values
    described = params.values
    size = np.maximum(np.abs(described), np.abs(values))
    changed = np.abs(values - described) > np.maximum(CHANGED * size, NEGLIGIBLE)
    identified = np.where(changed, values, described)
    return Fit(result, described, identified, changed, int(len(q)), consistent)

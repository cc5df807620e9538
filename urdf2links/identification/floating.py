"""A floating base identified from its six unactuated rows, without joint torques (docs/equations.md (E97)).

A robot in flight (or hanging from a crane) has no force on its floating root's six coordinates
``x, y, z, phi_x, phi_y, phi_z`` (E3): the base rows of ``Q = Y pi`` (E89) read ``Y_b(q, q', q'') pi = 0``
(with a contact wrench in the log: ``Y_b pi = Q_b``, the wrench's generalized force). No joint torque is
needed: the joints' motion alone moves the base, by an amount set by the links' inertias. The equations
are homogeneous: a robot twice as heavy everywhere flies the same way, so one mass must be known (weighed).
:func:`identify_floating` takes the base parameter (E91) of ``Y_b`` that carries the most mass (the total
mass, when the flight sees it) as known (its description value, or ``known_mass``): its column moves to the
right-hand side, ``Y_I' beta' = -Y_I[:, a0] beta_a0``. The joints' damping, friction, armature and offsets do
not enter the base rows and stay at the description's values (listed as unidentifiable).

The base parameters come from weighted least squares with each base row's noise from its residual and
the Newey-West covariance over the filter's correlation length (E96): the residual is the filtered
position noise through the regressor, correlated over the filter's window. Then the semidefinite program
(E92, :func:`~urdf2links.identification.consistency.consistent_fit`) keeps every link's H positive
definite.

Shapes: S samples, p parameters, r base parameters; the base's rows are the model's first six coordinates.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from .base import BaseParameters, base_parameters
from .fit import Identification, NormalEquations
from .regression import regressor
from .weighted import WeightedFit, weighted_fit

__all__ = ["FloatingIdentification", "identify_floating", "base_rows"]


@dataclass(frozen=True, eq=False)
class FloatingIdentification:
    """``params`` (with the root's mass at the known value), ``base``, ``fit`` (:class:`WeightedFit` of the
    base rows), ``values`` (p,) least squares, ``consistent`` (p,) every H positive definite (or None when
    cvxpy is missing), ``eig`` (links,) each link's smallest eigenvalue of H at ``consistent``, ``root_mass``
    (column, value), ``rows`` the samples used, ``notes``."""

    params: object
    base: BaseParameters
    fit: WeightedFit
    values: np.ndarray
    consistent: np.ndarray | None
    eig: np.ndarray | None
    root_mass: tuple
    rows: int
    notes: tuple

    def table(self) -> list[dict]:
        out = []
        for a, name in enumerate(self.base.names):
            lo, hi = self.fit.intervals[a]
            out.append({"combination": name, "description": float(self.base.beta(self.params.values)[a]),
                        "identified": float(self.fit.beta[a]), "std": float(self.fit.std[a]),
                        "interval95": [float(lo), float(hi)]})
        return out

    def summary(self) -> dict:
        return {"rows": self.rows, "parameters": self.params.p, "base_parameters": self.base.r,
                "known_mass": {"combination": self.base.names[self.root_mass[0]], "value": self.root_mass[1]},
                "fit": self.fit.summary(), "unidentifiable": list(self.base.unidentifiable()),
                "all_positive_definite": None if self.eig is None else bool(np.all(self.eig > 0)),
                "notes": list(self.notes)}


def base_rows(params, q, qd, qdd, wrench_forces=None) -> tuple[np.ndarray, np.ndarray]:
    """``Y_b`` (S, 6, p) and the right-hand side (S, 6): zero in flight, or ``wrench_forces`` (S, 6), the
    contact wrenches' generalized forces on the base coordinates, subtracted as applied loads."""
    Y = regressor(params, q, qd, qdd)[:, :6, :]
    rhs = np.zeros(Y.shape[:2]) if wrench_forces is None else -np.asarray(wrench_forces, float)
    return Y, rhs


def _mass_combination(params, base) -> int:
    """The base parameter that carries the most mass (the total mass, when the motion sees it): the largest
    description value among the combinations whose head or terms are masses."""
    is_mass = np.array([nm.startswith("m_") for nm in params.names])
    mass_like = is_mass[base.independent] | np.any((base.K != 0) & is_mass[base.dependent][None, :], axis=1)
    if not np.any(mass_like):
        raise ValueError("no base parameter of this flight involves a mass: the scale cannot be fixed")
    desc = np.where(mass_like, base.beta(params.values), -np.inf)
    return int(np.argmax(desc))


def _with_known(sub: WeightedFit, keep, a0: int, m0: float, r: int) -> WeightedFit:
    """``sub`` (the fit of the other base parameters) with the known one inserted at ``a0`` (std 0)."""
    beta, std, cov = np.empty(r), np.zeros(r), np.zeros((r, r))
    beta[keep], beta[a0] = sub.beta, m0
    std[keep] = sub.std
    cov[np.ix_(keep, keep)] = sub.covariance
    return dataclasses.replace(sub, beta=beta, std=std, covariance=cov,
                               intervals=np.stack([beta - 1.959963984540054 * std, beta + 1.959963984540054 * std], 1))


def identify_floating(params, d, *, known_mass: float | None = None, wrench_forces=None, consistent: bool = True,
                      samples: int | None = 2000, rtol: float = 1e-9) -> FloatingIdentification:
    """Fit a floating robot's link parameters from its base rows (module doc, E97). ``params``: a
    :class:`ParameterSet` of a floating model, links only (``joints=()``: the base rows see no joint term; coordinates: the root's six, then the joints in the log's
    order); ``d``: the log's :class:`~urdf2links.robot_logs.Derivatives` with ``d.base``; ``known_mass``: the
    root link's mass (default the description's); ``wrench_forces`` (S, 6): contact wrenches' generalized
    forces on the base coordinates at ``d.times``; ``rtol``: the base parameters' rank tolerance (E91; a short
    flight sees some combinations barely: a larger one leaves them at the description's values). Raises ValueError without the base's pose in the log."""
    if d.base is None:
        raise ValueError(f"{d.log.source}: no floating base's pose in the log (a base topic, or base.* columns): the "
                         "base rows need the base's motion")
    names = tuple(params.model.coordinate_names)
    if tuple(d.names) != names[6:]:
        raise ValueError(f"the log's joints {list(d.names)} are not the model's joints {list(names[6:])} in order")
    sl = d.interior
    q, qd, qdd = (np.concatenate([d.base[k][sl], x[sl]], axis=1)
                  for k, x in enumerate((d.positions, d.velocities, d.accelerations)))
    Y, rhs = base_rows(params, q, qd, qdd, None if wrench_forces is None else np.asarray(wrench_forces)[sl])
    idx = np.unique(np.linspace(0, len(q) - 1, min(samples or len(q), len(q))).round().astype(int))
    base = base_parameters(params, Y=Y[idx], rtol=rtol)
    a0 = _mass_combination(params, base)
    m0 = float(base.beta(params.values)[a0] if known_mass is None else known_mass)
    YI = Y[:, :, base.independent]
    rhs = rhs - YI[:, :, a0] * m0
    keep = np.setdiff1d(np.arange(base.r), [a0])
    YI = YI[:, :, keep]
    lags = int(np.ceil(d.filter.fs / d.filter.bandwidth_hz))
    sub = weighted_fit(YI, rhs, lags=lags)
    fit = _with_known(sub, keep, a0, m0, base.r)
    values = params.values.copy()
    values[base.independent] = fit.beta - base.K @ params.values[base.dependent]
    notes = [f"{len(q)} interior samples; the base's six rows, no joint torques; known: {base.names[a0]} = {m0:.6g} kg",
             f"joint damping, friction, armature and offsets are not in the base rows: kept at the description's "
             f"values"]
    cons = eig = None
    if consistent:
        cons, eig = _consistent(params, base, fit, Y[:, :, base.independent], rhs, values)
        notes.append("every link's H positive definite (semidefinite program, E92)")
    return FloatingIdentification(params=params, base=base, fit=fit, values=values, consistent=cons, eig=eig,
                                  root_mass=(a0, m0), rows=len(q), notes=tuple(notes))


def _consistent(params, base, fit, YI, rhs, values):
    """The consistent fit (E92) on the base rows' normal equations (weighted by the rows' noise): ``G`` of
    every base column (the known one too: moving it costs as moving any other); ``t`` of the known-mass
    right-hand side ``rhs`` (its scale sets the pull toward the description)."""
    from .consistency import consistent_fit, min_eigenvalues

    n = params.n
    r = base.r
    G, b, t = np.zeros((n, r, r)), np.zeros((n, r)), np.zeros(n)
    for j in range(6):
        G[j], b[j], t[j] = YI[:, j].T @ YI[:, j], YI[:, j].T @ rhs[:, j], rhs[:, j] @ rhs[:, j]
    w = np.ones(n)
    w[:6] = np.min(fit.sigma) / fit.sigma          # relative weights (the scale cancels; keeps the program well scaled)
    ne = NormalEquations(base=base, G=G, b=b, t=t, samples=YI.shape[0])
    ident = Identification(params=params, base=base, values=values, std=np.zeros(params.p),
                           covariance=np.zeros((params.p, params.p)), identifiable=np.isin(np.arange(params.p), base.independent),
                           alone=base.alone(), beta=fit.beta, beta_std=fit.std, condition_number=fit.condition_number,
                           sigma=1.0, rms_before=np.zeros(n), rms_after=np.zeros(n), samples=YI.shape[0], weights=w,
                           normal=ne)
    v = consistent_fit(ident).consistency.values
    return v, min_eigenvalues(params, v)[1]

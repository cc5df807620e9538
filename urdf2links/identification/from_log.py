"""Identification from a robot's log: the accelerations' regressor and the energy form, on the same data.

The log is read, checked and differentiated by :mod:`urdf2links.robot_logs` (docs/logs.md); this module
fits. :func:`identify_log` takes the :class:`~urdf2links.robot_logs.Derivatives` of a fixed-base robot's log
and fits the base parameters (E91) twice:

- **accelerations**: ``tau = Y(q, q', q'') pi`` (E89) per sample and joint, with the filtered positions,
  velocities and accelerations on the interior rows, and the efforts as logged (white sensor noise: the
  filter's bandwidth sits far above the motion, so the unfiltered efforts and the filtered regressor see
  the same signal); weighted least squares with each joint's noise from its residual (E96);
- **energy**: the power balance over intervals of ``window`` samples (E90), no accelerations: the
  filtered positions and velocities only, the work of the logged efforts integrated.

Both give the same base parameters ``beta``; :class:`LogIdentification` holds both fits, the parameters
``pi`` of the acceleration fit (``pi_D`` at the description's values, E91), and per base parameter the two
estimates' difference in units of its combined standard deviation.

Shapes: S samples, n coordinates, p parameters, r base parameters.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .base import BaseParameters, base_parameters
from .energy import energy_rows
from .regression import regressor
from .weighted import WeightedFit, weighted_fit

__all__ = ["LogIdentification", "identify_log", "derivative_noise_gain"]


def derivative_noise_gain(filt, *, order: int = 2, samples: int = 4096, seed: int = 0) -> float:
    """The standard deviation of the ``order``-th filtered derivative of unit white noise through ``filt``
    (a :class:`~urdf2links.robot_logs.Filter`), measured on ``samples`` samples (fixed seed)."""
    from ..robot_logs.filters import apply

    t = np.arange(samples) * filt.dt
    e = np.random.default_rng(seed).standard_normal((samples, 1))
    out = apply(filt, t, e)[order, samples // 4: 3 * samples // 4, 0]
    return float(np.std(out))


@dataclass(frozen=True, eq=False)
class LogIdentification:
    """The two fits of a log (module doc): ``base`` (:class:`BaseParameters`), ``acceleration`` and
    ``energy`` (:class:`~urdf2links.identification.weighted.WeightedFit`; ``energy`` None without every
    joint's effort), ``values`` (p,) the acceleration fit's parameters, ``joints`` the coordinates with
    efforts (the rows fitted), ``rows`` the samples used (interior), ``energy_rms`` (m,) the torque residual
    of the energy fit's beta on the acceleration rows, ``agreement`` (r,) ``(beta_a - beta_e) /
    sqrt(std_a^2 + std_e^2)``, ``notes``."""

    params: object
    base: BaseParameters
    acceleration: WeightedFit
    energy: WeightedFit | None
    values: np.ndarray
    joints: tuple
    rows: int
    energy_rms: np.ndarray | None
    agreement: np.ndarray | None
    notes: tuple

    def table(self) -> list[dict]:
        """One row per base parameter: its combination, both estimates with standard deviations and 95%
        intervals, the agreement."""
        out = []
        for a, name in enumerate(self.base.names):
            row = {"combination": name, "description": float(self.base.beta(self.params.values)[a]),
                   "acceleration": float(self.acceleration.beta[a]), "std": float(self.acceleration.std[a]),
                   "interval95": [float(x) for x in self.acceleration.intervals[a]]}
            if self.energy is not None:
                row.update(energy=float(self.energy.beta[a]), energy_std=float(self.energy.std[a]),
                           agreement=float(self.agreement[a]))
            out.append(row)
        return out

    def summary(self) -> dict:
        out = {"rows": self.rows, "joints": list(self.joints), "parameters": self.params.p,
               "base_parameters": self.base.r, "unidentifiable": list(self.base.unidentifiable()),
               "acceleration": self.acceleration.summary(), "notes": list(self.notes)}
        if self.energy is not None:
            out["energy"] = self.energy.summary()
            out["energy_torque_rms"] = self.energy_rms.tolist()
            out["agreement_max"] = float(np.max(np.abs(self.agreement)))
        return out


def _relative_error(d, sl, joints) -> float:
    """The regressor's relative error from the derivatives' noise: per joint the filtered acceleration's
    noise (position noise (E95) times the filter's gain on white noise) over the acceleration's RMS."""
    gain = derivative_noise_gain(d.filter, order=2)
    acc = d.accelerations[sl][:, joints]
    rms = np.sqrt(np.mean(acc ** 2, axis=0))
    return float(np.max(d.noise[joints] * gain / np.maximum(rms, np.finfo(float).tiny)))


def identify_log(params, d, *, base: BaseParameters | None = None, samples: int | None = 500,
                 energy_window: int = 50, iterations: int = 2) -> LogIdentification:
    """Fit ``params`` (:class:`~urdf2links.identification.ParameterSet`, coordinates in the log's order) to
    the derivatives ``d`` of a fixed-base robot's log (module doc). ``base``: given base parameters (else from
    ``samples`` rows spread over the log); ``energy_window``: samples per power-balance interval. Raises
    ValueError when the log's joints are not the model's coordinates or no joint has efforts."""
    names = tuple(params.model.coordinate_names)
    if tuple(d.names) != names:
        raise ValueError(f"the log's joints {list(d.names)} are not the model's coordinates {list(names)} in order: "
                         "check_log(log, joints=model.coordinate_names) orders them")
    sl = d.interior
    q, qd, qdd = d.positions[sl], d.velocities[sl], d.accelerations[sl]
    tau = d.log.efforts[sl]
    joints = np.flatnonzero(np.all(np.isfinite(tau), axis=0))
    if joints.size == 0:
        raise ValueError(f"{d.log.source}: no joint has efforts: a fixed-base robot is identified from its torques "
                         "(a floating base without torques: urdf2links.identification.floating)")
    notes = [f"{q.shape[0]} interior samples of {len(d.times)} (the filter's {d.edge} at each end left out); "
             "efforts as logged (unfiltered)"]
    if base is None:
        base = base_parameters(params, q, qd, qdd, samples=samples)
    Y = regressor(params, q, qd, qdd)[:, joints][:, :, base.independent]
    lags = int(np.ceil(d.filter.fs / d.filter.bandwidth_hz))      # the filtered noise's correlation length
    acc = weighted_fit(Y, tau[:, joints], iterations=iterations, lags=lags,
                       relative_error=_relative_error(d, sl, joints))
    values = params.values.copy()
    values[base.independent] = acc.beta - base.K @ params.values[base.dependent]
    energy = energy_rms = agreement = None
    rows = energy_rows(params, d.times[sl], q, qd, tau, window=energy_window) if joints.size == params.n else None
    if rows is not None and rows.y.size <= 2 * base.r:
        notes.append(f"energy form not fitted: {rows.y.size} intervals of {energy_window} samples for {base.r} base "
                     "parameters (a longer log or a shorter window)")
    elif rows is not None:
        YE = rows.Y[:, base.independent][:, None, :]
        energy = weighted_fit(YE, rows.y[:, None], iterations=0)
        energy_rms = np.sqrt(np.mean((tau - np.einsum("sjr,r->sj", Y, energy.beta)) ** 2, axis=0))
        agreement = (acc.beta - energy.beta) / np.sqrt(acc.std ** 2 + energy.std ** 2)
        notes.append(f"energy form: {rows.y.size} intervals of {energy_window} samples, no accelerations")
    else:
        missing = [names[j] for j in range(params.n) if j not in set(joints.tolist())]
        notes.append(f"energy form not fitted: the power balance needs every joint's effort; missing {missing}")
    return LogIdentification(params=params, base=base, acceleration=acc, energy=energy, values=values,
                             joints=tuple(names[j] for j in joints), rows=q.shape[0], energy_rms=energy_rms,
                             agreement=agreement, notes=tuple(notes))

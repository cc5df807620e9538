"""``identify DESCRIPTION --against OTHER`` as one call: record, fit, validate (docs/identify.md, "The command").

:func:`identify` records OTHER in MuJoCo along ``seeds`` excitation trajectories (:mod:`.recording`), builds
the library's regressor (:func:`urdf2links.identification.regressor`, E89) of DESCRIPTION's tree at those
samples, fits (:mod:`.fitting`), and checks the result on a held-out seed: the torque each model predicts
along OTHER's recorded motion (inverse dynamics, before and after), and the motion itself, OTHER's servo run
in MuJoCo with DESCRIPTION before and after (:mod:`.validation`).

The Coulomb term uses the library's regularised law ``f q' / sqrt(q'^2 + v_s^2)`` with ``v_s`` =
:data:`SLIP_SPEED`; with the rows of ``|q'| < band`` left out the law is ``f sign(q')`` to
``v_s^2 / (2 band^2)``, the same as MuJoCo's frictionloss away from its soft zone.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from urdf2links.compilation import clock
from urdf2links.identification import ParameterSet, regressor

from .excitation import bounds_of_parts, random_trajectory
from .fitting import FRICTION_BAND, Fit, fit, kept_samples
from .recording import Recording, inverse_consistency, open_pair, record
from .validation import validate
from .writers import urdf_values

__all__ = ["identify", "Identification", "SLIP_SPEED", "stacked"]

#: The Coulomb law's regularisation speed v_s (rad/s or m/s) in the fit (module doc).
SLIP_SPEED = 1e-8


def stacked(recs) -> tuple[np.ndarray, ...]:
    """``q, q', q'', tau`` of the recordings, stacked (S, n) each."""
    return tuple(np.concatenate([getattr(r, k) for r in recs]) for k in ("q", "qd", "qdd", "tau"))


@dataclass(frozen=True, eq=False)
class Identification:
    """The command's result: the ``pair``, the ``recordings`` fitted and the ``held_out`` one, the ``fit``,
    per coordinate (n,) the torque residual RMS ``residual_before`` / ``residual_after`` on the fitted data
    and ``heldout_before`` / ``heldout_after`` on the held-out seed, ``consistency`` (largest
    ``|qfrc_inverse - tau|``), ``times`` (s, by stage), ``notes``."""

    pair: object
    recordings: tuple
    held_out: Recording
    fit: Fit
    residual_before: np.ndarray
    residual_after: np.ndarray
    heldout_before: np.ndarray
    heldout_after: np.ndarray
    consistency: float
    band: float
    times: dict
    notes: list = field(default_factory=list)
    validation: list = field(default_factory=list)

    @property
    def names(self) -> tuple:
        return self.pair.names


def _rms(Y, pi, tau) -> np.ndarray:
    return np.sqrt(np.mean((tau - Y @ pi) ** 2, axis=0))


def identify(description, other, *, seeds=(1, 2, 3), held_out_seed: int = 101, t_end: float = 6.0,
             band: float = FRICTION_BAND, explicit_map: dict | None = None, trajectory=None,
             simulate: bool = True) -> Identification:
    """DESCRIPTION's parameters fitted to OTHER's motion in MuJoCo (module doc). ``trajectory``: a designed
    :class:`~.excitation.FourierTrajectory` used instead of the seeded ones (its seed is reported as 0). ``simulate``: the held-out run on both engines too (:mod:`.validation`)."""
    times = {}
    start = clock()
    pair = open_pair(description, other, explicit_map=explicit_map)
    bounds = bounds_of_parts(pair.parts, pair.names)
    trajectories = [(0, trajectory)] if trajectory is not None else [(s, random_trajectory(bounds, seed=s))
                                                                        for s in seeds]
    recs = tuple(record(pair, tr, seed=s, t_end=t_end) for s, tr in trajectories)
    held = record(pair, random_trajectory(bounds, seed=held_out_seed), seed=held_out_seed, t_end=t_end, decimate=1)
    consistency = max(inverse_consistency(pair, r) for r in recs + (held,))
    times["record"] = clock() - start
    joints = {j.name: j for j, _b in pair.parts.joints}
    params = ParameterSet.from_model(
        pair.built.model, damping={c: joints[c].damping for c in pair.names},
        friction={c: joints[c].friction for c in pair.names}, slip_speed=SLIP_SPEED)
    start = clock()
    q, qd, qdd, tau = stacked(recs)
    keep = kept_samples(qd, band=band)
    result = fit(params, q[keep], qd[keep], qdd[keep], tau[keep])
    times["fit"] = clock() - start
    Y = regressor(params, q, qd, qdd)
    Yh = regressor(params, held.q, held.qd, held.qdd)
    notes = list(pair.notes) + [
        f"{len(recs)} excitation run(s) of {t_end:g} s ({len(q)} samples, MuJoCo's qacc and the torque applied; "
        f"mj_inverse agrees to {consistency:.1e} N m); held-out seed {held_out_seed}",
        f"samples with some |q'| < {band:g} left out of the fit ({int(keep.sum())} of {len(q)} kept): MuJoCo's "
        f"frictionloss is a soft constraint there; Coulomb law f q'/sqrt(q'^2 + v_s^2), v_s = {SLIP_SPEED:g}"]
    if result.consistent is None:
        notes.append("the library's consistent fit (E92) is not available yet: the values are the least-squares "
                     "ones, the unidentifiable kept at the description's")
    if np.any(result.min_eigenvalues() <= 0):
        bad = [ln for ln, e in zip(pair.built.model.tree.link_names, result.min_eigenvalues()) if e <= 0
               and ln not in params.fixed_links]
        if bad:
            notes.append("identified H not positive definite (physically inconsistent) for links " + ", ".join(bad)
                         + ": the unconstrained fit; see the library's consistent fit")
    out = Identification(pair, recs, held, result, _rms(Y, result.described, tau), _rms(Y, result.identified, tau),
                         _rms(Yh, result.described, held.tau), _rms(Yh, result.identified, held.tau),
                         consistency, band, times, notes)
    if simulate:
        start = clock()
        # the identified values as written (armature the data cannot tell from the inertias moved into them: the
        # tree holds no negative armature), the same dynamics as result.identified
        written = urdf_values(result) if pair.parts.format == "urdf" else result.identified
        out.validation.extend(validate(out, {"description": result.described, "identified": written}))
        times["validation"] = clock() - start
    return out

"""Fixed tendons (MuJoCo's ``<tendon><fixed>``) as forces on the coordinates: docs/equations.md (E76).

A fixed tendon's length is ``l = sum_i c_i q_i`` (its Jacobian ``c`` constant), its rate ``l' = c . q'``.
MuJoCo's passive law gives it a spring ``-k (l - l_0)`` (``l_0`` a dead band ``[l_a, l_b]``: no force
inside it) and a damper ``-b l'``; an actuator whose transmission is the tendon acts with MuJoCo's
actuator law (E55) on ``(gear l, gear l')`` and its force ``gear F`` on the tendon. The generalized force
is ``c f_t``. The spring is a potential (``V`` gains ``0.5 k (l - l_0)^2``); the damper and actuators do
work (``P``). Spatial tendons and tendon friction loss are not modelled: the file's notes say so
(:mod:`urdf2links.scenes.file_constraints`).

A ``limited`` tendon (MuJoCo's ``range``) gets the project's tendon-limit law (E89, issue 45): past its range
by ``p = s (l - l_lim)`` (``s = +1`` above the upper end, ``-1`` below the lower), the force on the tendon is
``f = -s max(0, k p + b p')``, ``p' = s l'``: a stiff spring-damper that only pushes back, the contact law's
form (E79). ``k = m_t / (tau zeta)^2`` and ``b = 2 m_t / tau`` from the tendon's limit ``solref (tau, zeta)``
and its effective mass ``m_t = 1 / (c A(q0)^-1 c)`` at the scene's initial state (:func:`limit_gains`): MuJoCo's
reference acceleration for its own soft limit, made a force. Both engines apply this law (MuJoCo's own limit is
disabled for the run). It does work (``P``): its spring part is not in ``V``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["FixedTendon", "limit_gains"]


@dataclass(frozen=True)
class FixedTendon:
    """``name``; ``coef`` (n,) in the model's coordinates; ``stiffness``, ``damping``, ``lengthspring``
    ``(l_a, l_b)``; ``actuators``: objects with ``gear`` and ``force(t, length, rate)`` (E55)."""

    name: str
    coef: np.ndarray
    stiffness: float = 0.0
    damping: float = 0.0
    lengthspring: tuple = (0.0, 0.0)
    actuators: tuple = ()
    limit: tuple | None = None
    """``(l_lo, l_hi)`` of a ``limited`` tendon (in the model's coordinates), else None (E89)."""
    limit_gains: tuple = (0.0, 0.0)
    """``(k, b)`` of the limit law (E89): :func:`limit_gains`."""

    @property
    def limited(self) -> bool:
        return self.limit is not None

    def limit_force(self, l: float, ld: float) -> float:
        """The limit law's force on the tendon (E89): ``-s max(0, k p + b p')`` past the range, else 0."""
        if self.limit is None:
            return 0.0
        lo, hi = self.limit
        k, b = self.limit_gains
        if l > hi:
            return -max(0.0, k * (l - hi) + b * ld)
        if l < lo:
            return max(0.0, k * (lo - l) - b * ld)
        return 0.0

    def length(self, q) -> float:
        return float(self.coef @ q)

    def _stretch(self, l):
        a, b = self.lengthspring
        return l - b if l > b else (l - a if l < a else 0.0)

    def force(self, t, q, qd):
        """``(c f_t (n,), P)`` at ``t``, ``q``, ``q'`` (E76): the generalized force and the power of the
        damper and actuators."""
        l, ld = self.length(q), float(self.coef @ qd)
        spring = -self.stiffness * self._stretch(l)
        work = (-self.damping * ld + sum(a.gear * a.force(t, l, ld) for a in self.actuators)
                + self.limit_force(l, ld))
        return self.coef * (spring + work), work * ld

    def energy(self, q) -> float:
        """``0.5 k (l - l_0)^2`` (E76)."""
        return 0.5 * self.stiffness * self._stretch(self.length(q)) ** 2

    def describe(self) -> str:
        a, b = self.lengthspring
        sl = f"{a:g}" if a == b else f"[{a:g}, {b:g}]"
        acts = "".join(f"; actuator {a.name!r} (gear {a.gear:g})" for a in self.actuators)
        lim = ("" if self.limit is None else f"; limited to [{self.limit[0]:g}, {self.limit[1]:g}]: the project's "
               f"law on both engines (E89, k {self.limit_gains[0]:.4g}, b {self.limit_gains[1]:.4g})")
        return (f"{self.name!r}: length = " + " + ".join(f"{c:g} q{i}" for i, c in enumerate(self.coef) if c)
                + f", stiffness {self.stiffness:g}, damping {self.damping:g}, spring length {sl}{acts}{lim}")


def limit_gains(model, coef, q0, solref) -> tuple[float, float]:
    """``(k, b)`` of the tendon-limit law (E89): ``m_t = 1 / (c A(q0)^-1 c)`` the tendon's effective mass at
    ``q0``, ``k = m_t / (tau zeta)^2``, ``b = 2 m_t / tau`` from ``solref = (tau, zeta)`` (MuJoCo's reference
    acceleration ``-b' l' - k' p`` of a soft limit, ``b' = 2 / tau``, ``k' = 1 / (tau zeta)^2``, times ``m_t``)."""
    tau, zeta = float(solref[0]), float(solref[1])
    if tau <= 0.0 or zeta <= 0.0:
        raise ValueError(f"tendon limit solref {list(solref)}: the limit law (E89) takes a time constant and a "
                         "damping ratio, both > 0 (MuJoCo's direct form with negative numbers is not read)")
    A = model.mass_matrix(np.asarray(q0, float))
    m_t = 1.0 / float(coef @ np.linalg.solve(A, coef))
    return m_t / (tau * zeta) ** 2, 2.0 * m_t / tau

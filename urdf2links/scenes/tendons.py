"""Fixed tendons (MuJoCo's ``<tendon><fixed>``) as forces on the coordinates: docs/equations.md (E76).

A fixed tendon's length is ``l = sum_i c_i q_i`` (its Jacobian ``c`` constant), its rate ``l' = c . q'``.
MuJoCo's passive law gives it a spring ``-k (l - l_0)`` (``l_0`` a dead band ``[l_a, l_b]``: no force
inside it) and a damper ``-b l'``; an actuator whose transmission is the tendon acts with MuJoCo's
actuator law (E55) on ``(gear l, gear l')`` and its force ``gear F`` on the tendon. The generalized force
is ``c f_t``. The spring is a potential (``V`` gains ``0.5 k (l - l_0)^2``); the damper and actuators do
work (``P``). Spatial tendons and tendon friction loss are not modelled: the file's notes say so
(:mod:`urdf2links.scenes.file_constraints`).

A ``limited`` tendon (MuJoCo's ``range [l_lo, l_hi]``) gets the project's tendon-limit law (E87, issue 45): a stiff
one-sided spring on the length past the range, ``f = -k (l - l_hi)`` above it, ``k (l_lo - l)`` below it, 0 inside,
with ``k = m_t / (tau zeta)^2`` from the limit's ``solref (tau, zeta)`` and the tendon's effective mass
``m_t = 1 / (c A(q0)^-1 c)`` at the scene's initial state (:func:`limit_tendon`; MuJoCo's reference stiffness of its
own soft limit, ``1 / (tau zeta)^2`` per unit of effective mass, made a force). That is a spring with a dead band
(E76's spring, ``l_0 = [l_lo, l_hi]``): it runs as a second fixed tendon ``<name>__limit`` on the same coordinates,
conservative (its energy is in ``V``), on both engines; MuJoCo's own soft limit is disabled for the run.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["FixedTendon", "limit_tendon", "LIMIT_SUFFIX"]

#: The name of a limited tendon's limit law (E87) as a tendon of its own: ``<tendon>__limit``.
LIMIT_SUFFIX = "__limit"


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
        work = -self.damping * ld + sum(a.gear * a.force(t, l, ld) for a in self.actuators)
        return self.coef * (spring + work), work * ld

    def energy(self, q) -> float:
        """``0.5 k (l - l_0)^2`` (E76)."""
        return 0.5 * self.stiffness * self._stretch(self.length(q)) ** 2

    def describe(self) -> str:
        a, b = self.lengthspring
        sl = f"{a:g}" if a == b else f"[{a:g}, {b:g}]"
        acts = "".join(f"; actuator {a.name!r} (gear {a.gear:g})" for a in self.actuators)
        return (f"{self.name!r}: length = " + " + ".join(f"{c:g} q{i}" for i, c in enumerate(self.coef) if c)
                + f", stiffness {self.stiffness:g}, damping {self.damping:g}, spring length {sl}{acts}")


def limit_tendon(model, tendon: FixedTendon, limit, q0, solref) -> FixedTendon:
    """The tendon-limit law (E87) of ``tendon`` limited to ``limit = (l_lo, l_hi)`` (the model's coordinates) as a
    fixed tendon ``<name>__limit``: ``k = m_t / (tau zeta)^2``, ``m_t = 1 / (c A(q0)^-1 c)`` at ``q0``, the spring
    length the range (a dead band: no force inside it); no damping. ValueError for a ``solref`` that is not
    ``(tau > 0, zeta > 0)``."""
    tau, zeta = float(solref[0]), float(solref[1])
    if tau <= 0.0 or zeta <= 0.0:
        raise ValueError(f"limit solref {list(solref)}: the limit law (E87) takes a time constant and a damping ratio, "
                         "both > 0 (MuJoCo's direct form with negative numbers is not read)")
    c = np.asarray(tendon.coef, float)
    m_t = 1.0 / float(c @ np.linalg.solve(model.mass_matrix(np.asarray(q0, float)), c))
    return FixedTendon(tendon.name + LIMIT_SUFFIX, c, m_t / (tau * zeta) ** 2, 0.0,
                       (float(limit[0]), float(limit[1])))

"""Fixed tendons (MuJoCo's ``<tendon><fixed>``) as forces on the coordinates: docs/equations.md (E76).

A fixed tendon's length is ``l = sum_i c_i q_i`` (its Jacobian ``c`` constant), its rate ``l' = c . q'``.
MuJoCo's passive law gives it a spring ``-k (l - l_0)`` (``l_0`` a dead band ``[l_a, l_b]``: no force
inside it) and a damper ``-b l'``; an actuator whose transmission is the tendon acts with MuJoCo's
actuator law (E55) on ``(gear l, gear l')`` and its force ``gear F`` on the tendon. The generalized force
is ``c f_t``. The spring is a potential (``V`` gains ``0.5 k (l - l_0)^2``); the damper and actuators do
work (``P``). Tendon limits, spatial tendons and tendon friction loss are not modelled: the file's notes
say so (:mod:`urdf2links.scenes.file_constraints`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["FixedTendon"]


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

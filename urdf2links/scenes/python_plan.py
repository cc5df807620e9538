"""A scene's right-hand side in numpy: the readable twin of the compiled one, and its oracle.

:class:`PythonPlan` evaluates ``y' = (q', q'', P)`` (docs/equations.md (E24), (E40)) of a
:class:`~urdf2links.scenes.plan.Plan` with the numpy recursive form
(:class:`~urdf2links.dynamics.oracles.recursive.RecursivePlan`), term by term and only the terms the plan
lists, plus the scene's energies at one state. The tests compare
``plan.rhs`` (compiled) with it, and it is what a reader follows to see what the compiled
right-hand side computes.
"""

from __future__ import annotations

import numpy as np

from ..dynamics.oracles.armature import armature_terms
from ..dynamics.oracles.recursive import RecursivePlan
from ..dynamics.transforms import base_transforms

__all__ = ["PythonPlan"]


class PythonPlan:
    """The numpy twin of ``plan.rhs``: :meth:`rhs`, :meth:`accelerations`, :meth:`power`, and the
    energies ``E``, ``V`` (gravity and springs) and ``h`` at one state. ``nfev`` counts
    :meth:`accelerations`."""

    def __init__(self, plan):
        self.plan = plan
        self.model = plan.model
        self.rp = RecursivePlan(plan.model.tree)
        self.nfev = 0

    def _base_T(self, t):
        state = self.plan.base_state(t)
        return None if state is None else base_transforms(state)

    def _equation(self, qt, qdt, base_T):
        """``A`` and ``-(G + e)`` in model coordinates (E24), and the kinematics they came from."""
        rp, model, plan = self.rp, self.model, self.plan
        kin = rp.kinematics(qt, qdt, base_T, acceleration=True)
        Hc = rp.composite_inertia(kin)
        rhs = -rp.bias(kin)
        if plan.gravity_vector is not None:
            rhs -= rp.gravity(kin, plan.gravity_vector, Hc)
        A = rp.mass_matrix(kin, Hc)
        if model.tree.has_armature:     # (E49)
            arm = armature_terms(model.tree, qt, qdt)
            A, rhs = A + arm["A"], rhs - arm["e"]
        return model.reduce(A), model.reduce(rhs), kin

    def generalized_forces(self, t, q, qd, kin=None, *, computed: bool = True) -> np.ndarray:
        """Everything on the right of (E24) but ``-G - e``: Q of loads, tau, springs, dampers, actuators
        (E55) and, with ``computed``, the computed torque (E57). (n,)"""
        plan, model = self.plan, self.model
        f = np.zeros(plan.n)
        if plan.loads:
            if kin is None:
                qt, _ = model.tree_state(q)
                kin = self.rp.kinematics(qt, None, self._base_T(t))
            f += model.reduce(self.rp.generalized_forces(kin, plan.wrenches(t)))
        if plan.actuator_set.actuators:
            f += plan.actuator_forces(t, q, qd)
        if computed and plan.reference_funcs:
            f += self.computed_torque(t)
        if plan.torque_funcs:
            f[plan.torque_index] += [g(t) for g in plan.torque_funcs]
        if plan.spring_index.size:
            f[plan.spring_index] -= plan.stiffness * (q[plan.spring_index] - plan.rest)
        if plan.damper_index.size:
            f[plan.damper_index] -= plan.damping * qd[plan.damper_index]
        return f

    def computed_torque(self, t) -> np.ndarray:
        """The computed torque (E57) in numpy: ``A r'' + e + G`` from this twin's own terms at the
        reference ``(r, r', r'')`` minus every other force of the scene there (loads, torques, springs,
        dampers, actuators)."""
        plan, model = self.plan, self.model
        r, rd, rdd = plan.reference(t, 0), plan.reference(t, 1), plan.reference(t, 2)
        qt, qdt = model.tree_state(r, rd)
        A, rhs, kin = self._equation(qt, qdt, self._base_T(t))
        return A @ rdd - rhs - self.generalized_forces(t, r, rd, kin, computed=False)

    def accelerations(self, t, q, qd, *, with_power: bool = False):
        """q'' of (E24) with exactly the scene's terms; with ``with_power`` also the power of the
        non-potential forces and of the base (see :meth:`power`), from the same kinematics."""
        self.nfev += 1
        model = self.model
        qt, qdt = model.tree_state(q, qd)
        base_T = self._base_T(t)
        A, rhs, kin = self._equation(qt, qdt, base_T)
        f = self.generalized_forces(t, q, qd, kin)
        qdd = model.solve_mass_matrix(A, rhs + f, q=q)
        if not with_power:
            return qdd
        return qdd, self._power(qd, q, f, kin, base_T)

    def _power(self, qd, q, f, kin, base_T) -> float:
        plan = self.plan
        P = 0.0
        if any(term in plan.terms for term in ("Q", "tau", "damper", "gravcomp", "actuator", "computed_torque")):
            f = f.copy()
            if plan.spring_index.size:  # springs are a potential, not work
                f[plan.spring_index] += plan.stiffness * (q[plan.spring_index] - plan.rest)
            P += float(qd @ f)
        if base_T is not None:
            dE, dV = self.rp.explicit_time_rates(kin, base_T, plan.gravity_vector)
            P -= dE - dV  # -dL/dt
        return P

    def rhs(self, t, y) -> np.ndarray:
        """``y' = (qd, q'', P)`` for ``y = (q, qd, W)`` (2n + 1,)."""
        n = self.plan.n
        q, qd = y[:n], y[n:2 * n]
        out = np.empty(2 * n + 1)
        out[:n] = qd
        out[n:2 * n], out[2 * n] = self.accelerations(t, q, qd, with_power=True)
        return out

    def power(self, t, q, qd) -> float:
        """Power of the non-potential forces, ``qd . (Q + tau - c qd)``, and of the base, ``-dL/dt``
        (the explicit time derivative of the Lagrangian at fixed (q, qd)): ``P`` of (E40)."""
        return float(self.accelerations(t, q, qd, with_power=True)[1])

    # -- energy ----------------------------------------------------------------------------------
    def kinetic_energy(self, t, q, qd) -> float:
        qt, qdt = self.model.tree_state(q, qd)
        E = self.rp.kinetic_energy(self.rp.kinematics(qt, qdt, self._base_T(t)))
        if self.model.tree.has_armature:        # (E49)
            E += armature_terms(self.model.tree, qt, qdt)["E"]
        return E

    def potential_energy(self, t, q) -> float:
        """V = V of gravity (E21) + spring energies 0.5 k (q - rest)^2."""
        plan = self.plan
        V = 0.0
        if plan.gravity_vector is not None:
            qt, _ = self.model.tree_state(q)
            kin = self.rp.kinematics(qt, None, self._base_T(t))
            V += self.rp.potential_energy(kin, plan.gravity_vector)
        if plan.spring_index.size:
            V += 0.5 * float(plan.stiffness @ (q[plan.spring_index] - plan.rest) ** 2)
        return V

    def energy_function(self, t, q, qd) -> float:
        """h = qd . dL/dqd - L (E39); equals E + V for a fixed base. E is quadratic in qd
        (E = E2 + E1 + E0), so h = E2 - E0 + V from E at qd, -qd and 0."""
        if self.plan.base is None:
            return self.kinetic_energy(t, q, qd) + self.potential_energy(t, q)
        Ep, Em, E0 = (self.kinetic_energy(t, q, v) for v in (qd, -qd, np.zeros_like(qd)))
        return 0.5 * (Ep + Em) - 2.0 * E0 + self.potential_energy(t, q)

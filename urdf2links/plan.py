"""A scene compiled for the solver: only the terms the scene calls for.

``compile_plan(scene, model)`` decides once which terms exist; the right-hand side then calls
exactly those and nothing else:

==============  ==================================================  ==============================
term            computed by                                         present when
==============  ==================================================  ==============================
A, e            :meth:`RecursivePlan.mass_matrix`, ``.bias``        always (the kinetic energy)
base            :func:`~urdf2links.transforms.base_transforms`      ``[base]`` is given
G               :meth:`RecursivePlan.gravity`                       ``[gravity]`` is given
Q               :meth:`RecursivePlan.generalized_forces`            ``[[force]]`` or ``[[moment]]``
tau             joint torques ``[[torque]]``                        ``[[torque]]``
spring          ``-k (q - rest)`` (a potential)                     a ``[[spring]]`` with k > 0
damper          ``-c qd`` (dissipation D, (5.1))                    a ``[[spring]]`` with c > 0
==============  ==================================================  ==============================

``plan.rhs`` is the compiled right-hand side (:class:`~urdf2links.scene_kernels.CompiledScene`,
with the same flags: a term the scene does not call for is switched off there too);
``plan.python_rhs`` the same in numpy, its readable twin and oracle.

The state integrated is ``y = (q, qd, W)``: ``W`` is the work done on the system by everything
that is not a potential (Q, tau, dampers, and the moving base through ``-dL/dt``), so that
``h(t) - h(0) - W(t)`` (``h`` the energy function, ``E + V`` for a fixed base) measures the
integration's own energy error (the power balance).
"""

from __future__ import annotations

import numpy as np

from .scene_kernels import CompiledScene
from .transforms import BaseState, base_transforms

__all__ = ["Plan", "compile_plan"]


class Plan:
    """The compiled scene. ``terms`` lists what is computed; :meth:`describe` says it in words."""

    def __init__(self, scene, model):
        self.scene = scene
        self.model = model
        self.rp = model._plan
        tree = model.tree
        names = model.coordinate_names
        self.n = model.n
        self.base = scene.base
        self.gravity_vector = None if scene.gravity is None else np.asarray(scene.gravity, float)
        frame_of = model.info.get("frame_of") or {nm: (nm, np.eye(4).tolist()) for nm in tree.link_names}
        self.loads = []
        for load in scene.loads:
            tname, X = frame_of[load.link]
            X = np.asarray(X)
            self.loads.append((tree.link_index(tname), X, load))
        self.torque_index = np.array([names.index(c) for c, _ in scene.torques], dtype=int)
        self.torque_funcs = [f for _, f in scene.torques]
        springs = [s for s in scene.springs if s.stiffness > 0]
        dampers = [s for s in scene.springs if s.damping > 0]
        self.spring_index = np.array([names.index(s.coordinate) for s in springs], dtype=int)
        self.stiffness = np.array([s.stiffness for s in springs])
        self.rest = np.array([s.rest for s in springs])
        self.damper_index = np.array([names.index(s.coordinate) for s in dampers], dtype=int)
        self.damping = np.array([s.damping for s in dampers])
        self.terms = tuple(t for t, on in (
            ("A", True), ("e", True), ("base", self.base is not None), ("G", self.gravity_vector is not None),
            ("Q", bool(self.loads)), ("tau", len(self.torque_funcs) > 0), ("spring", len(springs) > 0),
            ("damper", len(dampers) > 0)) if on)
        self.nfev = 0
        self.rhs = CompiledScene(self)
        """``y' = (qd, q'', P)`` for ``y = (q, qd, W)`` (2n + 1,): the compiled right-hand side
        (:mod:`urdf2links.scene_kernels`), equal to :meth:`python_rhs` to rounding."""

    # -- pieces ----------------------------------------------------------------------------------
    def base_state(self, t) -> BaseState | None:
        if self.base is None:
            return None
        f = self.base
        return BaseState(np.array([g(t) for g in f]), np.array([g.derivative(t) for g in f]),
                         np.array([g.second_derivative(t) for g in f]))

    def _wrenches(self, t):
        out = []
        for link, X, load in self.loads:
            v = np.asarray(load.value(t), float)
            if load.frame == "link":
                v = X[:3, :3] @ v  # URDF link axes -> tree link axes
            point = X[:3, :3] @ load.point + X[:3, 3]
            if load.kind == "force":
                out.append((link, v, np.zeros(3), point, load.frame))
            else:
                out.append((link, np.zeros(3), v, point, load.frame))
        return out

    def generalized_forces(self, t, q, qd, kin=None) -> np.ndarray:
        """Everything on the right of (5.29) but ``-G - e``: Q of loads, tau, springs, dampers. (n,)"""
        model = self.model
        f = np.zeros(self.n)
        if self.loads:
            if kin is None:
                qt, _ = model._tree_state(q)
                kin = self.rp.kinematics(qt, None, _base_T(self.base_state(t)))
            f += model._reduce(self.rp.generalized_forces(kin, self._wrenches(t)))
        if self.torque_funcs:
            f[self.torque_index] += [g(t) for g in self.torque_funcs]
        if self.spring_index.size:
            f[self.spring_index] -= self.stiffness * (q[self.spring_index] - self.rest)
        if self.damper_index.size:
            f[self.damper_index] -= self.damping * qd[self.damper_index]
        return f

    def accelerations(self, t, q, qd, *, with_power: bool = False):
        """q'' of (5.29) with exactly the scene's terms; with ``with_power`` also the power of the
        non-potential forces and of the base (see :meth:`power`), from the same kinematics."""
        self.nfev += 1
        model = self.model
        qt, qdt = model._tree_state(q, qd)
        base_T = _base_T(self.base_state(t))
        A, rhs, kin = model.equation(qt, qdt, base_T, gravity_vector=self.gravity_vector)
        f = self.generalized_forces(t, q, qd, kin)
        qdd = model.solve_mass_matrix(A, rhs + f, q=q)
        if not with_power:
            return qdd
        return qdd, self._power(qd, q, f, kin, base_T)

    def _power(self, qd, q, f, kin, base_T) -> float:
        P = 0.0
        if any(term in self.terms for term in ("Q", "tau", "damper")):
            f = f.copy()
            if self.spring_index.size:  # springs are a potential, not work
                f[self.spring_index] += self.stiffness * (q[self.spring_index] - self.rest)
            P += float(qd @ f)
        if base_T is not None:
            dE, dV = self.rp.explicit_time_rates(kin, base_T, self.gravity_vector)
            P -= dE - dV  # -dL/dt
        return P

    def python_rhs(self, t, y) -> np.ndarray:
        """``y' = (qd, q'', P)`` for ``y = (q, qd, W)`` (2n + 1,), in Python (numpy recursive form):
        the readable twin of the compiled ``rhs``."""
        n = self.n
        q, qd = y[:n], y[n:2 * n]
        out = np.empty(2 * n + 1)
        out[:n] = qd
        out[n:2 * n], out[2 * n] = self.accelerations(t, q, qd, with_power=True)
        return out

    def power(self, t, q, qd) -> float:
        """Power of the non-potential forces, ``qd . (Q + tau - c qd)``, and of the base, ``-dL/dt``
        (the explicit time derivative of the Lagrangian at fixed (q, qd))."""
        return float(self.accelerations(t, q, qd, with_power=True)[1])

    # -- energy ----------------------------------------------------------------------------------
    def kinetic_energy(self, t, q, qd) -> float:
        return self.model.kinetic_energy(q, qd, t=t, base=self.base_state(t))

    def potential_energy(self, t, q) -> float:
        """V = V of gravity (5.21) + spring energies 0.5 k (q - rest)^2."""
        V = 0.0
        if self.gravity_vector is not None:
            qt, _ = self.model._tree_state(q)
            kin = self.rp.kinematics(qt, None, _base_T(self.base_state(t)))
            V += self.rp.potential_energy(kin, self.gravity_vector)
        if self.spring_index.size:
            V += 0.5 * float(self.stiffness @ (q[self.spring_index] - self.rest) ** 2)
        return V

    def energy_function(self, t, q, qd) -> float:
        """h = qd . dL/dqd - L; equals E + V for a fixed base. E is quadratic in qd
        (E = E2 + E1 + E0), so h = E2 - E0 + V from E at qd, -qd and 0."""
        if self.base is None:
            return self.kinetic_energy(t, q, qd) + self.potential_energy(t, q)
        Ep, Em, E0 = (self.kinetic_energy(t, q, v) for v in (qd, -qd, np.zeros_like(qd)))
        return 0.5 * (Ep + Em) - 2.0 * E0 + self.potential_energy(t, q)

    # -- words -----------------------------------------------------------------------------------
    def describe(self) -> str:
        s, m = self.scene, self.model
        lines = [f"scene {s.name!r}: robot {m.name!r} ({m.n} coordinates, {m.tree.n_links} links)",
                 f"terms computed: {', '.join(self.terms)}"]
        skipped = [t for t in ("base", "G", "Q", "tau", "spring", "damper") if t not in self.terms]
        lines.append(f"not computed (the scene does not call for them): {', '.join(skipped) or 'nothing'}")
        all_coords = ", ".join(m.coordinate_names)
        lines.append(f"  A, e: all coordinates ({all_coords})")
        if s.base is not None:
            lines.append("  base {A}: " + "; ".join(f"{p}: {f.describe()}" for p, f in
                                                   zip(("x", "y", "z", "phi_x", "phi_y", "phi_z"), s.base)))
        if self.gravity_vector is not None:
            lines.append(f"  G: gravity {self.gravity_vector.tolist()} m/s^2, all coordinates")
        for link, X, load in self.loads:
            lines.append(f"  Q: {load.kind} on {load.link!r} ({load.frame} axes): {load.value.describe()}"
                         f"; touches the coordinates that move {load.link!r}")
        for (c, f) in s.torques:
            lines.append(f"  tau: {c}: {f.describe()}")
        for sp in s.springs:
            lines.append(f"  spring/damper on {sp.coordinate}: k = {sp.stiffness:g}, rest = {sp.rest:g}, c = {sp.damping:g}")
        r = s.run
        lines.append(f"run: t_end {r.t_end:g} s, method {r.method}, rtol {r.rtol:g}, atol {r.atol:g}"
                     + (f", dt {r.dt:g}" if r.dt else "") + f", {r.samples} samples")
        return "\n".join(lines)


def _base_T(state):
    return None if state is None else base_transforms(state)


def compile_plan(scene, model) -> Plan:
    """Compile ``scene`` for ``model`` (names checked)."""
    scene.check_names(model)
    return Plan(scene, model)

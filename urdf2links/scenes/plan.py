"""A scene compiled for the solver: which terms exist, decided once, and the compiled right-hand side.

``compile_plan(scene, model)`` decides which terms the scene calls for; the right-hand side
(:class:`~urdf2links.scenes.scene_kernels.CompiledScene`, ``plan.rhs``) then computes exactly those, with
flags that switch the others off:

==============  ==================================================  ==============================
term            computed by                                         present when
==============  ==================================================  ==============================
A, e            :func:`urdf2links.dynamics.kernels.dynamics`                 always (the kinetic energy)
base            the base factors of :func:`~urdf2links.dynamics.kernels.kinematics`  ``[base]`` is given
G               gravity as a base acceleration (kinematics)         ``[gravity]`` is given
Q               :func:`urdf2links.dynamics.kernels.add_wrench`               ``[[force]]`` or ``[[moment]]``
tau             joint torques ``[[torque]]``                        ``[[torque]]``
spring          ``-k (q - rest)`` (a potential)                     a ``[[spring]]`` with k > 0
damper          ``-c qd`` (dissipation D)                           a ``[[spring]]`` with c > 0, or the
                                                                    file's damping with ``[dampers]``
gravcomp        ``-gravcomp m g`` at a body's COM (a constant load) ``[gravcomp]`` (MJCF ``from_file``,
                                                                    ``factor``, ``bodies``) and ``[gravity]``
actuator        MuJoCo's actuator law (E55): ``gear (gain c +      ``[[actuator]]`` (or ``--hold``)
                b0 + b1 gear q + b2 gear q')``, both clamps
computed_torque the scene's inverse dynamics at a reference (E57): ``[[computed_torque]]``
                one more O(n) pass
==============  ==================================================  ==============================

Armature (MJCF) is part of ``A`` and ``e`` (docs/equations.md (E49)), like the links' inertia: always
computed. A spring comes from a ``[[spring]]`` or, with ``[springs] from_file``, an MJCF joint's
stiffness at its springref.

The state integrated is ``y = (q, qd, W)``: ``W`` is the work done on the system by everything
that is not a potential (Q, tau, dampers, and the moving base through ``-dL/dt``), so that
``h(t) - h(0) - W(t)`` (``h`` the energy function, ``E + V`` for a fixed base) measures the
integration's own energy error (the power balance, docs/equations.md (E40)). The same right-hand side
in numpy, the oracle the tests compare it with, is :class:`urdf2links.scenes.python_plan.PythonPlan`.
"""

from __future__ import annotations

import numpy as np

from ..dynamics.transforms import BaseState
from .actuators import actuator_forces, describe_actuator, resolve_actuators
from .contact import resolve_contacts
from .constraints import describe_constraints
from .file_constraints import plan_constraints
from .functions import Constant
from .scene_kernels import CompiledScene

__all__ = ["Plan", "compile_plan", "as_plan"]


class Plan:
    """The compiled scene. ``terms`` lists what is computed; :meth:`describe` says it in words."""

    def __init__(self, scene, model):
        self.scene = scene
        self.model = model
        tree = model.tree
        names = model.coordinate_names
        self.n = model.n
        self.base = scene.base
        self.gravity_vector = None if scene.gravity is None else np.asarray(scene.gravity, float)
        frame_of = model.info.get("frame_of") or {nm: (nm, np.eye(4).tolist()) for nm in tree.link_names}
        self.loads = []
        gravcomp, self.gravcomp_notes = scene.gravcomp_loads(model)
        for load in scene.loads + gravcomp:
            tname, X = frame_of[load.link]
            X = np.asarray(X)
            self.loads.append((tree.link_index(tname), X, load))
        self.n_gravcomp = len(gravcomp)
        self.torque_index = np.array([names.index(c) for c, _ in scene.torques], dtype=int)
        self.torque_funcs = [f for _, f in scene.torques]
        self.spring_set = scene.springs_for(model)
        """The scene's springs and dampers on this model (URDF damping included when asked) and notes."""
        springs = [s for s in self.spring_set.springs if s.stiffness > 0]
        dampers = [s for s in self.spring_set.springs if s.damping > 0]
        self.spring_index = np.array([names.index(s.coordinate) for s in springs], dtype=int)
        self.stiffness = np.array([s.stiffness for s in springs])
        self.rest = np.array([s.rest for s in springs])
        self.damper_index = np.array([names.index(s.coordinate) for s in dampers], dtype=int)
        self.damping = np.array([s.damping for s in dampers])
        self.actuator_set = resolve_actuators(scene.actuators, model, where=str(scene.path or scene.name),
                                              file_tendons=bool(getattr(scene, "file_constraints", False)))
        """The scene's actuators on this model (:mod:`urdf2links.scenes.actuators`) and notes."""
        self.contact_set = resolve_contacts(scene.contacts, model, scene.initial_state(model)[0],
                                            where=str(scene.path or scene.name))
        """Issue 37: the scene's contact spheres on this model (:mod:`urdf2links.scenes.contact`)."""
        self.reference_funcs = self._references(scene, model)
        """``[[computed_torque]]``: the reference of every coordinate (n functions), or () without one."""
        self.constraints = plan_constraints(scene, model)    # issue 36: closed loops, couplings, fixed tendons
        """:class:`~urdf2links.scenes.constraints.SceneConstraints` or None (E68)-(E76)."""
        self.terms = tuple(t for t, on in (
            ("A", True), ("e", True), ("base", self.base is not None), ("G", self.gravity_vector is not None),
            ("Q", bool(scene.loads)), ("tau", len(self.torque_funcs) > 0), ("spring", len(springs) > 0),
            ("damper", len(dampers) > 0), ("gravcomp", self.n_gravcomp > 0),
            ("actuator", bool(self.actuator_set.actuators)), ("computed_torque", bool(self.reference_funcs)),
            ("constraint", self.constraints is not None and len(self.constraints.cset) > 0),
            ("tendon", self.constraints is not None and bool(self.constraints.tendons)),
            ("contact", bool(self.contact_set))) if on)
        self.rhs = CompiledScene(self)
        """``y' = (qd, q'', P)`` for ``y = (q, qd, W)`` (2n + 1,): the compiled right-hand side
        (:mod:`urdf2links.scenes.scene_kernels`)."""

    @staticmethod
    def _references(scene, model) -> tuple:
        """Every coordinate's reference for the computed torque: the scene's, else held at its initial value."""
        if not scene.computed_torque:
            return ()
        given = dict(scene.computed_torque)
        q0, _ = scene.initial_state(model)
        return tuple(given.get(nm, Constant(float(q0[i]))) for i, nm in enumerate(model.coordinate_names))

    # -- the scene's inputs at a time --------------------------------------------------------------
    def actuator_forces(self, t, q, qd) -> np.ndarray:
        """The actuators' generalized forces (n,) at ``t``, ``q``, ``qd`` (E55), in numpy."""
        return actuator_forces(self.actuator_set.actuators, t, q, qd, self.n)

    def ctrl(self, t) -> np.ndarray:
        """Every actuator's control at ``t`` (before MuJoCo's ctrlrange clamp), in the plan's order."""
        return np.array([float(a.ctrl(t)) for a in self.actuator_set.actuators])

    def reference(self, t, order: int = 0) -> np.ndarray:
        """The computed torque's reference (n,) at ``t`` (``order`` 0, 1, 2: r, r', r'')."""
        return np.array([float(f._at(t, order)) for f in self.reference_funcs])

    def computed_torque(self, t) -> np.ndarray:
        """The computed torque (n,) at ``t`` (E57), compiled (:func:`urdf2links.scenes.scene_kernels.computed_torque`)."""
        return self.rhs.computed_torque(t)

    def base_state(self, t) -> BaseState | None:
        """Pose, rate and acceleration of {A} at ``t`` (:meth:`Scene.base_state`); None for a fixed base."""
        return self.scene.base_state(t)

    def torques(self, t) -> np.ndarray:
        """Joint torques tau (n,) at ``t`` (zeros where none acts)."""
        tau = np.zeros(self.n)
        if self.torque_funcs:
            np.add.at(tau, self.torque_index, [g(t) for g in self.torque_funcs])
        return tau

    def wrenches(self, t) -> list:
        """The loads at ``t`` as ``(tree link index, force (3,), moment (3,), point (3,), frame)``, in
        the tree link's axes where ``frame`` is ``"link"``."""
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

    def energies(self, t, q, qd):
        """``(E, V, h)`` at times ``t`` (m,) and states ``q``, ``qd`` (m, n): kinetic energy, potential
        energy (gravity and springs) and the energy function, compiled."""
        return self.rhs.energies(t, q, qd)

    # -- words -----------------------------------------------------------------------------------
    def _contact_lines(self) -> list[str]:
        """Issue 37: the contact's lines of :meth:`describe`."""
        specs = {id(r[3]): r[3] for r in self.contact_set.rows}
        out = []
        for spec in specs.values():
            on = [f"{s.link} (r {s.radius:g} m, {s.source})" for r, s in zip(self.contact_set.rows,
                                                                             self.contact_set.spheres) if r[3] is spec]
            out.append(f"  contact (E77-E80, Q through the links' wrenches): {spec.describe()}; spheres on "
                       + ", ".join(on))
        if out and self.reference_funcs:
            out.append("  note: the computed torque (E57) leaves the contact out of its inverse dynamics")
        return out

    def describe(self) -> str:
        s, m = self.scene, self.model
        lines = [f"scene {s.name!r}: robot {m.name!r} ({m.n} coordinates, {m.tree.n_links} links)",
                 f"terms computed: {', '.join(self.terms)}"]
        skipped = [t for t in ("base", "G", "Q", "tau", "spring", "damper", "gravcomp", "actuator", "computed_torque")
                   if t not in self.terms]
        skipped += [t for t, key in (("constraint", "equalities"), ("tendon", "tendons"))      # issue 36: a file's own
                    if t not in self.terms and m.info.get(key)]
        if "gravcomp" in skipped and not m.info.get("gravcomp"):
            skipped.remove("gravcomp")
        lines.append(f"not computed (the scene does not call for them): {', '.join(skipped) or 'nothing'}")
        all_coords = ", ".join(m.coordinate_names)
        lines.append(f"  A, e: all coordinates ({all_coords})")
        if m.tree.has_armature:
            arm = [f"{nm} {a:g}" for nm, a in zip(m.tree.coordinate_names, m.tree.armature) if a]
            lines.append(f"  armature (part of A and e, always): {', '.join(arm)}")
        if s.base is not None:
            lines.append("  base {A}: " + "; ".join(f"{p}: {f.describe()}" for p, f in
                                                   zip(("x", "y", "z", "phi_x", "phi_y", "phi_z"), s.base)))
        if self.gravity_vector is not None:
            lines.append(f"  G: gravity {self.gravity_vector.tolist()} m/s^2, all coordinates")
        for link, X, load in self.loads[:len(self.loads) - self.n_gravcomp]:
            lines.append(f"  Q: {load.kind} on {load.link!r} ({load.frame} axes): {load.value.describe()}"
                         f"; touches the coordinates that move {load.link!r}")
        for link, X, load in self.loads[len(self.loads) - self.n_gravcomp:]:
            lines.append(f"  gravcomp: {load.value(0.0).tolist()} N (world axes) at the COM of {load.link!r}")
        for (c, f) in s.torques:
            lines.append(f"  tau: {c}: {f.describe()}")
        for sp in self.spring_set.springs:
            lines.append(f"  spring/damper on {sp.coordinate}: k = {sp.stiffness:g}, rest = {sp.rest:g}, c = {sp.damping:g}")
        for a in self.actuator_set.actuators:
            lines.append(f"  actuator {a.name!r} on {a.coordinate} ({a.source}): {describe_actuator(a)}")
        if self.reference_funcs:
            named = dict(s.computed_torque)
            lines.append("  computed_torque: inverse dynamics of the scene at the reference (one more O(n) pass): "
                         + "; ".join(f"{c}: {f.describe()}" for c, f in named.items())
                         + "; the other coordinates held at their initial value")
        lines += describe_constraints(self.constraints, m)
        if self.constraints is not None and len(self.constraints.cset):     # issue 45
            mode = getattr(s, "change_point", "continue")
            lines.append(f"  change_point = {mode!r}: a row that loses its independence (a Schur pivot at or below "
                         "1e-12 of S scaled to a unit diagonal, E88) " + ("stops the run with the named DynamicsError"
                         if mode == "stop" else "is dropped there and the run goes on; each event (time, row, pivot) "
                         "is named in the report"))
        lines += self._contact_lines()
        lines += [f"  note: {n}" for n in (*self.contact_set.notes, *self.spring_set.notes, *self.gravcomp_notes, *self.actuator_set.notes,
                                          *s.notes)]
        r = s.run
        lines.append(f"run: t_end {r.t_end:g} s, method {r.method}, rtol {r.rtol:g}, atol {r.atol:g}"
                     + (f", dt {r.dt:g}" if r.dt else "") + f", {r.samples} samples")
        return "\n".join(lines)


def compile_plan(scene, model) -> Plan:
    """Compile ``scene`` for ``model`` (names checked)."""
    scene.check_names(model)
    return Plan(scene, model)


def as_plan(source, *, model=None) -> Plan:
    """The compiled run of ``source``, made once and passed down to every stage that runs it (the
    warm-up, ``simulate``, MuJoCo's inputs): a :class:`Plan` is returned as it is; a
    :class:`~urdf2links.scenes.scene.Scene` or a scene file is loaded, its robot loaded (or ``model``
    taken) and compiled."""
    if isinstance(source, Plan):
        if model is not None and model is not source.model:
            raise ValueError("as_plan: a Plan brings its own model; model= must be None or that model")
        return source
    from .scene import Scene
    from .scene_read import load_scene

    scene = source if isinstance(source, Scene) else load_scene(source)
    return compile_plan(scene, scene.model() if model is None else model)


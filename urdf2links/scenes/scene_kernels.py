"""A compiled plan's right-hand side in numba, and the energies of its samples.

:func:`scene_rhs` computes ``y' = (q', q'', P)`` of ``y = (q, q', W)`` from the plan's flat arrays
(:mod:`urdf2links.scenes.scene_arrays`) next to the tree's (:mod:`urdf2links.dynamics.tree_arrays`), without
Python, so the compiled integration loops (:mod:`urdf2links.integration.loops`) call it directly. It computes
exactly the terms the plan lists: flags switch off the base (no base factors, no ``-dL/dt``), G (zero
gravity), Q (no wrench is added), tau, springs, dampers, actuators (MuJoCo's law, E55) and the
computed torque (the scene's inverse dynamics at its reference, E57, one more O(n) pass). Without coupled coordinates ``q''`` is
solved in place by the tree-sparse factorization (:mod:`urdf2links.dynamics.factor`, E47); with them, by a
dense Cholesky of ``C^T A C`` (E46).

**Effects compiled only where a scene has them.** Some terms are large pieces of compiled code that
most scenes never use: the computed torque (a second O(n) pass), the coupled coordinates' dense
solve, the actuators and the loads (forces, moments, gravcomp, contact). Each is an *effect*
(:data:`EFFECTS`): :func:`_rhs` takes one marker per effect (``FX``, :func:`effects_of`), ``1`` when
the scene has it and ``None`` when not, and the code of an effect sits behind ``if marker is not
None:``. numba decides such a test when it compiles (the marker's type is ``none`` or ``int64``) and
leaves the dead branch out, with every function only it calls: a pendulum's right-hand side never
compiles the computed torque.

**One compiled loop for every combination.** Each combination of effects is a compiled (and cached)
variant of :func:`_rhs`, wrapped as a C function (:func:`rhs_function`, numba's ``cfunc``) whose type
is its signature alone. The integration loops (:mod:`urdf2links.integration.loops`) get it as the last
of the scene's ``args`` and call it through its address: they are compiled once, not once per
combination of effects (a report's eleven scenes compiled DOP853's loop six times and Radau5's three
times when the loops called :func:`_rhs` directly, each time with the whole right-hand side inlined).
The indirect call costs 30-90 ns, 3-6 % of an evaluation in a bare loop and nothing measurable in the
RK4 loop (docs/speed.md).

The scene's inputs at ``t`` (time functions, the base's motion, loads, torques, dampers, actuators,
springs) are :mod:`urdf2links.scenes.scene_inputs`; this module assembles them into ``y'``.

To add an effect (a constraint, a contact): its arrays and counts in
:mod:`urdf2links.scenes.scene_arrays`; its kernel here or, for an input at ``t``, in
:mod:`urdf2links.scenes.scene_inputs`; its name in :data:`EFFECTS` and its test in
:func:`effects_of`; one marker argument more in :func:`_rhs` and in :func:`_variant`, and its call behind ``if marker is not None:`` where it acts (:func:`_rhs` for a
pass of its own, :func:`_applied` for a generalized force).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..compilation import kernel, one_signature

from ..dynamics.factor import cholesky, cholesky_solve, ltdl, ltdl_solve
from ..dynamics.inverse_kernels import own_armature
from ..dynamics.kernels import base_power, clear_wrenches, dynamics, energies, kinematics
from ..dynamics.model_kernels import reduce_mass, reduce_vector
from ..dynamics.tree_arrays import W_B, W_Q, W_SIZE, Tree, nonneg
from .contact_kernels import contact_potential, contact_wrenches   # issue 37
from .constraint_kernels import FAIL_BASE, kkt, tendon_forces     # issue 45
from .constraint_arrays import reset_constraint_stats
from .scene_arrays import (S_C, S_CON, S_CT, S_CT_FN, S_GRAV, S_NA, S_NCONTACT, S_REST, S_SPRING_IDX, S_STIFFNESS,
                           S_XSIZE, Scene, compile_scene)
from .scene_inputs import _apply_loads, _base_values, _inputs, _springs, _tree_state, fn_eval

__all__ = ["CompiledScene", "scene_rhs", "rhs_function", "rhs_signature", "scene_energies", "computed_torque",
           "ct_torque_at", "EFFECTS", "effects_of"]

#: The effects compiled only into the scenes that have them (module doc), in the order of ``FX``.
EFFECTS = ("loads", "actuators", "computed_torque", "coupled", "constraints")


def effects_of(SI) -> tuple:
    """``FX``: one marker per :data:`EFFECTS`, ``1`` when the compiled scene ``SI`` has the effect, else ``None``."""
    # "loads": every wrench on links, the scene's loads (forces, moments, gravcomp) or its contact (issue 37)
    present = {"loads": SI[5] > 0 or SI[S_NCONTACT] > 0, "actuators": SI[S_NA] > 0, "computed_torque": SI[S_CT] > 0, "coupled": SI[4] != 0,
               "constraints": SI[S_CON] > 0}     # issue 45: constraints and fixed tendons (E72), (E76)
    return tuple(1 if present[name] else None for name in EFFECTS)


# -- the right-hand side ------------------------------------------------------------------------------
@one_signature
@kernel
def _applied(scene, t, y, Q, Q_at, f, f_at, loads, actuators, ct):
    """``f[f_at:f_at + n]``: every generalized force the scene applies besides ``-(e + G)``: Q of the
    loads (``Q[Q_at:]``, when there are loads), joint torques, dampers ``-c q'``, actuators, the computed
    torque (already in ``X``, :func:`computed_torque`) and springs ``-k (q - rest)``. Returns the power
    ``q' . f`` of the non-potential ones (springs excluded). ``loads``, ``actuators``, ``ct``: the
    effects' markers (module doc)."""
    SI, SF, X = scene
    n = SI[0]
    for i in range(n):
        f[f_at + i] = 0.0
    if loads is not None:
        for i in range(n):
            f[f_at + i] = Q[Q_at + i]
    _inputs(SI, SF, t, y, 0, f, f_at, actuators)
    if ct is not None:
        xt = ct_torque_at(n, SI[1])
        for i in range(n):
            f[f_at + i] += X[xt + i]
    P = 0.0
    for i in range(n):
        P += y[n + i] * f[f_at + i]
    _springs(SI, SF, y, 0, f, f_at)
    return P


@one_signature
@kernel
def ct_torque_at(n, nt):
    """Where :func:`computed_torque` leaves the torque in the scene's scratch (scene_arrays.scratch_size)."""
    return 2 * nt + 18 + 2 * n * n + 2 * n + 3 * n + nt


@one_signature
@kernel
def computed_torque(t, tree, scene):
    """The computed torque at ``t`` (E57) into ``X[ct_torque_at(n, nt):]`` (n,): the inverse dynamics of
    the scene at its reference ``(r, r', r'')(t)`` (every coordinate's ``ct_fn``): ``A r'' + e + G - Q``
    (E54; the scene's base and loads at ``t``) minus every other force the scene applies there (torques,
    dampers, actuators, springs), so that ``q = r`` solves the scene when it starts on it. Overwrites the
    tree's scratch ``W`` and the start of ``X`` (``tree``: :class:`~urdf2links.dynamics.tree_arrays.Tree`,
    ``scene``: :class:`~urdf2links.scenes.scene_arrays.Scene`)."""
    TI, W = tree.TI, tree.W
    SI, SF, X = scene
    n, nt = SI[0], SI[1]
    has_base, coupled, loads = SI[2] != 0, SI[4] != 0, SI[5] > 0
    g = SI[S_GRAV]
    gx, gy, gz = SF[g], SF[g + 1], SF[g + 2]
    xb = 2 * nt
    xr = 2 * nt + 18 + 2 * n * n + 2 * n
    xa = xr + 2 * n
    xq = xa + n
    xt = xq + nt
    xo = xt + n
    cf = SI[S_CT_FN]
    for i in range(n):
        j = SI[cf + i]
        X[xr + i] = fn_eval(SI, SF, j, t, 0)
        X[xr + n + i] = fn_eval(SI, SF, j, t, 1)
        X[xa + i] = fn_eval(SI, SF, j, t, 2)
    if has_base:
        _base_values(SI, SF, t, X, xb)
    if coupled:
        C = SI[S_C]
        _tree_state(SI, SF, X, xr, X, xr + n, 1.0, X)
        for a in range(nt):
            s = 0.0
            for j in range(n):
                s += SF[C + a * n + j] * X[xa + j]
            X[xq + a] = s
        kinematics(tree, X, 0, X, nt, True, X, xb, has_base, gx, gy, gz, X, xq)
    else:
        kinematics(tree, X, xr, X, xr + n, True, X, xb, has_base, gx, gy, gz, X, xa)
    if loads:
        clear_wrenches(tree)
        _apply_loads(SI, SF, tree, t)
    dynamics(tree, False, loads, False)
    own_armature(tree, X, xq if coupled else xa)
    wb, wq = nonneg(TI[W_B]), nonneg(TI[W_Q])
    if coupled:
        C = SI[S_C]
        for i in range(n):
            s = 0.0
            for a in range(nt):
                v = -W[wb + a]
                if loads:
                    v -= W[wq + a]
                s += SF[C + a * n + i] * v
            X[xt + i] = s
    else:
        for i in range(n):
            v = -W[wb + i]
            if loads:
                v -= W[wq + i]
            X[xt + i] = v
    for i in range(n):
        X[xo + i] = 0.0
    _inputs(SI, SF, t, X, xr, X, xo, 1)
    _springs(SI, SF, X, xr, X, xo)
    for i in range(n):
        X[xt + i] -= X[xo + i]


@one_signature
@kernel
def _coupled_solve(tree, scene, t, y, out, loads, actuators, ct):
    """Coupled coordinates: ``A = C^T A_tree C``, ``rhs = C^T (b + Q) + f`` and ``q''`` by a dense
    Cholesky into ``out[n:2 n]``; returns the pivot (scratch layout: :func:`scratch_size`)."""
    TI, W = tree.TI, tree.W
    SI, SF, X = scene
    n, nt = SI[0], SI[1]
    C = SF[SI[S_C]:SI[S_C] + nt * n].reshape((nt, n))
    xa = 2 * nt + 18
    xl = xa + n * n
    xf = xl + n * n
    if loads is not None:
        reduce_vector(C, W, TI[W_Q], X, xf + n, 1.0)
    P = _applied(scene, t, y, X, xf + n, X, xf, loads, actuators, ct)
    reduce_vector(C, W, TI[W_B], out, n, 1.0)
    for i in range(n):
        out[n + i] += X[xf + i]
    reduce_mass(tree, C, X[xa:xl].reshape((n, n)))
    pivot = cholesky(X, xa, n, X, xl)
    if pivot < 0:
        cholesky_solve(X, xl, n, out, n)
    return pivot, P


@njit(cache=True)
def scene_rhs(t, y, out, TI, TF, W, SI, SF, X, rhs):
    """``out = (q', q'', P)`` (2n + 1,) at ``(t, y = (q, q', W))``; ``TI``, ``TF`` the tree's arrays and
    ``W`` its scratch (:class:`~urdf2links.dynamics.tree_arrays.Tree`), ``SI``, ``SF`` the scene's and ``X``
    its scratch (:class:`~urdf2links.scenes.scene_arrays.Scene`), ``rhs`` the compiled
    right-hand side of the scene's effects (:func:`rhs_function`: only their code is compiled).
    Returns -1, or the index of the failing pivot (then ``out`` is NaN). ``P`` is the power of the
    non-potential forces ``q' . (Q + tau - c q' + actuators + computed torque)`` minus the explicit
    rate ``dE/dt - dV/dt`` of a moving base (see :mod:`urdf2links.scenes.plan`). Compiled once: ``rhs``
    is a C function, typed by its signature alone (module doc)."""
    return rhs(t, y, out, TI, TF, W, SI, SF, X)


def _variant(loads, actuators, ct, coupled, constraints):
    """The right-hand side of one combination of effects: :func:`_rhs` with its markers fixed (numba
    takes a closure's variables for constants, and caches each combination apart)."""

    def scene_rhs_of_effects(t, y, out, TI, TF, W, SI, SF, X):
        return _rhs(t, y, out, Tree(TI, TF, W), Scene(SI, SF, X), loads, actuators, ct, coupled, constraints)

    return scene_rhs_of_effects


def rhs_signature():
    """The C signature of every :func:`rhs_function`: ``int64(t, y, out, TI, TF, W, SI, SF, X)``, each
    array one-dimensional and contiguous (``TI``, ``SI`` of int64, the others of float64). Inside, the
    arrays travel as two records, ``tree`` and ``scene`` (free in a function that counts no references)."""
    from numba import types

    f, i = types.float64[::1], types.int64[::1]
    return types.int64(types.float64, f, f, i, f, f, i, f, f)


_VARIANTS: dict = {}


def rhs_function(FX):
    """The compiled right-hand side of the effects ``FX`` (:func:`effects_of`), as a C function of
    :func:`rhs_signature` (:func:`urdf2links.compilation.c_function`), compiled or loaded from the
    cache at its first use in the process. The integration loops receive it as an argument (the
    last of :attr:`CompiledScene.args`): they are compiled once, whatever the scene's effects."""
    fn = _VARIANTS.get(FX)
    if fn is None:
        from ..compilation import c_function

        fn = _VARIANTS[FX] = c_function(_variant(*FX), rhs_signature(), refcounts=False)   # allocates nothing
    return fn


@njit(inline="always")
def _rhs(t, y, out, tree, scene, loads, actuators, ct, coupled, constraints):
    """:func:`scene_rhs` with the markers of :data:`EFFECTS` as arguments of their own (numba drops
    the code behind ``if marker is not None`` when a marker is None: module doc). Inlined into each
    :func:`_variant` (numba's ``inline="always"``, before typing: the markers are the closure's
    constants there): compiled once per combination, inside its C function, not a second time on its
    own (every compiled function generates the machine code of all it calls anew). ``tree``: the tree's
    arrays (:class:`~urdf2links.dynamics.tree_arrays.Tree`), ``scene``: the scene's
    (:class:`~urdf2links.scenes.scene_arrays.Scene`)."""
    TI, W = tree.TI, tree.W
    SI, SF, X = scene
    n, nt = SI[0], SI[1]
    has_base = SI[2] != 0
    applied = SI[6] > 0 or SI[7] > 0 or SI[8] > 0 or loads is not None or actuators is not None or ct is not None
    g = SI[S_GRAV]
    gx, gy, gz = SF[g], SF[g + 1], SF[g + 2]
    xb = 2 * nt
    if ct is not None:          # first: it uses the tree's scratch for its own pass
        computed_torque(t, tree, scene)
    if has_base:
        _base_values(SI, SF, t, X, xb)
    if coupled is not None:
        _tree_state(SI, SF, y, 0, y, n, 1.0, X)
        kinematics(tree, X, 0, X, nt, True, X, xb, has_base, gx, gy, gz)
    else:
        kinematics(tree, y, 0, y, n, True, X, xb, has_base, gx, gy, gz)
    Pel = 0.0
    if loads is not None:       # loads or contact (effects_of): wrenches on links
        clear_wrenches(tree)
        _apply_loads(SI, SF, tree, t)
        Pel = contact_wrenches(SI, SF, tree)       # issue 37: ground contact (E80), its elastic power (E81)
    dynamics(tree, True, loads is not None, has_base)
    for i in range(n):
        out[i] = y[n + i]
    P = 0.0
    if coupled is not None:
        pivot, P = _coupled_solve(tree, scene, t, y, out, loads, actuators, ct)
    else:
        wb = nonneg(TI[W_B])
        if applied:
            xf = 2 * nt + 18
            P = _applied(scene, t, y, W, TI[W_Q], X, xf, loads, actuators, ct)
            for i in range(n):
                out[n + i] = W[wb + i] + X[xf + i]
        else:
            for i in range(n):
                out[n + i] = W[wb + i]
        pivot = ltdl(TI, W)
        if pivot < 0:
            ltdl_solve(TI, W, out, n)
    if constraints is not None and pivot < 0:    # issue 45: the tendons (E76), then the KKT solve (E72)
        P += tendon_forces(tree, scene, t, y, out, coupled is not None)
        pivot = kkt(tree, scene, t, y, out, coupled is not None)
    if pivot >= 0:
        for i in range(out.size):
            out[i] = np.nan
        return pivot
    if has_base:   # the base's twist, acceleration and the links' momentum, recorded by the passes
        dE, dV = base_power(tree, gx, gy, gz)
        P -= dE - dV
    out[2 * n] = P + Pel
    return -1


@one_signature
@njit(cache=True)
def scene_energies(ts, Q, QD, out, TI, TF, W, SI, SF, X):
    """At each sample ``k``: ``out[k] = (E, V, h)``: kinetic energy and potential energy of gravity
    (docs/equations.md (E37)) plus springs ``0.5 k (q - rest)^2``, and the energy function ``h``
    (E39) (``E + V`` for a fixed base; ``E2 - E0 + V`` from E at ``q'``, ``-q'`` and 0 for a moving one)."""
    tree = Tree(TI, TF, W)
    n, nt = SI[0], SI[1]
    has_base, coupled = SI[2] != 0, SI[4] != 0
    g = SI[S_GRAV]
    gx, gy, gz = SF[g], SF[g + 1], SF[g + 2]
    xb = 2 * nt
    si, k, rest = SI[S_SPRING_IDX], SI[S_STIFFNESS], SI[S_REST]
    for s in range(ts.size):
        if has_base:
            _base_values(SI, SF, ts[s], X, xb)
        E0 = E1 = E2 = V = 0.0
        for pass_ in range(3 if has_base else 1):
            sign = 1.0 if pass_ == 0 else (-1.0 if pass_ == 1 else 0.0)
            if coupled:
                _tree_state(SI, SF, Q[s], 0, QD[s], 0, sign, X)
            else:
                for i in range(n):
                    X[i] = Q[s, i]
                    X[nt + i] = sign * QD[s, i]
            kinematics(tree, X, 0, X, nt, True, X, xb, has_base, 0.0, 0.0, 0.0)
            E, V = energies(tree, gx, gy, gz)
            if pass_ == 0:
                E0 = E
            elif pass_ == 1:
                E1 = E
            else:
                E2 = E
        for j in range(SI[7]):
            x = Q[s, SI[si + j]] - SF[rest + j]
            V += 0.5 * SF[k + j] * x * x
        V += contact_potential(SI, SF, tree)       # issue 37: the contact's elastic energy (E81)
        out[s, 0] = E0
        out[s, 1] = V
        out[s, 2] = (0.5 * (E0 + E1) - 2.0 * E2 + V) if has_base else E0 + V


class CompiledScene:
    """The compiled right-hand side of a plan: callable ``(t, y) -> (2n + 1,)``, and ``args`` for the
    compiled integration loops (:mod:`urdf2links.integration.loops`). A failing pivot raises the model's named
    :class:`~urdf2links.errors.DynamicsError`."""

    def __init__(self, plan, *, constraints: bool = True, rows: bool = True):
        self.plan = plan
        model = plan.model
        # issue 45: constraints False: the free scene; rows False: its fixed tendons without the constraint rows
        self.SI, self.SF = compile_scene(plan, constraints=constraints, rows=rows)
        self.closure = getattr(plan, "constraints", None) if constraints else None
        self.closure_parts = closure_parts(self.closure)   # what was packed: a later edit of them is seen
        """The constraints compiled in (issue 45): a plan whose ``constraints`` were replaced since is compiled
        again (:func:`urdf2links.integration.constrained.refresh_rhs`)."""
        self.I, self.F = model.compiled              # the tree flattened once, by the model
        self.W = np.zeros(int(self.I[W_SIZE]))
        self.X = np.zeros(int(self.SI[S_XSIZE]))
        reset_constraint_stats(self.SI, self.X)
        self.dim = 2 * model.n + 1
        self.FX = effects_of(self.SI)
        self._function = None

    @property
    def function(self):
        """The compiled right-hand side of this scene's effects (:func:`rhs_function`)."""
        if self._function is None:
            self._function = rhs_function(self.FX)
        return self._function

    @property
    def args(self):
        """``(I, F, W, SI, SF, X, rhs)``: the arguments of :func:`scene_rhs` after the state."""
        return (self.I, self.F, self.W, self.SI, self.SF, self.X, self.function)

    def fresh_args(self):
        """Arguments with their own scratch (for another thread)."""
        X = np.zeros_like(self.X)
        reset_constraint_stats(self.SI, X)
        return (self.I, self.F, np.zeros_like(self.W), self.SI, self.SF, X, self.function)

    def prepare(self, t, y):
        """Compile (or load from the cache) this scene's right-hand side and :func:`scene_rhs` before a
        timed run (:func:`urdf2links.compilation.ensure`)."""
        from .. import compilation

        y = np.ascontiguousarray(y, dtype=float)     # the C function takes contiguous arrays only
        compilation.ensure(scene_rhs, (float(t), y, np.empty(self.dim), *self.args))

    def __call__(self, t, y):
        y = np.ascontiguousarray(y, dtype=float)     # the C function takes contiguous arrays only
        out = np.empty(self.dim)
        pivot = scene_rhs(float(t), y, out, *self.args)
        if pivot >= 0:
            self.failure(t, y)
        return out

    def computed_torque(self, t) -> np.ndarray:
        """The computed torque (n,) at ``t`` (:func:`computed_torque`; zeros without one)."""
        n = self.plan.n
        if self.SI[S_CT] == 0:
            return np.zeros(n)
        SI, X = self.SI, np.zeros_like(self.X)
        computed_torque(float(t), Tree(self.I, self.F, np.zeros_like(self.W)), Scene(SI, self.SF, X))
        xt = ct_torque_at(n, int(SI[1]))
        return X[xt:xt + n].copy()

    def energies(self, t, Q, QD):
        """``(E, V, h)``, each (m,), at sample times ``t`` (m,) and states ``Q``, ``QD`` (m, n)."""
        t = np.ascontiguousarray(t, dtype=float)
        out = np.empty((t.size, 3))
        scene_energies(t, np.ascontiguousarray(Q, dtype=float), np.ascontiguousarray(QD, dtype=float), out,
                       *self.args[:6])
        return out[:, 0], out[:, 1], out[:, 2]

    def check(self, t, y):
        """At a state where the compiled right-hand side failed: raise the model's named
        :class:`~urdf2links.errors.DynamicsError` when A is not positive definite there."""
        y = np.ascontiguousarray(y, dtype=float)
        if not np.all(np.isfinite(y)):
            return
        code = scene_rhs(float(t), y, np.empty(self.dim), *self.fresh_args())
        if code >= FAIL_BASE:       # issue 45: a constraint row dependent here, the scene stops at its change point
            from .constraint_arrays import change_point_error

            raise change_point_error(self.plan, float(t), y, int(code - FAIL_BASE))
        if code >= 0:
            model = self.plan.model
            q = y[:model.n]
            raise model.not_positive_definite(model.mass_matrix(q, t=t, base=self.plan.base_state(t)), q)

    def failure(self, t, y):
        """Raise the model's error at a state where the compiled solve failed."""
        self.check(t, y)
        raise FloatingPointError(f"compiled right-hand side failed at t={t!r} (y={y!r})")


def closure_parts(closure) -> tuple:
    """What a plan's constraints packed into the compiled arrays (the constraint set and the tendons' tuple, held
    so that their identities stay theirs): :func:`urdf2links.integration.constrained.refresh_rhs` compiles again
    when one was replaced."""
    return () if closure is None else (closure, closure.cset, closure.tendons)

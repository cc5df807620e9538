"""A compiled plan (:mod:`urdf2links.plan`) as arrays, and its right-hand side in numba.

:func:`compile_scene` turns a :class:`~urdf2links.plan.Plan` into two flat arrays (``SI`` int64,
``SF`` float64; see :func:`scene_view`) next to the tree's (:mod:`urdf2links.kernels`), so the
right-hand side ``y' = (q', q'', P)`` of ``y = (q, q', W)`` runs without Python and the compiled
integration loops (:mod:`urdf2links.loops`) call it directly. It computes exactly
the terms the plan lists: flags switch off the base (no base factors, no ``-dL/dt``), G (zero
gravity), Q (no wrench is added), tau, springs and dampers.

Time functions (:mod:`urdf2links.functions`) are compiled as data: sums of sines
``offset + rate t + sum a sin(w t + phase)`` (constants have no terms) and piecewise polynomials
(tables: the spline's :class:`scipy.interpolate.PPoly` form), held at the end values outside their
interval with zero derivatives, exactly as the Python functions.
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np
from numba import njit
from scipy.interpolate import BSpline, PPoly

from . import kernels as K
from .functions import Constant, Sines, Table

__all__ = ["CompiledScene", "compile_scene", "scene_rhs", "function_data"]

SceneArrays = namedtuple("SceneArrays", [
    "n", "nt", "has_base", "has_g", "coupled",
    "base_fn",                       # (6,) function index of each base parameter
    "load_link", "load_kind", "load_local", "load_fn",   # (k,), (k,) 0 force 1 moment, (k,), (k, 3)
    "load_X", "load_point",          # (k, 3, 4) URDF -> tree frame, (k, 3)
    "torque_idx", "torque_fn",       # (m,), (m,)
    "spring_idx", "stiffness", "rest",
    "damper_idx", "damping",
    "g",                             # (3,)
    "C", "d",                        # (nt, n), (nt,) coupling q_tree = C q + d
    "fn_kind", "fn_ptr", "fn_data",  # compiled time functions
])


def function_data(fn) -> tuple[int, np.ndarray]:
    """``(kind, data)`` of a scalar time function: kind 0 sines ``[offset, rate, K, (a, w, phase)*K]``,
    kind 1 piecewise polynomial ``[m, k, x_0..x_m, c (k + 1, m) row-major]`` (scipy PPoly layout)."""
    if isinstance(fn, Constant):
        return 0, np.array([fn.value, 0.0, 0.0])
    if isinstance(fn, Sines):
        data = [fn.offset, fn.rate, float(len(fn.terms))]
        for a, f, p in fn.terms:
            data += [a, 2.0 * math.pi * f, p]
        return 0, np.array(data)
    if isinstance(fn, Table):
        spl = fn._spline
        pp = PPoly.from_spline(spl) if isinstance(spl, BSpline) else PPoly(spl.c, spl.x)
        x, c = np.asarray(pp.x, float), np.asarray(pp.c, float)
        # keep the intervals inside [t0, t1] (from_spline adds empty ones at the ends)
        t0, t1 = fn.times[0], fn.times[-1]
        keep = [i for i in range(c.shape[1]) if x[i + 1] > x[i] and x[i] >= t0 and x[i + 1] <= t1]
        xs = np.r_[x[keep], x[keep[-1] + 1]]
        cs = c[:, keep]
        return 1, np.r_[float(cs.shape[1]), float(cs.shape[0] - 1), xs, cs.ravel()]
    raise TypeError(f"cannot compile time function {fn!r}")


@njit(cache=True)
def fn_eval(kind, data, t, order):
    """d^order f / dt^order at t for :func:`function_data`."""
    if kind == 0:
        if order == 0:
            out = data[0] + data[1] * t
        elif order == 1:
            out = data[1]
        else:
            out = 0.0
        nk = int(data[2])
        for j in range(nk):
            a, w, ph = data[3 + 3 * j], data[4 + 3 * j], data[5 + 3 * j]
            x = w * t + ph
            if order == 0:
                out += a * np.sin(x)
            elif order == 1:
                out += a * w * np.cos(x)
            else:
                out -= a * w * w * np.sin(x)
        return out
    m = int(data[0])
    k = int(data[1])
    x = data[2:3 + m]
    c = data[3 + m:3 + m + (k + 1) * m]
    if t < x[0] or t > x[m]:
        if order > 0:
            return 0.0
        t = x[0] if t < x[0] else x[m]
    i = np.searchsorted(x, t, side="right") - 1
    if i < 0:
        i = 0
    if i > m - 1:
        i = m - 1
    s = t - x[i]
    out = 0.0
    for j in range(k + 1):       # c[j, i] (s)^(k - j)
        pw = k - j
        if pw < order:
            continue
        coef = c[j * m + i]
        for r in range(order):
            coef *= pw - r
        out += coef * s ** (pw - order)
    return out


def compile_scene(plan) -> tuple[np.ndarray, np.ndarray]:
    """``(SI, SF)`` of a :class:`~urdf2links.plan.Plan` (see :data:`SceneArrays`)."""
    model = plan.model
    tree = model.tree
    fns: list = []

    def fid(f):
        fns.append(function_data(f))
        return len(fns) - 1

    n, nt = model.n, tree.n
    has_base = plan.base is not None
    base_fn = [fid(f) for f in plan.base] if has_base else [0] * 6
    load_link, load_kind, load_local, load_fn, load_X, load_point = [], [], [], [], [], []
    for link, X, load in plan.loads:
        load_link.append(link)
        load_kind.append(0 if load.kind == "force" else 1)
        load_local.append(1 if load.frame == "link" else 0)
        load_fn.append([fid(c) for c in load.value.components])
        load_X.append(np.asarray(X, float)[:3, :4])
        load_point.append(np.asarray(load.point, float))
    torque_fn = [fid(f) for f in plan.torque_funcs]
    coupled = model.coupling is not None
    C, d = model.coupling if coupled else (np.zeros((0, 0)), np.zeros(0))
    g = np.zeros(3) if plan.gravity_vector is None else np.asarray(plan.gravity_vector, float)
    kinds = [k for k, _ in fns]
    ptr = np.cumsum([0] + [len(v) for _, v in fns])
    data = np.concatenate([v for _, v in fns]) if fns else np.zeros(0)
    k = len(load_link)
    ints = [np.array([n, nt, int(has_base), int(plan.gravity_vector is not None), int(coupled), k,
                      len(torque_fn), plan.spring_index.size, plan.damper_index.size, len(fns)]),
            base_fn, load_link, load_kind, load_local, np.reshape(load_fn, (-1,)), plan.torque_index, torque_fn,
            plan.spring_index, plan.damper_index, kinds, ptr]
    floats = [np.reshape(load_X, (-1,)), np.reshape(load_point, (-1,)), plan.stiffness, plan.rest,
              plan.damping, g, np.ravel(C), np.ravel(d), data]
    SI = np.concatenate([np.asarray(a, dtype=np.int64).ravel() for a in ints])
    SF = np.concatenate([np.asarray(a, dtype=float).ravel() for a in floats])
    return SI, SF


@njit(cache=True)
def scene_view(SI, SF):
    n, nt, has_base, has_g, coupled, k, m, ns, nd, nf = (SI[0], SI[1], SI[2], SI[3], SI[4], SI[5],
                                                       SI[6], SI[7], SI[8], SI[9])
    o = 10
    base_fn = SI[o:o + 6]
    o += 6
    load_link = SI[o:o + k]
    o += k
    load_kind = SI[o:o + k]
    o += k
    load_local = SI[o:o + k]
    o += k
    load_fn = SI[o:o + 3 * k].reshape((k, 3))
    o += 3 * k
    torque_idx = SI[o:o + m]
    o += m
    torque_fn = SI[o:o + m]
    o += m
    spring_idx = SI[o:o + ns]
    o += ns
    damper_idx = SI[o:o + nd]
    o += nd
    fn_kind = SI[o:o + nf]
    o += nf
    fn_ptr = SI[o:o + nf + 1]
    f = 0
    load_X = SF[f:f + 12 * k].reshape((k, 3, 4))
    f += 12 * k
    load_point = SF[f:f + 3 * k].reshape((k, 3))
    f += 3 * k
    stiffness = SF[f:f + ns]
    f += ns
    rest = SF[f:f + ns]
    f += ns
    damping = SF[f:f + nd]
    f += nd
    g = SF[f:f + 3]
    f += 3
    nc = nt * n if coupled else 0
    C = SF[f:f + nc].reshape((nt if coupled else 0, n if coupled else 0))
    f += nc
    d = SF[f:f + (nt if coupled else 0)]
    f += nt if coupled else 0
    fn_data = SF[f:]
    return SceneArrays(n, nt, has_base, has_g, coupled, base_fn, load_link, load_kind, load_local, load_fn,
                       load_X, load_point, torque_idx, torque_fn, spring_idx, stiffness, rest, damper_idx,
                       damping, g, C, d, fn_kind, fn_ptr, fn_data)


@njit(cache=True, inline="always")
def _fn(sc, j, t, order):
    return fn_eval(sc.fn_kind[j], sc.fn_data[sc.fn_ptr[j]:sc.fn_ptr[j + 1]], t, order)


def scratch_size(n: int, nt: int) -> int:
    return 2 * nt + 18 + 2 * n * n + 4 * n + 12


@njit(cache=True, inline="always")
def _tree_state(sc, q, qd, sign, qt, qdt):
    """The tree's coordinates ``qt = C q + d`` and rates ``qdt = sign C q'`` (the model's own
    without coupling); ``sign`` -1 or 0 gives the rates the energy function h needs."""
    if sc.coupled:
        for a in range(sc.nt):
            s1 = sc.d[a]
            s2 = 0.0
            for j in range(sc.n):
                s1 += sc.C[a, j] * q[j]
                s2 += sc.C[a, j] * qd[j]
            qt[a] = s1
            qdt[a] = sign * s2
    else:
        for a in range(sc.n):
            qt[a] = q[a]
            qdt[a] = sign * qd[a]


@njit(cache=True, inline="always")
def _base_values(sc, t, b18):
    """(18,) pose, rate and acceleration of {A} at ``t`` from the base functions (zeros: fixed)."""
    for j in range(18):
        b18[j] = 0.0
    if sc.has_base:
        for j in range(6):
            fj = sc.base_fn[j]
            b18[j] = _fn(sc, fj, t, 0)
            b18[6 + j] = _fn(sc, fj, t, 1)
            b18[12 + j] = _fn(sc, fj, t, 2)


@njit(cache=True, inline="always")
def _apply_loads(sc, ws, t, v3, val, pt, zero3):
    """Add every load of the scene at time ``t`` to the workspace's external wrenches (in the tree's
    link frames: ``load_X`` maps the URDF link's axes and point into them)."""
    for li in range(sc.load_link.size):
        for c in range(3):
            v3[c] = _fn(sc, sc.load_fn[li, c], t, 0)
        Xl = sc.load_X[li]
        local = sc.load_local[li] == 1
        for r in range(3):
            val[r] = (Xl[r, 0] * v3[0] + Xl[r, 1] * v3[1] + Xl[r, 2] * v3[2]) if local else v3[r]
            pt[r] = (Xl[r, 0] * sc.load_point[li, 0] + Xl[r, 1] * sc.load_point[li, 1]
                     + Xl[r, 2] * sc.load_point[li, 2] + Xl[r, 3])
            zero3[r] = 0.0
        if sc.load_kind[li] == 0:
            K.add_wrench(ws, sc.load_link[li], val, zero3, pt, local)
        else:
            K.add_wrench(ws, sc.load_link[li], zero3, val, pt, local)


@njit(cache=True, inline="always")
def _model_terms(sc, ws, A, rhs, Qr):
    """``A``, ``rhs = -(e + G)`` and ``Qr = Q`` in the model's coordinates: the tree's, or
    ``C^T A_t C``, ``C^T b_t``, ``C^T Q_t`` for coupled coordinates."""
    n, nt = sc.n, sc.nt
    if not sc.coupled:
        for i in range(n):
            rhs[i] = ws.b[i]
            Qr[i] = ws.Q[i]
            for j in range(n):
                A[i, j] = ws.A[i, j]
        return
    for i in range(n):
        s1 = 0.0
        s2 = 0.0
        for a in range(nt):
            s1 += sc.C[a, i] * ws.b[a]
            s2 += sc.C[a, i] * ws.Q[a]
        rhs[i] = s1
        Qr[i] = s2
        for j in range(n):
            s3 = 0.0
            for a in range(nt):
                ca = sc.C[a, i]
                if ca != 0.0:
                    for b_ in range(nt):
                        s3 += ca * ws.A[a, b_] * sc.C[b_, j]
            A[i, j] = s3


@njit(cache=True, inline="always")
def _applied(sc, t, q, qd, Qr, f):
    """``f``: every generalized force the scene applies besides ``-(e + G)``: Q of the loads, joint
    torques, dampers ``-c q'`` and springs ``-k (q - rest)``. Returns the power ``q' . f`` of the
    non-potential ones (springs excluded)."""
    n = sc.n
    for i in range(n):
        f[i] = Qr[i]
    for j in range(sc.torque_idx.size):
        f[sc.torque_idx[j]] += _fn(sc, sc.torque_fn[j], t, 0)
    for j in range(sc.damper_idx.size):
        i = sc.damper_idx[j]
        f[i] -= sc.damping[j] * qd[i]
    P = 0.0
    for i in range(n):
        P += qd[i] * f[i]
    for j in range(sc.spring_idx.size):
        i = sc.spring_idx[j]
        f[i] -= sc.stiffness[j] * (q[i] - sc.rest[j])
    return P


@njit(cache=True)
def scene_rhs(t, y, out, I, F, W, SI, SF, X):
    """``out = (q', q'', P)`` (2n + 1,) at ``(t, y = (q, q', W))``; ``X`` scratch of
    :func:`scratch_size` (it keeps ``A`` in model coordinates at offset ``2 nt + 18``). Returns -1,
    or the index of the failing Cholesky pivot (then ``out`` is NaN). ``P`` is the power of the
    non-potential forces ``q' . (Q + tau - c q')`` minus the explicit rate ``dE/dt - dV/dt`` of a
    moving base (see :mod:`urdf2links.plan`)."""
    sc = scene_view(SI, SF)
    ta = K.tree_view(I, F)
    ws = K.workspace_view(I, W)
    n, nt = sc.n, sc.nt
    o = 2 * nt + 18
    qt, qdt, b18 = X[0:nt], X[nt:2 * nt], X[2 * nt:o]
    A = X[o:o + n * n].reshape((n, n))
    o += n * n
    Lf = X[o:o + n * n].reshape((n, n))
    o += n * n
    rhs, f, qdd, Qr = X[o:o + n], X[o + n:o + 2 * n], X[o + 2 * n:o + 3 * n], X[o + 3 * n:o + 4 * n]
    o += 4 * n
    v3, val, pt, zero3 = X[o:o + 3], X[o + 3:o + 6], X[o + 6:o + 9], X[o + 9:o + 12]
    q = y[:n]
    qd = y[n:2 * n]
    _tree_state(sc, q, qd, 1.0, qt, qdt)
    _base_values(sc, t, b18)
    K.kinematics(ta, ws, qt, qdt, b18[0:6], b18[6:12], b18[12:18], sc.g)
    K.clear_wrenches(ws)
    _apply_loads(sc, ws, t, v3, val, pt, zero3)
    K.dynamics(ta, ws, True)
    _model_terms(sc, ws, A, rhs, Qr)
    P = _applied(sc, t, q, qd, Qr, f)
    for i in range(n):
        rhs[i] += f[i]
    pivot = K.cholesky_solve(A, rhs, Lf, qdd)
    if pivot >= 0:
        for i in range(out.size):
            out[i] = np.nan
        return pivot
    if sc.has_base:   # the base's twist and acceleration, recorded by kinematics
        dE, dV = K.base_power(ta, ws, ws.base_twist, ws.base_acc, sc.g)
        P -= dE - dV
    for i in range(n):
        out[i] = qd[i]
        out[n + i] = qdd[i]
    out[2 * n] = P
    return -1


class CompiledScene:
    """The compiled right-hand side of a plan: callable ``(t, y) -> (2n + 1,)``, and ``args`` for the
    compiled integration loops (:mod:`urdf2links.loops`). A failing Cholesky pivot raises the
    model's named :class:`~urdf2links.errors.DynamicsError`."""

    def __init__(self, plan):
        self.plan = plan
        model = plan.model
        self.SI, self.SF = compile_scene(plan)
        fast = model.compiled                   # the tree flattened once, by the model
        self.I, self.F, self.W = fast.I, fast.F, np.zeros_like(fast.W)
        self.X = np.zeros(scratch_size(model.n, model.tree.n))
        self.dim = 2 * model.n + 1

    @property
    def args(self):
        return (self.I, self.F, self.W, self.SI, self.SF, self.X)

    def fresh_args(self):
        """Arguments with their own scratch (for another thread)."""
        return (self.I, self.F, np.zeros_like(self.W), self.SI, self.SF, np.zeros_like(self.X))

    def __call__(self, t, y):
        y = np.asarray(y, dtype=float)
        out = np.empty(self.dim)
        pivot = scene_rhs(float(t), y, out, *self.args)
        if pivot >= 0:
            self.failure(t, y)
        return out

    def energies(self, t, Q, QD):
        """``(E, V, h)``, each (m,), at sample times ``t`` (m,) and states ``Q``, ``QD`` (m, n)."""
        t = np.ascontiguousarray(t, dtype=float)
        out = np.empty((t.size, 3))
        scene_energies(t, np.ascontiguousarray(Q, dtype=float), np.ascontiguousarray(QD, dtype=float), out,
                       *self.args)
        return out[:, 0], out[:, 1], out[:, 2]

    def check(self, t, y):
        """At a state where the compiled right-hand side failed: raise the model's named
        :class:`~urdf2links.errors.DynamicsError` when A is not positive definite there."""
        y = np.asarray(y, float)
        if not np.all(np.isfinite(y)):
            return
        model = self.plan.model
        n, nt = model.n, model.tree.n
        X = np.zeros_like(self.X)
        if scene_rhs(float(t), y, np.empty(self.dim), self.I, self.F, np.zeros_like(self.W), self.SI, self.SF, X) >= 0:
            o = 2 * nt + 18
            raise model.not_positive_definite(X[o:o + n * n].reshape(n, n).copy(), y[:n])

    def failure(self, t, y):
        """Raise the model's error at a state where the compiled solve failed."""
        self.check(t, y)
        raise FloatingPointError(f"compiled right-hand side failed at t={t!r} (y={y!r})")


@njit(cache=True)
def scene_energies(ts, Q, QD, out, I, F, W, SI, SF, X):
    """At each sample ``k``: ``out[k] = (E, V, h)``: kinetic energy and potential energy of gravity
    (docs/equations.md (E37)) plus springs ``0.5 k (q - rest)^2``, and the energy function ``h``
    (E39) (``E + V`` for a fixed base; ``E2 - E0 + V`` from E at ``q'``, ``-q'`` and 0 for a moving one)."""
    sc = scene_view(SI, SF)
    ta = K.tree_view(I, F)
    ws = K.workspace_view(I, W)
    nt = sc.nt
    qt = X[0:nt]
    qdt = X[nt:2 * nt]
    b18 = X[2 * nt:2 * nt + 18]
    zero = np.zeros(3)
    for k in range(ts.size):
        _base_values(sc, ts[k], b18)
        Es = np.zeros(3)
        V = 0.0
        for pass_ in range(3 if sc.has_base else 1):
            sign = 1.0 if pass_ == 0 else (-1.0 if pass_ == 1 else 0.0)
            _tree_state(sc, Q[k], QD[k], sign, qt, qdt)
            K.kinematics(ta, ws, qt, qdt, b18[0:6], b18[6:12], b18[12:18], zero)
            E, Vg = K.energies(ta, ws, sc.g)
            Es[pass_] = E
            V = Vg
        for j in range(sc.spring_idx.size):
            x = Q[k, sc.spring_idx[j]] - sc.rest[j]
            V += 0.5 * sc.stiffness[j] * x * x
        out[k, 0] = Es[0]
        out[k, 1] = V
        out[k, 2] = (0.5 * (Es[0] + Es[1]) - 2.0 * Es[2] + V) if sc.has_base else Es[0] + V

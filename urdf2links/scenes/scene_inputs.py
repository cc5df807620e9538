"""The scene's inputs at a time ``t``, compiled (numba): time functions, the base's motion, loads, joint
torques, dampers, actuators (MuJoCo's law, E55) and springs, read from the plan's flat arrays
(:mod:`urdf2links.scenes.scene_arrays`).

The right-hand side (:mod:`urdf2links.scenes.scene_kernels`) and the computed torque (E57) add them to
the generalized forces; MuJoCo's control callback (``urdf2links.compare.mujoco_side.mujoco_inputs``)
evaluates the same functions on the same data, so both engines see the same inputs. Coupled
coordinates' tree state (E42) is here too: every pass that reads a state of the model's coordinates
maps it first.
"""

from __future__ import annotations

import numpy as np

from ..compilation import kernel, one_signature

from ..dynamics.kernels import add_wrench
from .scene_arrays import (
    KA,
    S_ACT_FLAGS,
    S_ACT_FN,
    S_ACT_IDX,
    S_ACT_PRM,
    S_BASE_FN,
    S_C,
    S_D,
    S_DAMPER_IDX,
    S_DAMPING,
    S_FN_DATA,
    S_FN_KIND,
    S_FN_PTR,
    S_LOAD_FN,
    S_LOAD_KIND,
    S_LOAD_LINK,
    S_LOAD_LOCAL,
    S_LOAD_POINT,
    S_LOAD_X,
    S_NA,
    S_REST,
    S_SPRING_IDX,
    S_STIFFNESS,
    S_TORQUE_FN,
    S_TORQUE_IDX,
)

__all__ = ["fn_data_eval", "fn_eval"]


@one_signature
@kernel
def fn_data_eval(kind, data, o, t, order):
    """``d^order f / dt^order`` at ``t`` of a time function of ``kind`` whose data
    (:func:`urdf2links.scenes.scene_arrays.function_data`) starts at ``data[o]``."""
    if kind == 0:
        if order == 0:
            out = data[o] + data[o + 1] * t
        elif order == 1:
            out = data[o + 1]
        else:
            out = 0.0
        for k in range(int(data[o + 2])):
            a, w, ph = data[o + 3 + 3 * k], data[o + 4 + 3 * k], data[o + 5 + 3 * k]
            x = w * t + ph
            if order == 0:
                out += a * np.sin(x)
            elif order == 1:
                out += a * w * np.cos(x)
            else:
                out -= a * w * w * np.sin(x)
        return out
    m = int(data[o])
    k = int(data[o + 1])
    x = data[o + 2:o + 3 + m]
    c = o + 3 + m
    if t < x[0] or t > x[m]:
        if order > 0:
            return 0.0
        t = x[0] if t < x[0] else x[m]
    lo, hi = 0, m + 1             # np.searchsorted(x, t, side="right"): how many breakpoints are <= t
    while lo < hi:
        mid = (lo + hi) // 2
        if x[mid] <= t:
            lo = mid + 1
        else:
            hi = mid
    i = min(max(lo - 1, 0), m - 1)    # (written out: numpy's generic searchsorted compiled for a second)
    s = t - x[i]
    out = 0.0
    for j in range(k + 1):       # c[j, i] (s)^(k - j)
        pw = k - j
        if pw < order:
            continue
        coef = data[c + j * m + i]
        for r in range(order):
            coef *= pw - r
        out += coef * s ** (pw - order)
    return out


@one_signature
@kernel
def fn_eval(SI, SF, j, t, order):
    """``d^order f_j / dt^order`` at ``t`` of the scene's time function ``j`` (:func:`fn_data_eval`)."""
    return fn_data_eval(SI[SI[S_FN_KIND] + j], SF, SI[S_FN_DATA] + SI[SI[S_FN_PTR] + j], t, order)


@one_signature
@kernel
def _tree_state(SI, SF, q, q_at, qd, qd_at, sign, X):
    """Coupled coordinates: ``X[0:nt] = C q + d``, ``X[nt:2 nt] = sign C q'`` (E42); ``sign`` -1 or 0
    gives the rates the energy function h needs."""
    n, nt = SI[0], SI[1]
    C, d = SI[S_C], SI[S_D]
    for a in range(nt):
        s1 = SF[d + a]
        s2 = 0.0
        for j in range(n):
            s1 += SF[C + a * n + j] * q[q_at + j]
            s2 += SF[C + a * n + j] * qd[qd_at + j]
        X[a] = s1
        X[nt + a] = sign * s2


@one_signature
@kernel
def _base_values(SI, SF, t, X, base_at):
    """``X[base_at:base_at + 18]``: pose, rate and acceleration of {A} at ``t`` from the base functions."""
    for j in range(6):
        fj = SI[SI[S_BASE_FN] + j]
        X[base_at + j] = fn_eval(SI, SF, fj, t, 0)
        X[base_at + 6 + j] = fn_eval(SI, SF, fj, t, 1)
        X[base_at + 12 + j] = fn_eval(SI, SF, fj, t, 2)


@one_signature
@kernel
def _apply_loads(SI, SF, tree, t):
    """Add every load of the scene at time ``t`` to the links' external wrenches (in the tree's link
    frames: ``load_X`` maps the URDF link's axes and point into them)."""
    for li in range(SI[5]):
        fn = SI[S_LOAD_FN] + 3 * li
        v0, v1, v2 = fn_eval(SI, SF, SI[fn], t, 0), fn_eval(SI, SF, SI[fn + 1], t, 0), fn_eval(SI, SF, SI[fn + 2], t, 0)
        X = SI[S_LOAD_X] + 12 * li
        pt = SI[S_LOAD_POINT] + 3 * li
        local = SI[SI[S_LOAD_LOCAL] + li] == 1
        if local:
            v0, v1, v2 = (SF[X] * v0 + SF[X + 1] * v1 + SF[X + 2] * v2, SF[X + 4] * v0 + SF[X + 5] * v1 + SF[X + 6] * v2,
                          SF[X + 8] * v0 + SF[X + 9] * v1 + SF[X + 10] * v2)
        r0 = SF[X] * SF[pt] + SF[X + 1] * SF[pt + 1] + SF[X + 2] * SF[pt + 2] + SF[X + 3]
        r1 = SF[X + 4] * SF[pt] + SF[X + 5] * SF[pt + 1] + SF[X + 6] * SF[pt + 2] + SF[X + 7]
        r2 = SF[X + 8] * SF[pt] + SF[X + 9] * SF[pt + 1] + SF[X + 10] * SF[pt + 2] + SF[X + 11]
        link = SI[SI[S_LOAD_LINK] + li]
        if SI[SI[S_LOAD_KIND] + li] == 0:
            add_wrench(tree, link, v0, v1, v2, 0.0, 0.0, 0.0, r0, r1, r2, local)
        else:
            add_wrench(tree, link, 0.0, 0.0, 0.0, v0, v1, v2, r0, r1, r2, local)


@one_signature
@kernel
def _actuators(SI, SF, t, y, y_at, f, f_at):
    """Every actuator's generalized force (E55) at ``t``, ``q = y[y_at:y_at + n]``, ``q' = y[y_at + n:]`` added to
    ``f[f_at:]``: MuJoCo's order (``mj_fwdActuation``): ctrl clamped to ctrlrange, ``gain c + (b0 + b1 gear q
    + b2 gear q')``, clamped to forcerange, times the gear (the joint transmission's moment)."""
    n = SI[0]
    ai, af, fl, pr = SI[S_ACT_IDX], SI[S_ACT_FN], SI[S_ACT_FLAGS], SI[S_ACT_PRM]
    for j in range(SI[S_NA]):
        i = SI[ai + j]
        p = pr + KA * j
        c = fn_eval(SI, SF, SI[af + j], t, 0)
        flags = SI[fl + j]
        if flags & 1:
            c = min(max(c, SF[p + 5]), SF[p + 6])
        gear = SF[p + 4]
        a = SF[p] * c + (SF[p + 1] + SF[p + 2] * (y[y_at + i] * gear) + SF[p + 3] * (y[y_at + n + i] * gear))
        if flags & 2:
            a = min(max(a, SF[p + 7]), SF[p + 8])
        f[f_at + i] += gear * a


@one_signature
@kernel
def _inputs(SI, SF, t, y, y_at, f, f_at, actuators):
    """Joint torques, dampers ``-c q'`` and (``actuators`` not None: the effect's marker) actuators at
    ``(t, q = y[y_at:], q' = y[y_at + n:])`` added to ``f[f_at:]``."""
    n = SI[0]
    ti, tf = SI[S_TORQUE_IDX], SI[S_TORQUE_FN]
    for j in range(SI[6]):
        f[f_at + SI[ti + j]] += fn_eval(SI, SF, SI[tf + j], t, 0)
    di, dc = SI[S_DAMPER_IDX], SI[S_DAMPING]
    for j in range(SI[8]):
        i = SI[di + j]
        f[f_at + i] -= SF[dc + j] * y[y_at + n + i]
    if actuators is not None:
        if SI[S_NA] > 0:
            _actuators(SI, SF, t, y, y_at, f, f_at)


@one_signature
@kernel
def _springs(SI, SF, y, y_at, f, f_at):
    """Springs ``-k (q - rest)`` at ``q = y[y_at:]`` added to ``f[f_at:]``."""
    si, k, rest = SI[S_SPRING_IDX], SI[S_STIFFNESS], SI[S_REST]
    for j in range(SI[7]):
        i = SI[si + j]
        f[f_at + i] -= SF[k + j] * (y[y_at + i] - SF[rest + j])

"""Inverse dynamics compiled (numba): ``tau = A q'' + e + G - Q`` in one O(n) pass (docs/equations.md (E54)).

The recursive form of :mod:`urdf2links.dynamics.kernels` evaluates ``e + G`` as the pairing of each
coordinate's unit twist with the subtree's inertial wrench (E34), the wrench of the accelerations
at ``q'' = 0``. Propagating the *whole* accelerations instead -- each coordinate factor adds
``s_i q_i''`` besides ``(V x s_i) q_i'`` (E33) -- gives, by the same pairing, ``A q'' + e + G``
(E54): the point accelerations become ``a_0(r) + sum_l u_l(r) q_l''`` and
``int u_i . u_l dm = a_il`` (E31). So one root-to-leaves pass (:func:`kinematics_acc`) and one
leaves-to-root pass (:func:`~urdf2links.dynamics.kernels.dynamics` without ``A``) give ``tau``;
loads give ``Q`` in the same pass (E36). The armature (E49): a ball link's term in
:func:`~urdf2links.dynamics.kernels.armature` pairs ``w_i`` with the relative angular acceleration,
which now carries ``sum_l w_l q_l''`` (its ``A`` block times ``q''``); a coordinate's own armature
adds ``a_k q_k''``.

The row function :func:`id_row` is shared by the single-state entry :func:`id_one`, the batch
:func:`id_batch` (``prange`` over chunks, like :mod:`urdf2links.dynamics.model_kernels`) and the hot
path :func:`id_plain` (fixed base, no loads, no coupling), so a batch equals the per-state calls to
the bit. The scene's computed torque (:mod:`urdf2links.scenes.scene_kernels`) runs the same passes
(:func:`kinematics_acc`, the scene's loads, ``dynamics``, :func:`own_armature`) at the reference state.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from ..compilation import kernel, one_signature

from .kernels import _base_frame, _constant, _rates, _slot, _store, add_wrench, clear_wrenches, dynamics
from .tree_arrays import (
    AC,
    ARM_BALL,
    CONSTANT,
    F_ARM,
    F_SEG,
    I_ARM,
    I_PARENT,
    I_SEGCOORD,
    I_SEGPTR,
    I_SEGSLOT,
    KL,
    KS,
    N_ARM,
    O_,
    W_B,
    W_BASE,
    W_COORD,
    W_LINK,
    W_Q,
    W_QD,
    W_SIZE,
    WV,
    gravity_of,
    nn,
)

__all__ = ["kinematics_acc", "own_armature", "id_row", "id_one", "id_batch", "id_plain", "inverse_size"]


@one_signature
@kernel
def kinematics_acc(TI, TF, W, q, iq, qd, iqd, qdd, iqdd, B, ib, has_base, gx, gy, gz):
    """:func:`~urdf2links.dynamics.kernels.kinematics` with the coordinates' accelerations
    ``qdd[iqdd:iqdd + n]``: every link's spatial acceleration is then the whole one (E33 with
    ``x'' = q_i''``), gravity included as ``-g``; poses, twists and unit twists as there."""
    L, n = TI[0], nn(TI[1])
    par, sp, ss, sc = nn(TI[I_PARENT]), nn(TI[I_SEGPTR]), nn(TI[I_SEGSLOT]), nn(TI[I_SEGCOORD])
    fs, wl, wc, wb = nn(TI[F_SEG]), nn(TI[W_LINK]), nn(TI[W_COORD]), nn(TI[W_BASE])
    wqd = nn(TI[W_QD])
    iq, iqd, iqdd, ib = nn(iq), nn(iqd), nn(iqdd), nn(ib)
    _base_frame(W, wb, B, ib, has_base, gx, gy, gz)
    for p in range(L):
        s = TI[par + p]
        a = wb if s < 0 else wl + KL * nn(s)
        R = (W[a], W[a + 1], W[a + 2], W[a + 3], W[a + 4], W[a + 5], W[a + 6], W[a + 7], W[a + 8])
        o = (W[a + O_], W[a + O_ + 1], W[a + O_ + 2])
        V = (W[a + WV], W[a + WV + 1], W[a + WV + 2], W[a + WV + 3], W[a + WV + 4], W[a + WV + 5])
        Acc = (W[a + AC], W[a + AC + 1], W[a + AC + 2], W[a + AC + 3], W[a + AC + 4], W[a + AC + 5])
        s0 = nn(TI[sp + p])
        for u in range(TI[sp + p + 1] - s0):
            seg = s0 + u
            slot = TI[ss + seg]
            f = fs + KS * seg
            if slot == CONSTANT:
                R, o = _constant(TF, f, R, o)
            else:
                i = nn(TI[sc + seg])
                R, o, sv = _slot(slot, TF[f] + q[iq + i], R, o)
                for j in range(6):
                    W[wc + j * n + i] = sv[j]
                xd = qd[iqd + i]
                xdd = qdd[iqdd + i]
                W[wqd + i] = xd
                if xd != 0.0 or xdd != 0.0:
                    V, Acc = _rates(sv, xd, xdd, V, Acc)
        _store(W, wl + KL * p, R, o, V, Acc)


@one_signature
@kernel
def own_armature(TI, TF, W, qdd, iqdd):
    """``b_k -= a_k q_k''`` for every coordinate with an armature of its own (E49: ``a_k`` on ``a_kk``);
    a ball link's armature is already in ``b`` through its relative angular acceleration."""
    if TI[N_ARM] == 0:
        return
    ia, fa, wbv = nn(TI[I_ARM]), nn(TI[F_ARM]), nn(TI[W_B])
    iqdd = nn(iqdd)
    for k in range(TI[N_ARM]):
        if TI[ia + 3 * k] != ARM_BALL:
            i = nn(TI[ia + 3 * k + 1])
            W[wbv + i] -= TF[fa + k] * qdd[iqdd + i]


def inverse_size(nt: int) -> int:
    """Scratch of a coupled row: the tree's ``q``, ``q'``, ``q''`` (3 nt,)."""
    return 3 * nt


@one_signature
@kernel
def id_row(TI, TF, W, X, q, qd, qdd, base, has_base, gx, gy, gz, loads, C, d, coupled, out):
    """``tau = A q'' + e + G - Q`` (E54) into ``out`` (n,) at the model state ``(q, q', q'')``: ``base``
    (18,) when ``has_base``, gravity ``g``, ``loads`` (k, 11) as for
    :func:`~urdf2links.dynamics.model_kernels.terms_row`, coupled coordinates ``q_tree = C q + d``
    (then ``tau = C^T tau_tree`` at ``C q'``, ``C q''``, E42; ``X`` holds those, 3 n_tree)."""
    nl = loads.shape[0]
    if coupled:
        nt, n = C.shape
        for a in range(nt):
            s1 = d[a]
            s2 = 0.0
            s3 = 0.0
            for j in range(n):
                s1 += C[a, j] * q[j]
                s2 += C[a, j] * qd[j]
                s3 += C[a, j] * qdd[j]
            X[a] = s1
            X[nt + a] = s2
            X[2 * nt + a] = s3
        kinematics_acc(TI, TF, W, X, 0, X, nt, X, 2 * nt, base, 0, has_base, gx, gy, gz)
    else:
        kinematics_acc(TI, TF, W, q, 0, qd, 0, qdd, 0, base, 0, has_base, gx, gy, gz)
    if nl > 0:
        clear_wrenches(TI, W)
        for k in range(nl):
            add_wrench(TI, W, int(loads[k, 0]), loads[k, 1], loads[k, 2], loads[k, 3], loads[k, 4], loads[k, 5],
                       loads[k, 6], loads[k, 7], loads[k, 8], loads[k, 9], loads[k, 10] != 0.0)
    dynamics(TI, TF, W, False, nl > 0, False)
    if coupled:
        own_armature(TI, TF, W, X, 2 * C.shape[0])
    else:
        own_armature(TI, TF, W, qdd, 0)
    wb, wq = nn(TI[W_B]), nn(TI[W_Q])
    if not coupled:
        for i in range(out.size):
            v = -W[wb + i]
            if nl > 0:
                v -= W[wq + i]
            out[i] = v
        return
    nt, n = C.shape
    for i in range(n):
        s = 0.0
        for a in range(nt):
            v = -W[wb + a]
            if nl > 0:
                v -= W[wq + a]
            s += C[a, i] * v
        out[i] = s


@one_signature
@njit(cache=True)
def id_one(TI, TF, q, qd, qdd, base, has_base, gx, gy, gz, loads, C, d, coupled, out):
    """:func:`id_row` for one state, with its own scratch."""
    X = np.empty(3 * C.shape[0] if coupled else 0)
    id_row(TI, TF, np.empty(TI[W_SIZE]), X, q, qd, qdd, base, has_base, gx, gy, gz, loads, C, d, coupled, out)


@njit(cache=True, parallel=True)
def id_batch(TI, TF, Q, QD, QDD, BASE, has_base, gx, gy, gz, loads, C, d, coupled, OUT, nc):
    """:func:`id_row` for every row ``b`` of ``Q``, ``QD``, ``QDD`` (B, n) and ``BASE`` (B or 1, 18) into
    ``OUT[b]``, in ``nc`` chunks of rows (one scratch each)."""
    B = Q.shape[0]
    Ws = np.empty((nc, TI[W_SIZE]))
    Xs = np.empty((nc, 3 * C.shape[0] if coupled else 0))
    nb = BASE.shape[0]
    for c in prange(nc):
        for b in range(c * B // nc, (c + 1) * B // nc):
            id_row(TI, TF, Ws[c], Xs[c], Q[b], QD[b], QDD[b], BASE[b if nb > 1 else 0], has_base, gx, gy, gz,
                   loads, C, d, coupled, OUT[b])


@one_signature
@njit(cache=True)
def id_plain(TI, TF, q, qd, qdd, out):
    """:func:`id_row` for a fixed base, no loads, no coupling (the hot path of
    :meth:`~urdf2links.dynamics.model.Model.inverse_dynamics`), gravity in ``TF``'s last three
    entries (:func:`~urdf2links.dynamics.tree_arrays.tf_with_gravity`): the same operations, so the
    same bits. -2 when a size is wrong, else 0."""
    n = TI[1]
    if q.size != n or qd.size != n or qdd.size != n or out.size != n:
        return -2
    W = np.empty(TI[W_SIZE])
    gx, gy, gz = gravity_of(TF)
    kinematics_acc(TI, TF, W, q, 0, qd, 0, qdd, 0, TF, 0, False, gx, gy, gz)
    dynamics(TI, TF, W, False, False, False)
    own_armature(TI, TF, W, qdd, 0)
    wb = nn(TI[W_B])
    for i in range(n):
        out[i] = -W[wb + i]
    return 0

"""Inverse dynamics compiled (numba): ``tau = A q'' + e + G - Q`` in one O(n) pass (docs/equations.md (E54)).

The recursive form of :mod:`urdf2links.dynamics.kernels` evaluates ``e + G`` as the pairing of each
coordinate's unit twist with the subtree's inertial wrench (E34), the wrench of the accelerations
at ``q'' = 0``. Propagating the *whole* accelerations instead -- each coordinate factor adds
``s_i q_i''`` besides ``(V x s_i) q_i'`` (E33) -- gives, by the same pairing, ``A q'' + e + G``
(E54): the point accelerations become ``a_0(r) + sum_l u_l(r) q_l''`` and
``int u_i . u_l dm = a_il`` (E31). So one root-to-leaves pass (the same compiled
:func:`~urdf2links.dynamics.kernels.kinematics` as every other call, given ``q''``) and one
leaves-to-root pass (:func:`~urdf2links.dynamics.kernels.dynamics` without ``A``) give ``tau``;
loads give ``Q`` in the same pass (E36). The armature (E49): a ball link's term in
:func:`~urdf2links.dynamics.kernels.armature` pairs ``w_i`` with the relative angular acceleration,
which now carries ``sum_l w_l q_l''`` (its ``A`` block times ``q''``); a coordinate's own armature
adds ``a_k q_k''``.

The row function :func:`id_row` is shared by the single-state entry :func:`id_one`, the batch
:func:`id_batch` (``prange`` over chunks, like :mod:`urdf2links.dynamics.model_kernels`) and the hot
path :func:`id_plain` (fixed base, no loads, no coupling), so a batch equals the per-state calls to
the bit. The scene's computed torque (:mod:`urdf2links.scenes.scene_kernels`) runs the same passes
(``kinematics`` with ``q''``, the scene's loads, ``dynamics``, :func:`own_armature`) at the reference state.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from ..compilation import kernel, one_signature

from .kernels import dynamics, kinematics, set_loads
from .tree_arrays import ARM_BALL, F_ARM, I_ARM, N_ARM, W_B, W_Q, W_SIZE, Tree, gravity_of, nonneg, scratches

__all__ = ["own_armature", "id_row", "id_one", "id_batch", "id_plain", "inverse_size", "coupled_tree_state"]


@one_signature
@kernel
def own_armature(tree, qdd, qdd_at):
    """``b_k -= a_k q_k''`` for every coordinate with an armature of its own (E49: ``a_k`` on ``a_kk``);
    a ball link's armature is already in ``b`` through its relative angular acceleration."""
    TI, TF, W = tree
    if TI[N_ARM] == 0:
        return
    ia, fa, wbv = nonneg(TI[I_ARM]), nonneg(TI[F_ARM]), nonneg(TI[W_B])
    qdd_at = nonneg(qdd_at)
    for k in range(TI[N_ARM]):
        if TI[ia + 3 * k] != ARM_BALL:
            i = nonneg(TI[ia + 3 * k + 1])
            W[wbv + i] -= TF[fa + k] * qdd[qdd_at + i]


@njit(cache=True, inline="always")
def coupled_tree_state(C, d, q, qd, qdd, X):
    """The tree's ``q = C q + d``, ``q' = C q'``, ``q'' = C q''`` of coupled coordinates (E42) into ``X``
    (3 n_tree,): ``X[:nt]``, ``X[nt:2 nt]``, ``X[2 nt:]``."""
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


@njit(cache=True, inline="always")
def inverse_size(nt):
    """Scratch of a coupled row: the tree's ``q``, ``q'``, ``q''`` (3 nt,)."""
    return 3 * nt


@one_signature
@kernel
def id_row(TI, TF, W, X, q, qd, qdd, base, has_base, gx, gy, gz, loads, C, d, coupled, out):
    """``tau = A q'' + e + G - Q`` (E54) into ``out`` (n,) at the model state ``(q, q', q'')``: ``base``
    (18,) when ``has_base``, gravity ``g``, ``loads`` (k, 11) as for
    :func:`~urdf2links.dynamics.model_kernels.terms_row`, coupled coordinates ``q_tree = C q + d``
    (then ``tau = C^T tau_tree`` at ``C q'``, ``C q''``, E42; ``X`` holds those, 3 n_tree)."""
    tree = Tree(TI, TF, W)
    nl = loads.shape[0]
    if coupled:
        nt = C.shape[0]
        coupled_tree_state(C, d, q, qd, qdd, X)
        kinematics(tree, X, 0, X, nt, True, base, 0, has_base, gx, gy, gz, X, 2 * nt)
    else:
        kinematics(tree, q, 0, qd, 0, True, base, 0, has_base, gx, gy, gz, qdd, 0)
    if nl > 0:
        set_loads(tree, loads)
    dynamics(tree, False, nl > 0, False)
    if coupled:
        own_armature(tree, X, 2 * C.shape[0])
    else:
        own_armature(tree, qdd, 0)
    wb, wq = nonneg(TI[W_B]), nonneg(TI[W_Q])
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
    X = np.empty(inverse_size(C.shape[0]) if coupled else 0)
    id_row(TI, TF, np.empty(TI[W_SIZE]), X, q, qd, qdd, base, has_base, gx, gy, gz, loads, C, d, coupled, out)


@njit(cache=True, parallel=True)
def id_batch(TI, TF, Q, QD, QDD, BASE, has_base, gx, gy, gz, loads, C, d, coupled, OUT, nc):
    """:func:`id_row` for every row ``b`` of ``Q``, ``QD``, ``QDD`` (B, n) and ``BASE`` (B or 1, 18) into
    ``OUT[b]``, in ``nc`` chunks of rows (one scratch each)."""
    B, nb = Q.shape[0], BASE.shape[0]
    Ws, Xs = scratches(TI, nc, inverse_size(C.shape[0]) if coupled else 0)
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
    tree = Tree(TI, TF, W)
    gx, gy, gz = gravity_of(TF)
    kinematics(tree, q, 0, qd, 0, True, TF, 0, False, gx, gy, gz, qdd, 0)
    dynamics(tree, False, False, False)
    own_armature(tree, qdd, 0)
    wb = nonneg(TI[W_B])
    for i in range(n):
        out[i] = -W[wb + i]
    return 0

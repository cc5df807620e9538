"""The compiled calls behind :class:`~urdf2links.dynamics.model.Model`: one state, or a batch of states in parallel.

Each quantity has one row function (``fd_row``, ``terms_row``, ``energy_row``) that evaluates one
state into its outputs with a given scratch; the single-state entries (``*_one``) and the batched
entries (``*_batch``, numba ``prange`` over chunks of rows, one scratch per chunk, threads from
``NUMBA_NUM_THREADS`` / ``numba.set_num_threads``) call the same row function, so a batch gives the
per-state results to the last bit. ``fd_plain``, ``terms_plain``, ``forces_plain``, ``energy_plain`` and
``id_plain`` (inverse dynamics, :mod:`urdf2links.dynamics.inverse_kernels`) are the hot
single-state paths of :class:`~urdf2links.dynamics.model.Model` (fixed base, no loads, no coupling):
few arguments, since every array argument costs the dispatcher a fraction of a microsecond (so
their ``TF`` carries the gravity in its last three entries,
:func:`~urdf2links.dynamics.tree_arrays.tf_with_gravity`);
:func:`frozen` gives each with its signatures compiled and compilation switched off, so that an
argument of another type raises TypeError (the model then converts it) instead of compiling a new
variant. They compute what the row functions compute, operation for operation (the same bits).

Arguments shared by the row functions: ``TI``, ``TF`` the tree (:mod:`urdf2links.dynamics.tree_arrays`);
``W`` its scratch and ``X`` the coupling scratch (:func:`coupled_size`). The rows and the hot entries
take the tree's arrays and pass them on to the passes as one record
(:class:`~urdf2links.dynamics.tree_arrays.Tree`); the rows are kernels, which count no references: a
record built in a batch's loop would count them, atomically, on arrays every thread shares (a hot entry
builds its own, one count per call, docs/speed.md); ``base`` (18,) pose, rate and acceleration of {A}
when ``has_base``; ``gx, gy, gz`` gravity; ``loads`` (k, 11) wrenches
``(link, F (3), M (3), point (3), local)``; ``C`` (n_tree, n), ``d`` (n_tree,) coupled coordinates
``q_tree = C q + d`` when ``coupled`` (docs/equations.md (E42)).
"""

from __future__ import annotations

import numpy as np
from numba import get_num_threads, njit, prange, types

from ..compilation import kernel, one_signature

from .factor import cholesky, cholesky_solve, ltdl, ltdl_solve, unpack
from .inverse_kernels import id_plain  # noqa: F401  (a hot entry: frozen() finds it here)
from .kernels import dynamics, energies, kinematics, poses, set_loads
from .tree_arrays import I_ANCIDX, I_ANCPTR, W_A, W_B, W_Q, W_SIZE, Tree, gravity_of, nonneg, scratches

__all__ = ["coupled_size", "frozen", "FROZEN", "fd_plain", "terms_plain", "forces_plain", "energy_plain", "fd_one",
           "fd_batch", "terms_one", "terms_batch", "energy_one",
           "energy_batch", "poses_one", "chunks", "MASS", "BIAS", "FORCES"]

MASS, BIAS, FORCES = 0, 1, 2        # what terms_row returns: A, -b (e, or G), Q


@one_signature
@kernel
def coupled_size(n_tree, n):
    """Scratch of a coupled row: ``q_tree``, ``q'_tree`` (n_tree,), ``A``, its factor (n, n), ``rhs`` (n,)."""
    return 2 * n_tree + 2 * n * n + n


# -- one state ----------------------------------------------------------------------------------------
@one_signature
@kernel
def _state(tree, X, q, qd, moving, base, has_base, gx, gy, gz, C, d, coupled):
    """:func:`~urdf2links.dynamics.kernels.kinematics` at the model state ``(q, qd)`` (rates zero unless ``moving``)."""
    if not coupled:
        kinematics(tree, q, 0, qd, 0, moving, base, 0, has_base, gx, gy, gz)
        return
    nt, n = C.shape
    for a in range(nt):
        s1 = d[a]
        s2 = 0.0
        for j in range(n):
            s1 += C[a, j] * q[j]
            if moving:
                s2 += C[a, j] * qd[j]
        X[a] = s1
        X[nt + a] = s2
    kinematics(tree, X, 0, X, nt, moving, base, 0, has_base, gx, gy, gz)


@one_signature
@kernel
def _terms(tree, X, q, qd, moving, base, has_base, gx, gy, gz, loads, C, d, coupled, want_A):
    _state(tree, X, q, qd, moving, base, has_base, gx, gy, gz, C, d, coupled)
    nl = loads.shape[0]
    if nl > 0:
        set_loads(tree, loads)
    dynamics(tree, want_A, nl > 0, False)


@one_signature
@kernel
def reduce_vector(C, v, iv, out, io, sign):
    """``out[io + i] = sign sum_a C[a, i] v[iv + a]`` (E42)."""
    nt, n = C.shape
    for i in range(n):
        s = 0.0
        for a in range(nt):
            s += C[a, i] * v[iv + a]
        out[io + i] = sign * s


@one_signature
@kernel
def reduce_mass(tree, C, A):
    """``A = C^T A_tree C`` (n, n) from the packed tree matrix (E42); the lower triangle is summed,
    the upper one mirrors it."""
    TI, W = tree.TI, tree.W
    nt, n = C.shape
    ap, ai, wa = TI[I_ANCPTR], TI[I_ANCIDX], TI[W_A]
    for i in range(n):
        for k in range(n):
            A[i, k] = 0.0
    for a in range(nt):
        for j in range(TI[ap + a], TI[ap + a + 1]):
            l = TI[ai + j]
            v = W[wa + j]
            for i in range(n):
                x = C[a, i] * v
                y = C[l, i] * v
                if x == 0.0 and y == 0.0:
                    continue
                for k in range(i + 1):
                    A[i, k] += x * C[l, k]
                    if l != a:
                        A[i, k] += y * C[a, k]
    for i in range(n):
        for k in range(i):
            A[k, i] = A[i, k]


@njit(cache=True, inline="always")
def _solve_tree(tree, loaded, tau, has_tau, out):
    """q'' (E24) into ``out`` (n,) after :func:`~urdf2links.dynamics.kernels.dynamics`: ``A q'' = b (+ Q
    when ``loaded``) (+ tau)`` by the tree-sparse factorization (E47). Returns -1, or the failing pivot."""
    TI, W = tree.TI, tree.W
    wb, wq = nonneg(TI[W_B]), nonneg(TI[W_Q])
    for i in range(out.size):
        v = W[wb + i]
        if loaded:
            v += W[wq + i]
        if has_tau:
            v += tau[i]
        out[i] = v
    pivot = ltdl(TI, W)
    if pivot < 0:
        ltdl_solve(TI, W, out, 0)
    return pivot


@one_signature
@kernel
def fd_row(TI, TF, W, X, q, qd, tau, has_tau, base, has_base, gx, gy, gz, loads, C, d, coupled, out):
    """q'' (E24) into ``out`` (n,): ``A q'' = Q + tau - e - G``. Returns -1, or the failing pivot."""
    tree = Tree(TI, TF, W)
    _terms(tree, X, q, qd, True, base, has_base, gx, gy, gz, loads, C, d, coupled, True)
    nl = loads.shape[0]
    if not coupled:
        return _solve_tree(tree, nl > 0, tau, has_tau, out)
    wb, wq = nonneg(TI[W_B]), nonneg(TI[W_Q])
    nt, n = C.shape
    if nl > 0:
        for a in range(nt):
            W[wb + a] += W[wq + a]
    reduce_vector(C, W, wb, out, 0, 1.0)
    if has_tau:
        for i in range(n):
            out[i] += tau[i]
    A = X[2 * nt:2 * nt + n * n].reshape((n, n))
    reduce_mass(tree, C, A)
    o = 2 * nt + n * n
    pivot = cholesky(X, 2 * nt, n, X, o)
    if pivot < 0:
        cholesky_solve(X, o, n, out, 0)
    return pivot


@one_signature
@kernel
def terms_row(TI, TF, W, X, q, qd, moving, base, has_base, gx, gy, gz, loads, C, d, coupled, what, A, v):
    """``what``: MASS the mass matrix into ``A`` (n, n); BIAS ``-b = e + G`` into ``v`` (n,) (with
    ``g = 0``: e; at rest with gravity: G); FORCES ``Q`` of ``loads`` into ``v``."""
    tree = Tree(TI, TF, W)
    _terms(tree, X, q, qd, moving, base, has_base, gx, gy, gz, loads, C, d, coupled, what == MASS)
    if what == MASS:
        if coupled:
            reduce_mass(tree, C, A)
        else:
            unpack(TI, W, A)
        return
    k = TI[W_B] if what == BIAS else TI[W_Q]
    sign = -1.0 if what == BIAS else 1.0
    if coupled:
        reduce_vector(C, W, k, v, 0, sign)
    else:
        for i in range(v.size):
            v[i] = sign * W[k + i]


@one_signature
@kernel
def energy_row(TI, TF, W, X, q, qd, moving, base, has_base, gx, gy, gz, C, d, coupled):
    """``(E, V)`` (E37) at one state."""
    tree = Tree(TI, TF, W)
    _state(tree, X, q, qd, moving, base, has_base, 0.0, 0.0, 0.0, C, d, coupled)
    return energies(tree, gx, gy, gz)


# -- single-state entries -----------------------------------------------------------------------------
# Each hot entry builds the tree's record itself: it allocates its scratch, so it counts references, and
# the record costs about what a call into a kernel that built it would (docs/speed.md), without a second
# compiled function for a cold start.
@one_signature
@njit(cache=True)
def fd_plain(TI, TF, q, qd, tau, out):
    """:func:`fd_row` for a fixed base, no loads, no coupling, tau (n,) or (0,) (none: one signature,
    :data:`_PLAIN_SIGS`), gravity in ``TF`` (:func:`~urdf2links.dynamics.tree_arrays.tf_with_gravity`); -2
    when a size is wrong."""
    n = TI[1]
    if q.size != n or qd.size != n or out.size != n or (tau.size > 0 and tau.size != n):
        return -2
    tree = Tree(TI, TF, np.empty(TI[W_SIZE]))
    gx, gy, gz = gravity_of(TF)
    kinematics(tree, q, 0, qd, 0, True, TF, 0, False, gx, gy, gz)
    dynamics(tree, True, False, False)
    return _solve_tree(tree, False, tau, tau.size > 0, out)


@one_signature
@njit(cache=True)
def terms_plain(TI, TF, q, qd, what, A, v):
    """:func:`terms_row` for a fixed base, no loads, no coupling: MASS into ``A`` (n, n); BIAS ``-b``
    into ``v`` (n,): ``e`` with zero gravity in ``TF`` (:func:`~urdf2links.dynamics.tree_arrays.tf_with_gravity`),
    ``G`` with ``qd`` of size 0 (at rest). -2 when a size is wrong, else 0."""
    n = TI[1]
    if q.size != n or (qd.size != 0 and qd.size != n):
        return -2
    if what == MASS:
        if A.shape[0] != n or A.shape[1] != n:
            return -2
    elif v.size != n:
        return -2
    W = np.empty(TI[W_SIZE])
    tree = Tree(TI, TF, W)
    gx, gy, gz = gravity_of(TF)
    kinematics(tree, q, 0, qd, 0, qd.size > 0, TF, 0, False, gx, gy, gz)       # qd of size 0: at rest
    dynamics(tree, what == MASS, False, False)
    if what == MASS:
        unpack(TI, W, A)
    else:
        wb = nonneg(TI[W_B])
        for i in range(n):
            v[i] = -W[wb + i]
    return 0


@one_signature
@njit(cache=True)
def forces_plain(TI, TF, q, loads, v):
    """``Q`` (E23) of ``loads`` (k, 11) into ``v`` (n,) for a fixed base and no coupling (:func:`terms_row`
    with FORCES; the gravity in ``TF`` is not used). -2 when a size is wrong, else 0."""
    n = TI[1]
    if q.size != n or v.size != n or loads.shape[1] != 11:
        return -2
    W = np.empty(TI[W_SIZE])
    tree = Tree(TI, TF, W)
    kinematics(tree, q, 0, q, 0, False, q, 0, False, 0.0, 0.0, 0.0)
    set_loads(tree, loads)
    dynamics(tree, False, True, False)
    wq = nonneg(TI[W_Q])
    for i in range(n):
        v[i] = W[wq + i]
    return 0


@one_signature
@njit(cache=True)
def energy_plain(TI, TF, q, qd, out):
    """``(E, V)`` (E37) into ``out`` (2,) for a fixed base and no coupling, V for the gravity in ``TF``
    (:func:`~urdf2links.dynamics.tree_arrays.tf_with_gravity`); ``qd`` of size 0: at rest (V only is meaningful).
    -2 when a size is wrong, else 0."""
    n = TI[1]
    if q.size != n or out.size != 2 or (qd.size != 0 and qd.size != n):
        return -2
    tree = Tree(TI, TF, np.empty(TI[W_SIZE]))
    kinematics(tree, q, 0, qd, 0, qd.size > 0, TF, 0, False, 0.0, 0.0, 0.0)       # qd of size 0: at rest
    gx, gy, gz = gravity_of(TF)
    out[0], out[1] = energies(tree, gx, gy, gz)
    return 0


_F1 = types.Array(types.float64, 1, "C")
_F2 = types.Array(types.float64, 2, "C")
_I1 = types.Array(types.int64, 1, "C")
#: The one signature each hot single-state entry is compiled for (vectors: float64, C-contiguous; an
#: absent ``qd`` or ``tau`` is an array of size 0, not None, which would be a second compiled variant).
_PLAIN_SIGS = {
    "fd_plain": [types.int64(_I1, _F1, _F1, _F1, _F1, _F1)],
    "terms_plain": [types.int64(_I1, _F1, _F1, _F1, types.int64, _F2, _F1)],
    "forces_plain": [types.int64(_I1, _F1, _F1, _F2, _F1)],
    "energy_plain": [types.int64(_I1, _F1, _F1, _F1, _F1)],
    "id_plain": [types.int64(_I1, _F1, _F1, _F1, _F1, _F1)],
}

#: The hot entries :func:`frozen` has given in this process, by name (the model's hot path reads it
#: directly: one dictionary lookup).
FROZEN: dict = {}


def frozen(name: str):
    """The hot single-state entry ``name`` (``fd_plain``, ``terms_plain``, ``energy_plain``, ``id_plain``) compiled
    (or loaded from the cache) for its :data:`_PLAIN_SIGS`, with further compilation switched off:
    an argument of another type raises TypeError (the caller then converts it) instead of compiling
    a new variant."""
    fn = FROZEN.get(name)
    if fn is None:
        fn = globals()[name]
        for sig in _PLAIN_SIGS[name]:
            fn.compile(sig)
        fn.disable_compile()
        FROZEN[name] = fn
    return fn


@one_signature
@njit(cache=True)
def fd_one(TI, TF, q, qd, tau, has_tau, base, has_base, gx, gy, gz, loads, C, d, coupled, out):
    X = np.empty(coupled_size(C.shape[0], C.shape[1]) if coupled else 0)
    return fd_row(TI, TF, np.empty(TI[W_SIZE]), X, q, qd, tau, has_tau, base, has_base, gx, gy, gz, loads, C, d,
                  coupled, out)


@one_signature
@njit(cache=True)
def terms_one(TI, TF, q, qd, moving, base, has_base, gx, gy, gz, loads, C, d, coupled, what, A, v):
    X = np.empty(coupled_size(C.shape[0], C.shape[1]) if coupled else 0)
    terms_row(TI, TF, np.empty(TI[W_SIZE]), X, q, qd, moving, base, has_base, gx, gy, gz, loads, C, d, coupled,
              what, A, v)


@one_signature
@njit(cache=True)
def energy_one(TI, TF, q, qd, moving, base, has_base, gx, gy, gz, C, d, coupled):
    X = np.empty(coupled_size(C.shape[0], C.shape[1]) if coupled else 0)
    return energy_row(TI, TF, np.empty(TI[W_SIZE]), X, q, qd, moving, base, has_base, gx, gy, gz, C, d, coupled)


@one_signature
@njit(cache=True)
def poses_one(TI, TF, q, base, has_base, C, d, coupled, R, o):
    """The {0}-pose of every link: rotations ``R`` (L, 3, 3) and origins ``o`` (L, 3)."""
    W = np.empty(TI[W_SIZE])
    X = np.empty(coupled_size(C.shape[0], C.shape[1]) if coupled else 0)
    tree = Tree(TI, TF, W)
    _state(tree, X, q, q, False, base, has_base, 0.0, 0.0, 0.0, C, d, coupled)
    poses(tree, R, o)


# -- batches: chunks of rows in parallel ------------------------------------------------------------
def chunks(B: int) -> int:
    """Number of chunks of a batch of ``B`` rows: a few per thread (each chunk has its own scratch),
    for numba's thread count now. Computed here, not in the compiled code: a compiled function that
    asks numba for the thread count cannot be cached."""
    return max(1, min(B, 4 * get_num_threads()))


@njit(cache=True, parallel=True)
def fd_batch(TI, TF, Q, QD, TAU, has_tau, BASE, has_base, gx, gy, gz, loads, C, d, coupled, OUT, status, nc):
    """:func:`fd_row` for every row ``b`` of ``Q``, ``QD``, ``TAU`` (B, n) and ``BASE`` (B or 1, 18)
    into ``OUT[b]``; ``status[b]`` the failing pivot or -1; rows in ``nc`` chunks (:func:`chunks`)."""
    B, nb = Q.shape[0], BASE.shape[0]
    Ws, Xs = scratches(TI, nc, coupled_size(C.shape[0], C.shape[1]) if coupled else 0)
    for c in prange(nc):
        for b in range(c * B // nc, (c + 1) * B // nc):
            status[b] = fd_row(TI, TF, Ws[c], Xs[c], Q[b], QD[b], TAU[b if has_tau else 0], has_tau,
                               BASE[b if nb > 1 else 0], has_base, gx, gy, gz, loads, C, d, coupled, OUT[b])


@njit(cache=True, parallel=True)
def terms_batch(TI, TF, Q, QD, moving, BASE, has_base, gx, gy, gz, loads, C, d, coupled, what, A, V, nc):
    """:func:`terms_row` for every row: ``A[b]`` (n, n) for MASS, else ``V[b]`` (n,)."""
    B, nb = Q.shape[0], BASE.shape[0]
    Ws, Xs = scratches(TI, nc, coupled_size(C.shape[0], C.shape[1]) if coupled else 0)
    for c in prange(nc):
        for b in range(c * B // nc, (c + 1) * B // nc):
            terms_row(TI, TF, Ws[c], Xs[c], Q[b], QD[b if moving else 0], moving, BASE[b if nb > 1 else 0], has_base,
                      gx, gy, gz, loads, C, d, coupled, what, A[b if what == MASS else 0], V[0 if what == MASS else b])


@njit(cache=True, parallel=True)
def energy_batch(TI, TF, Q, QD, moving, BASE, has_base, gx, gy, gz, C, d, coupled, E, V, nc):
    """:func:`energy_row` for every row into ``E[b]``, ``V[b]``."""
    B, nb = Q.shape[0], BASE.shape[0]
    Ws, Xs = scratches(TI, nc, coupled_size(C.shape[0], C.shape[1]) if coupled else 0)
    for c in prange(nc):
        for b in range(c * B // nc, (c + 1) * B // nc):
            E[b], V[b] = energy_row(TI, TF, Ws[c], Xs[c], Q[b], QD[b if moving else 0], moving,
                                    BASE[b if nb > 1 else 0], has_base, gx, gy, gz, C, d, coupled)

"""The regressor ``Y(q, q', q'')`` with ``tau = Y pi``, compiled and batched (docs/equations.md (E89)).

One kinematics pass (:func:`urdf2links.dynamics.kernels.kinematics` given ``q''``, as inverse dynamics,
E54) gives every link's pose ``(R, o)``, twist ``(omega, v)``, whole acceleration ``(alpha, a)`` (gravity
as ``-g`` in ``a``, E33) and the unit twists ``s_i = (w_i, v_i)`` (E27). A link's inertial wrench (E35) is
linear in its H: in the link's axes, about its origin, with the origin's velocity ``v_o = omega x o + v``
and acceleration ``a_o = alpha x o + a + omega x v_o`` (E32 at ``r = o``) turned into the link's axes,

    f = m a_o + alpha x l + omega x (omega x l),     n = J alpha + omega x (J omega) + l x a_o,

with ``l = m c`` (H's last column) and ``J = tr(S) 1 - S`` (E29, ``S`` = H's planar moments). So each of
the 10 entries of H (:data:`~urdf2links.identification.parameters.LINK_ENTRIES`) has a wrench column
``Phi_p`` (6, 10), carried to {0} (``f_0 = R f``, ``n_0 = R n + o x f_0``), and ``tau_i`` pairs ``s_i`` with
the wrenches of the links of its subtree (E34): ``Y[i, cols(p)] = v_i . f_0 + w_i . n_0`` for every link
``p`` at or below ``link(i)``. The armature's columns are its terms of (E49) with the whole accelerations
(``q_k''`` for a coordinate of its own; ``w_i . (alpha_p - alpha_s - omega_p x (omega_p - omega_s))`` for
the three angles of a ball link); coupled coordinates (E42) take ``C^T`` of the tree's rows at
``(C q + d, C q', C q'')``; the joints' columns (``q'``, ``q' / sqrt(q'^2 + v_s^2)`` (E79), 1) and a fixed
tendon's (``c l'``, ``c reg(l')``, ``c l''``, ``l = c . q``, E76) act on the model's coordinates.

Public entries: :func:`regressor` (one state (n, p) or a batch (S, n, p)) and :func:`regressor_block` (a
batch into a caller's array, the blocked accumulations of :mod:`urdf2links.identification.fit` use it).
The batch is one compiled call, parallel over chunks of rows (numba threads), equal to the single-state
calls to the bit (one row function).
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from ..dynamics.inverse_kernels import coupled_tree_state
from ..dynamics.kernels import kinematics
from ..dynamics.model_kernels import chunks
from ..dynamics.rows import base_rows, kernel_array
from ..dynamics.tree_arrays import AC, KL, O_, W_COORD, W_LINK, W_BASE, W_SIZE, WV, I_PARENT, Tree, nonneg

__all__ = ["regressor", "regressor_block", "regressor_columns", "link_coordinates"]


def link_coordinates(tree) -> tuple[np.ndarray, np.ndarray]:
    """``(ptr (L + 1,), idx)``: for link ``p`` the tree coordinates ``idx[ptr[p]:ptr[p + 1]]`` whose link is
    ``p`` or one of its ancestors (the coordinates whose torque the link's wrench enters, E34)."""
    anc = np.asarray(tree.ancestor)
    cl = np.asarray(tree.coord_link)
    ptr, idx = [0], []
    for p in range(tree.n_links):
        idx += [i for i in range(tree.n) if anc[p, cl[i]]]
        ptr.append(len(idx))
    return np.array(ptr, np.int64), np.array(idx, np.int64)


@njit(cache=True, inline="always")
def _cross(a0, a1, a2, b0, b1, b2):
    return a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0


@njit(cache=True, inline="always")
def _jn(Jxx, Jyy, Jzz, Jxy, Jxz, Jyz, al, om):
    """``J alpha + omega x (J omega)`` for a symmetric J given by its 6 entries."""
    j0 = Jxx * om[0] + Jxy * om[1] + Jxz * om[2]
    j1 = Jxy * om[0] + Jyy * om[1] + Jyz * om[2]
    j2 = Jxz * om[0] + Jyz * om[1] + Jzz * om[2]
    c0, c1, c2 = _cross(om[0], om[1], om[2], j0, j1, j2)
    return (Jxx * al[0] + Jxy * al[1] + Jxz * al[2] + c0, Jxy * al[0] + Jyy * al[1] + Jyz * al[2] + c1,
            Jxz * al[0] + Jyz * al[1] + Jzz * al[2] + c2)


@njit(cache=True)
def _wrench_columns(W, d, Phi):
    """``Phi`` (10, 6): the wrench ``(f, n)`` about {0}, world axes, of each of the 10 entries of link
    record ``d``'s H (module doc) after the kinematics pass with the whole accelerations."""
    R = W[d:d + 9]
    o0, o1, o2 = W[d + O_], W[d + O_ + 1], W[d + O_ + 2]
    om = (W[d + WV], W[d + WV + 1], W[d + WV + 2])
    al = (W[d + AC], W[d + AC + 1], W[d + AC + 2])
    x0, x1, x2 = _cross(om[0], om[1], om[2], o0, o1, o2)
    vo = (x0 + W[d + WV + 3], x1 + W[d + WV + 4], x2 + W[d + WV + 5])
    y0, y1, y2 = _cross(al[0], al[1], al[2], o0, o1, o2)
    z0, z1, z2 = _cross(om[0], om[1], om[2], vo[0], vo[1], vo[2])
    ao = (y0 + W[d + AC + 3] + z0, y1 + W[d + AC + 4] + z1, y2 + W[d + AC + 5] + z2)
    # into the link's axes: x_b = R^T x
    omb = (R[0] * om[0] + R[3] * om[1] + R[6] * om[2], R[1] * om[0] + R[4] * om[1] + R[7] * om[2],
           R[2] * om[0] + R[5] * om[1] + R[8] * om[2])
    alb = (R[0] * al[0] + R[3] * al[1] + R[6] * al[2], R[1] * al[0] + R[4] * al[1] + R[7] * al[2],
           R[2] * al[0] + R[5] * al[1] + R[8] * al[2])
    aob = (R[0] * ao[0] + R[3] * ao[1] + R[6] * ao[2], R[1] * ao[0] + R[4] * ao[1] + R[7] * ao[2],
           R[2] * ao[0] + R[5] * ao[1] + R[8] * ao[2])
    for k in range(10):
        f0 = f1 = f2 = n0 = n1 = n2 = 0.0
        if k < 6:       # planar moments: J = tr(S) 1 - S of a unit entry
            if k == 0:
                n0, n1, n2 = _jn(0.0, 1.0, 1.0, 0.0, 0.0, 0.0, alb, omb)
            elif k == 1:
                n0, n1, n2 = _jn(1.0, 0.0, 1.0, 0.0, 0.0, 0.0, alb, omb)
            elif k == 2:
                n0, n1, n2 = _jn(1.0, 1.0, 0.0, 0.0, 0.0, 0.0, alb, omb)
            elif k == 3:
                n0, n1, n2 = _jn(0.0, 0.0, 0.0, -1.0, 0.0, 0.0, alb, omb)
            elif k == 4:
                n0, n1, n2 = _jn(0.0, 0.0, 0.0, 0.0, -1.0, 0.0, alb, omb)
            else:
                n0, n1, n2 = _jn(0.0, 0.0, 0.0, 0.0, 0.0, -1.0, alb, omb)
        elif k < 9:     # first moments l = e_k: f = alpha x l + omega x (omega x l), n = l x a_o
            e0, e1, e2 = (1.0 if k == 6 else 0.0), (1.0 if k == 7 else 0.0), (1.0 if k == 8 else 0.0)
            u0, u1, u2 = _cross(omb[0], omb[1], omb[2], e0, e1, e2)
            w0, w1, w2 = _cross(omb[0], omb[1], omb[2], u0, u1, u2)
            t0, t1, t2 = _cross(alb[0], alb[1], alb[2], e0, e1, e2)
            f0, f1, f2 = t0 + w0, t1 + w1, t2 + w2
            n0, n1, n2 = _cross(e0, e1, e2, aob[0], aob[1], aob[2])
        else:           # mass: f = a_o
            f0, f1, f2 = aob
        F0 = R[0] * f0 + R[1] * f1 + R[2] * f2
        F1 = R[3] * f0 + R[4] * f1 + R[5] * f2
        F2 = R[6] * f0 + R[7] * f1 + R[8] * f2
        c0, c1, c2 = _cross(o0, o1, o2, F0, F1, F2)
        Phi[k, 0], Phi[k, 1], Phi[k, 2] = F0, F1, F2
        Phi[k, 3] = R[0] * n0 + R[1] * n1 + R[2] * n2 + c0
        Phi[k, 4] = R[3] * n0 + R[4] * n1 + R[5] * n2 + c1
        Phi[k, 5] = R[6] * n0 + R[7] * n1 + R[8] * n2 + c2


@njit(cache=True)
def _tree_rows(TI, W, X, qdd_at, link_col, lc_ptr, lc_idx, arm, Phi, Y):
    """The link and armature columns of the tree's rows into ``Y`` (n_tree, p), after the kinematics."""
    n = nonneg(TI[1])
    wl, wc, wb, par = nonneg(TI[W_LINK]), nonneg(TI[W_COORD]), nonneg(TI[W_BASE]), nonneg(TI[I_PARENT])
    for p in range(TI[0]):
        c = link_col[p]
        if c < 0:
            continue
        _wrench_columns(W, wl + KL * p, Phi)
        for u in range(lc_ptr[p], lc_ptr[p + 1]):
            i = lc_idx[u]
            si = wc + i
            w0, w1, w2 = W[si], W[si + n], W[si + 2 * n]
            v0, v1, v2 = W[si + 3 * n], W[si + 4 * n], W[si + 5 * n]
            for k in range(10):
                Y[i, c + k] = (v0 * Phi[k, 0] + v1 * Phi[k, 1] + v2 * Phi[k, 2]
                               + w0 * Phi[k, 3] + w1 * Phi[k, 4] + w2 * Phi[k, 5])
    for k in range(arm.shape[0]):
        kind, i, p, c = arm[k, 0], arm[k, 1], arm[k, 2], arm[k, 3]
        if kind == 0:
            Y[i, c] = X[qdd_at + i]
            continue
        d = wl + KL * p
        s = TI[par + p]
        e = wb if s < 0 else wl + KL * nonneg(s)
        o0, o1, o2 = W[d + WV], W[d + WV + 1], W[d + WV + 2]
        r0, r1, r2 = o0 - W[e + WV], o1 - W[e + WV + 1], o2 - W[e + WV + 2]
        c0, c1, c2 = _cross(o0, o1, o2, r0, r1, r2)
        x0 = W[d + AC] - W[e + AC] - c0
        x1 = W[d + AC + 1] - W[e + AC + 1] - c1
        x2 = W[d + AC + 2] - W[e + AC + 2] - c2
        for u in range(3):
            si = wc + i + u
            Y[i + u, c] = W[si] * x0 + W[si + n] * x1 + W[si + 2 * n] * x2


@njit(cache=True)
def regressor_row(TI, TF, W, X, YT, Phi, q, qd, qdd, base, has_base, gx, gy, gz, C, d, coupled,
                  link_col, lc_ptr, lc_idx, arm, jcols, tcoef, tcols, vs, out):
    """``Y`` (n, p) of one state into ``out`` (module doc, E89). Scratch: ``W`` the tree's, ``X`` (3 n_tree,)
    the tree's ``q, q', q''``, ``YT`` (n_tree, p) the tree's rows when ``coupled``, ``Phi`` (10, 6)."""
    tree = Tree(TI, TF, W)
    nt = TI[1]
    n = out.shape[0]
    if coupled:
        coupled_tree_state(C, d, q, qd, qdd, X)
    else:
        for a in range(nt):
            X[a] = q[a]
            X[nt + a] = qd[a]
            X[2 * nt + a] = qdd[a]
    kinematics(tree, X, 0, X, nt, True, base, 0, has_base, gx, gy, gz, X, 2 * nt)
    out[:, :] = 0.0
    if coupled:
        YT[:, :] = 0.0
        _tree_rows(TI, W, X, 2 * nt, link_col, lc_ptr, lc_idx, arm, Phi, YT)
        for i in range(n):
            for a in range(nt):
                if C[a, i] != 0.0:
                    for k in range(YT.shape[1]):
                        out[i, k] += C[a, i] * YT[a, k]
    else:
        _tree_rows(TI, W, X, 2 * nt, link_col, lc_ptr, lc_idx, arm, Phi, out)
    for j in range(n):
        if jcols[j, 0] >= 0:
            out[j, jcols[j, 0]] = qd[j]
        if jcols[j, 1] >= 0:
            out[j, jcols[j, 1]] = qd[j] / np.sqrt(qd[j] * qd[j] + vs * vs)
        if jcols[j, 2] >= 0:
            out[j, jcols[j, 2]] = 1.0
    for t in range(tcoef.shape[0]):
        ld = 0.0
        ldd = 0.0
        for j in range(n):
            ld += tcoef[t, j] * qd[j]
            ldd += tcoef[t, j] * qdd[j]
        reg = ld / np.sqrt(ld * ld + vs * vs)
        for j in range(n):
            out[j, tcols[t, 0]] += tcoef[t, j] * ld
            out[j, tcols[t, 1]] += tcoef[t, j] * reg
            out[j, tcols[t, 2]] += tcoef[t, j] * ldd


@njit(cache=True, parallel=True)
def regressor_batch(TI, TF, Q, QD, QDD, BASE, has_base, gx, gy, gz, C, d, coupled, link_col, lc_ptr, lc_idx, arm,
                    jcols, tcoef, tcols, vs, OUT, nc):
    """:func:`regressor_row` for every row ``b`` of ``Q``, ``QD``, ``QDD`` (S, n) into ``OUT[b]`` (n, p), in
    ``nc`` chunks (one scratch each)."""
    B, nb = Q.shape[0], BASE.shape[0]
    nt = TI[1]
    p = OUT.shape[2]
    for c in prange(nc):
        W = np.empty(TI[W_SIZE])
        X = np.empty(3 * nt)
        YT = np.empty((nt if coupled else 0, p))
        Phi = np.empty((10, 6))
        for b in range(c * B // nc, (c + 1) * B // nc):
            regressor_row(TI, TF, W, X, YT, Phi, Q[b], QD[b], QDD[b], BASE[b if nb > 1 else 0], has_base,
                          gx, gy, gz, C, d, coupled, link_col, lc_ptr, lc_idx, arm, jcols, tcoef, tcols, vs, OUT[b])


@njit(cache=True, parallel=True)
def selected_batch(TI, TF, Q, QD, QDD, BASE, has_base, gx, gy, gz, C, d, coupled, link_col, lc_ptr, lc_idx, arm,
                   jcols, tcoef, tcols, vs, p, ptr, cols, OUT, nc):
    """Each coordinate's own columns of every row's ``Y`` into ``OUT`` (flat): coordinate ``j``'s columns are
    ``cols[ptr[j]:ptr[j + 1]]`` (r_j) and its block ``OUT[S ptr[j]:S ptr[j + 1]]`` is the (S, r_j) matrix of
    them, row-major. Each row's whole ``Y`` (n, p) stays in a scratch in cache; the blocks are ready for
    BLAS (:func:`urdf2links.identification.fit.normal_equations`)."""
    B, nb = Q.shape[0], BASE.shape[0]
    nt = TI[1]
    n = Q.shape[1]
    for c in prange(nc):
        W = np.empty(TI[W_SIZE])
        X = np.empty(3 * nt)
        YT = np.empty((nt if coupled else 0, p))
        Phi = np.empty((10, 6))
        Y = np.empty((n, p))
        for b in range(c * B // nc, (c + 1) * B // nc):
            regressor_row(TI, TF, W, X, YT, Phi, Q[b], QD[b], QDD[b], BASE[b if nb > 1 else 0], has_base,
                          gx, gy, gz, C, d, coupled, link_col, lc_ptr, lc_idx, arm, jcols, tcoef, tcols, vs, Y)
            for j in range(n):
                rj = ptr[j + 1] - ptr[j]
                o = B * ptr[j] + b * rj
                for a in range(rj):
                    OUT[o + a] = Y[j, cols[ptr[j] + a]]


class _Compiled:
    """The arrays of one ParameterSet the compiled rows take, built once per set (cached on it)."""

    def __init__(self, params):
        m = params.model
        self.TI, self.TF = m.compiled.TI, m.compiled.TF
        self.lc_ptr, self.lc_idx = link_coordinates(m.tree)
        cp = m.coupling
        self.coupled = cp is not None
        self.C = np.zeros((0, 0)) if cp is None else np.array(cp[0], float, order="C")
        self.d = np.zeros(0) if cp is None else np.array(cp[1], float, order="C")
        self.g = np.array(m.gravity_vector, float)
        self.link_col = np.ascontiguousarray(params.link_col, np.int64)
        self.arm = np.ascontiguousarray(params.arm_units, np.int64)
        self.jcols = np.ascontiguousarray(params.joint_cols, np.int64)
        self.tcoef = np.ascontiguousarray(params.tendon_coef, float)
        self.tcols = np.ascontiguousarray(params.tendon_cols, np.int64)


def compiled(params) -> _Compiled:
    c = params.__dict__.get("_compiled")
    if c is None:
        c = _Compiled(params)
        object.__setattr__(params, "_compiled", c)
    return c


def regressor_block(params, Q, QD, QDD, out, *, base=None, t=0.0, gravity: bool = True) -> np.ndarray:
    """``Y`` of the rows ``Q``, ``QD``, ``QDD`` (S, n) (float64, C-contiguous) into ``out`` (S, n, p): one
    compiled, parallel call (module doc). ``base``, ``t`` as for :meth:`Model.inverse_dynamics`."""
    k = compiled(params)
    S = Q.shape[0]
    BASE, has_base = base_rows(base, t, S, batched=True)
    g = k.g if gravity else np.zeros(3)
    regressor_batch(k.TI, k.TF, Q, QD, QDD, BASE, has_base, g[0], g[1], g[2], k.C, k.d, k.coupled, k.link_col,
                    k.lc_ptr, k.lc_idx, k.arm, k.jcols, k.tcoef, k.tcols, params.slip_speed, out, chunks(S))
    return out


def regressor_columns(params, Q, QD, QDD, ptr, cols, out, *, base=None, t=0.0, gravity: bool = True) -> np.ndarray:
    """Coordinate ``j``'s columns ``cols[ptr[j]:ptr[j + 1]]`` of ``Y`` of the rows ``Q``, ``QD``, ``QDD`` (S, n)
    into ``out`` (S ptr[n],): block ``j`` is the (S, r_j) matrix ``out[S ptr[j]:S ptr[j + 1]]`` (:func:`selected_batch`)."""
    k = compiled(params)
    S = Q.shape[0]
    BASE, has_base = base_rows(base, t, S, batched=True)
    g = k.g if gravity else np.zeros(3)
    selected_batch(k.TI, k.TF, Q, QD, QDD, BASE, has_base, g[0], g[1], g[2], k.C, k.d, k.coupled, k.link_col,
                   k.lc_ptr, k.lc_idx, k.arm, k.jcols, k.tcoef, k.tcols, params.slip_speed, params.p,
                   np.ascontiguousarray(ptr, np.int64), np.ascontiguousarray(cols, np.int64), out, chunks(S))
    return out


def regressor(params, q, qd, qdd, *, base=None, t=0.0, gravity: bool = True) -> np.ndarray:
    """``Y`` (n, p) of one state ``q, q', q''`` (n,), or (S, n, p) of a batch (S, n): ``tau = Y pi`` with
    ``pi`` laid out by ``params`` (:class:`~urdf2links.identification.parameters.ParameterSet`, E89).
    ``base`` (a moving base, as for :meth:`Model.inverse_dynamics`), ``gravity=False`` leaves ``G`` out.
    Applied loads are not in ``Y`` (they do not depend on ``pi``): subtract
    :meth:`Model.generalized_forces` from the measured torques. Raises ValueError naming the argument
    whose shape is wrong."""
    n = params.n
    arrs = []
    for name, a in (("q", q), ("qd", qd), ("qdd", qdd)):
        a = np.asarray(a, float)
        if a.ndim not in (1, 2) or a.shape[-1] != n:
            raise ValueError(f"{name} must have shape ({n},) or (S, {n}) for coordinates "
                             f"{params.model.coordinate_names}; got {a.shape}")
        arrs.append(a)
    single = arrs[0].ndim == 1
    Q, QD, QDD = (kernel_array(np.atleast_2d(a)) for a in arrs)
    if not Q.shape == QD.shape == QDD.shape:
        raise ValueError(f"q, qd, qdd must have the same shape; got {Q.shape}, {QD.shape}, {QDD.shape}")
    out = np.empty((Q.shape[0], n, params.p))
    regressor_block(params, Q, QD, QDD, out, base=base, t=t, gravity=gravity)
    return out[0] if single else out

"""The recursive form compiled (numba): docs/equations.md (E26)-(E38), over the tree in world-frame twists.

The recursive form writes every coordinate's derivative as one world twist,
``T_i^(p) = W_i T^(p)`` with ``W_i = [[w_i^, v_i], [0, 0]]``; the unit twist is kept here as the
6-vector ``s_i = (w_i, v_i)``. With the {0}-frame pseudo-inertia of a link,
``Hw = T H T^T = [[S, c], [c^T, m]]`` (``S = int r r^T dm``, ``c = int r dm``), and
``W r~ = w x r + v`` for a point ``r~ = (r, 1)``, the traces of the trace form (E19)-(E23) become integrals of
point velocities, which only need ``m``, ``c`` and ``J = tr(S) 1 - S`` (the inertia about {0}):

- (E31) ``a_il = tr(W_i Hc W_l^T) = int (w_i x r + v_i).(w_l x r + v_l) dm = v_l.p_i + w_l.h_i``,
  with the composite's momentum of the unit motion ``p_i = w_i x c + m v_i``,
  ``h_i = J w_i + c x v_i``; only ancestor pairs are visited.
- (E34) ``e_i + g_i = int (W_i r~).(a_0(r) - g) dm = v_i.f + w_i.n`` over the subtree of
  ``link(i)``, with ``a_0(r) = alpha x r + a + omega x (omega x r + v)`` the acceleration at
  ``q'' = 0`` of the point ``r`` of a body with twist ``(omega, v)`` and spatial acceleration
  ``(alpha, a)``, and ``(f, n)`` the wrench ``int (a_0 - g) dm``, ``int r x (a_0 - g) dm``:
  ``f = alpha x c + m (a - g) + omega x (omega x c + m v)``,
  ``n = J alpha + c x (a - g) + omega x (J omega) + c x (omega x v)``. Gravity is the uniform
  acceleration ``-g`` added to the base's (E33), which gives exactly the G of (E22).
- (E36) ``Q_i = v_i.f_ext + w_i.n_ext`` over the subtree (moments about {0}).

Twists propagate from root to leaves: a factor ``E_k(q_i)`` adds ``s_i q_i'`` to the twist and
``s_i q_i'' + (V x s_i) q_i'`` to the spatial acceleration (``dW_i/dt = [V, W_i]``); a constant
factor changes only the pose. The base {A} is the same chain of six factors with prescribed
values. Cost: O(n) for the passes, O(sum of depths) for A, O(n^3 / 6) for the Cholesky factor.

The functions take a :class:`~urdf2links.tree_arrays.TreeArrays` (built once from a LinkTree by
:func:`~urdf2links.tree_arrays.pack_tree`) and a :class:`~urdf2links.tree_arrays.Workspace`
(scratch arrays reused across calls; one per thread). Nothing allocates in the hot path. The numpy
form (:mod:`urdf2links.oracles.recursive`) and the literal form (:mod:`urdf2links.oracles.literal`)
are the oracles the tests check these against.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .tree_arrays import flat_tree, flat_workspace, pack_tree, tree_view, workspace_view

__all__ = ["CompiledTree", "kinematics", "dynamics", "energies", "cholesky_solve", "add_wrench",
           "clear_wrenches", "base_power", "forward_dynamics", "terms", "energy_pair", "poses",
           "wrench_forces"]

# -- one factor ------------------------------------------------------------------------------------
# (Hot loops index arrays directly: a view per link or per coordinate costs reference counting.)
@njit(cache=True, inline="always")
def _factor(cur, slot, val, rate, acc, S, i):
    """Apply ``E_slot(val)`` to the running frame ``cur`` (R, o, V, Acc); the factor's unit twist
    goes to ``S[i]`` (6,); its rate and acceleration update V and Acc (see module doc)."""
    if slot < 3:
        cur[9] += cur[slot] * val
        cur[10] += cur[3 + slot] * val
        cur[11] += cur[6 + slot] * val
        s0 = 0.0
        s1 = 0.0
        s2 = 0.0
        s3 = cur[slot]
        s4 = cur[3 + slot]
        s5 = cur[6 + slot]
    else:
        k = slot - 3
        a = (k + 1) % 3
        b = (k + 2) % 3
        c = np.cos(val)
        sn = np.sin(val)
        for r in range(3):
            ra = cur[3 * r + a]
            rb = cur[3 * r + b]
            cur[3 * r + a] = c * ra + sn * rb
            cur[3 * r + b] = -sn * ra + c * rb
        s0, s1, s2 = cur[k], cur[3 + k], cur[6 + k]
        o0, o1, o2 = cur[9], cur[10], cur[11]
        s3 = o1 * s2 - o2 * s1
        s4 = o2 * s0 - o0 * s2
        s5 = o0 * s1 - o1 * s0
    S[i, 0] = s0
    S[i, 1] = s1
    S[i, 2] = s2
    S[i, 3] = s3
    S[i, 4] = s4
    S[i, 5] = s5
    if rate != 0.0 or acc != 0.0:
        om0, om1, om2 = cur[12], cur[13], cur[14]
        v0, v1, v2 = cur[15], cur[16], cur[17]
        # V x s = (omega x w, omega x v_s + v x w)
        cur[18] += (om1 * s2 - om2 * s1) * rate + s0 * acc
        cur[19] += (om2 * s0 - om0 * s2) * rate + s1 * acc
        cur[20] += (om0 * s1 - om1 * s0) * rate + s2 * acc
        cur[21] += (om1 * s5 - om2 * s4 + v1 * s2 - v2 * s1) * rate + s3 * acc
        cur[22] += (om2 * s3 - om0 * s5 + v2 * s0 - v0 * s2) * rate + s4 * acc
        cur[23] += (om0 * s4 - om1 * s3 + v0 * s1 - v1 * s0) * rate + s5 * acc
        cur[12] += s0 * rate
        cur[13] += s1 * rate
        cur[14] += s2 * rate
        cur[15] += s3 * rate
        cur[16] += s4 * rate
        cur[17] += s5 * rate


@njit(cache=True, inline="always")
def kinematics(ta, ws, q, qd, base_pose, base_rate, base_accel, g):
    """Root to leaves: pose ``R, o``, twist ``V = (omega, v)`` and spatial acceleration at
    ``q'' = 0`` ``Acc`` of every link; unit twists ``s`` of every coordinate. ``base_pose`` etc.
    (6,) are the six parameters of {A} (zeros for a fixed base); ``g`` (3,) enters as the uniform
    acceleration ``-g`` (zeros: no gravity); the base's own twist and acceleration go to
    ``ws.base_twist``, ``ws.base_acc``. ``qd`` may be all zeros."""
    cur = ws.cur
    sb = ws.tmp.reshape((5, 6))
    L = ta.parent.size
    R, o, V, Acc = ws.R, ws.o, ws.V, ws.Acc
    seg_R, seg_p = ta.seg_R, ta.seg_p
    for p in range(L):
        s = ta.parent[p]
        if s < 0:
            for j in range(24):
                cur[j] = 0.0
            cur[0] = 1.0
            cur[4] = 1.0
            cur[8] = 1.0
            for k in range(6):
                if base_pose[k] != 0.0 or base_rate[k] != 0.0 or base_accel[k] != 0.0:
                    _factor(cur, k, base_pose[k], base_rate[k], base_accel[k], sb, 4)
            for j in range(6):
                ws.base_twist[j] = cur[12 + j]
                ws.base_acc[j] = cur[18 + j]
            cur[21] -= g[0]
            cur[22] -= g[1]
            cur[23] -= g[2]
        else:
            for r in range(3):
                for c in range(3):
                    cur[3 * r + c] = R[s, r, c]
                cur[9 + r] = o[s, r]
            for j in range(6):
                cur[12 + j] = V[s, j]
                cur[18 + j] = Acc[s, j]
        for seg in range(ta.seg_ptr[p], ta.seg_ptr[p + 1]):
            if ta.seg_kind[seg] == 0:
                p0, p1, p2 = seg_p[seg, 0], seg_p[seg, 1], seg_p[seg, 2]
                for r in range(3):
                    x0, x1, x2 = cur[3 * r], cur[3 * r + 1], cur[3 * r + 2]
                    cur[9 + r] += x0 * p0 + x1 * p1 + x2 * p2
                    for c in range(3):
                        cur[3 * r + c] = x0 * seg_R[seg, 0, c] + x1 * seg_R[seg, 1, c] + x2 * seg_R[seg, 2, c]
            else:
                i = ta.seg_coord[seg]
                _factor(cur, ta.seg_slot[seg], ta.seg_off[seg] + q[i], qd[i], 0.0, ws.s, i)
        for r in range(3):
            for c in range(3):
                R[p, r, c] = cur[3 * r + c]
            o[p, r] = cur[9 + r]
        for j in range(6):
            V[p, j] = cur[12 + j]
            Acc[p, j] = cur[18 + j]


@njit(cache=True, inline="always")
def _body(ta, ws, p):
    """{0}-frame first moment ``cc[p]`` (3,) and second moment ``cS[p]`` (3, 3) of link p alone
    (overwriting the slots of the composites); returns m."""
    m = ta.mass[p]
    R, o, mom, sec, cc, cS = ws.R, ws.o, ta.moment, ta.second, ws.cc, ws.cS
    o0, o1, o2 = o[p, 0], o[p, 1], o[p, 2]
    l0 = R[p, 0, 0] * mom[p, 0] + R[p, 0, 1] * mom[p, 1] + R[p, 0, 2] * mom[p, 2]
    l1 = R[p, 1, 0] * mom[p, 0] + R[p, 1, 1] * mom[p, 1] + R[p, 1, 2] * mom[p, 2]
    l2 = R[p, 2, 0] * mom[p, 0] + R[p, 2, 1] * mom[p, 1] + R[p, 2, 2] * mom[p, 2]
    cc[p, 0] = l0 + m * o0
    cc[p, 1] = l1 + m * o1
    cc[p, 2] = l2 + m * o2
    for r in range(3):
        x0 = R[p, r, 0] * sec[p, 0, 0] + R[p, r, 1] * sec[p, 1, 0] + R[p, r, 2] * sec[p, 2, 0]
        x1 = R[p, r, 0] * sec[p, 0, 1] + R[p, r, 1] * sec[p, 1, 1] + R[p, r, 2] * sec[p, 2, 1]
        x2 = R[p, r, 0] * sec[p, 0, 2] + R[p, r, 1] * sec[p, 1, 2] + R[p, r, 2] * sec[p, 2, 2]
        lr = l0 if r == 0 else (l1 if r == 1 else l2)
        orr = o0 if r == 0 else (o1 if r == 1 else o2)
        cS[p, r, 0] = x0 * R[p, 0, 0] + x1 * R[p, 0, 1] + x2 * R[p, 0, 2] + lr * o0 + orr * l0 + m * orr * o0
        cS[p, r, 1] = x0 * R[p, 1, 0] + x1 * R[p, 1, 1] + x2 * R[p, 1, 2] + lr * o1 + orr * l1 + m * orr * o1
        cS[p, r, 2] = x0 * R[p, 2, 0] + x1 * R[p, 2, 1] + x2 * R[p, 2, 2] + lr * o2 + orr * l2 + m * orr * o2
    ws.cm[p] = m
    return m


@njit(cache=True, inline="always")
def dynamics(ta, ws, want_A):
    """Leaves to root after :func:`kinematics` (and external wrenches in ``ws.fx``): ``ws.A``
    (E31) when ``want_A``, ``ws.b = -(e + G)`` (E34), ``ws.Q`` (E36)."""
    L = ta.parent.size
    n = ta.coord_link.size
    cc, cS, cm, fi, fx, V, Acc, sv = ws.cc, ws.cS, ws.cm, ws.fi, ws.fx, ws.V, ws.Acc, ws.s
    for p in range(L):
        m = _body(ta, ws, p)
        c0, c1, c2 = cc[p, 0], cc[p, 1], cc[p, 2]
        S00, S01, S02 = cS[p, 0, 0], cS[p, 0, 1], cS[p, 0, 2]
        S10, S11, S12 = cS[p, 1, 0], cS[p, 1, 1], cS[p, 1, 2]
        S20, S21, S22 = cS[p, 2, 0], cS[p, 2, 1], cS[p, 2, 2]
        om0, om1, om2 = V[p, 0], V[p, 1], V[p, 2]
        v0, v1, v2 = V[p, 3], V[p, 4], V[p, 5]
        al0, al1, al2 = Acc[p, 0], Acc[p, 1], Acc[p, 2]
        a0, a1, a2 = Acc[p, 3], Acc[p, 4], Acc[p, 5]
        tr = S00 + S11 + S22
        # J x = tr(S) x - S x
        Jo0 = tr * om0 - (S00 * om0 + S01 * om1 + S02 * om2)
        Jo1 = tr * om1 - (S10 * om0 + S11 * om1 + S12 * om2)
        Jo2 = tr * om2 - (S20 * om0 + S21 * om1 + S22 * om2)
        Ja0 = tr * al0 - (S00 * al0 + S01 * al1 + S02 * al2)
        Ja1 = tr * al1 - (S10 * al0 + S11 * al1 + S12 * al2)
        Ja2 = tr * al2 - (S20 * al0 + S21 * al1 + S22 * al2)
        # u = omega x c + m v (momentum), f = alpha x c + m a + omega x u
        u0 = om1 * c2 - om2 * c1 + m * v0
        u1 = om2 * c0 - om0 * c2 + m * v1
        u2 = om0 * c1 - om1 * c0 + m * v2
        fi[p, 0] = al1 * c2 - al2 * c1 + m * a0 + om1 * u2 - om2 * u1
        fi[p, 1] = al2 * c0 - al0 * c2 + m * a1 + om2 * u0 - om0 * u2
        fi[p, 2] = al0 * c1 - al1 * c0 + m * a2 + om0 * u1 - om1 * u0
        # n = J alpha + c x a + omega x (J omega) + c x (omega x v)
        x0 = om1 * v2 - om2 * v1 + a0
        x1 = om2 * v0 - om0 * v2 + a1
        x2 = om0 * v1 - om1 * v0 + a2
        fi[p, 3] = Ja0 + c1 * x2 - c2 * x1 + om1 * Jo2 - om2 * Jo1
        fi[p, 4] = Ja1 + c2 * x0 - c0 * x2 + om2 * Jo0 - om0 * Jo2
        fi[p, 5] = Ja2 + c0 * x1 - c1 * x0 + om0 * Jo1 - om1 * Jo0
    for p in range(L - 1, 0, -1):
        s = ta.parent[p]
        if s >= 0:
            cm[s] += cm[p]
            for r in range(3):
                cc[s, r] += cc[p, r]
                for k in range(3):
                    cS[s, r, k] += cS[p, r, k]
            for j in range(6):
                fi[s, j] += fi[p, j]
                fx[s, j] += fx[p, j]
    for i in range(n):
        p = ta.coord_link[i]
        w0, w1, w2, v0, v1, v2 = sv[i, 0], sv[i, 1], sv[i, 2], sv[i, 3], sv[i, 4], sv[i, 5]
        # wrench (f, n) . twist (w, v) = v . f + w . n
        ws.b[i] = -(v0 * fi[p, 0] + v1 * fi[p, 1] + v2 * fi[p, 2] + w0 * fi[p, 3] + w1 * fi[p, 4] + w2 * fi[p, 5])
        ws.Q[i] = v0 * fx[p, 0] + v1 * fx[p, 1] + v2 * fx[p, 2] + w0 * fx[p, 3] + w1 * fx[p, 4] + w2 * fx[p, 5]
        if not want_A:
            continue
        m = cm[p]
        c0, c1, c2 = cc[p, 0], cc[p, 1], cc[p, 2]
        tr = cS[p, 0, 0] + cS[p, 1, 1] + cS[p, 2, 2]
        p0 = w1 * c2 - w2 * c1 + m * v0
        p1 = w2 * c0 - w0 * c2 + m * v1
        p2 = w0 * c1 - w1 * c0 + m * v2
        h0 = tr * w0 - (cS[p, 0, 0] * w0 + cS[p, 0, 1] * w1 + cS[p, 0, 2] * w2) + c1 * v2 - c2 * v1
        h1 = tr * w1 - (cS[p, 1, 0] * w0 + cS[p, 1, 1] * w1 + cS[p, 1, 2] * w2) + c2 * v0 - c0 * v2
        h2 = tr * w2 - (cS[p, 2, 0] * w0 + cS[p, 2, 1] * w1 + cS[p, 2, 2] * w2) + c0 * v1 - c1 * v0
        for j in range(ta.anc_ptr[i], ta.anc_ptr[i + 1]):
            l = ta.anc_idx[j]
            a = (sv[l, 3] * p0 + sv[l, 4] * p1 + sv[l, 5] * p2 + sv[l, 0] * h0 + sv[l, 1] * h1 + sv[l, 2] * h2)
            ws.A[i, l] = a
            ws.A[l, i] = a
    return 0


@njit(cache=True, inline="always")
def clear_wrenches(ws):
    for p in range(ws.fx.shape[0]):
        for j in range(6):
            ws.fx[p, j] = 0.0


@njit(cache=True)
def add_wrench(ws, p, force, moment, point, local):
    """Add a force (3,) and a moment (3,) acting at ``point`` (3,) of link ``p`` (link frame) to
    ``ws.fx[p]`` as ``(f, n)`` about {0}; ``local``: force and moment in the link's axes."""
    R, o = ws.R[p], ws.o[p]
    F = np.empty(3)
    M = np.empty(3)
    r = np.empty(3)
    for k in range(3):
        r[k] = R[k, 0] * point[0] + R[k, 1] * point[1] + R[k, 2] * point[2] + o[k]
        if local:
            F[k] = R[k, 0] * force[0] + R[k, 1] * force[1] + R[k, 2] * force[2]
            M[k] = R[k, 0] * moment[0] + R[k, 1] * moment[1] + R[k, 2] * moment[2]
        else:
            F[k] = force[k]
            M[k] = moment[k]
    ws.fx[p, 0] += F[0]
    ws.fx[p, 1] += F[1]
    ws.fx[p, 2] += F[2]
    ws.fx[p, 3] += M[0] + r[1] * F[2] - r[2] * F[1]
    ws.fx[p, 4] += M[1] + r[2] * F[0] - r[0] * F[2]
    ws.fx[p, 5] += M[2] + r[0] * F[1] - r[1] * F[0]


@njit(cache=True, inline="always")
def cholesky_solve(A, b, Lf, x):
    """Solve ``A x = b`` (A symmetric positive definite) by Cholesky into ``x``; ``Lf`` (n, n)
    scratch. Returns -1 on success, else the index of the first failing pivot: a pivot at or
    below the rounding level of A (``10 eps n max|A_ii|``) counts as a zero eigenvalue."""
    n = b.size
    scale = 0.0
    for i in range(n):
        if abs(A[i, i]) > scale:
            scale = abs(A[i, i])
    tiny = 10.0 * 2.220446049250313e-16 * max(scale, 1e-300) * n
    for j in range(n):
        d = A[j, j]
        for k in range(j):
            d -= Lf[j, k] * Lf[j, k]
        if not d > tiny:
            return j
        d = np.sqrt(d)
        Lf[j, j] = d
        for i in range(j + 1, n):
            v = A[i, j]
            for k in range(j):
                v -= Lf[i, k] * Lf[j, k]
            Lf[i, j] = v / d
    for i in range(n):
        v = b[i]
        for k in range(i):
            v -= Lf[i, k] * x[k]
        x[i] = v / Lf[i, i]
    for i in range(n - 1, -1, -1):
        v = x[i]
        for k in range(i + 1, n):
            v -= Lf[k, i] * x[k]
        x[i] = v / Lf[i, i]
    return -1


@njit(cache=True)
def energies(ta, ws, g):
    """``(E, V)`` after :func:`kinematics` (E37): E ``= 0.5 sum (m v.v + 2 v.(omega x c) +
    omega.J omega)``, V ``= -g . sum c``."""
    E = 0.0
    V = 0.0
    for p in range(ta.parent.size):
        m = _body(ta, ws, p)
        c = ws.cc[p]
        S = ws.cS[p]
        om0, om1, om2 = ws.V[p, 0], ws.V[p, 1], ws.V[p, 2]
        v0, v1, v2 = ws.V[p, 3], ws.V[p, 4], ws.V[p, 5]
        tr = S[0, 0] + S[1, 1] + S[2, 2]
        oSo = 0.0
        for r in range(3):
            oSo += ws.V[p, r] * (S[r, 0] * om0 + S[r, 1] * om1 + S[r, 2] * om2)
        wJw = tr * (om0 * om0 + om1 * om1 + om2 * om2) - oSo
        x0 = om1 * c[2] - om2 * c[1]
        x1 = om2 * c[0] - om0 * c[2]
        x2 = om0 * c[1] - om1 * c[0]
        E += 0.5 * (m * (v0 * v0 + v1 * v1 + v2 * v2) + 2.0 * (v0 * x0 + v1 * x1 + v2 * x2) + wJw)
        V -= g[0] * c[0] + g[1] * c[1] + g[2] * c[2]
    return E, V


@njit(cache=True)
def _twist_matrix(x, out):
    for r in range(4):
        for c in range(4):
            out[r, c] = 0.0
    out[0, 1] = -x[2]
    out[0, 2] = x[1]
    out[1, 0] = x[2]
    out[1, 2] = -x[0]
    out[2, 0] = -x[1]
    out[2, 1] = x[0]
    out[0, 3] = x[3]
    out[1, 3] = x[4]
    out[2, 3] = x[5]


@njit(cache=True)
def base_power(ta, ws, base_twist, base_acc, g):
    """``(dE/dt, dV/dt)`` at fixed ``(q, q')`` due to the base motion alone (see
    :meth:`urdf2links.oracles.recursive.RecursivePlan.explicit_time_rates`): with the base's twist ``W1``
    and its rate ``W1'`` (4, 4), ``dE/dt = tr(W1' sum Hw V^T) + tr(W1 sum V Hw V^T)`` and
    ``dV/dt = -g . (W1 sum Hw e4)``; ``Hw = T H T^T``, ``V`` the link's twist matrix."""
    X1 = np.zeros((4, 4))
    X2 = np.zeros((4, 4))
    Hw = np.zeros((4, 4))
    Vm = np.zeros((4, 4))
    Y = np.empty((4, 4))
    ct = np.zeros(3)
    mt = 0.0
    for p in range(ta.parent.size):
        m = _body(ta, ws, p)
        c = ws.cc[p]
        S = ws.cS[p]
        for r in range(3):
            for k in range(3):
                Hw[r, k] = S[r, k]
            Hw[r, 3] = c[r]
            Hw[3, r] = c[r]
            ct[r] += c[r]
        Hw[3, 3] = m
        mt += m
        _twist_matrix(ws.V[p], Vm)
        for r in range(4):           # Y = Hw Vm^T
            for k in range(4):
                Y[r, k] = Hw[r, 0] * Vm[k, 0] + Hw[r, 1] * Vm[k, 1] + Hw[r, 2] * Vm[k, 2] + Hw[r, 3] * Vm[k, 3]
        for r in range(4):
            for k in range(4):
                X1[r, k] += Y[r, k]
                X2[r, k] += Vm[r, 0] * Y[0, k] + Vm[r, 1] * Y[1, k] + Vm[r, 2] * Y[2, k] + Vm[r, 3] * Y[3, k]
    W1 = np.empty((4, 4))
    W2 = np.empty((4, 4))
    _twist_matrix(base_twist, W1)
    _twist_matrix(base_acc, W2)
    dE = 0.0
    for r in range(4):
        for k in range(4):
            dE += W2[r, k] * X1[k, r] + W1[r, k] * X2[k, r]
    w, v = base_twist[:3], base_twist[3:]
    dV = -(g[0] * (w[1] * ct[2] - w[2] * ct[1] + mt * v[0]) + g[1] * (w[2] * ct[0] - w[0] * ct[2] + mt * v[1])
           + g[2] * (w[0] * ct[1] - w[1] * ct[0] + mt * v[2]))
    return dE, dV


@njit(cache=True)
def forward_dynamics(I, F, Wf, q, qd, tau, base, g, out):
    """q'' (E24) into ``out`` (n,): ``A q'' = tau - G - e`` by (E46); ``base`` (18,) pose, rate and
    acceleration of {A}; ``g`` (3,) (zeros: no G). Returns -1, or the failing Cholesky pivot."""
    ta = tree_view(I, F)
    ws = workspace_view(I, Wf)
    kinematics(ta, ws, q, qd, base[0:6], base[6:12], base[12:18], g)
    clear_wrenches(ws)
    dynamics(ta, ws, True)
    for i in range(q.size):
        ws.b[i] += tau[i]
    return cholesky_solve(ws.A, ws.b, ws.Lf, out)


@njit(cache=True)
def terms(I, F, Wf, q, qd, base, g, want_A, A, b):
    """``A`` (n, n) when ``want_A`` and ``b = -(e + G)`` (n,) into the given arrays."""
    ta = tree_view(I, F)
    ws = workspace_view(I, Wf)
    kinematics(ta, ws, q, qd, base[0:6], base[6:12], base[12:18], g)
    clear_wrenches(ws)
    dynamics(ta, ws, want_A)
    n = q.size
    for i in range(n):
        b[i] = ws.b[i]
        if want_A:
            for j in range(n):
                A[i, j] = ws.A[i, j]


@njit(cache=True)
def energy_pair(I, F, Wf, q, qd, base, g):
    """``(E, V)`` (E37) at one state."""
    ta = tree_view(I, F)
    ws = workspace_view(I, Wf)
    kinematics(ta, ws, q, qd, base[0:6], base[6:12], base[12:18], g)
    return energies(ta, ws, g)


@njit(cache=True)
def poses(I, F, Wf, q, base, R, o):
    """The {0}-pose of every link: rotations ``R`` (L, 3, 3) and origins ``o`` (L, 3)."""
    ta = tree_view(I, F)
    ws = workspace_view(I, Wf)
    zero = np.zeros(q.size)
    kinematics(ta, ws, q, zero, base[0:6], base[6:12], base[12:18], np.zeros(3))
    for p in range(ta.parent.size):
        for r in range(3):
            o[p, r] = ws.o[p, r]
            for c in range(3):
                R[p, r, c] = ws.R[p, r, c]


@njit(cache=True)
def wrench_forces(I, F, Wf, q, base, links, forces, moments, points, local, Q):
    """Q (E36) into ``Q`` (n,) of the wrenches ``k``: ``forces[k]``, ``moments[k]`` (3,) at
    ``points[k]`` (3,) of link ``links[k]``, in the link's axes where ``local[k]``."""
    ta = tree_view(I, F)
    ws = workspace_view(I, Wf)
    zero = np.zeros(q.size)
    kinematics(ta, ws, q, zero, base[0:6], base[6:12], base[12:18], np.zeros(3))
    clear_wrenches(ws)
    for k in range(links.size):
        add_wrench(ws, links[k], forces[k], moments[k], points[k], local[k])
    dynamics(ta, ws, False)
    for i in range(q.size):
        Q[i] = ws.Q[i]


class CompiledTree:
    """A LinkTree flattened for the kernels, with its own scratch (not thread-safe: one per
    thread). ``I``, ``F``: :func:`flat_tree`; ``W``: :func:`flat_workspace`."""

    __slots__ = ("I", "F", "W", "n", "n_links")

    def __init__(self, tree):
        self.I, self.F = flat_tree(pack_tree(tree))
        self.W = flat_workspace(self.I)
        self.n, self.n_links = tree.n, tree.n_links

    def terms(self, q, qd, base18, g, *, want_A=True):
        """``(A (n, n) or None, b = -(e + G) (n,))`` at a tree state."""
        n = self.n
        A = np.empty((n, n)) if want_A else np.empty((0, 0))
        b = np.empty(n)
        terms(self.I, self.F, self.W, q, qd, base18, g, want_A, A, b)
        return (A if want_A else None), b

    def energies(self, q, qd, base18, g):
        return energy_pair(self.I, self.F, self.W, q, qd, base18, g)

    def poses(self, q, base18) -> np.ndarray:
        """(L, 4, 4) {0}-poses of the links at a tree configuration."""
        L = self.n_links
        R, o = np.empty((L, 3, 3)), np.empty((L, 3))
        poses(self.I, self.F, self.W, q, base18, R, o)
        T = np.zeros((L, 4, 4))
        T[:, :3, :3], T[:, :3, 3], T[:, 3, 3] = R, o, 1.0
        return T

    def forces(self, q, base18, wrenches) -> np.ndarray:
        """Q (n,) of ``wrenches``: ``(link index, force, moment, point, frame)`` tuples."""
        k = len(wrenches)
        links = np.array([w[0] for w in wrenches], np.int64)
        vec = lambda j: np.array([np.asarray(w[j], float) for w in wrenches]).reshape(k, 3)  # noqa: E731
        local = np.array([w[4] == "link" for w in wrenches], np.bool_)
        Q = np.empty(self.n)
        wrench_forces(self.I, self.F, self.W, q, base18, links, vec(1), vec(2), vec(3), local, Q)
        return Q

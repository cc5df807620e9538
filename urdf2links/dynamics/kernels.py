"""The recursive form compiled (numba): docs/equations.md (E26)-(E38), over the tree in world-frame twists.

The recursive form writes every coordinate's derivative as one world twist,
``T_i^(p) = W_i T^(p)`` with ``W_i = [[w_i^, v_i], [0, 0]]``; the unit twist is kept here as the
6-vector ``s_i = (w_i, v_i)``. With the {0}-frame pseudo-inertia of a link,
``Hw = T H T^T = [[S, c], [c^T, m]]`` (``S = int r r^T dm``, ``c = int r dm``), and
``W r~ = w x r + v`` for a point ``r~ = (r, 1)``, the traces of the trace form (E19)-(E23) become integrals of
point velocities, which only need ``m``, ``c`` and ``J = tr(S) 1 - S`` (the inertia about {0}, E29):

- (E31) ``a_il = tr(W_i Hc W_l^T) = int (w_i x r + v_i).(w_l x r + v_l) dm = v_l.p_i + w_l.h_i``,
  with the composite's momentum of the unit motion ``p_i = w_i x c + m v_i``,
  ``h_i = J w_i + c x v_i``; only ancestor pairs are visited, and ``A`` is stored packed by them.
- (E34) ``e_i + g_i = int (W_i r~).(a_0(r) - g) dm = v_i.f + w_i.n`` over the subtree of
  ``link(i)``, with ``(f, n)`` the inertial wrench (E35)
  ``f = alpha x c + m (a - g) + omega x (omega x c + m v)``,
  ``n = J alpha + c x (a - g) + omega x (J omega) + c x (omega x v)``. Gravity is the uniform
  acceleration ``-g`` added to the base's (E33), which gives exactly the G of (E22).
- (E36) ``Q_i = v_i.f_ext + w_i.n_ext`` over the subtree (moments about {0}).
- (E49) armature: ``a`` on ``a_kk`` of a coordinate of its own; for the three angles of a ball or
  free link, ``a w_i.w_l`` in ``A`` and ``a w_i.(alpha - alpha_s - omega x (omega - omega_s))`` in
  ``e`` (``omega``, ``alpha``: the link's, ``_s``: its parent's), the world-twist form of
  ``J^T a J`` and ``J^T a J' q'`` (:func:`armature`).

Twists propagate from root to leaves (E33): a factor ``E_k(q_i)`` adds ``s_i q_i'`` to the twist and
``s_i q_i'' + (V x s_i) q_i'`` to the spatial acceleration; a constant factor changes only the pose;
a rotation factor turns two columns of the pose (a 2x2 rotation), a translation moves the origin
along one column. The base {A} is the same chain of six factors with prescribed values. One
kinematics pass serves ``A`` and ``e + G``: :func:`dynamics` forms each link's ``(m, c, J)`` in {0}
once, for its wrench and for the subtree sums. Cost: O(n) for the passes, O(sum of depths) for
``A``; its factorization (:mod:`urdf2links.dynamics.factor`) has no fill-in outside ancestor pairs.

All functions index the flat arrays of :mod:`urdf2links.dynamics.tree_arrays` (``TI``, ``TF``, and the scratch
``W``, one per thread) at header offsets; nothing allocates. The passes take the three as one record,
``tree`` (:class:`~urdf2links.dynamics.tree_arrays.Tree`; free between them, not from Python: docs/speed.md).
The numpy form (:mod:`urdf2links.dynamics.oracles.recursive`) and the literal form
(:mod:`urdf2links.dynamics.oracles.literal`) are the oracles the tests check these against.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..compilation import kernel, one_signature

from .tree_arrays import (
    AC,
    BASE_ACC,
    BASE_MOM,
    BASE_S,
    BASE_TWIST,
    CC,
    CJ,
    CM,
    CONSTANT,
    F_LINK,
    F_SEG,
    FI,
    FX,
    ARM_BALL,
    F_ARM,
    I_ANCIDX,
    I_ANCPTR,
    I_ARM,
    I_COORDLINK,
    I_PARENT,
    I_RUNPTR,
    I_RUNS,
    I_SEGCOORD,
    I_SEGPTR,
    I_SEGSLOT,
    KF,
    KL,
    KS,
    N_ARM,
    O_,
    W_A,
    W_B,
    W_BASE,
    W_COORD,
    W_LINK,
    W_Q,
    W_QD,
    WV,
    nonneg,
)

__all__ = ["kinematics", "dynamics", "energies", "add_wrench", "clear_wrenches", "set_loads", "base_power", "poses",
           "armature", "armature_energy"]


# -- root to leaves ---------------------------------------------------------------------------------
# The running frame is kept in registers as tuples: R (9, row-major), o (3), V = (omega, v) (6),
# Acc = (alpha, a) (6); a link's record is read once from its parent and written once.
@njit(cache=True, inline="always")
def _turn(k, c, sn, R):
    """``R Rot_k``: a rotation about the local axis ``k`` turns two columns ``a, b`` of R by
    ``(c, sn)`` (``a, b`` = 1, 2 about x; 2, 0 about y; 0, 1 about z): a 2x2 rotation (E48)."""
    R00, R01, R02, R10, R11, R12, R20, R21, R22 = R
    if k == 0:
        return (R00, c * R01 + sn * R02, -sn * R01 + c * R02, R10, c * R11 + sn * R12, -sn * R11 + c * R12,
                R20, c * R21 + sn * R22, -sn * R21 + c * R22)
    if k == 1:
        return (-sn * R02 + c * R00, R01, c * R02 + sn * R00, -sn * R12 + c * R10, R11, c * R12 + sn * R10,
                -sn * R22 + c * R20, R21, c * R22 + sn * R20)
    return (c * R00 + sn * R01, -sn * R00 + c * R01, R02, c * R10 + sn * R11, -sn * R10 + c * R11, R12,
            c * R20 + sn * R21, -sn * R20 + c * R21, R22)


@njit(cache=True, inline="always")
def _slot(slot, x, R, o):
    """``E_slot(x)`` applied to the pose ``(R, o)`` (E48); returns the new pose and the factor's unit twist
    ``s = (w, v)`` (E27): a translation moves o along column ``slot`` (``s = (0, R e)``), a rotation
    turns R (``s = (R e, o x R e)``)."""
    if slot < 3:
        e0, e1, e2 = R[slot], R[3 + slot], R[6 + slot]
        return R, (o[0] + e0 * x, o[1] + e1 * x, o[2] + e2 * x), (0.0, 0.0, 0.0, e0, e1, e2)
    k = slot - 3
    R = _turn(k, np.cos(x), np.sin(x), R)
    w0, w1, w2 = R[k], R[3 + k], R[6 + k]
    o0, o1, o2 = o
    return R, o, (w0, w1, w2, o1 * w2 - o2 * w1, o2 * w0 - o0 * w2, o0 * w1 - o1 * w0)


@njit(cache=True, inline="always")
def _rates(s, xd, xdd, V, Acc):
    """The twist ``V + s xd`` and the acceleration ``Acc + s xdd + (V x s) xd`` (E33), with
    ``V x s = (omega x w, omega x v_s + v x w)``."""
    s0, s1, s2, s3, s4, s5 = s
    om0, om1, om2, v0, v1, v2 = V
    Acc = (Acc[0] + (om1 * s2 - om2 * s1) * xd + s0 * xdd,
           Acc[1] + (om2 * s0 - om0 * s2) * xd + s1 * xdd,
           Acc[2] + (om0 * s1 - om1 * s0) * xd + s2 * xdd,
           Acc[3] + (om1 * s5 - om2 * s4 + v1 * s2 - v2 * s1) * xd + s3 * xdd,
           Acc[4] + (om2 * s3 - om0 * s5 + v2 * s0 - v0 * s2) * xd + s4 * xdd,
           Acc[5] + (om0 * s4 - om1 * s3 + v0 * s1 - v1 * s0) * xd + s5 * xdd)
    V = (om0 + s0 * xd, om1 + s1 * xd, om2 + s2 * xd, v0 + s3 * xd, v1 + s4 * xd, v2 + s5 * xd)
    return V, Acc


@njit(cache=True, inline="always")
def _constant(TF, f, R, o):
    """``T <- T C`` for the constant transform ``C`` at ``TF[f:]`` (R, p); twist and acceleration unchanged."""
    f = nonneg(f)
    C00, C01, C02, C10, C11, C12 = TF[f + 1], TF[f + 2], TF[f + 3], TF[f + 4], TF[f + 5], TF[f + 6]
    C20, C21, C22, p0, p1, p2 = TF[f + 7], TF[f + 8], TF[f + 9], TF[f + 10], TF[f + 11], TF[f + 12]
    R00, R01, R02, R10, R11, R12, R20, R21, R22 = R
    o = (o[0] + R00 * p0 + R01 * p1 + R02 * p2, o[1] + R10 * p0 + R11 * p1 + R12 * p2,
         o[2] + R20 * p0 + R21 * p1 + R22 * p2)
    R = (R00 * C00 + R01 * C10 + R02 * C20, R00 * C01 + R01 * C11 + R02 * C21, R00 * C02 + R01 * C12 + R02 * C22,
         R10 * C00 + R11 * C10 + R12 * C20, R10 * C01 + R11 * C11 + R12 * C21, R10 * C02 + R11 * C12 + R12 * C22,
         R20 * C00 + R21 * C10 + R22 * C20, R20 * C01 + R21 * C11 + R22 * C21, R20 * C02 + R21 * C12 + R22 * C22)
    return R, o


@njit(cache=True, inline="always")
def _store(W, d, R, o, V, Acc):
    d = nonneg(d)
    for j in range(9):
        W[d + j] = R[j]
    for j in range(3):
        W[d + O_ + j] = o[j]
    for j in range(6):
        W[d + WV + j] = V[j]
        W[d + AC + j] = Acc[j]


@one_signature
@kernel
def _base_frame(W, wb, base, base_at, has_base, gx, gy, gz):
    """The frame every root link starts from, into the base record at ``W[wb:]``: {A} from its six
    factors (``base[base_at:base_at + 18]``: pose, rate, acceleration) or the identity; its twist and
    acceleration are recorded, then ``a -= g``."""
    R = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)
    o = (0.0, 0.0, 0.0)
    V = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    Acc = V
    if has_base:
        for k in range(6):
            x, xd, xdd = base[base_at + k], base[base_at + 6 + k], base[base_at + 12 + k]
            if x != 0.0 or xd != 0.0 or xdd != 0.0:
                R, o, s = _slot(k, x, R, o)
                V, Acc = _rates(s, xd, xdd, V, Acc)
    _store(W, wb, R, o, V, Acc)
    for j in range(12):
        W[wb + BASE_TWIST + j] = W[wb + WV + j]
    W[wb + AC + 3] -= gx
    W[wb + AC + 4] -= gy
    W[wb + AC + 5] -= gz


@one_signature
@kernel
def kinematics(tree, q, q_at, qd, qd_at, moving, base, base_at, has_base, gx, gy, gz, qdd=None, qdd_at=0):
    """Root to leaves (E33): pose ``R, o``, twist ``(omega, v)`` and spatial acceleration of every link
    into its record; unit twists ``s`` of every coordinate. The tree's coordinates are
    ``q[q_at:q_at + n]`` and, when ``moving``, its rates ``qd[qd_at:qd_at + n]`` (else zero);
    ``base[base_at:base_at + 18]`` the pose, rate and acceleration of {A} when ``has_base``; gravity ``g``
    enters as the uniform acceleration ``-g`` (zeros: no gravity).

    The acceleration is the one at ``q'' = 0`` (the bias term's, E32) when ``qdd`` is None; with the
    coordinates' accelerations ``qdd[qdd_at:qdd_at + n]`` it is the whole one (E33 with ``x'' = q_i''``),
    which inverse dynamics pairs with the unit twists to give ``A q'' + e + G`` (E54). One compiled variant
    per type of ``qdd``: for None the ``q''`` term is not in the machine code."""
    TI, TF, W = tree
    L, n = TI[0], nonneg(TI[1])
    par, sp, ss, sc = nonneg(TI[I_PARENT]), nonneg(TI[I_SEGPTR]), nonneg(TI[I_SEGSLOT]), nonneg(TI[I_SEGCOORD])
    fs, wl, wc, wb = nonneg(TI[F_SEG]), nonneg(TI[W_LINK]), nonneg(TI[W_COORD]), nonneg(TI[W_BASE])
    wqd = nonneg(TI[W_QD])
    q_at, qd_at, qdd_at, base_at = nonneg(q_at), nonneg(qd_at), nonneg(qdd_at), nonneg(base_at)
    _base_frame(W, wb, base, base_at, has_base, gx, gy, gz)
    for p in range(L):
        s = TI[par + p]
        a = wb if s < 0 else wl + KL * nonneg(s)
        R = (W[a], W[a + 1], W[a + 2], W[a + 3], W[a + 4], W[a + 5], W[a + 6], W[a + 7], W[a + 8])
        o = (W[a + O_], W[a + O_ + 1], W[a + O_ + 2])
        V = (W[a + WV], W[a + WV + 1], W[a + WV + 2], W[a + WV + 3], W[a + WV + 4], W[a + WV + 5])
        Acc = (W[a + AC], W[a + AC + 1], W[a + AC + 2], W[a + AC + 3], W[a + AC + 4], W[a + AC + 5])
        s0 = nonneg(TI[sp + p])
        for u in range(TI[sp + p + 1] - s0):
            seg = s0 + u
            slot = TI[ss + seg]
            f = fs + KS * seg
            if slot == CONSTANT:
                R, o = _constant(TF, f, R, o)
            else:
                i = nonneg(TI[sc + seg])
                R, o, sv = _slot(slot, TF[f] + q[q_at + i], R, o)
                for j in range(6):          # s by components: W[wc + j n + i]
                    W[wc + j * n + i] = sv[j]
                xd = qd[qd_at + i] if moving else 0.0
                W[wqd + i] = xd
                if qdd is None:
                    if xd != 0.0:
                        V, Acc = _rates(sv, xd, 0.0, V, Acc)
                else:
                    xdd = qdd[qdd_at + i]
                    if xd != 0.0 or xdd != 0.0:
                        V, Acc = _rates(sv, xd, xdd, V, Acc)
        _store(W, wl + KL * p, R, o, V, Acc)


@one_signature
@kernel
def poses(tree, R, o):
    """Copy every link's rotation into ``R`` (L, 3, 3) and origin into ``o`` (L, 3) after :func:`kinematics`."""
    TI, W = tree.TI, tree.W
    wl = nonneg(TI[W_LINK])
    for p in range(TI[0]):
        d = wl + KL * p
        for r in range(3):
            o[p, r] = W[d + O_ + r]
            for c in range(3):
                R[p, r, c] = W[d + 3 * r + c]


# -- one link's mass in {0} -------------------------------------------------------------------------
@njit(cache=True, inline="always")
def _body(TI, TF, W, p, d):
    """m, the first moment c (3,) and J = tr(S) 1 - S (6,) about {0} of link ``p`` alone into the
    record's CM, CC, CJ slots (E28, E29): ``c = R m r_C + m o``,
    ``J = R J_l R^T + 2 (u.o) 1 - (u o^T + o u^T)`` with ``u = R m r_C + m o / 2``. Returns m."""
    fl = nonneg(TI[F_LINK]) + KF * nonneg(p)
    d = nonneg(d)
    m = TF[fl]
    mx, my, mz = TF[fl + 1], TF[fl + 2], TF[fl + 3]
    Jxx, Jyy, Jzz, Jxy, Jxz, Jyz = TF[fl + 4], TF[fl + 5], TF[fl + 6], TF[fl + 7], TF[fl + 8], TF[fl + 9]
    if m == 0.0 and mx == 0.0 and my == 0.0 and mz == 0.0 and Jxx == 0.0 and Jyy == 0.0 and Jzz == 0.0 \
            and Jxy == 0.0 and Jxz == 0.0 and Jyz == 0.0:
        for j in range(10):
            W[d + CM + j] = 0.0
        return 0.0
    R00, R01, R02 = W[d], W[d + 1], W[d + 2]
    R10, R11, R12 = W[d + 3], W[d + 4], W[d + 5]
    R20, R21, R22 = W[d + 6], W[d + 7], W[d + 8]
    o0, o1, o2 = W[d + O_], W[d + O_ + 1], W[d + O_ + 2]
    l0 = R00 * mx + R01 * my + R02 * mz
    l1 = R10 * mx + R11 * my + R12 * mz
    l2 = R20 * mx + R21 * my + R22 * mz
    # X = R J_l, then the upper triangle of X R^T
    X00 = R00 * Jxx + R01 * Jxy + R02 * Jxz
    X01 = R00 * Jxy + R01 * Jyy + R02 * Jyz
    X02 = R00 * Jxz + R01 * Jyz + R02 * Jzz
    X10 = R10 * Jxx + R11 * Jxy + R12 * Jxz
    X11 = R10 * Jxy + R11 * Jyy + R12 * Jyz
    X12 = R10 * Jxz + R11 * Jyz + R12 * Jzz
    X20 = R20 * Jxx + R21 * Jxy + R22 * Jxz
    X21 = R20 * Jxy + R21 * Jyy + R22 * Jyz
    X22 = R20 * Jxz + R21 * Jyz + R22 * Jzz
    u0 = l0 + 0.5 * m * o0
    u1 = l1 + 0.5 * m * o1
    u2 = l2 + 0.5 * m * o2
    W[d + CM] = m
    W[d + CC] = l0 + m * o0
    W[d + CC + 1] = l1 + m * o1
    W[d + CC + 2] = l2 + m * o2
    W[d + CJ] = X00 * R00 + X01 * R01 + X02 * R02 + 2.0 * (u1 * o1 + u2 * o2)
    W[d + CJ + 1] = X10 * R10 + X11 * R11 + X12 * R12 + 2.0 * (u0 * o0 + u2 * o2)
    W[d + CJ + 2] = X20 * R20 + X21 * R21 + X22 * R22 + 2.0 * (u0 * o0 + u1 * o1)
    W[d + CJ + 3] = X00 * R10 + X01 * R11 + X02 * R12 - (u0 * o1 + u1 * o0)
    W[d + CJ + 4] = X00 * R20 + X01 * R21 + X02 * R22 - (u0 * o2 + u2 * o0)
    W[d + CJ + 5] = X10 * R20 + X11 * R21 + X12 * R22 - (u1 * o2 + u2 * o1)
    return m


@njit(cache=True, inline="always")
def _link_wrench(W, d, wb, momentum):
    """The inertial wrench (f, n) (E35) of the link whose (m, c, J) are in its record; with
    ``momentum`` its momentum ``(omega x c + m v, J omega + c x v)`` is added to the base record."""
    d, wb = nonneg(d), nonneg(wb)
    m = W[d + CM]
    c0, c1, c2 = W[d + CC], W[d + CC + 1], W[d + CC + 2]
    Jxx, Jyy, Jzz = W[d + CJ], W[d + CJ + 1], W[d + CJ + 2]
    Jxy, Jxz, Jyz = W[d + CJ + 3], W[d + CJ + 4], W[d + CJ + 5]
    om0, om1, om2 = W[d + WV], W[d + WV + 1], W[d + WV + 2]
    v0, v1, v2 = W[d + WV + 3], W[d + WV + 4], W[d + WV + 5]
    al0, al1, al2 = W[d + AC], W[d + AC + 1], W[d + AC + 2]
    a0, a1, a2 = W[d + AC + 3], W[d + AC + 4], W[d + AC + 5]
    Jo0 = Jxx * om0 + Jxy * om1 + Jxz * om2
    Jo1 = Jxy * om0 + Jyy * om1 + Jyz * om2
    Jo2 = Jxz * om0 + Jyz * om1 + Jzz * om2
    Ja0 = Jxx * al0 + Jxy * al1 + Jxz * al2
    Ja1 = Jxy * al0 + Jyy * al1 + Jyz * al2
    Ja2 = Jxz * al0 + Jyz * al1 + Jzz * al2
    # u = omega x c + m v (momentum), f = alpha x c + m a + omega x u
    u0 = om1 * c2 - om2 * c1 + m * v0
    u1 = om2 * c0 - om0 * c2 + m * v1
    u2 = om0 * c1 - om1 * c0 + m * v2
    W[d + FI] = al1 * c2 - al2 * c1 + m * a0 + om1 * u2 - om2 * u1
    W[d + FI + 1] = al2 * c0 - al0 * c2 + m * a1 + om2 * u0 - om0 * u2
    W[d + FI + 2] = al0 * c1 - al1 * c0 + m * a2 + om0 * u1 - om1 * u0
    # n = J alpha + c x (a + omega x v) + omega x (J omega)
    x0 = om1 * v2 - om2 * v1 + a0
    x1 = om2 * v0 - om0 * v2 + a1
    x2 = om0 * v1 - om1 * v0 + a2
    W[d + FI + 3] = Ja0 + c1 * x2 - c2 * x1 + om1 * Jo2 - om2 * Jo1
    W[d + FI + 4] = Ja1 + c2 * x0 - c0 * x2 + om2 * Jo0 - om0 * Jo2
    W[d + FI + 5] = Ja2 + c0 * x1 - c1 * x0 + om0 * Jo1 - om1 * Jo0
    if momentum:
        e = wb + BASE_MOM
        W[e] += u0
        W[e + 1] += u1
        W[e + 2] += u2
        W[e + 3] += Jo0 + c1 * v2 - c2 * v1
        W[e + 4] += Jo1 + c2 * v0 - c0 * v2
        W[e + 5] += Jo2 + c0 * v1 - c1 * v0


# -- leaves to root ---------------------------------------------------------------------------------
@one_signature
@kernel
def _subtree_sums(tree, loads):
    """(E30): every link's (m, c, J), inertial wrench and (with ``loads``) external wrench summed over its subtree."""
    TI, W = tree.TI, tree.W
    wl = nonneg(TI[W_LINK])
    par = nonneg(TI[I_PARENT])
    for p in range(TI[0] - 1, 0, -1):
        s = TI[par + p]
        if s >= 0:
            d = wl + KL * p
            e = wl + KL * nonneg(s)
            for j in range(CM, FX):     # m, c, J, f, n
                W[e + j] += W[d + j]
            if loads:
                for j in range(FX, FX + 6):
                    W[e + j] += W[d + j]


@one_signature
@kernel
def dynamics(tree, want_A, loads, momentum):
    """Leaves to root after :func:`kinematics` (and, with ``loads``, the external wrenches of
    :func:`add_wrench`): ``b = -(e + G)`` (E34), ``Q`` (E36) with ``loads``, and with ``want_A`` the
    mass matrix (E31) packed by ancestor pairs (row ``i``: ``A[i, anc_idx[j]]`` at ``W[W_A + j]``,
    ``j`` in ``anc_ptr[i]:anc_ptr[i + 1]``), armature included (:func:`armature`). With ``momentum``
    the links' total momentum goes to the base record (for :func:`base_power`)."""
    TI, TF, W = tree
    L, n = TI[0], nonneg(TI[1])
    wl, wc, wb = nonneg(TI[W_LINK]), nonneg(TI[W_COORD]), nonneg(TI[W_BASE])
    if momentum:
        for j in range(6):
            W[wb + BASE_MOM + j] = 0.0
    for p in range(L):
        d = wl + KL * p
        _body(TI, TF, W, p, d)
        _link_wrench(W, d, wb, momentum)
    _subtree_sums(tree, loads)
    cl, ap, ai = nonneg(TI[I_COORDLINK]), nonneg(TI[I_ANCPTR]), nonneg(TI[I_ANCIDX])
    rp, rs = nonneg(TI[I_RUNPTR]), nonneg(TI[I_RUNS])
    wa, wbv, wq = nonneg(TI[W_A]), nonneg(TI[W_B]), nonneg(TI[W_Q])
    for i in range(n):
        d = wl + KL * nonneg(TI[cl + i])
        si = wc + i
        w0, w1, w2 = W[si], W[si + n], W[si + 2 * n]
        v0, v1, v2 = W[si + 3 * n], W[si + 4 * n], W[si + 5 * n]
        # wrench (f, n) . twist (w, v) = v . f + w . n
        f = d + FI
        W[wbv + i] = -(v0 * W[f] + v1 * W[f + 1] + v2 * W[f + 2] + w0 * W[f + 3] + w1 * W[f + 4] + w2 * W[f + 5])
        if loads:
            f = d + FX
            W[wq + i] = v0 * W[f] + v1 * W[f + 1] + v2 * W[f + 2] + w0 * W[f + 3] + w1 * W[f + 4] + w2 * W[f + 5]
        if not want_A:
            continue
        m = W[d + CM]
        c0, c1, c2 = W[d + CC], W[d + CC + 1], W[d + CC + 2]
        Jxx, Jyy, Jzz = W[d + CJ], W[d + CJ + 1], W[d + CJ + 2]
        Jxy, Jxz, Jyz = W[d + CJ + 3], W[d + CJ + 4], W[d + CJ + 5]
        p0 = w1 * c2 - w2 * c1 + m * v0
        p1 = w2 * c0 - w0 * c2 + m * v1
        p2 = w0 * c1 - w1 * c0 + m * v2
        h0 = Jxx * w0 + Jxy * w1 + Jxz * w2 + c1 * v2 - c2 * v1
        h1 = Jxy * w0 + Jyy * w1 + Jyz * w2 + c2 * v0 - c0 * v2
        h2 = Jxz * w0 + Jyz * w1 + Jzz * w2 + c0 * v1 - c1 * v0
        j0 = nonneg(TI[ap + i])
        m = TI[ap + i + 1] - j0
        if TI[rp + i + 1] - TI[rp + i] == 1:       # the row is one run of coordinates c0, c0 + 1, ...
            c0 = wc + nonneg(TI[rs + 2 * nonneg(TI[rp + i])])
            for u in range(m):
                sl = c0 + u
                W[wa + j0 + u] = (W[sl + 3 * n] * p0 + W[sl + 4 * n] * p1 + W[sl + 5 * n] * p2
                                  + W[sl] * h0 + W[sl + n] * h1 + W[sl + 2 * n] * h2)
        else:
            for u in range(m):
                sl = wc + nonneg(TI[ai + j0 + u])
                W[wa + j0 + u] = (W[sl + 3 * n] * p0 + W[sl + 4 * n] * p1 + W[sl + 5 * n] * p2
                                  + W[sl] * h0 + W[sl + n] * h1 + W[sl + 2 * n] * h2)
    if TI[N_ARM] > 0:
        armature(tree, want_A)


@one_signature
@kernel
def armature(tree, want_A):
    """The armature's terms (E49) added to the packed ``A`` (with ``want_A``) and to ``b = -(e + G)``,
    after :func:`dynamics`' own terms. A coordinate of its own: ``a`` on its diagonal. The three
    angles ``i`` of a ball link ``p`` (parent record ``s``): ``a w_i.w_l`` on the 3 x 3 block and
    ``-a w_i.(alpha_p - alpha_s - omega_p x (omega_p - omega_s))`` into ``b``: the relative angular
    velocity ``omega_p - omega_s = sum w_i q_i'`` in {0}, and ``J^T a J' q'`` in world twists."""
    TI, TF, W = tree
    n = nonneg(TI[1])
    ia, fa = nonneg(TI[I_ARM]), nonneg(TI[F_ARM])
    wl, wc, wb, wa, wbv = nonneg(TI[W_LINK]), nonneg(TI[W_COORD]), nonneg(TI[W_BASE]), nonneg(TI[W_A]), nonneg(TI[W_B])
    ap, par = nonneg(TI[I_ANCPTR]), nonneg(TI[I_PARENT])
    for k in range(TI[N_ARM]):
        kind, i, p = TI[ia + 3 * k], nonneg(TI[ia + 3 * k + 1]), nonneg(TI[ia + 3 * k + 2])
        a = TF[fa + k]
        if kind != ARM_BALL:
            if want_A:
                W[wa + nonneg(TI[ap + i + 1] - 1)] += a
            continue
        d = wl + KL * p
        s = TI[par + p]
        e = wb if s < 0 else wl + KL * nonneg(s)
        o0, o1, o2 = W[d + WV], W[d + WV + 1], W[d + WV + 2]
        r0, r1, r2 = o0 - W[e + WV], o1 - W[e + WV + 1], o2 - W[e + WV + 2]
        x0 = W[d + AC] - W[e + AC] - (o1 * r2 - o2 * r1)
        x1 = W[d + AC + 1] - W[e + AC + 1] - (o2 * r0 - o0 * r2)
        x2 = W[d + AC + 2] - W[e + AC + 2] - (o0 * r1 - o1 * r0)
        for u in range(3):
            si = wc + i + u
            w0, w1, w2 = W[si], W[si + n], W[si + 2 * n]
            W[wbv + i + u] -= a * (w0 * x0 + w1 * x1 + w2 * x2)
            if want_A:
                last = nonneg(TI[ap + i + u + 1] - 1)      # row i + u ends with i, .., i + u (the same link)
                for v in range(u + 1):
                    sl = wc + i + v
                    W[wa + last - u + v] += a * (w0 * W[sl] + w1 * W[sl + n] + w2 * W[sl + 2 * n])


# -- applied wrenches, energies, base power -----------------------------------------------------------
@one_signature
@kernel
def clear_wrenches(tree):
    """Every link's external wrench set to zero (before :func:`add_wrench`)."""
    TI, W = tree.TI, tree.W
    wl = nonneg(TI[W_LINK])
    for p in range(TI[0]):
        for j in range(6):
            W[wl + KL * p + FX + j] = 0.0


@one_signature
@kernel
def add_wrench(tree, p, F0, F1, F2, M0, M1, M2, r0, r1, r2, local):
    """Add a force ``F`` and a moment ``M`` acting at the point ``r`` (link frame) of link ``p`` to
    its external wrench as ``(F, M + r_N x F)`` about {0} (E36); ``local``: F and M in the link's axes."""
    TI, W = tree.TI, tree.W
    d = nonneg(TI[W_LINK]) + KL * nonneg(p)
    R00, R01, R02 = W[d], W[d + 1], W[d + 2]
    R10, R11, R12 = W[d + 3], W[d + 4], W[d + 5]
    R20, R21, R22 = W[d + 6], W[d + 7], W[d + 8]
    x0 = R00 * r0 + R01 * r1 + R02 * r2 + W[d + O_]
    x1 = R10 * r0 + R11 * r1 + R12 * r2 + W[d + O_ + 1]
    x2 = R20 * r0 + R21 * r1 + R22 * r2 + W[d + O_ + 2]
    if local:
        F0, F1, F2 = R00 * F0 + R01 * F1 + R02 * F2, R10 * F0 + R11 * F1 + R12 * F2, R20 * F0 + R21 * F1 + R22 * F2
        M0, M1, M2 = R00 * M0 + R01 * M1 + R02 * M2, R10 * M0 + R11 * M1 + R12 * M2, R20 * M0 + R21 * M1 + R22 * M2
    e = d + FX
    W[e] += F0
    W[e + 1] += F1
    W[e + 2] += F2
    W[e + 3] += M0 + x1 * F2 - x2 * F1
    W[e + 4] += M1 + x2 * F0 - x0 * F2
    W[e + 5] += M2 + x0 * F1 - x1 * F0


@one_signature
@kernel
def set_loads(tree, loads):
    """The links' external wrenches (E36) of ``loads`` (k, 11), one row per wrench
    ``(link, F (3), M (3), point (3), local)`` (:func:`add_wrench`), from zero."""
    clear_wrenches(tree)
    for k in range(loads.shape[0]):
        add_wrench(tree, int(loads[k, 0]), loads[k, 1], loads[k, 2], loads[k, 3], loads[k, 4], loads[k, 5],
                   loads[k, 6], loads[k, 7], loads[k, 8], loads[k, 9], loads[k, 10] != 0.0)


@one_signature
@kernel
def energies(tree, gx, gy, gz):
    """``(E, V)`` after :func:`kinematics` (E37): ``E = 0.5 sum (m v.v + 2 v.(omega x c) + omega.J omega)``,
    ``V = -g . sum c``."""
    TI, TF, W = tree
    wl = nonneg(TI[W_LINK])
    E = 0.0
    V = 0.0
    for p in range(TI[0]):
        d = wl + KL * p
        m = _body(TI, TF, W, p, d)
        c0, c1, c2 = W[d + CC], W[d + CC + 1], W[d + CC + 2]
        Jxx, Jyy, Jzz = W[d + CJ], W[d + CJ + 1], W[d + CJ + 2]
        Jxy, Jxz, Jyz = W[d + CJ + 3], W[d + CJ + 4], W[d + CJ + 5]
        om0, om1, om2 = W[d + WV], W[d + WV + 1], W[d + WV + 2]
        v0, v1, v2 = W[d + WV + 3], W[d + WV + 4], W[d + WV + 5]
        wJw = (om0 * (Jxx * om0 + Jxy * om1 + Jxz * om2) + om1 * (Jxy * om0 + Jyy * om1 + Jyz * om2)
               + om2 * (Jxz * om0 + Jyz * om1 + Jzz * om2))
        x0 = om1 * c2 - om2 * c1
        x1 = om2 * c0 - om0 * c2
        x2 = om0 * c1 - om1 * c0
        E += 0.5 * (m * (v0 * v0 + v1 * v1 + v2 * v2) + 2.0 * (v0 * x0 + v1 * x1 + v2 * x2) + wJw)
        V -= gx * c0 + gy * c1 + gz * c2
    if TI[N_ARM] > 0:
        E += armature_energy(tree)
    return E, V


@one_signature
@kernel
def armature_energy(tree):
    """The armature's kinetic energy (E49) after :func:`kinematics`: ``0.5 a q'^2`` per coordinate of
    its own, ``0.5 a |omega_p - omega_s|^2`` per ball link."""
    TI, TF, W = tree
    ia, fa = nonneg(TI[I_ARM]), nonneg(TI[F_ARM])
    wl, wb, wqd, par = nonneg(TI[W_LINK]), nonneg(TI[W_BASE]), nonneg(TI[W_QD]), nonneg(TI[I_PARENT])
    E = 0.0
    for k in range(TI[N_ARM]):
        kind, i, p = TI[ia + 3 * k], nonneg(TI[ia + 3 * k + 1]), nonneg(TI[ia + 3 * k + 2])
        a = TF[fa + k]
        if kind != ARM_BALL:
            E += 0.5 * a * W[wqd + i] * W[wqd + i]
            continue
        d = wl + KL * p
        s = TI[par + p]
        e = wb if s < 0 else wl + KL * nonneg(s)
        r0, r1, r2 = W[d + WV] - W[e + WV], W[d + WV + 1] - W[e + WV + 1], W[d + WV + 2] - W[e + WV + 2]
        E += 0.5 * a * (r0 * r0 + r1 * r1 + r2 * r2)
    return E


@one_signature
@kernel
def base_power(tree, gx, gy, gz):
    """``(dE/dt, dV/dt)`` at fixed ``(q, q')`` due to the base motion alone (E41), after
    :func:`dynamics` with ``momentum``: with the base's twist ``(omega_B, v_B)``, its acceleration
    ``(alpha_B, a_B)`` and the links' total momentum ``(P, H)`` about {0},
    ``dE/dt = tr(dW_B sum Hw Xi^T) = a_B.P + alpha_B.H`` (the second trace of E41 vanishes: a skew
    matrix against a symmetric one) and ``dV/dt = -g . (omega_B x sum c + (sum m) v_B)``."""
    TI, W = tree.TI, tree.W
    wb = nonneg(TI[W_BASE])
    wl = nonneg(TI[W_LINK])
    par = nonneg(TI[I_PARENT])
    dE = 0.0
    for j in range(6):
        dE += W[wb + BASE_ACC + j] * W[wb + BASE_MOM + (j + 3) % 6]
    mt = 0.0
    ct0 = 0.0
    ct1 = 0.0
    ct2 = 0.0
    for p in range(TI[0]):      # the roots' subtree sums cover every link
        if TI[par + p] < 0:
            d = wl + KL * p
            mt += W[d + CM]
            ct0 += W[d + CC]
            ct1 += W[d + CC + 1]
            ct2 += W[d + CC + 2]
    e = wb + BASE_TWIST
    w0, w1, w2, v0, v1, v2 = W[e], W[e + 1], W[e + 2], W[e + 3], W[e + 4], W[e + 5]
    dV = -(gx * (w1 * ct2 - w2 * ct1 + mt * v0) + gy * (w2 * ct0 - w0 * ct2 + mt * v1)
           + gz * (w0 * ct1 - w1 * ct0 + mt * v2))
    return dE, dV

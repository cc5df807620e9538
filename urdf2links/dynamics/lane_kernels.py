"""The recursive form in SIMD lanes: :mod:`urdf2links.dynamics.kernels`' passes for a block of ``LW`` states at once.

The scratch of a block is ``WL`` (W_SIZE, LW), flat: the rows are the single-state scratch ``W``'s entries, at
the same header offsets (:mod:`urdf2links.dynamics.tree_arrays`), and the state index (the lane) is
innermost and contiguous. Every scalar operation of the row kernels becomes a loop ``for l in range(LW)``
over contiguous memory, which LLVM turns into vector instructions (4 doubles per AVX2 register, 8 per
AVX-512 one). What depends on the tree alone (slot kinds, parents, which links have mass) is the same in
every lane and stays outside the lane loops; nothing inside them branches on the data: the scalar
kernels' skips of a zero rate (``if xd != 0.0``) are gone (adding ``s 0`` changes no value but the sign
of a zero). ``LW`` reaches these functions as a compile-time constant: the length of the type of their
argument ``lanes``, a tuple of ``LW`` booleans (one compiled variant per width; numba's ``literally`` would
cost a failed compilation at every call from Python): the loops then have a constant trip count. Each lane
loop is a small function whose arguments are views of a few rows (a link's record :func:`rows`, a
coordinate's unit twist, a row of ``A``): inside it every access is a constant row of one view, and the
views are distinct arguments, which LLVM checks for overlap once per call and then vectorizes. (Offsets
into one array that differ by a number known only at run time -- the parent's record and the child's --
stop its vectorizer: it cannot prove the reordering safe.)

Unlike ``W``, the unit twists are stored by coordinate: ``s_i[j]`` at row ``W_COORD + 6 i + j``, so that a
coordinate's six rows are one view.

The operations are the row kernels' own, in the same order, without ``fastmath`` (no reassociation, no
fused multiply-add): a lane's result is the scalar row's, to the last bit on the tested robots
(tests/test_lanes.py allows 1e-14 relative). The cosines and sines of a block are computed first
(:func:`angles`), one libm call per lane (numba has no vector math library here; the calls stay scalar),
and the passes read them. Scope: a fixed base, no loads, no coupling, no armature (the batch entry falls
back to the scalar rows otherwise); ``-g`` enters as the base's acceleration (E33) as in
:func:`~urdf2links.dynamics.kernels.kinematics`.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..compilation import kernel

from .tree_arrays import (
    AC, CC, CJ, CM, CONSTANT, F_LINK, F_SEG, FI, FX, I_ANCIDX, I_ANCPTR, I_COORDLINK, I_PARENT, I_RUNPTR,
    I_RUNS, I_SEGCOORD,
    I_SEGPTR, I_SEGSLOT, KF, KL, KS, O_, W_A, W_B, W_BASE, W_COORD, W_LINK, WV,
)

__all__ = ["angles", "lane_kinematics", "lane_dynamics", "small", "rows"]


@njit(cache=True, inline="always")
def small(k):
    """An offset or index (never negative, below 2^28) said so to the compiler by its bits: ``k & (2^28 - 1)``.
    numba wraps a negative index around (a compare and a select per access), which stops LLVM's vectorizer;
    :func:`~urdf2links.dynamics.tree_arrays.nonneg` (``max(k, 0)``) is not enough here, because
    ``(d + j) LW + l`` may overflow for all LLVM knows, while an offset with its top bits known zero
    cannot. A scratch of 2^28 doubles (2 GB) is far above any tree's."""
    return k & 0xFFFFFFF


@njit(cache=True, inline="always")
def rows(A, r, m, LW):
    """The view of ``m`` rows of the lane array ``A`` (rows of ``LW``, flat) from row ``r``."""
    r = small(r)
    return A[r * LW:(r + m) * LW]


# -- root to leaves ---------------------------------------------------------------------------------
@kernel
def angles(TI, TF, QL, CL, SL, lanes):
    """Per variable segment ``seg`` of coordinate ``i``: ``x = offset + q_i`` in every lane; a rotation
    slot's ``cos x`` into ``CL[seg]`` and ``sin x`` into ``SL[seg]``, a translation's ``x`` into ``CL[seg]``.
    ``QL`` (n, LW) the block's coordinates; ``CL``, ``SL`` (S, LW) (flat)."""
    LW = len(lanes)
    ss, sc, fs = small(TI[I_SEGSLOT]), small(TI[I_SEGCOORD]), small(TI[F_SEG])
    for seg in range(TI[2]):
        slot = TI[ss + seg]
        if slot != CONSTANT:
            _angle(rows(QL, TI[sc + seg], 1, LW), TF[fs + KS * seg], slot < 3, rows(CL, seg, 1, LW),
                   rows(SL, seg, 1, LW), lanes)


@kernel
def _angle(q, off, linear, c, s, lanes):
    """``x = off + q`` (one row); a translation's ``x`` into ``c``, else ``cos x``, ``sin x`` into ``c``, ``s``:
    libm's calls, one per lane, the scalar rows' own (docs/speed.md, "Lanes": branch-free polynomials within
    1 ulp were measured, and rejected)."""
    LW = len(lanes)
    if linear:
        for l in range(LW):
            c[l] = off + q[l]
        return
    for l in range(LW):
        x = off + q[l]
        c[l] = np.cos(x)
        s[l] = np.sin(x)


@kernel
def _base(B, gx, gy, gz, lanes):
    """The fixed base's record ``B``: identity pose, no motion, acceleration ``-g`` (E33)."""
    LW = len(lanes)
    for j in range(24):
        for l in range(LW):
            B[j * LW + l] = 0.0
    for j in range(3):
        for l in range(LW):
            B[4 * j * LW + l] = 1.0
    for l in range(LW):
        B[(AC + 3) * LW + l] = -gx
        B[(AC + 4) * LW + l] = -gy
        B[(AC + 5) * LW + l] = -gz


@kernel
def _copy(src, dst, lanes):
    """The parent's pose, twist and acceleration (24 rows) into a child's record."""
    LW = len(lanes)
    for x in range(24 * LW):
        dst[x] = src[x]


@kernel
def _constant(TF, f, D, lanes):
    """``T <- T C`` for the constant transform at ``TF[f:]`` on the pose of the record ``D``, every lane."""
    LW = len(lanes)
    f = small(f)
    C00, C01, C02, C10, C11, C12 = TF[f + 1], TF[f + 2], TF[f + 3], TF[f + 4], TF[f + 5], TF[f + 6]
    C20, C21, C22, p0, p1, p2 = TF[f + 7], TF[f + 8], TF[f + 9], TF[f + 10], TF[f + 11], TF[f + 12]
    for l in range(LW):
        R00, R01, R02 = D[l], D[LW + l], D[2 * LW + l]
        R10, R11, R12 = D[3 * LW + l], D[4 * LW + l], D[5 * LW + l]
        R20, R21, R22 = D[6 * LW + l], D[7 * LW + l], D[8 * LW + l]
        D[O_ * LW + l] = D[O_ * LW + l] + R00 * p0 + R01 * p1 + R02 * p2
        D[(O_ + 1) * LW + l] = D[(O_ + 1) * LW + l] + R10 * p0 + R11 * p1 + R12 * p2
        D[(O_ + 2) * LW + l] = D[(O_ + 2) * LW + l] + R20 * p0 + R21 * p1 + R22 * p2
        D[l] = R00 * C00 + R01 * C10 + R02 * C20
        D[LW + l] = R00 * C01 + R01 * C11 + R02 * C21
        D[2 * LW + l] = R00 * C02 + R01 * C12 + R02 * C22
        D[3 * LW + l] = R10 * C00 + R11 * C10 + R12 * C20
        D[4 * LW + l] = R10 * C01 + R11 * C11 + R12 * C21
        D[5 * LW + l] = R10 * C02 + R11 * C12 + R12 * C22
        D[6 * LW + l] = R20 * C00 + R21 * C10 + R22 * C20
        D[7 * LW + l] = R20 * C01 + R21 * C11 + R22 * C21
        D[8 * LW + l] = R20 * C02 + R21 * C12 + R22 * C22


@kernel
def _constant_from(TF, f, P, D, lanes):
    """A link's first factor, constant: the record ``D`` gets the parent's (``P``) pose times the constant
    transform at ``TF[f:]``, and its twist and acceleration (one pass instead of a copy and :func:`_constant`)."""
    LW = len(lanes)
    f = small(f)
    C00, C01, C02, C10, C11, C12 = TF[f + 1], TF[f + 2], TF[f + 3], TF[f + 4], TF[f + 5], TF[f + 6]
    C20, C21, C22, p0, p1, p2 = TF[f + 7], TF[f + 8], TF[f + 9], TF[f + 10], TF[f + 11], TF[f + 12]
    for l in range(LW):
        R00, R01, R02 = P[l], P[LW + l], P[2 * LW + l]
        R10, R11, R12 = P[3 * LW + l], P[4 * LW + l], P[5 * LW + l]
        R20, R21, R22 = P[6 * LW + l], P[7 * LW + l], P[8 * LW + l]
        D[O_ * LW + l] = P[O_ * LW + l] + R00 * p0 + R01 * p1 + R02 * p2
        D[(O_ + 1) * LW + l] = P[(O_ + 1) * LW + l] + R10 * p0 + R11 * p1 + R12 * p2
        D[(O_ + 2) * LW + l] = P[(O_ + 2) * LW + l] + R20 * p0 + R21 * p1 + R22 * p2
        D[l] = R00 * C00 + R01 * C10 + R02 * C20
        D[LW + l] = R00 * C01 + R01 * C11 + R02 * C21
        D[2 * LW + l] = R00 * C02 + R01 * C12 + R02 * C22
        D[3 * LW + l] = R10 * C00 + R11 * C10 + R12 * C20
        D[4 * LW + l] = R10 * C01 + R11 * C11 + R12 * C21
        D[5 * LW + l] = R10 * C02 + R11 * C12 + R12 * C22
        D[6 * LW + l] = R20 * C00 + R21 * C10 + R22 * C20
        D[7 * LW + l] = R20 * C01 + R21 * C11 + R22 * C21
        D[8 * LW + l] = R20 * C02 + R21 * C12 + R22 * C22
        for j in range(WV, AC + 6):
            D[j * LW + l] = P[j * LW + l]


@kernel
def _constant_rotation(TF, f, P, D, k, c, s, xd, S, lanes):
    """A link whose factors are a constant transform then a rotation about the local axis ``k`` (most joints):
    :func:`_constant_from` and :func:`_rotation` in one pass, the pose kept in registers between them."""
    LW = len(lanes)
    f = small(f)
    C = (TF[f + 1], TF[f + 2], TF[f + 3], TF[f + 4], TF[f + 5], TF[f + 6], TF[f + 7], TF[f + 8], TF[f + 9])
    p = (TF[f + 10], TF[f + 11], TF[f + 12])
    if k == 0:
        _constant_rotation_about(C, p, P, D, 0, 1, 2, c, s, xd, S, LW)
    elif k == 1:
        _constant_rotation_about(C, p, P, D, 1, 2, 0, c, s, xd, S, LW)
    else:
        _constant_rotation_about(C, p, P, D, 2, 0, 1, c, s, xd, S, LW)


@njit(cache=True, inline="always")
def _constant_rotation_about(C, p, P, D, k, a, b, c, s, xd, S, LW):
    C00, C01, C02, C10, C11, C12, C20, C21, C22 = C
    p0, p1, p2 = p
    for l in range(LW):
        R00, R01, R02 = P[l], P[LW + l], P[2 * LW + l]
        R10, R11, R12 = P[3 * LW + l], P[4 * LW + l], P[5 * LW + l]
        R20, R21, R22 = P[6 * LW + l], P[7 * LW + l], P[8 * LW + l]
        o0 = P[O_ * LW + l] + R00 * p0 + R01 * p1 + R02 * p2
        o1 = P[(O_ + 1) * LW + l] + R10 * p0 + R11 * p1 + R12 * p2
        o2 = P[(O_ + 2) * LW + l] + R20 * p0 + R21 * p1 + R22 * p2
        M = (R00 * C00 + R01 * C10 + R02 * C20, R00 * C01 + R01 * C11 + R02 * C21, R00 * C02 + R01 * C12 + R02 * C22,
             R10 * C00 + R11 * C10 + R12 * C20, R10 * C01 + R11 * C11 + R12 * C21, R10 * C02 + R11 * C12 + R12 * C22,
             R20 * C00 + R21 * C10 + R22 * C20, R20 * C01 + R21 * C11 + R22 * C21, R20 * C02 + R21 * C12 + R22 * C22)
        co, sn = c[l], s[l]
        for r in range(3):
            Ra, Rb = M[3 * r + a], M[3 * r + b]
            D[(3 * r + a) * LW + l] = co * Ra + sn * Rb
            D[(3 * r + b) * LW + l] = -sn * Ra + co * Rb
            D[(3 * r + k) * LW + l] = M[3 * r + k]
        D[O_ * LW + l] = o0
        D[(O_ + 1) * LW + l] = o1
        D[(O_ + 2) * LW + l] = o2
        for j in range(WV, AC + 6):
            D[j * LW + l] = P[j * LW + l]
        w0, w1, w2 = M[k], M[3 + k], M[6 + k]
        _rates(D, S, l, LW, w0, w1, w2, o1 * w2 - o2 * w1, o2 * w0 - o0 * w2, o0 * w1 - o1 * w0, xd[l])


@kernel
def _rotation(D, k, c, s, xd, S, lanes):
    """A rotation slot about the local axis ``k`` on the record ``D`` (E48): R's columns ``a, b`` (1, 2 about
    x; 2, 0 about y; 0, 1 about z) turned by ``(c, s)`` (the row kernel's ``_turn``), the unit twist
    ``s = (w, o x w)`` (``w = R e_k``) into ``S`` (6 rows), and its rates ``xd`` (:func:`_rates`). The columns
    are constants in each branch: rows of one view at distances known only at run time stop the vectorizer."""
    LW = len(lanes)
    if k == 0:
        _rotation_about(D, 0, 1, 2, c, s, xd, S, LW)
    elif k == 1:
        _rotation_about(D, 1, 2, 0, c, s, xd, S, LW)
    else:
        _rotation_about(D, 2, 0, 1, c, s, xd, S, LW)


@njit(cache=True, inline="always")
def _rotation_about(D, k, a, b, c, s, xd, S, LW):
    for l in range(LW):
        co, sn = c[l], s[l]
        Ra0, Ra1, Ra2 = D[a * LW + l], D[(3 + a) * LW + l], D[(6 + a) * LW + l]
        Rb0, Rb1, Rb2 = D[b * LW + l], D[(3 + b) * LW + l], D[(6 + b) * LW + l]
        D[a * LW + l] = co * Ra0 + sn * Rb0
        D[(3 + a) * LW + l] = co * Ra1 + sn * Rb1
        D[(6 + a) * LW + l] = co * Ra2 + sn * Rb2
        D[b * LW + l] = -sn * Ra0 + co * Rb0
        D[(3 + b) * LW + l] = -sn * Ra1 + co * Rb1
        D[(6 + b) * LW + l] = -sn * Ra2 + co * Rb2
        w0, w1, w2 = D[k * LW + l], D[(3 + k) * LW + l], D[(6 + k) * LW + l]
        o0, o1, o2 = D[O_ * LW + l], D[(O_ + 1) * LW + l], D[(O_ + 2) * LW + l]
        _rates(D, S, l, LW, w0, w1, w2, o1 * w2 - o2 * w1, o2 * w0 - o0 * w2, o0 * w1 - o1 * w0, xd[l])


@kernel
def _translation(D, k, x, xd, S, lanes):
    """A translation slot along the local axis ``k`` by ``x`` (one row) on the record ``D``: ``o += R e_k x``,
    the unit twist ``s = (0, R e_k)`` into ``S`` and its rates; ``k`` a constant in each branch (:func:`_rotation`)."""
    LW = len(lanes)
    if k == 0:
        _translation_along(D, 0, x, xd, S, LW)
    elif k == 1:
        _translation_along(D, 1, x, xd, S, LW)
    else:
        _translation_along(D, 2, x, xd, S, LW)


@njit(cache=True, inline="always")
def _translation_along(D, k, x, xd, S, LW):
    for l in range(LW):
        e0, e1, e2 = D[k * LW + l], D[(3 + k) * LW + l], D[(6 + k) * LW + l]
        D[O_ * LW + l] = D[O_ * LW + l] + e0 * x[l]
        D[(O_ + 1) * LW + l] = D[(O_ + 1) * LW + l] + e1 * x[l]
        D[(O_ + 2) * LW + l] = D[(O_ + 2) * LW + l] + e2 * x[l]
        _rates(D, S, l, LW, 0.0, 0.0, 0.0, e0, e1, e2, xd[l])


@njit(cache=True, inline="always")
def _rates(D, S, l, LW, s0, s1, s2, s3, s4, s5, x):
    """Lane ``l``: the unit twist ``s`` into ``S``, then ``V + s xd`` and ``Acc + (V x s) xd`` on the record
    ``D`` (E33 at q'' = 0), ``V x s = (omega x w, omega x v_s + v x w)``; always computed (the row kernel
    skips ``xd = 0``: adding ``s 0`` changes no value)."""
    S[l] = s0
    S[LW + l] = s1
    S[2 * LW + l] = s2
    S[3 * LW + l] = s3
    S[4 * LW + l] = s4
    S[5 * LW + l] = s5
    om0, om1, om2 = D[WV * LW + l], D[(WV + 1) * LW + l], D[(WV + 2) * LW + l]
    v0, v1, v2 = D[(WV + 3) * LW + l], D[(WV + 4) * LW + l], D[(WV + 5) * LW + l]
    D[AC * LW + l] = D[AC * LW + l] + (om1 * s2 - om2 * s1) * x
    D[(AC + 1) * LW + l] = D[(AC + 1) * LW + l] + (om2 * s0 - om0 * s2) * x
    D[(AC + 2) * LW + l] = D[(AC + 2) * LW + l] + (om0 * s1 - om1 * s0) * x
    D[(AC + 3) * LW + l] = D[(AC + 3) * LW + l] + (om1 * s5 - om2 * s4 + v1 * s2 - v2 * s1) * x
    D[(AC + 4) * LW + l] = D[(AC + 4) * LW + l] + (om2 * s3 - om0 * s5 + v2 * s0 - v0 * s2) * x
    D[(AC + 5) * LW + l] = D[(AC + 5) * LW + l] + (om0 * s4 - om1 * s3 + v0 * s1 - v1 * s0) * x
    D[WV * LW + l] = om0 + s0 * x
    D[(WV + 1) * LW + l] = om1 + s1 * x
    D[(WV + 2) * LW + l] = om2 + s2 * x
    D[(WV + 3) * LW + l] = v0 + s3 * x
    D[(WV + 4) * LW + l] = v1 + s4 * x
    D[(WV + 5) * LW + l] = v2 + s5 * x


@kernel
def lane_kinematics(TI, TF, WL, CL, SL, QDL, gx, gy, gz, lanes):
    """Root to leaves (E33) in every lane: pose, twist and acceleration at ``q'' = 0`` of every link
    into its record, the unit twists of every coordinate; after :func:`angles`. ``QDL`` (n, LW) the rates.
    Each link's own (m, c, J) and inertial wrench (:func:`_body`) follow its pose at once, for
    :func:`lane_dynamics`."""
    LW = len(lanes)
    L = TI[0]
    par, sp, ss, sc = small(TI[I_PARENT]), small(TI[I_SEGPTR]), small(TI[I_SEGSLOT]), small(TI[I_SEGCOORD])
    fs, wl, wc, wb = small(TI[F_SEG]), small(TI[W_LINK]), small(TI[W_COORD]), small(TI[W_BASE])
    _base(rows(WL, wb, KL, LW), gx, gy, gz, lanes)
    for p in range(L):
        s = TI[par + p]
        D = rows(WL, wl + KL * p, KL, LW)
        P = rows(WL, wb if s < 0 else wl + KL * small(s), 24, LW)
        s0 = small(TI[sp + p])
        n_seg = TI[sp + p + 1] - s0
        skip = False
        for u in range(n_seg):
            if skip:        # done with the constant before it
                skip = False
                continue
            seg = s0 + u
            slot = TI[ss + seg]
            if slot == CONSTANT:
                if u == 0 and u + 1 < n_seg and 3 <= TI[ss + seg + 1] < CONSTANT:      # constant, then rotation
                    i = small(TI[sc + seg + 1])
                    _constant_rotation(TF, fs + KS * seg, P, D, TI[ss + seg + 1] - 3, rows(CL, seg + 1, 1, LW),
                                       rows(SL, seg + 1, 1, LW), rows(QDL, i, 1, LW), rows(WL, wc + 6 * i, 6, LW),
                                       lanes)
                    skip = True
                elif u == 0:
                    _constant_from(TF, fs + KS * seg, P, D, lanes)
                else:
                    _constant(TF, fs + KS * seg, D, lanes)
                continue
            if u == 0:
                _copy(P, D, lanes)
            i = small(TI[sc + seg])
            S, xd = rows(WL, wc + 6 * i, 6, LW), rows(QDL, i, 1, LW)
            if slot < 3:
                _translation(D, slot, rows(CL, seg, 1, LW), xd, S, lanes)
            else:
                _rotation(D, slot - 3, rows(CL, seg, 1, LW), rows(SL, seg, 1, LW), xd, S, lanes)
        if TI[sp + p + 1] == s0:
            _copy(P, D, lanes)
        _body(TI, TF, p, D, lanes)      # while the record is in the cache


# -- leaves to root ---------------------------------------------------------------------------------
@kernel
def _body_wrench(TF, fl, D, lanes):
    """Link ``p``'s (m, c, J) about {0} (E28, E29) and its inertial wrench (f, n) (E35) into its record
    ``D``, every lane; ``fl`` its mass entries in ``TF`` (the same in every lane: read once)."""
    LW = len(lanes)
    fl = small(fl)
    m = TF[fl]
    mx, my, mz = TF[fl + 1], TF[fl + 2], TF[fl + 3]
    Jxx, Jyy, Jzz, Jxy, Jxz, Jyz = TF[fl + 4], TF[fl + 5], TF[fl + 6], TF[fl + 7], TF[fl + 8], TF[fl + 9]
    for l in range(LW):
        R00, R01, R02 = D[l], D[LW + l], D[2 * LW + l]
        R10, R11, R12 = D[3 * LW + l], D[4 * LW + l], D[5 * LW + l]
        R20, R21, R22 = D[6 * LW + l], D[7 * LW + l], D[8 * LW + l]
        o0, o1, o2 = D[O_ * LW + l], D[(O_ + 1) * LW + l], D[(O_ + 2) * LW + l]
        l0 = R00 * mx + R01 * my + R02 * mz
        l1 = R10 * mx + R11 * my + R12 * mz
        l2 = R20 * mx + R21 * my + R22 * mz
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
        c0, c1, c2 = l0 + m * o0, l1 + m * o1, l2 + m * o2
        Kxx = X00 * R00 + X01 * R01 + X02 * R02 + 2.0 * (u1 * o1 + u2 * o2)
        Kyy = X10 * R10 + X11 * R11 + X12 * R12 + 2.0 * (u0 * o0 + u2 * o2)
        Kzz = X20 * R20 + X21 * R21 + X22 * R22 + 2.0 * (u0 * o0 + u1 * o1)
        Kxy = X00 * R10 + X01 * R11 + X02 * R12 - (u0 * o1 + u1 * o0)
        Kxz = X00 * R20 + X01 * R21 + X02 * R22 - (u0 * o2 + u2 * o0)
        Kyz = X10 * R20 + X11 * R21 + X12 * R22 - (u1 * o2 + u2 * o1)
        D[CM * LW + l] = m
        D[CC * LW + l] = c0
        D[(CC + 1) * LW + l] = c1
        D[(CC + 2) * LW + l] = c2
        D[CJ * LW + l] = Kxx
        D[(CJ + 1) * LW + l] = Kyy
        D[(CJ + 2) * LW + l] = Kzz
        D[(CJ + 3) * LW + l] = Kxy
        D[(CJ + 4) * LW + l] = Kxz
        D[(CJ + 5) * LW + l] = Kyz
        _wrench(D, l, LW, m, c0, c1, c2, Kxx, Kyy, Kzz, Kxy, Kxz, Kyz)


@kernel
def _zero_body(D, lanes):
    """A link without mass (the same in every lane): its (m, c, J) rows zero, then its wrench."""
    LW = len(lanes)
    for j in range(10):
        for l in range(LW):
            D[(CM + j) * LW + l] = 0.0
    for l in range(LW):
        _wrench(D, l, LW, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)


@njit(cache=True, inline="always")
def _wrench(D, l, LW, m, c0, c1, c2, Jxx, Jyy, Jzz, Jxy, Jxz, Jyz):
    """The inertial wrench (f, n) (E35) of lane ``l`` of the record ``D`` from its (m, c, J)."""
    om0, om1, om2 = D[WV * LW + l], D[(WV + 1) * LW + l], D[(WV + 2) * LW + l]
    v0, v1, v2 = D[(WV + 3) * LW + l], D[(WV + 4) * LW + l], D[(WV + 5) * LW + l]
    al0, al1, al2 = D[AC * LW + l], D[(AC + 1) * LW + l], D[(AC + 2) * LW + l]
    a0, a1, a2 = D[(AC + 3) * LW + l], D[(AC + 4) * LW + l], D[(AC + 5) * LW + l]
    Jo0 = Jxx * om0 + Jxy * om1 + Jxz * om2
    Jo1 = Jxy * om0 + Jyy * om1 + Jyz * om2
    Jo2 = Jxz * om0 + Jyz * om1 + Jzz * om2
    Ja0 = Jxx * al0 + Jxy * al1 + Jxz * al2
    Ja1 = Jxy * al0 + Jyy * al1 + Jyz * al2
    Ja2 = Jxz * al0 + Jyz * al1 + Jzz * al2
    u0 = om1 * c2 - om2 * c1 + m * v0
    u1 = om2 * c0 - om0 * c2 + m * v1
    u2 = om0 * c1 - om1 * c0 + m * v2
    D[FI * LW + l] = al1 * c2 - al2 * c1 + m * a0 + om1 * u2 - om2 * u1
    D[(FI + 1) * LW + l] = al2 * c0 - al0 * c2 + m * a1 + om2 * u0 - om0 * u2
    D[(FI + 2) * LW + l] = al0 * c1 - al1 * c0 + m * a2 + om0 * u1 - om1 * u0
    x0 = om1 * v2 - om2 * v1 + a0
    x1 = om2 * v0 - om0 * v2 + a1
    x2 = om0 * v1 - om1 * v0 + a2
    D[(FI + 3) * LW + l] = Ja0 + c1 * x2 - c2 * x1 + om1 * Jo2 - om2 * Jo1
    D[(FI + 4) * LW + l] = Ja1 + c2 * x0 - c0 * x2 + om2 * Jo0 - om0 * Jo2
    D[(FI + 5) * LW + l] = Ja2 + c0 * x1 - c1 * x0 + om0 * Jo1 - om1 * Jo0


@kernel
def _accumulate(D, E, lanes):
    """(E30): a child's (m, c, J, f, n) rows (``CM`` to ``FX``) added to its parent's."""
    LW = len(lanes)
    for x in range(CM * LW, FX * LW):
        E[x] = E[x] + D[x]


@kernel
def _momenta(D, S, b, lanes):
    """A coordinate of the link whose subtree sums are in ``D``, with unit twist ``S`` (6 rows):
    ``b_i = -(v.f + w.n)`` (E34) into ``b`` (one row), and the subtree's momentum of the unit motion
    ``p_i, h_i`` (E31) into the record's six rows at ``FX`` (unused without loads), for the row of ``A``."""
    LW = len(lanes)
    for l in range(LW):
        w0, w1, w2 = S[l], S[LW + l], S[2 * LW + l]
        v0, v1, v2 = S[3 * LW + l], S[4 * LW + l], S[5 * LW + l]
        b[l] = -(v0 * D[FI * LW + l] + v1 * D[(FI + 1) * LW + l] + v2 * D[(FI + 2) * LW + l]
                 + w0 * D[(FI + 3) * LW + l] + w1 * D[(FI + 4) * LW + l] + w2 * D[(FI + 5) * LW + l])
        m = D[CM * LW + l]
        c0, c1, c2 = D[CC * LW + l], D[(CC + 1) * LW + l], D[(CC + 2) * LW + l]
        Jxx, Jyy, Jzz = D[CJ * LW + l], D[(CJ + 1) * LW + l], D[(CJ + 2) * LW + l]
        Jxy, Jxz, Jyz = D[(CJ + 3) * LW + l], D[(CJ + 4) * LW + l], D[(CJ + 5) * LW + l]
        D[FX * LW + l] = w1 * c2 - w2 * c1 + m * v0
        D[(FX + 1) * LW + l] = w2 * c0 - w0 * c2 + m * v1
        D[(FX + 2) * LW + l] = w0 * c1 - w1 * c0 + m * v2
        D[(FX + 3) * LW + l] = Jxx * w0 + Jxy * w1 + Jxz * w2 + c1 * v2 - c2 * v1
        D[(FX + 4) * LW + l] = Jxy * w0 + Jyy * w1 + Jyz * w2 + c2 * v0 - c0 * v2
        D[(FX + 5) * LW + l] = Jxz * w0 + Jyz * w1 + Jzz * w2 + c0 * v1 - c1 * v0


@kernel
def _mass_entry(D, S, a, lanes):
    """An entry of ``A`` into ``a`` (one row): ``a_il = v_l.p_i + w_l.h_i`` (E31), ``s_l`` in ``S``,
    ``p_i, h_i`` in the record ``D``'s rows at ``FX``."""
    LW = len(lanes)
    for l in range(LW):
        a[l] = (S[3 * LW + l] * D[FX * LW + l] + S[4 * LW + l] * D[(FX + 1) * LW + l]
                + S[5 * LW + l] * D[(FX + 2) * LW + l] + S[l] * D[(FX + 3) * LW + l]
                + S[LW + l] * D[(FX + 4) * LW + l] + S[2 * LW + l] * D[(FX + 5) * LW + l])


@kernel
def _mass_row(D, S, a, m, lanes):
    """``m`` entries of a row of ``A`` whose coordinates are consecutive (one run): ``S`` their unit twists
    (6 m rows), ``a`` the row's ``m`` slots: :func:`_mass_entry` for each, in one call."""
    LW = len(lanes)
    for u in range(m):
        e = 6 * u * LW
        for l in range(LW):
            a[u * LW + l] = (S[e + 3 * LW + l] * D[FX * LW + l] + S[e + 4 * LW + l] * D[(FX + 1) * LW + l]
                             + S[e + 5 * LW + l] * D[(FX + 2) * LW + l] + S[e + l] * D[(FX + 3) * LW + l]
                             + S[e + LW + l] * D[(FX + 4) * LW + l] + S[e + 2 * LW + l] * D[(FX + 5) * LW + l])


@kernel
def _body(TI, TF, p, D, lanes):
    """Link ``p``'s (m, c, J) about {0} and inertial wrench into its record ``D`` (:func:`_body_wrench`), or zeros
    and the wrench of nothing for a link without mass: the row kernel's skip, on the tree's constants (the same
    in every lane)."""
    f = small(TI[F_LINK]) + KF * small(p)
    massless = True
    for j in range(10):
        if TF[f + j] != 0.0:
            massless = False
    if massless:
        _zero_body(D, lanes)
    else:
        _body_wrench(TF, f, D, lanes)


@kernel
def _coordinate(TI, WL, i, D, lanes):
    """Coordinate ``i`` of the link whose subtree sums are in ``D``: ``b_i`` (E34) and row ``i`` of ``A`` (E31)."""
    LW = len(lanes)
    i = small(i)
    wc, ap, ai = small(TI[W_COORD]), small(TI[I_ANCPTR]), small(TI[I_ANCIDX])
    wa, wbv, rp, rs = small(TI[W_A]), small(TI[W_B]), small(TI[I_RUNPTR]), small(TI[I_RUNS])
    _momenta(D, rows(WL, wc + 6 * i, 6, LW), rows(WL, wbv + i, 1, LW), lanes)
    j0 = small(TI[ap + i])
    m = small(TI[ap + i + 1] - j0)
    if TI[rp + i + 1] - TI[rp + i] == 1:       # the row is one run of coordinates c0, c0 + 1, ...
        c0 = small(TI[rs + 2 * small(TI[rp + i])])
        _mass_row(D, rows(WL, wc + 6 * c0, 6 * m, LW), rows(WL, wa + j0, m, LW), m, lanes)
        return
    for u in range(m):
        _mass_entry(D, rows(WL, wc + 6 * small(TI[ai + j0 + u]), 6, LW), rows(WL, wa + j0 + u, 1, LW), lanes)


@kernel
def lane_dynamics(TI, WL, lanes):
    """Leaves to root after :func:`lane_kinematics` (which leaves every link's own (m, c, J) and inertial wrench in
    its record), every lane: the subtree sums (E30), ``b = -(e + G)`` (E34) at ``W_B`` and the packed mass matrix
    (E31) at ``W_A``, as :func:`~urdf2links.dynamics.kernels.dynamics` (no loads, no armature). A link's
    coordinates are done as soon as its subtree is summed (its children have larger indices), while its record
    is in the cache."""
    LW = len(lanes)
    L, n = TI[0], TI[1]
    wl, par, cl = small(TI[W_LINK]), small(TI[I_PARENT]), small(TI[I_COORDLINK])
    for p in range(L - 1, -1, -1):
        D = rows(WL, wl + KL * p, KL, LW)
        for i in range(n):
            if TI[cl + i] == p:
                _coordinate(TI, WL, i, D, lanes)
        s = TI[par + p]
        if p > 0 and s >= 0:
            _accumulate(D, rows(WL, wl + KL * small(s), KL, LW), lanes)

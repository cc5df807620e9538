"""The constrained right-hand side compiled (issue 45): fixed tendons (E76), constraint terms (E71), the KKT
block elimination (E72) with a pivoted Schur factorisation (E88), and the pieces the projection (E74) reuses.

Called from :func:`urdf2links.scenes.scene_kernels._rhs` behind its ``constraints`` marker, after the free
solve: ``out[n:2n]`` holds ``q''_free = A^-1 f`` and the tree's scratch ``W`` the kinematics pass of the
evaluation (poses, twists, accelerations at ``q'' = 0`` with ``-g`` in them, unit twists) and ``A``'s
factorisation (``L^T D L`` of the tree, or the dense Cholesky of ``C^T A C`` in ``X`` for coupled
coordinates). Nothing is computed twice:

- :func:`tendon_forces`: ``c (-k stretch - b l' + sum gear F)`` (E76), its ``q''`` by one more solve with A's
  factor, and its power;
- :func:`constraint_terms`: ``Phi``, ``Phi_q``, ``gamma`` (E68)-(E71) from the pass already in ``W`` (the
  linear accelerations carry ``-g``: a point's ``a_0`` gets ``+g`` back, E32);
- :func:`kkt`: ``Z = L^-T J^T`` (one half solve per row with A's factor ``L^T D L``, from the leaves: a
  sparse row costs its coordinates' ancestors only), ``S = J A^-1 J^T = Z^T D^-1 Z``, factorised by a
  Cholesky with diagonal pivoting (E88); ``lambda = S^-1 (-gamma - J q''_free)``, ``q'' = q''_free + A^-1
  (J^T lambda)`` (one full solve) (E72). The rows solved are the ones chosen (the start's ``keep``, E73); where
  their smallest pivot falls below :data:`ROW_CHOICE` (on a floating base a planar loop's plane turns with the
  base, and the world-axis row left out at the start stops being the redundant one) they are chosen again among
  all ``m`` rows by the pivoted factor of the whole ``S``, as many as at the start, and kept for the following
  evaluations and the projection (:func:`_choose_rows`: no event). A change point is a rank over all rows below
  the start's (a pivot at or below :data:`SCHUR_PIVOT`): the rows left are dropped there (``[constraints]
  change_point = "continue"``; an event (t, row, pivot) is recorded when a row starts being dropped) or the
  evaluation fails with the row (``"stop"``: the run then raises the named DynamicsError);
- :func:`schur_correction`: ``A^-1 J^T S^-1 v`` for rows' values ``v`` (the projection's Gauss-Newton step and its
  velocity step, E74).

The block's arrays: :mod:`urdf2links.scenes.constraint_arrays`.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..compilation import kernel, one_signature
from ..dynamics.factor import cholesky_solve, ltdl_solve
from ..dynamics.tree_arrays import AC, I_ANCIDX, I_ANCPTR, I_RUNPTR, I_RUNS, KL, O_, W_A, W_COORD, W_LINK, WV, nonneg
from .constraint_arrays import (CACT, CF, CKEEP, CM, CMODE, CNA, CNC, CNT, CREC, CX, KCF, KCI, KEV,
                                KIND_POLY, KIND_WELD, x_layout)
from .scene_arrays import KA, S_C, S_CON, S_GRAV
from .scene_inputs import fn_eval

__all__ = ["SCHUR_PIVOT", "FAIL_BASE", "tendon_forces", "constraint_terms", "kkt", "schur_correction", "a_solve"]

SCHUR_PIVOT = 1e-12     # a pivot of S at or below this fraction of its largest diagonal: the row is dependent there
CHANGE_POINT_PIVOT = 1e-12  # the same with change_point = "continue": the row is dropped there
ROW_CHOICE = 1e-6       # the rows solved have a pivot below this fraction of S's largest diagonal: choose again
FAIL_BASE = 1 << 40     # the right-hand side's return value for a constraint row that stops the run: + row


@one_signature
@kernel
def a_solve(tree, scene, v, at, coupled):
    """``v[at:at + n] <- A^-1 v[at:at + n]`` with the factor of A left by the evaluation."""
    SI, X = scene.SI, scene.X
    n, nt = nonneg(SI[0]), nonneg(SI[1])
    if coupled:
        cholesky_solve(X, 2 * nt + 18 + n * n, n, v, at)
    else:
        ltdl_solve(tree.TI, tree.W, v, at)


@one_signature
@kernel
def half_solve(tree, scene, v, at, coupled):
    """``v[at:at + n] <- Z = L^-T v`` with the factor of A left by the evaluation (the tree's ``A = L^T D L``: from
    the leaves, a zero entry skipped, so a sparse row costs its ancestors only; coupled coordinates'
    ``A = L L^T``: forward), so that ``J A^-1 J^T = Z^T W Z`` with :func:`weights` ``W`` (E88)."""
    SI, X = scene.SI, scene.X
    n, nt = nonneg(SI[0]), nonneg(SI[1])
    at = nonneg(at)
    if coupled:
        l0 = 2 * nt + 18 + n * n
        for i in range(n):
            s = v[at + i]
            for k in range(i):
                s -= X[l0 + i * n + k] * v[at + k]
            v[at + i] = s / X[l0 + i * n + i]
        return
    TI, W = tree.TI, tree.W
    ap, ai, rp, rs = nonneg(TI[I_ANCPTR]), nonneg(TI[I_ANCIDX]), nonneg(TI[I_RUNPTR]), nonneg(TI[I_RUNS])
    wa = nonneg(TI[W_A])
    for kk in range(n):                     # L^T z = x: from the leaves (factor.ltdl_solve's first half)
        k = nonneg(n - 1 - kk)
        r0 = nonneg(TI[ap + k])
        m = nonneg(TI[ap + k + 1] - 1 - r0)
        j = wa + r0
        xk = v[at + k]
        if xk == 0.0:
            continue
        if TI[rp + k + 1] - TI[rp + k] == 1:
            c0 = at + nonneg(TI[rs + 2 * nonneg(TI[rp + k])])
            for u in range(m):
                v[c0 + u] -= W[j + u] * xk
        else:
            for u in range(m):
                v[at + nonneg(TI[ai + r0 + u])] -= W[j + u] * xk


@njit(cache=True, inline="always")     # inlined into kkt, its one caller (a call passes every array as seven words)
def _half_solves(tree, scene, X, xy, xperm, r, coupled):
    """:func:`half_solve` of the rows ``X[xy + k n:xy + (k + 1) n]`` for ``k`` in ``X[xperm:xperm + r]``, in one pass
    over the tree (its structure read once for all rows)."""
    n = nonneg(scene.SI[0])
    xy, xperm = nonneg(xy), nonneg(xperm)
    if coupled:
        for a in range(r):
            half_solve(tree, scene, X, xy + nonneg(int(X[xperm + a])) * n, coupled)
        return
    TI, W = tree.TI, tree.W
    ap, ai, rp, rs = nonneg(TI[I_ANCPTR]), nonneg(TI[I_ANCIDX]), nonneg(TI[I_RUNPTR]), nonneg(TI[I_RUNS])
    wa = nonneg(TI[W_A])
    for kk in range(n):                     # L^T z = x: from the leaves (factor.ltdl_solve's first half)
        k = nonneg(n - 1 - kk)
        r0 = nonneg(TI[ap + k])
        m = nonneg(TI[ap + k + 1] - 1 - r0)
        j = wa + r0
        run = TI[rp + k + 1] - TI[rp + k] == 1
        c0 = nonneg(TI[rs + 2 * nonneg(TI[rp + k])]) if run else 0
        for a in range(r):
            at = xy + nonneg(int(X[xperm + a])) * n
            xk = X[at + k]
            if xk == 0.0:
                continue
            if run:
                for u in range(m):
                    X[at + c0 + u] -= W[j + u] * xk
            else:
                for u in range(m):
                    X[at + nonneg(TI[ai + r0 + u])] -= W[j + u] * xk


@njit(cache=True, inline="always")     # inlined into kkt, its one caller (a call passes every array as seven words)
def back_solve(tree, scene, v, at, coupled):
    """``v[at:at + n] <- L^-1 v`` for the tree's ``A = L^T D L`` (from the root), ``L^-T v`` for coupled
    coordinates' ``A = L L^T``: the other half of :func:`half_solve`, so that ``A^-1 J^T lambda = L^-1 W Z lambda``
    (E88) reuses ``Z``."""
    SI, X = scene.SI, scene.X
    n, nt = nonneg(SI[0]), nonneg(SI[1])
    at = nonneg(at)
    if coupled:
        l0 = 2 * nt + 18 + n * n
        for ii in range(n):
            i = n - 1 - ii
            s = v[at + i]
            for k in range(i + 1, n):
                s -= X[l0 + k * n + i] * v[at + k]
            v[at + i] = s / X[l0 + i * n + i]
        return
    TI, W = tree.TI, tree.W
    ap, ai, rp, rs = nonneg(TI[I_ANCPTR]), nonneg(TI[I_ANCIDX]), nonneg(TI[I_RUNPTR]), nonneg(TI[I_RUNS])
    wa = nonneg(TI[W_A])
    for k in range(n):                      # L y = z: from the root (factor.ltdl_solve's second half, D apart)
        r0 = nonneg(TI[ap + k])
        m = nonneg(TI[ap + k + 1] - 1 - r0)
        j = wa + r0
        s = v[at + k]
        if TI[rp + k + 1] - TI[rp + k] == 1:
            c0 = at + nonneg(TI[rs + 2 * nonneg(TI[rp + k])])
            for u in range(m):
                s -= W[j + u] * v[c0 + u]
        else:
            for u in range(m):
                s -= W[j + u] * v[at + nonneg(TI[ai + r0 + u])]
        v[at + k] = s


@njit(cache=True, inline="always")     # inlined into kkt, its one caller (a call passes every array as seven words)
def weights(tree, scene, w, w_at, coupled):
    """``w[w_at:w_at + n]``: ``1 / D`` of the tree's ``A = L^T D L`` (ones for the coupled ``L L^T``), the weights of
    :func:`half_solve`'s ``Z^T W Z``."""
    n = scene.SI[0]
    if coupled:
        for i in range(n):
            w[w_at + i] = 1.0
        return
    TI, W = tree.TI, tree.W
    ap, wa = nonneg(TI[I_ANCPTR]), nonneg(TI[W_A])
    for k in range(n):
        w[w_at + k] = 1.0 / W[wa + nonneg(TI[ap + k + 1] - 1)]


@one_signature
@kernel
def tendon_forces(tree, scene, t, y, out, coupled):
    """The fixed tendons' generalized forces (E76) solved into ``out[n:2n]`` (``+= A^-1 c f_t``); returns their
    power ``l' (-b l' + sum gear F)`` (the spring is a potential)."""
    SI, SF, X = scene
    n = SI[0]
    c0 = nonneg(SI[S_CON])
    ntd, na = nonneg(SI[c0 + CNT]), nonneg(SI[c0 + CNA])
    if ntd == 0:
        return 0.0
    m = nonneg(SI[c0 + CM])
    xt = nonneg(SI[c0 + CX] + x_layout(m, n, SI[1])[10])
    ft = nonneg(SI[c0 + CF] + SI[c0 + CNC] * (KCF + 2 * n))
    fa = ft + ntd * (n + 4)
    for i in range(n):
        X[xt + i] = 0.0
    P = 0.0
    for k in range(ntd):
        a = ft + k * (n + 4)
        l = 0.0
        ld = 0.0
        for i in range(n):
            l += SF[a + i] * y[i]
            ld += SF[a + i] * y[n + i]
        la, lb = SF[a + n + 2], SF[a + n + 3]
        x = l - lb if l > lb else (l - la if l < la else 0.0)
        work = -SF[a + n + 1] * ld
        for j in range(na):
            r = nonneg(c0 + SI[c0 + CACT] + 3 * j)
            if SI[r] != k:
                continue
            p = fa + KA * j
            c = fn_eval(SI, SF, SI[r + 1], t, 0)
            if SI[r + 2] & 1:
                c = min(max(c, SF[p + 5]), SF[p + 6])
            gear = SF[p + 4]
            F = SF[p] * c + (SF[p + 1] + SF[p + 2] * (l * gear) + SF[p + 3] * (ld * gear))
            if SI[r + 2] & 2:
                F = min(max(F, SF[p + 7]), SF[p + 8])
            work += gear * F
        ftot = -SF[a + n] * x + work
        P += work * ld
        for i in range(n):
            X[xt + i] += SF[a + i] * ftot
    a_solve(tree, scene, X, xt, coupled)
    for i in range(n):
        out[n + i] += X[xt + i]
    return P


@njit(cache=True, inline="always")
def _point(TI, W, SF, fp, p, side, gx, gy, gz):
    """The world point ``r`` of one side (``side`` 0, 1) of a connect/weld and its acceleration at ``q'' = 0``
    (E32, gravity taken out): ``(r0, r1, r2, a0, a1, a2)``, in registers."""
    pt = nonneg(fp + 3 * side)
    if p < 0:
        return SF[pt], SF[pt + 1], SF[pt + 2], 0.0, 0.0, 0.0
    d = nonneg(TI[W_LINK]) + KL * nonneg(p)
    p0, p1, p2 = SF[pt], SF[pt + 1], SF[pt + 2]
    r0 = W[d + O_] + W[d] * p0 + W[d + 1] * p1 + W[d + 2] * p2
    r1 = W[d + O_ + 1] + W[d + 3] * p0 + W[d + 4] * p1 + W[d + 5] * p2
    r2 = W[d + O_ + 2] + W[d + 6] * p0 + W[d + 7] * p1 + W[d + 8] * p2
    om0, om1, om2 = W[d + WV], W[d + WV + 1], W[d + WV + 2]
    al0, al1, al2 = W[d + AC], W[d + AC + 1], W[d + AC + 2]
    v0 = om1 * r2 - om2 * r1 + W[d + WV + 3]
    v1 = om2 * r0 - om0 * r2 + W[d + WV + 4]
    v2 = om0 * r1 - om1 * r0 + W[d + WV + 5]
    a0 = al1 * r2 - al2 * r1 + W[d + AC + 3] + gx + om1 * v2 - om2 * v1
    a1 = al2 * r0 - al0 * r2 + W[d + AC + 4] + gy + om2 * v0 - om0 * v2
    a2 = al0 * r1 - al1 * r0 + W[d + AC + 5] + gz + om0 * v1 - om1 * v0
    return r0, r1, r2, a0, a1, a2


@njit(cache=True, inline="always")
def _point_columns(TI, W, SI, rec, side, nt, r0, r1, r2, X, t0):
    """The Jacobian rows ``+-u_i(r)`` of the point ``r`` of one side, over the tree coordinates that move its link
    (the record's mask), added to the three rows of ``nt`` at ``X[t0:]``."""
    sign = 1.0 if side == 0 else -1.0
    wc, t0 = nonneg(TI[W_COORD]), nonneg(t0)
    mk = nonneg(rec + KCI + side * nt)
    for i in range(nt):
        if SI[mk + i] == 0:
            continue
        w0, w1, w2 = W[wc + i], W[wc + nt + i], W[wc + 2 * nt + i]
        X[t0 + i] += sign * (w1 * r2 - w2 * r1 + W[wc + 3 * nt + i])
        X[t0 + nt + i] += sign * (w2 * r0 - w0 * r2 + W[wc + 4 * nt + i])
        X[t0 + 2 * nt + i] += sign * (w0 * r1 - w1 * r0 + W[wc + 5 * nt + i])


@njit(cache=True, inline="always")
def _frame(W, SF, wl, l, f, r, c):
    """``(R_l F)[r, c]``: a welded frame's rotation in world axes (the world's R the identity)."""
    if l < 0:
        return SF[f + 3 * r + c]
    a = wl + KL * l + 3 * r
    return W[a] * SF[f + c] + W[a + 1] * SF[f + 3 + c] + W[a + 2] * SF[f + 6 + c]


@njit(cache=True, inline="always")
def _re(W, SF, wl, l1, l2, f1, f2, a, b):
    """``R_e[a, b]`` of ``R_e = (R_1 F_1) (R_2 F_2)^T`` (E69)."""
    s = 0.0
    for c in range(3):
        s += _frame(W, SF, wl, l1, f1, a, c) * _frame(W, SF, wl, l2, f2, b, c)
    return s


@one_signature
@kernel
def _weld_rows(TI, W, SI, SF, rec, fp, l1, l2, X, xphi, xgam, k, t0, nt):
    """A weld's orientation rows ``k .. k + 2`` (E69): ``Phi_R = 0.5 vee(R_e - R_e^T)``, Jacobian rows ``w_i``
    of link1's coordinates minus link2's (into the three rows of ``nt`` at ``X[t0:]``), ``gamma = alpha_1 - alpha_2``."""
    wl, wc, t0 = nonneg(TI[W_LINK]), nonneg(TI[W_COORD]), nonneg(t0)
    f1, f2 = fp + 6, fp + 15
    X[xphi + k] = 0.5 * (_re(W, SF, wl, l1, l2, f1, f2, 2, 1) - _re(W, SF, wl, l1, l2, f1, f2, 1, 2))
    X[xphi + k + 1] = 0.5 * (_re(W, SF, wl, l1, l2, f1, f2, 0, 2) - _re(W, SF, wl, l1, l2, f1, f2, 2, 0))
    X[xphi + k + 2] = 0.5 * (_re(W, SF, wl, l1, l2, f1, f2, 1, 0) - _re(W, SF, wl, l1, l2, f1, f2, 0, 1))
    for j in range(3):
        g = 0.0
        if l1 >= 0:
            g += W[wl + KL * l1 + AC + j]
        if l2 >= 0:
            g -= W[wl + KL * l2 + AC + j]
        X[xgam + k + j] = g
    for side in range(2):
        mk = rec + KCI + side * nt
        sign = 1.0 if side == 0 else -1.0
        for i in range(nt):
            if SI[mk + i] != 0:
                for j in range(3):
                    X[t0 + j * nt + i] += sign * W[wc + j * nt + i]


@njit(cache=True, inline="always")     # inlined into kkt, its one caller (a call passes every array as seven words)
def _poly_row(SI, SF, y, n, rec, fp, X, xphi, xgam, xj, k):
    """A polynomial row (E70): ``Phi = l_a - l_a0 - p(l_b - l_b0)``, its row ``u_a - p'(x) u_b`` (model
    coordinates), ``gamma = -p''(x) l_b'^2``; ``l = u . q`` a coordinate or a fixed tendon's length."""
    u1, u2 = fp + KCF, fp + KCF + n
    la = 0.0
    x = 0.0
    xd = 0.0
    for i in range(n):
        la += SF[u1 + i] * y[i]
        x += SF[u2 + i] * y[i]
        xd += SF[u2 + i] * y[n + i]
    a = fp + 24
    a0, a1, a2, a3, a4 = SF[a], SF[a + 1], SF[a + 2], SF[a + 3], SF[a + 4]
    if SI[rec + 4] == 0:
        X[xphi + k] = la - SF[fp + 29] - a0
        X[xgam + k] = 0.0
        for i in range(n):
            X[xj + k * n + i] = SF[u1 + i]
        return
    x -= SF[fp + 30]
    p = a0 + x * (a1 + x * (a2 + x * (a3 + x * a4)))
    dp = a1 + x * (2.0 * a2 + x * (3.0 * a3 + x * 4.0 * a4))
    ddp = 2.0 * a2 + x * (6.0 * a3 + x * 12.0 * a4)
    X[xphi + k] = la - SF[fp + 29] - p
    X[xgam + k] = -ddp * xd * xd
    for i in range(n):
        X[xj + k * n + i] = SF[u1 + i] - dp * SF[u2 + i]


@njit(cache=True, inline="always")     # inlined into kkt, its one caller (a call passes every array as seven words)
def constraint_terms(tree, scene, y):
    """``Phi``, ``gamma`` (m,) and ``J = Phi_q`` (m, n) into the constraints' scratch (E68)-(E71), from the
    kinematics pass already in the tree's scratch; connect/weld rows in the tree's coordinates times ``C``
    for coupled ones (E42)."""
    TI, W = tree.TI, tree.W
    SI, SF, X = scene
    n, nt = nonneg(SI[0]), nonneg(SI[1])
    c0 = nonneg(SI[S_CON])
    m = nonneg(SI[c0 + CM])
    xc = nonneg(SI[c0 + CX])
    lay = x_layout(m, n, nt)
    xphi, xgam, xj, xt = xc + lay[0], xc + lay[1], xc + lay[2], xc + lay[10]
    g = SI[S_GRAV]
    gx, gy, gz = SF[g], SF[g + 1], SF[g + 2]
    coupled = SI[4] != 0
    Cat = SI[S_C]
    jt = xc + lay[14]      # one point pair's rows (3, nt) in the tree's coordinates, for coupled ones
    rec0 = nonneg(c0 + SI[c0 + CREC])
    for ci in range(SI[c0 + CNC]):
        rec = rec0 + ci * (KCI + 2 * nt)
        fp = nonneg(SI[c0 + CF] + ci * (KCF + 2 * n))
        kind, l1, l2, k = SI[rec], SI[rec + 1], SI[rec + 2], nonneg(SI[rec + 3])
        if kind == KIND_POLY:
            _poly_row(SI, SF, y, n, rec, fp, X, xphi, xgam, xj, k)
            continue
        for blk in range(2 if kind == KIND_WELD else 1):
            kr = k + 3 * blk
            # the rows themselves (tree coordinates are the model's), else one block times C (E42)
            t0 = jt if coupled else xj + kr * n
            for j in range(3):
                for i in range(nt):
                    X[t0 + j * nt + i] = 0.0
            if blk == 0:
                ra0, ra1, ra2, aa0, aa1, aa2 = _point(TI, W, SF, fp, l1, 0, gx, gy, gz)
                rb0, rb1, rb2, ab0, ab1, ab2 = _point(TI, W, SF, fp, l2, 1, gx, gy, gz)
                if l1 >= 0:
                    _point_columns(TI, W, SI, rec, 0, nt, ra0, ra1, ra2, X, t0)
                if l2 >= 0:
                    _point_columns(TI, W, SI, rec, 1, nt, rb0, rb1, rb2, X, t0)
                X[xphi + k], X[xphi + k + 1], X[xphi + k + 2] = ra0 - rb0, ra1 - rb1, ra2 - rb2
                X[xgam + k], X[xgam + k + 1], X[xgam + k + 2] = aa0 - ab0, aa1 - ab1, aa2 - ab2
            else:
                _weld_rows(TI, W, SI, SF, rec, fp, l1, l2, X, xphi, xgam, kr, t0, nt)
            if coupled:
                for j in range(3):
                    row = xj + (kr + j) * n
                    for i in range(n):
                        s = 0.0
                        for a in range(nt):
                            s += X[jt + j * nt + a] * SF[Cat + a * n + i]
                        X[row + i] = s


@one_signature
@kernel
def _pivoted_cholesky(X, xl, xd, xperm, r, m, tol, limit):
    """``P D S D P^T = L P_d L^T`` in place (r, r) with row stride ``m`` at ``X[xl:]`` (E88): the largest diagonal
    left first; stops at a pivot at or below ``tol`` or after ``limit`` rows. ``L`` unit lower triangular below the
    diagonal, the reciprocal pivots ``1 / p_j`` on it, the upper triangle the columns before scaling: no square
    root and no division on the solves' chains (:func:`schur_solve`). Swaps the order ``X[xperm:]`` and the scales
    ``X[xd:]`` with the rows. Returns ``(rank, smallest pivot of the rows factored, the pivot where it stopped)``
    (the smallest when it did not stop)."""
    xl, xd, xperm, m = nonneg(xl), nonneg(xd), nonneg(xperm), nonneg(m)
    smallest = np.inf
    for j in range(min(r, limit)):
        p = j
        for i in range(j + 1, r):
            if X[xl + i * m + i] > X[xl + p * m + p]:
                p = i
        if p != j:
            for c in range(r):
                a, b = xl + j * m + c, xl + p * m + c
                X[a], X[b] = X[b], X[a]
            for c in range(r):
                a, b = xl + c * m + j, xl + c * m + p
                X[a], X[b] = X[b], X[a]
            X[xperm + j], X[xperm + p] = X[xperm + p], X[xperm + j]
            X[xd + j], X[xd + p] = X[xd + p], X[xd + j]
        piv = X[xl + j * m + j]
        if not piv > tol:
            return j, smallest, piv
        smallest = min(smallest, piv)
        inv = 1.0 / piv
        X[xl + j * m + j] = inv
        for i in range(j + 1, r):           # l_ij = s_ij / p_j below; s_ji (unscaled) stays above
            X[xl + i * m + j] = X[xl + j * m + i] * inv
        for i in range(j + 1, r):
            lij = X[xl + i * m + j]
            for k in range(j + 1, i + 1):
                v = X[xl + i * m + k] - lij * X[xl + j * m + k]
                X[xl + i * m + k] = v
                X[xl + k * m + i] = v
    return min(r, limit), smallest, smallest


@njit(cache=True, inline="always")     # inlined into kkt, its one caller (a call passes every array as seven words)
def _events(X, m, xact, xprev, xst, xev, xsel, t, piv):
    """A row chosen and solved at the accepted step before and dropped at this one (the rows over all ``m`` of
    lower rank than at the start: a change point): an event ``(t, row, pivot)`` (the first :data:`KEV` kept, all
    counted). Only the evaluations of the projection after an accepted step count (``X[xst + 6]`` set): trial
    stages near a change point would flicker."""
    if X[xst + 6] == 0.0:
        return
    for k in range(m):
        dropped = 1.0 if (X[xsel + k] != 0.0 and X[xact + k] == 0.0) else 0.0
        if dropped != 0.0 and X[xprev + k] == 0.0:
            e = nonneg(int(X[xst + 2]))
            if e < KEV:
                X[xev + 3 * e] = t
                X[xev + 3 * e + 1] = k
                X[xev + 3 * e + 2] = piv
            X[xst + 2] = e + 1
        X[xprev + k] = dropped


@one_signature
@kernel
def _schur(X, xy, xw, xl, xs, xperm, r, m, n):
    """``S = Z^T W Z`` (r, r) over the rows ``X[xperm:xperm + r]`` (their ``Z`` rows at ``X[xy:]``, the weights at
    ``X[xw:]``), its scales set to 1; returns its largest diagonal (E88)."""
    big = 0.0      # the pivots compare with S's largest diagonal (a row whose J vanishes is dependent too)
    for a in range(r):
        ka = nonneg(int(X[xperm + a]))
        for b in range(a + 1):
            kb = nonneg(int(X[xperm + b]))
            s = 0.0
            for i in range(n):
                s += X[xy + ka * n + i] * X[xw + i] * X[xy + kb * n + i]
            X[xl + a * m + b] = s
            X[xl + b * m + a] = s
        X[xs + a] = 1.0
        big = max(big, X[xl + a * m + a])
    return big


@one_signature
@kernel
def _choose_rows(tree, scene, coupled, tol_rel):
    """The rows chosen again among all ``m`` (E73 at the current state): ``Z`` of the rows not chosen before,
    ``S`` over every row, its pivoted factor (E88) for as many rows as chosen at the start (``keep``); the new
    choice: the rows factored, then (where the rows have lower rank here than at the start: a change point) the
    ones left with the largest diagonals, dropped at this evaluation. Kept for the following evaluations
    (``sel``). Returns ``(rank, smallest pivot, the pivot where it stopped, S's largest diagonal)``."""
    SI, X = scene.SI, scene.X
    n, nt = nonneg(SI[0]), nonneg(SI[1])
    c0 = nonneg(SI[S_CON])
    m = nonneg(SI[c0 + CM])
    xc = nonneg(SI[c0 + CX])
    lay = x_layout(m, n, nt)
    xj, xy, xs, xl, xperm, xsel = xc + lay[2], xc + lay[3], xc + lay[4], xc + lay[5], xc + lay[13], xc + lay[15]
    keep = nonneg(c0 + SI[c0 + CKEEP])
    r0 = 0
    for k in range(m):
        r0 += SI[keep + k]
        X[xperm + k] = k
        if X[xsel + k] == 0.0:
            for i in range(n):
                X[xy + k * n + i] = X[xj + k * n + i]
            half_solve(tree, scene, X, xy + k * n, coupled)
    big = _schur(X, xy, xc + lay[10], xl, xs, xperm, m, m, n)
    rank, smallest, piv = _pivoted_cholesky(X, xl, xs, xperm, m, m, tol_rel * big, r0)
    for f in range(rank + 1, r0):       # rows to keep trying past a change point: the largest diagonals left
        p = f
        for i in range(f + 1, m):
            if X[xl + i * m + i] > X[xl + p * m + p]:
                p = i
        X[xperm + f], X[xperm + p] = X[xperm + p], X[xperm + f]
        X[xl + f * m + f], X[xl + p * m + p] = X[xl + p * m + p], X[xl + f * m + f]
    changed = False
    for a in range(m):
        flag = 1.0 if a < r0 else 0.0
        k = nonneg(int(X[xperm + a]))
        changed = changed or X[xsel + k] != flag
        X[xsel + k] = flag
    if changed:
        X[xc + lay[11] + 7] += 1.0
    return rank, smallest, piv, big


@one_signature
@kernel
def kkt(tree, scene, t, y, out, coupled):
    """``q''`` of (E72) in place of ``q''_free`` in ``out[n:2n]`` and ``lambda`` into the scratch; returns -1,
    or ``FAIL_BASE + row`` where the rows over all ``m`` have lower rank than at the start (a pivot at or below
    :data:`SCHUR_PIVOT`: a change point) and the scene stops there (module doc). The rows solved are the ones
    chosen (``sel``); where their smallest pivot falls below :data:`ROW_CHOICE` (a planar loop's plane turned
    with a floating base: the row left out at the start is no longer the redundant one) they are chosen again
    among all rows (:func:`_choose_rows`), which is no event unless the rank over all rows fell."""
    SI, SF, X = scene
    n, nt = nonneg(SI[0]), nonneg(SI[1])
    c0 = nonneg(SI[S_CON])
    m = nonneg(SI[c0 + CM])
    if m == 0:
        return -1
    xc = nonneg(SI[c0 + CX])
    lay = x_layout(m, n, nt)
    xj, xy, xs, xl, xlam = xc + lay[2], xc + lay[3], xc + lay[4], xc + lay[5], xc + lay[6]
    xgam, xact, xprev, xst, xev, xperm = xc + lay[1], xc + lay[8], xc + lay[9], xc + lay[11], xc + lay[12], xc + lay[13]
    xtmp, xsel = xc + lay[10], xc + lay[15]
    constraint_terms(tree, scene, y)
    weights(tree, scene, X, xtmp, coupled)
    r = 0
    for k in range(m):
        X[xact + k] = 0.0
        X[xlam + k] = 0.0
        if X[xsel + k] == 0.0:
            continue
        X[xperm + r] = k
        r += 1
        for i in range(n):
            X[xy + k * n + i] = X[xj + k * n + i]
    _half_solves(tree, scene, X, xy, xperm, r, coupled)     # Z = L^-T J^T
    big = _schur(X, xy, xtmp, xl, xs, xperm, r, m, n)
    tol_rel = SCHUR_PIVOT if SI[c0 + CMODE] == 1 else CHANGE_POINT_PIVOT
    rank, smallest, piv = _pivoted_cholesky(X, xl, xs, xperm, r, m, tol_rel * big, r)
    if rank < r or not smallest > ROW_CHOICE * big:
        rank, smallest, piv, big = _choose_rows(tree, scene, coupled, tol_rel)
    if big > 0.0:
        smallest /= big
        piv /= big
    if smallest < X[xst]:
        X[xst] = smallest
        X[xst + 1] = t
    r0 = 0
    for k in range(m):
        r0 += nonneg(int(X[xsel + k]))
    if rank < r0 and SI[c0 + CMODE] == 1:
        X[xst + 3] = X[xperm + rank]
        return FAIL_BASE + int(X[xperm + rank])
    for a in range(rank):
        X[xact + nonneg(int(X[xperm + a]))] = 1.0
    _events(X, m, xact, xprev, xst, xev, xsel, t, piv)
    for a in range(rank):           # the Schur right-hand side -gamma - J q''_free, scaled
        k = nonneg(int(X[xperm + a]))
        s = -X[xgam + k]
        for i in range(n):
            s -= X[xj + k * n + i] * out[n + i]
        X[xlam + k] = s
    schur_solve(X, xc, m, n, nt, rank)
    for i in range(n):              # q'' = q''_free + A^-1 J^T lambda = q''_free + L^-1 W Z lambda (E88)
        s = 0.0
        for a in range(rank):
            k = nonneg(int(X[xperm + a]))
            s += X[xy + k * n + i] * X[xlam + k]
        X[xtmp + i] *= s            # the weights W left there by weights()
    back_solve(tree, scene, X, xtmp, coupled)
    for i in range(n):
        out[n + i] += X[xtmp + i]
    return -1


@one_signature
@kernel
def schur_solve(X, xc, m, n, nt, rank):
    """``lambda <- S^-1 lambda`` (rows by index in the ``lam`` block) over the first ``rank`` rows of the pivot
    order, with the factor left by :func:`kkt`; the other rows' entries set to 0."""
    lay = x_layout(m, n, nt)
    xs, xl, xlam, xb, xperm = xc + lay[4], xc + lay[5], xc + lay[6], xc + lay[7], xc + lay[13]
    for a in range(rank):           # L z = D b (L unit lower triangular)
        k = nonneg(int(X[xperm + a]))
        v = X[xlam + k] * X[xs + a]
        for c in range(a):
            v -= X[xl + a * m + c] * X[xb + c]
        X[xb + a] = v
    for a in range(rank):           # the reciprocal pivots on the diagonal: independent products
        X[xb + a] *= X[xl + a * m + a]
    for a in range(rank - 1, -1, -1):   # L^T x = z
        v = X[xb + a]
        for c in range(a + 1, rank):
            v -= X[xl + c * m + a] * X[xb + c]
        X[xb + a] = v
    for k in range(m):
        X[xlam + k] = 0.0
    for a in range(rank):
        X[xlam + nonneg(int(X[xperm + a]))] = X[xb + a] * X[xs + a]


@one_signature
@kernel
def schur_correction(tree, scene, v, v_at, dst):
    """``dst (n,) = A^-1 J^T S^-1 v`` for the rows' values ``v[v_at:v_at + m]`` over the rows solved at the last
    evaluation, with its factors (E74's steps); uses the ``lam`` block as its scratch."""
    SI, X = scene.SI, scene.X
    n, nt = nonneg(SI[0]), nonneg(SI[1])
    c0 = nonneg(SI[S_CON])
    m = nonneg(SI[c0 + CM])
    xc = nonneg(SI[c0 + CX])
    lay = x_layout(m, n, nt)
    xj, xlam, xact = xc + lay[2], xc + lay[6], xc + lay[8]
    rank = 0
    for k in range(m):
        X[xlam + k] = v[v_at + k]
        if X[xact + k] != 0.0:
            rank += 1
    schur_solve(X, xc, m, n, nt, rank)
    for i in range(n):
        dst[i] = 0.0
    for k in range(m):
        lam = X[xlam + k]
        if lam != 0.0:
            for i in range(n):
                dst[i] += X[xj + k * n + i] * lam
    a_solve(tree, scene, dst, 0, SI[4] != 0)

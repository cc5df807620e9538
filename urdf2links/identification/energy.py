"""The energy form: ``E + V`` linear in ``pi``, and the power balance over intervals (docs/equations.md (E90)).

For data without accelerations. A link's kinetic energy (E17, E37) in its own axes, with the body twist
``(omega, v_o)`` (``v_o = omega x o + v`` the origin's velocity, turned by ``R^T``), is

    E_p = 1/2 m |v_o|^2 + l . (v_o x omega) + 1/2 (tr(S) |omega|^2 - omega^T S omega)

and its potential ``V_p = -g . (R l + m o)`` (E21): both linear in the 10 entries of H. The armature adds
``1/2 q_k'^2`` (a coordinate of its own) or ``1/2 |omega_p - omega_s|^2`` (a ball link) per unit (E49), a
tendon's ``1/2 l'^2`` (E76). So ``E + V = h(q, q') . pi`` (:func:`energy_regressor`, (S, p)).

Over an interval ``[t_a, t_b]`` the power balance (E40) with the joints' dissipation reads

    h(t_b) . pi - h(t_a) . pi + int (b q'^2 + f reg(q') q' + o q') dt = int tau . q' dt

(and a tendon's ``b_t l'^2 + f_t reg(l') l'``), one row per interval (:func:`energy_rows`); the integrals
by the trapezoidal rule over the samples. The rows go to :func:`~urdf2links.identification.base.base_parameters`
and a least-squares fit like the regressor's, with ``q''`` never needed.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit, prange

from ..dynamics.kernels import kinematics
from ..dynamics.model_kernels import chunks
from ..dynamics.rows import kernel_array
from ..dynamics.tree_arrays import KL, O_, W_BASE, W_LINK, W_SIZE, WV, I_PARENT, Tree, nonneg
from .regression import compiled

__all__ = ["energy_regressor", "energy_rows", "EnergyRows"]


@njit(cache=True)
def _energy_row(TI, TF, W, X, q, qd, C, d, coupled, gx, gy, gz, link_col, arm, out):
    tree = Tree(TI, TF, W)
    nt = TI[1]
    n = q.size
    for a in range(nt):
        if coupled:
            s1 = d[a]
            s2 = 0.0
            for j in range(n):
                s1 += C[a, j] * q[j]
                s2 += C[a, j] * qd[j]
            X[a] = s1
            X[nt + a] = s2
        else:
            X[a] = q[a]
            X[nt + a] = qd[a]
    kinematics(tree, X, 0, X, nt, True, TF, 0, False, 0.0, 0.0, 0.0)
    out[:] = 0.0
    wl, wb, par = nonneg(TI[W_LINK]), nonneg(TI[W_BASE]), nonneg(TI[I_PARENT])
    for p in range(TI[0]):
        c = link_col[p]
        if c < 0:
            continue
        e = wl + KL * p
        R = W[e:e + 9]
        o0, o1, o2 = W[e + O_], W[e + O_ + 1], W[e + O_ + 2]
        w0, w1, w2 = W[e + WV], W[e + WV + 1], W[e + WV + 2]
        u0 = w1 * o2 - w2 * o1 + W[e + WV + 3]
        u1 = w2 * o0 - w0 * o2 + W[e + WV + 4]
        u2 = w0 * o1 - w1 * o0 + W[e + WV + 5]
        a0, a1, a2 = R[0] * w0 + R[3] * w1 + R[6] * w2, R[1] * w0 + R[4] * w1 + R[7] * w2, R[2] * w0 + R[5] * w1 + R[8] * w2
        b0, b1, b2 = R[0] * u0 + R[3] * u1 + R[6] * u2, R[1] * u0 + R[4] * u1 + R[7] * u2, R[2] * u0 + R[5] * u1 + R[8] * u2
        out[c] = 0.5 * (a1 * a1 + a2 * a2)
        out[c + 1] = 0.5 * (a0 * a0 + a2 * a2)
        out[c + 2] = 0.5 * (a0 * a0 + a1 * a1)
        out[c + 3] = -a0 * a1
        out[c + 4] = -a0 * a2
        out[c + 5] = -a1 * a2
        # l . (v_o x omega) - g . R l
        out[c + 6] = b1 * a2 - b2 * a1 - (R[0] * gx + R[3] * gy + R[6] * gz)
        out[c + 7] = b2 * a0 - b0 * a2 - (R[1] * gx + R[4] * gy + R[7] * gz)
        out[c + 8] = b0 * a1 - b1 * a0 - (R[2] * gx + R[5] * gy + R[8] * gz)
        out[c + 9] = 0.5 * (b0 * b0 + b1 * b1 + b2 * b2) - (gx * o0 + gy * o1 + gz * o2)
    for k in range(arm.shape[0]):
        kind, i, p, c = arm[k, 0], arm[k, 1], arm[k, 2], arm[k, 3]
        if kind == 0:
            out[c] = 0.5 * X[nt + i] * X[nt + i]
            continue
        e = wl + KL * p
        s = TI[par + p]
        f = wb if s < 0 else wl + KL * nonneg(s)
        r0, r1, r2 = W[e + WV] - W[f + WV], W[e + WV + 1] - W[f + WV + 1], W[e + WV + 2] - W[f + WV + 2]
        out[c] = 0.5 * (r0 * r0 + r1 * r1 + r2 * r2)


@njit(cache=True, parallel=True)
def _energy_batch(TI, TF, Q, QD, C, d, coupled, gx, gy, gz, link_col, arm, OUT, nc):
    B = Q.shape[0]
    for c in prange(nc):
        W = np.empty(TI[W_SIZE])
        X = np.empty(2 * TI[1])
        for b in range(c * B // nc, (c + 1) * B // nc):
            _energy_row(TI, TF, W, X, Q[b], QD[b], C, d, coupled, gx, gy, gz, link_col, arm, OUT[b])


def energy_regressor(params, q, qd) -> np.ndarray:
    """``h`` (S, p) (or (p,) for one state) with ``E + V = h . pi`` at ``q, q'`` (S, n) (module doc, E90):
    the links' and the armature's columns; the joints' dissipative columns are 0 (they store no energy),
    a tendon's armature ``1/2 l'^2``. Fixed base (the power balance of a moving base has the base's work
    too, E41)."""
    k = compiled(params)
    single = np.ndim(q) == 1
    Q, QD = (kernel_array(np.atleast_2d(np.asarray(a, float))) for a in (q, qd))
    if Q.shape != QD.shape or Q.shape[1] != params.n:
        raise ValueError(f"q and qd must have shape (S, {params.n}); got {Q.shape}, {QD.shape}")
    out = np.zeros((Q.shape[0], params.p))
    g = k.g
    _energy_batch(k.TI, k.TF, Q, QD, k.C, k.d, k.coupled, g[0], g[1], g[2], k.link_col, k.arm, out, chunks(len(Q)))
    for t, cols in enumerate(params.tendon_cols):
        out[:, cols[2]] = 0.5 * (QD @ params.tendon_coef[t]) ** 2
    return out[0] if single else out


@dataclass(frozen=True)
class EnergyRows:
    """``Y`` (K, p) and ``y`` (K,): ``Y pi = y`` over ``K`` intervals (E90); ``bounds`` (K, 2) their sample
    indices."""

    Y: np.ndarray
    y: np.ndarray
    bounds: np.ndarray


def _trapz(f, t):
    return np.concatenate(([0.0], np.cumsum(0.5 * (f[1:] + f[:-1]) * np.diff(t))))


def energy_rows(params, t, q, qd, tau, *, window: int = 50) -> EnergyRows:
    """The power balance (module doc, E90) over consecutive intervals of ``window`` samples of the run
    ``t`` (S,), ``q, q', tau`` (S, n) (tau: the joints' generalized forces)."""
    t = np.asarray(t, float)
    q, qd, tau = (np.atleast_2d(np.asarray(a, float)) for a in (q, qd, tau))
    S = t.size
    if q.shape != (S, params.n) or qd.shape != q.shape or tau.shape != q.shape:
        raise ValueError(f"t (S,), q, qd, tau (S, {params.n}) of one run: got {t.shape}, {q.shape}, {qd.shape}, "
                         f"{tau.shape}")
    if window < 1 or S <= window:
        raise ValueError(f"window ({window}) must be >= 1 and shorter than the run ({S} samples)")
    h = energy_regressor(params, q, qd)
    vs = params.slip_speed
    cum = np.zeros((S, params.p))
    for j in range(params.n):
        cols = params.joint_cols[j]
        w = qd[:, j]
        for k, f in enumerate((w * w, w * w / np.sqrt(w * w + vs * vs), w)):
            if cols[k] >= 0:
                cum[:, cols[k]] = _trapz(f, t)
    for k, cols in enumerate(params.tendon_cols):
        ld = qd @ params.tendon_coef[k]
        cum[:, cols[0]] = _trapz(ld * ld, t)
        cum[:, cols[1]] = _trapz(ld * ld / np.sqrt(ld * ld + vs * vs), t)
    work = _trapz(np.einsum("sj,sj->s", tau, qd), t)
    a = np.arange(0, S - window, window)
    b = a + window
    total = h + cum
    return EnergyRows(Y=total[b] - total[a], y=work[b] - work[a], bounds=np.stack([a, b], axis=1))

"""Integration loops compiled with numba around the compiled scene (:mod:`urdf2links.scene_kernels`).

The same methods as :mod:`urdf2links.integrators`, step for step: ``RK45`` and ``DOP853`` are
scipy's explicit Runge-Kutta pairs (their tableaux taken from scipy, the same initial step
selection, error norms and step-size control, the same dense output: the quartic of RK45 and the
seventh-degree polynomial of DOP853 with its three extra stages), ``RK4`` the classic fixed step,
``midpoint`` the implicit midpoint rule with the simplified Newton iteration of
:func:`urdf2links.integrators._run_midpoint`. Without Python in the loop, a step costs its
evaluations and little else (scipy's ``OdeSolver`` costs tens of microseconds per step).

Each loop runs in chunks: it returns after ``chunk`` steps (or when its storage is full), so that
the caller shows progress and grows the storage, and resumes from the state it left (``st``).
Status codes: 0 running, 1 reached ``t_end``, 2 stopped by the angle guard, -1 step size too
small, -2 the right-hand side failed (non-finite, or A not positive definite), -3 Newton failed.
"""

from __future__ import annotations

import numpy as np
from numba import njit
from scipy.integrate._ivp import dop853_coefficients as _dop
from scipy.integrate._ivp.rk import RK45 as _RK45

from .scene_kernels import scene_rhs

__all__ = ["TABLEAUX", "erk_chunk", "rk4_chunk", "midpoint_chunk"]

SAFETY, MIN_FACTOR, MAX_FACTOR = 0.9, 0.2, 10.0


def _tableau_rk45():
    A = np.zeros((16, 16))
    A[:6, :5] = _RK45.A
    C = np.zeros(16)
    C[:6] = _RK45.C
    E = np.zeros(13)
    E[:7] = _RK45.E
    P = np.zeros((16, 7))
    P[:7, :4] = _RK45.P
    return dict(stages=6, order=4, A=A, B=np.r_[_RK45.B, np.zeros(6)], C=C, E5=E, E3=np.zeros(13),
                D=np.zeros((4, 16)), P=P, n_dense=4)


def _tableau_dop853():
    return dict(stages=12, order=7, A=np.ascontiguousarray(_dop.A, dtype=float), B=np.asarray(_dop.B, float),
                C=np.asarray(_dop.C, float), E5=np.asarray(_dop.E5, float), E3=np.asarray(_dop.E3, float),
                D=np.ascontiguousarray(_dop.D, dtype=float), P=np.zeros((16, 7)), n_dense=7)


TABLEAUX = {"RK45": _tableau_rk45(), "DOP853": _tableau_dop853()}
"""Butcher tableaux (padded to DOP853's 16 extended stages) and dense-output matrices."""


@njit(cache=True)
def _rms(x, scale):
    s = 0.0
    for i in range(x.size):
        v = x[i] / scale[i]
        s += v * v
    return np.sqrt(s / x.size)


@njit(cache=True)
def _finite(x):
    for i in range(x.size):
        if not np.isfinite(x[i]):
            return False
    return True


@njit(cache=True)
def _guard(y, guard_idx, guard_cos):
    for j in range(guard_idx.size):
        if abs(np.cos(y[guard_idx[j]])) < guard_cos:
            return True
    return False


@njit(cache=True)
def _f(t, y, out, args, cnt, fail):
    """One evaluation; on failure the state goes to ``fail`` = [t, y] for the caller's error."""
    cnt[0] += 1
    I, F, W, SI, SF, X = args
    pivot = scene_rhs(t, y, out, I, F, W, SI, SF, X)
    if pivot < 0 and _finite(out):
        return True
    fail[0] = t
    for i in range(y.size):
        fail[1 + i] = y[i]
    return False


@njit(cache=True)
def initial_step(t0, y0, f0, t_end, max_step, order, rtol, atol, args, cnt, fail):
    """scipy's ``select_initial_step`` (Hairer, Norsett, Wanner I, II.4)."""
    d = y0.size
    interval = abs(t_end - t0)
    scale = np.empty(d)
    for i in range(d):
        scale[i] = atol[i] + abs(y0[i]) * rtol
    d0 = _rms(y0, scale)
    d1 = _rms(f0, scale)
    h0 = 1e-6 if (d0 < 1e-5 or d1 < 1e-5) else 0.01 * d0 / d1
    h0 = min(h0, interval)
    y1 = y0 + h0 * f0
    f1 = np.empty(d)
    _f(t0 + h0, y1, f1, args, cnt, fail)
    d2 = _rms(f1 - f0, scale) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (1.0 / (order + 1))
    return min(100 * h0, h1, interval, max_step)


@njit(cache=True)
def erk_chunk(stages, order, A, B, C, E5, E3, D, P, n_dense, dop, t_end, rtol, atol, max_step, dense,
              st, y, f, K, ts, ys, dens, guard_idx, guard_cos, cnt, chunk, fail, args):
    """Up to ``chunk`` accepted steps of an explicit pair (RK45: ``dop`` False; DOP853: True).

    ``st`` = [t, h_abs, stored]; ``y``, ``f`` (d,) the current state and slope (in/out); ``K``
    (16, d) stages; ``ts`` (cap,), ``ys`` (cap, d) accepted steps, ``dens`` (cap, n_dense, d) the
    dense-output coefficients of the step ending there; ``cnt`` = [nfev, nsteps, nrejected,
    status]. Returns the status."""
    d = y.size
    error_exponent = -1.0 / (order + 1)
    y_new = np.empty(d)
    f_new = np.empty(d)
    ystage = np.empty(d)
    scale = np.empty(d)
    err5 = np.empty(d)
    err3 = np.empty(d)
    cap = ts.size
    t = st[0]
    h_abs = st[1]
    stored = int(st[2])
    taken = 0
    status = 0
    while taken < chunk and stored < cap:
        min_step = 10.0 * abs(np.nextafter(t, np.inf) - t)
        if h_abs > max_step:
            h_abs = max_step
        elif h_abs < min_step:
            h_abs = min_step
        rejected = False
        while True:
            if h_abs < min_step:
                status = -1
                break
            t_new = t + h_abs
            if t_new - t_end > 0:
                t_new = t_end
            h = t_new - t
            h_abs = abs(h)
            ok = True
            for i in range(d):
                K[0, i] = f[i]
            for s in range(1, stages):
                for i in range(d):
                    acc = 0.0
                    for j in range(s):
                        acc += K[j, i] * A[s, j]
                    ystage[i] = y[i] + acc * h
                if not _f(t + C[s] * h, ystage, K[s], args, cnt, fail):
                    ok = False
                    break
            if ok:
                for i in range(d):
                    acc = 0.0
                    for j in range(stages):
                        acc += K[j, i] * B[j]
                    y_new[i] = y[i] + h * acc
                ok = _f(t + h, y_new, f_new, args, cnt, fail)
            if not ok:
                status = -2
                break
            for i in range(d):
                K[stages, i] = f_new[i]
                scale[i] = atol[i] + max(abs(y[i]), abs(y_new[i])) * rtol
            if dop:
                for i in range(d):
                    a5 = 0.0
                    a3 = 0.0
                    for j in range(stages + 1):
                        a5 += K[j, i] * E5[j]
                        a3 += K[j, i] * E3[j]
                    err5[i] = a5 / scale[i]
                    err3[i] = a3 / scale[i]
                n5 = 0.0
                n3 = 0.0
                for i in range(d):
                    n5 += err5[i] * err5[i]
                    n3 += err3[i] * err3[i]
                if n5 == 0.0 and n3 == 0.0:
                    error_norm = 0.0
                else:
                    error_norm = abs(h) * n5 / np.sqrt((n5 + 0.01 * n3) * d)
            else:
                for i in range(d):
                    a5 = 0.0
                    for j in range(stages + 1):
                        a5 += K[j, i] * E5[j]
                    err5[i] = a5 * h
                error_norm = _rms(err5, scale)
            if error_norm < 1.0:
                if error_norm == 0.0:
                    factor = MAX_FACTOR
                else:
                    factor = min(MAX_FACTOR, SAFETY * error_norm ** error_exponent)
                if rejected:
                    factor = min(1.0, factor)
                h_abs *= factor
                break
            h_abs *= max(MIN_FACTOR, SAFETY * error_norm ** error_exponent)
            rejected = True
            cnt[2] += 1
        if status != 0:
            break
        if dense:
            row = dens[stored]
            if dop:
                for s in range(stages + 1, 16):       # the three extra stages
                    for i in range(d):
                        acc = 0.0
                        for j in range(s):
                            acc += K[j, i] * A[s, j]
                        ystage[i] = y[i] + acc * h
                    if not _f(t + C[s] * h, ystage, K[s], args, cnt, fail):
                        status = -2
                        break
                if status != 0:
                    break
                for i in range(d):
                    dy = y_new[i] - y[i]
                    row[0, i] = dy
                    row[1, i] = h * K[0, i] - dy
                    row[2, i] = 2.0 * dy - h * (f_new[i] + K[0, i])
                for r in range(4):
                    for i in range(d):
                        acc = 0.0
                        for j in range(16):
                            acc += D[r, j] * K[j, i]
                        row[3 + r, i] = h * acc
            else:
                for r in range(n_dense):
                    for i in range(d):
                        acc = 0.0
                        for j in range(stages + 1):
                            acc += K[j, i] * P[j, r]
                        row[r, i] = acc
        t = t_new
        for i in range(d):
            y[i] = y_new[i]
            f[i] = f_new[i]
        ts[stored] = t
        for i in range(d):
            ys[stored, i] = y[i]
        stored += 1
        taken += 1
        cnt[1] += 1
        if t >= t_end:
            status = 1
            break
        if _guard(y, guard_idx, guard_cos):
            status = 2
            break
    st[0] = t
    st[1] = h_abs
    st[2] = stored
    cnt[3] = status
    return status


@njit(cache=True)
def rk4_chunk(grid, st, ys, fs, guard_idx, guard_cos, cnt, chunk, fail, args):
    """Up to ``chunk`` RK4 steps along ``grid`` from index ``st[0]``; ``ys``, ``fs`` (m, d) hold
    the states and slopes at the grid points (row ``st[0]`` filled on entry)."""
    d = ys.shape[1]
    k2 = np.empty(d)
    k3 = np.empty(d)
    k4 = np.empty(d)
    yt = np.empty(d)
    i = int(st[0])
    m = grid.size
    status = 0
    taken = 0
    while taken < chunk:
        if i >= m - 1:
            status = 1
            break
        t, h = grid[i], grid[i + 1] - grid[i]
        hh = 0.5 * h
        y = ys[i]
        k1 = fs[i]
        for j in range(d):
            yt[j] = y[j] + hh * k1[j]
        ok = _f(t + hh, yt, k2, args, cnt, fail)
        for j in range(d):
            yt[j] = y[j] + hh * k2[j]
        ok = ok and _f(t + hh, yt, k3, args, cnt, fail)
        for j in range(d):
            yt[j] = y[j] + h * k3[j]
        ok = ok and _f(t + h, yt, k4, args, cnt, fail)
        if ok:
            for j in range(d):
                ys[i + 1, j] = y[j] + (h / 6.0) * (k1[j] + 2.0 * (k2[j] + k3[j]) + k4[j])
            ok = _f(grid[i + 1], ys[i + 1], fs[i + 1], args, cnt, fail)
        if not ok:
            status = -2
            break
        i += 1
        taken += 1
        cnt[1] += 1
        if _guard(ys[i], guard_idx, guard_cos):
            status = 2
            break
    if i >= m - 1 and status == 0:
        status = 1
    st[0] = i
    cnt[3] = status
    return status


@njit(cache=True)
def _jacobian(t, y, f, J, args, cnt, fail):
    d = y.size
    yp = y.copy()
    fp = np.empty(d)
    for j in range(d):
        step = np.sqrt(2.220446049250313e-16) * max(abs(y[j]), 1.0)
        yp[j] = y[j] + step
        ok = _f(t, yp, fp, args, cnt, fail)
        if not ok:
            return False
        dstep = yp[j] - y[j]
        for i in range(d):
            J[i, j] = (fp[i] - f[i]) / dstep
        yp[j] = y[j]
    return True


@njit(cache=True)
def midpoint_chunk(grid, rtol, atol, st, ts, ys, ks, hist_h, hist_k, J, minv, cnt, chunk,
                   max_halvings, maxiter, guard_idx, guard_cos, fail, args):
    """Up to ``chunk`` grid intervals of the implicit midpoint rule (the algorithm of
    :func:`urdf2links.integrators._run_midpoint`, compiled). ``st`` = [grid index, stored n,
    t, need_jac, jac_fresh, have_minv, inv_h, hist_len, njev]; ``ts``, ``ys`` (cap, d) the
    steps, ``ks`` (cap, d) the stage slope of each step; ``cnt`` = [nfev, nsteps, nrejected,
    status]."""
    d = ys.shape[1]
    eps = 2.220446049250313e-16
    tol = max(10 * eps / rtol, min(0.03, rtol ** 0.5))
    atol_zero = True
    for i in range(d):
        if atol[i] != 0.0:
            atol_zero = False
    gi = int(st[0])
    n = int(st[1])
    t = st[2]
    need_jac = st[3] != 0.0
    jac_fresh = st[4] != 0.0
    have_minv = st[5] != 0.0
    inv_h = st[6]
    hist_len = int(st[7])
    njev = int(st[8])
    cap = ts.size
    k = np.empty(d)
    k_pred = np.empty(d)
    dk = np.empty(d)
    ym = np.empty(d)
    f = np.empty(d)
    scale = np.empty(d)
    status = 0
    taken = 0
    m = grid.size
    while taken < chunk:
        if gi >= m - 1:
            status = 1
            break
        target = grid[gi + 1]
        h_try = target - t
        halvings = 0
        while t < target:
            if n + 1 >= cap:
                status = 3          # storage full: the caller grows it and calls again
                break
            last = h_try >= target - t
            h = target - t if last else h_try
            y = ys[n]
            if hist_len == 3 and h == hist_h[0] and h == hist_h[1] and h == hist_h[2]:
                for i in range(d):
                    k_pred[i] = 3.0 * (hist_k[0, i] - hist_k[1, i]) + hist_k[2, i]
            elif hist_len >= 2 and h == hist_h[0] and h == hist_h[1]:
                for i in range(d):
                    k_pred[i] = 2.0 * hist_k[0, i] - hist_k[1, i]
            elif hist_len >= 1:
                for i in range(d):
                    k_pred[i] = hist_k[0, i]
            else:
                for i in range(d):
                    k_pred[i] = ks[0, i]          # f(t0, y0) on entry (filled by the caller)
            ymax = 0.0
            for i in range(d):
                k[i] = k_pred[i]
                scale[i] = atol[i] + rtol * abs(y[i])
                ymax = max(ymax, abs(y[i]))
            if atol_zero:
                for i in range(d):
                    scale[i] = max(scale[i], rtol * 1e-8 * ymax + 1e-300)
            tm = t + 0.5 * h
            hh = 0.5 * h
            noise = 0.0
            for i in range(d):
                v = (abs(y[i]) + abs(h * k[i])) / scale[i]
                noise += v * v
            noise = 8 * eps * np.sqrt(noise / d)
            ok = False
            dy_old = -1.0
            rate = -1.0
            it = 0
            while True:
                for i in range(d):
                    ym[i] = y[i] + hh * k[i]
                good = _f(tm, ym, f, args, cnt, fail)
                if need_jac:
                    jac_fresh = True
                    it = 0
                    dy_old = -1.0
                    if not good:
                        break
                    if not _jacobian(tm, ym, f, J, args, cnt, fail):
                        break
                    njev += 1
                    need_jac = False
                    have_minv = False
                if not good:              # as in Python: a failed slope counts as no convergence
                    it += 1
                    if jac_fresh:
                        break
                    need_jac = True
                    for i in range(d):
                        k[i] = k_pred[i]
                    dy_old = -1.0
                    continue
                if not have_minv or inv_h != h:
                    M = -hh * J
                    for i in range(d):
                        M[i, i] += 1.0
                    minv[:, :] = np.linalg.inv(M)
                    have_minv = True
                    inv_h = h
                dy = 0.0
                for i in range(d):
                    acc = 0.0
                    for j in range(d):
                        acc += minv[i, j] * (f[j] - k[j])
                    dk[i] = acc
                for i in range(d):
                    k[i] += dk[i]
                    v = dk[i] * h / scale[i]
                    dy += v * v
                it += 1
                dy = np.sqrt(dy / d)
                if dy <= noise:
                    ok = True
                    break
                slow = not np.isfinite(dy) or it >= maxiter
                if not slow and dy_old >= 0.0:
                    rate = dy / dy_old
                    if rate < 1 and rate / (1 - rate) * dy < tol:
                        ok = True
                        break
                    slow = (not jac_fresh) and (rate >= 1 or rate ** (maxiter - it) / (1 - rate) * dy > tol)
                if slow:
                    if jac_fresh:
                        break
                    need_jac = True
                    if not (np.isfinite(dy) and rate < 1.0):
                        for i in range(d):
                            k[i] = k_pred[i]
                dy_old = dy
            if not ok:
                cnt[2] += 1
                halvings += 1
                if halvings > max_halvings:
                    status = -3
                    break
                h_try *= 0.5
                continue
            n += 1
            t = target if last else t + h
            ts[n] = t
            for i in range(d):
                ks[n - 1, i] = k[i]
                ys[n, i] = ys[n - 1, i] + h * k[i]
            for r in range(2, 0, -1):
                hist_h[r] = hist_h[r - 1]
                for i in range(d):
                    hist_k[r, i] = hist_k[r - 1, i]
            hist_h[0] = h
            for i in range(d):
                hist_k[0, i] = k[i]
            hist_len = min(hist_len + 1, 3)
            if not jac_fresh:
                need_jac = rate > 0.2
            jac_fresh = False
            cnt[1] += 1
            if not _finite(ys[n]):
                status = -2
                break
            if _guard(ys[n], guard_idx, guard_cos):
                status = 2
                break
        if status != 0:
            break
        gi += 1
        taken += 1
    if gi >= m - 1 and status == 0:
        status = 1
    st[0] = gi
    st[1] = n
    st[2] = t
    st[3] = 1.0 if need_jac else 0.0
    st[4] = 1.0 if jac_fresh else 0.0
    st[5] = 1.0 if have_minv else 0.0
    st[6] = inv_h
    st[7] = hist_len
    st[8] = njev
    cnt[3] = status
    return status


# -- drivers (Python): chunks, storage, progress, results ---------------------------------------
CHUNK = 2000


def run(method, rhs, f0, t0, t1, y0, rtol, atol, dt, callback, max_steps, need_dense, guard, grid):
    """Integrate the compiled scene ``rhs`` (a :class:`~urdf2links.scene_kernels.CompiledScene`)
    with a compiled loop. Returns ``(ts, ys, sol, nfev, njev, nrejected, success, message,
    stopped)``; ``sol`` a :class:`~urdf2links.integrators.DenseOutput` when ``need_dense``."""
    from .integrators import NEWTON_MAXITER, MAX_HALVINGS, DenseOutput, IntegrationError, midpoint_dense

    args = rhs.args
    d = y0.size
    atol_v = np.ascontiguousarray(np.broadcast_to(np.asarray(atol, float), (d,)))
    gidx = np.zeros(0, np.int64) if guard is None else guard.indices
    gcos = 0.0 if guard is None else guard.cos_min
    cnt = np.zeros(4, np.int64)
    fail = np.zeros(d + 1)
    budget = np.inf if max_steps is None else int(max_steps)
    njev = 0

    def chunk_size():
        return int(min(CHUNK, budget - cnt[1]))

    if method in ("RK45", "DOP853"):
        tab = TABLEAUX[method]
        max_step = np.inf if dt is None else float(dt)
        h_abs = initial_step(t0, y0, f0, t1, max_step, tab["order"], float(rtol), atol_v, args, cnt, fail)
        cap = 256
        ts, ys = np.empty(cap), np.empty((cap, d))
        nd = tab["n_dense"]
        dens = np.empty((cap if need_dense else 0, nd, d))
        ts[0], ys[0] = t0, y0
        st = np.array([t0, h_abs, 1.0])
        y, f, K = y0.copy(), f0.copy(), np.zeros((16, d))
        while True:
            status = erk_chunk(tab["stages"], tab["order"], tab["A"], tab["B"], tab["C"], tab["E5"], tab["E3"],
                               tab["D"], tab["P"], nd, method == "DOP853", float(t1), float(rtol), atol_v, max_step,
                               need_dense, st, y, f, K, ts, ys, dens, gidx, gcos, cnt, chunk_size(), fail, args)
            if callback is not None:
                callback(float(st[0]), y)
            if status != 0 or cnt[1] >= budget:
                break
            if int(st[2]) >= ts.size:
                ts = np.concatenate([ts, np.empty(ts.size)])
                ys = np.concatenate([ys, np.empty_like(ys)])
                if need_dense:
                    dens = np.concatenate([dens, np.empty_like(dens)])
        m = int(st[2])
        ts, ys = ts[:m], ys[:m]
        sol = DenseOutput(ts, ys, poly=(method, dens[:m])) if need_dense and m > 1 else None
        nrejected = int(cnt[2])
    elif method == "RK4":
        m = grid.size
        ys, fs = np.empty((m, d)), np.empty((m, d))
        ys[0], fs[0] = y0, f0
        st = np.zeros(1)
        while True:
            status = rk4_chunk(grid, st, ys, fs, gidx, gcos, cnt, chunk_size(), fail, args)
            if callback is not None:
                callback(float(grid[int(st[0])]), ys[int(st[0])])
            if status != 0 or cnt[1] >= budget:
                break
        m = int(st[0]) + 1
        ts, ys, fs = grid[:m].copy(), ys[:m], fs[:m]
        sol = DenseOutput(ts, ys, fs) if need_dense else None
        nrejected = 0
    else:
        cap = grid.size + 16
        ts, ys, ks = np.empty(cap), np.empty((cap, d)), np.empty((cap, d))
        ts[0], ys[0], ks[0] = t0, y0, f0
        st = np.array([0.0, 0.0, t0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0])
        hist_h, hist_k = np.zeros(3), np.zeros((3, d))
        J, minv = np.zeros((d, d)), np.zeros((d, d))
        while True:
            status = midpoint_chunk(grid, float(rtol), atol_v, st, ts, ys, ks, hist_h, hist_k, J, minv, cnt,
                                    chunk_size(), MAX_HALVINGS, NEWTON_MAXITER, gidx, gcos, fail, args)
            n = int(st[1])
            if callback is not None:
                callback(float(st[2]), ys[n])
            if status == 3:
                grow = max(16, ts.size // 2)
                ts = np.concatenate([ts, np.empty(grow)])
                ys, ks = (np.concatenate([a, np.empty((grow, d))]) for a in (ys, ks))
                continue
            if status != 0 or cnt[1] >= budget:
                break
        njev = int(st[8])
        n = int(st[1])
        if status == -3:
            raise IntegrationError(f"implicit midpoint: Newton iteration did not converge at t={float(st[2])!r} "
                                   f"(step {n + 1} after {MAX_HALVINGS} halvings of dt={dt!r}; rtol={rtol!r})")
        ts, ys, ks = ts[:n + 1], ys[:n + 1], ks[:n]
        sol = None
        if need_dense:
            cnt[0] += 1
            sol = midpoint_dense(ts, ys, ks, f0, rhs(ts[n], ys[n]))
        nrejected = int(cnt[2])
    if status == -2:
        rhs.check(float(fail[0]), fail[1:])      # raises the named error of the model if there is one
        raise IntegrationError(f"{method}: non-finite state or right-hand side at t={float(fail[0])!r}"
                               + (f" (dt={dt!r})" if dt else ""))
    stopped = status == 2
    success, message = True, "reached t_end"
    if status == -1:
        success, message = False, f"{method} failed at t={float(ts[-1])!r}: Required step size is less than spacing between numbers."
    elif status == 0 and cnt[1] >= budget:
        success, message = False, f"max_steps={max_steps} reached at t={float(ts[-1])!r}"
    elif stopped:
        message = f"stopped by stop(t, y) at t={float(ts[-1])!r}"
    return ts, ys, sol, int(cnt[0]), njev, nrejected, success, message, stopped

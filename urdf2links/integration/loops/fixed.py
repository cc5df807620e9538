"""The fixed-step loops, compiled with numba: classic RK4 and the implicit midpoint rule.

The midpoint rule ``y1 = y0 + h k``, ``k = F(t0 + h/2, y0 + h/2 k)`` is solved by simplified
Newton iterations on ``(1 - h/2 J) dk = F - k`` (:func:`_newton`; the tolerances are stated in
:mod:`urdf2links.integration.integrators`), halving a step whose iteration fails. These functions are also run
interpreted, on Python right-hand sides (:mod:`urdf2links.integration.loops.driver`): one source for both.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ...compilation import one_signature

from .common import EPS, evaluate, finite, guard_fires, settle

__all__ = ["rk4_chunk", "midpoint_chunk", "NEWTON_MAXITER", "MAX_HALVINGS"]

MAX_HALVINGS = 4          # midpoint: step halvings before giving up
NEWTON_MAXITER = 8        # midpoint: simplified Newton iterations per attempt


# -- RK4 --------------------------------------------------------------------------------------------
@one_signature
@njit(cache=True)
def rk4_chunk(grid, state, guard, counters, chunk, args):
    """Up to ``chunk`` RK4 steps along ``grid`` from index ``st[0]``; ``state = (st, ys, fs)``, ``ys``,
    ``fs`` (m, d) the states and slopes at the grid points (row ``st[0]`` filled on entry)."""
    st, ys, fs = state
    cnt = counters[0]
    d = ys.shape[1]
    k2 = np.empty(d)
    k3 = np.empty(d)
    k4 = np.empty(d)
    yt = np.empty(d)
    i = int(st[0])
    m = grid.size
    status = 0
    taken = 0
    while taken < chunk and i < m - 1:
        t, h = grid[i], grid[i + 1] - grid[i]
        hh = 0.5 * h
        y = ys[i]
        k1 = fs[i]
        for j in range(d):
            yt[j] = y[j] + hh * k1[j]
        ok = evaluate(t + hh, yt, k2, args, counters)
        for j in range(d):
            yt[j] = y[j] + hh * k2[j]
        ok = ok and evaluate(t + hh, yt, k3, args, counters)
        for j in range(d):
            yt[j] = y[j] + h * k3[j]
        ok = ok and evaluate(t + h, yt, k4, args, counters)
        if ok:
            for j in range(d):
                ys[i + 1, j] = y[j] + (h / 6.0) * (k1[j] + 2.0 * (k2[j] + k3[j]) + k4[j])
            ok = settle(grid[i + 1], ys[i + 1], fs[i + 1], args, counters)     # issue 45: projected (E74)
        if not ok:
            status = -2
            break
        i += 1
        taken += 1
        cnt[1] += 1
        if guard_fires(ys[i], guard):
            status = 2
            break
    if i >= m - 1 and status == 0:
        status = 1
    st[0] = i
    cnt[3] = status
    return status


# -- implicit midpoint ------------------------------------------------------------------------------
# st = [grid index, stored n, t, need_jac, jac_fresh, have_minv, inv_h, hist_len, njev, jac_const, h]
@one_signature
@njit(cache=True)
def _jacobian(t, y, f, J, args, counters):
    """Forward differences of the right-hand side around ``(t, y)`` (``f`` = F(t, y)) into ``J``."""
    d = y.size
    yp = y.copy()
    fp = np.empty(d)
    for j in range(d):
        step = np.sqrt(EPS) * max(abs(y[j]), 1.0)
        yp[j] = y[j] + step
        if not evaluate(t, yp, fp, args, counters):
            return False
        dstep = yp[j] - y[j]
        for i in range(d):
            J[i, j] = (fp[i] - f[i]) / dstep
        yp[j] = y[j]
    return True


@one_signature
@njit(cache=True)
def _predict(hist_h, hist_k, hist_len, h, k0, k_pred):
    """The first guess of the stage slope: extrapolation of the last accepted slopes at a
    constant step (quadratic with three, linear with two), else the last one, else ``k0``."""
    d = k_pred.size
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
            k_pred[i] = k0[i]


@one_signature
@njit(cache=True)
def _newton(t, h, y, k, k_pred, scale, tol, st, J, minv, work, args, counters):
    """Simplified Newton iterations for ``k = F(t + h/2, y + h/2 k)`` from ``k = k_pred``.

    Stops on convergence (estimated remaining error ``rate / (1 - rate) |h dk| < tol``, or ``h dk``
    at the rounding level of ``y + h k``), refreshes a stale Jacobian when the contraction rate
    predicts no convergence within :data:`NEWTON_MAXITER` iterations, and gives up with a fresh
    one, or when ``1 - h/2 J`` cannot be inverted. Returns ``(converged, rate)`` (``rate`` -1 when
    unknown); the Jacobian state lives in ``st``."""
    ym, f, dk = work
    d = y.size
    hh = 0.5 * h
    tm = t + hh
    noise = 0.0
    for i in range(d):
        v = (abs(y[i]) + abs(h * k[i])) / scale[i]
        noise += v * v
    noise = 8 * EPS * np.sqrt(noise / d)
    dy_old = -1.0
    rate = -1.0
    it = 0
    while True:
        for i in range(d):
            ym[i] = y[i] + hh * k[i]
        good = evaluate(tm, ym, f, args, counters)
        if st[3] != 0.0:                                   # need a Jacobian
            st[4] = 1.0
            it = 0
            dy_old = -1.0
            if not good or not _jacobian(tm, ym, f, J, args, counters):
                return False, rate
            st[8] += 1
            st[3] = 0.0
            st[5] = 0.0
        if not good:              # a failed slope counts as no convergence
            it += 1
            if st[4] != 0.0:
                return False, rate
            st[3] = 1.0
            for i in range(d):
                k[i] = k_pred[i]
            dy_old = -1.0
            continue
        if st[5] == 0.0 or st[6] != h:
            M = -hh * J
            for i in range(d):
                M[i, i] += 1.0
            if not _invert(M, minv):
                return False, rate
            st[5] = 1.0
            st[6] = h
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
            return True, rate
        slow = not np.isfinite(dy) or it >= NEWTON_MAXITER
        if not slow and dy_old >= 0.0:
            rate = dy / dy_old
            if rate < 1 and rate / (1 - rate) * dy < tol:
                return True, rate
            # simplified Newton (stale J) converges linearly: predict failure
            slow = st[4] == 0.0 and (rate >= 1 or rate ** (NEWTON_MAXITER - it) / (1 - rate) * dy > tol)
        if slow:                  # refresh a stale Jacobian and go on, else give up
            if st[4] != 0.0:
                return False, rate
            st[3] = 1.0
            if not (np.isfinite(dy) and rate < 1.0):
                for i in range(d):
                    k[i] = k_pred[i]
        dy_old = dy


@one_signature
@njit(cache=True)
def _invert(M, out):
    """``out = M^-1``; False when ``M`` is singular or not finite (the iteration then fails)."""
    if not finite(M.ravel()):
        return False
    try:
        out[:, :] = np.linalg.inv(M)
    except Exception:  # numba: singular matrix
        return False
    return finite(out.ravel())


@one_signature
@njit(cache=True)
def _midpoint_scale(y, atol, rtol, scale):
    """Error weights ``atol + rtol |y|``; with ``atol`` all zero, floored at ``1e-8 rtol max|y|``."""
    d = y.size
    ymax = 0.0
    atol_zero = True
    for i in range(d):
        scale[i] = atol[i] + rtol * abs(y[i])
        ymax = max(ymax, abs(y[i]))
        if atol[i] != 0.0:
            atol_zero = False
    if atol_zero:
        for i in range(d):
            scale[i] = max(scale[i], rtol * 1e-8 * ymax + 1e-300)


@one_signature
@njit(cache=True)
def _record(n, t, h, k, store, hist):
    """Accept the step ``y_n+1 = y_n + h k`` at ``t``; push ``(h, k)`` onto the slope history."""
    ts, ys, ks = store
    hist_h, hist_k = hist
    d = k.size
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


@one_signature
@njit(cache=True)
def midpoint_chunk(grid, ctl, state, store, guard, counters, chunk, args):
    """Up to ``chunk`` grid intervals of the implicit midpoint rule.

    ``ctl = (rtol, atol (d,))``; ``state = (st, hist_h (3,), hist_k (3, d), J, minv (d, d))`` with
    ``st`` as commented above (the Newton iteration's Jacobian state carries over steps and
    chunks); ``store = (ts, ys, ks)`` (cap,), (cap, d), (cap, d): the steps and the stage slope of
    each (``ks[0]`` holds ``F(t0, y0)`` on the first entry); ``counters = (cnt, fail)``."""
    rtol, atol = ctl
    st, hist_h, hist_k, J, minv = state
    ts, ys, ks = store
    cnt = counters[0]
    d = ys.shape[1]
    tol = max(10 * EPS / rtol, min(0.03, rtol ** 0.5))
    k = np.empty(d)
    k_pred = np.empty(d)
    scale = np.empty(d)
    work = (np.empty(d), np.empty(d), np.empty(d))
    k0 = ks[0].copy()
    gi, n, t = int(st[0]), int(st[1]), st[2]
    status = 0
    taken = 0
    while taken < chunk and status == 0:
        if gi >= grid.size - 1:
            status = 1
            break
        target = grid[gi + 1]
        h_try = target - t
        halvings = 0
        while t < target:
            if n + 1 >= ts.size:
                status = 3          # storage full: the caller grows it and calls again
                break
            last = h_try >= target - t
            h = target - t if last else h_try
            st[10] = h
            _predict(hist_h, hist_k, int(st[7]), h, k0, k_pred)
            for i in range(d):
                k[i] = k_pred[i]
            _midpoint_scale(ys[n], atol, rtol, scale)
            ok, rate = _newton(t, h, ys[n], k, k_pred, scale, tol, st, J, minv, work, args, counters)
            if not ok:
                cnt[2] += 1
                halvings += 1
                if halvings > MAX_HALVINGS:
                    status = -3
                    break
                h_try *= 0.5
                continue
            n += 1
            t = target if last else t + h
            _record(n, t, h, k, store, (hist_h, hist_k))
            st[7] = min(st[7] + 1, 3)
            if st[4] == 0.0:               # slow convergence: fresh Jacobian next step
                st[3] = 1.0 if rate > 0.2 else 0.0
            st[4] = st[9]
            cnt[1] += 1
            if not finite(ys[n]):
                status = -2
                break
            if guard_fires(ys[n], guard):
                status = 2
                break
        if status != 0:
            break
        gi += 1
        taken += 1
    if gi >= grid.size - 1 and status == 0:
        status = 1
    st[0], st[1], st[2] = gi, n, t
    cnt[3] = status
    return status

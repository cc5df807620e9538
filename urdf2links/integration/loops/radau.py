"""Radau IIA of order 5 (three stages), compiled with numba: the implicit loop for stiff scenes.

The method and its strategies are Hairer & Wanner's RADAU5 (Solving ODEs II, IV.8): collocation at
the Radau points ``c = ((4 - sqrt 6)/10, (4 + sqrt 6)/10, 1)``, order 5, stiffly accurate and
L-stable; the stage system solved by simplified Newton iterations after the transformation that
splits ``A^-1`` into one real eigenvalue and a complex pair, so that each iteration solves one real
and one complex linear system of the size of the problem (the constants ``T``, ``TI``, ``MU_*``, the
error weights ``E`` and the dense-output matrix ``P`` are scipy's, :mod:`scipy.integrate._ivp.radau`).
Hairer's strategies, not scipy's, are followed where they differ:

* the error estimate (of order 3) is held to ``rtol' = rtol^(5/6)``, ``atol' = atol rtol' / rtol``
  (:func:`radau_tolerances`: the global error then comes out near ``rtol``, as DOP853's does at the
  same ``rtol``; RADAU5's own map ``0.1 rtol^(2/3)`` aims at the local error and left the global
  error 3-6x larger on the shipped scenes);
* the Newton iteration stops once ``faccon |dW| <= fnewt``, ``faccon`` the contraction factor
  ``theta / (1 - theta)`` (carried over from the previous step until measured), and divergence is
  predicted from the contraction (the step shrunk at once); unlike RADAU5, never after a single
  iteration (as scipy's Radau): a Jacobian gone stale contracts badly while its first correction
  is small and would pass for convergence (a scalar problem whose ``lambda`` falls from 1e5 to 1 /s
  took a 1.1 s step to an error of 0.12 at rtol 1e-8; the second iteration costs the Allegro hand
  13 % more evaluations in ``auto``);
* the Jacobian is kept across steps and recomputed only after a step whose iteration contracted
  slower than ``thet`` (:func:`strategy_for`: RADAU5's 0.001, or its 0.1 for costly Jacobians beyond
  20 differenced columns), after a rejection made with a stale one, and (``auto``)
  every :data:`~urdf2links.integration.loops.stiffness.JAC_REFRESH` steps; the factorisations are
  kept while the step size would change by less than 20 % (``1 <= h_new / h <= 1.2`` keeps ``h``;
  for a large system ``0.99 .. 2``, RADAU5's advice: the factorisations cost ``n^3``);
* the predictive (Gustafsson) step-size controller, the error estimate refined with one more
  evaluation after a rejection, the first step cut by 10 when rejected.

**The Jacobian** is forward differences of the compiled right-hand side inside the loop, and the
linear algebra uses the structure of a scene's system ``y = (q, v, W)``, ``y' = (v, a(t, q, v),
P(t, q, v))`` (E59): ``dq'/dq = 0``, ``dq'/dv = 1``, nothing depends on ``W``; only the ``2n`` columns
of ``q`` and ``v`` are differenced (``2n`` evaluations), and ``(g - J) x = r`` is solved by
eliminating ``x_q = (r_q + x_v) / g`` and ``x_W``: one ``n x n`` system
``(g - J_v - J_q / g) x_v = r_v + J_q r_q / g`` (E60), for ``g`` real and complex. A system without
that structure (a Python right-hand side) runs with ``nq = 0``: the full ``d x d`` systems.

**Dense output**: the collocation polynomial of each step (cubic, ``y_old + sum_k Q_k x^k``,
``x = (t - t_old) / h``; RADAU5's ``CONTR5``), also the predictor of the next step's stages. It is
of order 3 inside a step (the stage order; the steps themselves are of order 5): on a very stiff
run whose steps grow long, values between the steps are less accurate than at them (4.8e-5 inside
a 0.4 s step on ``y' = -1e5 (y - cos t) - sin t`` at rtol 1e-8, 1e-9 at the steps). A quintic
Hermite polynomial on the steps' states and slopes was tried and dropped: on a stiff component the
slope ``F(y_n)`` multiplies the state's own error by ``|lambda|``.

These functions are also run interpreted (:mod:`urdf2links.integration.loops.driver`), on Python
right-hand sides: one source for both.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ...compilation import one_signature
from scipy.integrate._ivp import radau as _sr

from .common import EPS, evaluate, guard_fires, has_rows, project
from .lu import lu_factor, lu_solve
from .stiffness import JAC_REFRESH, MIN_IMPLICIT_STEPS, explicit_cheaper, spectral_radius

__all__ = ["radau_chunk", "radau_jacobian", "radau_tolerances", "strategy_for", "R_SIZE", "NIT", "THET", "THET_COSTLY", "C", "P",
           "R_T", "R_H", "R_STORED", "R_NQ", "R_NV", "R_DETECT", "R_RHO", "R_NJEV", "R_NLU", "R_NFEV0", "R_STEPS",
           "R_RATE_D", "R_RATE_I", "R_HNEW", "R_FIRST", "R_NEED_JAC", "R_RHO0", "R_HDOP", "R_EDOP"]

C = np.asarray(_sr.C, float)
E = np.asarray(_sr.E, float)
P = np.ascontiguousarray(_sr.P, float)
T = np.ascontiguousarray(_sr.T, float)
TI = np.ascontiguousarray(_sr.TI, float)
TI_REAL = np.ascontiguousarray(_sr.TI_REAL, float)
TI_COMPLEX = np.ascontiguousarray(_sr.TI_COMPLEX, np.complex128)
MU_REAL = float(_sr.MU_REAL)
MU_COMPLEX = complex(_sr.MU_COMPLEX)

#: Newton iterations per attempt before the step is halved (RADAU5: 7).
NIT = 7
#: Contraction factor above which the Jacobian is recomputed after the step, for a cheap Jacobian
#: (:func:`strategy_for`): RADAU5's default.
THET = 0.001
#: ... and for a costly one (RADAU5's manual: "increase to 0.1 when Jacobian evaluations are costly").
THET_COSTLY = 0.1
#: Jacobian columns (differenced components) above which a Jacobian counts as costly: 20 evaluations,
#: about three steps' worth (a step takes ~7).
COSTLY_COLUMNS = 20


def strategy_for(columns: int) -> tuple[float, float, float]:
    """``(thet, quot1, quot2)`` of a system whose Jacobian differences ``columns`` components: RADAU5's
    defaults (:data:`THET`, :data:`QUOT1`, :data:`QUOT2`) up to :data:`COSTLY_COLUMNS`, its settings for
    costly Jacobians and large systems (:data:`THET_COSTLY`, :data:`QUOT_COSTLY`) beyond. Measured at
    rtol 1e-10 (evaluations, 0.001 -> 0.1, and the error against DOP853 at 1e-13): TIAGo dual (2n =
    202) 16 231 -> 3 557, 1.5e-10 -> 7.8e-11; TALOS full (2n = 88) 17 402 -> 7 816, 1.8e-9 -> 9.1e-10.
    On the stiff spring arm (2n = 6, whose stiff mode oscillates: -44 +- 2017i /s) 0.1 let the stale
    Jacobian's error estimate pass steps whose global error grew from 8 to 65 x rtol: a cheap Jacobian
    is kept fresh."""
    if columns <= COSTLY_COLUMNS:
        return THET, QUOT1, QUOT2
    return (THET_COSTLY, *QUOT_COSTLY)


SAFE, FACL, FACR = 0.9, 5.0, 0.125
CFAC = SAFE * (2 * NIT + 1)
#: The step is kept (and with it the factorisations) while ``QUOT1 <= h_new / h <= QUOT2`` (RADAU5's
#: defaults), ``QUOT_COSTLY`` for large systems (its manual: "for large full systems 0.99 and 2").
QUOT1, QUOT2 = 1.0, 1.2
QUOT_COSTLY = (0.99, 2.0)
#: The tolerance map ``rtol' = TOL_FACTOR rtol^TOL_EXP`` (:func:`radau_tolerances`).
TOL_FACTOR, TOL_EXP = 1.0, 5.0 / 6.0

# st: the loop's state between steps and chunks
R_T, R_H, R_STORED, R_HOLD, R_FIRST, R_REJECT, R_FACCON, R_THETA = 0, 1, 2, 3, 4, 5, 6, 7
R_DYNOLD, R_THQOLD, R_HACC, R_ERRACC, R_JAC_FRESH, R_NEED_JAC, R_LU_H, R_NACCPT = 8, 9, 10, 11, 12, 13, 14, 15
R_NSING, R_NUNEXP, R_NJEV, R_NLU, R_NQ, R_NV, R_DETECT, R_RHO = 16, 17, 18, 19, 20, 21, 22, 23
R_SINCE_J, R_NFEV0, R_STEPS, R_RATE_D, R_RATE_I, R_HNEW, R_HHFAC = 24, 25, 26, 27, 28, 29, 30
R_RHO0, R_HDOP, R_EDOP = 31, 32, 33
R_SIZE = 34


def radau_tolerances(rtol: float, atol):
    """The tolerances the error estimate is held to: ``(rtol', atol', fnewt)`` with ``rtol' =
    rtol^(5/6)``, ``atol' = atol rtol' / rtol`` and RADAU5's Newton tolerance ``fnewt = max(10 eps /
    rtol', min(0.03, rtol'^0.5))``. The estimate is of order 3 (``~h^4``) for a method of order 5:
    holding it at ``rtol^(5/6)`` makes the steps ``~rtol^(5/24)`` long and the global error (``~h^5``)
    come out near ``rtol^(25/24)``, i.e. near ``rtol``, as DOP853's does at the same ``rtol``. RADAU5
    itself maps ``rtol`` to ``0.1 rtol^(2/3)`` (for the local error): measured on the shipped spring arm
    at rtol 1e-10 (against DOP853 at 1e-13) that gives a global error of 3.8e-10 where DOP853 gives
    6.4e-11 and this map 1.0e-10; on the stiff spring arm 3.3e-9 against 7.7e-10 (docs/accuracy.md)."""
    r = TOL_FACTOR * rtol ** TOL_EXP
    a = np.asarray(atol, float) * (r / rtol)
    return r, a, max(10.0 * EPS / r, min(0.03, r ** 0.5))


# -- the structured linear algebra ------------------------------------------------------------------
@one_signature
@njit(cache=True)
def radau_jacobian(t, y, f, Jl, nq, nv, yp, fp, args, counters):
    """Forward differences (RADAU5's increments ``sqrt(eps max(1e-5, |y_j|))``, backward when the
    forward evaluation fails) of the right-hand side around ``(t, y)`` (``f = F(t, y)``) into
    ``Jl`` (nv + nw, nq + nv): the rows of ``v'`` and ``w'``, the columns of ``q`` and ``v`` (E59).
    False when no difference can be evaluated."""
    d = y.size
    for i in range(d):
        yp[i] = y[i]
    for j in range(nq + nv):
        delt = np.sqrt(EPS * max(1e-5, abs(y[j])))
        yp[j] = y[j] + delt
        if not evaluate(t, yp, fp, args, counters):
            yp[j] = y[j] - delt
            if not evaluate(t, yp, fp, args, counters):
                return False
        step = yp[j] - y[j]
        for i in range(nq, d):
            Jl[i - nq, j] = (fp[i] - f[i]) / step
        yp[j] = y[j]
    return True


@one_signature
@njit(cache=True)
def _factor(h, Jl, nq, nv, E1, p1, E2, p2):
    """The reduced iteration matrices ``g - J_v - J_q / g`` (E60) for ``g = MU_REAL / h`` (real) and
    ``MU_COMPLEX / h`` (complex), factored; False when one is singular."""
    g1 = MU_REAL / h
    g2 = MU_COMPLEX / h
    i1 = 1.0 / g1
    i2 = 1.0 / g2
    for i in range(nv):
        for j in range(nv):
            a = -Jl[i, nq + j]
            b = Jl[i, j] if nq > 0 else 0.0
            E1[i, j] = a - b * i1
            E2[i, j] = a - b * i2
        E1[i, i] += g1
        E2[i, i] += g2
    return lu_factor(E1, p1) < 0 and lu_factor(E2, p2) < 0


@one_signature
@njit(cache=True)
def _solve(g, Jl, nq, nv, E, piv, r, tmp):
    """``r`` (d,) <- ``(g - J)^-1 r`` with the factors of :func:`_factor` (E60): ``x_v`` from the
    reduced system, then ``x_q = (r_q + x_v) / g``, ``x_w = (r_w + J_w (x_q, x_v)) / g``."""
    d = r.size
    ig = 1.0 / g
    for i in range(nv):
        s = r[nq + i]
        for j in range(nq):
            s += Jl[i, j] * r[j] * ig
        tmp[i] = s
    lu_solve(E, piv, tmp)
    for i in range(nv):
        r[nq + i] = tmp[i]
    for i in range(nq):
        r[i] = (r[i] + r[nq + i]) * ig
    for k in range(d - nq - nv):
        s = r[nq + nv + k]
        for j in range(nq + nv):
            s += Jl[nv + k, j] * r[j]
        r[nq + nv + k] = s * ig


# -- one step ---------------------------------------------------------------------------------------
@one_signature
@njit(cache=True)
def _predict(st, h, Z, Q, prev):
    """Starting stages ``Z`` (3, d): zero on the first step, else the last step's collocation
    polynomial extrapolated to ``t + c_k h`` (minus the last step's increment ``prev``)."""
    d = prev.size
    if st[R_FIRST] != 0.0:
        for k in range(3):
            for i in range(d):
                Z[k, i] = 0.0
        return
    r = h / st[R_HOLD]
    for k in range(3):
        x = 1.0 + C[k] * r
        x2 = x * x
        x3 = x2 * x
        for i in range(d):
            Z[k, i] = Q[0, i] * x + Q[1, i] * x2 + Q[2, i] * x3 - prev[i]


@one_signature
@njit(cache=True)
def _newton(t, h, y, scal, fnewt, thet, st, arrays, lin, args, counters):
    """Simplified Newton iterations on the stage system from ``Z`` (RADAU5). Returns ``(code,
    iterations)``: 0 converged (``Z`` the stages), 1 divergence predicted (``st[R_HHFAC]`` the step
    factor), 2 too many iterations or no contraction, 3 the right-hand side failed at a stage."""
    Z, W, F, ystage, fr, fc, tmpr, tmpc = arrays
    Jl, E1, p1, E2, p2 = lin
    nq, nv = int(st[R_NQ]), int(st[R_NV])
    d = y.size
    g1 = MU_REAL / h
    g2 = MU_COMPLEX / h
    for i in range(d):
        for k in range(3):
            W[k, i] = TI[k, 0] * Z[0, i] + TI[k, 1] * Z[1, i] + TI[k, 2] * Z[2, i]
    faccon = max(st[R_FACCON], EPS) ** 0.8
    theta = thet
    newt = 0
    code = 2
    while newt < NIT:
        failed = False
        for k in range(3):
            for i in range(d):
                ystage[i] = y[i] + Z[k, i]
            if not evaluate(t + C[k] * h, ystage, F[k], args, counters):
                failed = True
                break
        if failed:
            code = 3
            break
        for i in range(d):
            fr[i] = F[0, i] * TI_REAL[0] + F[1, i] * TI_REAL[1] + F[2, i] * TI_REAL[2] - g1 * W[0, i]
            fc[i] = (F[0, i] * TI_COMPLEX[0] + F[1, i] * TI_COMPLEX[1] + F[2, i] * TI_COMPLEX[2]
                     - g2 * (W[1, i] + 1j * W[2, i]))
        _solve(g1, Jl, nq, nv, E1, p1, fr, tmpr)
        _solve(g2, Jl, nq, nv, E2, p2, fc, tmpc)
        newt += 1
        dyno = 0.0
        for i in range(d):
            a = fr[i] / scal[i]
            b = fc[i].real / scal[i]
            c = fc[i].imag / scal[i]
            dyno += a * a + b * b + c * c
        dyno = np.sqrt(dyno / (3 * d))
        if 1 < newt < NIT:
            thq = dyno / st[R_DYNOLD]
            theta = thq if newt == 2 else np.sqrt(thq * st[R_THQOLD])
            st[R_THQOLD] = thq
            if not theta < 0.99:
                break
            faccon = theta / (1.0 - theta)
            dyth = faccon * dyno * theta ** (NIT - 1 - newt) / fnewt
            if dyth >= 1.0:
                qnewt = max(1e-4, min(20.0, dyth))
                st[R_HHFAC] = 0.8 * qnewt ** (-1.0 / (4.0 + NIT - 1 - newt))
                code = 1
                break
        st[R_DYNOLD] = max(dyno, EPS)
        for i in range(d):
            W[0, i] += fr[i]
            W[1, i] += fc[i].real
            W[2, i] += fc[i].imag
            for k in range(3):
                Z[k, i] = T[k, 0] * W[0, i] + T[k, 1] * W[1, i] + T[k, 2] * W[2, i]
        # never after one iteration: a stale Jacobian's small first correction would pass for convergence
        if faccon * dyno <= fnewt and newt > 1:
            code = 0
            break
    st[R_FACCON] = faccon
    st[R_THETA] = theta
    return code, newt


@one_signature
@njit(cache=True)
def _error(t, h, y, f0, scal, refine, st, arrays, lin, args, counters):
    """RADAU5's error estimate ``(g1 - J)^-1 (F(t, y) + Z E / h)`` in units of ``scal`` (rms, at least
    1e-10); with ``refine`` and an estimate >= 1, once more from ``F(t, y + err)``. -1 when that
    evaluation fails."""
    Z, W, F, ystage, fr, fc, tmpr, tmpc = arrays
    Jl, E1, p1, E2, p2 = lin
    nq, nv = int(st[R_NQ]), int(st[R_NV])
    d = y.size
    g1 = MU_REAL / h
    for i in range(d):
        fr[i] = f0[i] + (E[0] * Z[0, i] + E[1] * Z[1, i] + E[2] * Z[2, i]) / h
    _solve(g1, Jl, nq, nv, E1, p1, fr, tmpr)
    err = 0.0
    for i in range(d):
        v = fr[i] / scal[i]
        err += v * v
    err = max(np.sqrt(err / d), 1e-10)
    if err < 1.0 or not refine:
        return err
    for i in range(d):
        ystage[i] = y[i] + fr[i]
    if not evaluate(t, ystage, F[0], args, counters):
        return -1.0
    for i in range(d):
        fr[i] = F[0, i] + (E[0] * Z[0, i] + E[1] * Z[1, i] + E[2] * Z[2, i]) / h
    _solve(g1, Jl, nq, nv, E1, p1, fr, tmpr)
    err = 0.0
    for i in range(d):
        v = fr[i] / scal[i]
        err += v * v
    return max(np.sqrt(err / d), 1e-10)


@one_signature
@njit(cache=True)
def _new_matrices(t, y, f0, st, arrays, lin, args, counters):
    """A fresh Jacobian when one is due (with ``rho`` in ``auto``), and the factorisations for the
    step ``st[R_H]``. Returns 0, -2 (the Jacobian's evaluations failed) or 1 (singular: the step
    was halved, try again)."""
    Z, W, F, ystage, fr, fc, tmpr, tmpc = arrays
    Jl, E1, p1, E2, p2 = lin
    nq, nv = int(st[R_NQ]), int(st[R_NV])
    h = st[R_H]
    if st[R_NEED_JAC] != 0.0:
        if not radau_jacobian(t, y, f0, Jl, nq, nv, ystage, F[0], args, counters):
            return -2
        st[R_NJEV] += 1.0
        st[R_JAC_FRESH] = 1.0
        st[R_NEED_JAC] = 0.0
        st[R_LU_H] = 0.0
        st[R_SINCE_J] = 0.0
        if st[R_DETECT] != 0.0:
            st[R_RHO] = spectral_radius(Jl, nq, nv, F[1], F[2])
            if st[R_RHO0] < 0.0:
                st[R_RHO0] = st[R_RHO]
    if st[R_LU_H] != h:
        if not _factor(h, Jl, nq, nv, E1, p1, E2, p2):
            st[R_NSING] += 1.0
            st[R_H] = 0.5 * h
            st[R_REJECT] = 1.0
            st[R_LU_H] = 0.0
            if st[R_JAC_FRESH] == 0.0:
                st[R_NEED_JAC] = 1.0
            return 1
        st[R_LU_H] = h
        st[R_NLU] += 1.0
    return 0


@one_signature
@njit(cache=True)
def _accept(t, h, last, err, quot, y, f0, ctl, st, arrays, dense3, args, counters):
    """The accepted step: the new state and slope, the dense coefficients ``Q`` and the next step
    size (Gustafsson's controller, kept when ``1 <= h_new / h <= 1.2`` and the Jacobian is good).
    False when the slope at the new state cannot be evaluated."""
    t_end, max_step = ctl[0], ctl[3]
    Z, W, F, ystage, fr, fc, tmpr, tmpc = arrays
    Q, prev = dense3
    d = y.size
    st[R_FIRST] = 0.0
    st[R_NACCPT] += 1.0
    st[R_SINCE_J] += 1.0
    if st[R_NACCPT] > 1.0:
        facgus = st[R_HACC] / h * (err * err / st[R_ERRACC]) ** 0.25 / SAFE
        quot = max(quot, max(FACR, min(FACL, facgus)))
    hnew = h / quot
    st[R_HACC] = h
    st[R_ERRACC] = max(0.01, err)
    for i in range(d):
        prev[i] = Z[2, i]
        y[i] += Z[2, i]
        for k in range(3):
            Q[k, i] = Z[0, i] * P[0, k] + Z[1, i] * P[1, k] + Z[2, i] * P[2, k]
    t_new = t_end if last else t + h
    st[R_HOLD] = h
    st[R_T] = t_new
    st[R_JAC_FRESH] = 0.0
    st[R_NSING] = 0.0
    st[R_NUNEXP] = 0.0
    if t_new < t_end and not evaluate(t_new, y, f0, args, counters):
        return False
    hnew = min(hnew, max_step)
    if st[R_REJECT] != 0.0:
        hnew = min(hnew, h)
        st[R_REJECT] = 0.0
    st[R_HNEW] = hnew
    qt = hnew / h
    if st[R_THETA] <= ctl[6] and ctl[7] <= qt <= ctl[8]:
        return True                          # same h, same factorisations
    st[R_H] = hnew
    if st[R_THETA] > ctl[6]:
        st[R_NEED_JAC] = 1.0
    return True


@one_signature
@njit(cache=True)
def _step(ctl, st, y, f0, scal, arrays, dense3, lin, args, counters):
    """Attempts from ``st[R_T]`` until one is accepted (RADAU5's control flow). Returns 0, or -1
    (step size below the spacing of floats at ``t``), -2 (the right-hand side failed repeatedly, or
    at an accepted state), -4 (the iteration matrix stayed singular)."""
    t_end, max_step, fnewt = ctl[0], ctl[3], ctl[5]
    Z = arrays[0]
    Q, prev = dense3
    cnt = counters[0]
    t = st[R_T]
    while True:
        h = min(st[R_H], max_step)
        last = t + 1.0001 * h >= t_end
        if last:
            h = t_end - t
        if not (0.1 * h > abs(t) * EPS and h > 0.0):
            return -1
        st[R_H] = h
        code = _new_matrices(t, y, f0, st, arrays, lin, args, counters)
        if code == -2:
            return -2
        if code == 1:
            if st[R_NSING] >= 5.0:
                return -4
            cnt[2] += 1
            continue
        _predict(st, h, Z, Q, prev)
        code, newt = _newton(t, h, y, scal, fnewt, ctl[6], st, arrays, lin, args, counters)
        err = 0.0
        if code == 0:
            err = _error(t, h, y, f0, scal, st[R_FIRST] != 0.0 or st[R_REJECT] != 0.0, st, arrays, lin, args,
                         counters)
            if err < 0.0:
                code = 3
        if code != 0:                       # unexpected rejection: a smaller step
            cnt[2] += 1
            if code == 3:
                st[R_NUNEXP] += 1.0
                if st[R_NUNEXP] >= 10.0:
                    return -2
            st[R_H] = h * (st[R_HHFAC] if code == 1 else 0.5)
            st[R_REJECT] = 1.0
            if st[R_JAC_FRESH] == 0.0:
                st[R_NEED_JAC] = 1.0
            continue
        fac = min(SAFE, CFAC / (newt + 2 * NIT))
        quot = max(FACR, min(FACL, err ** 0.25 / fac))
        if err < 1.0:
            if not _accept(t, h, last, err, quot, y, f0, ctl, st, arrays, dense3, args, counters):
                return -2
            return 0
        cnt[2] += 1
        st[R_REJECT] = 1.0
        st[R_H] = 0.1 * h if st[R_FIRST] != 0.0 else h / quot
        if st[R_JAC_FRESH] == 0.0:
            st[R_NEED_JAC] = 1.0


@one_signature
@njit(cache=True)
def radau_chunk(ctl, state, store, guard, counters, chunk, args):
    """Up to ``chunk`` accepted steps of Radau IIA (5).

    ``ctl = (t_end, rtol', atol' (d,), max_step, dense, fnewt, thet, quot1, quot2)`` (tolerances mapped by
    :func:`radau_tolerances`); ``state = (st, y, f0, arrays, dense3, lin)``: ``st`` (:data:`R_SIZE`,)
    the loop's state (``R_*``), ``y``, ``f0`` (d,) the state and its slope, ``arrays = (Z, W, F
    (3, d), ystage, fr (d,), fc (d,) complex, tmpr (nv,), tmpc (nv,) complex)``, ``dense3 = (Q (3, d),
    prev (d,))`` the last step's polynomial and increment, ``lin = (Jl (nv + nw, nq + nv), E1 (nv,
    nv), p1 (nv,), E2 (nv, nv) complex, p2 (nv,))``; ``store = (ts (cap,), ys (cap, d), dens (cap,
    3, d))``: each step's collocation polynomial ``Q``. With ``st[R_DETECT]`` (``auto``) the loop also ends with status 5 when DOP853 would be
    cheaper (:func:`~urdf2links.integration.loops.stiffness.explicit_cheaper`). Returns the status."""
    rtol, atol, dense = ctl[1], ctl[2], ctl[4]
    st, y, f0, arrays, dense3, lin = state
    ts, ys, dens = store
    cnt = counters[0]
    d = y.size
    scal = np.empty(d)
    stored = int(st[R_STORED])
    taken = 0
    status = 0
    while taken < chunk and stored < ts.size:
        for i in range(d):
            scal[i] = atol[i] + rtol * abs(y[i])
        status = _step(ctl, st, y, f0, scal, arrays, dense3, lin, args, counters)
        if status != 0:
            break
        if has_rows(args) and not project(st[R_T], y, f0, args, counters):     # issue 45: (E74)
            status = -2
            break
        ts[stored] = st[R_T]
        for i in range(d):
            ys[stored, i] = y[i]
        if dense:
            Q = dense3[0]
            for k in range(3):
                for i in range(d):
                    dens[stored, k, i] = Q[k, i]
        stored += 1
        taken += 1
        cnt[1] += 1
        st[R_STEPS] += 1.0
        if st[R_T] >= ctl[0]:
            status = 1
            break
        if guard_fires(y, guard):
            status = 2
            break
        if st[R_DETECT] != 0.0:
            if st[R_SINCE_J] >= JAC_REFRESH:
                st[R_NEED_JAC] = 1.0
            if st[R_STEPS] >= MIN_IMPLICIT_STEPS and st[R_RHO] >= 0.0:
                cheaper, dop, imp = explicit_cheaper(st[R_RHO], st[R_RHO0], st[R_HDOP], st[R_EDOP],
                                                     (cnt[0] - st[R_NFEV0]) / st[R_STEPS],
                                                     max(st[R_HOLD], st[R_HNEW]), ctl[3])
                st[R_RATE_D], st[R_RATE_I] = dop, imp
                if cheaper:
                    status = 5
                    break
    st[R_STORED] = stored
    cnt[3] = status
    return status

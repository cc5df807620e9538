"""scipy's explicit Runge-Kutta pairs RK45 and DOP853, compiled with numba, step for step.

The tableaux are scipy's; so are the initial step selection, the error norms, the step-size
controller and the dense output (RK45's quartic, DOP853's seventh-degree polynomial with its three
extra stages). scipy itself is their reference in the tests.
"""

from __future__ import annotations

import importlib.util
from collections import namedtuple
from collections.abc import Mapping
from pathlib import Path

import numpy as np
from numba import njit

from ...compilation import one_signature
from .common import evaluate, guard_fires, has_rows, project, rms
from .stiffness import E_DETECT, explicit_stiff

__all__ = ["Tableau", "TABLEAUX", "initial_step", "erk_chunk"]

SAFETY, MIN_FACTOR, MAX_FACTOR = 0.9, 0.2, 10.0

Tableau = namedtuple("Tableau", ["stages", "order", "A", "B", "C", "E5", "E3", "D", "P", "n_dense", "dop"])
"""An explicit pair, padded to DOP853's 16 extended stages: ``A`` (16, 16), ``B`` (s,), ``C`` (16,),
error weights ``E5``, ``E3`` (13,), DOP853's dense matrix ``D`` (4, 16), RK45's ``P`` (16, 7);
``dop`` selects DOP853's error norm and dense output."""


def _tableau_rk45() -> Tableau:
    from scipy.integrate._ivp.rk import RK45 as _RK45

    A = np.zeros((16, 16))
    A[:6, :5] = _RK45.A
    C = np.zeros(16)
    C[:6] = _RK45.C
    E = np.zeros(13)
    E[:7] = _RK45.E
    P = np.zeros((16, 7))
    P[:7, :4] = _RK45.P
    return Tableau(6, 4, A, np.r_[_RK45.B, np.zeros(6)], C, E, np.zeros(13), np.zeros((4, 16)), P, 4, False)


def _scipy_dop853():
    """scipy's DOP853 coefficients (``scipy/integrate/_ivp/dop853_coefficients.py``: numpy arrays and
    nothing else), loaded from their file: importing them as a module of ``scipy.integrate`` would
    import that whole package first (half a second of every command's start)."""
    root = Path(importlib.util.find_spec("scipy").submodule_search_locations[0])
    spec = importlib.util.spec_from_file_location("urdf2links_scipy_dop853_coefficients",
                                                  root / "integrate" / "_ivp" / "dop853_coefficients.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _tableau_dop853() -> Tableau:
    _dop = _scipy_dop853()
    return Tableau(12, 7, np.ascontiguousarray(_dop.A, dtype=float), np.asarray(_dop.B, float),
                   np.asarray(_dop.C, float), np.asarray(_dop.E5, float), np.asarray(_dop.E3, float),
                   np.ascontiguousarray(_dop.D, dtype=float), np.zeros((16, 7)), 7, True)


class _Tableaux(Mapping):
    """The pairs by name, each built at its first use (RK45's from scipy's class, which imports
    ``scipy.integrate``)."""

    _BUILD = {"RK45": _tableau_rk45, "DOP853": _tableau_dop853}

    def __init__(self):
        self._built = {}

    def __getitem__(self, name) -> Tableau:
        if name not in self._built:
            self._built[name] = self._BUILD[name]()
        return self._built[name]

    def __iter__(self):
        return iter(self._BUILD)

    def __len__(self):
        return len(self._BUILD)


TABLEAUX = _Tableaux()


@one_signature
@njit(cache=True)
def initial_step(t0, y0, f0, t_end, max_step, order, rtol, atol, args, counters):
    """scipy's ``select_initial_step`` (Hairer, Norsett, Wanner I, II.4)."""
    d = y0.size
    interval = abs(t_end - t0)
    scale = np.empty(d)
    for i in range(d):
        scale[i] = atol[i] + abs(y0[i]) * rtol
    d0 = rms(y0, scale)
    d1 = rms(f0, scale)
    h0 = 1e-6 if (d0 < 1e-5 or d1 < 1e-5) else 0.01 * d0 / d1
    h0 = min(h0, interval)
    y1 = y0 + h0 * f0
    f1 = np.empty(d)
    evaluate(t0 + h0, y1, f1, args, counters)
    d2 = rms(f1 - f0, scale) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (1.0 / (order + 1))
    return min(100 * h0, h1, interval, max_step)


# -- RK45 / DOP853 ----------------------------------------------------------------------------------
@one_signature
@njit(cache=True)
def _stages(tab, first, last, t, h, y, K, ystage, args, counters):
    """Stages ``first .. last - 1``: ``K[s] = F(t + C_s h, y + h sum_j A_sj K[j])``."""
    d = y.size
    for s in range(first, last):
        for i in range(d):
            acc = 0.0
            for j in range(s):
                acc += K[j, i] * tab.A[s, j]
            ystage[i] = y[i] + acc * h
        if not evaluate(t + tab.C[s] * h, ystage, K[s], args, counters):
            return False
    return True


@one_signature
@njit(cache=True)
def _error_norm(tab, h, K, scale, err5, err3):
    """The pair's error estimate in units of ``scale`` (scipy's norms: RK45 rms, DOP853's
    blend of its fifth- and third-order estimates)."""
    d = scale.size
    if tab.dop:
        n5 = 0.0
        n3 = 0.0
        for i in range(d):
            a5 = 0.0
            a3 = 0.0
            for j in range(tab.stages + 1):
                a5 += K[j, i] * tab.E5[j]
                a3 += K[j, i] * tab.E3[j]
            err5[i] = a5 / scale[i]
            err3[i] = a3 / scale[i]
        for i in range(d):
            n5 += err5[i] * err5[i]
            n3 += err3[i] * err3[i]
        if n5 == 0.0 and n3 == 0.0:
            return 0.0
        return abs(h) * n5 / np.sqrt((n5 + 0.01 * n3) * d)
    for i in range(d):
        a5 = 0.0
        for j in range(tab.stages + 1):
            a5 += K[j, i] * tab.E5[j]
        err5[i] = a5 * h
    return rms(err5, scale)


@one_signature
@njit(cache=True)
def _attempt(tab, ctl, t, h_abs, y, f, K, work, args, counters):
    """Steps from ``t`` until one is accepted: returns ``(status, t_new, h, h_abs)`` with the next
    step size ``h_abs`` from the controller; ``work[0]``, ``work[1]`` hold ``y_new``, ``f_new``."""
    t_end, rtol, atol = ctl[0], ctl[1], ctl[2]
    y_new, f_new, ystage, scale, err5, err3 = work
    cnt = counters[0]
    d = y.size
    exponent = -1.0 / (tab.order + 1)
    min_step = 10.0 * abs(np.nextafter(t, np.inf) - t)
    rejected = False
    while True:
        if h_abs < min_step:
            return -1, t, 0.0, h_abs
        t_new = t + h_abs
        if t_new - t_end > 0:
            t_new = t_end
        h = t_new - t
        h_abs = abs(h)
        for i in range(d):
            K[0, i] = f[i]
        ok = _stages(tab, 1, tab.stages, t, h, y, K, ystage, args, counters)
        if ok:
            for i in range(d):
                acc = 0.0
                for j in range(tab.stages):
                    acc += K[j, i] * tab.B[j]
                y_new[i] = y[i] + h * acc
            ok = evaluate(t + h, y_new, f_new, args, counters)
        if not ok:               # a trial step through a non-finite stage (an unstable step size on a stiff
            h_abs *= MIN_FACTOR  # scene): rejected with the smallest factor, as scipy's NaN error norm does
            rejected = True
            cnt[2] += 1
            continue
        for i in range(d):
            K[tab.stages, i] = f_new[i]
            scale[i] = atol[i] + max(abs(y[i]), abs(y_new[i])) * rtol
        error_norm = _error_norm(tab, h, K, scale, err5, err3)
        if error_norm < 1.0:
            factor = MAX_FACTOR if error_norm == 0.0 else min(MAX_FACTOR, SAFETY * error_norm ** exponent)
            if rejected:
                factor = min(1.0, factor)
            return 0, t_new, h, h_abs * factor
        h_abs *= max(MIN_FACTOR, SAFETY * error_norm ** exponent)
        rejected = True
        cnt[2] += 1


@one_signature
@njit(cache=True)
def _dense_row(tab, t, h, y, y_new, f_new, K, ystage, row, args, counters):
    """The dense-output coefficients (n_dense, d) of the accepted step into ``row`` (DOP853's three
    extra stages evaluated here)."""
    d = y.size
    if not tab.dop:
        for r in range(tab.n_dense):
            for i in range(d):
                acc = 0.0
                for j in range(tab.stages + 1):
                    acc += K[j, i] * tab.P[j, r]
                row[r, i] = acc
        return True
    if not _stages(tab, tab.stages + 1, 16, t, h, y, K, ystage, args, counters):
        return False
    for i in range(d):
        dy = y_new[i] - y[i]
        row[0, i] = dy
        row[1, i] = h * K[0, i] - dy
        row[2, i] = 2.0 * dy - h * (f_new[i] + K[0, i])
    for r in range(4):
        for i in range(d):
            acc = 0.0
            for j in range(16):
                acc += tab.D[r, j] * K[j, i]
            row[3 + r, i] = h * acc
    return True


@one_signature
@njit(cache=True)
def erk_chunk(tab, ctl, state, store, guard, counters, chunk, args):
    """Up to ``chunk`` accepted steps of an explicit pair.

    ``tab`` a :data:`Tableau`; ``ctl = (t_end, rtol, atol (d,), max_step, dense)``; ``state =
    (st, y, f, K)`` with ``st = [t, h_abs, stored]``, ``y``, ``f`` (d,) the current state and
    slope, ``K`` (16, d) the stages (all in/out); ``store = (ts (cap,), ys (cap, d), dens (cap,
    n_dense, d))`` the accepted steps and the dense-output rows of the step ending there;
    ``guard = (indices, thresholds)``; ``counters = (cnt, fail)`` with ``cnt = [nfev, nsteps,
    nrejected, status]``. With ``st`` longer than three and ``st[E_DETECT]`` set (``auto``), Hairer's
    stiffness test runs after every accepted step (:func:`~urdf2links.integration.loops.stiffness.explicit_stiff`)
    and a stiff verdict ends the chunk with status 4 after storing the step. Returns the status."""
    max_step, dense = ctl[3], ctl[4]
    st, y, f, K = state
    ts, ys, dens = store
    cnt = counters[0]
    d = y.size
    work = (np.empty(d), np.empty(d), np.empty(d), np.empty(d), np.empty(d), np.empty(d))
    y_new, f_new, ystage = work[0], work[1], work[2]
    t, h_abs, stored = st[0], st[1], int(st[2])
    detect = st.size > E_DETECT and st[E_DETECT] != 0.0
    taken = 0
    status = 0
    while taken < chunk and stored < ts.size:
        min_step = 10.0 * abs(np.nextafter(t, np.inf) - t)
        if h_abs > max_step:
            h_abs = max_step
        elif h_abs < min_step:
            h_abs = min_step
        status, t_new, h, h_abs = _attempt(tab, ctl, t, h_abs, y, f, K, work, args, counters)
        if status != 0:
            break
        stiff = detect and explicit_stiff(st, h, y_new, f_new, f, ystage, K[tab.stages - 1])
        if dense and not _dense_row(tab, t, h, y, y_new, f_new, K, ystage, dens[stored], args, counters):
            status = -2
            break
        t = t_new
        for i in range(d):
            y[i] = y_new[i]
            f[i] = f_new[i]
        if has_rows(args) and not project(t, y, f, args, counters):    # issue 45: onto the constraints (E74)
            status = -2
            break
        for i in range(d):
            ys[stored, i] = y[i]
        ts[stored] = t
        stored += 1
        taken += 1
        cnt[1] += 1
        if t >= ctl[0]:
            status = 1
            break
        if guard_fires(y, guard):
            status = 2
            break
        if stiff:
            status = 4
            break
    st[0], st[1], st[2] = t, h_abs, stored
    cnt[3] = status
    return status

"""One method's stretch of steps: an explicit pair (:func:`run_erk`) or Radau5 (:func:`run_radau`) from ``(t0, y0)``
through its compiled chunks until its status says stop, the storage grown as it goes.

The driver (:mod:`.driver`) runs one stretch per integration; ``auto`` (:mod:`.auto`) alternates them. Both call
these with the same driver state ``drv`` (counters, budgets, guard and callback); this module sits below both.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from ..dense import DenseOutput
from . import radau
from .radau import R_FIRST, R_NEED_JAC, R_NQ, R_NV, R_SIZE, R_STORED, R_T, radau_tolerances
from .stiffness import E_DETECT, E_ND, E_NEEDED, E_SIZE

__all__ = ["Stretch", "run_erk", "run_radau", "grow"]

Stretch = namedtuple("Stretch", ["status", "t", "y", "sol", "st", "f", "njev"])
"""One loop's run from a state until its status says stop: ``t`` (m,), ``y`` (m, d) its steps (the
first the starting state), ``sol`` its dense output (or None), ``st`` its state array (``h``,
counters and stiffness figures), ``f`` the slope at the last state, ``njev`` Jacobians."""


def grow(arrays, extra):
    """The storage ``arrays`` each with ``extra`` more rows (uninitialised)."""
    return tuple(np.concatenate([a, np.empty((extra,) + a.shape[1:])]) for a in arrays)


def run_erk(drv, loops, tab, args, f0, t0, t1, y0, rtol, atol, dt, need_dense, *, h0=None, stiff_tests=0,
            nd=0) -> Stretch:
    """An explicit pair from ``(t0, y0)`` (slope ``f0``) until its status says stop; ``h0`` the first
    step (default: scipy's initial step); ``stiff_tests`` > 0 turns on the stiffness test over the
    first ``nd`` components, which ends the stretch (status 4) after that many stiff verdicts."""
    d = y0.size
    max_step = np.inf if dt is None else float(dt)
    h_abs = drv.call(loops, "initial_step", t0, y0, f0, t1, max_step, tab.order, rtol, atol, args,
                                      drv.counters) if h0 is None \
        else min(float(h0), max_step)
    cap = 256
    ts, ys, dens = np.empty(cap), np.empty((cap, d)), np.empty((cap if need_dense else 0, tab.n_dense, d))
    ts[0], ys[0] = t0, y0
    st = np.zeros(E_SIZE if stiff_tests else 3)
    st[:3] = t0, h_abs, 1.0
    if stiff_tests:
        st[E_DETECT], st[E_NEEDED], st[E_ND] = 1.0, float(stiff_tests), float(nd)
    state = (st, y0.copy(), f0.copy(), np.zeros((16, d)))
    ctl = (float(t1), rtol, atol, max_step, need_dense)
    while True:
        status = drv.call(loops, "erk_chunk", tab, ctl, state, (ts, ys, dens), drv.guard, drv.counters, drv.size(), args)
        if drv.after_chunk(status, st[0], state[1]):
            break
        if int(st[2]) >= ts.size:
            ts, ys = grow((ts, ys), ts.size)
            if need_dense:
                (dens,) = grow((dens,), dens.shape[0])
    m = int(st[2])
    sol = DenseOutput(ts[:m], ys[:m], poly=("DOP853" if tab.dop else "RK45", dens[:m])) if need_dense and m > 1 else None
    return Stretch(status, ts[:m], ys[:m], sol, st, state[2], 0)


def run_radau(drv, loops, args, f0, t0, t1, y0, rtol, atol, dt, need_dense, structure, *, h0=None,
              detect=None) -> Stretch:
    """Radau5 (:mod:`.radau`) from ``(t0, y0)`` until its status says stop; ``structure = (nq, nv)``;
    ``h0`` the first step (default: scipy's initial step for an error of order 3 at the mapped
    tolerances); ``detect = (h_D, e_D)`` (``auto``: DOP853's last step and evaluations per step when
    it handed over) ends the stretch (status 5) when DOP853 would be cheaper."""
    d = y0.size
    nq, nv = structure
    r, a, fnewt = radau_tolerances(rtol, atol)
    max_step = np.inf if dt is None else float(dt)
    if h0 is None:
        h0 = drv.call(loops, "initial_step", t0, y0, f0, t1, max_step, 3, r, a, args, drv.counters)
    st = np.zeros(R_SIZE)
    st[R_T], st[1], st[R_STORED], st[R_FIRST], st[R_NEED_JAC] = t0, min(float(h0), max_step), 1.0, 1.0, 1.0
    st[radau.R_FACCON], st[radau.R_ERRACC], st[R_NQ], st[R_NV] = 1.0, 0.01, nq, nv
    st[radau.R_DETECT], st[radau.R_RHO], st[radau.R_RHO0] = float(detect is not None), -1.0, -1.0
    st[radau.R_NFEV0] = float(drv.cnt[0])
    if detect is not None:
        st[radau.R_HDOP], st[radau.R_EDOP] = detect
    arrays = (np.zeros((3, d)), np.zeros((3, d)), np.zeros((3, d)), np.empty(d), np.empty(d),
              np.empty(d, np.complex128), np.empty(nv), np.empty(nv, np.complex128))
    lin = (np.zeros((d - nq, nq + nv)), np.empty((nv, nv)), np.zeros(nv, np.int64),
           np.empty((nv, nv), np.complex128), np.zeros(nv, np.int64))
    y = y0.copy()
    f = f0.copy()
    state = (st, y, f, arrays, (np.zeros((3, d)), np.zeros(d)), lin)
    ctl = (float(t1), r, a, max_step, need_dense, fnewt, *radau.strategy_for(nq + nv))
    cap = 256
    ts, ys, dens = np.empty(cap), np.empty((cap, d)), np.empty((cap if need_dense else 0, 3, d))
    ts[0], ys[0] = t0, y0
    while True:
        status = drv.call(loops, "radau_chunk", ctl, state, (ts, ys, dens), drv.guard, drv.counters, drv.size(), args)
        if drv.after_chunk(status, st[R_T], y):
            break
        if int(st[R_STORED]) >= ts.size:
            ts, ys = grow((ts, ys), ts.size)
            if need_dense:
                (dens,) = grow((dens,), dens.shape[0])
    m = int(st[R_STORED])
    sol = DenseOutput(ts[:m], ys[:m], poly=("Radau5", dens[:m])) if need_dense and m > 1 else None
    return Stretch(status, ts[:m], ys[:m], sol, st, f, int(st[radau.R_NJEV]))

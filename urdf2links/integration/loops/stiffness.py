"""Stiffness in both directions, for ``method = "auto"``: when DOP853's step is held by the stiff
modes, and when the implicit loop's step is long enough that DOP853 would be cheaper.

**Explicit -> implicit** (Hairer's test in DOP853; Hairer, Norsett & Wanner I, IV.2 and the code
``dop853.f``): after an accepted step of length ``h``, the last stage (at ``t + h``, argument
``y_12``) and the new solution give a Rayleigh-like estimate of the dominant eigenvalue's size,

    h |lambda| ~ h ||F(t + h, y_new) - F(t + h, y_12)|| / ||y_new - y_12||          (E58)

(over the components that feed back: ``q`` and ``q'``, not the work ``W``). A step set by accuracy
keeps ``h |lambda|`` small; a step held by a stiff mode sits near the edge of DOP853's stability
region, ~6.1 on the negative real axis (Hairer's threshold). At the tolerances scenes use the
controller settles lower: measured medians of ``h |lambda|`` on the hard case's 1e6 N m/rad servo
6.4 at rtol 1e-6, 4.3 at 1e-10, 1.1 at 1e-12 (on ``y' = -1e5 (y - cos t)``: 6.4, 5.8, 3.6), while on
the shipped non-stiff scenes at rtol 1e-3 to 1e-12 at most a few percent of the steps exceed 3. A
mildly stiff scene at a tight tolerance keeps ``h |lambda|`` near 1, like a non-stiff one (a joint
damped at 100 N m s/rad on the spring arm, rtol 1e-10: median 0.73; the shipped spring arm: 0.96),
and DOP853 still pays for the stiff mode (15x the evaluations of the undamped arm). What tells them
apart is how slowly the solution moves compared with ``|lambda|``, the stiffness ratio

    S = |lambda| / (|F(t + h) - F(t)| / (h |F(t + h)|))                               (E58)

(median 93 on that damped arm, 930 at 1000 N m s/rad; at most 25 on the shipped scenes, their 90th
percentile at most 70). A test is stiff when ``h |lambda| >`` :data:`STIFF_HLAMBDA` = 3.0, or when
``h |lambda| >`` :data:`RATIO_HLAMBDA` = 0.3 and ``S >`` :data:`STIFF_RATIO` = 100; the run is stiff
after :data:`STIFF_TESTS` stiff tests without :data:`NONSTIFF_RESET` consecutive others (which reset
the count): Hairer's counting rule (docs/accuracy.md, the stiffness test).

**Implicit -> explicit** (a cost comparison, as LSODA's switching makes one): DOP853's cost when it
handed over is known (its last step ``h_D`` and its evaluations per step ``e_D`` over the stretch);
whenever the implicit loop has a Jacobian ``J`` it estimates its spectral radius ``rho``
(:func:`spectral_radius`, power iteration on the ``(q, q')`` block) and predicts DOP853's step as
``h_D rho_0 / rho`` (``rho_0`` the first estimate of the stretch: the explicit step scales with
``1 / |lambda|``), so DOP853 would cost ``e_D rho / (h_D rho_0)`` evaluations per second of
simulated time against the implicit loop's own ``e / h`` (evaluations per accepted step in this
stretch, Jacobians included, over its step). DOP853 takes over when it would cost less than
:data:`SWITCH_BACK` times as much (its step also capped by the run's maximum step).

Against chattering, each return to DOP853 that the cost comparison ordered multiplies the number of
stiff tests needed for the next switch by :data:`BACKOFF` (15, 60, 240, ...).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ...compilation import one_signature

__all__ = ["STIFF_HLAMBDA", "STIFF_RATIO", "RATIO_HLAMBDA", "STIFF_TESTS", "NONSTIFF_RESET", "SWITCH_BACK", "BACKOFF",
           "MIN_IMPLICIT_STEPS", "JAC_REFRESH", "E_DETECT", "E_IASTI", "E_NONSTI", "E_HLAMB", "E_NEEDED", "E_ND",
           "E_HMAX", "E_HSUM", "E_RATIO", "E_SIZE", "explicit_stiff", "spectral_radius", "explicit_cheaper"]

#: ``h |lambda|`` above which a step counts as held by a stiff mode (Hairer's 6.1 lowered: module doc).
STIFF_HLAMBDA = 3.0
#: The stiffness ratio ``|lambda| / (|F'| / |F|)`` above which a step with ``h |lambda|`` over
#: :data:`RATIO_HLAMBDA` counts as held by a stiff mode (module doc).
STIFF_RATIO = 100.0
RATIO_HLAMBDA = 0.3
#: Stiff tests above the threshold before the run is called stiff (``dop853.f``: 15).
STIFF_TESTS = 15
#: Consecutive tests below the threshold that reset the count (``dop853.f``: 6).
NONSTIFF_RESET = 6
#: DOP853 takes over when it would cost less than this fraction of the implicit loop's evaluations.
SWITCH_BACK = 0.5
#: Each cost-ordered return to DOP853 multiplies the stiff tests needed next time by this.
BACKOFF = 4.0
#: The implicit loop's accepted steps in a stretch before its cost is compared.
MIN_IMPLICIT_STEPS = 10
#: In ``auto``, the implicit loop refreshes its Jacobian (and ``rho``) at least every so many steps.
JAC_REFRESH = 100

# The explicit loop's ``st`` beyond ``[t, h_abs, stored]`` (the batch loop passes only those three):
E_DETECT, E_IASTI, E_NONSTI, E_HLAMB, E_NEEDED, E_ND, E_HMAX, E_HSUM, E_RATIO = 3, 4, 5, 6, 7, 8, 9, 10, 11
E_SIZE = 12


@one_signature
@njit(cache=True)
def explicit_stiff(st, h, y_new, f_new, f_old, y_last, k_last):
    """Hairer's stiffness test (E58) after an accepted explicit step ``h`` from a state of slope
    ``f_old`` to ``y_new`` of slope ``f_new``: ``y_last``, ``k_last`` the argument and slope of the
    last stage (at ``t + h``). A test is stiff when ``h |lambda|`` exceeds :data:`STIFF_HLAMBDA`, or
    exceeds :data:`RATIO_HLAMBDA` with a stiffness ratio (E58) above :data:`STIFF_RATIO`. Updates the
    counts in ``st`` (``E_*``); True when the run is stiff."""
    nd = int(st[E_ND])
    num = 0.0
    den = 0.0
    df = 0.0
    nf = 0.0
    for i in range(nd):
        a = f_new[i] - k_last[i]
        b = y_new[i] - y_last[i]
        c = f_new[i] - f_old[i]
        num += a * a
        den += b * b
        df += c * c
        nf += f_new[i] * f_new[i]
    if den > 0.0:
        st[E_HLAMB] = abs(h) * np.sqrt(num / den)
    st[E_RATIO] = st[E_HLAMB] * np.sqrt(nf / df) if df > 0.0 else 0.0
    st[E_HMAX] = max(st[E_HMAX], st[E_HLAMB])
    if st[E_HLAMB] > STIFF_HLAMBDA or (st[E_HLAMB] > RATIO_HLAMBDA and st[E_RATIO] > STIFF_RATIO):
        st[E_NONSTI] = 0.0
        st[E_IASTI] += 1.0
        st[E_HSUM] += st[E_HLAMB]
        return st[E_IASTI] >= st[E_NEEDED]
    st[E_NONSTI] += 1.0
    if st[E_NONSTI] >= NONSTIFF_RESET:
        st[E_IASTI] = 0.0
    return False


@one_signature
@njit(cache=True)
def spectral_radius(Jl, nq, nv, x, xn):
    """Spectral radius of the Jacobian of the ``m = nq + nv`` components that feed back (``q' = v``
    known: ``J = [[0, 1], [Jq, Jv]]`` with ``Jl[:nv] = [Jq, Jv]``; ``nq = 0``: ``J = Jv``), by power
    iteration from a fixed start: the geometric mean of the growth over the last half of 40
    iterations (a dominant complex pair makes single ratios oscillate, not their mean). ``x``,
    ``xn`` (m,) scratch. 0 for a nilpotent or zero ``J``."""
    m = nq + nv
    if m == 0:
        return 0.0
    s = 0.0
    for i in range(m):
        x[i] = 1.0 + 0.5 * ((7 * i + 3) % 11) / 11.0
        s += x[i] * x[i]
    s = np.sqrt(s)
    for i in range(m):
        x[i] /= s
    iters = 40
    logsum = 0.0
    for it in range(iters):
        for i in range(nq):
            xn[i] = x[nq + i]
        for i in range(nv):
            acc = 0.0
            for j in range(m):
                acc += Jl[i, j] * x[j]
            xn[nq + i] = acc
        nrm = 0.0
        for i in range(m):
            nrm += xn[i] * xn[i]
        nrm = np.sqrt(nrm)
        if nrm == 0.0 or not np.isfinite(nrm):
            return 0.0 if nrm == 0.0 else np.inf
        if it >= iters // 2:
            logsum += np.log(nrm)
        for i in range(m):
            x[i] = xn[i] / nrm
    return np.exp(logsum / (iters - iters // 2))


@one_signature
@njit(cache=True)
def explicit_cheaper(rho, rho0, h_dop, e_dop, evals_per_step, h, max_step):
    """``(yes, dop_rate, implicit_rate)``: DOP853's predicted evaluations per second of simulated time
    (``e_dop`` per step of ``h_dop rho0 / rho``, capped by ``max_step``), the implicit loop's
    ``evals_per_step / h``, and whether the first is below :data:`SWITCH_BACK` times the second."""
    h_d = max_step
    if rho > 0.0 and rho0 > 0.0:
        h_d = min(h_dop * rho0 / rho, max_step)
    elif rho > 0.0:
        h_d = min(h_dop, max_step)
    dop = e_dop / h_d if h_d > 0.0 else np.inf
    imp = evals_per_step / h
    return dop < SWITCH_BACK * imp, dop, imp

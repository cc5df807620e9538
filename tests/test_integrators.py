"""Tests of urdf2links.integration.integrators: accuracy against closed forms, convergence orders,
invariants of the implicit midpoint rule, stiffness, counters, dense output, errors."""

from __future__ import annotations

import dataclasses
import math
import re

import numpy as np
import pytest

from urdf2links.integration.integrators import METHODS, DenseOutput, IntegrationError, IntegrationResult, integrate

ADAPTIVE = ("RK45", "DOP853", "Radau", "BDF", "LSODA")
FIXED = ("RK4", "midpoint")
W = 2.0                                   # oscillator q'' = -W^2 q
Y0 = np.array([1.0, 0.5])
T = 10.0


def oscillator(t, y):
    return np.array([y[1], -W * W * y[0]])


def exact(t):
    t = np.asarray(t, dtype=float)
    q = Y0[0] * np.cos(W * t) + Y0[1] / W * np.sin(W * t)
    v = -Y0[0] * W * np.sin(W * t) + Y0[1] * np.cos(W * t)
    return np.stack([q, v], axis=-1)


def energy_norm(e):
    """|(W dq, dv)|: the norm in which the oscillator's flow is a rotation."""
    e = np.atleast_2d(e)
    return np.hypot(W * e[:, 0], e[:, 1])


A_E = float(energy_norm(Y0)[0])           # radius of the orbit in that norm


def complex_state(y):
    """c = W q + i v evolves as c(t) = exp(-i W t) c0 (eigenvalue -iW of the flow)."""
    return W * y[..., 0] + 1j * y[..., 1]


def amplification(method, theta):
    """Stability function R(z) at z = -i W dt: one step maps c to R c on the oscillator."""
    z = -1j * theta
    if method == "RK4":
        return 1 + z + z**2 / 2 + z**3 / 6 + z**4 / 24
    return (1 + z / 2) / (1 - z / 2)      # implicit midpoint


def fixed_step_final_error(method, dt):
    res = integrate(oscillator, (0.0, T), Y0, method=method, dt=dt)
    return float(energy_norm(res.y[-1] - exact(T))[0]), res


# ---------------------------------------------------------------- accuracy, closed forms

@pytest.mark.parametrize("method", ADAPTIVE)
def test_adaptive_methods_match_closed_form(method):
    res = integrate(oscillator, (0.0, T), Y0, method=method)
    assert isinstance(res, IntegrationResult) and res.success, res.message
    assert res.method == method and res.rtol == 1e-9 and res.atol == 1e-12 and res.dt is None
    assert res.t[0] == 0.0 and res.t[-1] == T and np.all(np.diff(res.t) > 0)
    assert res.y.shape == (res.t.size, 2) and res.nsteps == res.t.size - 1
    np.testing.assert_array_equal(res.y[0], Y0)
    # Error control bounds each local error by ~ rtol |y| + atol; the oscillator's flow
    # preserves (is a rotation in) the energy norm, so local errors add up at most linearly.
    bound = res.nsteps * (res.rtol * np.abs(res.y).max() + res.atol)
    err = np.abs(res.y - exact(res.t)).max()
    assert err < bound, (method, err, bound)
    assert err < 1e-6


@pytest.mark.parametrize("method", FIXED)
def test_fixed_step_methods_match_closed_form_and_their_stability_function(method):
    dt = 0.01
    err, res = fixed_step_final_error(method, dt)
    assert res.success and res.nsteps == 1000 and res.dt == dt
    np.testing.assert_allclose(np.diff(res.t), dt, rtol=1e-9)
    assert res.nrejected == 0
    # On a linear problem a one-step method multiplies c = W q + i v by R(-i W dt) per step,
    # so the numerical solution is known in closed form too, and so is its error.
    n = np.arange(res.t.size)
    c_disc = complex_state(Y0) * amplification(method, W * dt) ** n
    np.testing.assert_allclose(complex_state(res.y), c_disc, rtol=0, atol=1e-11 * A_E)
    # Global error: RK4 phase error (W dt)^5/120 per step (|R| = 1 - (W dt)^6/144),
    # midpoint phase error (W dt)^3/12 per step (|R| = 1 exactly).
    theta, steps = W * dt, T / dt
    per_step = theta**5 / 120 + theta**6 / 144 if method == "RK4" else theta**3 / 12
    assert err <= 1.05 * A_E * steps * per_step
    assert err >= 0.9 * A_E * steps * per_step       # the estimate is the actual error


@pytest.mark.parametrize("method, dt, expected", [("RK4", 0.05, 16.0), ("midpoint", 0.02, 4.0)])
def test_convergence_order(method, dt, expected):
    e1, _ = fixed_step_final_error(method, dt)
    e2, _ = fixed_step_final_error(method, dt / 2)
    assert e1 > 1e-7                          # far from the rounding floor
    assert abs(e1 / e2 / expected - 1) < 0.05, (method, e1 / e2)


def test_rk4_is_exact_for_cubics_and_so_is_its_hermite_interpolant():
    # y' = (1, 2t, 3t^2): RK4 reduces to Simpson's rule, exact for cubics, and the cubic
    # Hermite interpolant built on exact values and slopes reproduces t^3 everywhere.
    res = integrate(lambda t, y: [1.0, 2 * t, 3 * t * t], (0.0, 1.0), [0.0, 0.0, 0.0],
                    method="RK4", dt=0.3, dense=True)
    np.testing.assert_allclose(np.diff(res.t), [0.3, 0.3, 0.3, 0.1], atol=1e-15)
    tt = np.linspace(0.0, 1.0, 37)
    np.testing.assert_allclose(res.sol(tt), np.stack([tt, tt**2, tt**3], 1), atol=1e-14)


# ------------------------------------------------- implicit midpoint: invariants, energy

def test_midpoint_conserves_quadratic_invariant_over_1e4_steps():
    res = integrate(oscillator, (0.0, 1000.0), Y0, method="midpoint", dt=0.1)
    assert res.nsteps == 10_000
    e = 0.5 * res.y[:, 1] ** 2 + 0.5 * W * W * res.y[:, 0] ** 2
    drift = np.abs(e / e[0] - 1).max()
    # Exact for the method; what is left is the Newton tolerance (~3e-5 of rtol|y| per
    # step) and rounding (~eps per step, random walk ~ 100 eps over 1e4 steps).
    assert drift < 1e-12, drift
    # RK4 at the same step loses energy steadily: |R|^(2N) - 1 ~ -N (W dt)^6 / 72.
    rk4 = integrate(oscillator, (0.0, 1000.0), Y0, method="RK4", dt=0.1)
    e4 = 0.5 * rk4.y[:, 1] ** 2 + 0.5 * W * W * rk4.y[:, 0] ** 2
    assert abs(e4[-1] / e4[0] - 1) == pytest.approx(1e4 * 0.2**6 / 72, rel=0.05)


def pendulum(t, y):
    return np.array([y[1], -np.sin(y[0])])


def pendulum_energy(y):
    return 0.5 * y[:, 1] ** 2 - np.cos(y[:, 0])


def test_midpoint_pendulum_energy_error_bounded_without_drift():
    t_end = 1000.0                           # 1e4 steps, ~130 periods of a 2 rad swing
    res = integrate(pendulum, (0.0, t_end), [2.0, 0.0], method="midpoint", dt=0.1)
    assert res.success and res.nsteps == 10_000
    de = pendulum_energy(res.y) - pendulum_energy(res.y[:1])
    amplitude = np.abs(de).max()
    assert 1e-5 < amplitude < 2e-3          # O(dt^2) oscillation of the energy error
    slope = np.polyfit(res.t, de, 1)[0]
    assert abs(slope) * t_end < 0.01 * amplitude, (slope, amplitude)
    half = de.size // 2                      # bounded: no growth from one half to the other
    assert np.abs(de[half:]).max() < 1.2 * np.abs(de[:half]).max()
    # RK4 (4th order, not symplectic) has a far smaller error but it is a secular drift.
    rk4 = integrate(pendulum, (0.0, t_end), [2.0, 0.0], method="RK4", dt=0.1)
    de4 = pendulum_energy(rk4.y) - pendulum_energy(rk4.y[:1])
    assert abs(np.polyfit(rk4.t, de4, 1)[0]) * t_end > 0.5 * np.abs(de4).max()


# ------------------------------------------------------------------------------ stiffness

LAM = (-1.0, -1e6)
V = np.array([[1.0, 1.0], [1.0, -1.0]])
A_STIFF = V @ np.diag(LAM) @ np.linalg.inv(V)


def test_stiff_linear_system():
    y0, t_end, tol = np.array([1.0, 2.0]), 0.02, dict(rtol=1e-6, atol=1e-10)
    expected = V @ (np.exp(np.array(LAM) * t_end) * np.linalg.solve(V, y0))
    steps = {}
    for method in ("Radau", "BDF", "LSODA", "RK45"):
        res = integrate(lambda t, y: A_STIFF @ y, (0.0, t_end), y0, method=method, **tol)
        assert res.success, res.message
        # the fast mode decays: errors are damped, the global error stays ~ local tolerance
        np.testing.assert_allclose(res.y[-1], expected, atol=10 * (1e-6 * 2 + 1e-10))
        steps[method] = res.nsteps
    for method in ("Radau", "BDF", "LSODA"):
        assert steps[method] < 200, steps
        assert steps["RK45"] > 10 * steps[method], steps      # explicit: |h lam| < ~3.3


def test_jac_is_passed_to_implicit_methods():
    for method in ("Radau", "BDF", "midpoint"):
        calls = []

        def jac(t, y):
            calls.append(t)
            return A_STIFF

        res = integrate(lambda t, y: A_STIFF @ y, (0.0, 0.01), [1.0, 2.0], method=method,
                        rtol=1e-6, atol=1e-10, jac=jac, dt=1e-3 if method == "midpoint" else None)
        assert res.success and calls and res.njev == len(calls)
    # a constant matrix: no Jacobian evaluation at all, exact Newton on a linear problem
    res = integrate(oscillator, (0.0, 1.0), Y0, method="midpoint", dt=0.1,
                    jac=np.array([[0.0, 1.0], [-W * W, 0.0]]))
    assert res.njev == 0 and res.nfev == 1 + 2 * res.nsteps


# ------------------------------------------------------------------ counters, callback

class Counting:
    def __init__(self, fun):
        self.fun, self.calls = fun, 0

    def __call__(self, t, y):
        self.calls += 1
        return self.fun(t, y)


@pytest.mark.parametrize("method", METHODS)
def test_counters_and_callback(method):
    rhs, seen = Counting(oscillator), []
    dt = 0.05 if method in FIXED else None
    res = integrate(rhs, (0.0, 3.0), Y0, method=method, dt=dt, dense=True,
                    callback=lambda t, y: seen.append((t, y.copy())))
    assert res.nfev == rhs.calls                     # every evaluation, Jacobian FD included
    assert res.nsteps == res.t.size - 1 == len(seen) > 0
    np.testing.assert_array_equal([t for t, _ in seen], res.t[1:])
    np.testing.assert_array_equal(np.array([y for _, y in seen]), res.y[1:])
    assert seen[-1][0] == 3.0 and res.wall_time > 0
    d = Y0.size
    if method == "RK4":
        assert res.nfev == 1 + 4 * res.nsteps and res.njev == 0 and res.nrejected == 0
    elif method == "midpoint":
        # linear problem: the first Newton correction is exact, the second confirms it;
        # plus the initial F, the FD Jacobian columns and F(t_end) for the interpolant
        assert res.nfev == 1 + 2 * res.nsteps + d * res.njev + 1 and res.njev == 1
    elif method in ("RK45", "DOP853", "auto"):
        # auto on the (non-stiff) oscillator is DOP853 throughout: one stretch
        stages = 6 if method == "RK45" else 12
        extra = 3 * res.nsteps if method != "RK45" else 0   # DOP853 dense: 3 more stages
        attempts = res.nsteps + res.nrejected
        assert 0 <= res.nfev - extra - stages * attempts <= 4
        assert method != "auto" or [s["method"] for s in res.stretches] == ["DOP853"]
    elif method == "Radau5":
        # the initial F, scipy's initial step (1), the Jacobian's d columns, three stages per Newton
        # iteration (at least one per attempt), F at each accepted state but the last
        # the smooth oscillator: rejections are rare (measured 2 of 152 accepted steps, 3 Jacobians);
        # a step controller that rejected one step in ten would be broken
        assert res.njev >= 1 and isinstance(res.nrejected, int) and res.nrejected <= res.nsteps // 10
        assert res.nfev >= 1 + d * res.njev + 3 * (res.nsteps + res.nrejected) + res.nsteps - 1
    else:
        assert res.nrejected is None and res.nfev >= res.nsteps


def test_rk45_counts_rejected_steps_and_t_eval_keeps_counters():
    res = integrate(oscillator, (0.0, T), Y0, method="RK45")
    assert res.nrejected > 0
    te = np.linspace(0.0, T, 7)
    sampled = integrate(oscillator, (0.0, T), Y0, method="RK45", t_eval=te)
    np.testing.assert_array_equal(sampled.t, te)
    assert sampled.y.shape == (7, 2) and sampled.sol is None
    assert (sampled.nsteps, sampled.nrejected) == (res.nsteps, res.nrejected)
    np.testing.assert_allclose(sampled.y, exact(te), atol=1e-6)


def test_max_steps_stops_with_failure():
    for method in ("RK4", "midpoint", "DOP853"):
        res = integrate(oscillator, (0.0, T), Y0, method=method, dt=0.01, max_steps=5)
        assert not res.success and res.nsteps == 5 and "max_steps=5" in res.message
        assert res.t[-1] < T
    res = integrate(oscillator, (0.0, 0.05), Y0, method="RK4", dt=0.01, max_steps=5)
    assert res.success and res.nsteps == 5                     # reaching t_end is fine


# ------------------------------------------------------------------------- dense output

@pytest.mark.parametrize("method", METHODS)
def test_dense_output_between_steps(method):
    dt = 0.01 if method in FIXED else None
    res = integrate(oscillator, (0.0, T), Y0, method=method, dt=dt, dense=True)
    sol = res.sol
    assert isinstance(sol, DenseOutput) and (sol.t_min, sol.t_max) == (0.0, T)
    np.testing.assert_allclose(sol(res.t), res.y, rtol=0, atol=1e-12)   # through the steps
    mid = 0.5 * (res.t[1:] + res.t[:-1])
    err_nodes = np.abs(res.y - exact(res.t)).max()
    err_mid = np.abs(sol(mid) - exact(mid)).max()
    if method in FIXED:
        # Hermite interpolation error ~ dt^4 |y''''| / 384 ~ 1e-9 << the method's error
        assert err_mid < 1.1 * err_nodes + 1e-8
    else:
        assert err_mid < res.nsteps * (res.rtol * 2.1 + res.atol)
        assert err_mid < 1e-6
    assert sol(1.5).shape == (2,) and sol([1.5, 2.5]).shape == (2, 2)
    np.testing.assert_array_equal(sol([1.5, 2.5])[1], sol(2.5))
    with pytest.raises(ValueError, match=r"t=11\.0"):
        sol(11.0)
    te = np.linspace(0.5, 9.5, 11)
    sampled = integrate(oscillator, (0.0, T), Y0, method=method, dt=dt, t_eval=te)
    np.testing.assert_array_equal(sampled.t, te)
    np.testing.assert_allclose(sampled.y, sol(te), rtol=0, atol=1e-13)


@pytest.mark.parametrize("method", METHODS)
def test_rhs_returning_a_reused_buffer(method):
    buf = np.empty(2)

    def in_place(t, y):                  # a fast rhs writing into its own output buffer
        buf[0], buf[1] = y[1], -W * W * y[0]
        return buf

    dt = 0.05 if method in FIXED else None
    got = integrate(in_place, (0.0, 2.0), Y0, method=method, dt=dt)
    ref = integrate(oscillator, (0.0, 2.0), Y0, method=method, dt=dt)
    np.testing.assert_array_equal(got.y, ref.y)
    assert got.nfev == ref.nfev


def test_result_is_frozen_and_no_sol_unless_dense():
    res = integrate(oscillator, (0.0, 1.0), [1.0, 0.5], method="RK4", dt=0.1)
    assert res.sol is None
    with pytest.raises(dataclasses.FrozenInstanceError):
        res.nfev = 0


def test_last_fixed_step_shortened_to_land_on_t_end():
    for method in FIXED:
        res = integrate(oscillator, (0.0, 1.0), Y0, method=method, dt=0.3)
        np.testing.assert_allclose(np.diff(res.t), [0.3, 0.3, 0.3, 0.1], atol=1e-15)
        assert res.t[-1] == 1.0
    # a remainder at rounding level is absorbed rather than taken as a tiny step
    res = integrate(oscillator, (0.0, 0.3), Y0, method="RK4", dt=0.1)
    assert res.nsteps == 3 and res.t[-1] == 0.3


# ------------------------------------------------------------------------------- errors

@pytest.mark.parametrize("kwargs, match", [
    (dict(method="RK5"), r"method='RK5'.*auto, RK45, DOP853, Radau5, Radau, BDF, LSODA, RK4, midpoint"),
    (dict(t_span=(1.0, 0.0)), r"t_span.*\(1\.0, 0\.0\)"),
    (dict(t_span=(0.0, math.nan)), r"t_span"),
    (dict(t_span=(0.0,)), r"t_span"),
    (dict(y0=[1.0, math.nan]), r"y0 must be finite.*nan"),
    (dict(y0=[[1.0, 2.0]]), r"y0.*shape \(1, 2\)"),
    (dict(method="RK4"), r"requires dt > 0, got dt=None"),
    (dict(method="midpoint"), r"dt=None"),
    (dict(method="RK4", dt=-0.1), r"dt=-0\.1"),
    (dict(method="midpoint", dt=0.0), r"dt=0\.0"),
    (dict(rtol=0.0), r"rtol.*0\.0"),
    (dict(atol=-1.0), r"atol.*-1\.0"),
    (dict(t_eval=[0.0, 2.0]), r"t_eval"),
    (dict(t_eval=[0.5, 0.2]), r"t_eval"),
    (dict(max_steps=0), r"max_steps.*0"),
    (dict(method="RK45", jac=np.eye(2)), r"jac"),
    (dict(rhs=lambda t, y: np.zeros(3)), r"shape \(2,\).*shape \(3,\)"),
])
def test_argument_errors_name_argument_and_value(kwargs, match):
    args = dict(rhs=oscillator, t_span=(0.0, 1.0), y0=Y0)
    args.update(kwargs)
    with pytest.raises(ValueError, match=match):
        integrate(args.pop("rhs"), args.pop("t_span"), args.pop("y0"), **args)


def test_type_errors():
    with pytest.raises(TypeError, match="rhs"):
        integrate(None, (0.0, 1.0), Y0)
    with pytest.raises(TypeError, match="callback"):
        integrate(oscillator, (0.0, 1.0), Y0, callback=3)


def test_midpoint_newton_failure_names_t_and_step():
    def broken(t, y):                   # no solution beyond t = 0.55: rhs is NaN there
        return oscillator(t, y) if t < 0.55 else np.full(2, np.nan)

    # halving lets the solution creep up to t = 0.55, where no step is possible any more
    with pytest.raises(IntegrationError, match=r"did not converge at t=\S+ \(step \d+, h=\S+ .*dt=0\.1") as info:
        integrate(broken, (0.0, 1.0), Y0, method="midpoint", dt=0.1)
    assert isinstance(info.value, RuntimeError)
    # parsed, not matched as printed (0.5499999... or 0.55 as the halvings land): the step from t with the
    # smallest h fails because its midpoint t + h/2 reaches 0.55, and the one before it succeeded, so |t - 0.55| <= h/2
    found = re.search(r"at t=(\S+) \(step \d+, h=([^ ]+) ", str(info.value))
    t, h = float(found.group(1)), float(found.group(2))
    assert 0.0 < h < 0.1 and abs(t - 0.55) <= h / 2 + 1e-12


def test_rk4_non_finite_and_scipy_failure():
    with pytest.raises(IntegrationError, match=r"non-finite.*t="), np.errstate(over="ignore"):
        integrate(lambda t, y: y * y, (0.0, 2.0), [1.0], method="RK4", dt=0.1)
    res = integrate(lambda t, y: y * y, (0.0, 2.0), [1.0], method="RK45")   # blows up at 1
    assert not res.success and "RK45 failed at t=" in res.message and res.t[-1] < 1.0


@pytest.mark.parametrize("method", ["DOP853", "RK45", "Radau", "RK4", "midpoint"])
def test_stop_ends_the_run_at_the_first_step_past_the_guard(method):
    """y' = 1 from 0: AngleGuard(cos_min=0.5) fires on the first accepted step with y > arccos(0.5);
    the step sizes bound how far past it the run may go (dt 0.01; adaptive steps on y' = 1 are
    capped by dt as max step)."""
    from urdf2links.integration.integrators import AngleGuard

    res = integrate(lambda t, y: np.array([1.0]), (0.0, 3.0), [0.0], method=method, dt=0.01,
                    stop=AngleGuard([0], 0.5))
    assert res.stopped and res.success and "stopped" in res.message
    assert np.arccos(0.5) < res.y[-1, 0] <= np.arccos(0.5) + 0.01 + 1e-12
    assert res.t[-1] < 3.0


def test_stop_must_be_callable():
    with pytest.raises(TypeError, match="stop"):
        integrate(lambda t, y: -y, (0.0, 1.0), [1.0], stop=3)

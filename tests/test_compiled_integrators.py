"""The compiled integration loops (urdf2links.loops) on the shipped scenes: RK4 and the midpoint rule
against the same loops interpreted, RK45 and DOP853 against scipy's.

The interpreted loop gets the compiled rhs wrapped in a lambda (so that it is a plain Python
callable): both then evaluate identical arithmetic in the right-hand side, and differ only in the
loop's own rounding (numba vs the interpreter). Fixed-step methods therefore agree to rounding
(1e-10 absolute on states of order 1-10 over thousands of steps); adaptive ones take scipy's
steps unless an error estimate sits at its rounding floor, so they are compared through their
error against a tight reference instead (bounded by 100 x rtol, the usual global-error slack of
an adaptive method on a non-chaotic interval).
"""

from __future__ import annotations

import numpy as np
import pytest

from urdf2links.integrators import AngleGuard, integrate
from urdf2links.locations import shipped_robots_dir
from urdf2links.plan import compile_plan
from urdf2links.scene import load_scene

SCENES = ["double_pendulum_chaos", "ship_crane", "spring_arm_torques", "ur5_falling"]


def _setup(name, T=0.5):
    scene = load_scene(shipped_robots_dir() / f"{name}.toml")
    model = scene.model()
    plan = compile_plan(scene, model)
    q, qd = scene.initial_state(model)
    return plan, np.r_[q, qd, 0.0], T


@pytest.mark.parametrize("name", SCENES)
@pytest.mark.parametrize("method", ["RK4", "midpoint"])
def test_fixed_step_compiled_loop_equals_python_loop(name, method):
    plan, y0, T = _setup(name)
    te = np.linspace(0, T, 51)
    kw = dict(method=method, dt=2e-3, rtol=1e-10, atol=1e-12, t_eval=te, dense=True)
    fast = integrate(plan.rhs, (0, T), y0, **kw)
    slow = integrate(lambda t, y: plan.rhs(t, y), (0, T), y0, **kw)
    assert fast.nsteps == slow.nsteps
    assert np.abs(fast.y - slow.y).max() < 1e-10
    assert np.abs(fast.sol(0.123) - slow.sol(0.123)).max() < 1e-10


@pytest.mark.parametrize("name", SCENES)
@pytest.mark.parametrize("method,rtol", [("DOP853", 1e-9), ("RK45", 1e-7)])
def test_adaptive_compiled_loop_meets_its_tolerance(name, method, rtol):
    plan, y0, T = _setup(name)
    te = np.linspace(0, T, 51)
    ref = integrate(lambda t, y: plan.rhs(t, y), (0, T), y0, method="DOP853", rtol=1e-13, atol=1e-14, t_eval=te)
    fast = integrate(plan.rhs, (0, T), y0, method=method, rtol=rtol, atol=1e-12, t_eval=te, dense=True)
    slow = integrate(lambda t, y: plan.rhs(t, y), (0, T), y0, method=method, rtol=rtol, atol=1e-12, t_eval=te)
    scale = np.abs(ref.y).max(axis=0) + 1e-3
    err_fast = (np.abs(fast.y - ref.y) / scale).max()
    err_slow = (np.abs(slow.y - ref.y) / scale).max()
    assert err_fast < 100 * rtol, err_fast
    assert abs(fast.nsteps - slow.nsteps) <= max(2, slow.nsteps // 50)   # same controller
    assert err_fast < 10 * err_slow + 1e-12                                  # same accuracy


def test_dense_output_of_dop853_is_seventh_order():
    """DOP853's interpolant between steps: halving the step (via rtol) should cut the interpolation
    error by ~2^7; checked loosely as the error at off-step times staying within 10 x the error
    at the steps themselves."""
    plan, y0, T = _setup("double_pendulum_chaos", 1.0)
    fast = integrate(plan.rhs, (0, T), y0, method="DOP853", rtol=1e-10, atol=1e-12, dense=True)
    mid = 0.5 * (fast.t[1:] + fast.t[:-1])
    ref = integrate(lambda t, y: plan.rhs(t, y), (0, T), y0, method="DOP853", rtol=1e-13, atol=1e-14, t_eval=mid)
    err_mid = np.abs(fast.sol(mid) - ref.y).max()
    ref_steps = integrate(lambda t, y: plan.rhs(t, y), (0, T), y0, method="DOP853", rtol=1e-13, atol=1e-14,
                          t_eval=fast.t)
    err_steps = np.abs(fast.y - ref_steps.y).max()
    assert err_mid < 10 * err_steps + 1e-12


def test_rk4_compiled_is_fourth_order():
    plan, y0, T = _setup("double_pendulum_chaos", 0.5)
    ref = integrate(plan.rhs, (0, T), y0, method="DOP853", rtol=1e-13, atol=1e-14)
    errs = [np.abs(integrate(plan.rhs, (0, T), y0, method="RK4", dt=dt).y[-1] - ref.y[-1]).max()
            for dt in (4e-3, 2e-3, 1e-3)]
    slopes = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
    assert np.all((slopes > 3.6) & (slopes < 4.4)), slopes


@pytest.mark.parametrize("method", ["DOP853", "RK45", "RK4", "midpoint"])
def test_angle_guard_stops_the_compiled_loop(method):
    """The shoulder of the double pendulum (released at 2 rad) swings through pi/2: a guard on
    |cos q0| < 0.05 stops the run at the first step inside the band, not before."""
    plan, y0, T = _setup("double_pendulum_chaos", 5.0)
    assert abs(np.cos(y0[0])) > 0.05
    res = integrate(plan.rhs, (0, T), y0, method=method, dt=1e-3, rtol=1e-9, atol=1e-12,
                    stop=AngleGuard([0], 0.05))
    assert res.stopped and res.success and res.t[-1] < T
    assert abs(np.cos(res.y[-1, 0])) < 0.05
    assert np.all(np.abs(np.cos(res.y[:-1, 0])) >= 0.05)


def test_max_steps_and_progress_callback():
    plan, y0, T = _setup("double_pendulum_chaos", 5.0)
    seen = []
    res = integrate(plan.rhs, (0, T), y0, method="RK4", dt=1e-3, max_steps=100, callback=lambda t, y: seen.append(t))
    assert not res.success and res.nsteps == 100 and "max_steps" in res.message
    assert seen and seen[-1] == pytest.approx(0.1)

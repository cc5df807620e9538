"""The compiled integration loops (urdf2links.integration.loops) on the shipped scenes: RK4 and the midpoint rule
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

from urdf2links.integration.integrators import AngleGuard, integrate
from urdf2links.locations import shipped_robots_dir
from urdf2links.scenes.plan import compile_plan
from urdf2links.scenes.scene_read import load_scene

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
    """DOP853's interpolant is a continuous extension of order 7: inside one step of length h from y_k,
    its distance to the exact solution through y_k is O(h^8). Measured on a pendulum released at 1 rad
    (smooth: the asymptotic regime starts at h ~ 0.2 s) with steps held at h by the maximum step (rtol 1e-2
    does not bind: no rejection), at theta = 1/4, 1/2, 3/4 of every step in [0.2, 1.4] s, against DOP853
    at rtol 1e-13 from the same y_k. Halving h from 0.2 to 0.025 s must divide the worst error by 2^p
    with p in [7.3, 8.7] each time (measured 7.75, 7.97, 8.00; errors 2e-6 down to 1.5e-13, above the
    rounding floor ~1e-15). A cubic Hermite interpolant through the steps would give p = 4 (its error,
    h^4, would also swamp the step's own)."""
    from urdf2links.scenes.scene_read import scene_from_dict

    scene = scene_from_dict({"robot": {"shipped": "pendulum"}, "gravity": {}, "initial": {"q": {"hinge": 1.0}}})
    model = scene.model()
    plan = compile_plan(scene, model)
    q, qd = scene.initial_state(model)
    y0 = np.r_[q, qd, 0.0]
    hs, errs = (0.2, 0.1, 0.05, 0.025), []
    for h in hs:
        res = integrate(plan.rhs, (0, 1.6), y0, method="DOP853", rtol=1e-2, atol=1e-2, dt=h, dense=True)
        assert res.nrejected == 0
        worst, n = 0.0, 0
        for k in range(res.nsteps):
            tk, tk1 = res.t[k], res.t[k + 1]
            if tk < 0.2 or tk1 > 1.4 + 1e-9 or abs(tk1 - tk - h) > 1e-12:
                continue
            n += 1
            for theta in (0.25, 0.5, 0.75):
                exact = integrate(lambda t, y: plan.rhs(t, y), (tk, tk + theta * h), res.y[k], method="DOP853",
                                  rtol=1e-13, atol=1e-15).y[-1]
                worst = max(worst, float(np.abs(res.sol(tk + theta * h) - exact).max()))
        assert n >= 1.2 / h - 2     # the steps really are h long
        errs.append(worst)
    orders = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
    assert np.all((orders > 7.3) & (orders < 8.7)), (errs, orders)


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

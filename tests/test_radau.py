"""Radau5, the compiled implicit loop (urdf2links.integration.loops.radau), and its pieces: the LU
factorisation, the structured Jacobian and solves (E59, E60), the order of the method, stiff
problems with known solutions, the dense output, the compiled loop against its interpreted twin
and against scipy's Radau, the angle guard and the budgets."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import expm

from urdf2links.integration.integrators import AngleGuard, integrate
from urdf2links.integration.loops import driver
from urdf2links.integration.loops.lu import lu_factor, lu_solve
from urdf2links.integration.loops.radau import MU_COMPLEX, MU_REAL, _factor, _solve, radau_jacobian
from urdf2links.integration.loops.stiffness import spectral_radius
from urdf2links.locations import shipped_robots_dir
from urdf2links.scenes.plan import compile_plan
from urdf2links.scenes.scene_read import load_scene


def _scene(name):
    scene = load_scene(shipped_robots_dir() / f"{name}.toml")
    model = scene.model()
    plan = compile_plan(scene, model)
    q, qd = scene.initial_state(model)
    return plan, np.r_[q, qd, 0.0]


# ------------------------------------------------------------------------------ linear algebra

@pytest.mark.parametrize("kind", [float, complex])
def test_lu_solves_like_numpy_and_flags_singular(kind):
    """Random well-conditioned systems (seeded): the in-place LU with partial pivoting solves to
    1e-13 relative (cond ~ 10-100: rounding ~ cond eps); a matrix with a zero column is flagged at
    that column's step instead of dividing by zero."""
    rng = np.random.default_rng(3)
    for m in (1, 2, 5, 17):
        A = rng.normal(size=(m, m)) + (1j * rng.normal(size=(m, m)) if kind is complex else 0)
        A = A + m * np.eye(m)
        b = rng.normal(size=m) + (1j * rng.normal(size=m) if kind is complex else 0)
        F, piv = np.array(A, dtype=kind), np.zeros(m, np.int64)
        assert lu_factor(F, piv) == -1
        x = np.array(b, dtype=kind)
        lu_solve(F, piv, x)
        np.testing.assert_allclose(x, np.linalg.solve(A, b), rtol=1e-13, atol=1e-13)
    S = np.eye(4, dtype=kind)
    S[:, 2] = 0.0
    assert lu_factor(S, np.zeros(4, np.int64)) == 2


def _structured_jacobian(rng, n, nw=1):
    """A random Jacobian of y = (q, v, w) with q' = v and nothing depending on w: (d, d) and its
    rows of v', w' on the columns of q, v (Jl)."""
    d = 2 * n + nw
    J = np.zeros((d, d))
    J[:n, n:2 * n] = np.eye(n)
    J[n:, :2 * n] = rng.normal(size=(n + nw, 2 * n)) * 3.0
    return J, np.ascontiguousarray(J[n:, :2 * n])


@pytest.mark.parametrize("h", [1e-3, 0.1, 10.0])
def test_reduced_solves_equal_the_full_systems(h):
    """(E60): eliminating x_q and x_w leaves an n x n system; its solution must be the full
    (g - J) x = r solution, for the real and the complex g of Radau IIA, at short and long steps
    (to 1e-11 relative: the full systems' condition is ~1e3 here)."""
    rng = np.random.default_rng(7)
    n = 6
    J, Jl = _structured_jacobian(rng, n)
    d = J.shape[0]
    E1, E2 = np.empty((n, n)), np.empty((n, n), complex)
    p1, p2 = np.zeros(n, np.int64), np.zeros(n, np.int64)
    assert _factor(h, Jl, n, n, E1, p1, E2, p2)
    for g, E, p, kind in ((MU_REAL / h, E1, p1, float), (MU_COMPLEX / h, E2, p2, complex)):
        r = rng.normal(size=d) + (1j * rng.normal(size=d) if kind is complex else 0)
        x = np.array(r, dtype=kind)
        _solve(g, Jl, n, n, E, p, x, np.empty(n, kind))
        full = np.linalg.solve(g * np.eye(d) - J, r)
        np.testing.assert_allclose(x, full, rtol=1e-11, atol=1e-11 * np.abs(full).max())


def test_structured_jacobian_matches_full_differences():
    """radau_jacobian differences only the q and v columns of a scene's right-hand side and keeps
    the rows of q'' and P; those entries must equal a central-difference Jacobian of the whole
    right-hand side (to 1e-5 relative: forward differences with steps sqrt(eps |y|)), and the rest
    of that full Jacobian must be the known structure (dq'/dq = 0, dq'/dq' = 1, d./dW = 0)."""
    plan, y0 = _scene("spring_arm_torques")
    rhs, n = plan.rhs, plan.model.n
    y0 = y0 + np.r_[0.1 * np.arange(2 * n), 0.0]
    d = y0.size
    f0 = rhs(0.3, y0)
    Jl = np.zeros((n + 1, 2 * n))
    cnt = (np.zeros(4, np.int64), np.zeros(d + 1))
    assert radau_jacobian(0.3, y0, f0, Jl, n, n, np.empty(d), np.empty(d), rhs.args, cnt)
    assert cnt[0][0] == 2 * n                  # 2n evaluations, not d
    full = np.empty((d, d))
    for j in range(d):
        e = np.zeros(d)
        e[j] = 1e-6 * max(1.0, abs(y0[j]))
        full[:, j] = (rhs(0.3, y0 + e) - rhs(0.3, y0 - e)) / (2 * e[j])
    np.testing.assert_allclose(Jl, full[n:, :2 * n], rtol=1e-5, atol=1e-5 * np.abs(full).max())
    np.testing.assert_allclose(full[:n, :n], 0.0, atol=1e-9)
    np.testing.assert_allclose(full[:n, n:2 * n], np.eye(n), atol=1e-9)
    np.testing.assert_allclose(full[:, 2 * n], 0.0, atol=1e-9)


def test_spectral_radius_of_structured_jacobians():
    """The power-iteration estimate against numpy's eigenvalues on seeded random structured
    Jacobians (a dominant complex pair is the common case: within 10 %), and on a damped chain whose
    dominant eigenvalue is real and far from the rest (within 1 %)."""
    rng = np.random.default_rng(11)
    x, xn = np.empty(12), np.empty(12)
    for _ in range(5):
        J, Jl = _structured_jacobian(rng, 6, nw=0)
        rho = np.abs(np.linalg.eigvals(J)).max()
        assert abs(spectral_radius(Jl, 6, 6, x, xn) / rho - 1) < 0.1
    Jl = np.zeros((6, 12))
    Jl[:, :6] = -np.diag([1.0, 2, 3, 4, 5, 6])
    Jl[:, 6:] = -np.diag([1e6, 10, 10, 10, 10, 10])           # one heavily damped coordinate
    rho = np.abs(np.linalg.eigvals(np.block([[np.zeros((6, 6)), np.eye(6)], [Jl]]))).max()
    assert abs(spectral_radius(Jl, 6, 6, x, xn) / rho - 1) < 0.01


# ------------------------------------------------------------------------------ the method

def test_radau5_is_fifth_order_on_a_linear_system():
    """y' = A y, A with eigenvalues -1 +- 5i and -3: with the exact Jacobian the stage system is
    linear and one Newton iteration solves it (to rounding), so the error at t = 2 is the method's
    own. Steps held at h by the maximum step (rtol 0.5 does not bind); halving h from 0.1 to 0.0125
    must divide the error by 2^p with p in [4.6, 5.4] each time (order 5; measured 4.96-5.00)."""
    A = np.array([[-1.0, 5.0, 0.0], [-5.0, -1.0, 1.0], [0.0, 0.0, -3.0]])
    y0 = np.array([1.0, 0.0, 1.0])
    exact = expm(2.0 * A) @ y0
    errs = []
    for h in (0.1, 0.05, 0.025, 0.0125):
        res = integrate(lambda t, y: A @ y, (0.0, 2.0), y0, method="Radau5", rtol=0.5, atol=0.5, dt=h,
                        jac=lambda t, y: A)
        assert res.nsteps == round(2.0 / h)
        errs.append(np.abs(res.y[-1] - exact).max())
    p = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
    assert np.all((4.6 < p) & (p < 5.4)), (errs, p)


def test_radau5_robertson_reference_values():
    """Robertson's chemical kinetics (Hairer & Wanner II, IV.1; stiff, eigenvalues down to -1e4 and
    a conserved sum): at t = 40 the reference values 0.7158271, 9.185535e-6, 0.2841637 (to the
    digits given), with the sum y1 + y2 + y3 = 1 kept to 1e-12; a few hundred steps, where an explicit
    method needs tens of thousands."""
    def robertson(t, y):
        return np.array([-0.04 * y[0] + 1e4 * y[1] * y[2],
                         0.04 * y[0] - 1e4 * y[1] * y[2] - 3e7 * y[1] ** 2,
                         3e7 * y[1] ** 2])

    res = integrate(robertson, (0.0, 40.0), [1.0, 0.0, 0.0], method="Radau5", rtol=1e-8, atol=1e-12)
    assert res.success and res.nsteps < 400, res.nsteps
    np.testing.assert_allclose(res.y[-1], [0.7158271, 9.185535e-6, 0.2841637], rtol=2e-7)
    assert abs(res.y[-1].sum() - 1.0) < 1e-12


def test_radau5_dense_output_is_the_collocation_polynomial():
    """The interpolant passes through the steps; between them it is the collocation polynomial,
    of order 3 inside a step (its error O(h^4) against the end points' O(h^5)): on the oscillator
    at rtol 1e-8 the midpoints' error stays within 3 x rtol (measured 1.5e-8, the nodes' 1.8e-9),
    and the nodes' within rtol."""
    W = 2.0
    res = integrate(lambda t, y: np.array([y[1], -W * W * y[0]]), (0.0, 5.0), [1.0, 0.0], method="Radau5",
                    rtol=1e-8, atol=1e-10, dense=True)
    np.testing.assert_allclose(res.sol(res.t), res.y, rtol=0, atol=1e-14)
    mid = 0.5 * (res.t[1:] + res.t[:-1])
    err_nodes = np.abs(res.y[:, 0] - np.cos(W * res.t)).max()
    err_mid = np.abs(res.sol(mid)[:, 0] - np.cos(W * mid)).max()
    assert err_nodes < 1e-8 and err_mid < 3e-8, (err_nodes, err_mid)


# ------------------------------------------------------------------------------ the compiled loop

@pytest.mark.parametrize("name", ["spring_arm_torques", "hard/stiff_spring_arm"])
def test_compiled_loop_equals_interpreted_and_general_solves(name):
    """The compiled loop against the same source interpreted on the compiled right-hand side wrapped
    in a lambda (same arithmetic in the rhs): the same steps and states to 1e-12 (the loops' own
    rounding); and against the interpreted loop without the structure (full (2n + 1)-systems, E59
    unused): the same steps (within 2), the final states to 1e-7 of each component's size. The
    reduced and the full solves round differently, and a Newton iteration stops anywhere within its
    tolerance fnewt scal ~ 1e-10 |y| (rtol 1e-8): over ~230 steps the two may drift ~2e-8 apart."""
    plan, y0 = _scene(name)
    T = 0.05
    kw = dict(rtol=1e-8, atol=1e-10, dt=None, grid=None, need_dense=False)
    f0 = plan.rhs(0.0, y0)
    fast = driver.run("Radau5", plan.rhs, f0, 0.0, T, y0, **kw)
    slow = driver.run("Radau5", lambda t, y: plan.rhs(t, y), f0, 0.0, T, y0, structure=(plan.model.n, plan.model.n),
                      **kw)
    full = driver.run("Radau5", lambda t, y: plan.rhs(t, y), f0, 0.0, T, y0, **kw)
    assert fast.success and slow.success and full.success
    assert fast.t.size == slow.t.size and np.abs(fast.y - slow.y).max() < 1e-12
    scale = np.abs(fast.y).max(axis=0) + 1.0
    assert abs(fast.t.size - full.t.size) <= 2 and (np.abs(fast.y[-1] - full.y[-1]) / scale).max() < 1e-7
    assert fast.nfev == slow.nfev < full.nfev        # the full Jacobian differences the W column too


@pytest.mark.parametrize("name,rtol", [("spring_arm_torques", 1e-9), ("hard/stiff_spring_arm", 1e-9)])
def test_compiled_radau5_and_scipy_radau_meet_the_reference(name, rtol):
    """Against DOP853 at rtol 1e-13: the compiled Radau5 within 20 x rtol of the reference (its rtol is
    mapped to rtol^(5/6) for an order-3 estimate of an order-5 method: the global error lands near
    rtol; measured 2-8 x rtol), and in the same range as scipy's Radau at the same rtol (which
    controls the order-3 estimate at rtol itself: more accurate, more steps). Measured (rtol 1e-9):
    ours 0.52 and 2.97 x rtol, scipy 0.012 and 1.8 x rtol; ours in 261 and 498 steps, scipy in 624 and
    1196 (0.42 x both). Bounds: 20 x rtol for both errors (a wrong reference would put both off), and
    ours in fewer than 0.6 x scipy's steps (the point of the mapped tolerance)."""
    plan, y0 = _scene(name)
    T = 0.3
    te = np.linspace(0.0, T, 61)
    ref = integrate(plan.rhs, (0.0, T), y0, method="DOP853", rtol=1e-13, atol=1e-14, t_eval=te)
    ours = integrate(plan.rhs, (0.0, T), y0, method="Radau5", rtol=rtol, atol=1e-2 * rtol, t_eval=te)
    scipys = integrate(lambda t, y: plan.rhs(t, y), (0.0, T), y0, method="Radau", rtol=rtol, atol=1e-2 * rtol,
                       t_eval=te)
    n = plan.model.n
    err = np.abs(ours.y[:, :n] - ref.y[:, :n]).max()
    err_scipy = np.abs(scipys.y[:, :n] - ref.y[:, :n]).max()
    assert err < 20 * rtol and err_scipy < 20 * rtol, (err, err_scipy)
    assert ours.nsteps < 0.6 * scipys.nsteps, (ours.nsteps, scipys.nsteps)


@pytest.mark.parametrize("method", ["Radau5", "auto"])
def test_angle_guard_and_budgets_stop_the_implicit_loop(method):
    """The compiled Radau5 and auto loops stop at the first step past the angle guard (status 2 ->
    stopped, success), at max_steps (success False, saying so), and raise nothing."""
    plan, y0 = _scene("spring_arm_torques")
    idx = 0
    guard = AngleGuard([idx], np.cos(y0[idx] + 0.05))
    res = integrate(plan.rhs, (0.0, 6.0), y0, method=method, rtol=1e-8, atol=1e-10, stop=guard)
    assert res.stopped and res.success and res.t[-1] < 6.0
    assert abs(np.cos(res.y[-1, idx])) < np.cos(y0[idx] + 0.05) <= abs(np.cos(res.y[-2, idx]))
    short = integrate(plan.rhs, (0.0, 6.0), y0, method=method, rtol=1e-8, atol=1e-10, max_steps=7)
    assert not short.success and short.nsteps == 7 and "max_steps=7" in short.message

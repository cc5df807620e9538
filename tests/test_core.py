"""The trace-method core against closed forms, its own literal form, and conservation laws."""

from __future__ import annotations

import numpy as np
import pytest

from urdf2links import BaseState, DynamicsError, LinkSpec, Model, Wrench, build_tree
from urdf2links.dynamics.oracles.recursive import RecursivePlan
from urdf2links.dynamics.transforms import base_transforms, elementary, link_transform

from builders import (DOUBLE, FREE_BODY, PENDULUM, PRISMATIC_REVOLUTE, double_pendulum, free_body,
                      pendulum, prismatic_revolute, random_tree, rod_H)

G0 = 9.81


def rel(a, b):
    a, b = np.asarray(a, float), np.asarray(b, float)
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300))


# ---- closed forms -------------------------------------------------------------------------------

@pytest.mark.parametrize("theta", [0.0, 0.3, -2.0, np.pi / 2])
def test_single_pendulum_closed_form(theta):
    p = PENDULUM
    m = pendulum()
    q, qd = np.array([theta]), np.array([1.7])
    assert m.mass_matrix(q)[0, 0] == pytest.approx(p["I"] + p["m"] * p["c"] ** 2, rel=1e-14)
    assert m.bias(q, qd)[0] == pytest.approx(0.0, abs=1e-14)
    assert m.gravity(q)[0] == pytest.approx(p["m"] * G0 * p["c"] * np.sin(theta), rel=1e-13, abs=1e-14)
    assert m.potential_energy(q) == pytest.approx(-p["m"] * G0 * p["c"] * np.cos(theta), rel=1e-13, abs=1e-14)


def test_double_pendulum_closed_form():
    p = DOUBLE
    m = double_pendulum()
    rng = np.random.default_rng(1)
    for _ in range(10):
        (t1, t2), (w1, w2) = rng.uniform(-3, 3, 2), rng.uniform(-3, 3, 2)
        q, qd = np.array([t1, t2]), np.array([w1, w2])
        m1, m2, l1, c1, c2, I1, I2 = (p[k] for k in ("m1", "m2", "l1", "c1", "c2", "I1", "I2"))
        A = np.array([
            [I1 + m1 * c1**2 + I2 + m2 * (l1**2 + c2**2 + 2 * l1 * c2 * np.cos(t2)), I2 + m2 * (c2**2 + l1 * c2 * np.cos(t2))],
            [I2 + m2 * (c2**2 + l1 * c2 * np.cos(t2)), I2 + m2 * c2**2],
        ])
        h = m2 * l1 * c2 * np.sin(t2)
        e = np.array([-h * (2 * w1 * w2 + w2**2), h * w1**2])
        G = G0 * np.array([m1 * c1 * np.sin(t1) + m2 * (l1 * np.sin(t1) + c2 * np.sin(t1 + t2)),
                           m2 * c2 * np.sin(t1 + t2)])
        np.testing.assert_allclose(m.mass_matrix(q), A, rtol=1e-13, atol=1e-14)
        np.testing.assert_allclose(m.bias(q, qd), e, rtol=1e-12, atol=1e-13)
        np.testing.assert_allclose(m.gravity(q), G, rtol=1e-12, atol=1e-13)


def test_prismatic_revolute_closed_form():
    p = PRISMATIC_REVOLUTE
    m = prismatic_revolute()
    rng = np.random.default_rng(2)
    for _ in range(10):
        (s, th), (sd, thd) = rng.uniform(-2, 2, 2), rng.uniform(-2, 2, 2)
        q, qd = np.array([s, th]), np.array([sd, thd])
        m1, m2, c, I = p["m1"], p["m2"], p["c"], p["I"]
        A = np.array([[m1 + m2, -m2 * c * np.sin(th)], [-m2 * c * np.sin(th), I + m2 * c**2]])
        e = np.array([-m2 * c * np.cos(th) * thd**2, 0.0])
        G = np.array([0.0, -m2 * G0 * c * np.cos(th)])
        np.testing.assert_allclose(m.mass_matrix(q), A, rtol=1e-13, atol=1e-14)
        np.testing.assert_allclose(m.bias(q, qd), e, rtol=1e-12, atol=1e-13)
        np.testing.assert_allclose(m.gravity(q), G, rtol=1e-12, atol=1e-13)


def _body_rate_jacobian(phi):
    """Jb (3, 3): body angular velocity = Jb(phi) phi' for R = Rx Ry Rz (columns R^T e_x, Rz^T e_y, e_z)."""
    Rx, Ry, Rz = (elementary(3 + k, phi[k])[:3, :3] for k in range(3))
    return np.column_stack([(Rx @ Ry @ Rz).T @ [1, 0, 0], Rz.T @ [0, 1, 0], [0, 0, 1]])


@pytest.mark.parametrize("seed", range(4))
def test_free_body_against_euler_equations(seed):
    """Six coordinates x..phi_z of one body against m a = F and I w_b' + w_b x I w_b = M_b (body axes)."""
    p = FREE_BODY
    model = free_body()
    rng = np.random.default_rng(seed)
    q = np.r_[rng.normal(size=3), rng.uniform(-1.2, 1.2, 3)]  # |phi_y| < pi/2: away from the singularity
    qd = rng.normal(size=6) * 2
    F_world, M_body = rng.normal(size=3), rng.normal(size=3)
    qdd = model.forward_dynamics(q, qd, loads=[Wrench("body", force=F_world, frame="world"),
                                               Wrench("body", moment=M_body, frame="link")])
    np.testing.assert_allclose(qdd[:3], F_world / p["m"], rtol=1e-12, atol=1e-12)
    phi, phid, phidd = q[3:], qd[3:], qdd[3:]
    I = np.diag([p["Ixx"], p["Iyy"], p["Izz"]])
    Jb = _body_rate_jacobian(phi)
    h = 1e-6  # central difference of Jb along phi': truncation ~h^2 * |J'''| ~ 1e-12, rounding ~1e-10
    Jb_dot = (_body_rate_jacobian(phi + h * phid) - _body_rate_jacobian(phi - h * phid)) / (2 * h)
    w = Jb @ phid
    w_dot = Jb @ phidd + Jb_dot @ phid
    euler = I @ w_dot + np.cross(w, I @ w)
    np.testing.assert_allclose(euler, M_body, rtol=1e-8, atol=1e-8)


# ---- literal == recursive -----------------------------------------------------------------------

def _random_base(rng):
    return BaseState(rng.normal(size=6), rng.normal(size=6), rng.normal(size=6))


@pytest.mark.parametrize("seed", range(8))
@pytest.mark.parametrize("moving_base", [False, True])
def test_literal_equals_recursive(seed, moving_base):
    """Random trees with branching, mixed coordinate types and massless frames (links 2 and 5)."""
    model = random_tree(seed, links=7, massless=(2, 5))
    rng = np.random.default_rng(100 + seed)
    q, qd = rng.normal(size=model.n), rng.normal(size=model.n)
    base = _random_base(rng) if moving_base else None
    loads = [Wrench(f"link{k}", rng.normal(size=3), rng.normal(size=3), rng.normal(size=3), frame)
             for k, frame in ((1, "link"), (4, "world"), (6, "link"))]
    tol = 1e-12
    kw = dict(base=base)
    assert rel(model.mass_matrix(q, **kw), model.mass_matrix(q, method="literal", **kw)) < tol
    assert rel(model.bias(q, qd, **kw), model.bias(q, qd, method="literal", **kw)) < tol
    assert rel(model.gravity(q, **kw), model.gravity(q, method="literal", **kw)) < tol
    assert rel(model.generalized_forces(q, loads, **kw), model.generalized_forces(q, loads, method="literal", **kw)) < tol
    assert rel(model.kinetic_energy(q, qd, **kw), model.kinetic_energy(q, qd, method="literal", **kw)) < tol
    assert rel(model.potential_energy(q, **kw), model.potential_energy(q, method="literal", **kw)) < tol


@pytest.mark.parametrize("seed", range(6))
def test_mass_matrix_symmetric_positive_definite(seed):
    model = random_tree(seed, links=8, min_coords=1)
    rng = np.random.default_rng(seed)
    for _ in range(5):
        A = model.mass_matrix(rng.normal(size=model.n))
        np.testing.assert_allclose(A, A.T, rtol=0, atol=1e-13 * np.abs(A).max())
        assert np.linalg.eigvalsh(A).min() > 0


def test_kinetic_energy_is_half_qd_A_qd():
    model = random_tree(3, links=6, massless=(4,))
    rng = np.random.default_rng(3)
    q, qd = rng.normal(size=model.n), rng.normal(size=model.n)
    assert model.kinetic_energy(q, qd) == pytest.approx(0.5 * qd @ model.mass_matrix(q) @ qd, rel=1e-13)


# ---- conservation and Lagrange's equations -----------------------------------------------------

def _five_point(f, h):
    """d/ds f(s) at 0, five-point stencil: error ~h^4 f^(5)/30."""
    return (-f(2 * h) + 8 * f(h) - 8 * f(-h) + f(-2 * h)) / (12 * h)


@pytest.mark.parametrize("seed", range(4))
def test_power_balance(seed):
    """dE/dt = qd . (tau + Q - G) along the motion (fixed base), E's rate by finite differences."""
    model = random_tree(seed, links=6, min_coords=1)
    rng = np.random.default_rng(seed)
    q, qd, tau = rng.normal(size=model.n), rng.normal(size=model.n), rng.normal(size=model.n)
    loads = [Wrench("link3", rng.normal(size=3), rng.normal(size=3), rng.normal(size=3))]
    qdd = model.forward_dynamics(q, qd, tau, loads=loads)
    dE = _five_point(lambda s: model.kinetic_energy(q + s * qd + 0.5 * s * s * qdd, qd + s * qdd), 1e-3)
    power = qd @ (tau + model.generalized_forces(q, loads) - model.gravity(q))
    # h = 1e-3: truncation ~1e-12 relative, rounding ~eps*E/h ~ 1e-13 relative.
    assert dE == pytest.approx(power, rel=1e-8, abs=1e-9)


def _moving_base(rng):
    a0, w, ph = rng.normal(size=6) * 0.5, rng.uniform(0.5, 2.0, 6), rng.uniform(0, 6, 6)

    def base(t):
        s, c = np.sin(w * t + ph), np.cos(w * t + ph)
        return BaseState(a0 * s, a0 * w * c, -a0 * w * w * s)
    return base


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("moving_base", [False, True])
def test_lagrange_equations_by_finite_differences(seed, moving_base):
    """d/dt dL/dqd - dL/dq (L = E - V) at random (q, qd, qdd, t) equals A qdd + e + G."""
    model = random_tree(seed, links=5, min_coords=1, massless=(2,))
    rng = np.random.default_rng(50 + seed)
    base = _moving_base(rng) if moving_base else None
    q, qd, qdd, t = rng.normal(size=model.n), rng.normal(size=model.n), rng.normal(size=model.n), 0.3
    n = model.n
    eye = np.eye(n)

    def dL_dqd(q_, qd_, t_):
        # E is quadratic in qd (with a linear base term), so a unit central difference is exact.
        return np.array([(model.kinetic_energy(q_, qd_ + eye[k], t=t_, base=base)
                          - model.kinetic_energy(q_, qd_ - eye[k], t=t_, base=base)) / 2 for k in range(n)])

    def L(q_):
        return model.kinetic_energy(q_, qd, t=t, base=base) - model.potential_energy(q_, t=t, base=base)

    ddt = _five_point(lambda s: dL_dqd(q + s * qd + 0.5 * s * s * qdd, qd + s * qdd, t + s), 1e-3)
    dLdq = np.array([_five_point(lambda s: L(q + s * eye[k]), 1e-3) for k in range(n)])
    lhs = ddt - dLdq
    rhs = model.mass_matrix(q, t=t, base=base) @ qdd + model.bias(q, qd, t=t, base=base) + model.gravity(q, t=t, base=base)
    # five-point stencils with h = 1e-3: truncation ~1e-12, rounding ~eps*|L|/h ~ 1e-12 (relative).
    assert rel(lhs, rhs) < 1e-8


def test_translating_base_is_gravity_minus_acceleration():
    """A base translating with constant acceleration a acts as gravity g - a on a fixed base."""
    rng = np.random.default_rng(7)
    a = np.array([1.5, -0.7, 3.0])
    g = np.array([0.0, 0.0, -9.81])
    moving = random_tree(4, links=6, min_coords=1, gravity=g)
    fixed = random_tree(4, links=6, min_coords=1, gravity=g - a)
    v0 = np.array([0.3, 2.0, -1.0])

    def base(t):
        return BaseState(np.r_[v0 * t + 0.5 * a * t * t, 0, 0, 0], np.r_[v0 + a * t, 0, 0, 0], np.r_[a, 0, 0, 0])
    for _ in range(3):
        q, qd = rng.normal(size=moving.n), rng.normal(size=moving.n)
        np.testing.assert_allclose(moving.forward_dynamics(q, qd, t=0.8, base=base),
                                   fixed.forward_dynamics(q, qd), rtol=1e-11, atol=1e-11)


def test_base_transform_derivatives():
    """B', B'' of the base against finite differences of B(t)."""
    base = _moving_base(np.random.default_rng(9))
    B = lambda t: base_transforms(base(t))[0]
    _, Bd, Bdd = base_transforms(base(0.4))
    np.testing.assert_allclose(_five_point(lambda s: B(0.4 + s), 1e-3), Bd, atol=1e-10)
    np.testing.assert_allclose(_five_point(lambda s: base_transforms(base(0.4 + s))[1], 1e-3), Bdd, atol=1e-10)


def test_link_transform_matches_rotation_convention():
    """T~ = T1 T2 T3 T4 T5 T6: origin (x, y, z) in the parent's axes, R = Rx Ry Rz."""
    p = np.array([0.1, -0.2, 0.3, 0.4, -0.5, 0.6])
    T = link_transform(p)
    Rx, Ry, Rz = (elementary(3 + k, p[3 + k])[:3, :3] for k in range(3))
    np.testing.assert_allclose(T[:3, :3], Rx @ Ry @ Rz, atol=1e-15)
    np.testing.assert_allclose(T[:3, 3], p[:3], atol=1e-15)


# ---- errors -------------------------------------------------------------------------------------

def test_massless_moving_leaf_raises_named_error():
    tree = build_tree([
        LinkSpec("arm", None, coordinates={"phi_z": "shoulder"}, H=rod_H(1.0, (0.5, 0, 0), Izz=0.1)),
        LinkSpec("finger", "arm", params=(1, 0, 0, 0, 0, 0), coordinates={"phi_x": "finger_joint"}),
    ])
    model = Model(tree, name="ghost")
    with pytest.raises(DynamicsError) as info:
        model.forward_dynamics(np.zeros(2), np.zeros(2))
    msg = str(info.value)
    assert "finger_joint" in msg and "finger" in msg and "not positive definite" in msg
    assert info.value.coordinates == ("finger_joint",)


def test_bad_shapes_are_named():
    model = double_pendulum()
    with pytest.raises(ValueError, match=r"q must have shape \(2,\)"):
        model.mass_matrix(np.zeros(3))
    with pytest.raises(ValueError, match="method must be one of"):
        model.gravity(np.zeros(2), method="fast")
    with pytest.raises(ValueError, match="parent 'nowhere'"):
        build_tree([LinkSpec("a", "nowhere")])
    with pytest.raises(KeyError, match="no link named 'hand'"):
        model.generalized_forces(np.zeros(2), [Wrench("hand", force=np.ones(3))])


def test_explicit_time_rates_of_the_base_against_finite_differences():
    """dE/dt and dV/dt at fixed (q, qd), used for the work done by a moving base."""
    model = random_tree(2, links=5, min_coords=1, massless=(3,))
    rng = np.random.default_rng(21)
    base = _moving_base(rng)
    q, qd, t = rng.normal(size=model.n), rng.normal(size=model.n), 0.7
    rp = RecursivePlan(model.tree)
    kin = rp.kinematics(q, qd, base_transforms(base(t)))
    dE, dV = rp.explicit_time_rates(kin, base_transforms(base(t)), model.gravity_vector)
    fd_E = _five_point(lambda s: model.kinetic_energy(q, qd, t=t + s, base=base), 1e-3)
    fd_V = _five_point(lambda s: model.potential_energy(q, t=t + s, base=base), 1e-3)
    assert dE == pytest.approx(fd_E, rel=1e-8)
    assert dV == pytest.approx(fd_V, rel=1e-8)


def test_with_gravity_reaches_every_call_and_leaves_the_model_alone():
    """``Model.with_gravity``: every call of the copy, the compiled hot path included (which reads its
    own copy of the gravity, inside the hot ``TF``), equals a model built with that gravity, to the bit;
    the original keeps its own; the caller's array stays writable. (The copies the comparison made by
    setting a private ``_g`` missed the hot ``TF``: G and q'' kept the model's gravity.)"""
    model = double_pendulum()           # gravity (0, 0, -9.81)
    g = np.array([0.3, -0.2, -1.62])
    moon, built = model.with_gravity(g), Model(model.tree, gravity=g)
    rng = np.random.default_rng(0)
    q, qd, qdd = rng.uniform(-1, 1, model.n), rng.normal(size=model.n), rng.normal(size=model.n)
    calls = {"gravity": lambda m: m.gravity(q), "forward_dynamics": lambda m: m.forward_dynamics(q, qd),
             "inverse_dynamics": lambda m: m.inverse_dynamics(q, qd, qdd),
             "potential_energy": lambda m: m.potential_energy(q),
             "gravity (numpy oracle)": lambda m: m.gravity(q, method="numpy")}
    before = {k: f(model) for k, f in calls.items()}
    for name, f in calls.items():
        assert np.array_equal(f(moon), f(built)), name
        assert not np.allclose(f(moon), before[name]), name
        assert np.array_equal(f(model), before[name]), name
    assert g.flags.writeable and np.array_equal(moon.gravity_vector, g)
    assert model.with_gravity([0.0, 0.0, -9.81]) is model
    with pytest.raises(ValueError, match="3 finite numbers"):
        model.with_gravity([0.0, np.nan, 1.0])

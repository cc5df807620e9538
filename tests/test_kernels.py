"""The compiled recursive form (urdf2links.dynamics.kernels) against the numpy recursive form and the
literal trace form (docs/equations.md §5), on random trees (branching, all six slot types, massless frames,
moving base) and on real robots; forward dynamics against a dense solve; base power against the
numpy form.

Tolerance 1e-12 relative: the three forms sum the same terms in different orders, so they differ
by rounding (observed ~1e-16 relative); a wrong term is O(1).
"""

from __future__ import annotations

import numpy as np
import pytest

from builders import random_tree
import corpus
from corpus import NAMED, needs_corpus
from urdf2links import BaseState, load_urdf
from urdf2links.dynamics import kernels as K
from urdf2links.dynamics.factor import cholesky, cholesky_solve
from urdf2links.dynamics.tree_arrays import AC, KL, W_COORD, W_LINK, W_SIZE, Tree, flat_tree
from urdf2links.dynamics.oracles.recursive import RecursivePlan
from urdf2links.dynamics.transforms import base_transforms

TOL = 1e-12


def rel(a, b):
    a, b = np.asarray(a, float), np.asarray(b, float)
    return float(np.abs(a - b).max() / max(np.abs(b).max(), 1e-300))


def _state(model, seed, moving):
    rng = np.random.default_rng(seed)
    q, qd = rng.normal(size=model.n), rng.normal(size=model.n)
    base = BaseState(rng.normal(size=6), rng.normal(size=6), rng.normal(size=6)) if moving else None
    return q, qd, base


@pytest.mark.parametrize("seed", range(10))
@pytest.mark.parametrize("moving", [False, True])
def test_compiled_equals_numpy_and_literal(seed, moving):
    model = random_tree(seed, links=8, massless=(3,))
    q, qd, base = _state(model, 1000 + seed, moving)
    for name, args in (("mass_matrix", (q,)), ("bias", (q, qd)), ("gravity", (q,)),
                       ("kinetic_energy", (q, qd)), ("potential_energy", (q,))):
        fn = getattr(model, name)
        fast = fn(*args, base=base)
        assert rel(fast, fn(*args, base=base, method="numpy")) < TOL, name
        assert rel(fast, fn(*args, base=base, method="literal")) < TOL, name


@pytest.mark.parametrize("seed", range(6))
def test_forward_dynamics_solves_the_equation(seed):
    """q'' from the compiled Cholesky against numpy's dense solve of A q'' = tau - G - e: two
    backward-stable solves differ by at most ~ n eps cond(A) relative (bound 100 eps cond(A))."""
    model = random_tree(seed, links=8, min_coords=1)
    q, qd, base = _state(model, 2000 + seed, True)
    tau = np.random.default_rng(seed).normal(size=model.n)
    qdd = model.forward_dynamics(q, qd, tau, base=base)
    A = model.mass_matrix(q, base=base, method="literal")
    rhs = tau - model.bias(q, qd, base=base, method="literal") - model.gravity(q, base=base, method="literal")
    assert rel(qdd, np.linalg.solve(A, rhs)) < 100 * np.finfo(float).eps * np.linalg.cond(A)


def _link_accelerations(TI, TF, q, qd, b18, *qdd):
    """Every link's spatial acceleration (L, 6) and the unit twists (6, n) after one call of the compiled
    kinematics pass, with ``qdd`` (an array and its offset) or without (the q'' = 0 variant)."""
    W = np.zeros(TI[W_SIZE])
    K.kinematics(Tree(TI, TF, W), q, 0, qd, 0, True, b18, 0, True, 0.0, 0.0, -9.81, *qdd)
    L, n = int(TI[0]), int(TI[1])
    rec = TI[W_LINK] + KL * np.arange(L)[:, None] + AC + np.arange(6)
    return W[rec], W[TI[W_COORD]:TI[W_COORD] + 6 * n].reshape(6, n)


@pytest.mark.parametrize("seed", range(4))
def test_one_kinematics_pass_with_and_without_qdd(seed):
    """``kernels.kinematics`` is the one root-to-leaves pass (E33) of every call: without ``q''`` (None, the
    variant the forward path compiles) each link's acceleration is that at ``q'' = 0`` to the bit (E32);
    given ``q''`` (inverse dynamics, E54) it is that plus ``sum s_i q_i''`` over the coordinates that move
    the link (world twists are constant along the chain: exact up to rounding, 1e-12 relative). The planted
    wrong case: a pass that dropped the term would leave the accelerations unchanged."""
    model = random_tree(seed, links=6)
    q, qd, base = _state(model, 4000 + seed, True)
    qdd = np.random.default_rng(5000 + seed).normal(size=model.n)
    b18 = np.r_[base.pose, base.rate, base.accel]
    TI, TF = flat_tree(model.tree)
    a0, S = _link_accelerations(TI, TF, q, qd, b18)
    assert np.array_equal(_link_accelerations(TI, TF, q, qd, b18, np.zeros(model.n), 0)[0], a0)
    tree = model.tree
    above = np.eye(tree.n_links, dtype=bool)         # above[:, p]: p and its ancestors
    for p in range(tree.n_links):
        if tree.parent[p] >= 0:
            above[:, p] |= above[:, tree.parent[p]]
    moves = above[np.asarray(tree.coord_link, int)]  # (n, L): coordinate i moves link p
    expected = a0 + (moves * qdd[:, None]).T @ S.T
    got = _link_accelerations(TI, TF, q, qd, b18, qdd, 0)[0]
    assert rel(got, expected) < TOL
    assert rel(a0, expected) > 1e-3, "q'' moved no acceleration: the check cannot see a dropped term"


@pytest.mark.parametrize("seed", range(4))
def test_base_power_equals_numpy_form(seed):
    model = random_tree(seed, links=6)
    q, qd, base = _state(model, 3000 + seed, True)
    TI, TF = flat_tree(model.tree)
    W = np.zeros(TI[W_SIZE])
    b18 = np.r_[base.pose, base.rate, base.accel]
    g = np.asarray(model.gravity_vector)
    tree = Tree(TI, TF, W)
    K.kinematics(tree, q, 0, qd, 0, True, b18, 0, True, *g)   # records the base's twist
    K.dynamics(tree, False, False, True)                        # and the links' momentum
    dE, dV = K.base_power(tree, *g)
    bt = base_transforms(base)
    rp = RecursivePlan(model.tree)
    ref = rp.explicit_time_rates(rp.kinematics(q, qd, bt, acceleration=True), bt, model.gravity_vector)
    assert rel(dE, ref[0]) < TOL and rel(dV, ref[1]) < TOL


def test_cholesky_flags_a_singular_matrix():
    A = np.array([1.0, 1.0, 1.0, 1.0])
    x, Lf = np.ones(2), np.empty(4)
    assert cholesky(A, 0, 2, Lf, 0) == 1
    assert cholesky(np.array([2.0, 0.0, 0.0, 2.0]), 0, 2, Lf, 0) == -1
    cholesky_solve(Lf, 0, 2, x, 0)
    assert np.allclose(x, 0.5)


@needs_corpus
@pytest.mark.parametrize("name", sorted(NAMED))
def test_real_robots_compiled_equals_literal(name):
    model = load_urdf(corpus.path(NAMED[name]), inertia="repair")
    q, qd, _ = _state(model, 7, False)
    assert rel(model.forward_dynamics(q, qd), np.linalg.solve(
        model.mass_matrix(q, method="literal"),
        -model.bias(q, qd, method="literal") - model.gravity(q, method="literal"))) < 1e-9

"""The compiled recursive form (urdf2links.kernels) against the numpy recursive form and the
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
from urdf2links import kernels as K
from urdf2links.oracles.recursive import RecursivePlan
from urdf2links.transforms import base_transforms

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


@pytest.mark.parametrize("seed", range(4))
def test_base_power_equals_numpy_form(seed):
    model = random_tree(seed, links=6)
    q, qd, base = _state(model, 3000 + seed, True)
    ct = K.CompiledTree(model.tree)
    b18 = np.r_[base.pose, base.rate, base.accel]
    ct.terms(q, qd, b18, np.asarray(model.gravity_vector))   # kinematics records the base's twist
    ws = K.workspace_view(ct.I, ct.W)
    dE, dV = K.base_power(K.tree_view(ct.I, ct.F), ws, ws.base_twist, ws.base_acc,
                          np.asarray(model.gravity_vector))
    bt = base_transforms(base)
    rp = RecursivePlan(model.tree)
    ref = rp.explicit_time_rates(rp.kinematics(q, qd, bt, acceleration=True), bt, model.gravity_vector)
    assert rel(dE, ref[0]) < TOL and rel(dV, ref[1]) < TOL


def test_cholesky_flags_a_singular_matrix():
    A = np.array([[1.0, 1.0], [1.0, 1.0]])
    x, Lf = np.empty(2), np.empty((2, 2))
    assert K.cholesky_solve(A, np.ones(2), Lf, x) == 1
    assert K.cholesky_solve(np.eye(2) * 2.0, np.ones(2), Lf, x) == -1 and np.allclose(x, 0.5)


@needs_corpus
@pytest.mark.parametrize("name", sorted(NAMED))
def test_real_robots_compiled_equals_literal(name):
    model = load_urdf(corpus.path(NAMED[name]), inertia="repair")
    q, qd, _ = _state(model, 7, False)
    assert rel(model.forward_dynamics(q, qd), np.linalg.solve(
        model.mass_matrix(q, method="literal"),
        -model.bias(q, qd, method="literal") - model.gravity(q, method="literal"))) < 1e-9

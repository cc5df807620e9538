"""Identifiability (E91), the least-squares fit with standard deviations, the energy form (E90) and the
physically consistent fit (E92).

- The Panda of issue 46: joints 1-3 meet at the shoulder. Data from a Panda whose link3 was changed (mass,
  centre of mass, inertia): the fit names ``m_panda_link3`` unidentifiable, keeps it at the description's
  value, and still reproduces every torque (the change it cannot see is a direction of the null space).
- Planted recovery: every identifiable combination of a planted UR5 (links and joint terms) back to 1e-8.
- Standard deviations: with Gaussian noise of known sigma, the estimated sigma within 5 %, and every base
  parameter within 5 of its standard deviations of the truth (fixed seed).
- The energy form: ``h . pi = E + V`` against ``Model.kinetic_energy + potential_energy`` (links fixed to the
  base add a constant V) on arms, a humanoid, a coupled mimic model, with armature; the power balance's
  rows over a smooth motion equal the work of the torques to the trapezoidal rule's accuracy.
- Rows: the power balance's rows alone recover damping and friction (``fit_rows``); constraint forces
  ``J^T lambda`` are projected out (``project_constraints``), and without the projection they spoil the fit.
- Consistency: data from a consistent UR5 with noise; the least-squares fit has links whose H is not
  positive definite, the consistent fit has none and says which links it moved.

Planted wrong cases, seen to fail once: the pivot's weights reversed (masses last: the Panda test fails,
link3's mass is identified), the kinetic coefficient of ``Hxy`` with a + sign (the energy test fails).
Tolerances are in each test.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import corpus
from test_identification_regressor import MIMIC
from urdf2links import load_urdf, load_urdf_string
from urdf2links.identification import (ParameterSet, base_parameters, fit_rows, identify, project_constraints,
                                       regressor)
from urdf2links.identification.energy import energy_regressor, energy_rows


def _load(name):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return load_urdf(corpus.path(corpus.NAMED.get(name, name)))


def _states(n, S, seed):
    rng = np.random.default_rng(seed)
    return rng.uniform(-2, 2, (S, n)), rng.normal(size=(S, n)) * 2, rng.normal(size=(S, n)) * 4


def _planted_link(params, values, link, rng):
    """``values`` with ``link``'s H changed by a positive definite amount: a point mass of 20 % of its mass
    off its centre, and a little inertia."""
    from urdf2links.identification import link_matrix, link_vector

    sl = params.link_parameters(link)
    H = link_matrix(values[sl])
    r = np.append(rng.uniform(-0.05, 0.05, 3), 1.0)
    dm = 0.2 * H[3, 3]
    out = values.copy()
    out[sl] = link_vector(H + dm * np.outer(r, r) + np.diag([2e-3, 1e-3, 3e-3, 0.0]))
    return out


@corpus.needs_corpus
def test_panda_shoulder_mass_is_named_unidentifiable_and_kept():
    model = _load("panda")
    params = ParameterSet.from_model(model)
    rng = np.random.default_rng(11)
    truth = _planted_link(params, params.values, "panda_link3", rng)
    Q, QD, QDD = _states(model.n, 3000, 12)
    tau = regressor(params, Q, QD, QDD) @ truth
    fit = identify(params, Q, QD, QDD, tau)
    k = params.index("m_panda_link3")
    assert "m_panda_link3" in fit.base.unidentifiable()
    assert not fit.identifiable[k] and fit.std[k] == 0.0
    assert fit.values[k] == params.values[k] != truth[k]          # kept at the description's value
    assert any(d.startswith("m_panda_link3 ") for d in fit.base.directions), fit.base.directions
    # the data are reproduced all the same: the change in link3's mass is a direction no torque sees
    # (the residual from the normal equations' sums has a floor of ~sqrt(eps) |tau|: cancellation in
    # t - 2 beta.b + beta G beta; the identified model's own torques below are the sharp check)
    assert np.abs(fit.rms_after).max() < 1e-6 * np.abs(tau).max()
    scale = np.abs(fit.base.beta(truth)).max()
    assert np.abs(fit.base.beta(fit.values) - fit.base.beta(truth)).max() < 1e-9 * scale
    ident = fit.model()
    assert np.abs(ident.inverse_dynamics(Q[:50], QD[:50], QDD[:50]) - tau[:50]).max() < 1e-8 * np.abs(tau).max()
    # link3's first moment and its moments about the shoulder are seen: in identifiable combinations
    assert fit.identifiable[params.index("mx_panda_link3")]
    assert 0 < fit.condition_number < 1e6


@corpus.needs_corpus
def test_planted_recovery_links_and_joints():
    model = _load("ur5")
    params = ParameterSet.from_model(model)
    rng = np.random.default_rng(5)
    truth = _planted_link(params, params.values, "forearm_link", rng)
    truth = _planted_link(params, truth, "wrist_2_link", rng)
    for kind in ("damping", "friction", "armature", "offset"):
        for cn in model.coordinate_names:
            truth[params.index(f"{kind}_{cn}")] = rng.uniform(0.05, 1.0)
    Q, QD, QDD = _states(model.n, 4000, 6)
    tau = regressor(params, Q, QD, QDD) @ truth
    fit = identify(params, Q, QD, QDD, tau)
    b_true, b_fit = fit.base.beta(truth), fit.beta
    assert np.all(np.abs(b_fit - b_true) <= 1e-8 * np.maximum(np.abs(b_true), 1e-3 * np.abs(b_true).max()))
    # every joint parameter is identified by itself (they multiply distinct functions of the motion)
    for kind in ("damping", "friction", "offset"):
        for cn in model.coordinate_names:
            k = params.index(f"{kind}_{cn}")
            assert fit.alone[k] and abs(fit.values[k] - truth[k]) < 1e-8, (kind, cn)
    assert len(fit.table()) == params.p and fit.summary()["identifiable_combinations"] == fit.base.r
    combos = fit.combinations()
    assert len(combos) == fit.base.r and all(abs(c["identified"] - b) <= 1e-8 * max(abs(b), 1e-3 * np.abs(b_true).max())
                                             for c, b in zip(combos, b_true))


@corpus.needs_corpus
def test_standard_deviations_match_the_noise():
    model = _load("ur5")
    params = ParameterSet.from_model(model, joints=("damping", "offset"))
    Q, QD, QDD = _states(model.n, 3000, 7)
    tau0 = regressor(params, Q, QD, QDD) @ params.values
    rng = np.random.default_rng(8)
    sigma = 0.05
    fit = identify(params, Q, QD, QDD, tau0 + sigma * rng.normal(size=tau0.shape))
    assert abs(fit.sigma / sigma - 1.0) < 0.05, fit.sigma
    z = (fit.beta - fit.base.beta(params.values)) / fit.beta_std
    assert np.abs(z).max() < 5.0, np.abs(z).max()     # 5 sigma over ~50 parameters: p ~ 3e-5 of a false alarm
    assert np.all(fit.rms_after <= fit.rms_before + 1e-12)


def _fixed_potential(model, q):
    """V of the links fixed to the base (not parameters: a constant), at ``q``."""
    T = model.link_poses(q)
    params = ParameterSet.from_model(model, joints=())
    V = 0.0
    for p, c in enumerate(params.link_col):
        if c < 0:
            V -= model.gravity_vector @ (T[p] @ model.tree.H[p][:, 3])[:3]
    return V


@corpus.needs_corpus
@pytest.mark.parametrize("name", ["panda", "talos", "mimic", "ur5_armature"])
def test_energy_form_equals_the_models_energies(name):
    """``h . pi = E + V`` to 1e-12 relative (the same sums in another order)."""
    if name == "mimic":
        model = load_urdf_string(MIMIC, mimic="coupled")
    else:
        model = _load("ur5" if name == "ur5_armature" else name)
    params = ParameterSet.from_model(model)
    if name == "ur5_armature":
        v = params.values.copy()
        for cn in model.coordinate_names:
            v[params.index(f"armature_{cn}")] = 0.3
        model = params.to_model(v)
        params = ParameterSet.from_model(model)
    Q, QD, _ = _states(model.n, 6, 9)
    h = energy_regressor(params, Q, QD)
    for k in range(6):
        E, V = model.kinetic_energy(Q[k], QD[k]), model.potential_energy(Q[k])
        ref = E + V - _fixed_potential(model, Q[k])
        assert abs(h[k] @ params.values - ref) < 1e-12 * max(abs(E), abs(V), 1.0), (name, k)


@corpus.needs_corpus
def test_power_balance_rows():
    """A smooth motion ``q(t) = a sin(w t + c)`` with its exact ``q'``, ``q''`` and torques (damping,
    friction, offset planted): each interval's row equals the work of the torques to the trapezoidal
    rule's error (dt = 2e-4 s: ~1e-8 relative; bound 1e-6)."""
    model = _load("ur5")
    params = ParameterSet.from_model(model)
    rng = np.random.default_rng(10)
    truth = params.values.copy()
    for kind in ("damping", "friction", "offset"):
        for cn in model.coordinate_names:
            truth[params.index(f"{kind}_{cn}")] = rng.uniform(0.1, 1.0)
    t = np.arange(0.0, 1.0, 2e-4)
    a, w, c = rng.uniform(0.3, 1.0, model.n), rng.uniform(1.0, 4.0, model.n), rng.uniform(0, 6, model.n)
    Q = a * np.sin(np.outer(t, w) + c)
    QD = a * w * np.cos(np.outer(t, w) + c)
    QDD = -a * w ** 2 * np.sin(np.outer(t, w) + c)
    tau = regressor(params, Q, QD, QDD) @ truth
    rows = energy_rows(params, t, Q, QD, tau, window=500)
    assert rows.Y.shape == (9, params.p)
    err = np.abs(rows.Y @ truth - rows.y) / np.abs(rows.y).max()
    assert err.max() < 1e-6, err.max()


@corpus.needs_corpus
def test_consistent_fit_keeps_every_H_positive_definite():
    """UR5, consistent description (every H positive definite), 400 samples, torque noise sigma = 3 N m
    (seed 1): the least-squares fit gives links with an indefinite H, and so does the same program without
    its constraints (the regularisation alone); the consistent fit gives none, and says which links it had
    to move (the note names each). Planted wrong case, seen to fail once: the constraint dropped from the
    program (cons = []) leaves an indefinite H."""
    model = _load("ur5")
    params = ParameterSet.from_model(model)
    from urdf2links.identification.consistency import min_eigenvalues

    assert np.all(min_eigenvalues(params, params.values)[1] > 0)
    rng = np.random.default_rng(1)
    S = 400
    Q, QD, QDD = rng.uniform(-1, 1, (S, model.n)), rng.normal(size=(S, model.n)), rng.normal(size=(S, model.n))
    tau = model.inverse_dynamics(Q, QD, QDD) + 3.0 * rng.normal(size=(S, model.n))
    fit = identify(params, Q, QD, QDD, tau, consistent=True)
    c = fit.consistency
    assert np.any(min_eigenvalues(params, fit.values)[1] < 0)     # least squares alone: not consistent
    assert np.any(c.eig_before < 0) and np.all(c.eig_after > 0)
    bad = [ln for ln, e in zip(c.links, c.eig_free) if e < 0]       # the constraint had to act on these
    assert bad and set(bad) <= set(c.moved)
    assert all(any(f"link {ln!r}" in note for note in c.notes) for ln in bad)
    assert np.all(min_eigenvalues(params, c.values)[1] > 0)
    assert np.all(np.linalg.eigvalsh(fit.model().tree.H[params.link_col >= 0])[:, 0] > 0)
    assert c.rms_increase < 0.5 * fit.sigma


@corpus.needs_corpus
def test_fit_from_power_balance_rows():
    """The energy form's rows alone (no q''): ``fit_rows`` recovers the planted damping and friction of the
    smooth motion to the trapezoidal rule's accuracy: 1e-3 relative (measured ~1e-4 for the friction, whose
    regularised law turns over |q'| ~ v_s = 0.01 rad/s, crossed in ~10 samples of dt = 1 ms; less for damping)."""
    model = _load("ur5")
    params = ParameterSet.from_model(model, joints=("damping", "friction", "offset"))
    rng = np.random.default_rng(13)
    truth = params.values.copy()
    for kind in ("damping", "friction", "offset"):
        for cn in model.coordinate_names:
            truth[params.index(f"{kind}_{cn}")] = rng.uniform(0.1, 1.0)
    t = np.arange(0.0, 20.0, 1e-3)
    a, w, c = rng.uniform(0.5, 1.5, (3, model.n)), rng.uniform(0.3, 3.0, (3, model.n)), rng.uniform(0, 6, (3, model.n))
    ph = t[:, None, None] * w[None] + c[None]
    Q, QD, QDD = (np.sum(a * np.sin(ph), axis=1), np.sum(a * w * np.cos(ph), axis=1),
                  -np.sum(a * w ** 2 * np.sin(ph), axis=1))
    tau = regressor(params, Q, QD, QDD) @ truth
    rows = energy_rows(params, t, Q, QD, tau, window=100)
    fit = fit_rows(params, rows.Y, rows.y)
    for kind in ("damping", "friction"):
        for cn in model.coordinate_names:
            k = params.index(f"{kind}_{cn}")
            assert fit.identifiable[k] and abs(fit.values[k] - truth[k]) < 1e-3 * truth[k], (kind, cn)


def test_constraint_forces_projected_out():
    """A mimic joint as a constraint (loaded independent, ``J q = c`` with ``J = (0, 0.5, 1)``): torques with
    arbitrary constraint forces ``J^T lambda`` added are fitted exactly on the projected rows
    (:func:`project_constraints`), and the fit is blind to lambda."""
    model = load_urdf_string(MIMIC, mimic="independent")
    params = ParameterSet.from_model(model, joints=("damping",))
    J = np.array([[0.0, 0.5, 1.0]])
    rng = np.random.default_rng(14)
    S = 300
    q2, qd2, qdd2 = rng.uniform(-1, 1, (3, S))
    Q = np.stack([rng.uniform(-1, 1, S), q2, 0.1 - 0.5 * q2], axis=1)
    QD = np.stack([rng.normal(size=S), qd2, -0.5 * qd2], axis=1)
    QDD = np.stack([rng.normal(size=S), qdd2, -0.5 * qdd2], axis=1)
    truth = params.values.copy()
    truth[params.index("damping_j1")] = 0.4
    Y = regressor(params, Q, QD, QDD)
    tau = Y @ truth + rng.normal(size=(S, 1)) * 10.0 * J       # the constraint's forces J^T lambda
    fit = fit_rows(params, *project_constraints(Y, tau, J))
    assert np.abs(fit.rms_after).max() < 1e-9 * np.abs(tau).max()
    assert abs(fit.values[params.index("damping_j1")] - 0.4) < 1e-9
    plain = fit_rows(params, Y.reshape(-1, params.p), tau.reshape(-1))     # unprojected: lambda spoils it
    assert np.abs(plain.rms_after).max() > 1e-3


def test_consistent_fit_without_cvxpy_names_the_extra(monkeypatch):
    """Without cvxpy (the extra ``identify``) the consistent fit says what to install."""
    import sys

    model = load_urdf_string(MIMIC)
    params = ParameterSet.from_model(model, joints=())
    Q, QD, QDD = _states(model.n, 50, 15)
    fit = identify(params, Q, QD, QDD, regressor(params, Q, QD, QDD) @ params.values)
    monkeypatch.setitem(sys.modules, "cvxpy", None)
    from urdf2links.identification import consistent_fit

    with pytest.raises(ImportError, match=r"urdf2links\[identify\]"):
        consistent_fit(fit)

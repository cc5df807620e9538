"""``Model.inverse_dynamics`` (E54): ``tau = A q'' + e + G - Q`` in one compiled pass, against

- the literal oracle (the trace formulas term by term) on every kind of model: shipped robots, random
  trees, a moving base, loads, coupled (mimic) coordinates, MJCF armature (hinges and balls);
- the forward dynamics it inverts (``forward_dynamics(q, qd, tau) == qdd``);
- Pinocchio's ``rnea(q, v, a)`` on every example-robot-data file both load (1e-10, as tests/test_pinocchio.py);
- MuJoCo's ``mj_inverse`` (``qfrc_inverse``): route 1 (the project's tree as MJCF) and MJCF files
  through ``to_mujoco`` (``tau = J^T qfrc_inverse`` at ``qacc = J q'' + J' q'``, E50);
- batches, equal to the per-state calls to the bit (the same row function).

Tolerances: the oracles and the compiled pass are the same mathematics in a different order, so
they agree to rounding; 1e-12 relative to the largest of |tau|, |A| |q''|, |A| |q'|^2 (the sizes of the
terms that cancel) leaves three decades above the measured ~1e-15. Against Pinocchio and MuJoCo, 1e-10
(another code, another order of operations, entries up to 1e3: measured worst ~1e-14).
"""

from __future__ import annotations

import warnings

import mujoco
import numpy as np
import pytest

import corpus
from builders import random_tree
from mjcf_models import write_models
from test_importer import MIMIC
from test_mjcf import GYM
from urdf2links import BaseState, Wrench, load_mjcf, load_urdf, load_urdf_string
from urdf2links.compare.mujoco_side.mjcf import mjcf_from_model
from urdf2links.locations import shipped_robots_dir

import pinocchio as pin  # noqa: E402 -- in the test extra

TOL = 1e-12
TOL_PEER = 1e-10


def _shipped(name, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return load_urdf(shipped_robots_dir() / name, **kw)


def _scale(model, q, qd, qdd, tau):
    A = model.mass_matrix(q)
    return max(float(np.abs(tau).max()), float(np.abs(A).max()) * (1.0 + float(np.abs(qdd).max())
                                                                       + float(np.abs(qd).max()) ** 2))


def _rel(a, b, scale):
    return float(np.abs(np.asarray(a) - np.asarray(b)).max()) / scale


MODELS = {
    "double_pendulum": lambda: _shipped("double_pendulum.urdf"),
    "ur5_like": lambda: _shipped("ur5_like.urdf"),
    "deck_crane": lambda: _shipped("deck_crane.urdf"),
    "free_body_floating": lambda: _shipped("free_body.urdf", floating_base=True),
    "random_branched": lambda: random_tree(7, links=11, min_coords=1),
    "mimic_coupled": lambda: load_urdf_string(MIMIC, mimic="coupled"),
}


@pytest.fixture(scope="module")
def mjcf_files(tmp_path_factory):
    return write_models(tmp_path_factory.mktemp("mjcf_id"))


@pytest.mark.parametrize("name", list(MODELS))
def test_inverse_dynamics_equals_the_literal_oracle(name):
    model = MODELS[name]()
    rng = np.random.default_rng(3)
    for k in range(4):
        q, qd, qdd = rng.uniform(-1, 1, model.n), rng.normal(size=model.n), rng.normal(size=model.n)
        kw = {}
        if k >= 2:      # a moving base and loads on the last link
            kw["base"] = BaseState(rng.normal(size=6), rng.normal(size=6), rng.normal(size=6))
            link = model.link_names[-1]
            kw["loads"] = [Wrench(link, force=rng.normal(size=3), point=rng.normal(size=3)),
                           Wrench(link, moment=rng.normal(size=3), frame="world")]
        tau = model.inverse_dynamics(q, qd, qdd, **kw)
        lit = model.inverse_dynamics(q, qd, qdd, method="literal", **kw)
        num = model.inverse_dynamics(q, qd, qdd, method="numpy", **kw)
        s = _scale(model, q, qd, qdd, lit)
        assert _rel(tau, lit, s) < TOL, (name, k, _rel(tau, lit, s))
        assert _rel(num, lit, s) < TOL
        # the definition, from the terms: A q'' + e + G - Q
        A = model.mass_matrix(q, base=kw.get("base"))
        e = model.bias(q, qd, base=kw.get("base"))
        G = model.gravity(q, base=kw.get("base"))
        Q = model.generalized_forces(q, kw.get("loads", []), base=kw.get("base"))
        assert _rel(tau, A @ qdd + e + G - Q, s) < TOL
        # and the forward dynamics it inverts
        back = model.forward_dynamics(q, qd, tau, **kw)
        assert np.abs(back - qdd).max() < 1e-9 * (1 + np.abs(qdd).max())
        # gravity=False leaves G out
        assert _rel(model.inverse_dynamics(q, qd, qdd, gravity=False, **kw), tau - G, s) < TOL


def test_armature_is_included(mjcf_files):
    """MJCF armature (E49): a hinge's ``a q''``, a ball's ``a J^T (J q'' + J' q')``, against the literal
    oracle (which writes the armature term by term)."""
    rng = np.random.default_rng(4)
    for name in ("hinge_anchor", "ball", "free", "multi_joint"):
        model = load_mjcf(mjcf_files[name])
        assert model.tree.has_armature
        for _ in range(3):
            q = model.info["q0"] + rng.uniform(-1, 1, model.n)
            qd, qdd = rng.normal(size=model.n), rng.normal(size=model.n)
            tau = model.inverse_dynamics(q, qd, qdd)
            lit = model.inverse_dynamics(q, qd, qdd, method="literal")
            assert _rel(tau, lit, _scale(model, q, qd, qdd, lit)) < TOL, name


def test_batches_equal_single_states_to_the_bit(mjcf_files):
    rng = np.random.default_rng(5)
    B = 13      # more rows than the chunks of a 2-thread machine, not a multiple of them
    models = [MODELS[k]() for k in ("ur5_like", "random_branched", "mimic_coupled")] + [load_mjcf(mjcf_files["ball"])]
    for model in models:
        Q, QD, QDD = rng.uniform(-1, 1, (B, model.n)), rng.normal(size=(B, model.n)), rng.normal(size=(B, model.n))
        T = model.inverse_dynamics(Q, QD, QDD)
        assert T.shape == (B, model.n)
        for b in range(B):
            assert np.array_equal(T[b], model.inverse_dynamics(Q[b], QD[b], QDD[b])), (model.name, b)
        base = BaseState(rng.normal(size=(B, 6)), rng.normal(size=(B, 6)), rng.normal(size=(B, 6)))
        loads = [Wrench(model.link_names[-1], force=[1.0, -2.0, 0.5], point=[0.1, 0, 0])]
        T = model.inverse_dynamics(Q, QD, QDD, base=base, loads=loads)
        for b in range(B):
            one = model.inverse_dynamics(Q[b], QD[b], QDD[b], loads=loads,
                                         base=BaseState(base.pose[b], base.rate[b], base.accel[b]))
            assert np.array_equal(T[b], one), (model.name, b)


def test_hot_path_equals_the_general_path_to_the_bit():
    """The frozen single-state entry (fixed base, no loads) computes what the row function computes."""
    model = MODELS["ur5_like"]()
    rng = np.random.default_rng(6)
    q, qd, qdd = rng.normal(size=(3, model.n))
    hot = model.inverse_dynamics(q, qd, qdd)
    general = model.inverse_dynamics(q[None], qd[None], qdd[None])[0]
    assert np.array_equal(hot, general)
    assert np.array_equal(model.inverse_dynamics(list(q), list(qd), list(qdd)), hot)    # converted, same bits


def test_bad_shapes_name_the_argument():
    model = MODELS["double_pendulum"]()
    with pytest.raises(ValueError, match="qdd must have the shape of q"):
        model.inverse_dynamics(np.zeros(2), np.zeros(2), np.zeros(3))
    with pytest.raises(ValueError, match="method"):
        model.inverse_dynamics(np.zeros(2), np.zeros(2), np.zeros(2), method="fast")


# -- Pinocchio -----------------------------------------------------------------------------------------
@corpus.needs_corpus
def test_inverse_dynamics_agrees_with_pinocchios_rnea():
    """``rnea(q, v, a)`` on every corpus file both load, at seeded states, by joint name (see
    tests/test_pinocchio.py for the matching); the worst relative difference is printed."""
    from test_pinocchio import ONE_DOF, _ours, _pin_state, _pinocchio

    rng = np.random.default_rng(7)
    worst, compared = {}, 0
    for rel in corpus.corpus_files():
        f = corpus.path(rel)
        pm = _pinocchio(f)
        if pm is None:
            continue
        model = _ours(f)
        if model.n == 0 or not all(pm.joints[j].shortname().endswith(ONE_DOF) for j in range(1, pm.njoints)):
            continue
        perm = [pm.joints[pm.getJointId(nm)].idx_v for nm in model.coordinate_names]
        pd = pm.createData()
        for _ in range(3):
            q, v, a = rng.uniform(-1, 1, model.n), rng.standard_normal(model.n), rng.standard_normal(model.n)
            qp, vp = _pin_state(pm, model.coordinate_names, q, v)
            ap = np.zeros(pm.nv)
            ap[perm] = a
            ref = pin.rnea(pm, pd, qp, vp, ap)[perm]
            tau = model.inverse_dynamics(q, v, a)
            scale = max(float(np.abs(ref).max()), float(np.abs(model.mass_matrix(q)).max()))
            worst[rel] = max(worst.get(rel, 0.0), float(np.abs(tau - ref).max()) / scale)
        compared += 1
    print(f"\ninverse_dynamics against pin.rnea: {compared} files, worst {max(worst.values()):.2e} "
          f"({max(worst, key=worst.get)})")
    assert compared > 50
    assert max(worst.values()) < TOL_PEER, sorted(worst.items(), key=lambda x: -x[1])[:3]


# -- MuJoCo ---------------------------------------------------------------------------------------------
def test_inverse_dynamics_agrees_with_mj_inverse_route1():
    """Route 1 (the project's tree as MJCF): ``qfrc_inverse`` at ``qacc = q''``, every coordinate."""
    rng = np.random.default_rng(8)
    for name in ("double_pendulum", "ur5_like", "deck_crane", "random_branched"):
        model = MODELS[name]()
        mj = mjcf_from_model(model, gravity=model.gravity_vector)
        d = mujoco.MjData(mj.model)
        for _ in range(3):
            q, qd, qdd = rng.uniform(-1, 1, model.n), rng.normal(size=model.n), rng.normal(size=model.n)
            mj.set_state(d, q, qd)
            d.qacc[mj.dof_index] = qdd
            mujoco.mj_inverse(mj.model, d)
            ref = d.qfrc_inverse[mj.dof_index]
            tau = model.inverse_dynamics(q, qd, qdd)
            assert _rel(tau, ref, _scale(model, q, qd, qdd, ref)) < TOL_PEER, name


def test_inverse_dynamics_agrees_with_mj_inverse_through_the_map(mjcf_files):
    """MJCF files (gymnasium's and the element files) run by MuJoCo itself: ``tau = J^T qfrc_inverse`` at
    ``qacc = J q'' + J' q'`` (E50), passive forces and constraints off, armature included."""
    rng = np.random.default_rng(9)
    worst = {}
    for path in list(GYM) + list(mjcf_files.values()):
        model = load_mjcf(path)
        m = mujoco.MjModel.from_xml_path(str(path))
        for flag in ("mjDSBL_SPRING", "mjDSBL_DAMPER", "mjDSBL_CONSTRAINT", "mjDSBL_CONTACT"):
            m.opt.disableflags |= int(getattr(mujoco.mjtDisableBit, flag))
        m.body_gravcomp[:] = 0.0
        m.opt.gravity[:] = model.gravity_vector
        d = mujoco.MjData(m)
        qmap = model.info["mujoco"]
        for _ in range(3):
            q = model.info["q0"] + rng.uniform(-1, 1, model.n)
            qd, qdd = rng.normal(size=model.n), rng.normal(size=model.n)
            d.qpos[:], d.qvel[:] = model.to_mujoco(q, qd)
            J = qmap.jacobian(q)
            d.qacc[:] = J @ qdd + qmap.jacobian_rate(q, qd)
            mujoco.mj_inverse(m, d)
            ref = J.T @ d.qfrc_inverse
            tau = model.inverse_dynamics(q, qd, qdd)
            worst[path.stem] = max(worst.get(path.stem, 0.0), _rel(tau, ref, _scale(model, q, qd, qdd, ref)))
    print(f"\ninverse_dynamics against mj_inverse (MJCF files): worst {max(worst.values()):.2e} "
          f"({max(worst, key=worst.get)})")
    assert max(worst.values()) < TOL_PEER, worst

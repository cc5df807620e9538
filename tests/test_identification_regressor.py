"""The regressor ``tau = Y(q, q', q'') pi`` (docs/equations.md (E89)), against

- ``Model.inverse_dynamics`` (E54) on twelve example-robot-data robots (arms, legged robots, humanoids,
  a mobile manipulator, a hand-held arm with a gripper): ``Y pi`` with the description's ``pi``;
- Pinocchio's ``computeJointTorqueRegressor`` on the same twelve, columns mapped: Pinocchio's per-joint parameters
  ``(m, m c, I about the joint frame)`` are linear in our link's H, through the constant transform ``X``
  from Pinocchio's joint frame to our link frame (``H = X H_pin X^T``, E11), written out in :func:`pin_map`;
- the joint terms in closed form (damping ``q'``, Coulomb ``q' / sqrt(q'^2 + v_s^2)`` (E79), offset 1,
  armature: ``Model.inverse_dynamics`` of a model with that armature, E49), coupled (mimic) coordinates
  (E42) and fixed tendons (E76);
- MJCF armature (a hinge's own unit, a ball's or free body's one unit on three angles) and a moving base;
- batches equal to the single-state calls to the bit.

Tolerances: ``Y pi`` and inverse dynamics are the same wrenches summed in another order: 1e-12 relative to
the largest ``|tau|`` (measured ~1e-15). Against Pinocchio 1e-10 relative to the largest entry of its mapped
regressor (another code; measured ~1e-14), as tests/test_pinocchio.py.
Planted wrong cases, seen to fail once: the sign of one planar-moment column (``_jn`` with +1 on ``Hxy``:
17 of 22 failed), a column map with ``X^-T`` for ``X^-1`` (6 of the 7 robots then checked failed), and a ball's armature
column without ``omega_p x (omega_p - omega_s)`` (the ball and free models failed).
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import corpus
from urdf2links import load_urdf, load_urdf_string
from urdf2links.identification import LINK_ENTRIES, ParameterSet, link_matrix, regressor

import pinocchio as pin  # noqa: E402 -- in the test extra

TOL, TOL_PEER = 1e-12, 1e-10

ROBOTS = corpus.TWELVE       # the twelve example-robot-data robots of the equality tests


def _load(rel, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")     # inertia findings: not what these tests check
        return load_urdf(corpus.path(rel), **kw)


def _states(model, S, seed):
    rng = np.random.default_rng(seed)
    return rng.uniform(-1, 1, (S, model.n)), rng.normal(size=(S, model.n)), rng.normal(size=(S, model.n))


@corpus.needs_corpus
@pytest.mark.parametrize("name", list(ROBOTS))
def test_y_pi_equals_inverse_dynamics(name):
    model = _load(ROBOTS[name])
    params = ParameterSet.from_model(model)
    Q, QD, QDD = _states(model, 8, 1)
    Y = regressor(params, Q, QD, QDD)
    assert Y.shape == (8, model.n, params.p)
    tau = model.inverse_dynamics(Q, QD, QDD)
    err = np.abs(Y @ params.values - tau).max() / np.abs(tau).max()
    assert err < TOL, (name, err)
    # one state: the same rows, to the bit (one row function)
    assert np.array_equal(regressor(params, Q[3], QD[3], QDD[3]), Y[3])


# -- Pinocchio ---------------------------------------------------------------------------------------------
def pin_map(X) -> np.ndarray:
    """M (10, 10) with ``pi_pin = M pi`` for one link: our 10 entries (LINK_ENTRIES, our link frame) to
    Pinocchio's ``(m, mc_x, mc_y, mc_z, I_xx, I_xy, I_yy, I_xz, I_yz, I_zz)`` about its joint frame, where ``X``
    (4, 4) takes Pinocchio's joint frame to ours (``r_ours = X r_pin``): ``H_pin = X^-1 H X^-T`` (E11) and
    ``I = tr(S) 1 - S`` (E29)."""
    Xi = np.linalg.inv(X)
    M = np.zeros((10, 10))
    for k in range(10):
        e = np.zeros(10)
        e[k] = 1.0
        Hp = Xi @ link_matrix(e) @ Xi.T
        S = Hp[:3, :3]
        I = np.trace(S) * np.eye(3) - S
        M[:, k] = [Hp[3, 3], *Hp[:3, 3], I[0, 0], I[0, 1], I[1, 1], I[0, 2], I[1, 2], I[2, 2]]
    return M


@corpus.needs_corpus
@pytest.mark.parametrize("name", list(ROBOTS))
def test_regressor_equals_pinocchios_mapped(name):
    """``Y[:, cols(p)] = Y_pin[:, cols(j)] M_p`` for every link ``p`` that carries joint ``j``'s coordinate
    (massless frame links of prismatic joints have no Pinocchio body and are left out)."""
    from test_pinocchio import _pin_state

    model = _load(ROBOTS[name])
    params = ParameterSet.from_model(model, joints=())
    pm = pin.buildModelFromUrdf(str(corpus.path(ROBOTS[name])))
    pd = pm.createData()
    perm = [pm.joints[pm.getJointId(nm)].idx_v for nm in model.coordinate_names]
    tree = model.tree
    Q, QD, QDD = _states(model, 3, 2)
    compared = 0
    for q, qd, qdd in zip(Q, QD, QDD):
        qp, vp = _pin_state(pm, model.coordinate_names, q, qd)
        ap = np.zeros(pm.nv)
        ap[perm] = qdd
        Yp = pin.computeJointTorqueRegressor(pm, pd, qp, vp, ap)[perm]
        pin.forwardKinematics(pm, pd, qp)
        T = model.link_poses(q)
        Y = regressor(params, q, qd, qdd)
        scale = np.abs(Yp).max()
        for i, cn in enumerate(model.coordinate_names):
            p = int(tree.coord_link[i])
            jid = pm.getJointId(cn)
            X = np.linalg.inv(T[p]) @ pd.oMi[jid].homogeneous
            mapped = Yp[:, 10 * (jid - 1):10 * jid] @ pin_map(X)
            c = params.link_parameters(tree.link_names[p])
            err = np.abs(Y[:, c] - mapped).max() / scale
            assert err < TOL_PEER, (name, cn, err)
            compared += 1
    assert compared == 3 * model.n


# -- joint terms, couplings, tendons ------------------------------------------------------------------------
@corpus.needs_corpus
def test_joint_columns_in_closed_form():
    """damping ``b q'``, Coulomb ``f q' / sqrt(q'^2 + v_s^2)``, offset, armature: against inverse dynamics of a
    model with that armature (E49) plus the closed forms."""
    model = _load(ROBOTS["ur5"])
    params = ParameterSet.from_model(model, slip_speed=0.05)
    rng = np.random.default_rng(4)
    v = params.values.copy()
    b, f, o, a = (rng.uniform(0.1, 2.0, model.n) for _ in range(4))
    for kind, vals in (("damping", b), ("friction", f), ("offset", o), ("armature", a)):
        for j, cn in enumerate(model.coordinate_names):
            v[params.index(f"{kind}_{cn}")] = vals[j]
    Q, QD, QDD = _states(model, 5, 5)
    armed = params.to_model(v)
    assert np.array_equal(armed.tree.armature, a)
    expect = armed.inverse_dynamics(Q, QD, QDD) + b * QD + f * QD / np.sqrt(QD ** 2 + 0.05 ** 2) + o
    got = regressor(params, Q, QD, QDD) @ v
    assert np.abs(got - expect).max() < TOL * np.abs(expect).max()


MIMIC = """<robot name="mimic_arm">
  <link name="base"/>
  <link name="a"><inertial><mass value="1.2"/><origin xyz="0.1 0.02 0"/><inertia ixx="0.01" iyy="0.02" izz="0.015" ixy="0.001" ixz="0" iyz="0"/></inertial></link>
  <link name="b"><inertial><mass value="0.7"/><origin xyz="0.2 0 0.03"/><inertia ixx="0.004" iyy="0.006" izz="0.005" ixy="0" ixz="0.0005" iyz="0"/></inertial></link>
  <link name="c"><inertial><mass value="0.3"/><origin xyz="0.05 0.01 0"/><inertia ixx="0.001" iyy="0.002" izz="0.002" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="a"/><axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="10" velocity="5"/></joint>
  <joint name="j2" type="revolute"><parent link="a"/><child link="b"/><origin xyz="0.3 0 0" rpy="1.5707963 0 0"/><axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="10" velocity="5"/></joint>
  <joint name="j3" type="revolute"><parent link="b"/><child link="c"/><origin xyz="0.25 0 0"/><axis xyz="0 1 0"/><mimic joint="j2" multiplier="-0.5" offset="0.1"/><limit lower="-3" upper="3" effort="10" velocity="5"/></joint>
</robot>"""


def test_coupled_coordinates_and_tendons():
    """Mimic coupled (E42): ``Y pi`` = inverse dynamics in the model's coordinates. A fixed tendon (E76)
    ``l = c . q``: its columns ``c l'``, ``c reg(l')``, ``c l''``."""
    model = load_urdf_string(MIMIC, mimic="coupled")
    assert model.coupling is not None and model.n == 2
    c = np.array([1.0, -0.4])
    params = ParameterSet.from_model(model, tendons=[("t0", c, 0.3, 0.2, 0.05)])
    Q, QD, QDD = _states(model, 6, 6)
    tau = model.inverse_dynamics(Q, QD, QDD)
    v = params.values.copy()
    for kind in ("damping", "friction", "offset", "armature"):
        v[[k for k, kd in enumerate(params.kind) if kd == kind]] = 0.0
    ld, ldd = QD @ c, QDD @ c
    tendon = np.outer(0.3 * ld + 0.2 * ld / np.sqrt(ld ** 2 + params.slip_speed ** 2) + 0.05 * ldd, c)
    got = regressor(params, Q, QD, QDD) @ v
    assert np.abs(got - tau - tendon).max() < TOL * np.abs(tau).max()
    assert params.names[-3:] == ("tendon_damping_t0", "tendon_friction_t0", "tendon_armature_t0")


def test_parameter_layout_round_trip():
    """``link_vector``/``link_matrix`` and ``to_model`` keep H; names follow LINK_ENTRIES."""
    model = load_urdf_string(MIMIC)
    params = ParameterSet.from_model(model)
    assert params.names[:10] == tuple(f"{e}_a" for e in LINK_ENTRIES)
    back = params.to_model(params.values)
    assert np.array_equal(back.tree.H, model.tree.H)
    assert back.info["identified"] is True
    with pytest.raises(ValueError, match="coordinates"):
        ParameterSet.from_model(model, damping={"nope": 1.0})
    with pytest.raises(ValueError, match="shape"):
        regressor(params, np.zeros(2), np.zeros(3), np.zeros(3))


# -- MJCF armature (hinges, balls, a free body), a moving base ------------------------------------------------
@pytest.fixture(scope="module")
def mjcf_files(tmp_path_factory):
    from mjcf_models import write_models

    return write_models(tmp_path_factory.mktemp("mjcf_ident"))


@pytest.mark.parametrize("name", ["hinge_anchor", "ball", "free", "multi_joint"])
def test_armature_units_and_a_moving_base(mjcf_files, name):
    """MJCF models with armature (E49): a hinge's own unit and a ball's or free body's one unit on its three
    angles; ``Y pi`` equals inverse dynamics, also under a moving base {A} (E13), per row."""
    from urdf2links import BaseState, load_mjcf

    model = load_mjcf(mjcf_files[name])
    params = ParameterSet.from_model(model)
    assert any(k == "armature" for k in params.kind)
    rng = np.random.default_rng(16)
    S = 5
    Q = model.info["q0"] + rng.uniform(-1, 1, (S, model.n))
    QD, QDD = rng.normal(size=(S, model.n)), rng.normal(size=(S, model.n))
    tau = model.inverse_dynamics(Q, QD, QDD)
    Y = regressor(params, Q, QD, QDD)
    assert np.abs(Y @ params.values - tau).max() < TOL * np.abs(tau).max()
    base = BaseState(rng.normal(size=(S, 6)), rng.normal(size=(S, 6)), rng.normal(size=(S, 6)))
    tau = model.inverse_dynamics(Q, QD, QDD, base=base)
    Y = regressor(params, Q, QD, QDD, base=base)
    assert np.abs(Y @ params.values - tau).max() < TOL * np.abs(tau).max()

"""Route 1 of the MuJoCo comparison: the project's own tree as MJCF (urdf2links.compare.mujoco_side.mjcf, urdf2links.compare.mujoco_side.mujoco_run)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import mujoco  # a declared dependency: a broken MuJoCo fails the suite

from scipy.integrate import solve_ivp  # noqa: E402

import urdf2links  # noqa: E402
from builders import random_H, random_tree  # noqa: E402
from urdf2links.compare.mujoco_side.mjcf import mjcf_from_model  # noqa: E402
from urdf2links.compare.mujoco_side.mujoco_run import mujoco_accelerations, run_mujoco  # noqa: E402
from urdf2links import BaseState, LinkSpec, Model, Wrench, build_tree  # noqa: E402
from urdf2links.dynamics.transforms import base_transforms  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
ROBOTS = ROOT / "robots"


def load(name, **kw):
    return urdf2links.load_urdf(str(ROBOTS / name), **kw)


def shipped():
    return [load("double_pendulum.urdf"), load("prismatic_revolute.urdf"),
            load("free_body.urdf", floating_base=True), load("deck_crane.urdf"), load("ur5_like.urdf")]


# Random trees with massless links at 1 and 4: seed 0 gives both a negligible mass (two children
# each), seed 13 folds link4 (one child), seed 16 does one of each; seed 3 has 2 to 6 coordinates
# per link (up to six joints in one body). All have a positive definite A.
RANDOM = [(0, dict(links=8, massless=(1, 4), max_coords=4)),
          (13, dict(links=8, massless=(1, 4), max_coords=4)),
          (16, dict(links=8, massless=(1, 4), max_coords=4)),
          (3, dict(links=6, max_coords=6, min_coords=2))]


def gimbal_chain():
    """A ball joint written as three hinges through two massless links (a cascade of folds into
    'ball'), then a massless slide with a massive child, and a massive branch off the ball."""
    H = random_H(np.random.default_rng(7))
    return Model(build_tree([
        LinkSpec("g1", None, (0.1, 0.2, 0.3, 0.4, -0.2, 0.3), {"phi_x": "bx"}),
        LinkSpec("g2", "g1", (0.0, 0.5, 0.0, 0.0, 0.7, 0.0), {"phi_y": "by"}),
        LinkSpec("ball", "g2", (0.3, 0.0, -0.2, 1.1, 0.0, 0.4), {"phi_z": "bz"}, H),
        LinkSpec("slider", "ball", (0.5, 0.1, 0.0, 0.0, 0.0, 0.9), {"x": "sx", "phi_y": "sy"}),
        LinkSpec("tip", "slider", (0.2, 0.0, 0.1, 0.3, 0.2, 0.1), {"phi_x": "tx"}, 0.5 * H),
        LinkSpec("branch", "ball", (0.0, -0.4, 0.0, 0.0, 0.0, 0.0), {"phi_x": "rx"}, 0.3 * H),
    ]), name="gimbal_chain")


def random_models():
    return [random_tree(seed, **kw) for seed, kw in RANDOM] + [gimbal_chain()]


def rel(a, b):
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300))


def random_base(rng):
    return BaseState(rng.normal(size=6), rng.normal(size=6), rng.normal(size=6))


# --------------------------------------------------------------------------- MuJoCo's semantics


def test_mujoco_multi_joint_semantics():
    """What urdf2links.compare.mujoco_side.mjcf relies on: a body's joints apply in order, each axis in the body frame as
    moved by the joints before it (F <- F Rot(axis_j, q_j)), slides along the axis as rotated by
    the hinges before them, hinges about their anchor ``pos``."""
    xml = """<mujoco><compiler angle="radian" inertiafromgeom="false"/><worldbody>
      <body name="b" pos="0.1 0.2 0.3" quat="0.8 0.6 0 0">
        <inertial pos="0 0 0" mass="1" diaginertia="1 1 1"/>
        <joint name="h1" type="hinge" axis="1 0 0"/>
        <joint name="h2" type="hinge" axis="0 1 0" pos="0 0 0.5"/>
        <joint name="s" type="slide" axis="0 0 1"/>
      </body></worldbody></mujoco>"""
    m = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(m)
    a, b, s = 0.7, -1.1, 0.4
    d.qpos[:] = (a, b, s)
    mujoco.mj_kinematics(m, d)

    def rot(axis, v):
        K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
        return np.eye(3) + np.sin(v) * K + (1 - np.cos(v)) * K @ K

    def T(R=np.eye(3), p=np.zeros(3)):
        out = np.eye(4)
        out[:3, :3], out[:3, 3] = R, p
        return out

    M = T(rot(np.array([1.0, 0, 0]), 2 * np.arctan2(0.6, 0.8)), np.array([0.1, 0.2, 0.3]))
    anchor = np.array([0, 0, 0.5])
    J2 = T(p=anchor) @ T(rot(np.array([0, 1.0, 0]), b)) @ T(p=-anchor)
    expected = M @ T(rot(np.array([1.0, 0, 0]), a)) @ J2 @ T(p=np.array([0, 0, s]))
    assert np.allclose(d.xmat[1].reshape(3, 3), expected[:3, :3], atol=1e-14)
    assert np.allclose(d.xpos[1], expected[:3, 3], atol=1e-14)
    # the other order would differ: the second hinge's axis is NOT the parent's y
    wrong = M @ T(rot(np.array([0, 1.0, 0]), b)) @ T(rot(np.array([1.0, 0, 0]), a))
    assert not np.allclose(d.xmat[1].reshape(3, 3), wrong[:3, :3], atol=1e-3)


# --------------------------------------------------------------------------- (a) frames


@pytest.mark.parametrize("model", shipped() + random_models(), ids=lambda m: m.name)
def test_link_poses_equal(model):
    mj = mjcf_from_model(model)
    rng = np.random.default_rng(1)
    for _ in range(5):
        q = rng.uniform(-3, 3, model.n)
        d = mj.data(q)
        assert np.max(np.abs(mj.link_poses(d) - model.link_poses(q))) < 1e-12
    # MuJoCo's qpos is the project's q: dofs are mapped one to one
    assert sorted(mj.dof_index.tolist()) == list(range(model.n))
    assert mj.model.nv == model.n


@pytest.mark.parametrize("model", [load("double_pendulum.urdf"), load("free_body.urdf", floating_base=True),
                                   random_models()[1]], ids=lambda m: m.name)
def test_link_poses_with_moving_base(model):
    mj = mjcf_from_model(model, moving_base=True)
    assert mj.base_dofs.tolist() == list(range(6))  # base_A comes first
    rng = np.random.default_rng(2)
    for _ in range(5):
        q = rng.uniform(-3, 3, model.n)
        bs = random_base(rng)
        d = mj.data(q, base=bs)
        B = base_transforms(bs)[0]
        assert np.max(np.abs(np.asarray(d.xmat[mj.base_body]).reshape(3, 3) - B[:3, :3])) < 1e-13
        assert np.max(np.abs(d.xpos[mj.base_body] - B[:3, 3])) < 1e-13
        assert np.max(np.abs(mj.link_poses(d) - model.link_poses(q, base=bs))) < 1e-12


def test_folding_and_tiny_mass_are_recorded():
    crane = mjcf_from_model(load("deck_crane.urdf"))
    assert crane.folded_links == ("sway_gimbal",)
    assert crane.body_of_link[crane.source.tree.link_index("sway_gimbal")] == -1
    assert any("folded" in n for n in crane.notes)
    tiny = mjcf_from_model(random_models()[0])
    assert tiny.tiny_mass_links == ("link1", "link4") and any("negligible mass" in n for n in tiny.notes)
    one = mjcf_from_model(random_models()[1])
    assert one.folded_links == ("link4",) and not one.tiny_mass_links
    chain = mjcf_from_model(gimbal_chain())
    assert chain.folded_links == ("g1", "g2", "slider") and not chain.tiny_mass_links
    m = chain.model
    ball = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "ball")
    assert m.body_jntnum[ball] == 3 and m.nbody == 4  # world, ball (bx, by, bz), tip, branch


def test_physics_switched_off():
    mj = mjcf_from_model(load("double_pendulum.urdf"))
    m = mj.model
    flags = int(m.opt.disableflags)
    for name in ("mjDSBL_CONTACT", "mjDSBL_LIMIT", "mjDSBL_EQUALITY", "mjDSBL_FRICTIONLOSS",
                 "mjDSBL_SPRING", "mjDSBL_DAMPER"):
        assert flags & int(getattr(mujoco.mjtDisableBit, name)), name
    assert np.all(m.dof_armature == 0) and np.all(m.dof_damping == 0) and np.all(m.jnt_stiffness == 0)
    assert m.ngeom == 0 and np.allclose(m.opt.gravity, 0)
    assert m.opt.integrator == mujoco.mjtIntegrator.mjINT_RK4 and m.opt.timestep == 1e-4
    assert np.isclose(m.body_mass.sum(), mj.source.tree.mass.sum())
    from urdf2links.scenes.scene import Spring

    sp = mjcf_from_model(mj.source, springs=[Spring("elbow", 3.0, 0.2, 0.5)])
    flags = int(sp.model.opt.disableflags)
    assert not flags & int(mujoco.mjtDisableBit.mjDSBL_SPRING)
    assert not flags & int(mujoco.mjtDisableBit.mjDSBL_DAMPER)


# --------------------------------------------------------------------------- (b) terms


@pytest.mark.parametrize("model", shipped() + random_models(), ids=lambda m: m.name)
def test_mass_matrix_and_bias(model):
    mj = mjcf_from_model(model, gravity=model.gravity_vector)
    rng = np.random.default_rng(3)
    for _ in range(5):
        q, qd = rng.uniform(-3, 3, model.n), rng.normal(size=model.n)
        M, bias = mj.terms(q, qd)
        assert rel(M, model.mass_matrix(q)) < 1e-10
        assert rel(bias, model.bias(q, qd) + model.gravity(q)) < 1e-10


def test_random_trees_mix_coordinate_types():
    slots = np.concatenate([m.tree.coord_slot for m in random_models()])
    assert {0, 1, 2} & set(slots.tolist()) and {3, 4, 5} & set(slots.tolist())


@pytest.mark.parametrize("model", [load("double_pendulum.urdf"), load("deck_crane.urdf"), random_models()[3]],
                         ids=lambda m: m.name)
def test_terms_with_moving_base(model):
    """Robot block of M and robot rows of qfrc_bias at the base's pose and rate (no base acceleration)."""
    mj = mjcf_from_model(model, gravity=model.gravity_vector, moving_base=True)
    rng = np.random.default_rng(4)
    for _ in range(4):
        q, qd = rng.uniform(-3, 3, model.n), rng.normal(size=model.n)
        bs = random_base(rng)
        bs0 = BaseState(bs.pose, bs.rate, np.zeros(6))
        M, bias = mj.terms(q, qd, base=bs)
        assert rel(M, model.mass_matrix(q, base=bs)) < 1e-10
        assert rel(bias, model.bias(q, qd, base=bs0) + model.gravity(q, base=bs0)) < 1e-10


# --------------------------------------------------------------------------- (c) base imposed


@pytest.mark.parametrize("model", [load("double_pendulum.urdf"), load("prismatic_revolute.urdf"),
                                   load("deck_crane.urdf"), load("free_body.urdf", floating_base=True),
                                   random_models()[1], random_models()[3], gimbal_chain()], ids=lambda m: m.name)
def test_accelerations_with_prescribed_base(model):
    mj = mjcf_from_model(model, gravity=model.gravity_vector, moving_base=True)
    rng = np.random.default_rng(5)
    for _ in range(4):
        q, qd = rng.uniform(-1.5, 1.5, model.n), rng.normal(size=model.n)
        bs = random_base(rng)
        t = float(rng.uniform(0, 3))
        ours = model.forward_dynamics(q, qd, t=t, base=bs)
        theirs = mujoco_accelerations(mj, q, qd, t=t, base=bs)
        assert rel(theirs, ours) < 1e-9


def test_torques_loads_springs_match_forward_dynamics():
    """Joint torques, springs and dampers, forces at points and moments (link and world axes),
    one on a folded massless link (deck crane's sway_gimbal), with and without a moving base."""
    from urdf2links.scenes.scene import Spring

    model = load("deck_crane.urdf")
    springs = [Spring("luff", 5e3, 0.3, 200.0), Spring("sway_y", 0.0, 0.0, 50.0)]
    rng = np.random.default_rng(6)
    for moving in (False, True):
        mj = mjcf_from_model(model, gravity=model.gravity_vector, springs=springs, moving_base=moving)
        for _ in range(3):
            q, qd = rng.uniform(-1, 1, model.n), rng.normal(size=model.n)
            tau = rng.normal(size=model.n) * 1e3
            loads = [Wrench("load", force=rng.normal(size=3) * 1e3, point=rng.normal(size=3), frame="link"),
                     Wrench("boom", force=rng.normal(size=3) * 1e3, moment=rng.normal(size=3) * 1e3,
                            point=rng.normal(size=3), frame="world"),
                     Wrench("sway_gimbal", force=rng.normal(size=3) * 1e3, moment=rng.normal(size=3) * 1e3,
                            point=rng.normal(size=3), frame="link")]
            bs = random_base(rng) if moving else None
            passive = np.zeros(model.n)
            for s in springs:
                i = model.coordinate_names.index(s.coordinate)
                passive[i] = -s.stiffness * (q[i] - s.rest) - s.damping * qd[i]
            ours = model.forward_dynamics(q, qd, tau + passive, loads=loads, base=bs)
            theirs = mujoco_accelerations(mj, q, qd, tau=tau, loads=loads, base=bs)
            assert rel(theirs, ours) < 1e-9


# --------------------------------------------------------------------------- (d), (e) trajectories


def _reference(model, q0, qd0, t_eval, base=None):
    n = model.n

    def f(t, y):
        return np.concatenate([y[n:], model.forward_dynamics(y[:n], y[n:], t=t, base=base)])

    sol = solve_ivp(f, (0.0, t_eval[-1]), np.concatenate([q0, qd0]), method="DOP853", rtol=1e-12,
                    atol=1e-12, t_eval=t_eval)
    assert sol.success
    return sol.y[:n].T, sol.y[n:].T


def test_double_pendulum_trajectory():
    model = load("double_pendulum.urdf")
    mj = mjcf_from_model(model, gravity=model.gravity_vector, timestep=1e-4, integrator="RK4")
    q0, qd0 = np.array([1.0, -0.5]), np.array([0.3, 0.0])
    run = run_mujoco(mj, q0=q0, qd0=qd0, t_end=2.0, samples=201)
    assert run.nsteps == 20000 and run.q.shape == (201, 2) and not run.notes
    assert np.allclose(run.t, np.linspace(0, 2, 201), rtol=0, atol=1e-12)
    q_ref, qd_ref = _reference(model, q0, qd0, run.t)
    assert np.max(np.abs(run.q - q_ref)) < 1e-6
    assert np.max(np.abs(run.qd - qd_ref)) < 1e-5
    E = np.array([model.kinetic_energy(q, qd) for q, qd in zip(run.q, run.qd)])
    V = np.array([model.potential_energy(q) for q in run.q])
    assert np.max(np.abs(run.kinetic - E)) < 1e-9 and np.max(np.abs(run.potential - V)) < 1e-9
    assert np.ptp(run.total_energy) < 1e-9
    assert mujoco.get_mjcb_control() is None


def heave(t):
    w = 2 * np.pi * 0.5
    z = np.zeros(6)
    pose, rate, accel = z.copy(), z.copy(), z.copy()
    pose[2], rate[2], accel[2] = 0.2 * np.sin(w * t), 0.2 * w * np.cos(w * t), -0.2 * w * w * np.sin(w * t)
    return BaseState(pose, rate, accel)


def test_heaving_base_trajectory():
    model = load("double_pendulum.urdf")
    mj = mjcf_from_model(model, gravity=model.gravity_vector, moving_base=True)
    q0, qd0 = np.array([0.8, 0.4]), np.array([0.0, -0.2])
    run = run_mujoco(mj, q0=q0, qd0=qd0, t_end=2.0, samples=101, base=heave)
    q_ref, _ = _reference(model, q0, qd0, run.t, base=heave)
    assert np.max(np.abs(run.q - q_ref)) < 1e-6
    assert run.base_tracking_error < 1e-9
    assert np.allclose(run.base_pose[:, 2], [heave(t).pose[2] for t in run.t], rtol=0, atol=1e-9)
    E = np.array([model.kinetic_energy(q, qd, t=t, base=heave) for t, q, qd in zip(run.t, run.q, run.qd)])
    V = np.array([model.potential_energy(q, t=t, base=heave) for t, q in zip(run.t, run.q)])
    assert np.max(np.abs(run.kinetic - E)) < 1e-8 and np.max(np.abs(run.potential - V)) < 1e-8
    assert mujoco.get_mjcb_control() is None


# --------------------------------------------------------------------------- run plumbing


def test_scene_run_matches_plan():
    """A scene with torque, spring/damper, a force at a point and base motion: run_mujoco(scene)
    against the project's own plan of the same scene."""
    import urdf2links.scenes.plan as plan_mod
    from urdf2links.scenes.python_plan import PythonPlan
    from urdf2links.compare.mujoco_side.mjcf import mjcf_from_scene
    from urdf2links.scenes.scene_read import scene_from_dict

    scene = scene_from_dict({
        "robot": {"urdf": str(ROBOTS / "double_pendulum.urdf")},
        "gravity": {"magnitude": 9.81},
        "base": {"y": {"sines": [[0.1, 0.7]]}},
        "torque": [{"coordinate": "shoulder", "value": {"sines": [[2.0, 0.5]]}}],
        "spring": [{"coordinate": "elbow", "stiffness": 4.0, "rest": 0.2, "damping": 0.3}],
        "force": [{"link": "lower", "point": [0, 0, -1.0], "frame": "world", "value": [0, 1.5, 0.5]}],
        "initial": {"q": {"shoulder": 0.5}},
        "run": {"t_end": 0.5, "samples": 11},
    }, where="<test>")
    model = scene.model()
    plan = PythonPlan(plan_mod.compile_plan(scene, model))
    mj = mjcf_from_scene(scene, model, timestep=1e-4)
    run = run_mujoco(mj, scene)
    n = model.n
    q0, qd0 = scene.initial_state(model)
    sol = solve_ivp(lambda t, y: np.concatenate([y[n:], plan.accelerations(t, y[:n], y[n:])]), (0, 0.5),
                    np.concatenate([q0, qd0]), method="DOP853", rtol=1e-12, atol=1e-12, t_eval=run.t)
    assert np.max(np.abs(run.q - sol.y[:n].T)) < 1e-8
    assert run.base_tracking_error < 1e-9
    Vp = [plan.potential_energy(t, q) for t, q in zip(run.t, run.q)]
    assert np.max(np.abs(run.potential - Vp)) < 1e-8
    with pytest.raises(ValueError, match="gravity"):
        run_mujoco(mjcf_from_model(model, moving_base=True), scene)


def test_callback_removed_on_error_and_samples_off_grid():
    model = load("double_pendulum.urdf")
    mj = mjcf_from_model(model, gravity=model.gravity_vector)

    def bad(t):
        raise RuntimeError("torque function failed")

    with pytest.raises(RuntimeError, match="torque function failed"):
        run_mujoco(mj, q0=[0.1, 0.0], t_end=0.01, samples=3, torques=bad)
    assert mujoco.get_mjcb_control() is None
    run = run_mujoco(mj, q0=[0.1, 0.0], t_end=0.01, samples=4, timestep=0.002, integrator="Euler")
    assert run.integrator == "Euler" and run.nsteps == 5 and run.notes
    assert mj.model.opt.timestep == 1e-4  # the caller's model is not changed
    assert np.max(np.abs(run.t - np.linspace(0, 0.01, 4))) <= 0.001 + 1e-12


def test_urdf2links_does_not_import_mujoco():
    code = ("import sys, urdf2links, urdf2links.dynamics.model, urdf2links.scenes.scene, urdf2links.dynamics.transforms; "
            "assert 'mujoco' not in sys.modules, 'urdf2links imported mujoco'")
    subprocess.run([sys.executable, "-c", code], check=True, cwd=ROOT)

"""Re-charting floating links through phi_y = +-pi/2 (urdf2links.integration.charts): the switch changes nothing
physical, the shipped tumbling box keeps its momenta through the passages and agrees with an
independent rigid-body integration, and without re-charting the run stops with a clear error."""

from __future__ import annotations

import textwrap
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from urdf2links.integration.charts import Chart, angle_block_condition, floating_links, rechart, to_original
from urdf2links.errors import DynamicsError, SceneError
from urdf2links.dynamics.model import Model
from urdf2links.dynamics.rotations import xyz_angles_to_matrix
from urdf2links.scenes.scene_read import load_scene
from urdf2links.dynamics.oracles.recursive import RecursivePlan
from urdf2links.integration.simulate import simulate
from urdf2links.dynamics.tree import LinkSpec, build_tree

ROBOTS = Path(__file__).resolve().parent.parent / "robots"
GIMBAL = ROBOTS / "free_body_gimbal.toml"
M_BODY, J_BODY = 3.0, np.diag([0.2, 0.35, 0.5])  # robots/free_body.urdf: COM at the link origin


def _kinematics(model: Model, q, qd):
    """T and T' of every link (the numpy recursive form, an oracle independent of the kernels)."""
    return RecursivePlan(model.tree).kinematics(*model.tree_state(q, qd), None)


def momenta(model: Model, q, qd):
    """Linear momentum p = sum T' H e4 and angular momentum about {0} L = sum of the antisymmetric
    part of K = T H T'^T = integral(r v^T dm) (L_x = K_yz - K_zy, ...), from the poses and their rates."""
    kin = _kinematics(model, q, qd)
    p = np.einsum("lab,lb->a", kin.Td, model.tree.H[:, :, 3])[:3]
    K = np.einsum("lab,lbc,ldc->ad", kin.T, model.tree.H, kin.Td)[:3, :3]
    return p, np.array([K[1, 2] - K[2, 1], K[2, 0] - K[0, 2], K[0, 1] - K[1, 0]])


def floating_arm(gravity=(0.0, 0.0, -9.81)):
    """A free base (offsets in its angle slots) carrying a two-link arm: the re-charted link has children."""
    rng = np.random.default_rng(3)

    def H(m, c, d):
        c, J = np.asarray(c, float), np.diag(d)
        S = 0.5 * np.trace(J) * np.eye(3) - J + m * np.outer(c, c)
        return np.block([[S, m * c[:, None]], [m * c[None, :], np.array([[m]])]])
    coords = {s: f"base.{s}" for s in ("x", "y", "z", "phi_x", "phi_y", "phi_z")}
    return Model(build_tree([
        LinkSpec("base", None, (0.1, -0.2, 0.3, 0.2, -0.1, 0.4), coords, H(4.0, (0.05, 0.0, -0.02), (0.3, 0.4, 0.5))),
        LinkSpec("upper", "base", (0.2, 0.0, 0.1, 0.3, 0.0, 0.0), {"phi_y": "shoulder"}, H(1.0, (0, 0, -0.3), (0.05, 0.05, 0.01))),
        LinkSpec("lower", "upper", (0.0, 0.0, -0.6, 0.0, 0.0, 0.0), {"phi_x": "elbow"}, H(0.5, (0, 0, -0.2), (0.02, 0.02, 0.005))),
    ]), name="floating_arm", gravity=gravity), rng


def test_a_switch_changes_no_pose_energy_or_momentum():
    """Re-charting twice (near phi_y = pi/2, then from a non-zero chart) keeps every link's T and T',
    E, V and the momenta to rounding, and maps back to the original coordinates."""
    model, rng = floating_arm()
    link, = floating_links(model)
    q = np.r_[rng.normal(size=3), 0.7, 1.42, -2.1, rng.normal(size=2)]
    qd = rng.normal(size=8)
    chart = Chart(model)
    for rep in range(2):
        new, q2, qd2 = rechart(model, chart, [link], q, qd)
        assert np.all(q2[link.angles] == 0) and np.array_equal(q2[:3], q[:3]) and np.array_equal(qd2[:3], qd[:3])
        k1 = _kinematics(chart.model, q, qd)
        k2 = _kinematics(new.model, q2, qd2)
        idx = [new.model.link_names.index(nm) for nm in chart.model.link_names if not nm.endswith("~chart")]
        keep = [i for i, nm in enumerate(chart.model.link_names) if not nm.endswith("~chart")]
        assert np.abs(k1.T[keep] - k2.T[idx]).max() < 1e-13
        assert np.abs(k1.Td[keep] - k2.Td[idx]).max() < 1e-12
        E1, E2 = chart.model.kinetic_energy(q, qd), new.model.kinetic_energy(q2, qd2)
        assert abs(E1 - E2) < 1e-12 * E1
        assert abs(chart.model.potential_energy(q) - new.model.potential_energy(q2)) < 1e-12 * abs(model.potential_energy(q))
        for a, b in zip(momenta(chart.model, q, qd), momenta(new.model, q2, qd2)):
            assert np.abs(a - b).max() < 1e-12 * np.abs(a).max()
        if rep == 0:  # the new chart is regular where the old one was nearly singular (cos phi_y = 0.15)
            assert angle_block_condition(new.model, link, q2) < 0.1 * angle_block_condition(chart.model, link, q)
        chart, q, qd = new, q2 + np.r_[0, 0, 0, 0.3, -0.2, 0.5, 0, 0], qd2  # move on in the new chart
    # back to the loaded model's coordinates: same poses and velocities
    ref = np.r_[q[:3], 0.7, 1.42, -2.1, q[6:]]
    qo, qdo = to_original(chart, [link], q, qd, ref)
    k1 = _kinematics(chart.model, q, qd)
    ko = _kinematics(model, qo, qdo)
    assert np.abs(k1.T[[1, 2, 3]] - ko.T).max() < 1e-13 and np.abs(k1.Td[[1, 2, 3]] - ko.Td).max() < 1e-11
    R = xyz_angles_to_matrix(qo[3:6] + link.offsets)
    assert np.allclose(R, chart.relative_rotation(link, q), atol=1e-14)


@pytest.fixture(scope="module")
def gimbal():
    return simulate(GIMBAL, progress=False)


def test_the_tumbling_box_passes_the_singularity_keeping_its_momenta(gimbal):
    tr = gimbal
    s = tr.stats
    # phi_y reaches the guard (|cos phi_y| < 0.3) at every half turn: re-charts happen and are reported
    assert s["success"] and s["n_recharts"] >= 8 and s["segments"] == s["n_recharts"] + 1
    assert all(0 < r["t"] < 4 and r["cos_phi_y"] < 0.3 and r["cond_after"] < r["cond_before"] for r in s["recharts"])
    # the original chart really went to the singularity: |cos phi_y| of the reported angles gets small
    assert np.abs(np.cos(tr.q[:, 4])).min() < 0.05
    # momenta from the poses and their rates, in the chart that computed each sample
    ch = tr.charts
    P, L = zip(*(momenta(ch.segments[k].chart.model, y[:6], y[6:12]) for k, y in zip(ch.segment_of, ch.y_chart)))
    P, L = np.array(P), np.array(L)
    # DOP853 at rtol 1e-11 over ~350 steps in 13 segments: momenta hold to ~1e-11 relative; 1e-9 is the bound
    assert np.abs(P - P[0]).max() <= 1e-9 * np.abs(P[0]).max()
    assert np.abs(L - L[0]).max() <= 1e-9 * np.abs(L[0]).max()
    assert tr.energy_error < 1e-9
    # the body really tumbled: its angular momentum in body axes moved from the y axis (a flip)
    R = tr.poses["body"][:, :3, :3]
    Lb = np.einsum("kba,b->ka", R, L[0] - M_BODY * np.cross(tr.poses["body"][0, :3, 3], P[0] / M_BODY))
    assert Lb[:, 1].min() < -0.9 * np.abs(Lb[0, 1])


def test_the_trajectory_is_continuous_and_in_the_loaded_coordinates(gimbal):
    tr = gimbal
    scene = load_scene(GIMBAL)
    model = scene.model()
    dt = tr.t[1] - tr.t[0]
    # poses: consecutive samples differ by at most (|omega| r + |v|) dt, |omega| <= 6.1 rad/s, r = 1 (axes)
    jump = np.abs(np.diff(tr.poses["body"], axis=0)).max(axis=(1, 2))
    assert jump.max() < 6.5 * dt
    # q, qd are the loaded model's coordinates: they reproduce the recorded poses; angles unwrapped
    # (no 2 pi jumps; near the passage the original phi_x, phi_z swing by ~pi within a few samples)
    for i in range(0, len(tr.t), 7):
        assert np.abs(model.link_poses(tr.q[i])[0] - tr.poses["body"][i]).max() < 1e-12
    assert np.abs(np.diff(tr.q[:, 3:], axis=0)).max() < 3.0
    assert np.array_equal(tr.q[:, :3], tr.poses["body"][:, :3, 3])  # translation: the same numbers
    # the dense output gives the same original coordinates between and at the samples
    assert np.abs(tr.sol(tr.t[::50]) - np.c_[tr.q, tr.qd, tr.energy["work"]][::50]).max() < 1e-9
    mid = 0.5 * (tr.t[100] + tr.t[101])
    assert np.abs(model.link_poses(tr.sol(mid)[:6])[0] - 0.5 * (tr.poses["body"][100] + tr.poses["body"][101])).max() < 0.01


def test_the_tumbling_box_agrees_with_an_independent_rigid_body_integration(gimbal):
    """Oracle: Euler's equations J w' = -w x J w and R' = R hat(w) in rotation matrices (no angles),
    x' = v, v' = 0, by scipy's DOP853 at rtol 1e-13."""
    tr = gimbal
    scene = load_scene(GIMBAL)
    q0, qd0 = scene.initial_state(scene.model())
    Jinv = np.linalg.inv(J_BODY)

    def rhs(t, y):
        R, w = y[6:15].reshape(3, 3), y[15:]
        W = np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])
        return np.r_[y[3:6], np.zeros(3), (R @ W).ravel(), -Jinv @ np.cross(w, J_BODY @ w)]
    w0 = np.array([qd0[3], qd0[4], qd0[5]])  # E(0) = 1: the body rates are the angle rates at zero angles
    y0 = np.r_[q0[:3], qd0[:3], xyz_angles_to_matrix(q0[3:]).ravel(), w0]
    ref = solve_ivp(rhs, (0, tr.t[-1]), y0, method="DOP853", rtol=1e-13, atol=1e-14, t_eval=tr.t)
    assert ref.success
    R_ref = ref.y[6:15].T.reshape(-1, 3, 3)
    # both at rtol <= 1e-11 over 4 s of an unstable (Dzhanibekov) spin: they agree to ~1e-9
    assert np.abs(tr.poses["body"][:, :3, :3] - R_ref).max() < 1e-8
    assert np.abs(tr.poses["body"][:, :3, 3] - ref.y[:3].T).max() < 1e-8


def test_without_recharting_the_run_stops_with_a_clear_error():
    """A near-exact passage (x rate 1e-4 rad/s): the original chart comes within |cos phi_y| < 1e-3 at the
    first half turn; recharting off raises a DynamicsError there, recharting on passes."""
    scene = load_scene(GIMBAL)
    scene = replace(scene, qd0={**scene.qd0, "body.phi_x": 1e-4}, run=replace(scene.run, t_end=0.6, samples=121))
    with pytest.raises(DynamicsError, match=r"link 'body'.*singularity of their chart.*re-charting is off") as info:
        simulate(scene, progress=False, recharting=False)
    assert info.value.coordinates == ("body.phi_x", "body.phi_y", "body.phi_z")
    tr = simulate(scene, progress=False)
    assert tr.stats["n_recharts"] >= 2 and tr.energy_error < 1e-9


def test_work_carries_over_the_switches(tmp_path):
    """A world-frame moment does work on the tumbling box: h - h(0) - W stays at the integration's
    error across the re-charts (W is integrated on, not restarted)."""
    text = GIMBAL.read_text().replace('shipped = "free_body"', f'urdf = "{ROBOTS / "free_body.urdf"}"')
    text += textwrap.dedent("""
        [[moment]]
        link = "body"
        frame = "world"
        value = [0.3, 0, { sines = [[0.5, 2.0]] }]
        """)
    p = tmp_path / "gimbal_moment.toml"
    p.write_text(text)
    tr = simulate(p, t_end=1.5, progress=False)
    assert tr.stats["n_recharts"] >= 3 and np.abs(tr.energy["work"]).max() > 0.1
    assert tr.energy_error < 1e-9


def test_torques_on_angles_keep_the_chart_and_recharting_is_a_scene_key(tmp_path):
    scene = load_scene(GIMBAL)
    from urdf2links.scenes.functions import Constant
    sc = replace(scene, torques=(("body.phi_x", Constant(0.0)),), run=replace(scene.run, t_end=0.6))
    with pytest.raises(DynamicsError, match="not re-charted because"):
        simulate(replace(sc, qd0={**scene.qd0, "body.phi_x": 1e-4}), progress=False)
    bad = tmp_path / "bad.toml"
    bad.write_text(GIMBAL.read_text().replace("recharting = true", 'recharting = "yes"')
                   .replace('shipped = "free_body"', f'urdf = "{ROBOTS / "free_body.urdf"}"'))
    with pytest.raises(SceneError, match="run.recharting: must be true or false"):
        load_scene(bad)
    off = tmp_path / "off.toml"
    off.write_text(bad.read_text().replace('recharting = "yes"', "recharting = false"))
    assert load_scene(off).run.recharting is False

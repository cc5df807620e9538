"""Sweeps (urdf2links.integration.batch.simulate_batch) against one-at-a-time simulate(): the gravity-only UR5 scene, and
scenes where every effect acts (moving base, forces, torques, springs and dampers), each on its own."""

from __future__ import annotations

import numpy as np
import pytest

from urdf2links.integration.batch import simulate_batch
from urdf2links.locations import shipped_robots_dir
from urdf2links.scenes.scene_read import load_scene
from urdf2links.integration.simulate import simulate


@pytest.mark.parametrize("method", ["DOP853", "RK45"])
def test_batch_matches_single_runs(method):
    """Same scene, same tolerances; the batch lands steps on the sample times while simulate()
    interpolates, so the two differ by the integration error: bound 1e-6 rad at rtol 1e-9 over
    1 s (the pendulum is chaotic, growth ~1.8/s, so errors of ~1e-9 per step grow by ~e^1.8)."""
    scene = load_scene(shipped_robots_dir() / "ur5_falling.toml")
    model = scene.model()
    rng = np.random.default_rng(5)
    q0 = rng.uniform(-1, 1, size=(6, model.n))
    qd0 = rng.normal(size=(6, model.n))
    res = simulate_batch(scene, q0, qd0, t_end=1.0, samples=21, method=method, rtol=1e-9, atol=1e-12, model=model)
    assert res.success and res.q.shape == (6, 21, model.n)
    for b in (0, 3, 5):
        one = simulate(scene, q0=q0[b], qd0=qd0[b], t_end=1.0, samples=21, method=method, rtol=1e-9,
                       atol=1e-12, model=model, progress=False)
        assert np.abs(res.q[b] - one.q).max() < 1e-6
        assert np.abs(res.qd[b] - one.qd).max() < 1e-5


DRIVEN = {
    "base": {"base": {"z": {"sines": [[0.3, 0.8]]}, "phi_y": {"sines": [[0.2, 0.5, 0.3]]}}},
    "force": {"force": [{"link": "lower", "point": [0, 0, -1.1], "frame": "world",
                         "value": [0, {"sines": [[2.0, 0.7]]}, 0]}]},
    "torque": {"torque": [{"coordinate": "shoulder", "value": {"sines": [[1.5, 0.9]], "offset": 0.2}}]},
    "spring": {"spring": [{"coordinate": "elbow", "stiffness": 40.0, "rest": 0.3, "damping": 0.5}]},
}
DRIVEN["all"] = {k: v for d in DRIVEN.values() for k, v in d.items()}


@pytest.mark.parametrize("effect", sorted(DRIVEN))
def test_batch_matches_single_runs_with_every_effect(effect):
    """The double pendulum with gravity plus a moving base, a force, a torque or a spring-damper (and all
    together): each of B = 4 trajectories of the sweep equals simulate() from the same state, to 1e-6
    rad and 1e-5 rad/s over 1 s at rtol 1e-9 (the sweep lands steps on the samples, simulate interpolates:
    they differ by the integration error, grown by the chaotic motion as in the test above), and the
    work W of the non-potential forces too (1e-6 J). The effect really acts: the work differs from the
    gravity-only scene's zero by more than 1e-2 J in at least one run (the spring is potential: its
    damper works)."""
    from urdf2links.scenes.scene_read import scene_from_dict

    scene = scene_from_dict({"robot": {"shipped": "double_pendulum"}, "gravity": {}, **DRIVEN[effect]},
                            name=f"double_pendulum_{effect}")
    model = scene.model()
    rng = np.random.default_rng(7)
    q0, qd0 = rng.uniform(-1, 1, size=(4, model.n)), rng.normal(size=(4, model.n))
    res = simulate_batch(scene, q0, qd0, t_end=1.0, samples=11, rtol=1e-9, atol=1e-12, model=model)
    assert res.success, res.status
    for b in range(4):
        one = simulate(scene, q0=q0[b], qd0=qd0[b], t_end=1.0, samples=11, rtol=1e-9, atol=1e-12, model=model,
                       progress=False)
        assert np.abs(res.q[b] - one.q).max() < 1e-6, (effect, b)
        assert np.abs(res.qd[b] - one.qd).max() < 1e-5, (effect, b)
        assert np.abs(res.work[b] - one.energy["work"]).max() < 1e-6, (effect, b)
    assert np.abs(res.work).max() > 1e-2


def test_batch_rejects_bad_shapes():
    scene = load_scene(shipped_robots_dir() / "double_pendulum_chaos.toml")
    with pytest.raises(ValueError, match="q0 must have shape"):
        simulate_batch(scene, np.zeros((3, 5)))
    with pytest.raises(ValueError, match="method"):
        simulate_batch(scene, np.zeros((3, 2)), method="RK4")


def test_split_rows_and_sweep_states():
    from urdf2links.integration.batch import split_rows, sweep_states

    assert split_rows(10, 3) == [(0, 3), (3, 7), (7, 10)]
    assert split_rows(2, 5) == [(0, 1), (1, 2)]              # never an empty chunk
    scene = load_scene(shipped_robots_dir() / "double_pendulum_chaos.toml")
    model = scene.model()
    q0, qd0 = sweep_states(scene, model, 4, seed=2, spread=0.3)
    q, qd = scene.initial_state(model)
    assert q0.shape == (4, 2) and np.all(np.abs(q0 - q) <= 0.3) and np.all(qd0 == qd)
    assert np.array_equal(q0, sweep_states(scene, model, 4, seed=2, spread=0.3)[0])   # seeded
    with pytest.raises(ValueError, match="spread"):
        sweep_states(scene, model, 4, spread=-1.0)


def test_sweep_on_a_dask_cluster_is_the_one_machine_sweep(dask_client):
    """Split into three chunks over two workers, put back in order: every trajectory is integrated on
    its own by the same compiled loop, so the result is the one machine's bit for bit."""
    from urdf2links.integration.batch import sweep_states

    scene = load_scene(shipped_robots_dir() / "double_pendulum_chaos.toml")
    model = scene.model()
    q0, qd0 = sweep_states(scene, model, 7, seed=1, spread=0.2)
    here = simulate_batch(scene, q0, qd0, t_end=0.3, samples=7, model=model)
    there = simulate_batch(scene, q0, qd0, t_end=0.3, samples=7, model=model, client=dask_client, chunks=3)
    assert [c["rows"] for c in there.chunks] == [[0, 2], [2, 5], [5, 7]] and here.chunks == ()
    # every worker warmed before the timed round (one clock: the sweep's wall time leaves compilation out)
    assert there.compilation is not None and there.compilation.seconds > 0 and there.wall_time > 0
    for name in ("t", "q", "qd", "work", "nfev", "status"):
        assert np.array_equal(getattr(here, name), getattr(there, name)), name


def test_sweep_command(tmp_path):
    import subprocess
    import sys

    out = subprocess.run([sys.executable, "-m", "urdf2links.cli", "sweep",
                          str(shipped_robots_dir() / "double_pendulum_chaos.toml"), "--count", "5", "--t-end", "0.2",
                          "--samples", "5", "--spread", "0.05", "--out", str(tmp_path)], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert "5 initial states" in out.stdout and "5 reached the end" in out.stdout
    data = np.load(tmp_path / "double_pendulum_chaos_sweep.npz")
    assert data["q"].shape == (5, 5, 2) and data["q0"].shape == (5, 2)
    np.testing.assert_array_equal(data["q"][:, 0, :], data["q0"])
    assert "no batch loop" not in out.stdout        # the scene names DOP853: nothing replaced


def test_a_sweep_of_an_auto_scene_says_it_runs_dop853(tmp_path):
    """auto (the default method) has no batch loop: the sweep runs DOP853 and says so, not silently."""
    import subprocess
    import sys

    out = subprocess.run([sys.executable, "-m", "urdf2links.cli", "sweep", "ur5_stiff_servo", "--count", "2",
                          "--t-end", "0.01", "--samples", "3", "--out", str(tmp_path)], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert "the scene's method 'auto' has no batch loop; the sweep ran DOP853" in out.stdout, out.stdout
    res = simulate_batch(shipped_robots_dir() / "ur5_stiff_servo.toml", np.zeros((1, 6)), t_end=0.01, samples=3)
    assert res.method == "DOP853" and "has no batch loop" in res.notes[0]        # the API says it too

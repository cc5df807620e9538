"""Sweeps (urdf2links.batch.simulate_batch) against one-at-a-time simulate() on a shipped scene."""

from __future__ import annotations

import numpy as np
import pytest

from urdf2links.batch import simulate_batch
from urdf2links.locations import shipped_robots_dir
from urdf2links.scene import load_scene
from urdf2links.simulate import simulate


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


def test_batch_rejects_bad_shapes():
    scene = load_scene(shipped_robots_dir() / "double_pendulum_chaos.toml")
    with pytest.raises(ValueError, match="q0 must have shape"):
        simulate_batch(scene, np.zeros((3, 5)))
    with pytest.raises(ValueError, match="method"):
        simulate_batch(scene, np.zeros((3, 2)), method="RK4")

"""``identify --design``: the excitation scene (compare/identify/design.py).

- the scene's references (``[[computed_torque]]`` sines, as urdf2links reads them) are the designed Fourier
  series: position, velocity and acceleration to 1e-12 at 50 times (planted wrong once: the phase written as
  ``atan2(a, b)`` instead of ``atan2(b, a)`` made the positions differ by ~1 rad);
- the series stays within 0.8 of each joint's half range and velocity limit and the effort limit (the description's
  inverse dynamics along it), and its condition number is the one recomputed from the library's base parameters,
  not above the first candidate's.
"""

from __future__ import annotations

import numpy as np

from cli_runner import run_cli


def test_design_scene_is_the_trajectory_within_limits(tmp_path):
    from urdf2links.compare.identify.design import _score, design_trajectory, scene_toml
    from urdf2links.compare.identify.excitation import SAFETY, bounds_of_parts
    from urdf2links.identification import ParameterSet
    from urdf2links.locations import find_input
    from urdf2links.parsers.parts import parts_model, robot_parts
    from urdf2links.scenes.scene_read import load_scene

    urdf, _ = find_input("ur5_like")
    parts = robot_parts(urdf)
    model = parts_model(parts).model
    bounds = bounds_of_parts(parts, model.coordinate_names)
    d = design_trajectory(model, bounds, seed=3, candidates=3, rounds=5, samples=200)
    assert d.condition <= d.start_condition
    c, _peak = _score(ParameterSet.from_model(model, slip_speed=1e-2), model, d.trajectory, bounds, 200)
    assert c == d.condition
    t = np.linspace(0.0, d.trajectory.period, 50)
    q, qd, qdd = d.trajectory.evaluate(t)
    half = 0.5 * (bounds.upper - bounds.lower)
    assert np.all(np.abs(q - 0.5 * (bounds.upper + bounds.lower)) <= SAFETY * half * (1 + 1e-9))
    assert np.all(np.abs(qd) <= SAFETY * bounds.velocity * (1 + 1e-9))
    assert np.all(d.peak_effort <= SAFETY * bounds.effort)
    out = tmp_path / "design.toml"
    out.write_text(scene_toml(d, urdf, out=out))
    scene = load_scene(out)
    refs = dict(scene.computed_torque)
    for i, name in enumerate(d.trajectory.names):
        f = refs[name]
        got = np.c_[f(t), f.derivative(t), f.second_derivative(t)]
        np.testing.assert_allclose(got, np.c_[q[:, i], qd[:, i], qdd[:, i]], rtol=0, atol=1e-12)


def test_design_command_writes_a_scene(tmp_path):
    r = run_cli("identify", "ur5_like", "--design", str(tmp_path / "d.toml"))
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "d.toml").exists() and "condition number of the base regressor" in r.stdout

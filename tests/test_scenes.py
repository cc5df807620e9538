"""Scenes and simulation: validation, only-what-is-called-for, closed forms and balance laws."""

from __future__ import annotations

import dataclasses

import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from scipy.special import ellipk

from urdf2links.scenes import python_plan as python_plan_module
from urdf2links.dynamics.oracles import recursive
from urdf2links.scenes.python_plan import PythonPlan
from urdf2links.scenes.scene_kernels import CompiledScene
from urdf2links.locations import report_scene_files, shipped_robots_dir
from urdf2links.errors import SceneError
from urdf2links.scenes.plan import compile_plan
from urdf2links.scenes.scene_read import load_scene
from urdf2links.integration.simulate import simulate

ROBOTS = Path(__file__).resolve().parent.parent / "robots"


def write_scene(tmp_path, text, name="scene.toml"):
    p = tmp_path / name
    p.write_text(textwrap.dedent(text))
    return p


# ---- validation ---------------------------------------------------------------------------------

@pytest.mark.parametrize("body, message", [
    ("[robot]\nshipped = 'double_pendulum'\n[gravty]\n", "unknown key (did you mean 'gravity'?)"),
    ("[robot]\nshipped = 'double_pendulm'\n", "did you mean 'double_pendulum'"),
    ("[robot]\nshipped = 'double_pendulum'\n[run]\nmethod = 'RK5'\n", "'RK5' is not one of"),
    ("[robot]\nshipped = 'double_pendulum'\n[run]\nmethod = 'RK4'\n", "give dt"),
    ("[robot]\nshipped = 'double_pendulum'\n[gravity]\nmagnitude = '9.81'\n", "gravity.magnitude: must be a finite number"),
    ("[robot]\nshipped = 'double_pendulum'\n[base]\nheave = 1.0\n", "base.heave: unknown key"),
    ("[robot]\nshipped = 'double_pendulum'\n[base]\nz = { sine = [[1, 1]] }\n", "did you mean 'sines'"),
    ("[robot]\nurdf = 'nowhere.urdf'\n", "does not exist"),
    ("[gravity]\nmagnitude = 1\n", "[robot]: missing"),
    ("[robot]\nshipped = 'double_pendulum'\n[[spring]]\ncoordinate = 'elbow'\nstiffness = -3\n", "must not be negative"),
])
def test_scene_errors_name_file_key_and_choices(tmp_path, body, message):
    p = write_scene(tmp_path, body)
    with pytest.raises(SceneError) as info:
        load_scene(p).model()
    assert message in str(info.value)
    assert str(p) in str(info.value)


@pytest.mark.parametrize("body, message", [
    ("[[torque]]\ncoordinate = 'elbw'\nvalue = 1.0\n", "did you mean 'elbow'"),
    ("[[force]]\nlink = 'lowr'\nvalue = [0, 0, 1]\n", "did you mean 'lower'"),
    ("[initial]\nq = { shoulderr = 1.0 }\n", "coordinates are ['shoulder', 'elbow']"),
])
def test_scene_names_are_checked_against_the_robot(tmp_path, body, message):
    p = write_scene(tmp_path, "[robot]\nshipped = 'double_pendulum'\n" + body)
    with pytest.raises(SceneError, match=message.replace("[", r"\[").replace("(", r"\(")):
        load_scene(p).model()


# ---- only what the scene calls for --------------------------------------------------------------

def _forbid(monkeypatch, name, target, attr):
    calls = []

    def boom(*a, **k):
        calls.append(name)
        raise AssertionError(f"{name} computed although the scene does not call for it")
    monkeypatch.setattr(target, attr, boom)
    return calls


def test_unnamed_effects_cost_nothing(tmp_path, monkeypatch):
    """A scene without gravity, base motion and loads never calls the code for them."""
    p = write_scene(tmp_path, """
        [robot]
        shipped = "double_pendulum"
        [initial]
        qd = { shoulder = 1.0 }
        [run]
        t_end = 0.5
        """)
    _forbid(monkeypatch, "G", recursive.RecursivePlan, "gravity")
    _forbid(monkeypatch, "Q", recursive.RecursivePlan, "generalized_forces")
    _forbid(monkeypatch, "base", python_plan_module, "base_transforms")
    scene = load_scene(p)
    plan = compile_plan(scene, scene.model())
    assert plan.terms == ("A", "e")
    # the compiled twin has the same terms switched off: no base factors, no gravity, no wrench
    from urdf2links.scenes.scene_arrays import scene_view
    sc = scene_view(plan.rhs.SI, plan.rhs.SF)
    assert (sc.has_base, sc.has_g, sc.load_link.size, sc.torque_idx.size, sc.spring_idx.size) == (0, 0, 0, 0, 0)
    PythonPlan(plan).rhs(0.1, np.r_[0.3, 0.2, 0.1, -0.1, 0.0])     # the Python twin runs under the forbids
    traj = simulate(scene, progress=False)
    assert traj.stats["terms"] == ("A", "e")
    assert traj.energy_error < 1e-8  # it really ran: a free double pendulum keeps its energy


def test_named_effects_are_computed(tmp_path, monkeypatch):
    p = write_scene(tmp_path, """
        [robot]
        shipped = "double_pendulum"
        [gravity]
        magnitude = 9.81
        [base]
        z = { sines = [[0.1, 0.5]] }
        [[force]]
        link = "lower"
        point = [0, 0, -1.1]
        frame = "world"
        value = [0, 1.0, 0]
        [[torque]]
        coordinate = "shoulder"
        value = 0.5
        [[spring]]
        coordinate = "elbow"
        stiffness = 3.0
        damping = 0.2
        """)
    scene = load_scene(p)
    plan = compile_plan(scene, scene.model())
    assert plan.terms == ("A", "e", "base", "G", "Q", "tau", "spring", "damper")
    text = plan.describe()
    assert "not computed (the scene does not call for them): actuator, computed_torque" in text   # (issue 26's effects)
    counts = {"G": 0, "Q": 0}
    for name, attr in (("G", "gravity"), ("Q", "generalized_forces")):
        original = getattr(recursive.RecursivePlan, attr)

        def counting(self, *a, _orig=original, _name=name, **k):
            counts[_name] += 1
            return _orig(self, *a, **k)
        monkeypatch.setattr(recursive.RecursivePlan, attr, counting)
    y = np.r_[0.3, 0.2, 0.1, -0.1, 0.0]
    out = PythonPlan(plan).rhs(0.1, y)
    assert counts["G"] == 1 and counts["Q"] >= 1
    from urdf2links.scenes.scene_arrays import scene_view
    sc = scene_view(plan.rhs.SI, plan.rhs.SF)
    assert (sc.has_base, sc.has_g, sc.load_link.size, sc.torque_idx.size, sc.spring_idx.size,
            sc.damper_idx.size) == (1, 1, 1, 1, 1, 1)
    # the compiled twin computes the same terms: equal to rounding (1e-12 relative)
    assert np.abs(plan.rhs(0.1, y) - out).max() < 1e-12 * np.abs(out).max()


# ---- closed forms and balance laws --------------------------------------------------------------

def test_pendulum_period_against_elliptic_integral(tmp_path):
    """Large-amplitude period T = 4 sqrt(I_O / (m g c)) K(sin^2(theta0 / 2))."""
    theta0 = 2.5
    p = write_scene(tmp_path, f"""
        [robot]
        shipped = "pendulum"
        [gravity]
        magnitude = 9.81
        [initial]
        q = {{ hinge = {theta0} }}
        [run]
        t_end = 8.0
        rtol = 1e-12
        atol = 1e-13
        samples = 4001
        """)
    traj = simulate(load_scene(p), progress=False)
    m, c, I = 1.3, 0.7, 0.05
    T = 4 * np.sqrt((I + m * c * c) / (m * 9.81 * c)) * ellipk(np.sin(theta0 / 2) ** 2)
    # times where the velocity changes sign from + to - are turning points at +theta0, one period apart
    f = lambda t: traj.sol(t)[1]
    qd = traj.qd[:, 0]
    crossings = []
    for i in np.nonzero((qd[:-1] > 0) & (qd[1:] <= 0))[0]:
        from scipy.optimize import brentq
        crossings.append(brentq(f, traj.t[i], traj.t[i + 1], xtol=1e-14))
    assert len(crossings) >= 2
    # dense output at rtol 1e-12: the period is found to ~1e-9 s
    assert np.diff(crossings)[0] == pytest.approx(T, rel=1e-8)


@pytest.mark.parametrize("method, options, bound", [
    ("DOP853", {"rtol": 1e-10}, 1e-7),
    ("Radau", {"rtol": 1e-8}, 1e-5),
    ("RK4", {"dt": 1e-3}, 1e-7),
    ("midpoint", {"dt": 2e-3}, 1e-4),
])
def test_power_balance_with_torques_springs_dampers_and_base(tmp_path, method, options, bound):
    """h(t) - h(0) = W(t): energy put in by torques, forces and the moving base, taken by dampers."""
    p = write_scene(tmp_path, """
        [robot]
        shipped = "double_pendulum"
        [gravity]
        magnitude = 9.81
        [base]
        z = { sines = [[0.2, 0.4]] }
        phi_y = { sines = [[0.1, 0.3, 0.5]] }
        [[force]]
        link = "lower"
        point = [0, 0, -1.1]
        frame = "link"
        value = [0, { sines = [[1.0, 0.7]] }, 0]
        [[torque]]
        coordinate = "shoulder"
        value = { sines = [[0.8, 0.5]] }
        [[spring]]
        coordinate = "elbow"
        stiffness = 4.0
        rest = 0.3
        damping = 0.3
        [initial]
        q = { shoulder = 0.5, elbow = -0.3 }
        [run]
        t_end = 3.0
        samples = 301
        """)
    traj = simulate(load_scene(p), method=method, progress=False, **options)
    assert np.abs(traj.energy["work"]).max() > 0.1  # energy really flows in and out
    assert traj.energy_error < bound


def test_free_body_keeps_its_momentum():
    """Zero gravity: linear momentum and angular momentum about the origin are constant."""
    scene = load_scene(ROBOTS / "free_body_tumble.toml")
    traj = simulate(scene, progress=False)
    m, I_b = 3.0, np.diag([0.2, 0.35, 0.5])
    R = traj.poses["body"][:, :3, :3]
    x = traj.poses["body"][:, :3, 3]
    v = traj.qd[:, :3]
    from test_core import _body_rate_jacobian
    w_b = np.array([_body_rate_jacobian(q[3:]) @ qd[3:] for q, qd in zip(traj.q, traj.qd)])
    L = np.einsum("kab,bc,kc->ka", R, I_b, w_b) + m * np.cross(x, v)
    p = m * v
    # it really spins (about its major axis) and wobbles, staying clear of phi_y = +-pi/2
    assert traj.q[-1, 5] - traj.q[0, 5] > 2 * np.pi
    assert np.ptp(w_b[:, 0]) > 0.1 and np.abs(traj.q[:, 4]).max() < 1.2
    # DOP853 at rtol 1e-11 over ~600 steps: momenta hold to ~1e-10 relative
    assert np.abs(p - p[0]).max() <= 1e-9 * np.abs(p[0]).max()
    assert np.abs(L - L[0]).max() <= 1e-9 * np.abs(L[0]).max()
    assert traj.energy_error < 1e-8


def test_trajectory_files_and_cli(tmp_path):
    out = subprocess.run([sys.executable, "-m", "urdf2links.cli", "simulate", str(ROBOTS / "double_pendulum_chaos.toml"),
                          "--t-end", "1.0", "--out", str(tmp_path), "--plot", "--quiet"], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert "energy balance error" in out.stdout
    data = np.load(tmp_path / "double_pendulum_chaos.npz")
    assert data["q"].shape[1] == 2 and data["t"][-1] == pytest.approx(1.0)
    header = (tmp_path / "double_pendulum_chaos.csv").read_text().splitlines()[0]
    assert header.startswith("t,shoulder,elbow,d_shoulder,d_elbow,energy_kinetic")
    assert (tmp_path / "double_pendulum_chaos.png").stat().st_size > 10_000
    inspect = subprocess.run([sys.executable, "-m", "urdf2links.cli", "inspect", str(ROBOTS / "double_pendulum_chaos.toml")],
                             capture_output=True, text=True)
    assert "terms computed: A, e, G" in inspect.stdout


@pytest.mark.parametrize("scene_file", [p.relative_to(ROBOTS).as_posix() for p in report_scene_files(ROBOTS)])
def test_shipped_scenes_run_and_balance_energy(scene_file):
    """Every scene ``urdf2links report`` runs (robots/*.toml, robots/loops/*.toml) runs its first second with the
    power balance holding; a hard case that stops by design (its [expect]) stops with the error it names."""
    scene = load_scene(ROBOTS / scene_file)
    if scene.expected_stop is not None:
        with pytest.raises(Exception) as info:
            simulate(scene, t_end=min(1.0, scene.run.t_end), samples=101, progress=False)
        assert scene.expected_stop.matches(info.value), info.value
        return
    traj = simulate(scene, t_end=min(1.0, scene.run.t_end), samples=101, progress=False)
    assert traj.stats["success"]
    # the scenes run DOP853 at rtol <= 1e-9: the balance holds far below that
    assert traj.energy_error < 1e-8


def test_progress_bar_draws_only_when_enabled():
    import io

    from urdf2links.integration.simulate import Progress
    stream = io.StringIO()
    bar = Progress(2.0, label="run", enabled=True, stream=stream)
    bar(1.0)
    bar.close()
    assert "100.0%" in stream.getvalue() and "run [" in stream.getvalue()
    quiet = io.StringIO()
    off = Progress(2.0, stream=quiet)  # a StringIO is not a terminal: silent
    off(1.0)
    off.close()
    assert quiet.getvalue() == ""


@pytest.mark.parametrize("path", report_scene_files(shipped_robots_dir()), ids=lambda p: p.stem)
def test_compiled_rhs_equals_python_rhs(path):
    """plan.rhs (numba) against plan.python_rhs (numpy) at random states and times of every
    shipped scene: the same sums in another order, so equal to ~cond(A) eps (bound 1e-11 relative
    to the largest component; observed <= 5e-14)."""
    scene = load_scene(path)
    model = scene.model()
    # PythonPlan has no contact: a [[contact]] scene is checked without it here, its contact's Q against the
    # literal trace form in tests/test_contact.py
    plan = compile_plan(dataclasses.replace(scene, contacts=()), model)
    q, qd = scene.initial_state(model)
    rng = np.random.default_rng(11)
    # the python plan is the free tree's right-hand side: a constrained scene's compiled one solves the KKT system
    # (E72) too, checked against its own oracle in tests/test_constraints_compiled.py; here its free part
    free_rhs = plan.rhs if plan.constraints is None else CompiledScene(plan, constraints=False)
    for t in (0.0, 0.37, 1.3):
        y = np.r_[q + 0.1 * rng.normal(size=model.n), qd + rng.normal(size=model.n), 0.0]
        ref = PythonPlan(plan).rhs(t, y)
        assert np.abs(free_rhs(t, y) - ref).max() < 1e-11 * np.abs(ref).max()

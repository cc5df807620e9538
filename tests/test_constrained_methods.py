"""A constrained scene's ``method`` and ``dt`` honoured, or refused by name (issues 42, 45;
urdf2links/integration/constrained_steps.py): in the compiled loops, RK4 with its dt, projected after every step,
converges to the DOP853 run as dt shrinks; RK45 runs its own steps; Radau5 and auto (its stretches) run and say
so; a method that takes no projection (scipy's Radau, BDF, the implicit midpoint) is a SceneError naming the
method, the scene and what is accepted."""

from __future__ import annotations

import re

import numpy as np
import pytest
from cli_runner import run_cli

from urdf2links.errors import SceneError
from urdf2links.integration import simulate
from urdf2links.integration.constrained_steps import CONSTRAINED_METHODS, step_times
from urdf2links.locations import shipped_robots_dir
from urdf2links.scenes import as_plan

LOOPS = shipped_robots_dir() / "loops"
T_END = 0.5


@pytest.fixture(scope="module")
def crank():
    """The four-bar's plan and its DOP853 run at the scene's rtol 1e-12 (the reference: its own error is
    ~1e-10 here, far below RK4's at the step sizes below)."""
    plan = as_plan(LOOPS / "four_bar_crank.toml")
    return plan, simulate(plan, t_end=T_END, samples=11, progress=False)


def test_rk4_with_dt_converges_to_dop853(crank):
    """RK4 at dt = 0.01, 0.005, 0.0025 s: each run takes exactly T_END / dt steps of RK4 (not DOP853's), stays
    on the loop, and its largest |q - q_DOP853| falls at least 8x per halving of dt (a fourth-order method falls
    16x; measured 21.6x and 19.6x, 1.9e-5 then 9.8e-7 rad). A run that ignored method and dt (DOP853 at the
    scene's rtol, as before issue 42) would give the same ~1e-10 at every dt and fail the ratio."""
    plan, ref = crank
    assert ref.stats["method"] == "auto"
    errors = []
    for dt in (0.01, 0.005, 0.0025):
        tr = simulate(plan, t_end=T_END, samples=11, progress=False, method="RK4", dt=dt)
        assert tr.stats["method"] == "RK4" and tr.stats["dt"] == dt
        assert tr.stats["nsteps"] == round(T_END / dt)
        # the projection after each step keeps the loop closed to rounding whatever the step's error
        assert tr.stats["constraints"]["max_residual"] < 1e-12
        errors.append(float(np.abs(tr.q - ref.q).max()))
    ratios = [a / b for a, b in zip(errors, errors[1:])]
    assert min(ratios) > 8.0, (errors, ratios)
    assert 1e-9 < errors[-1] < 1e-5, errors      # far above the reference's own error, and converged


def test_rk45_runs_its_own_steps(crank):
    """RK45 at rtol 1e-10 (scipy's pair, projected like DOP853): more steps than DOP853 at 1e-12 on this run
    (measured 240 against 103) and within 1e-8 rad of it (measured 1.2e-10)."""
    plan, ref = crank
    tr = simulate(plan, t_end=T_END, samples=11, progress=False, method="RK45", rtol=1e-10)
    assert tr.stats["method"] == "RK45" and tr.stats["nsteps"] > ref.stats["nsteps"]
    assert np.abs(tr.q - ref.q).max() < 1e-8


def test_auto_runs_its_stretches_compiled_and_says_so(crank):
    """Issue 45: the scene's method is auto: the compiled loops run its stretches (DOP853 on this non-stiff
    run), and the statistics say it (the interpreted path ran DOP853 with no stiffness test)."""
    plan, ref = crank
    assert plan.scene.run.method == "auto" and ref.stats["scene_method"] == "auto"
    assert ref.stats["stretches"] and ref.stats["stretches"][0]["method"] == "DOP853"
    assert "compiled" in ref.stats["constraints"]["method"]


def test_radau5_runs_projected(crank):
    """Issue 45: Radau5 (refused before: its Newton matrices did not follow the projected state) runs in the
    compiled loop with the projection after every step: on the loop to rounding (1e-12) and within 1e-7 rad
    of DOP853 at 1e-12 (Radau5 at rtol 1e-10, order 5)."""
    plan, ref = crank
    tr = simulate(plan, t_end=T_END, samples=11, progress=False, method="Radau5", rtol=1e-10, atol=1e-10)
    assert tr.stats["method"] == "Radau5" and tr.stats["njev"] > 0
    assert tr.stats["constraints"]["max_residual"] < 1e-12
    assert np.abs(tr.q - ref.q).max() < 1e-7


@pytest.mark.parametrize("method", ["Radau", "BDF", "midpoint"])
def test_a_method_the_constrained_path_cannot_carry_is_refused(crank, method):
    """Methods that take no projection after each step (scipy's Radau, BDF; the implicit midpoint) are refused
    before any step, naming the method, the scene and the accepted methods (a planted run of each: none may
    run silently without its projection)."""
    plan, _ = crank
    with pytest.raises(SceneError) as info:
        simulate(plan, t_end=0.1, progress=False, method=method, dt=0.01)
    text = str(info.value)
    assert f"method {method!r}" in text and "four_bar_crank.toml" in text
    assert all(m in text for m in CONSTRAINED_METHODS)


def test_simulate_command_honours_method_and_dt(tmp_path):
    """``urdf2links simulate four_bar_crank --method RK4 --dt 0.01`` runs RK4 (issue 42: it ran DOP853 silently);
    ``--method BDF`` exits 2 with the refusal."""
    out = run_cli("simulate", "four_bar_crank", "--method", "RK4", "--dt", "0.01", "--t-end", "0.2", "--out",
                  tmp_path, cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    m = re.search(r", (\w+) \(rtol [^,]+, dt ([0-9.e+-]+)\): (\d+) steps", out.stdout)
    assert m and m.group(1) == "RK4" and float(m.group(2)) == 0.01 and int(m.group(3)) == 20, out.stdout
    bad = run_cli("simulate", "four_bar_crank", "--method", "BDF", "--t-end", "0.2", "--out", tmp_path, cwd=tmp_path)
    assert bad.returncode == 2 and "method 'BDF' does not run a scene with constraints" in bad.stderr


def test_step_times_end_at_t_end():
    """The open path's RK4 grid: a last step shorter than dt ends at t_end; a remainder below 1e-9 dt is absorbed."""
    g = step_times(0.25, 0.1)
    assert g.size == 4 and g[-1] == 0.25 and abs(g[2] - 0.2) < 1e-15
    assert step_times(0.3, 0.1).size == 4

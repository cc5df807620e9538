"""Issue 45: constrained scenes in the compiled loops against the literal oracle (the interpreted KKT solve and
projection, urdf2links/integration/constrained_oracle.py), on every method.

The compiled right-hand side (free forces, fixed tendons (E76), constraint terms from the evaluation's own
kinematics pass, KKT block elimination with the pivoted Schur factorisation, E72 and E77) equals the oracle's
(numpy: the free right-hand side, ``ConstraintSet.terms``, Cholesky of A and S) to rounding at states on the
loop; whole runs agree to the integration's tolerance; the residual stays at rounding level with every method.
"""

from __future__ import annotations

import numpy as np
import pytest

from urdf2links.integration import simulate
from urdf2links.integration.constrained import project_state
from urdf2links.integration.constrained_oracle import ConstrainedRHS, simulate_interpreted
from urdf2links.locations import shipped_robots_dir
from urdf2links.scenes import as_plan

LOOPS = shipped_robots_dir() / "loops"
SCENES = ("four_bar_crank", "closed_leg_swing", "gripper2f_close", "mimic_gripper_swing")


@pytest.fixture(scope="module", params=SCENES)
def plan(request):
    return as_plan(LOOPS / f"{request.param}.toml")


def test_right_hand_side_equals_the_oracle(plan):
    """At five states on the loop (the scene's start with seeded random q' (normal) and small random q offsets,
    projected): ``y'`` and ``lambda`` of the compiled right-hand side equal the oracle's to 1e-11 relative to the
    largest |q''| (rounding: both solve the same system, with different factorisations: tree-sparse L^T D L and
    a pivoted Schur Cholesky against dense Choleskys). Planted: the compiled right-hand side without its
    constraints (CompiledScene(plan, constraints=False)) differs by O(1) on every scene."""
    from urdf2links.scenes.scene_kernels import CompiledScene

    rng = np.random.default_rng(0)
    n = plan.model.n
    q0, _ = plan.scene.initial_state(plan.model)
    oracle = ConstrainedRHS(plan, q0=q0)
    free = CompiledScene(plan, constraints=False)
    for _ in range(5):
        y = np.r_[q0 + 0.05 * rng.normal(size=n), rng.normal(size=n), 0.0]
        y, _ = project_state(plan.rhs, 0.0, y)
        a, lam, _ = oracle.solve(0.0, y)
        b = plan.rhs(0.0, y)
        scale = max(1.0, np.abs(a[n:2 * n]).max())
        assert np.abs(a - b).max() < 1e-11 * scale
        c = plan.constraints
        if len(c.cset):
            assert np.abs(free(0.0, y) - a).max() > 1e-3 * scale       # the planted case differs


def test_runs_equal_the_oracle(plan):
    """0.3 s of the scene at its tolerances (rtol 1e-12 or the scene's) compiled and by the oracle: the same
    trajectory to 1e-8 (both DOP853 at the same tolerance; their steps differ by the projection's metric and the
    oracle's auto = DOP853), the residual at rounding level (below 1e-12) on both, lambda to 1e-6 relative."""
    run = plan.scene.run
    tr = simulate(plan, t_end=0.3, samples=16, method="DOP853", progress=False)
    q, qd = plan.scene.initial_state(plan.model)
    import dataclasses

    ref = simulate_interpreted(plan, dataclasses.replace(run, t_end=0.3, samples=16, method="DOP853"), q, qd,
                               progress=False)
    assert np.abs(tr.q - ref.q).max() < 1e-8
    c, r = tr.stats["constraints"], ref.stats["constraints"]
    assert c["max_residual"] < 1e-12 and r["max_residual"] < 1e-12
    assert c["solved_rows"] == r["solved_rows"] and c["rows"] == r["rows"]
    if c["lambda"].size:
        assert np.abs(c["lambda"] - r["lambda"]).max() < 1e-6 * max(1.0, np.abs(r["lambda"]).max())
    assert tr.energy_error < 1e-8


@pytest.mark.parametrize("method", ["RK4", "RK45", "DOP853", "Radau5", "auto"])
def test_every_method_keeps_the_loop_closed(method):
    """closed_leg_swing (a connect, a joint equality and a tendon spring) with each method: the run finishes,
    its residual stays at rounding level (1e-12: the projection stops at 1e-13 after every step) and it agrees
    with DOP853 at 1e-12 to the method's accuracy (RK4 dt 1e-3: 1e-6; the others at rtol 1e-10: 1e-7)."""
    plan = as_plan(LOOPS / "closed_leg_swing.toml")
    ref = simulate(plan, t_end=0.3, samples=7, method="DOP853", progress=False)
    kw = {"dt": 1e-3} if method == "RK4" else {"rtol": 1e-10, "atol": 1e-10}
    tr = simulate(plan, t_end=0.3, samples=7, method=method, progress=False, **kw)
    assert tr.stats["constraints"]["max_residual"] < 1e-12
    assert np.abs(tr.q - ref.q).max() < (1e-6 if method == "RK4" else 1e-7)

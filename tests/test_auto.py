"""method = "auto" (urdf2links.integration.loops.auto): DOP853 while a run is not stiff, Radau5 while it
is, switching both ways; the record of its stretches; the default of scenes; on every shipped scene at
least as accurate as today's default (DOP853); the explicit loop's rejection of non-finite trial steps."""

from __future__ import annotations

import numpy as np
import pytest

from corpus import needs_corpus, path as corpus_path
from urdf2links.integration.integrators import integrate
from urdf2links.integration.simulate import describe_stretches, simulate
from urdf2links.locations import shipped_robots_dir
from urdf2links.scenes.plan import as_plan
from urdf2links.scenes.default_scenes import default_scene
from urdf2links.scenes.scene import RunSettings
from urdf2links.scenes.scene_read import load_scene


def _lam(t):
    """1e5 /s until t = 1, then falling smoothly to ~1 /s by t = 1.6."""
    return 1e5 if t < 1.0 else max(1.0, 1e5 * np.exp(-20.0 * (t - 1.0)))


def _forced(t, y):
    """y' = -lambda(t) (y - cos t) - sin t: y = cos t + (y0 - 1) exp(-int lambda) from y0."""
    return np.array([-_lam(t) * (y[0] - np.cos(t)) - np.sin(t)])


def test_auto_switches_to_radau5_when_stiff_and_back_when_not():
    """A scalar problem stiff until t = 1 (lambda = 1e5) and not after (lambda -> 1 by t = 1.6): auto
    runs DOP853, hands over to Radau5 after the stiffness test's 15 verdicts (in the first 2e-3 s), and
    back to DOP853 once the cost comparison says DOP853 is cheaper again; the solution stays within
    1e-7 of cos t after the transient at the steps (rtol 1e-8: measured 1.5e-8),
    and the whole run costs a fraction of DOP853's alone (which pays ~1e5 / 6 steps per second while
    stiff: > 10x more evaluations)."""
    res = integrate(_forced, (0.0, 3.0), [2.0], method="auto", rtol=1e-8, atol=1e-10, dense=True)
    assert res.success
    methods = [s["method"] for s in res.stretches]
    assert methods == ["DOP853", "Radau5", "DOP853"], methods
    first, stiff, back = res.stretches
    assert first["ended"] == "stiff" and first["t1"] < 2e-3 and first["end_figures"]["lambda"] > 1e4
    assert stiff["ended"] == "non-stiff" and 1.0 < stiff["t1"] < 2.0
    assert stiff["end_figures"]["dop853_evals_per_s"] < 0.5 * stiff["end_figures"]["radau5_evals_per_s"]
    assert back["ended"] == "t_end" and back["t1"] == 3.0
    assert sum(s["steps"] for s in res.stretches) == res.nsteps
    assert sum(s["nfev"] for s in res.stretches) == res.nfev - 1      # the initial F is integrate()'s
    late = res.t > 0.01
    assert np.abs(res.y[late, 0] - np.cos(res.t[late])).max() < 1e-7
    # between the steps Radau5's collocation polynomial is of order 3 (module doc of loops.radau): on
    # this very stiff stretch its steps reach 0.4 s and the interpolant is off by up to 5e-5 inside them
    mid = np.linspace(0.01, 3.0, 300)
    assert np.abs(res.sol(mid)[:, 0] - np.cos(mid)).max() < 1e-4
    dop = integrate(_forced, (0.0, 3.0), [2.0], method="DOP853", rtol=1e-8, atol=1e-10)
    assert dop.nfev > 10 * res.nfev, (dop.nfev, res.nfev)


def test_auto_records_its_stretches_in_simulate():
    """simulate() keeps auto's stretches in stats (method, interval, steps, evaluations, why), names
    the methods used in turn, and describe_stretches says it in one line per stretch (the stiff spring
    arm: DOP853 for a few milliseconds, then Radau5 to the end)."""
    scene = load_scene(shipped_robots_dir() / "hard/stiff_spring_arm.toml")
    traj = simulate(scene, method="auto", progress=False)
    st = traj.stats
    assert st["method"] == "auto" and st["methods_used"] == "DOP853 then Radau5"
    assert [s["method"] for s in st["stretches"]] == ["DOP853", "Radau5"]
    assert st["stretches"][0]["t1"] == st["stretches"][1]["t0"] < 0.01
    assert st["njev"] == st["stretches"][1]["njev"] > 0
    lines = describe_stretches(st["stretches"])
    assert len(lines) == 2 and lines[1].startswith("Radau5 t = ") and "stiff at t=" in lines[1]
    assert "h|lambda|" in lines[1] and "auto begins explicit" in lines[0]


def test_auto_is_the_default_of_scenes_and_default_scenes():
    assert RunSettings().method == "auto"
    assert default_scene(shipped_robots_dir() / "ur5_like.urdf").run.method == "auto"


def _shipped_dop853_scenes():
    out = []
    for path in sorted(shipped_robots_dir().glob("*.toml")) + sorted((shipped_robots_dir() / "hard").glob("*.toml")):
        scene = load_scene(path)
        if scene.run.method in ("DOP853", "auto"):
            out.append(path.relative_to(shipped_robots_dir()).with_suffix("").as_posix())
    return out


#: scenes where auto hands over to Radau5 at their own rtol (measured): every other shipped scene runs
#: DOP853's steps to the bit under auto
SWITCHING = {"spring_arm_torques", "ur5_servo", "ur5_stiff_servo", "quad12_drop", "quad12_stand", "biped10_stand"}


@pytest.mark.parametrize("name", _shipped_dop853_scenes())
def test_auto_is_at_least_as_accurate_as_dop853_on_every_shipped_scene(name):
    """Every shipped scene that runs DOP853 or auto (DOP853 was the default before auto), over its whole
    run at its own rtol, against DOP853 at rtol 1e-13. Where the stiffness test never calls the run stiff,
    auto takes DOP853's steps to the bit: exactly as accurate. Where auto switches (:data:`SWITCHING`),
    its largest error must be at most twice ``max(DOP853's error, rtol)``:

    - on a stiff scene (ur5_stiff_servo, rtol 1e-8) DOP853's step is held by stability and its error falls
      far below what was asked (1.7e-10, for 21x auto's evaluations); auto delivers the rtol asked (7e-9),
      which is the accuracy DOP853 promises at that rtol;
    - on ur5_servo (rtol 1e-10) both errors are set by the clamp of the last wrist's ctrl, a kink in time
      that every step across it loses order on, and the undamped wrist keeps what it lost: DOP853's own
      error moves between 9e-8 and 4.8e-7 when its rtol moves by 30 % either way (measured); auto's 2.0e-7
      against DOP853's 1.4e-7 is inside that spread, hence the factor 2;
    - spring_arm_torques slows under its dampers and auto hands over at t = 4.29 s; its error (9.7e-11) is
      DOP853's, reached before the switch.
    - the ground-contact scenes (issue 37) are stiff while a foot touches: auto's errors 1.3e-11 (quad12_drop),
      6.3e-12 (quad12_stand), 3.1e-11 (biped10_stand), below rtol 1e-10, at 0.93x, 0.24x and 0.09x DOP853's
      evaluations (DOP853's own errors 3.4e-11, 4e-14, 8e-15: its step held far below what rtol asks).

    The test fails if auto's Radau5 stretches are less accurate than their mapped tolerance promises (a
    wrong rtol map, a converged-too-early Newton iteration: 0.12 rad on a 1.1 s step, once), or if a
    scene starts switching that did not (then it joins SWITCHING with its measured figures)."""
    plan = as_plan(load_scene(shipped_robots_dir() / f"{name}.toml"))
    auto = simulate(plan, method="auto", progress=False)
    dop = simulate(plan, method="DOP853", progress=False)
    if np.array_equal(auto.q, dop.q) and np.array_equal(auto.qd, dop.qd):
        assert auto.stats["methods_used"] == "DOP853" and auto.stats["nfev"] == dop.stats["nfev"]
        assert name not in SWITCHING, f"{name} no longer switches: take it out of SWITCHING"
        return
    assert name in SWITCHING, (name, auto.stats["methods_used"])
    ref = simulate(plan, method="DOP853", rtol=1e-13, atol=1e-14, progress=False)
    err_auto, err_dop = np.abs(auto.q - ref.q).max(), np.abs(dop.q - ref.q).max()
    assert err_auto <= 2 * max(err_dop, plan.scene.run.rtol), (err_auto, err_dop)
    assert auto.stats["nfev"] <= dop.stats["nfev"] * 1.2, (auto.stats["nfev"], dop.stats["nfev"])


@needs_corpus
def test_dop853_rejects_a_non_finite_trial_step_like_scipy():
    """The Allegro hand's default scene is stiff (finger dampers on grams: |lambda| ~ 2e6 /s): at rtol
    1e-13 scipy's first step estimate (~1e-3 s) is ~1000x DOP853's stable step and the trial stages
    overflow to inf. scipy's DOP853 rejects such a step (its error norm is NaN) and shrinks it; so does
    the compiled loop now (it used to end the run with 'non-finite state'). What matters is asserted:
    steps were rejected and the run recovered to the end, at scipy's final state to 1e-11 (measured
    2.4e-15). The counts of steps are not compared: at rtol 1e-13 a step size decision may fall either
    way of its threshold on a rounding, and one different decision moves the counts (seen: 155 rejected
    steps against scipy's 148 on one machine, 157 on another)."""
    scene = default_scene(corpus_path("allegro_hand_description/urdf/allegro_left_hand.urdf"), q0="random", seed=0)
    plan = as_plan(scene)
    q, qd = scene.initial_state(plan.model)
    y0 = np.r_[q, qd, 0.0]
    with np.errstate(all="ignore"):
        ours = integrate(plan.rhs, (0.0, 2e-3), y0, method="DOP853", rtol=1e-13, atol=1e-15)
        scipys = integrate(lambda t, y: plan.rhs(t, y), (0.0, 2e-3), y0, method="DOP853", rtol=1e-13, atol=1e-15)
    assert ours.success and scipys.success, (ours.message, scipys.message)
    assert ours.nrejected > 0 and scipys.nrejected > 0       # the overflowing trial steps were rejected ...
    assert ours.t[-1] == scipys.t[-1] == 2e-3                 # ... and both runs recovered to the end
    assert np.all(np.isfinite(ours.y))
    np.testing.assert_allclose(ours.y[-1], scipys.y[-1], rtol=0, atol=1e-11)

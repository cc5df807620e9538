"""Both engines on stiff models: the comparison harness falls back to a MuJoCo setting that stays
stable and shows its convergence (urdf2links.compare.mujoco_side.stable_run); the Allegro hands, whose
default scene MuJoCo's RK4 at 1e-4 s blows up within milliseconds, compare within the divergence
threshold; the study's MuJoCo rows count a reset as a failure."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from corpus import needs_corpus, path as corpus_path
from urdf2links.compare.agreement.trajectory import DIVERGENCE_THRESHOLD, compare_scene
from urdf2links.compare.mujoco_side.mjcf import mjcf_from_scene
from urdf2links.compare.mujoco_side.stable_run import CONVERGED, stable_run
from urdf2links.compare.tradeoff.study import _mujoco_failure
from urdf2links.locations import shipped_robots_dir
from urdf2links.scenes.plan import as_plan
from urdf2links.scenes.default_scenes import default_scene
from urdf2links.scenes.scene_read import load_scene


@needs_corpus
@pytest.mark.parametrize("hand", ["left", "right"])
def test_allegro_hands_compare_without_a_mujoco_blow_up(hand):
    """The corpus's setting (default scene, q0 random seed 0, 0.5 s, MuJoCo RK4 at 1e-4 s): RK4 blows up
    (BADQACC: dampers of 3-10 N m s/rad on finger links of grams, |lambda| ~ 2e6 /s, far beyond RK4's
    2.8 / dt); the harness falls back to implicitfast at the same step, whose run at half the step
    differs by < 1e-4 rad (measured 7.7e-10), and the engines then agree far inside the divergence
    threshold 1e-3 rad (measured 1.5e-9). The project's auto ran DOP853 then Radau5; the summary
    says all of it."""
    scene = default_scene(corpus_path(f"allegro_hand_description/urdf/allegro_{hand}_hand.urdf"), t_end=0.5,
                          q0="random", seed=0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        c = compare_scene(scene, mujoco_integrator="RK4", mujoco_dt=1e-4, progress=False, states=2)
    s = c.summary()
    fb = s["mujoco"]["fallback"]
    assert fb["asked"]["integrator"] == "RK4" and fb["asked"]["blow_ups"]
    assert fb["chosen"] == {"integrator": "implicitfast", "timestep": 1e-4} and fb["converged"]
    assert fb["convergence"]["max_abs_difference"] < CONVERGED
    assert s["mujoco"]["integrator"] == "implicitfast" and not s["mujoco"]["blow_ups"]
    assert s["trajectory"]["divergence_time"] is None
    assert s["trajectory"]["max_abs_error"] < 1e-3 * DIVERGENCE_THRESHOLD
    assert s["project"]["methods_used"] == "DOP853 then Radau5"
    assert any("blew up" in n and "converged" in n for n in s["notes"])
    assert any("auto method ran DOP853 then Radau5" in n for n in s["notes"])


def test_stable_run_prefers_a_converged_setting_over_a_merely_stable_one():
    """The stiff spring arm (hard case 3: a 1e6 N m/rad servo, a 320 Hz mode) with MuJoCo's RK4 at 1 ms
    blows up. implicitfast stays stable at 1 ms but its run at 0.5 ms differs by 0.19 rad (stable, not
    converged), at 0.1 ms still by 0.014, at 10 us by 1.02e-4 (first order); RK4 at 10 us (4th order,
    h |lambda| = 0.42) differs from its half step by 4.4e-5 < 1e-4: that one is chosen, and the record
    lists every candidate tried."""
    scene = load_scene(shipped_robots_dir() / "hard/stiff_spring_arm.toml")
    plan = as_plan(scene)
    mj = mjcf_from_scene(scene, plan.model)
    run, rec = stable_run(mj, plan, t_end=0.3, samples=31, integrator="RK4", timestep=1e-3)
    assert rec["converged"] and rec["chosen"] == {"integrator": "RK4", "timestep": 1e-5}
    assert not run.blow_ups and rec["convergence"]["max_abs_difference"] < CONVERGED
    first = rec["tried"][0]
    assert first["integrator"] == "implicitfast" and first["stable"] and first["max_abs_difference"] > 0.1
    assert "converged" in rec["note"] and run.notes[0] == rec["note"]
    kept, none = stable_run(mj, plan, t_end=0.3, samples=31, integrator="RK4", timestep=1e-5)
    assert none is None and kept.integrator == "RK4"             # a stable asked setting is kept as it is


def test_study_counts_a_mujoco_reset_as_a_failure():
    """MuJoCo resets its state and time after a blow-up; run_mujoco then reports the steps' times, so a
    reset run looks regular in time: the study must still call it failed (it once drew RK4's blow-ups on
    the hand as errors of 1e9 rad)."""
    scene = load_scene(shipped_robots_dir() / "hard/stiff_spring_arm.toml")
    plan = as_plan(scene)
    from urdf2links.compare.mujoco_side.mujoco_run import run_mujoco

    run = run_mujoco(mjcf_from_scene(scene, plan.model), plan, t_end=0.05, timestep=1e-3, integrator="RK4", samples=6)
    assert run.blow_ups and np.all(np.diff(run.t) > 0)
    assert "reset" in _mujoco_failure(run, 0.05)

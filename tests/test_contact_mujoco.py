"""Ground contact in MuJoCo (issue 37): the same law in the compiled control callback (E83) agrees with the
project's run to integration accuracy; MuJoCo's energy with the contact's elastic energy balances too."""

from __future__ import annotations

import numpy as np
import pytest

from urdf2links.compare.mujoco_side.contact_inputs import contact_energy
from urdf2links.compare.mujoco_side.mjcf import mjcf_from_scene
from urdf2links.compare.mujoco_side.mujoco_run import run_mujoco
from urdf2links.integration.simulate import simulate
from urdf2links.locations import shipped_robots_dir
from urdf2links.scenes.plan import compile_plan
from urdf2links.scenes.scene_read import load_scene

T_END = 0.4     # the landing (t ~ 0.12 s) and the first rebound of quad12_drop


@pytest.fixture(scope="module")
def drop():
    scene = load_scene(shipped_robots_dir() / "quad12_drop.toml")
    model = scene.model()
    plan = compile_plan(scene, model)
    return scene, model, plan, simulate(plan, t_end=T_END, samples=81, progress=False)


def test_mujoco_runs_the_same_contact_law(drop):
    """RK4 at 1e-4 s with the law in the callback lands where the project does, and the difference falls as
    MuJoCo's step shrinks; without the callback's contact the robot falls through the ground."""
    scene, model, plan, traj = drop
    errors = []
    for dt in (2e-4, 1e-4):
        run = run_mujoco(mjcf_from_scene(scene, model, timestep=dt), plan, t_end=T_END, samples=81)
        errors.append(np.max(np.abs(run.q - traj.q)))
        assert not run.blow_ups and run.inputs == "compiled"
    # measured 1.8e-3 at 2e-4 s and 2e-8 at 1e-4 s (the contact's stiff modes, |lambda| ~ 5e3 /s, near RK4's
    # stability edge at 2e-4 s); the feet sink ~5 mm, the trunk falls 9 cm
    assert errors[1] < 1e-6 < errors[0]
    assert traj.q[-1, 2] > 0.25             # standing: the trunk 0.3 m up, not on the floor


def test_mujoco_energy_balance_counts_the_contact(drop):
    """MuJoCo's E + V plus the contact's elastic energy V_c at its states (E81), minus the project's work W,
    stays at RK4's error: the same physics in both, dissipation included."""
    scene, model, plan, traj = drop
    run = run_mujoco(mjcf_from_scene(scene, model, timestep=1e-4), plan, t_end=T_END, samples=81)
    h = run.total_energy + contact_energy(plan, run.t, run.q)
    W = traj.energy["work"]
    scale = np.abs(W).max()
    # measured 1e-7 relative; without V_c the balance is off by the feet's elastic energy (0.16 relative)
    assert np.max(np.abs(h - h[0] - W)) < 1e-5 * scale
    assert np.max(np.abs(run.total_energy - run.total_energy[0] - W)) > 1e-3 * scale


# --------------------------------------------------------------------------- MuJoCo's native contact (E84)


@pytest.fixture(scope="module")
def stand():
    from urdf2links.compare.agreement.trajectory import compare_scene

    return compare_scene(shipped_robots_dir() / "quad12_stand.toml", t_end=0.5, states=1, progress=False)


def test_native_contact_holds_the_robot_up_near_the_law(stand):
    """MuJoCo's own contacts (sphere geoms, solref and friction from the law) carry the standing quadruped:
    no blow-up, the base within a centimetre of the law's, the feet within a centimetre; the summary and the
    report carry the figures."""
    from urdf2links.compare.mujoco_side.native_contact import native_mjcf
    from urdf2links.compare.reports.contact_section import contact_section
    from urdf2links.compare.reports.report import render_markdown

    s = stand.summary()
    nat = s["contact"]["native"]
    assert not nat["native_blow_ups"]
    # measured 5.3 mm (MuJoCo's impedance ~1 sinks the feet far less than the law's 5 mm) and 5.6 mm
    assert 1e-4 < abs(nat["base_height"]["native_final"] - nat["base_height"]["ours_final"]) < 0.01
    assert nat["feet"]["final_max_distance"] < 0.01
    assert s["trajectory"]["max_abs_error"] < 1e-6          # the same law in both engines
    native, _ = native_mjcf(stand.mj, compile_plan(stand.scene, stand.model))
    assert native.model.ngeom == 5 and not native.model.opt.disableflags & 1   # 4 spheres, the plane; contact on
    page = "".join(contact_section(stand, s))
    assert "MuJoCo's native contact" in page and "time to settle" in page and "base64" in page
    assert "## Ground contact" in render_markdown(s)


# --------------------------------------------------------------------------- --ground on a real quadruped


@pytest.mark.usefixtures("corpus_installed")
def test_ground_on_go1_agrees_once_mujocos_step_resolves_the_contact():
    """go1 (example-robot-data) at q = 0 on its four feet, its joints free (issue 37's --ground; since issue 43
    --ground holds a stance, tests/test_stance.py), collapses onto its feet; an impact at t ~ 0.55 s makes the
    contact's stiffest mode ~1e5 /s: MuJoCo's RK4 step is halved for it (at 1e-4 s the feet land 7e-2 rad
    away, not blowing up) and the engines then agree."""
    import dataclasses
    import warnings

    from corpus import ROOT

    from urdf2links.compare.mujoco_side.contact_inputs import contact_timestep
    from urdf2links.scenes.contact import _robot_spheres, ground_contact
    from urdf2links.scenes.default_scenes import default_scene

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")         # go1's base inertia finding: audited, not the point here
        scene = default_scene(ROOT / "go1_description/urdf/go1.urdf", floating=True, q0="zero", t_end=0.6)
        model = scene.model()
    feet = _robot_spheres(model)
    assert sorted(s.link for s in feet) == ["FL_foot", "FR_foot", "RL_foot", "RR_foot"]
    scene = dataclasses.replace(scene, contacts=(dataclasses.replace(ground_contact(model, feet), height="touching"),))
    plan = compile_plan(scene, model)
    traj = simulate(plan, samples=121, progress=False)
    dt, note = contact_timestep(plan, traj, 1e-4)
    assert dt <= 1e-4 / 8 and "halved" in note
    # both engines through the impact, from the project's state at t = 0.45 s (nothing in the scene depends on t)
    k = 90
    ours = simulate(plan, q0=traj.q[k], qd0=traj.qd[k], t_end=0.15, samples=31, progress=False)
    run = run_mujoco(mjcf_from_scene(scene, model, timestep=dt), plan, q0=traj.q[k], qd0=traj.qd[k], t_end=0.15,
                     samples=31)
    assert not run.blow_ups
    # measured 2e-11 at dt 6.25e-6 s (the whole second at 1e-4 s: 7e-2); the divergence threshold is 1e-3
    assert np.max(np.abs(run.q - ours.q)) < 1e-6

"""The compiled control callback (urdf2links.compare.mujoco_side.control_callback) against the Python one it replaces.

The Python callback (``run_mujoco(..., inputs="python")``, numpy at every RK4 stage) is the harness
the MuJoCo comparison used before; the compiled one must give the same trajectories to 1e-12 on
every shipped scene with time-dependent inputs and on a scene with every kind of load.
"""

from __future__ import annotations

import ctypes

import numpy as np
import pytest

import mujoco

from urdf2links.compare.mujoco_side.mjcf import mjcf_from_scene  # noqa: E402
from urdf2links.compare.mujoco_side.mujoco_constraints import with_constraints  # noqa: E402
from urdf2links.compare.mujoco_side.mjdata_layout import LayoutError, check_offsets, mjdata_offsets  # noqa: E402
from urdf2links.compare.mujoco_side.mujoco_run import run_mujoco  # noqa: E402
from urdf2links.locations import shipped_robots_dir  # noqa: E402
from urdf2links.scenes.plan import compile_plan  # noqa: E402
from urdf2links.scenes.scene_read import load_scene, scene_from_dict  # noqa: E402

ROBOTS = shipped_robots_dir()


def _driven(scene) -> bool:
    return scene.base is not None or bool(scene.torques) or bool(scene.loads) or bool(scene.actuators) \
        or bool(scene.computed_torque)


def shipped_driven_scenes():
    out = []
    for f in [*sorted(ROBOTS.glob("*.toml")), *sorted((ROBOTS / "hard").glob("*.toml")), *sorted((ROBOTS / "loops").glob("*.toml"))]:
        scene = load_scene(f)
        # a [[contact]] scene's law runs only in the compiled callback (tests/test_contact_mujoco.py checks it)
        if _driven(scene) and not scene.contacts:
            out.append(pytest.param(f, id=f.stem))
    return out


def every_load_scene():
    """The deck crane on a moving base with a joint torque, a force in link axes at a point, a force
    and a moment in world axes on the boom, and a force and a moment in link axes on the folded
    massless link sway_gimbal (mapped through the host body's Jacobian)."""
    sines = lambda a, f, p=0.0: {"sines": [[a, f, p]]}  # noqa: E731
    return scene_from_dict({
        "robot": {"shipped": "deck_crane"},
        "gravity": {"magnitude": 9.81},
        "base": {"z": sines(0.5, 0.2), "phi_x": sines(0.05, 0.3), "phi_z": sines(0.1, 0.1, 0.4)},
        "torque": [{"coordinate": "slew", "value": sines(2e4, 0.5)}],
        "spring": [{"coordinate": "luff", "stiffness": 1e6, "rest": -0.6, "damping": 1e5}],
        "force": [{"link": "load", "point": [0.1, 0.0, -0.2], "frame": "link", "value": [sines(500.0, 1.0), 0, 100.0]},
                  {"link": "boom", "point": [2.0, 0.0, 0.0], "frame": "world", "value": [0, 300.0, sines(200.0, 0.7)]},
                  {"link": "sway_gimbal", "point": [0.0, 0.2, 0.0], "frame": "link", "value": [sines(400.0, 0.9), 50.0, 0]}],
        "moment": [{"link": "boom", "frame": "world", "value": [sines(1e3, 0.4), 0, 0]},
                   {"link": "sway_gimbal", "frame": "link", "value": [0, sines(300.0, 1.3), 0]}],
        "initial": {"q": {"luff": -0.6, "sway_y": 0.5}},
        "run": {"t_end": 1.0, "samples": 11},
    }, where="<every load>", name="every_load")


def _both(scene, *, t_end, integrator="RK4", dt=1e-4, samples=11):
    model = scene.model()
    mj = mjcf_from_scene(scene, model, timestep=dt, integrator=integrator)
    plan = compile_plan(scene, model)
    if plan.constraints is not None:        # a closed loop or a tendon: route 1 carries them as compare does
        mj = with_constraints(mj, plan.constraints)
    fast = run_mujoco(mj, scene, t_end=t_end, samples=samples)
    slow = run_mujoco(mj, scene, t_end=t_end, samples=samples, inputs="python")
    assert mujoco.get_mjcb_control() is None
    return fast, slow


def _assert_same(fast, slow):
    """Equal trajectories: 1e-12 absolute on q (rad or m) and on qd scaled by max(1, |qd|) (the
    velocities of the stiff servo springs reach tens of rad/s); both callbacks run the same
    arithmetic in another order (a Cholesky instead of an LU solve), so only rounding differs."""
    assert fast.inputs == "compiled" and slow.inputs == "python"
    assert fast.callback_calls == slow.callback_calls > 0
    assert np.max(np.abs(fast.q - slow.q)) <= 1e-12
    assert np.max(np.abs(fast.qd - slow.qd)) <= 1e-12 * max(1.0, float(np.max(np.abs(slow.qd))))
    scale = max(1.0, float(np.max(np.abs(slow.energy))))
    assert np.max(np.abs(fast.energy - slow.energy)) <= 1e-10 * scale
    assert abs(fast.base_tracking_error - slow.base_tracking_error) <= 1e-12
    np.testing.assert_array_equal(fast.t, slow.t)


@pytest.mark.parametrize("path", shipped_driven_scenes())
def test_compiled_callback_equals_python_on_shipped_scenes(path):
    scene = load_scene(path)
    fast, slow = _both(scene, t_end=0.1)
    _assert_same(fast, slow)
    assert fast.callback_calls == 4 * fast.nsteps  # RK4: one call per stage


def test_compiled_callback_equals_python_with_every_load():
    fast, slow = _both(every_load_scene(), t_end=0.2)
    _assert_same(fast, slow)
    assert fast.base_tracking_error < 1e-9
    # the scene moves: the loads did something (the run without them differs)
    assert np.max(np.abs(fast.q[-1] - fast.q[0])) > 1e-3


def test_compiled_callback_with_euler():
    """Euler calls the callback once per step; the base is then exact without dampers only, so
    the spring arm (no base) is the case to compare."""
    fast, slow = _both(load_scene(ROBOTS / "spring_arm_torques.toml"), t_end=0.2, integrator="Euler")
    _assert_same(fast, slow)
    assert fast.callback_calls == fast.nsteps


def test_timed_region_is_the_engine():
    """A passive scene without dampers (the double pendulum): wall_time is inside mj_step only (less than the
    harness's total), the energy flag is off in the stepping model, and a run without inputs installs no
    callback."""
    scene = load_scene(ROBOTS / "double_pendulum_chaos.toml")
    mj = mjcf_from_scene(scene, scene.model(), timestep=1e-3)
    run = run_mujoco(mj, scene, t_end=0.5, samples=51)
    assert run.inputs == "none" and run.callback_calls == 0
    assert 0 < run.wall_time < run.harness_time
    assert not mj.model.opt.enableflags & int(mujoco.mjtEnableBit.mjENBL_ENERGY)
    assert np.ptp(run.total_energy) < 1e-3 * np.max(np.abs(run.energy))  # energies were computed


def test_layout_checked_against_the_bindings():
    m = mujoco.MjModel.from_xml_string("<mujoco><worldbody><body><joint/><geom size='.1'/></body></worldbody></mujoco>")
    d = mujoco.MjData(m)
    d.time = 0.25
    good = mjdata_offsets(d)
    assert ctypes.c_double.from_address(d._address + good["time"]).value == 0.25 and d.time == 0.25
    with pytest.raises(LayoutError, match="qfrc_applied"):
        check_offsets(d, {**good, "qfrc_applied": good["qfrc_applied"] + 8})
    with pytest.raises(LayoutError, match="time"):
        check_offsets(d, {**good, "time": good["time"] + 8})
    assert d.time == 0.25


@pytest.mark.slow
def test_ship_crane_two_seconds_unchanged():
    """The Done-when run of issue 13: `urdf2links compare robots/ship_crane.toml --t-end 2` (RK4, dt
    1e-4 s, 201 samples): the compiled callback's trajectory is the Python callback's to 1e-12."""
    fast, slow = _both(load_scene(ROBOTS / "ship_crane.toml"), t_end=2.0, samples=201)
    _assert_same(fast, slow)
    assert fast.nsteps == 20000

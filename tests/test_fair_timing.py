"""Both engines timed the same way (issue 13): what each timed region contains, compilation kept out.

No test here asserts a speed: that compilation stays out of the timed regions is checked on numba's
own compile events (a fresh environment's first scene compiles nothing outside its warm-up), not by
timing a run against itself, which a loaded machine moves (a 2x bound failed at 3.0x under load).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from numba import njit

from urdf2links.integration.simulate import record_compilation, simulate, warm_up

ROOT = Path(__file__).resolve().parent.parent
ROBOTS = ROOT / "robots"


def test_record_compilation_sees_a_compile_and_not_a_cached_call():
    @njit
    def twice(x):
        return 2.0 * x

    with record_compilation() as rec:
        assert twice(1.5) == 3.0
    assert rec.happened and any("twice" in f for f in rec.functions) and rec.seconds > 0
    with record_compilation() as again:
        twice(2.0)
    assert not again.happened and again.functions == []


def test_warm_up_leaves_nothing_to_compile_in_the_run():
    scene = ROBOTS / "spring_arm_torques.toml"
    warm_up(scene, methods=("DOP853", "RK4"))
    for method, kw in (("DOP853", {}), ("RK4", {"dt": 1e-3})):
        with record_compilation() as rec:
            tr = simulate(scene, t_end=0.2, samples=21, progress=False, method=method, **kw)
        assert not rec.happened, f"{method}: compiled inside the run: {rec.functions}"
        # the timed region is the integration only: inside the whole call
        assert 0 < tr.stats["wall_time"] <= tr.stats["run_s"]


def test_summary_states_the_timed_regions():
    from urdf2links.compare.agreement.trajectory import compare_scene

    s = compare_scene(ROBOTS / "ship_crane.toml", t_end=0.05, states=2, progress=False).summary()["wall_time"]
    assert set(s["regions"]) == {"project_s", "mujoco_s", "project_run_s", "mujoco_harness_s", "project_warmup_s",
                                 "mujoco_callback_load_s"}
    assert "mj_step(m, d, nstep=k)" in s["regions"]["mujoco_s"] and "energy flag off" in s["regions"]["mujoco_s"]
    assert "numba's compilation" in s["regions"]["project_s"]
    assert 0 < s["project_s"] <= s["project_run_s"] and 0 < s["mujoco_s"] <= s["mujoco_harness_s"]
    assert s["mujoco_inputs"] == "compiled" and s["mujoco_callback_calls"] == 4 * 500


_FIRST_SCENE = """
import json
from urdf2links.compare.commands import shipped_scenes
from urdf2links.compare.agreement import trajectory
from urdf2links.integration.simulate import record_compilation
inside, timed = [], trajectory.simulate

def simulate(*args, **kwargs):          # compare_scene's timed run (its warm-up calls simulate elsewhere)
    with record_compilation() as rec:
        out = timed(*args, **kwargs)
    inside.extend(rec.functions)
    return out

trajectory.simulate = simulate
with record_compilation() as everything:
    s = trajectory.compare_scene(shipped_scenes()[0], states=2, progress=False).summary()
print(json.dumps({"scene": s["key"], "all": everything.functions, "warm_up": s["wall_time"]["project_compiled"],
                  "inside_run": inside}))
"""


@pytest.mark.slow
def test_first_scene_in_a_fresh_environment_compiles_only_in_its_warm_up(tmp_path):
    """`urdf2links report`'s first scene with an empty numba cache (everything compiles), then again
    with the cache it filled. In the fresh run numba compiles nothing inside the timed run (the whole
    simulate() call that holds the timed integration: numba's compile events, whatever the machine's
    load); the warm-up compiled. The second run compiles nothing at all: the disk cache serves a new
    process."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba-cache"))

    def run():
        out = subprocess.run([sys.executable, "-c", _FIRST_SCENE], env=env, cwd=tmp_path, capture_output=True,
                             text=True, timeout=3600)
        assert out.returncode == 0, out.stderr[-3000:]
        return json.loads(out.stdout.strip().splitlines()[-1])

    first = run()
    assert first["all"], "nothing recorded"
    assert not first["inside_run"], f"{first['scene']}: compiled inside the timed run: {first['inside_run']}"
    assert first["warm_up"], "the first run found a filled cache: not a fresh environment"
    second = run()
    assert not second["all"], f"the second run compiled again: {second['all']}"

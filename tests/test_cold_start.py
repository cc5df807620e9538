"""Issue 32: a fast first command. Light imports, compilation only of what a run uses and never in a
reported time, tidy caches. (The process wall times themselves are measured by
``benchmarks/cold_start.py``, not by tests.)"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
from numba import njit

from urdf2links import compilation
from urdf2links.numba_cache import ORIGIN, cache_folders, clear_cache

ROOT = Path(__file__).resolve().parent.parent
HEAVY = {"numba", "scipy", "mujoco", "matplotlib", "trimesh", "meshcat"}


def _python(code: str, env: dict | None = None, timeout: float = 600) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=timeout,
                          env=dict(os.environ, **(env or {})), cwd=ROOT)


def test_import_and_help_load_nothing_heavy():
    """``import urdf2links`` and the command line's parser import none of numba, scipy, MuJoCo,
    matplotlib, trimesh, meshcat; the public names still resolve (loaded at first use)."""
    code = ("import sys, urdf2links, urdf2links.cli as cli; cli.build_parser().format_help(); "
            f"print(sorted(set(m.split('.')[0] for m in sys.modules) & {HEAVY!r})); "
            "urdf2links.Model; print('numba' in sys.modules, 'mujoco' in sys.modules)")
    out = _python(code)
    assert out.returncode == 0, out.stderr
    loaded, after = out.stdout.strip().splitlines()
    assert loaded == "[]", f"imported by `import urdf2links` or the parser: {loaded}"
    assert after == "True False"      # urdf2links.Model loads the compiled dynamics, never MuJoCo


_PENDULUM = """
import json, numpy as np
from numba import njit
from urdf2links import load_robot
from urdf2links.integration.loops import radau, lu
from urdf2links.integration.simulate import simulate
from urdf2links.scenes import scene_inputs as SN, scene_kernels as SK
from urdf2links.dynamics import kernels, model_kernels as MK
tr = simulate(load_robot("robots/pendulum.urdf"), t_end=0.5, method="auto", progress=False)
from urdf2links.scenes.plan import compile_plan
from urdf2links.integration.simulate import _scene_and_model
scene, model, _ = _scene_and_model(load_robot("robots/pendulum.urdf"), None)
rhs = compile_plan(scene, model).rhs
fresh = njit(SK._rhs.py_func)          # typed anew here: every callee it reaches is compiled or loaded now
y = np.zeros(rhs.dim)
from urdf2links.dynamics.tree_arrays import Tree
from urdf2links.scenes.scene_arrays import Scene
fresh(0.0, y, np.empty(rhs.dim), Tree(*rhs.args[:3]), Scene(*rhs.args[3:6]), *rhs.FX)
used = {f.__name__: len(f.overloads) for f in (SK.computed_torque, SN._actuators, SN._apply_loads, SK._coupled_solve,
        radau.radau_chunk, lu.lu_factor, MK.fd_batch, kernels.kinematics)}
print(json.dumps({"used": used, "wall": tr.stats["wall_time"], "methods": tr.stats["methods_used"]}))
"""


def test_a_pendulum_compiles_only_what_it_runs():
    """A pendulum's right-hand side reaches none of the computed torque, actuators, loads or coupled
    solve (typed anew in a fresh process: a callee it reaches gets a compiled variant), its ``auto`` run
    neither Radau5 nor its LU, nor a batch kernel; and its reported wall time leaves out the loading of
    the compiled loops from the cache (measured 0.002-0.004 s; it was 0.3 s when that load was timed;
    the issue's bound 0.05 s)."""
    out = _python(_PENDULUM)
    assert out.returncode == 0, out.stderr
    got = json.loads(out.stdout.strip().splitlines()[-1])
    assert got["used"].pop("kinematics") >= 1 and got["methods"] == "DOP853"
    assert not any(got["used"].values()), f"compiled without being used: {got['used']}"
    assert got["wall"] < 0.05, got


_THREE_SCENES = """
import json
from urdf2links.integration.simulate import simulate
from urdf2links.integration.loops import erk
from urdf2links.scenes import load_scene, scene_kernels as SK
for path in ("robots/ship_crane.toml", "robots/ur5_servo.toml", "robots/spring_arm_torques.toml"):
    simulate(load_scene(path), t_end=0.05, method="DOP853", progress=False)
# (a loop loaded from the cache brings its callees inside it: only the loops' own variants are counted)
print(json.dumps({"erk_chunk": len(erk.erk_chunk.overloads), "initial_step": len(erk.initial_step.overloads),
                  "effects": sorted(str(fx) for fx in SK._VARIANTS)}))
"""


def test_the_loops_are_compiled_once_whatever_the_effects():
    """Three scenes with three combinations of effects (none; actuators; loads) in one process: three
    variants of the right-hand side, one of DOP853's loop (the right-hand side reaches the loops as a C
    function typed by its signature alone; with the effects' markers among the loops' arguments, the
    loop was compiled once per combination, 66 of a first report's 105 s of compilation)."""
    out = _python(_THREE_SCENES)
    assert out.returncode == 0, out.stderr
    got = json.loads(out.stdout.strip().splitlines()[-1])
    assert got["effects"] == ["(1, None, None, None, None)", "(None, 1, None, None, None)",
                             "(None, None, None, None, None)"], got     # the fifth: constraints (issue 45)
    assert got["erk_chunk"] == 1 and got["initial_step"] == 1, got


_CALLBACK = """
import json
from numba import cfunc, types
from urdf2links.compare.mujoco_side import control_callback as MI
sig = types.void(types.voidptr, types.voidptr)
got = {}
for name, effects in (("none", (None,) * 5), ("ct", (1, None, None, None, None))):
    cfunc(sig)(MI._callback_of(*effects))       # typed anew here: every callee it reaches gets a variant now
    got[name] = {f.__name__: len(f.overloads) for f in (MI._computed_torque, MI._ball_servos, MI._apply_loads,
                                                        MI._contact, MI._prescribe_base)}
print(json.dumps(got))
"""


def test_mujoco_callback_compiles_only_the_effects_of_its_run():
    """MuJoCo's control callback for a run without effects reaches none of the computed torque, ball
    servos, loads, contact or prescribed base; with the computed torque, that one only."""
    out = _python(_CALLBACK)
    assert out.returncode == 0, out.stderr
    got = json.loads(out.stdout.strip().splitlines()[-1])
    assert not any(got["none"].values()), got
    assert got["ct"] == {"_computed_torque": 1, "_ball_servos": 0, "_apply_loads": 0, "_contact": 0,
                         "_prescribe_base": 0}, got


_REFCOUNTS = """
import json, numpy as np
from urdf2links import load_robot
from urdf2links.dynamics import factor, inverse_kernels as IK, kernels, model_kernels as MK
m = load_robot("robots/ur5_like.urdf")
m.forward_dynamics(np.zeros(m.n), np.ones(m.n))
m.inverse_dynamics(np.zeros(m.n), np.ones(m.n), np.ones(m.n))
def counts(fn):     # NRT_incref / NRT_decref calls in fn's own compiled code (compiled here: the cache is empty)
    tag, n = f"{len(fn.__name__)}{fn.__name__}", 0
    for ir in fn.inspect_llvm().values():
        own = False
        for line in ir.splitlines():
            own = tag in line.split("(")[0] if line.startswith("define") else own
            n += own and ("call void @NRT_incref" in line or "call void @NRT_decref" in line)
    return n
got = {f.__name__: counts(f) for f in (kernels.kinematics, kernels.dynamics, factor.ltdl, factor.ltdl_solve,
                                      IK.own_armature, MK.fd_plain)}     # kinematics: with and without q''
from urdf2links.scenes import scene_kernels as SK
for key, effects in (("scene_rhs", (None,) * 5), ("scene_rhs_constraints", (None,) * 4 + (1,))):
    ir = SK.rhs_function(effects).inspect_llvm()     # a scene's right-hand side, callees included (issue 45: with
    got[key] = ir.count("call void @NRT_incref") + ir.count("call void @NRT_decref")    # the KKT solve too)
print(json.dumps(got))
"""


def test_the_kernels_carry_no_reference_counting(tmp_path):
    """The passes over the tree and the factorization, and a scene's right-hand side with all it calls,
    compiled afresh (an empty cache), call none of numba's reference counting (:func:`compilation.kernel`;
    with plain ``njit`` the kinematics alone had 12 call sites, and they took a fifth of a UR5 forward
    dynamics; the right-hand side as a counting C function had 24). ``fd_plain`` allocates its scratch,
    so it keeps them: the control of the check itself."""
    out = _python(_REFCOUNTS, env={"URDF2LINKS_CACHE_DIR": str(tmp_path)})
    assert out.returncode == 0, out.stderr
    got = json.loads(out.stdout.strip().splitlines()[-1])
    assert got.pop("fd_plain") > 0, "the check finds no reference counting where it must be"
    assert not any(got.values()), got


def test_clock_stands_still_while_numba_compiles():
    """A duration taken with :func:`compilation.clock` around a first call leaves its compilation out;
    one kernel is compiled once whatever constants its callers pass (:func:`compilation.one_signature`)."""
    @compilation.one_signature
    @njit
    def callee(x, i, flag):
        return x[i] + (1.0 if flag else 0.0)

    @njit
    def caller(x, n):
        return callee(x, 0, True) + callee(x, n, False) + callee(x, 1, n > 0)

    compilation.watch()
    c0, t0, s0 = compilation.clock(), time.perf_counter(), compilation.seconds()
    assert caller(np.ones(3), 2) == 5.0
    elapsed, clocked, compiled = time.perf_counter() - t0, compilation.clock() - c0, compilation.seconds() - s0
    assert compiled > 0.05 and clocked < 0.2 * elapsed, (elapsed, clocked, compiled)
    assert len(callee.overloads) == 1, list(callee.overloads)       # literals 0, True, 1, False: one variant


def _fake(folder: Path, name: str, source: Path | None, size: int = 10) -> Path:
    sub = folder / name
    sub.mkdir(parents=True)
    (sub / "f.nbc").write_bytes(b"x" * size)
    if source is not None:
        (sub / ORIGIN).write_text(f"{source}\n")
    return sub


def test_cache_list_and_clear(tmp_path):
    """Each cache folder's status from the source folder it records: this install's, another's (still
    there), gone (removed), unknown (not recorded: an older layout, or a folder another process is
    creating at this moment -- two xdist workers start at once -- so never removed at start);
    ``stale`` clears all but this install's."""
    cache = tmp_path / "cache"
    here = ROOT / "urdf2links" / "dynamics"
    other = tmp_path / "other_install"
    other.mkdir()
    _fake(cache, "dynamics_1", here)
    _fake(cache, "dynamics_2", other)
    _fake(cache, "dynamics_3", tmp_path / "removed")
    _fake(cache, "dynamics_4", None)
    status = {f.path.name: f.status for f in cache_folders(cache)}
    assert status == {"dynamics_1": "current", "dynamics_2": "other", "dynamics_3": "gone", "dynamics_4": "unknown"}
    assert {f.path.name for f in clear_cache(cache, which="gone")} == {"dynamics_3"}
    assert {f.path.name for f in clear_cache(cache, which="stale")} == {"dynamics_2", "dynamics_4"}
    assert [f.path.name for f in cache_folders(cache)] == ["dynamics_1"]
    out = subprocess.run([sys.executable, "-m", "urdf2links", "cache", "--list"], capture_output=True, text=True,
                         env=dict(os.environ, URDF2LINKS_CACHE_DIR=str(cache)), cwd=tmp_path)
    assert out.returncode == 0 and "dynamics_1" in out.stdout and "this install" in out.stdout, out.stdout + out.stderr


def test_a_cache_that_cannot_be_written_says_so_once(tmp_path):
    """A cache folder that cannot be made (here: below a file) falls back to a folder for this
    process only, with one note naming the folder, and the compiled code still runs."""
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    code = ("import urdf2links.dynamics, urdf2links.scenes, urdf2links.integration; "
            "from urdf2links.dynamics.factor import pivot_floor; print(pivot_floor(1.0, 1) > 0)")
    out = _python(code, env={"URDF2LINKS_CACHE_DIR": str(blocker / "cache")})
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "True"
    assert out.stderr.count("cannot be written") == 1 and str(blocker / "cache") in out.stderr, out.stderr

"""Batched dynamics (``Model.forward_dynamics(Q, QD, TAU)`` and the terms with a leading batch axis)
against the per-state calls, to the last bit; shapes and errors that name the offending row; the
batched q'' against MuJoCo's mj_forward on the route-1 model.

A batch runs the same compiled row function as a single state (``urdf2links.dynamics.model_kernels``), so
every row must equal the single call exactly (``np.array_equal``): any difference means the batch
evaluates something else (another base, another coupling, a scratch shared between threads).
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import corpus
from builders import random_tree
from test_importer import MIMIC
from urdf2links import BaseState, DynamicsError, LinkSpec, Model, build_tree, load_urdf, load_urdf_string
from urdf2links.locations import shipped_robots_dir

B = 13          # rows: more than the chunks of a 2-thread machine (4 per thread), not a multiple of them


def _shipped(name):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return load_urdf(shipped_robots_dir() / name)


def _corpus(rel, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return load_urdf(corpus.path(rel), inertia="repair", **kw)


MODELS = {
    "double_pendulum": lambda: _shipped("double_pendulum.urdf"),
    "ur5_like": lambda: _shipped("ur5_like.urdf"),
    "random_branched": lambda: random_tree(4, links=9, min_coords=1),
    "mimic_coupled": lambda: load_urdf_string(MIMIC, mimic="coupled"),
    "panda_coupled": lambda: _corpus("panda_description/urdf/panda.urdf", mimic="coupled"),
    "talos_full_coupled": lambda: _corpus("talos_data/robots/talos_full_v2.urdf", mimic="coupled"),
}
NEEDS_CORPUS = {"panda_coupled", "talos_full_coupled"}


@pytest.fixture(scope="module", params=list(MODELS))
def model(request):
    if request.param in NEEDS_CORPUS and corpus.ROOT is None:
        pytest.fail(corpus.MISSING)         # a test dependency: missing means a broken install, not a skip
    m = MODELS[request.param]()
    assert ("coupled" in request.param) == (m.coupling is not None), "a coupled model must have coupled coordinates"
    return m


def _states(model, seed=0):
    rng = np.random.default_rng(seed)
    n = model.n
    return rng.uniform(-1, 1, (B, n)), rng.normal(size=(B, n)), rng.normal(size=(B, n))


def _bases(seed=1):
    rng = np.random.default_rng(seed)
    return BaseState(rng.normal(size=(B, 6)), rng.normal(size=(B, 6)), rng.normal(size=(B, 6)))


def _row_base(base, b):
    return BaseState(base.pose[b], base.rate[b], base.accel[b])


def _per_row(fn, arrays, base=None, **kw):
    out = []
    for b in range(arrays[0].shape[0]):
        kb = dict(kw, base=_row_base(base, b) if isinstance(base, BaseState) and np.ndim(base.pose) == 2 else base)
        out.append(fn(*(a[b] for a in arrays), **kb))
    return np.array(out)


def _same(batched, single, what):
    assert batched.shape == single.shape, what
    diff = np.flatnonzero(~(batched == single).reshape(batched.shape[0], -1).all(axis=1))
    assert diff.size == 0, f"{what}: rows {diff.tolist()} differ from the per-state calls; max |diff| " \
                           f"{np.abs(batched - single).max():.3e}"


SHARED = BaseState(np.array([0.1, -0.2, 0.3, 0.2, -0.1, 0.4]), np.array([0.3, 0.1, -0.2, 0.5, -0.4, 0.2]),
                   np.array([-0.2, 0.4, 0.1, -0.3, 0.2, 0.1]))


@pytest.mark.parametrize("base_kind", ["fixed", "shared", "per_row"])
def test_batch_equals_per_state_calls_to_the_last_bit(model, base_kind):
    Q, QD, TAU = _states(model)
    base = {"fixed": None, "shared": SHARED, "per_row": _bases()}[base_kind]
    cases = [("forward_dynamics", (Q, QD, TAU)), ("forward_dynamics", (Q, QD)), ("mass_matrix", (Q,)),
             ("bias", (Q, QD)), ("gravity", (Q,)), ("kinetic_energy", (Q, QD)), ("potential_energy", (Q,))]
    for name, arrays in cases:
        fn = getattr(model, name)
        batched = fn(*arrays, base=base)
        expected_shape = {"mass_matrix": (B, model.n, model.n), "kinetic_energy": (B,),
                          "potential_energy": (B,)}.get(name, (B, model.n))
        assert batched.shape == expected_shape, name
        _same(batched, _per_row(fn, arrays, base), f"{name} ({len(arrays)} arguments), base {base_kind}")


def test_batch_with_loads_and_without_gravity(model):
    from urdf2links import Wrench

    Q, QD, TAU = _states(model, 5)
    link = model.tree.link_names[-1]
    loads = [Wrench(link, force=(1.0, -2.0, 0.5), moment=(0.1, 0.0, -0.2), point=(0.0, 0.01, 0.02))]
    for kw in (dict(loads=loads), dict(gravity=False), dict(loads=loads, base=SHARED)):
        _same(model.forward_dynamics(Q, QD, TAU, **kw), _per_row(model.forward_dynamics, (Q, QD, TAU), **kw),
              f"forward_dynamics {sorted(kw)}")
    _same(model.generalized_forces(Q, loads), np.array([model.generalized_forces(q, loads) for q in Q]),
          "generalized_forces")


def test_batch_base_as_a_function_of_time():
    """A callable base at one time for every row, and at each row's own time."""
    model = _shipped("ur5_like.urdf")
    Q, QD, TAU = _states(model, 2)

    def heave(t):
        return BaseState(np.array([0, 0, 0.1 * np.sin(t), 0, 0, 0.2 * t]),
                         np.array([0, 0, 0.1 * np.cos(t), 0, 0, 0.2]),
                         np.array([0, 0, -0.1 * np.sin(t), 0, 0, 0.0]))

    ts = np.linspace(0.0, 1.2, B)
    _same(model.forward_dynamics(Q, QD, TAU, base=heave, t=0.7),
          _per_row(model.forward_dynamics, (Q, QD, TAU), heave, t=0.7), "base(t) shared")
    _same(model.forward_dynamics(Q, QD, TAU, base=heave, t=ts),
          np.array([model.forward_dynamics(Q[b], QD[b], TAU[b], base=heave, t=ts[b]) for b in range(B)]),
          "base(t) per row")


def test_batch_thread_count_does_not_change_the_result():
    """One thread and all threads: the rows are split into other chunks, the figures stay the same."""
    import numba

    model = _shipped("ur5_like.urdf")
    Q, QD, TAU = _states(model, 3)
    before = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        one = model.forward_dynamics(Q, QD, TAU)
    finally:
        numba.set_num_threads(before)
    _same(model.forward_dynamics(Q, QD, TAU), one, "all threads against one")


# -- shapes and errors --------------------------------------------------------------------------------
def test_batch_shapes_are_checked():
    model = _shipped("double_pendulum.urdf")
    Q, QD, TAU = _states(model)
    with pytest.raises(ValueError, match=r"qd must have the shape of q, \(13, 2\).*got shape \(12, 2\)"):
        model.forward_dynamics(Q, QD[:-1])
    with pytest.raises(ValueError, match=r"tau must have the shape of q.*got shape \(2,\)"):
        model.forward_dynamics(Q, QD, TAU[0])
    with pytest.raises(ValueError, match=r"q must have shape \(2,\) for one state or \(B, 2\).*\(13, 2, 1\)"):
        model.mass_matrix(Q[..., None])
    with pytest.raises(ValueError, match=r"base: pose, rate and accel must have shape \(6,\) or \(13, 6\)"):
        model.forward_dynamics(Q, QD, base=BaseState(np.zeros((B + 1, 6)), np.zeros((B + 1, 6)),
                                                      np.zeros((B + 1, 6))))
    with pytest.raises(ValueError, match=r"t must be a number, or an array of shape \(13,\)"):
        model.forward_dynamics(Q, QD, base=SHARED, t=np.zeros(B - 1))
    assert model.forward_dynamics(np.zeros((0, 2)), np.zeros((0, 2))).shape == (0, 2)


def _slider():
    """A massless arm turning about z carrying a point mass that slides along it:
    ``A = diag(m (a + s)^2, m)``, singular where ``s = -a`` (the mass on the axis)."""
    m, a = 2.0, 0.3
    H = np.zeros((4, 4))
    H[3, 3] = m
    specs = [LinkSpec("arm", None, coordinates={"phi_z": "turn"}),
             LinkSpec("mass", "arm", params=(a, 0, 0, 0, 0, 0), coordinates={"x": "slide"}, H=H)]
    return Model(build_tree(specs), name="slider", gravity=(0, 0, 0))


def test_batch_error_names_the_row_with_a_singular_mass_matrix():
    model = _slider()
    Q = np.array([[0.1, 0.2], [0.0, 0.5], [0.3, -0.3], [0.2, 0.1]])     # row 2: the mass on the axis
    QD = np.ones_like(Q)
    assert np.all(np.isfinite(model.forward_dynamics(np.delete(Q, 2, axis=0), np.delete(QD, 2, axis=0))))
    with pytest.raises(DynamicsError, match=r"^row 2 of the batch: mass matrix A of model 'slider' is not "
                                            r"positive definite at q=\[ 0\.3, -0\.3\].*coordinates turn") as err:
        model.forward_dynamics(Q, QD)
    assert err.value.row == 2 and err.value.coordinates == ("turn",)
    with pytest.raises(DynamicsError, match=r"^mass matrix A") as single:
        model.forward_dynamics(Q[2], QD[2])
    assert single.value.row is None


def test_batch_error_names_the_row_with_nan():
    model = _shipped("ur5_like.urdf")
    Q, QD, TAU = _states(model, 4)
    Q[5, 3] = np.nan
    with pytest.raises(DynamicsError, match=r"^row 5 of the batch: mass matrix A has non-finite entries") as err:
        model.forward_dynamics(Q, QD, TAU)
    assert err.value.row == 5


# -- against MuJoCo -----------------------------------------------------------------------------------
MUJOCO_MODELS = ["double_pendulum.urdf", "ur5_like.urdf"]


@pytest.mark.parametrize("name", MUJOCO_MODELS)
def test_batch_against_mujoco_mj_forward(name):
    """q'' of a batch against MuJoCo's qacc (mj_forward) on the route-1 model, row by row.

    Both engines solve ``A q'' = tau - e - G`` in double precision: the terms agree to ~1e-15
    relative (tests/test_mjcf_route.py), and each solve is backward stable, so q'' agrees to
    ~ n eps cond(A) relative. Bound: 1e3 eps cond(A) |q''| (a wrong term is O(|q''|))."""
    import mujoco        # a core dependency: missing is a broken install, not a skip

    from urdf2links.compare.mujoco_side.mjcf import mjcf_from_model

    model = _shipped(name)
    Q, QD, TAU = _states(model, 6)
    QDD = model.forward_dynamics(Q, QD, TAU)
    mj = mjcf_from_model(model, gravity=model.gravity_vector)
    d = mujoco.MjData(mj.model)
    eps = np.finfo(float).eps
    for b in range(B):
        mj.set_state(d, Q[b], QD[b])
        d.qfrc_applied[:] = 0.0
        d.qfrc_applied[mj.dof_index] = TAU[b]
        mujoco.mj_forward(mj.model, d)
        theirs = d.qacc[mj.dof_index]
        bound = 1e3 * eps * np.linalg.cond(model.mass_matrix(Q[b])) * np.abs(theirs).max()
        assert np.abs(QDD[b] - theirs).max() <= bound, (b, QDD[b], theirs)


def test_read_only_and_strided_inputs_compile_nothing_new():
    """A read-only or strided array is another numba type: the model hands the kernels a writable
    C-contiguous copy, so such inputs (rows of a memory map, frozen arrays) reuse the compiled code
    (a fresh environment's second run once recompiled ``poses_one`` for them)."""
    from urdf2links.integration.simulate import record_compilation

    model = _shipped("ur5_like.urdf")
    Q, QD, TAU = _states(model, 7)
    calls = [lambda q, qd: model.link_poses(q[0]), lambda q, qd: model.forward_dynamics(q, qd),
             lambda q, qd: model.forward_dynamics(q[0], qd[0], base=SHARED), lambda q, qd: model.mass_matrix(q),
             lambda q, qd: model.kinetic_energy(q[0], qd[0])]
    for call in calls:
        call(Q, QD)
    frozen = [np.array(a) for a in (Q, QD)]
    for a in frozen:
        a.setflags(write=False)
    strided = [np.asfortranarray(a) for a in (Q, QD)]
    with record_compilation() as rec:
        for call in calls:
            for q, qd in (frozen, strided):
                call(q, qd)
    assert not rec.happened, rec.functions


def test_a_model_without_coordinates():
    """n = 0 (a welded robot): one state and a batch give empty results, not a reshape error."""
    H = np.diag([0.1, 0.1, 0.1, 1.0])
    model = Model(build_tree([LinkSpec("body", None, H=H)]), name="welded")
    assert model.mass_matrix(np.zeros(0)).shape == (0, 0)
    assert model.forward_dynamics(np.zeros(0), np.zeros(0)).shape == (0,)
    assert model.forward_dynamics(np.zeros((3, 0)), np.zeros((3, 0))).shape == (3, 0)
    assert model.potential_energy(np.zeros((3, 0))).shape == (3,)


def test_every_single_state_call_takes_the_hot_path_with_any_input():
    """Each call's hot path (model_kernels.frozen: a fixed base, float64 vectors) and its general path
    give the same bits; inputs of other types (lists, float32, read-only, strided rows) are converted on
    the general path, compile nothing, and give the same numbers."""
    from urdf2links.dynamics.loads import Wrench
    from urdf2links.integration.simulate import record_compilation

    model = _shipped("ur5_like.urdf")
    Q, QD, _ = _states(model, 2)
    w = [Wrench(model.link_names[-1], force=[1.0, -2.0, 0.5], moment=[0.1, 0.0, 0.3], point=[0.0, 0.1, 0.0])]
    calls = {"mass_matrix": lambda q, qd: model.mass_matrix(q), "bias": lambda q, qd: model.bias(q, qd),
             "gravity": lambda q, qd: model.gravity(q), "generalized_forces": lambda q, qd: model.generalized_forces(q, w),
             "kinetic_energy": lambda q, qd: model.kinetic_energy(q, qd),
             "potential_energy": lambda q, qd: model.potential_energy(q),
             "forward_dynamics": lambda q, qd: model.forward_dynamics(q, qd)}
    for name, call in calls.items():
        hot = call(Q[0], QD[0])
        assert np.array_equal(hot, np.asarray(call(Q, QD))[0]), name          # batch: the general path
        call([float(x) for x in Q[1]], list(QD[1]))                           # compile whatever lists need
    strided = np.asfortranarray(Q)[0]            # a row of a Fortran-ordered array: not C-contiguous
    assert not strided.flags.c_contiguous
    odd = [([float(x) for x in Q[0]], list(QD[0])), (Q[0].astype(np.float32), QD[0]), (strided, QD[0])]
    frozen = Q[0].copy()
    frozen.setflags(write=False)
    odd.append((frozen, QD[0]))
    with record_compilation() as rec:
        for name, call in calls.items():
            for q, qd in odd:
                assert np.array_equal(np.asarray(call(q, qd)), np.asarray(call(np.array(q, float), qd))), name
    assert not rec.happened, rec.functions


@pytest.mark.parametrize("method", ["literal", "numpy"])
def test_forward_dynamics_takes_the_oracle_methods(method):
    """Every Model call takes ``method=``: forward_dynamics solves the oracle's A q'' = Q + tau - e - G.
    The oracles agree with the compiled form to rounding (1e-12 relative: the oracle tests' bound)."""
    from urdf2links.dynamics.loads import Wrench

    model = _shipped("ur5_like.urdf")
    Q, QD, TAU = _states(model, 1)
    w = [Wrench(model.link_names[-1], force=[1.0, -2.0, 0.5])]
    for kw in ({}, {"loads": w}, {"gravity": False}):
        ref = model.forward_dynamics(Q[0], QD[0], TAU[0], **kw)
        got = model.forward_dynamics(Q[0], QD[0], TAU[0], method=method, **kw)
        assert np.max(np.abs(got - ref)) <= 1e-12 * max(1.0, np.max(np.abs(ref)))
    with pytest.raises(ValueError, match="method must be one of"):
        model.forward_dynamics(Q[0], QD[0], method="fast")


# -- what a batched call leaves behind -----------------------------------------------------------------
SLEEPING = """
import sys, time, warnings
import numpy as np
import urdf2links
with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    model = urdf2links.load_urdf(sys.argv[1])
rng = np.random.default_rng(0)
Q, QD = rng.uniform(-1, 1, (1000, model.n)), rng.normal(size=(1000, model.n))
burnt = []
for _ in range(10):
    model.forward_dynamics(Q, QD)
    c0 = time.process_time()
    time.sleep(0.05)
    burnt.append(time.process_time() - c0)
print(1e3 * float(np.mean(burnt)))
"""


def test_numba_threads_sleep_after_a_batched_call():
    """After a batched call numba's worker threads sleep: they do not spin on a core, taking it from
    whatever the process runs next (MuJoCo's threads, in benchmarks/batch_cost.py). Measured as the CPU
    time the process burns while its only running thread sleeps 50 ms right after a call (mean of 10):
    0.04-0.06 ms when the workers sleep; libgomp's default active wait (GOMP_SPINCOUNT 300000) spins
    them 1.4-6 ms (the least on a busy machine), OMP_WAIT_POLICY=active the whole 50 ms. Bound 0.5 ms. In a fresh interpreter with 2 numba threads
    (libgomp reads its settings once, when numba first loads it) and neither setting in the
    environment (urdf2links/__init__.py then asks for passive waiting)."""
    import os
    import subprocess
    import sys

    env = {k: v for k, v in os.environ.items() if k not in ("OMP_WAIT_POLICY", "GOMP_SPINCOUNT")}
    env["NUMBA_NUM_THREADS"] = "2"
    out = subprocess.run([sys.executable, "-c", SLEEPING, str(shipped_robots_dir() / "ur5_like.urdf")],
                         capture_output=True, text=True, env=env, timeout=600)
    assert out.returncode == 0, out.stderr[-2000:]
    assert float(out.stdout.split()[-1]) < 0.5, out.stdout

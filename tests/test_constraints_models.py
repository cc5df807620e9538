"""Real MJCF models with equalities or fixed tendons, compared with them enabled on both engines (issue 36).

dm_control's suite (a test dependency, read as files: ``importlib.resources``, never imported as environments)
and gymnasium's MuJoCo models: every file of theirs with an ``<equality>`` or a ``<tendon>`` is loaded with
``[constraints] from_file = true`` and run by ``compare_scene`` against MuJoCo running the file itself (route 2)
with the equalities the project models switched on and the fixed tendons' forces restored. What the project does
not model (tendon equalities) is dropped on both sides and the verdict's scope says so: these tests check that
it does, not only that the numbers agree.

``python -m pytest tests/test_constraints_models.py --figures reports/constraints_models -n 0`` writes the
table that docs/constraints.md shows (reports/constraints_models/constraints_models.md).
"""

from __future__ import annotations

import importlib.resources
import warnings

import mujoco
import numpy as np
import pytest

import urdf2links
from urdf2links.compare.agreement.trajectory import DIVERGENCE_THRESHOLD, compare_scene
from urdf2links.compare.mujoco_side.mujoco_mjcf import mujoco_from_mjcf
from urdf2links.scenes import as_plan
from urdf2links.scenes.scene_read import scene_from_dict

DM = importlib.resources.files("dm_control")
GYM = importlib.resources.files("gymnasium").joinpath("envs", "mujoco", "assets")

#: The coupled joints move from the start, at velocities the couplings allow (MuJoCo starts from the scene's
#: state as given): quadruped's legs (pitch + knee + ankle held by each tendon equality), the hands' thumb and
#: finger together (the tendon equality holds finger - thumb).
_LEGS = {"yaw_front_left": 2.0, "pitch_front_left": 1.0, "knee_front_left": 1.0, "ankle_front_left": -2.0,
         "knee_back_right": 3.0, "ankle_back_right": -3.0, "pitch_front_right": 2.0, "knee_front_right": -1.0,
         "ankle_front_right": -1.0}
_HAND = {"arm_shoulder": 1.0, "arm_elbow": -1.5, "thumb": 2.0, "finger": 2.0}
#: file -> (path, equalities, tendons, [initial] q, [initial] qd). Counts checked by grep
#: of the files and against MuJoCo's compile. Fish's fins start apart so that its tendon spring (fins_sym,
#: stiffness 1e-4) acts from the first step.
MODELS = {
    "dm_control/suite/quadruped.xml": (DM / "suite/quadruped.xml", 4, 12, {}, _LEGS),
    "dm_control/suite/manipulator.xml": (DM / "suite/manipulator.xml", 1, 2, {}, _HAND),
    "dm_control/suite/fish.xml": (DM / "suite/fish.xml", 0, 2, {"finleft_roll": 0.5, "finright_roll": -0.1}, {}),
    "dm_control/suite/point_mass.xml": (DM / "suite/point_mass.xml", 0, 2, {}, {}),
    "dm_control/suite/stacker.xml": (DM / "suite/stacker.xml", 1, 2, {}, _HAND),
    "dm_control/suite/dog.xml": (DM / "suite/dog.xml", 0, 8, {}, {}),
    "dm_control/mujoco/testing/assets/humanoid.xml": (DM / "mujoco/testing/assets/humanoid.xml", 0, 2, {}, {}),
    "gymnasium humanoid.xml": (GYM / "humanoid.xml", 0, 2, {}, {}),
    "gymnasium humanoidstandup.xml": (GYM / "humanoidstandup.xml", 0, 2, {}, {}),
}
#: 0.1 s of each run: the engines' difference is at most 3.3e-9 rad (manipulator and stacker: MuJoCo's soft
#: tendon equality at solref 1e-3 s), far below the comparison's divergence threshold (1e-3).
T_END = 0.1
FIGURE_BOUNDS = {name: f"max |dq| < {DIVERGENCE_THRESHOLD:g} over {T_END:g} s" for name in MODELS}
FIGURE_NOTE = ("Each file run by `compare_scene` with `[constraints] from_file = true` and gravity 9.81, from qpos0 "
               "(fish: fins at 0.5 and -0.1 rad), MuJoCo RK4 at 1e-4 s running the file itself (route 2). "
               "Tendons 'with a force' have a stiffness or damping (or carry an actuator the scene names); the "
               "others carry none on either engine (their actuators act on neither). Equalities 'solved': exact "
               "rows here (E70 on fixed tendons' lengths), MuJoCo's soft constraint at solref 1e-3 s, solimp "
               "0.9999 in its run of the file. The coupled joints start moving (quadruped's legs, the hands' "
               "thumb and finger, the arms), at velocities the couplings allow.")
_RUNS: dict = {}


def _scene(path, q=None, qd=None):
    data = {"robot": {"mjcf": str(path)}, "gravity": {"magnitude": 9.81}, "constraints": {"from_file": True},
            "run": {"t_end": T_END, "samples": 21}}
    initial = {k: dict(v) for k, v in (("q", q), ("qd", qd)) if v}
    if initial:
        data["initial"] = initial
    return scene_from_dict(data, where=f"{path.name}.toml")


def compared(name):
    """The comparison of model ``name`` with its file's constraints on (computed once per module)."""
    if name not in _RUNS:
        path, _, _, q, qd = MODELS[name]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")     # the import's audit findings on these files (notes)
            model = urdf2links.load_mjcf(path)
        _RUNS[name] = model, compare_scene(_scene(path, q, qd), model=model, progress=False, mujoco_fallback=False)
    return _RUNS[name]


@pytest.mark.parametrize("name", list(MODELS))
def test_model_compared_with_its_constraints(name, record_figure):
    """The file's equalities and tendons read (MuJoCo's counts), every equality solved and run by MuJoCo's
    file with it on, the tendons with a force acting on both engines (the others have none to drop); the
    engines within the divergence threshold; nothing cut from the mechanism (verdict.cut)."""
    path, n_eq, n_td, _, _ = MODELS[name]
    m = mujoco.MjModel.from_xml_path(str(path))
    model, cmp = compared(name)
    eqs, tds = model.info.get("equalities", []), model.info.get("tendons", [])
    assert (len(eqs), len(tds)) == (m.neq, m.ntendon) == (n_eq, n_td)      # read: every one of the file's
    assert all(e["supported"] and e["active"] for e in eqs)                  # every one of them solved
    plan = as_plan(cmp.scene, model=model)
    cons = plan.constraints
    modelled = [] if cons is None else [c.name for c in cons.cset.constraints]
    acting = [] if cons is None else [t.name for t in cons.tendons]
    # MuJoCo's run of the file (route 2): the modelled equalities on, the unmodelled off, the acting tendons'
    # stiffness and damping as written; the other tendons carry no force in the file either.
    mf = mujoco_from_mjcf(plan, timestep=1e-4, integrator="RK4")
    for i in range(m.neq):
        nm = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_EQUALITY, i)
        assert bool(mf.model.eq_active0[i]) == (nm in modelled)
    for t in range(m.ntendon):
        nm = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_TENDON, t)
        want = (m.tendon_stiffness[t], m.tendon_damping[t]) if nm in acting else (0.0, 0.0)
        assert (mf.model.tendon_stiffness[t], mf.model.tendon_damping[t]) == want
        if nm not in acting:
            row = next(r for r in tds if r["name"] == nm)
            assert not (row["stiffness"] or row["damping"] or row["limited"] or row["frictionloss"])
    s = cmp.summary()
    assert s["route"].startswith("route 2")
    verdict = s["verdict"]
    assert not verdict["cut"]["cut"], verdict["scope"]       # nothing dropped (a cut one: the next test)
    err = s["trajectory"]["max_abs_error"]
    assert s["trajectory"]["divergence_time"] is None and err < DIVERGENCE_THRESHOLD
    kinds = {}
    for e in eqs:
        kinds.setdefault(e["kind"], []).append(e["supported"])
    record_figure(name, "equalities", ", ".join(f"{len(v)} {k} (solved)" for k, v in kinds.items()) or "none", "{}")
    record_figure(name, "tendons", f"{n_td} fixed, with a force: {', '.join(acting) or 'none'}", "{}")
    stats = cmp.traj.stats.get("constraints")
    if stats is not None and stats["rows"]:
        record_figure(name, "max |lambda|", float(np.abs(stats["lambda"]).max()), "{:.2g}")
    record_figure(name, "max |dq|", err, "{:.1e}")
    record_figure(name, "verdict scope", verdict["scope"], "{}")


def test_what_is_not_modelled_is_named_in_the_scope(tmp_path):
    """manipulator.xml with friction loss on its grasp tendon (tendon friction loss is not modelled; MuJoCo's run
    disables it): the comparison still runs the tendon equality on both engines, and its verdict's scope names the
    tendon it dropped instead of calling the run the whole model. (Issue 45: a tendon limit is modelled now, E87:
    the same tendon limited is the whole model, its scope naming the law; tests/test_loops_default.py.)"""
    spec = mujoco.MjSpec.from_file(str(DM / "suite/manipulator.xml"))
    t = spec.tendon("grasp")
    t.frictionloss = 0.1
    file = tmp_path / "manipulator_friction.xml"
    file.write_text(spec.to_xml())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = urdf2links.load_mjcf(file)
    cmp = compare_scene(_scene(file, None, _HAND), model=model, progress=False, mujoco_fallback=False)
    s = cmp.summary()
    plan = as_plan(_scene(file, None, _HAND), model=model)
    assert [c.name for c in plan.constraints.cset.constraints] == ["coupling"]
    assert s["verdict"]["cut"]["text"] == "open tree of a closed mechanism (0 constraints, 1 tendon dropped)"
    assert s["verdict"]["scope"].startswith(s["verdict"]["cut"]["text"])   # then what is switched off (issue 43)
    assert "not the whole mechanism" in s["verdict"]["text"] and s["trajectory"]["max_abs_error"] < 1e-8


@pytest.mark.parametrize("name, what", [("dm_control/suite/fish.xml", "tendon fins_sym"),
                                        ("dm_control/suite/quadruped.xml", "equality coupling_front_left"),
                                        ("dm_control/suite/manipulator.xml", "equality coupling")])
def test_dropping_a_coupling_on_one_side_is_seen(name, what):
    """What the comparison checks is not a bystander: our run without the fish's tendon spring (fins_sym, E76),
    or without a tendon equality (E70 on the tendons' lengths), is far from MuJoCo's run of the file with it
    (measured 0.17 rad on fish, 0.031 on quadruped, 0.044 on manipulator over 0.1 s), against at most 3.3e-9
    with it on both sides (MuJoCo's soft constraint at solref 1e-3 s; DOP853's tolerance on fish)."""
    from urdf2links.dynamics.constraints import ConstraintSet
    from urdf2links.integration import simulate
    from urdf2links.scenes.constraints import SceneConstraints

    model, cmp = compared(name)
    path, *_, q, qd = MODELS[name]
    plan = as_plan(_scene(path, q, qd), model=model)
    kind, dropped = what.split()
    cons, tendons = plan.constraints.cset.constraints, plan.constraints.tendons
    assert dropped in [c.name for c in cons] + [t.name for t in tendons]
    assert cmp.summary()["trajectory"]["max_abs_error"] < 1e-8
    plan.constraints = SceneConstraints(ConstraintSet(model, [c for c in cons if c.name != dropped]),
                                        tuple(t for t in tendons if t.name != dropped))   # dropped on our side
    run = simulate(plan, progress=False)
    assert np.allclose(run.t, cmp.t)
    assert np.abs(run.q - cmp.q_mujoco).max() > 10 * DIVERGENCE_THRESHOLD


def test_tendon_equality_against_the_file_in_mujoco(tmp_path):
    """A tendon equality of two fixed tendons (E70 on their lengths l = c . q, E76): manipulator.xml's coupling
    made to follow its grasp tendon by a cubic polycoef, thumb and finger given a ``ref`` (so that ``qpos0`` and
    the lengths there, MuJoCo's ``tendon_length0``, are not 0). Our Phi and Phi_q against MuJoCo's efc_pos and
    efc_J of that file at seeded states: equal to rounding (measured 1e-16)."""
    from urdf2links.compare.mujoco_side.mujoco_constraints import equality_rows

    spec = mujoco.MjSpec.from_file(str(DM / "suite/manipulator.xml"))
    (e,) = spec.equalities
    e.name2, e.data[:5] = "grasp", [0.01, -0.4, 0.3, 0.2, 0.0]
    spec.joint("thumb").ref, spec.joint("finger").ref = 0.3, -0.2
    file = tmp_path / "manipulator_cubic.xml"
    file.write_text(spec.to_xml())
    m = mujoco.MjModel.from_xml_path(str(file))
    m.opt.disableflags &= ~int(mujoco.mjtDisableBit.mjDSBL_EQUALITY)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = urdf2links.load_mjcf(file)
    plan = as_plan(_scene(file), model=model)
    (c,) = plan.constraints.cset.constraints
    assert c.kind == "tendon" and c.coef2 is not None
    adr = {j.coordinates[0]: j.qposadr for j in model.info["mujoco"].joints if j.kind in ("hinge", "slide")}
    so = [(r.get("sign", 1.0), r.get("offset", 0.0)) for r in model.info["coordinates"]]
    assert m.tendon_length0[0] != 0.0 and m.tendon_length0[1] != 0.0
    rng = np.random.default_rng(3)
    d = mujoco.MjData(m)
    for _ in range(4):
        q = rng.uniform(-0.6, 0.6, model.n)
        d.qpos[:] = m.qpos0
        d.qpos[[adr[i] for i in range(model.n)]] = [(x - o) / s for x, (s, o) in zip(q, so)]
        mujoco.mj_forward(m, d)
        rows = equality_rows(m, d, 0)
        T = plan.constraints.cset.terms(q)
        J = np.asarray(d.efc_J).reshape(-1, m.nv)[rows][:, [m.jnt_dofadr[m.jnt_qposadr.tolist().index(adr[i])]
                                                            for i in range(model.n)]]
        assert abs(float(d.efc_pos[rows[0]]) - T.phi[0]) < 1e-14
        assert np.abs(J * [s for s, _ in so] - T.J).max() < 1e-14     # dq = s dqpos


def test_docs_table_is_the_recorded_figures():
    """docs/constraints.md's table of these models is the committed report's figures as rendered by
    ``python -m urdf2links.compare.reports.models_table`` (not typed by hand; regenerate both together)."""
    import json
    from pathlib import Path

    from urdf2links.compare.reports.models_table import BEGIN, END, render

    root = Path(__file__).resolve().parents[1]
    data = json.loads((root / "reports/constraints_models/constraints_models.json").read_text())
    assert {r["case"] for r in data["rows"]} == set(MODELS) and not any(r["failed"] for r in data["rows"])
    doc = (root / "docs/constraints.md").read_text()
    assert doc.split(BEGIN, 1)[1].split(END, 1)[0].strip() == render(data).strip()


@pytest.mark.parametrize("name", ["dm_control/suite/quadruped.xml", "dm_control/suite/manipulator.xml"])
def test_tendon_equalities_in_route_1(name):
    """Route 1 (the project's tree as MJCF) writes each tendon equality as two fixed tendons and a ``<tendon>``
    equality: at states of the run our Phi_q equals its efc_J rows to rounding and lambda its efc_force to
    MuJoCo's regularizer at solimp 0.9999 (measured 1e-4 relative on both; bound 5e-3 as the loops' test)."""
    from urdf2links.compare.agreement.constraint_agreement import constraint_terms, states_of
    from urdf2links.compare.mujoco_side.mjcf import mjcf_from_scene
    from urdf2links.compare.mujoco_side.mujoco_constraints import with_constraints

    model, cmp = compared(name)
    plan = as_plan(cmp.scene, model=model)
    mj = with_constraints(mjcf_from_scene(plan.scene, model), plan.constraints)
    t = constraint_terms(plan, mj, states_of(cmp.traj))
    assert t["jacobian"]["max_abs"] < 1e-12 * max(1.0, t["jacobian"]["scale"])
    assert t["force"]["max_abs"] < 5e-3 * t["force"]["scale"]

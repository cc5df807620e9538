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
from urdf2links.scenes.scene import scene_from_dict

DM = importlib.resources.files("dm_control")
GYM = importlib.resources.files("gymnasium").joinpath("envs", "mujoco", "assets")

#: file -> (equalities, tendons, equalities not modelled (tendon equalities), [initial] q). Counts checked by grep
#: of the files and against MuJoCo's compile. Fish's fins start apart so that its tendon spring (fins_sym,
#: stiffness 1e-4) acts from the first step.
MODELS = {
    "dm_control/suite/quadruped.xml": (DM / "suite/quadruped.xml", 4, 12, 4, {}),
    "dm_control/suite/manipulator.xml": (DM / "suite/manipulator.xml", 1, 2, 1, {}),
    "dm_control/suite/fish.xml": (DM / "suite/fish.xml", 0, 2, 0, {"finleft_roll": 0.5, "finright_roll": -0.1}),
    "dm_control/suite/point_mass.xml": (DM / "suite/point_mass.xml", 0, 2, 0, {}),
    "dm_control/suite/stacker.xml": (DM / "suite/stacker.xml", 1, 2, 1, {}),
    "dm_control/suite/dog.xml": (DM / "suite/dog.xml", 0, 8, 0, {}),
    "dm_control/mujoco/testing/assets/humanoid.xml": (DM / "mujoco/testing/assets/humanoid.xml", 0, 2, 0, {}),
    "gymnasium humanoid.xml": (GYM / "humanoid.xml", 0, 2, 0, {}),
    "gymnasium humanoidstandup.xml": (GYM / "humanoidstandup.xml", 0, 2, 0, {}),
}
#: 0.1 s of each run: the engines' difference is at rounding (measured at most 3.3e-10 rad, on stacker) and
#: far below the comparison's divergence threshold (1e-3).
T_END = 0.1
FIGURE_BOUNDS = {name: f"max |dq| < {DIVERGENCE_THRESHOLD:g} over {T_END:g} s" for name in MODELS}
FIGURE_NOTE = ("Each file run by `compare_scene` with `[constraints] from_file = true` and gravity 9.81, from qpos0 "
               "(fish: fins at 0.5 and -0.1 rad), MuJoCo RK4 at 1e-4 s running the file itself (route 2). "
               "'acting' tendons have a stiffness or damping, or carry an actuator the scene names; the other "
               "tendons carry no force on either engine.")
_RUNS: dict = {}


def _scene(path, q=None):
    data = {"robot": {"mjcf": str(path)}, "gravity": {"magnitude": 9.81}, "constraints": {"from_file": True},
            "run": {"t_end": T_END, "samples": 21}}
    if q:
        data["initial"] = {"q": dict(q)}
    return scene_from_dict(data, where=f"{path.name}.toml")


def compared(name):
    """The comparison of model ``name`` with its file's constraints on (computed once per module)."""
    if name not in _RUNS:
        path, _, _, _, q = MODELS[name]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")     # the import's audit findings on these files (notes)
            model = urdf2links.load_mjcf(path)
        _RUNS[name] = model, compare_scene(_scene(path, q), model=model, progress=False, mujoco_fallback=False)
    return _RUNS[name]


@pytest.mark.parametrize("name", list(MODELS))
def test_model_compared_with_its_constraints(name, record_figure):
    path, n_eq, n_td, n_cut, _ = MODELS[name]
    m = mujoco.MjModel.from_xml_path(str(path))
    model, cmp = compared(name)
    eqs, tds = model.info.get("equalities", []), model.info.get("tendons", [])
    assert (len(eqs), len(tds)) == (m.neq, m.ntendon) == (n_eq, n_td)      # read: every one of the file's
    unmodelled = [e["name"] for e in eqs if not e["supported"]]
    assert len(unmodelled) == n_cut and all(e["kind"] == "tendon" for e in eqs if not e["supported"])
    plan = cmp.plan if hasattr(cmp, "plan") else as_plan(cmp.scene, model=model)
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
    # The scope states exactly what was cut: the unmodelled equalities, nothing else.
    if n_cut:
        assert f"({n_cut} constraint{'s' * (n_cut != 1)}, 0 tendons dropped)" in verdict["scope"]
        assert "not the whole mechanism" in verdict["text"]
    else:
        assert not verdict["cut"]["cut"], verdict["scope"]
    err = s["trajectory"]["max_abs_error"]
    assert s["trajectory"]["divergence_time"] is None and err < DIVERGENCE_THRESHOLD
    record_figure(name, "equalities", f"{n_eq}" + (f" ({n_cut} tendon equalities: not modelled, dropped on both "
                                                   "engines)" if n_cut else ""), "{}")
    record_figure(name, "tendons", f"{n_td} fixed, acting: {', '.join(acting) or 'none'}", "{}")
    record_figure(name, "max |dq|", err, "{:.1e}")
    record_figure(name, "verdict scope", verdict["scope"], "{}")


def test_dropping_a_tendon_on_one_side_is_seen():
    """The fish's tendon spring (fins_sym, E76) is what the comparison checks, not a bystander: our run without
    it is 0.17 rad away from MuJoCo's run of the file with it (measured; the fins are light), against 4.4e-11
    with it on both sides (the constrained path's DOP853 at the scene's default tolerances)."""
    from urdf2links.integration import simulate
    from urdf2links.scenes.constraints import SceneConstraints

    name = "dm_control/suite/fish.xml"
    model, cmp = compared(name)
    path, *_, q = MODELS[name]
    plan = as_plan(_scene(path, q), model=model)
    assert [t.name for t in plan.constraints.tendons] == ["fins_sym"]
    assert cmp.summary()["trajectory"]["max_abs_error"] < 1e-9
    plan.constraints = SceneConstraints(plan.constraints.cset, ())        # the tendon dropped on our side
    dropped = simulate(plan, progress=False)
    assert np.allclose(dropped.t, cmp.t)
    assert np.abs(dropped.q - cmp.q_mujoco).max() > 100 * DIVERGENCE_THRESHOLD

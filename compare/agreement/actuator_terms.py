"""The actuators' generalized forces at identical states: the project's law (E55) against MuJoCo's ``qfrc_actuator``.

For a scene that names actuators, each route's MuJoCo model carries them (route 1 writes them into its
MJCF, route 2 adds them to MuJoCo's URDF import, an MJCF file keeps its own and gets the scene's added):
at seeded states ``(t, q, q')`` the project's ``plan.actuator_forces(t, q, q')``
(:mod:`urdf2links.scenes.actuators`) is compared with MuJoCo's ``qfrc_actuator`` after ``mj_forward`` with
``d.ctrl`` set to the controls at ``t`` (MuJoCo clamps and applies its own law). States: ``q`` uniform in
[-1, 1] around the model's ``q0`` (wide enough to cross ctrlrange and forcerange clamps), ``q'`` standard
normal, ``t`` uniform over the run. The figure is ``max |ours - MuJoCo| / max(max |MuJoCo|, 1 N)``.

Issue 43: the file's actuators on fixed tendons (``[constraints] from_file``; their law on the tendon's length,
E76) are compared too, on both routes, and every actuator's scalar force (MuJoCo's ``actuator_force``: the
law's ``f`` after both clamps) beside the generalized forces: ``max_rel_error_actuator`` covers both.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from urdf2links.compilation import clock  # durations without numba's compilation

from ..mujoco_side.tendon_controls import tendon_actuator_ids, tendon_actuators

__all__ = ["actuator_terms", "route1_actuators", "route2_actuators", "file_actuators", "merged"]


def actuator_terms(plan, m, set_state, to_project, actuator_ids, *, label: str, states: int = 8,
                   seed: int = 0) -> dict:
    """The comparison (module doc) on MuJoCo model ``m``: ``set_state(d, q, qd)`` writes a project state,
    ``to_project(qfrc)`` maps MuJoCo's generalized forces to the project's coordinates, ``actuator_ids[k]``
    is MuJoCo's actuator of the plan's ``k``-th (-1: not a MuJoCo actuator, left out of both sides); the
    plan's actuators on fixed tendons are ``m``'s of the same name. A JSON-ready dict."""
    from urdf2links.scenes.actuators import actuator_forces

    start = clock()
    acts = [a for a, i in zip(plan.actuator_set.actuators, actuator_ids) if i >= 0]
    joint_ids = [i for i in actuator_ids if i >= 0]
    tendons, tendon_ids = tendon_actuators(plan), tendon_actuator_ids(plan, m)     # issue 43
    rng = np.random.default_rng(seed)
    d = mujoco.MjData(m)
    q0 = plan.model.info.get("q0")
    q0 = np.zeros(plan.n) if q0 is None else np.asarray(q0, float)
    worst, worst_f, per_state = 0.0, 0.0, []
    for _ in range(states):
        t = float(rng.uniform(0.0, plan.scene.run.t_end))
        q, qd = q0 + rng.uniform(-1.0, 1.0, plan.n), rng.standard_normal(plan.n)
        d.ctrl[:] = 0.0
        set_state(d, q, qd)
        ctrl = plan.ctrl(t)
        for k, a in enumerate(actuator_ids):
            if a >= 0:
                d.ctrl[m.actuator_ctrladr[a]] = ctrl[k]
        for ta, a in zip(tendons, tendon_ids):
            d.ctrl[m.actuator_ctrladr[a]] = float(ta.actuator.ctrl(t))
        mujoco.mj_forward(m, d)
        theirs = np.asarray(to_project(np.array(d.qfrc_actuator)), float)
        ours = actuator_forces(acts, t, q, qd, plan.n) + sum((ta.generalized(t, q, qd) for ta in tendons), np.zeros(plan.n))
        f_ours = [a.force(t, float(q[a.index]), float(qd[a.index])) for a in acts] + [ta.force(t, q, qd) for ta in tendons]
        f_theirs = np.asarray(d.actuator_force)[joint_ids + tendon_ids]
        scale = max(float(np.abs(theirs).max()) if theirs.size else 0.0, 1.0)
        err = float(np.abs(ours - theirs).max()) / scale if theirs.size else 0.0
        err_f = (float(np.abs(np.asarray(f_ours) - f_theirs).max()) / max(float(np.abs(f_theirs).max()), 1.0)
                 if f_theirs.size else 0.0)
        per_state.append(max(err, err_f))
        worst, worst_f = max(worst, err), max(worst_f, err_f)
    left = len(actuator_ids) - len(acts)
    return {"label": label, "max_rel_error_actuator": max(worst, worst_f), "max_rel_error_qfrc_actuator": worst,
            "max_rel_error_actuator_force": worst_f, "states": states, "seed": seed,
            "actuators": len(acts) + len(tendons), "tendon_actuators": len(tendons), "not_mujoco_actuators": left,
            "per_state": per_state, "wall_time_s": clock() - start,
            "mapping": "the project's actuator law (E55; on a fixed tendon's length, E76) vs MuJoCo's qfrc_actuator and "
                       "actuator_force with d.ctrl at the same t"}


def route1_actuators(plan, mj, *, states: int = 8, seed: int = 0) -> dict:
    """Route 1: the project's tree as MJCF with the scene's actuators written as ``general`` (in plan order)."""
    return actuator_terms(plan, mj.model, lambda d, q, qd: mj.set_state(d, q, qd), lambda f: f[mj.dof_index],
                          list(range(len(mj.actuators))), label="route 1", states=states, seed=seed)


def route2_actuators(plan, robot, *, states: int = 8, seed: int = 0) -> dict:
    """Route 2 for a URDF: MuJoCo's own import of ``robot`` with the scene's actuators added on its joints
    (coordinates by joint name). A file MuJoCo refuses is skipped, its reason recorded."""
    from ..mujoco_side.mujoco_urdf import MujocoRefused, mujoco_from_urdf

    acts = plan.actuator_set.actuators
    try:
        mu = mujoco_from_urdf(robot, gravity=(0.0, 0.0, 0.0), actuators=acts)
    except (MujocoRefused, ValueError, NotImplementedError) as err:
        return {"label": "route 2", "skipped": f"MuJoCo's URDF import: {getattr(err, 'reason', err)}"}
    names = plan.model.coordinate_names
    missing = [nm for nm in names if nm not in mu.dof_of_joint]
    if missing:
        return {"label": "route 2", "skipped": f"coordinates without a MuJoCo hinge/slide joint: {missing[:6]}"}
    qadr = [mu.qpos_of_joint[nm] for nm in names]
    dadr = [mu.dof_of_joint[nm] for nm in names]

    def set_state(d, q, qd):
        d.qpos[qadr], d.qvel[dadr] = q, qd

    ids = [mujoco.mj_name2id(mu.model, mujoco.mjtObj.mjOBJ_ACTUATOR, a.name) for a in acts]
    return actuator_terms(plan, mu.model, set_state, lambda f: f[dadr], ids, label="route 2", states=states, seed=seed)


def file_actuators(plan, mf, *, states: int = 8, seed: int = 0) -> dict:
    """Route 2 for an MJCF file: MuJoCo's run of the file (its actuators the scene names, the scene's own
    added), through the state map: ``tau = J^T qfrc_actuator`` (E50)."""
    if not any(i >= 0 for i in mf.actuator_ids) and not mf.tendon_actuator_ids:
        return {"label": "route 2", "skipped": "no MuJoCo actuator in the file's run (see its notes)"}
    qmap = plan.model.info["mujoco"]
    last = {}

    def set_state(d, q, qd):
        d.qpos[:], d.qvel[:] = qmap.to_mujoco(q, qd)
        last["q"] = q

    return actuator_terms(plan, mf.model, set_state, lambda f: qmap.jacobian(last["q"]).T @ f, list(mf.actuator_ids),
                          label="route 2", states=states, seed=seed)


def merged(route: dict, act: dict) -> dict:
    """``route``'s terms with the actuators' figure added (``max_rel_error`` then covers it too)."""
    out = dict(route)
    out["actuators"] = act
    if "max_rel_error_actuator" in act:
        out["max_rel_error_actuator"] = act["max_rel_error_actuator"]
        if "max_rel_error" in out and out["max_rel_error"] is not None and math.isfinite(out["max_rel_error"]):
            out["max_rel_error"] = max(out["max_rel_error"], act["max_rel_error_actuator"])
    return out

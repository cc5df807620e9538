"""Actuators on an MJCF file's fixed tendons in MuJoCo's runs: both engines get the same controls (issue 43).

A scene that names a file's actuator whose transmission is a fixed tendon (``[[actuator]] name =
"fingers_actuator"; ctrl = ...`` with ``[constraints] from_file = true``) makes that actuator act in the
project's run through its tendon (docs/equations.md (E76): MuJoCo's law (E55) on the tendon's length
``l = c . q``, its force ``gear f`` on the tendon, ``c gear f`` on the coordinates;
:mod:`urdf2links.scenes.file_constraints`). It is not one of the plan's joint actuators
(``plan.actuator_set``), so the compiled control callback's table of controls
(:mod:`urdf2links.compare.mujoco_side.mujoco_inputs`) does not hold it. Here it is added to that table:

* :func:`tendon_actuators` lists the plan's actuators on fixed tendons, each with its tendon;
* :func:`add_tendon_controls` appends their ``ctrl(t)`` (the same time functions, compiled as the project's
  right-hand side compiles its own: :func:`~urdf2links.scenes.scene_arrays.function_data`) to the
  callback's function table, and MuJoCo's ``ctrl`` address of each actuator (found by its name in the
  model: the file's own on route 2, the one :func:`~urdf2links.compare.mujoco_side.mujoco_constraints.with_constraints`
  writes on route 1) to its list of controls. The callback writes ``d->ctrl`` at every stage; MuJoCo then
  clamps it and applies the actuator's own law, so no new compiled code is needed.

An actuator MuJoCo's model does not hold under that name is an error naming it (it would otherwise act on one
engine only). Site transmissions and spatial tendons are not modelled: the plan refuses a scene that names
such an actuator (:func:`urdf2links.scenes.actuators.resolve_actuators`), on both engines.

Issue 45: a ``limited`` fixed tendon gets the project's limit law (E87, :mod:`urdf2links.scenes.tendons`) on both
engines. MuJoCo's own soft limit is disabled for the run (``mjDSBL_LIMIT``) and the law is applied instead as a
second fixed tendon on the same joints (:func:`add_limit_tendons`): a spring whose dead band is the range is the
law exactly, evaluated by MuJoCo's own compiled passive forces at every stage (no control, no callback code).
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from urdf2links.scenes.scene_arrays import function_data
from urdf2links.scenes.tendons import LIMIT_SUFFIX

__all__ = ["TendonActuator", "tendon_actuators", "tendon_actuator_ids", "add_tendon_controls", "limit_tendons",
           "add_limit_tendons"]


@dataclass(frozen=True)
class TendonActuator:
    """One of the plan's actuators on a fixed tendon: ``actuator`` (its law, E55, and ``ctrl``) and
    ``tendon`` (:class:`~urdf2links.scenes.tendons.FixedTendon`: its length ``c . q``)."""

    actuator: object
    tendon: object

    @property
    def name(self) -> str:
        return self.actuator.name

    def force(self, t, q, qd) -> float:
        """MuJoCo's ``actuator_force``: the scalar ``f`` of the law on ``(gear l, gear l')`` (E55, E76)."""
        return self.actuator.force(t, self.tendon.length(q), float(self.tendon.coef @ qd))

    def generalized(self, t, q, qd) -> np.ndarray:
        """Its part of ``qfrc_actuator`` in the model's coordinates: ``c gear f`` (E76)."""
        return self.tendon.coef * (self.actuator.gear * self.force(t, q, qd))


def tendon_actuators(plan) -> tuple[TendonActuator, ...]:
    """The plan's actuators on fixed tendons, tendon by tendon (empty without ``[constraints] from_file``)."""
    cons = getattr(plan, "constraints", None)
    if cons is None:
        return ()
    return tuple(TendonActuator(a, td) for td in cons.tendons for a in td.actuators)


def tendon_actuator_ids(plan, m) -> list[int]:
    """MuJoCo's actuator id of each of :func:`tendon_actuators` in model ``m``, by name; a ValueError names
    one that ``m`` does not hold (its control would reach one engine only)."""
    ids = []
    for ta in tendon_actuators(plan):
        k = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, ta.name)
        if k < 0:
            raise ValueError(f"actuator {ta.name!r} (on tendon {ta.tendon.name!r}) acts in the project's run but "
                             "MuJoCo's model has no actuator of that name: its control would reach one engine only")
        if int(m.actuator_trntype[k]) != int(mujoco.mjtTrn.mjTRN_TENDON):
            raise ValueError(f"actuator {ta.name!r}: MuJoCo's model drives no tendon with it (transmission "
                             f"{mujoco.mjtTrn(int(m.actuator_trntype[k])).name}), the project's run drives tendon "
                             f"{ta.tendon.name!r}")
        ids.append(k)
    return ids


def add_tendon_controls(plan, m, ints: dict, floats: dict) -> list[int]:
    """The tendon actuators' controls added to the control callback's sections (``ints``: ``fn_kind``,
    ``fn_ptr``, ``act_fn``, ``act_ctrl``; ``floats``: ``fn_data``; replaced by extended copies): each
    actuator's ``ctrl`` function appended to the function table, its MuJoCo ``ctrl`` address to the
    controls the callback writes. Returns MuJoCo's ids of those actuators (module doc)."""
    tas = tendon_actuators(plan)
    ids = tendon_actuator_ids(plan, m)
    if not tas:
        return ids
    kind = list(np.asarray(ints["fn_kind"], np.int64))
    ptr = list(np.asarray(ints["fn_ptr"], np.int64)) or [0]
    data = [np.asarray(floats["fn_data"], float)]
    fn = list(np.asarray(ints["act_fn"], np.int64))
    ctrl = list(np.asarray(ints["act_ctrl"], np.int64))
    for ta, k in zip(tas, ids):
        kd, values = function_data(ta.actuator.ctrl)
        fn.append(len(kind))
        kind.append(kd)
        data.append(np.asarray(values, float))
        ptr.append(ptr[-1] + len(values))
        ctrl.append(int(m.actuator_ctrladr[k]))
    ints.update({"fn_kind": kind, "fn_ptr": ptr, "act_fn": fn, "act_ctrl": ctrl})
    floats["fn_data"] = np.concatenate(data)
    return ids


# -- issue 45: tendon limits, the project's law (E87) on MuJoCo's side ------------------------------------------


def limit_tendons(plan) -> tuple:
    """The plan's limit laws (E87): its tendons named ``<tendon>__limit``
    (:func:`urdf2links.scenes.tendons.limit_tendon`), each a one-sided spring with the range as its dead band."""
    cons = getattr(plan, "constraints", None)
    return () if cons is None else tuple(td for td in cons.tendons if td.name.endswith(LIMIT_SUFFIX))


def add_limit_tendons(spec, plan, joints_of: dict) -> list[str]:
    """Each of :func:`limit_tendons` added to MuJoCo's ``MjSpec`` of the file as a fixed tendon on the limited
    tendon's own joints and coefficients (``joints_of``: ``{tendon: [(joint, coef)]}``, the file's), with the law's
    stiffness and the file's range as its spring length (MuJoCo's length, ``range`` as written): MuJoCo's passive
    tendon spring with a dead band is the law exactly. Returns their names."""
    names = []
    for td in limit_tendons(plan):
        base = td.name.removesuffix(LIMIT_SUFFIX)
        lo, hi = joints_of[base]["range"]
        t = spec.add_tendon(name=td.name, stiffness=td.stiffness, damping=0.0, springlength=[lo, hi])
        for joint, coef in joints_of[base]["joints"]:
            t.wrap_joint(joint, coef)
        names.append(td.name)
    return names

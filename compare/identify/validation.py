"""The held-out run simulated with the description and with the identified model, on both engines.

Each model is driven, step for step, by the torque OTHER was given on the held-out seed (recorded at every step)
plus a PD pull toward OTHER's recorded state, ``tau_OTHER(t) + Kp (q_OTHER - q) + Kd (q'_OTHER - q')`` (the same
gains for every model and engine, :data:`PULL_HZ`), so that a model that moves as OTHER does stays on its
recording and one that does not drifts from it, boundedly. The engines:

- MuJoCo: the model as route 1 writes it (:func:`urdf2links.compare.mujoco_side.mjcf.mjcf_from_model`: the same
  frames, H, armature) with the joints' damping and Coulomb friction as ``damping`` and ``frictionloss``, stepped
  as OTHER was (semi-implicit Euler, 1 ms); MuJoCo refuses a body whose inertia is not positive definite: then
  that run is not made and the result says why;
- urdf2links: the project's own simulation (:func:`urdf2links.integration.simulate.simulate`) of a scene built in Python
  (:func:`held_out_scene`): the same law as one MuJoCo ``general`` actuator per coordinate (E55) whose control
  is a cubic spline through OTHER's recorded steps, the joints' damping as the scene's dampers, gravity, the
  project's integrator at the scenes' tolerances (rtol 1e-10, atol 1e-12). The scenes do not model Coulomb
  joint friction: the identified friction acts along OTHER's recorded velocity, in the control
  (``-f q'_OTHER / sqrt(q'_OTHER^2 + v_s^2)``, v_s = :data:`SLIP`). OTHER was stepped by MuJoCo (semi-implicit
  Euler, 1 ms, the torque held over each step): this run is the continuous motion, so even the exact model
  differs from the recording by that discretisation.

The error of a run is ``max_t |q(t) - q_OTHER(t)|`` per coordinate against OTHER's held-out recording.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np
from lxml import etree

from ..mujoco_side.mjcf import mjcf_from_model
from .recording import DT, OtherEngine, Pair

__all__ = ["ValidationRun", "validate", "SLIP", "held_out_scene", "RTOL", "ATOL"]

#: The PD pull toward OTHER's recorded state (Hz, critically damped, gains from the description's A at the start).
PULL_HZ = 2.0
#: A negative fitted armature above -this (kg m^2) is a zero one's rounding.
ARMATURE_ROUNDING = 1e-8
#: The regularisation speed of the Coulomb law in the urdf2links run (rad/s): the scenes' contact default.
SLIP = 1e-2
#: The project's integrator's tolerances for the held-out run (the scenes' defaults: tight).
RTOL, ATOL = 1e-10, 1e-12


@dataclass(frozen=True)
class ValidationRun:
    """One model on one engine: ``label`` (description / identified), ``engine``, ``error`` (n,) rad or m
    (None: not run, ``note`` says why)."""

    label: str
    engine: str
    error: np.ndarray | None
    note: str = ""

    def to_json(self) -> dict:
        return {"model": self.label, "engine": self.engine, "note": self.note,
                "max_error": None if self.error is None else self.error.tolist()}


def _mujoco_engine(pair: Pair, model, joints: dict) -> OtherEngine:
    mm = mjcf_from_model(model, gravity=model.gravity_vector)
    root = etree.fromstring(mm.xml.encode())
    option = root.find("option")
    option.remove(option.find("flag"))
    for j in root.find("worldbody").iter("joint"):
        damping, friction = joints.get(j.get("name"), (0.0, 0.0))
        j.set("damping", repr(float(max(damping, 0.0))))
        j.set("frictionloss", repr(float(max(friction, 0.0))))
    m = mujoco.MjModel.from_xml_string(etree.tostring(root, encoding="unicode"))
    m.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT) | int(mujoco.mjtDisableBit.mjDSBL_LIMIT)
    m.opt.integrator = int(mujoco.mjtIntegrator.mjINT_EULER)
    m.opt.timestep = DT
    n = len(pair.names)
    return OtherEngine(pair.engine.path, m, "route 1", np.asarray(mm.qpos_index), np.asarray(mm.dof_index),
                       np.ones(n), np.zeros(n))


def _law(held, i, q, qd, kp, kd) -> np.ndarray:
    """OTHER's recorded torque at step ``i`` and a PD pull toward its recorded state (module doc)."""
    return held.tau[i] + kp * (held.q[i] - q) + kd * (held.qd[i] - qd)


def held_out_scene(model, joints: dict, names, held, kp, kd, *, robot=None):
    """The held-out run as a project scene (:class:`urdf2links.scenes.scene.Scene`, built in Python; module doc):
    one MuJoCo ``general`` actuator per coordinate (E55, gain 1, bias ``(0, -kp, -kd)``) whose control is the
    cubic spline through ``tau_OTHER + kp q_OTHER + kd q'_OTHER`` at OTHER's recorded steps, so that its force is
    the law of :func:`_law`; the joints' damping as the scene's dampers (E16); the Coulomb friction, which the
    scenes do not model, along OTHER's recorded velocity in the control (``-f q'_OTHER / sqrt(q'_OTHER^2 +
    v_s^2)``, v_s = :data:`SLIP`: the servo keeps the model on that velocity); gravity the model's; OTHER's first
    recorded state as the start; the scene's tolerances (rtol 1e-10, atol 1e-12), one sample per recorded step."""
    from urdf2links.scenes.actuators import ActuatorSpec
    from urdf2links.scenes.functions import Table
    from urdf2links.scenes.scene import RunSettings, Scene, Spring

    times = tuple(float(x) for x in held.t)
    specs, springs = [], []
    for k, c in enumerate(names):
        b, f = joints.get(c, (0.0, 0.0))
        v = held.qd[:, k]
        ctrl = held.tau[:, k] + kp[k] * held.q[:, k] + kd[k] * v - f * v / np.sqrt(v * v + SLIP * SLIP)
        specs.append(ActuatorSpec(f"held-out:{c}", c, "general", Table(times, tuple(float(x) for x in ctrl)),
                                  gain=1.0, bias=(0.0, -float(kp[k]), -float(kd[k]))))
        if b:
            springs.append(Spring(c, damping=float(b)))
    return Scene(name="held-out", path=None, robot=Path(robot or model.source or "."), load_options={}, gravity=model.gravity_vector,
                 actuators=tuple(specs), springs=tuple(springs),
                 q0={c: float(held.q[0, k]) for k, c in enumerate(names)},
                 qd0={c: float(held.qd[0, k]) for k, c in enumerate(names)},
                 run=RunSettings(t_end=times[-1], rtol=RTOL, atol=ATOL, samples=len(times)))


def _project_run(model, joints, names, held, kp, kd) -> np.ndarray:
    """q (T, n) of urdf2links' model in the held-out scene (:func:`held_out_scene`), simulated by the project
    (:func:`urdf2links.integration.simulate.simulate`), sampled at OTHER's recorded times."""
    from urdf2links.integration.simulate import simulate

    scene = held_out_scene(model, joints, names, held, kp, kd)
    tr = simulate(scene, model=model, progress=False)
    if not np.allclose(tr.t, held.t, rtol=0.0, atol=1e-9):
        raise ValueError(f"{model.name}: the urdf2links run's samples are not OTHER's recorded times")
    idx = [list(tr.coordinate_names).index(c) for c in names]
    return np.asarray(tr.q)[:, idx]


def _mujoco_run(e: OtherEngine, held, kp, kd) -> np.ndarray:
    """q (T, n) of MuJoCo's model driven by the law, as OTHER was stepped (module doc)."""
    m = e.model
    d = mujoco.MjData(m)
    d.qpos[e.qpos], d.qvel[e.dof] = held.q[0], held.qd[0]
    out = np.empty_like(held.q)
    for i in range(len(held.t)):
        mujoco.mj_step1(m, d)
        q, qd = d.qpos[e.qpos].copy(), d.qvel[e.dof].copy()
        out[i] = q
        d.qfrc_applied[e.dof] = _law(held, i, q, qd, kp, kd)
        mujoco.mj_step2(m, d)
    return out


def validate(ident, values: dict) -> list[ValidationRun]:
    """Both engines, each model of ``values`` ({label: pi (p,)}), on the held-out seed (module doc)."""
    pair, held, params = ident.pair, ident.held_out, ident.fit.parameters
    wn = 2 * np.pi * PULL_HZ
    m0 = np.diag(pair.built.model.mass_matrix(held.q[0]))
    kp, kd = m0 * wn * wn, 2 * m0 * wn
    runs = []
    for label, v in values.items():
        arm = np.array([k == "armature" for k in params.kind])
        v = np.where(arm & (v < 0) & (v > -ARMATURE_ROUNDING), 0.0, v)     # an armature of 0 fitted as -1e-12
        if np.any(v[arm] < 0):
            bad = [params.names[i] for i in np.flatnonzero(arm & (v < 0))]
            runs += [ValidationRun(label, e, None, f"negative armature {bad}: no tree holds it")
                     for e in ("urdf2links", "MuJoCo")]
            continue
        model = params.to_model(v)
        jv = params.joint_values(v)
        joints = {c: (jv.get("damping", {}).get(c, 0.0), jv.get("friction", {}).get(c, 0.0)) for c in pair.names}
        try:
            q = _project_run(model, joints, pair.names, held, kp, kd)
            runs.append(ValidationRun(label, "urdf2links", np.max(np.abs(q - held.q), axis=0),
                                      f"the project's simulation of the held-out scene (rtol {RTOL:g}), continuous "
                                      f"in time, against OTHER's recording stepped by MuJoCo ({DT:g} s Euler)"))
        except (ValueError, np.linalg.LinAlgError) as err:
            runs.append(ValidationRun(label, "urdf2links", None, str(err)))
        try:
            engine = _mujoco_engine(pair, model, joints)
        except ValueError as err:
            runs.append(ValidationRun(label, "MuJoCo", None, f"MuJoCo refuses the model: {str(err).strip()[:200]}"))
            continue
        q = _mujoco_run(engine, held, kp, kd)
        runs.append(ValidationRun(label, "MuJoCo", np.max(np.abs(q - held.q), axis=0)))
    return runs

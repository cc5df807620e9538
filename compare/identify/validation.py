"""The held-out run simulated with the description and with the identified model, on both engines.

Each model is driven, step for step, by the torque OTHER was given on the held-out seed (recorded at every step)
plus a PD pull toward OTHER's recorded state, ``tau_OTHER(t) + Kp (q_OTHER - q) + Kd (q'_OTHER - q')`` (the same
gains for every model and engine, :data:`PULL_HZ`), so that a model that moves as OTHER does stays on its
recording and one that does not drifts from it, boundedly. The engines:

- MuJoCo: the model as route 1 writes it (:func:`urdf2links.compare.mujoco_side.mjcf.mjcf_from_model`: the same
  frames, H, armature) with the joints' damping and Coulomb friction as ``damping`` and ``frictionloss``, stepped
  as OTHER was (semi-implicit Euler, 1 ms); MuJoCo refuses a body whose inertia is not positive definite: then
  that run is not made and the result says why;
- urdf2links: the same servo on :meth:`Model.forward_dynamics` (the trace method's equations), the joints'
  damping ``-b q'`` and Coulomb friction ``-f q' / sqrt(q'^2 + v_s^2)`` (v_s = :data:`SLIP`), the same
  semi-implicit Euler steps.

The error of a run is ``max_t |q(t) - q_OTHER(t)|`` per coordinate against OTHER's held-out recording.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np
from lxml import etree

from ..mujoco_side.mjcf import mjcf_from_model
from .recording import DT, OtherEngine, Pair

__all__ = ["ValidationRun", "validate", "SLIP"]

#: The PD pull toward OTHER's recorded state (Hz, critically damped, gains from the description's A at the start).
PULL_HZ = 2.0
#: A negative fitted armature above -this (kg m^2) is a zero one's rounding.
ARMATURE_ROUNDING = 1e-8
#: The regularisation speed of the Coulomb law in the urdf2links run (rad/s): the scenes' contact default.
SLIP = 1e-2


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


def _project_run(model, joints, names, held, kp, kd) -> np.ndarray:
    """q (T, n) of urdf2links' model driven by the law, semi-implicit Euler (module doc)."""
    b = np.array([joints.get(c, (0.0, 0.0))[0] for c in names])
    f = np.array([joints.get(c, (0.0, 0.0))[1] for c in names])
    q, qd = held.q[0].copy(), held.qd[0].copy()
    out = np.empty_like(held.q)
    for i in range(len(held.t)):
        out[i] = q
        passive = -b * qd - f * qd / np.sqrt(qd * qd + SLIP * SLIP)
        qdd = model.forward_dynamics(q, qd, _law(held, i, q, qd, kp, kd) + passive)
        qd = qd + DT * qdd
        q = q + DT * qd
        if not np.all(np.isfinite(q)):
            raise ValueError(f"{model.name}: the urdf2links run diverged at t = {held.t[i]:.4g} s")
    return out


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
            runs.append(ValidationRun(label, "urdf2links", np.max(np.abs(q - held.q), axis=0)))
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

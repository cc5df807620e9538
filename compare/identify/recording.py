"""OTHER run by MuJoCo with known applied torques, recorded in DESCRIPTION's coordinates (docs/identify.md).

MuJoCo loads OTHER as written (an MJCF file; a URDF through MuJoCo's own import,
:func:`urdf2links.compare.pairs.mujoco_import.save_mujoco_import`), with contact and joint limits switched off
(``mjDSBL_CONTACT``, ``mjDSBL_LIMIT``: the excitation stays inside the limits, and neither is a parameter of the
fit) and everything else as the file says: gravity, damping, armature, frictionloss. The joints are paired by
:func:`urdf2links.compare.pairs.context.pair_context` (E52: ``qpos = s q + o`` per one-coordinate joint).

A computed-torque servo follows an excitation trajectory (:mod:`.excitation`): ``tau = c(q, q') + M(q) (q''_r +
Kp e + Kd e')`` (``c`` MuJoCo's ``qfrc_bias``, ``M`` its ``mj_fullM``; damping, armature's share aside, and
frictionloss are left to the feedback), applied as ``qfrc_applied``.
Each step is ``mj_step1`` (positions, velocities, ``qfrc_bias``), the torque, then ``mj_step2`` (semi-implicit
Euler); a sample is the state before the step, the torque applied and MuJoCo's own ``qacc`` at that state,
so ``(q, q', q'', tau)`` satisfy MuJoCo's equations of motion exactly, whatever the integration error: the
identification data are noise free. :func:`inverse_consistency` checks this with ``mj_inverse``
(``qfrc_inverse`` against the torque applied). MuJoCo's own frictionloss force (``qfrc_constraint``) is kept
beside, to say where its soft-constraint law sticks (:attr:`Recording.sticking`).
"""

from __future__ import annotations

import tempfile
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np

from urdf2links.parsers.mjcf import is_mjcf_path
from urdf2links.parsers.parts import parts_model, robot_parts

from ..pairs.context import pair_context
from ..pairs.mujoco_import import save_mujoco_import

__all__ = ["OtherEngine", "Recording", "open_pair", "record", "inverse_consistency", "Pair", "DT", "SERVO_HZ"]

#: MuJoCo's timestep of the recordings (s); a sample every ``DECIMATE`` steps.
DT = 1e-3
DECIMATE = 2
#: The servo's natural frequency (Hz) and damping ratio 1.
SERVO_HZ = 4.0
#: MuJoCo's solver tolerance in the recordings: frictionloss forces converged far below the fit's 1e-6.
TOLERANCE = 1e-14


@dataclass(frozen=True, eq=False)
class OtherEngine:
    """OTHER compiled by MuJoCo (``model``), its ``path``, how it was read (``how``), and per DESCRIPTION
    coordinate (n,): ``qpos``, ``dof`` addresses, ``sign`` and ``offset`` (E52)."""

    path: Path
    model: object
    how: str
    qpos: np.ndarray
    dof: np.ndarray
    sign: np.ndarray
    offset: np.ndarray


@dataclass(frozen=True, eq=False)
class Pair:
    """DESCRIPTION's parts and tree of links (``parts``, ``built``: :class:`~urdf2links.parsers.parts.PartsModel`),
    OTHER's ``other_parts`` and its MuJoCo ``engine``, the ``context`` of the pair, ``names`` (n,) DESCRIPTION's
    coordinates, ``notes``."""

    description: Path
    parts: object
    built: object
    other_parts: object
    engine: OtherEngine
    context: object
    names: tuple
    notes: tuple


def _compile_other(path: Path, workdir: Path) -> tuple[object, str]:
    if is_mjcf_path(path):
        return mujoco.MjModel.from_xml_path(str(path)), "MJCF, compiled by MuJoCo as written"
    saved = save_mujoco_import(path, workdir / f"{path.stem}.mujoco.xml", keep_geometry=False)
    return mujoco.MjModel.from_xml_path(str(saved.path)), "URDF, through MuJoCo's own URDF import (meshes left out)"


def open_pair(description, other, *, explicit_map: dict | None = None) -> Pair:
    """DESCRIPTION and OTHER read, paired joint by joint, and OTHER compiled by MuJoCo (module doc).

    Raises ValueError naming the joint when a moving joint of either side has no partner, or is not a
    one-coordinate joint (hinge, slide)."""
    description, other = Path(description), Path(other)
    parts, other_parts = robot_parts(description), robot_parts(other)
    ctx = pair_context(parts, other_parts, explicit_map=explicit_map)
    built = parts_model(parts)
    names = tuple(built.model.coordinate_names)
    with tempfile.TemporaryDirectory() as tmp:
        m, how = _compile_other(other, Path(tmp))
    m.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT) | int(mujoco.mjtDisableBit.mjDSBL_LIMIT)
    m.opt.integrator = int(mujoco.mjtIntegrator.mjINT_EULER)
    m.opt.timestep = DT
    m.opt.tolerance = TOLERANCE
    m.opt.iterations = max(int(m.opt.iterations), 200)
    qpos, dof, sign, offset = [], [], [], []
    for name in names:
        match = ctx.mapping.of_urdf(name)
        if match is None:
            raise ValueError(f"{description}: joint {name!r} has no partner in {other} (unmatched there: "
                             f"{list(ctx.mapping.unmatched_mjcf)}); pair it with --map {name}=OTHER_JOINT")
        jid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, match.mjcf)
        if jid < 0 or int(m.jnt_type[jid]) not in (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE)):
            raise ValueError(f"{other}: joint {match.mjcf!r} (partner of {name!r}) is not a hinge or slide joint "
                             "in MuJoCo's model; identify handles one-coordinate joints")
        qpos.append(m.jnt_qposadr[jid]), dof.append(m.jnt_dofadr[jid])
        sign.append(match.sign), offset.append(match.offset)
    if m.nv != len(names):
        raise ValueError(f"{other}: MuJoCo's model has {m.nv} degrees of freedom, {description} {len(names)} "
                         f"coordinates; unmatched in {other}: {list(ctx.mapping.unmatched_mjcf)}")
    notes = [f"OTHER read as {how}; contact and joint limits switched off in its MuJoCo run"]
    if ctx.root.urdf is not None and not np.allclose(ctx.alignment[:3, :3], np.eye(3), atol=1e-9):
        notes.append("the roots are turned against each other: OTHER's gravity is expressed in DESCRIPTION's world")
    engine = OtherEngine(other, m, how, np.array(qpos), np.array(dof), np.array(sign, float), np.array(offset, float))
    return Pair(description, parts, built, other_parts, engine, ctx, names, tuple(notes))


@dataclass(frozen=True, eq=False)
class Recording:
    """One run of OTHER in DESCRIPTION's coordinates: ``t`` (S,), ``q``, ``qd``, ``qdd``, ``tau`` (the
    applied torque), ``friction`` (MuJoCo's frictionloss force, ``qfrc_constraint``), ``reference`` (the
    trajectory's q at ``t``), all (S, n); ``seed`` of its trajectory, ``trajectory`` itself."""

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    tau: np.ndarray
    friction: np.ndarray
    reference: np.ndarray
    seed: int
    trajectory: object

    @property
    def samples(self) -> int:
        return len(self.t)

    def sticking(self, frictionloss) -> np.ndarray:
        """(S, n) bool: where MuJoCo's frictionloss force on a joint with frictionloss ``f`` (n,) is below
        ``f`` (its soft constraint's linear zone around q' = 0), so its law is not Coulomb's there."""
        f = np.asarray(frictionloss, float)
        return (f > 0) & (np.abs(self.friction) < f * (1 - 1e-9))


def record(pair: Pair, trajectory, *, seed: int, t_end: float, decimate: int = DECIMATE) -> Recording:
    """OTHER servoed along ``trajectory`` for ``t_end`` seconds (module doc); one sample every ``decimate`` steps."""
    e, m = pair.engine, pair.engine.model
    d = mujoco.MjData(m)
    steps = int(round(t_end / m.opt.timestep))
    times = np.arange(steps) * m.opt.timestep
    qr, qdr, qddr = trajectory.evaluate(times)
    s, o = e.sign, e.offset
    d.qpos[e.qpos] = s * qr[0] + o
    d.qvel[e.dof] = s * qdr[0]
    M = np.zeros((m.nv, m.nv))
    wn = 2 * np.pi * SERVO_HZ
    keep = np.arange(0, steps, decimate)
    out = {k: np.empty((len(keep), len(s))) for k in ("q", "qd", "qdd", "tau", "friction")}
    row = 0
    for i in range(steps):
        mujoco.mj_step1(m, d)
        q = (d.qpos[e.qpos] - o) * s
        qd = d.qvel[e.dof] * s
        mujoco.mj_fullM(m, d, M)
        u = np.zeros(m.nv)
        u[e.dof] = s * (qddr[i] + wn * wn * (qr[i] - q) + 2 * wn * (qdr[i] - qd))
        d.qfrc_applied[:] = d.qfrc_bias + M @ u
        record_now = i % decimate == 0
        if record_now:
            out["q"][row], out["qd"][row] = q, qd
            out["tau"][row] = d.qfrc_applied[e.dof] * s
        mujoco.mj_step2(m, d)
        if record_now:
            out["qdd"][row] = _qacc(d, e) * s
            out["friction"][row] = d.qfrc_constraint[e.dof] * s
            row += 1
        if not np.all(np.isfinite(d.qvel)):
            raise ValueError(f"{e.path}: MuJoCo's run diverged at t = {times[i]:.4g} s (seed {seed}); lower the "
                             "excitation (--t-end, --harmonics)")
    return Recording(times[keep], out["q"], out["qd"], out["qdd"], out["tau"], out["friction"], qr[keep], seed,
                     trajectory)


def _qacc(d, e) -> np.ndarray:
    """MuJoCo's acceleration at the state before the step (``mj_step2`` leaves ``qacc`` as ``mj_forward``
    computed it; Euler's implicit damping works on a copy)."""
    return d.qacc[e.dof]


def inverse_consistency(pair: Pair, rec: Recording, *, samples: int = 200) -> float:
    """The largest ``|qfrc_inverse - tau|`` (N m) of ``mj_inverse`` at ``samples`` recorded states with
    MuJoCo's own ``qacc``: how exactly the recording satisfies MuJoCo's equations of motion."""
    e, m = pair.engine, pair.engine.model
    d = mujoco.MjData(m)
    worst = 0.0
    for i in np.linspace(0, rec.samples - 1, min(samples, rec.samples)).astype(int):
        d.qpos[e.qpos] = e.sign * rec.q[i] + e.offset
        d.qvel[e.dof] = e.sign * rec.qd[i]
        d.qacc[e.dof] = e.sign * rec.qdd[i]
        mujoco.mj_inverse(m, d)
        worst = max(worst, float(np.max(np.abs(d.qfrc_inverse[e.dof] * e.sign - rec.tau[i]))))
    return worst

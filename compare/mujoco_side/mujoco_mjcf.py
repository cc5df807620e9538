"""Route 2 for an MJCF robot: MuJoCo runs the file as written, with only the scene's effects enabled.

Route 2 is "MuJoCo's own reading of the robot file": for a URDF, MuJoCo's URDF import
(:mod:`urdf2links.compare.mujoco_side.mujoco_urdf`); for an MJCF file, the file itself, compiled by
MuJoCo (:func:`mujoco_from_mjcf`). What the scene does not name is switched off so that both engines
run the same physics (:data:`urdf2links.parsers.mjcf_notes.MUJOCO_OFF`): contacts, every constraint
(equality, limits, friction loss), actuation unless the scene names actuators (then the file's actuators
it names keep their law, its own ``[[actuator]]`` blocks are added to the file's joints through
``MjSpec``, the others get zero gain and bias, and the controls come from the compiled control callback,
:meth:`~urdf2links.compare.mujoco_side.mujoco_inputs.CompiledInputs.for_file`, which feeds the file's actuators
on fixed tendons too, issue 43: :mod:`~urdf2links.compare.mujoco_side.tendon_controls`); tendons' stiffness and
damping, fluid forces (density, viscosity, wind) set to 0. The joints' springs and dampers are the scene's
(:meth:`~urdf2links.scenes.scene.Scene.springs_for`: the file's own in the default scene) written into
``jnt_stiffness``, ``qpos_spring`` and ``dof_damping`` of hinges and slides (0 elsewhere, ball and
free joints included); ``body_gravcomp`` is the scene's ``[gravcomp]`` (the file's own with
``from_file``); gravity is the scene's (0 without ``[gravity]``). The armature is the file's (part of the model's inertia, E49).

States go through the model's own map (:meth:`~urdf2links.dynamics.model.Model.to_mujoco`), so
MuJoCo's terms are compared in the project's coordinates (:func:`file_terms`): ``A`` against
``J^T M J`` and ``e + G`` against ``J^T (qfrc_bias + M J' q')`` (docs/equations.md (E50)), and its
runs (:func:`run_file`) are read back with :meth:`~urdf2links.dynamics.model.Model.from_mujoco`, each
ball or free joint's angles on the branch nearest the previous sample's (then nearest the project's
own run when given). MuJoCo is timed as in route 1: ``mj_step(m, d, nstep=k)`` from sample to sample.
"""

from __future__ import annotations

import copy
import dataclasses
import math
from dataclasses import dataclass, field

import mujoco
import numpy as np

from urdf2links.compilation import clock  # durations without numba's compilation
from urdf2links.parsers.mjcf import compile_mjcf
from urdf2links.parsers.mjcf_notes import MUJOCO_OFF
from urdf2links.scenes.excitation import coordinate_ranges

from urdf2links.integration.simulate import Compilation

from .mjcf import add_spec_actuators
from .mujoco_constraints import route2_constraints
from .mujoco_inputs import CompiledInputs
from .mujoco_run import MujocoRun
from .mujoco_stepping import (blow_up_counts, implicit_note, instability_note, integrator_name, recorded_energies,
                              set_stepping, step_samples)
from .tendon_controls import add_limit_tendons, limit_tendons, tendon_actuators

__all__ = ["MujocoFile", "mujoco_from_mjcf", "file_terms", "run_file", "file_runner", "FILE_LABEL",
           "file_route_inputs"]

FILE_LABEL = "route 2: MuJoCo runs the MJCF file as written (only the scene's effects enabled)"


@dataclass(frozen=True, eq=False)
class MujocoFile:
    """An MJCF file compiled by MuJoCo for a scene: ``model`` (``mujoco.MjModel``), the project's
    ``source`` model (its map of states), ``gravity``, ``notes`` (what was switched off and why)."""

    model: mujoco.MjModel
    source: object
    gravity: np.ndarray
    path: str
    notes: list[str] = field(default_factory=list)
    moving_base: bool = False
    actuator_ids: tuple = ()
    """MuJoCo's actuator id of each of the plan's actuators (the scene's own added after the file's), -1 for
    those on a ball's or free joint's angles (applied through the control callback); empty: no actuators."""
    tendon_actuator_ids: tuple = ()
    """MuJoCo's actuator id of each of the plan's actuators on fixed tendons (issue 43:
    :func:`~urdf2links.compare.mujoco_side.tendon_controls.tendon_actuators`; their controls come from the
    control callback too)."""

    @property
    def n(self) -> int:
        return self.source.n

    @property
    def coordinate_names(self) -> tuple[str, ...]:
        return self.source.coordinate_names


def file_route_inputs(scene, plan=None) -> list[str]:
    """What of ``scene`` route 2 for an MJCF file does not run (time-dependent inputs, and with ``plan``
    the scene actuators on a hinge or slide the file leaves unnamed, which ``MjSpec`` cannot address):
    empty when it runs it. Actuators on a ball's or free joint's angles run through the control callback
    (:meth:`~urdf2links.compare.mujoco_side.mujoco_inputs.CompiledInputs.for_file`)."""
    out = [w for w, on in (("[base]", scene.base is not None), ("[[force]]/[[moment]]", bool(scene.loads)),
                           ("[[torque]]", bool(scene.torques) and file_torques(scene, plan) is None),
                           ("[[computed_torque]]", bool(scene.computed_torque)),
                           ("[[contact]]", bool(getattr(scene, "contacts", ()))))     # issue 37: route 1 carries it
           if on]
    if plan is not None:
        bad = [a.name for a in plan.actuator_set.actuators if _carried(plan, a) is False]
        if bad:
            out.append(f"actuators on joints the file leaves unnamed ({', '.join(bad[:4])}" + (", ..." if len(bad) > 4
                                                                                            else "") + ")")
    return out


def file_torques(scene, plan=None) -> dict | None:
    """``{dof address: torque}`` of the scene's ``[[torque]]`` when every one is constant and on a hinge or
    slide of the file (the default scene's damper torques, E65): MuJoCo's run of the file applies them
    as a constant ``qfrc_applied``. None when one is not (then the run is route 1's); needs ``plan``."""
    from urdf2links.scenes.functions import Constant

    if plan is None or any(_carried(plan, a) is None for a in plan.actuator_set.actuators):
        return None     # the control callback writes qfrc_applied (actuators on ball or free joints' angles)
    joints = {plan.model.coordinate_names[j.coordinates[0]]: j for j in plan.model.info["mujoco"].joints
              if j.kind in ("hinge", "slide")}
    out = {}
    for coord, f in scene.torques:
        if not isinstance(f, Constant) or coord not in joints:
            return None
        out[joints[coord].dofadr] = out.get(joints[coord].dofadr, 0.0) + float(f.value)
    return out


def _carried(plan, a):
    """How MuJoCo's run of the file carries the scene's actuator ``a``: True as a MuJoCo actuator (the file's
    own, or the scene's on a named hinge or slide), None through the callback (a ball's or free joint's
    coordinate), False not at all (a hinge or slide without a name in the file)."""
    if a.source == "file":
        return True
    joint = {c: j for j in plan.model.info["mujoco"].joints for c in j.coordinates}[a.index]
    if joint.kind in ("ball", "free"):
        return None
    return joint.name == plan.model.coordinate_names[a.index] or False


def _edit(actuators, gravcomp: dict, notes: list[str], limited=None):
    """An ``MjSpec`` edit: the scene's own actuators (not the file's) added on their joints, as route 1
    writes them (``general``: dynamics none, gain fixed, bias affine, E55), and the scene's gravcomp on the
    bodies (MuJoCo counts the bodies with gravcomp when it compiles: ``ngravcomp``; a gravcomp set
    afterwards on a model compiled without any would not act)."""

    def edit(spec):
        if limited is not None:     # issue 45: the tendon-limit law (E87), noted
            rows = {r["name"]: r for r in limited.model.info.get("tendons", [])}
            names = add_limit_tendons(spec, limited, rows)
            notes.append("tendon limit of " + ", ".join(n.removesuffix("__limit") for n in names) + ": the project's "
                         "law on both engines (E87: MuJoCo's own soft limit disabled, the law added as the tendon "
                         + ", ".join(names) + ", a spring whose dead band is the range)")
        for body, f in gravcomp.items():
            b = spec.body(body)
            if b is None:
                notes.append(f"gravcomp of body {body!r} not written (the file does not name it)")
                continue
            b.gravcomp = f
        add_spec_actuators(spec, actuators, target=lambda a: a.joint)
    return edit


def _actuation(m, acts, notes) -> list[int]:
    """Actuation for the scene's actuators only: the file's actuators the scene names keep MuJoCo's own
    law; the others get zero gain and bias (no force: one by one, since MuJoCo switches actuation off
    only as a whole); actuator-level damping (MuJoCo 4's, a passive force the tree does not read) is
    zeroed. Returns MuJoCo's actuator id of each of the plan's actuators, in the plan's order."""
    import mujoco

    names = {a.name for a in acts}
    ids, off = [], []
    for a in acts:
        ids.append(mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, a.name))
    for k in range(m.nu):
        name = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_ACTUATOR, k) or f"#{k}"
        if name in names:
            continue
        off.append(name)
        m.actuator_gainprm[k, :] = 0.0
        m.actuator_biasprm[k, :] = 0.0
        if int(m.actuator_gaintype[k]) in (int(mujoco.mjtGain.mjGAIN_MUSCLE), int(mujoco.mjtGain.mjGAIN_AFFINE)):
            m.actuator_gaintype[k] = int(mujoco.mjtGain.mjGAIN_FIXED)
        if int(m.actuator_biastype[k]) == int(mujoco.mjtBias.mjBIAS_MUSCLE):
            m.actuator_biastype[k] = int(mujoco.mjtBias.mjBIAS_NONE)
        m.actuator_forcelimited[k] = 0
    if np.any(m.jnt_actfrclimited):
        notes.append("joints' actuatorfrcrange switched off (a scene's forcerange says what saturates; the file's "
                     "actuators on such joints are refused by name)")
        m.jnt_actfrclimited[:] = 0
    damping = np.ravel(getattr(m, "actuator_damping", np.zeros(0)))
    if np.any(damping):
        notes.append("actuator damping (MuJoCo's passive damping of an actuator's joint) set to 0: the tree reads "
                     "joint damping only")
        damping[:] = 0.0
    if off:
        notes.append(f"actuation on for the scene's {len(acts)} actuator(s); the file's actuators it does not name get "
                     f"zero gain and bias: {', '.join(off[:8])}" + (f", ... ({len(off)} in all)" if len(off) > 8 else ""))
    return ids


def mujoco_from_mjcf(plan, *, timestep: float | None = None, integrator: str | None = None) -> MujocoFile:
    """The scene's MJCF robot compiled by MuJoCo with only the scene's effects (module doc)."""
    scene, model = plan.scene, plan.model
    notes: list[str] = []
    acts = _run_actuators(plan, notes)
    carried_acts = [a for a in acts if _carried(plan, a)]
    tendon_acts = [ta.actuator for ta in tendon_actuators(plan)]     # issue 43: fed their controls too
    own = [a for a in carried_acts if a.source != "file"]
    table = scene.gravcomp_table(model)
    limits = limit_tendons(plan) if scene.file_constraints else ()     # issue 45: E87 as tendons of their own
    m, where = compile_mjcf(str(scene.robot), notes, edit=_edit(own, table, notes, plan if limits else None)
                            if own or table or limits else None)
    g = np.zeros(3) if scene.gravity is None else np.asarray(scene.gravity, float)
    springs = plan.spring_set.springs
    off_flags = _scene_flags(m, g, springs, actuated=bool(acts or tendon_acts), gravcomp=bool(table))
    kept = carried_acts + tendon_acts
    ids = dict(zip((a.name for a in kept), _actuation(m, kept, notes))) if kept else {}
    _scene_springs(m, model, springs)
    changed = _tendons_off(m, plan, notes)
    fluid = _fluid_off(m)
    _scene_gravcomp(m, table, notes, actuated=bool(acts or tendon_acts))
    set_stepping(m, timestep=timestep, integrator=integrator)
    notes.append(f"the file compiled by MuJoCo {mujoco.__version__}; gravity {g.tolist()}; disabled: "
                 + ", ".join(n.removeprefix("mjDSBL_").lower() for n in off_flags)
                 + "; joint stiffness, springref and damping set to the scene's springs and dampers ("
                 + (", ".join(f"{s.coordinate}: k {s.stiffness:g} rest {s.rest:g} c {s.damping:g}" for s in springs)
                    or "none") + ")"
                 + (f"; {', '.join(changed)} set to 0" if changed else "")
                 + (f"; fluid {', '.join(fluid)} set to 0" if fluid else ""))
    return MujocoFile(model=m, source=model, gravity=g, path=where, notes=notes,
                      actuator_ids=tuple(ids.get(a.name, -1) for a in acts),
                      tendon_actuator_ids=tuple(ids[a.name] for a in tendon_acts))


def _run_actuators(plan, notes: list[str]) -> list:
    """The scene's actuators MuJoCo's run of the file carries: none when the file's joints do not carry them
    all, those on ball or free joints' angles through the control callback (both noted)."""
    acts = list(plan.actuator_set.actuators)
    if acts and any(w.startswith("actuators on") for w in file_route_inputs(plan.scene, plan)):
        notes.append("the scene's actuators are not all carried by the file's joints: this model runs without them "
                     "(its terms only; the trajectory is route 1's)")
        return []
    via_callback = [a for a in acts if _carried(plan, a) is None]
    if via_callback:
        notes.append(f"actuators on ball or free joints' angles ({', '.join(a.name for a in via_callback[:6])}"
                     + (", ..." if len(via_callback) > 6 else "") + "): no MuJoCo joint actuator acts on ZYX angles; "
                     "the project's law is applied through qfrc_applied from the control callback (f = E^-T tau, E50)")
    return acts


def _scene_flags(m, g, springs, *, actuated: bool, gravcomp: bool) -> list[str]:
    """The scene's gravity ``g`` and MuJoCo's switches as the scene says, the file's flags notwithstanding:
    gravity, springs, dampers, actuation (when ``actuated``) and clamping on, what the project does not model
    off (:data:`~urdf2links.parsers.mjcf_notes.MUJOCO_OFF`), springs off without a stiffness (and without
    ``gravcomp``: MuJoCo's ``mj_passive`` skips gravcomp too when springs and dampers are both off), dampers
    off without a damping. Returns the flags of MUJOCO_OFF switched off."""
    m.opt.gravity[:] = g
    for name in ("mjDSBL_GRAVITY", "mjDSBL_SPRING", "mjDSBL_DAMPER", "mjDSBL_ACTUATION", "mjDSBL_CLAMPCTRL"):
        m.opt.disableflags &= ~int(getattr(mujoco.mjtDisableBit, name))
    off_flags = [n for n in MUJOCO_OFF if not (actuated and n == "mjDSBL_ACTUATION")]
    for name in off_flags:
        m.opt.disableflags |= int(getattr(mujoco.mjtDisableBit, name))
    if not any(s.stiffness > 0 for s in springs) and not gravcomp:
        m.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_SPRING)
    if not any(s.damping > 0 for s in springs):
        m.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_DAMPER)
    return off_flags


def _scene_springs(m, model, springs) -> None:
    """The scene's springs and dampers as the joints' ``jnt_stiffness``, ``qpos_spring`` and ``dof_damping``
    (hinges and slides; 0 everywhere else)."""
    m.jnt_stiffness[:] = 0.0
    m.dof_damping[:] = 0.0
    by_coord = {model.coordinate_names[j.coordinates[0]]: j for j in model.info["mujoco"].joints
                if j.kind in ("hinge", "slide")}
    for s in springs:
        j = by_coord[s.coordinate]
        jid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, j.name)
        if jid < 0:     # an unnamed joint: found by its address
            jid = int(np.flatnonzero(m.jnt_qposadr == j.qposadr)[0])
        m.jnt_stiffness[jid] = s.stiffness
        m.qpos_spring[j.qposadr] = s.rest
        m.dof_damping[j.dofadr] = s.damping


def _tendons_off(m, plan, notes: list[str]) -> list[str]:
    """Tendons' stiffness and damping set to 0, then the file's equalities and fixed tendons on when the scene
    asks (issue 36: :func:`~urdf2links.compare.mujoco_side.mujoco_constraints.route2_constraints`): what was
    changed, for the note."""
    changed = [a for a in ("tendon_stiffness", "tendon_damping") if np.any(getattr(m, a))]
    tendons = m.tendon_stiffness.copy(), m.tendon_damping.copy()
    m.tendon_stiffness[:] = 0.0
    m.tendon_damping[:] = 0.0
    if plan.constraints is not None and plan.scene.file_constraints:    # the file's equalities and
        changed = route2_constraints(m, plan, tendons, notes)          # fixed tendons act, as written
    elif m.neq:     # issue 45: none acts (opened, inactive or not modelled): off one by one too, not only the flag
        m.eq_active0[:] = 0
    return changed


def _fluid_off(m) -> list[str]:
    """Fluid forces (density, viscosity, wind) set to 0: those that were not, for the note."""
    fluid = [k for k in ("density", "viscosity") if getattr(m.opt, k) != 0.0] + (["wind"] if np.any(m.opt.wind) else [])
    m.opt.density, m.opt.viscosity = 0.0, 0.0
    m.opt.wind[:] = 0.0
    return fluid


def _scene_gravcomp(m, table: dict, notes: list[str], *, actuated: bool) -> None:
    """``body_gravcomp`` set to the scene's ``[gravcomp]`` (``table``: ``{body: factor}``), noted."""
    before = np.array(m.body_gravcomp)
    for b in range(1, m.nbody):
        m.body_gravcomp[b] = table.get(mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, b) or f"body{b}", 0.0)
    if not np.array_equal(before, m.body_gravcomp):
        notes.append("body gravcomp set to the scene's [gravcomp]" + ("" if table else " (none: the scene does not ask)"))
    if table and np.any(m.jnt_actgravcomp) and not actuated:
        notes.append("joints with actuatorgravcomp: MuJoCo routes their gravcomp through actuation, which this run "
                     "switches off (the scene names no actuator): MuJoCo applies no gravcomp on them, the project does")


def _rel(ours, theirs, floor: float = 0.0) -> float:
    theirs = np.asarray(theirs, float)
    if theirs.size == 0:
        return 0.0
    diff = float(np.max(np.abs(np.asarray(ours, float) - theirs)))
    scale = max(float(np.max(np.abs(theirs))), floor)
    return 0.0 if diff == 0.0 else (math.inf if scale == 0.0 else diff / scale)


def file_terms(mf: MujocoFile, model, scene, *, states: int = 8, seed: int = 0) -> dict:
    """``A`` against ``J^T M J`` and ``e + G`` (the scene's gravity) against ``J^T (qfrc_bias + M J' q')``
    at seeded states within the joints' limits, ``+-1`` around MuJoCo's qpos0 where a joint has none
    (:func:`~urdf2links.scenes.excitation.coordinate_ranges`; ``q'`` standard normal). Returns a
    JSON-ready dict like route 2's for a URDF."""
    g = np.zeros(3) if scene.gravity is None else np.asarray(scene.gravity, float)
    ours = model.with_gravity(g)
    m = mf.model
    d = mujoco.MjData(m)
    qmap = model.info["mujoco"]
    rng = np.random.default_rng(seed)
    span = coordinate_ranges(model)     # within the joints' limits, else +-1 around qpos0 (or the home keyframe)
    err_A = err_b = 0.0
    per_state = []
    start = clock()
    M = np.zeros((m.nv, m.nv))
    for _ in range(states):
        q = rng.uniform(span.lower, span.upper)
        qd = rng.standard_normal(model.n)
        d.qpos[:], d.qvel[:] = qmap.to_mujoco(q, qd)
        mujoco.mj_forward(m, d)
        mujoco.mj_fullM(m, d, M)
        J = qmap.jacobian(q)
        A_mj = J.T @ M @ J
        b_mj = J.T @ (d.qfrc_bias + M @ qmap.jacobian_rate(q, qd))
        A = ours.mass_matrix(q)
        eG = ours.bias(q, qd) + (ours.gravity(q) if scene.gravity is not None else 0.0)
        floor = float(np.max(np.abs(A_mj))) * max(1.0, float(np.max(np.abs(qd))) ** 2) * 1e-3 if model.n else 0.0
        ra, rb = _rel(A, A_mj), _rel(eG, b_mj, floor)
        per_state.append([ra, rb])
        err_A, err_b = max(err_A, ra), max(err_b, rb)
    return {"label": FILE_LABEL, "route": "mjcf-file", "max_rel_error_A": err_A, "max_rel_error_bias": err_b,
            "max_rel_error": max(err_A, err_b), "states": states, "seed": seed, "per_state": per_state,
            "mapping": "A vs J^T mj_fullM J, e + G vs J^T (qfrc_bias + mj_fullM J' q'), qvel = J q' (E50)",
            "refusals": [], "notes": list(mf.notes), "wall_time_s": clock() - start}


def run_file(mf: MujocoFile, plan, *, t_end: float, samples: int, reference=None) -> MujocoRun:
    """MuJoCo's run of the file from the scene's initial state: ``mj_step(nstep)`` from sample to sample,
    the samples read back in the project's coordinates (module doc), MuJoCo's energies (armature and
    springs included) from an untimed pass. ``reference`` (samples, n): the project's ``q`` at the same
    times, for the branch of the angles."""
    start = clock()
    m, model = mf.model, mf.source
    qmap = model.info["mujoco"]
    q0, qd0 = plan.scene.initial_state(model)
    d = mujoco.MjData(m)
    d.qpos[:], d.qvel[:] = qmap.to_mujoco(q0, qd0)
    for dof, tau in (file_torques(plan.scene, plan) or {}).items():      # the scene's constant joint torques
        d.qfrc_applied[dof] = tau
    dt = float(m.opt.timestep)
    t_req = np.linspace(0.0, float(t_end), int(samples))
    ks = np.rint(t_req / dt).astype(np.int64)
    notes = []
    offset = float(np.max(np.abs(ks * dt - t_req)))
    if offset > 1e-9 * dt:
        notes.append(f"timestep {dt:g} s does not divide the sample interval: samples at the nearest steps "
                     f"(largest offset {offset:.3g} s)")
    fed = mf.actuator_ids or mf.tendon_actuator_ids     # issue 43: controls of actuators on tendons too
    inputs = CompiledInputs.for_file(plan, m, d, mf.actuator_ids) if fed else None
    rec, engine = step_samples(m, d, inputs, ks)
    ts, qpos, qvel = rec["t"], rec["qpos"], rec["qvel"]
    blow = blow_up_counts(d)
    integ = integrator_name(m)
    note = implicit_note(integ, m)
    if note:
        notes.append(note)
    if blow:
        notes.append(instability_note(blow, integ, dt))
        ts = ks * dt
    S = len(ks)
    q, qd = np.empty((S, model.n)), np.empty((S, model.n))
    prev = np.asarray(q0, float)
    for j in range(S):
        ref = prev if reference is None else np.asarray(reference[j], float)
        q[j], qd[j] = qmap.from_mujoco(qpos[j], qvel[j], reference=ref)
        prev = q[j]
    energy = recorded_energies(m, rec, lambda me, de: (de.energy[1], de.energy[0]))     # MuJoCo's order: V, E
    return MujocoRun(t=ts, q=q, qd=qd, energy=energy, base_tracking_error=0.0, wall_time=engine, nsteps=int(ks[-1]),
                     timestep=dt, integrator=integ, coordinate_names=model.coordinate_names, notes=notes,
                     harness_time=clock() - start, inputs="none" if inputs is None else "compiled",
                     callback_calls=0 if inputs is None else int(inputs.calls), blow_ups=blow,
                     compilation=inputs.compilation if inputs is not None else Compilation())


def file_runner(mf: MujocoFile, plan, *, t_end: float, samples: int, reference=None):
    """``run_at(integrator, timestep) -> MujocoRun``: :func:`run_file` of a copy of ``mf`` whose model
    steps with that integrator and timestep (the file itself is not changed), for
    :func:`~urdf2links.compare.mujoco_side.stable_run.stable_run` on the file's route."""

    def run_at(integrator: str, timestep: float) -> MujocoRun:
        m = copy.deepcopy(mf.model)
        set_stepping(m, timestep=timestep, integrator=integrator)
        return run_file(dataclasses.replace(mf, model=m), plan, t_end=t_end, samples=samples, reference=reference)

    return run_at

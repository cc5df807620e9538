"""Run the route-1 MJCF model (:mod:`urdf2links.compare.mujoco_side.mjcf`) in MuJoCo: trajectories, energies, time.

**How MuJoCo is run** (as its experts run it): ``mujoco.mj_step(m, d, nstep=k)`` from one sample to
the next, the energy flag ``mjENBL_ENERGY`` off; the states at the samples are copied between the
calls. ``MujocoRun.wall_time`` is the time inside those ``mj_step`` calls only (MuJoCo's engine);
``harness_time`` the whole :func:`run_mujoco` call (model copy, inputs, the sample copies, the
energy pass). Energies come from an untimed pass over the recorded states (below).

**Time-dependent inputs** are applied from MuJoCo's control callback (``mjcb_control``), which
``mj_forward`` calls after positions and velocities are computed and before the accelerations --
at every stage of RK4 too, with ``d.time`` set to the stage's time. So ``qM`` (through
``mj_fullM``), ``qfrc_bias`` and ``qfrc_passive`` are current when it runs:

* joint torques ``tau(t)`` (n,) of the project's coordinates -> ``qfrc_applied`` on their dofs;
* loads on links (force at a point, moment; link or world axes) -> ``xfrc_applied`` of the link's
  body as a world-frame force and a moment about the body's COM ``d.xipos``. A load on a folded
  massless link (it has no body, see :mod:`urdf2links.compare.mujoco_side.mjcf`) is mapped with the host body's Jacobian
  at the point, restricted to the dofs that move that link, into ``qfrc_applied``;
* the prescribed base {A} (``moving_base=True``): with ``a_b`` the base parameters' second
  derivatives at ``d.time``, ``f`` every generalized force but the bias and the base's own
  ``qfrc_applied`` (``qfrc_applied`` + loads + ``qfrc_passive``), the robot's accelerations are
  ``a_r = M_rr^{-1} (f_r - bias_r - M_rb a_b)`` and the base gets
  ``qfrc_applied_b = M_bb a_b + M_br a_r + bias_b - f_b``: MuJoCo's own ``M qacc = f - bias``
  then yields ``qacc_b = a_b`` exactly and the robot's motion of the prescribed base. Exact for
  RK4 and for Euler without dampers (Euler with dampers, and the implicit integrators, change
  the acceleration after the callback: the base then only approximately follows;
  ``base_tracking_error`` shows by how much).

Two implementations of that callback, chosen by ``inputs``:

* ``"compiled"`` (default, a scene's inputs): :class:`urdf2links.compare.mujoco_side.mujoco_inputs.CompiledInputs`,
  numba code installed as a C function pointer: no Python runs during ``mj_step``. It evaluates
  the scene's time functions as the project's compiled right-hand side does.
* ``"python"``: :class:`PythonInputs`, the same steps in numpy from a Python callback (about a
  millisecond per RK4 step: the harness's time, not MuJoCo's). It serves inputs given as Python
  callables (``base``, ``torques``, ``loads`` arguments) and is the compiled one's oracle (the
  tests require equal trajectories to 1e-12).

The callback is process-global: it is installed for the run only, acts only on the run's own
``MjData`` and is always removed afterwards (the previous callback, normally None, is restored),
also when something raises.

Sampling: the run takes ``K = round(t_end / timestep)`` steps and records at the steps nearest to
``linspace(0, t_end, samples)``; ``MujocoRun.t`` holds the actual times (``d.time``), equal to
the requested ones when the timestep divides the sample interval (otherwise ``notes`` gives the
largest offset). Energies are MuJoCo's (``mjENBL_ENERGY``: ``mj_energyPos``, ``mj_energyVel``)
evaluated after the run at each recorded state (``qpos``, ``qvel``) with the energy flag on; with a
moving base the ``base_A`` body's own kinetic and potential energy is removed, so they are the
robot's energies in {0} like the project's ``E`` and ``V`` (spring energy ``0.5 k (q - rest)^2``
included in the potential).
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, field
from typing import Callable, Iterable

import mujoco
import numpy as np

from urdf2links.compilation import clock as _clock  # durations without numba's compilation
from urdf2links.dynamics.loads import Wrench
from urdf2links.dynamics.transforms import BaseState
from urdf2links.integration.simulate import Compilation
from urdf2links.scenes.file_constraints import tendon_actuator_names

from .mjcf_model import MjcfModel
from .mujoco_inputs import CompiledInputs
from .mujoco_stepping import (blow_up_counts, implicit_note, instability_note, integrator_name, recorded_energies,
                              set_stepping, step_samples)
from .tendon_controls import tendon_actuators

__all__ = ["MujocoRun", "run_mujoco", "mujoco_accelerations", "robot_energy", "energy_function", "ENERGY_COLUMNS",
           "PythonInputs", "INPUTS", "TIMED_REGION"]

ENERGY_COLUMNS = ("kinetic", "potential")
#: The implementations of the control callback (see the module doc).
INPUTS = ("compiled", "python")
#: What ``MujocoRun.wall_time`` contains.
TIMED_REGION = ("MuJoCo's engine: the mujoco.mj_step(m, d, nstep=k) calls from sample to sample, energy flag off, "
                "the control callback (if the scene has inputs) included; not the model copy, the sample copies, "
                "the energy pass nor the callback's compilation")

@dataclass(frozen=True)
class MujocoRun:
    """A MuJoCo trajectory of the route-1 model, in the project's coordinate order.

    ``t`` (m,) actual sample times; ``q``, ``qd`` (m, n); ``energy`` (m, 2) columns
    :data:`ENERGY_COLUMNS` (kinetic, potential; see module doc); ``base_tracking_error``: max over
    samples of ``|base qpos - prescribed pose|`` (0.0 for a fixed base); ``wall_time`` (s): MuJoCo's
    engine, the ``mj_step(nstep)`` calls only (:data:`TIMED_REGION`); ``harness_time`` (s): the whole
    :func:`run_mujoco` call; ``nsteps`` MuJoCo steps; ``timestep``, ``integrator``; ``inputs``:
    ``"none"``, ``"compiled"`` or ``"python"`` (the control callback used); ``callback_calls`` its
    calls (4 per RK4 step); ``compilation`` the compiled callback's
    :class:`~urdf2links.integration.simulate.Compilation` in this run (its loading from numba's cache, or its
    compilation, once per process; empty afterwards); ``blow_ups``: how often MuJoCo met NaN, Inf or huge
    values and reset its state (``{"BADQACC": 3}``; empty when it never did; ``notes`` then says what
    it means).
    """

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    energy: np.ndarray
    base_tracking_error: float
    wall_time: float
    nsteps: int
    timestep: float
    integrator: str
    coordinate_names: tuple[str, ...]
    base_pose: np.ndarray | None = None
    notes: list[str] = field(default_factory=list)
    harness_time: float = 0.0
    inputs: str = "none"
    callback_calls: int = 0
    compilation: Compilation = field(default_factory=Compilation)
    blow_ups: dict = field(default_factory=dict)

    @property
    def kinetic(self) -> np.ndarray:
        return self.energy[:, 0]

    @property
    def potential(self) -> np.ndarray:
        return self.energy[:, 1]

    @property
    def total_energy(self) -> np.ndarray:
        return self.energy.sum(axis=1)


# --------------------------------------------------------------------------- the callback


def _as_base_fn(base) -> Callable[[float], BaseState] | None:
    if base is None:
        return None
    if isinstance(base, BaseState):
        return lambda t, _b=base: _b
    if callable(base):
        return base
    raise TypeError(f"base must be None, a BaseState or a callable t -> BaseState; got {type(base).__name__}")


class PythonInputs:
    """The control callback in Python for one ``MjData``: torques, loads, prescribed base (module
    doc). ``base``, ``torques``, ``loads``: callables of ``t`` (see :func:`run_mujoco`)."""

    def __init__(self, mj: MjcfModel, m: mujoco.MjModel, d: mujoco.MjData, *, base=None, torques=None,
                 loads=None, ctrl=None):
        self.mj, self.m, self.d = mj, m, d
        self.ctrl = ctrl
        self.base = _as_base_fn(base)
        if self.base is not None and not mj.moving_base:
            raise ValueError("a base motion was given but the MJCF model has no base_A body: build it "
                             "with mjcf_from_model(..., moving_base=True)")
        if self.base is None and mj.moving_base:
            self.base = lambda t: _HELD  # base_A exists: hold it at the origin
        self.torques = torques
        self.loads = loads
        tree = mj.source.tree
        self.n = mj.n
        self._M = np.zeros((m.nv, m.nv))
        self._fx = np.zeros(m.nv)
        self._jacp = np.zeros((3, m.nv))
        self._jacr = np.zeros((3, m.nv))
        # dofs that move each tree link (its own coordinates and its ancestors'), for folded links
        anc = tree.ancestor
        self._moving_dofs = []
        for p in range(tree.n_links):
            coords = [c for c in range(tree.n) if anc[p, tree.coord_link[c]]]
            dofs = list(mj.dof_index[coords]) + list(mj.base_dofs)
            self._moving_dofs.append(np.array(sorted(dofs), dtype=np.int64))
        b, r = mj.base_dofs, mj.dof_index
        self._rr, self._rb, self._bb, self._br = np.ix_(r, r), np.ix_(r, b), np.ix_(b, b), np.ix_(b, r)
        self.active = bool(self.base is not None or torques is not None or loads is not None or ctrl is not None)
        self.calls = 0

    def __call__(self, m, d):
        if d is not self.d:  # the callback is global: leave other MjData alone
            return
        self.calls += 1
        self.apply(d)

    def installed(self):
        """Context in which this is MuJoCo's control callback (restored afterwards)."""
        return _Installed(self)

    def apply(self, d) -> None:
        mj = self.mj
        t = float(d.time)
        d.qfrc_applied[:] = 0.0
        d.xfrc_applied[:] = 0.0
        if self.torques is not None:
            tau = np.asarray(self.torques(t), float)
            if tau.shape != (self.n,):
                raise ValueError(f"torques(t) must return shape ({self.n},), got {tau.shape}")
            d.qfrc_applied[mj.dof_index] += tau
        if self.ctrl is not None:
            d.ctrl[:] = np.asarray(self.ctrl(t), float)
        if self.loads is not None:
            self._apply_loads(d, t)
        if self.base is not None:
            if self.ctrl is not None:       # MuJoCo computes qfrc_actuator after this callback: now, for the base
                mujoco.mj_fwdActuation(self.m, d)
            self._prescribe_base(d, t)

    def _apply_loads(self, d, t) -> None:
        mj, tree = self.mj, self.mj.source.tree
        for w in self.loads(t):
            if isinstance(w, Wrench):
                p, force, moment, point, frame = tree.link_index(w.link), w.force, w.moment, w.point, w.frame
            else:
                p, force, moment, point, frame = w
            T = mj.link_pose(d, int(p))
            R = T[:3, :3]
            F = np.asarray(force, float)
            Mo = np.asarray(moment, float)
            if frame == "link":
                F, Mo = R @ F, R @ Mo
            elif frame != "world":
                raise ValueError(f"load frame must be 'link' or 'world', got {frame!r}")
            x = T[:3, 3] + R @ np.asarray(point, float)
            b = int(mj.body_of_link[p])
            if b >= 0:
                d.xfrc_applied[b, :3] += F
                d.xfrc_applied[b, 3:] += Mo + np.cross(x - d.xipos[b], F)
            else:  # folded massless link: its host body's Jacobian, on the dofs that move the link
                hb = int(mj.host_body[p])
                mujoco.mj_jac(self.m, d, self._jacp, self._jacr, x, hb)
                dofs = self._moving_dofs[p]
                d.qfrc_applied[dofs] += self._jacp[:, dofs].T @ F + self._jacr[:, dofs].T @ Mo

    def _prescribe_base(self, d, t) -> None:
        m, mj = self.m, self.mj
        a_b = np.asarray(self.base(t).accel, float)
        M = self._M
        mujoco.mj_fullM(m, d, M)
        # every generalized force except the bias and the base's own qfrc_applied
        f = d.qfrc_applied + d.qfrc_passive + d.qfrc_actuator
        if self.loads is not None:
            fx = self._fx
            fx[:] = 0.0
            for body in np.nonzero(np.any(d.xfrc_applied != 0.0, axis=1))[0]:
                mujoco.mj_applyFT(m, d, np.array(d.xfrc_applied[body, :3]), np.array(d.xfrc_applied[body, 3:]),
                                  np.array(d.xipos[body]), int(body), fx)
            f += fx
        rhs = f - d.qfrc_bias
        b, r = mj.base_dofs, mj.dof_index
        if r.size:
            a_r = np.linalg.solve(M[self._rr], rhs[r] - M[self._rb] @ a_b)
            d.qfrc_applied[b] += M[self._bb] @ a_b + M[self._br] @ a_r - rhs[b]
        else:
            d.qfrc_applied[b] += M[self._bb] @ a_b - rhs[b]


_HELD = BaseState.fixed()


class _Installed:
    """Context manager: install the driver as MuJoCo's control callback, always restore."""

    def __init__(self, driver: PythonInputs):
        self.driver = driver
        self.previous = None

    def __enter__(self):
        if self.driver.active:
            self.previous = mujoco.get_mjcb_control()
            mujoco.set_mjcb_control(self.driver)
        return self

    def __exit__(self, *exc):
        if self.driver.active:
            mujoco.set_mjcb_control(self.previous)
        return False


# --------------------------------------------------------------------------- public


def mujoco_accelerations(mj: MjcfModel, q, qd, *, t: float = 0.0, base=None, tau=None,
                         loads: Iterable = ()) -> np.ndarray:
    """MuJoCo's ``qacc`` (n,) of the robot's coordinates at one state, in the project's order.

    ``base``: a :class:`BaseState` (or callable ``t -> BaseState``) imposed on ``base_A`` exactly as
    in :func:`run_mujoco` (pose, rate and acceleration); ``tau`` (n,) joint forces; ``loads``
    :class:`~urdf2links.dynamics.loads.Wrench` objects or ``(link index, force, moment, point, frame)``.
    Compare with ``model.forward_dynamics(q, qd, tau, loads=..., t=t, base=base)``.
    """
    m = mj.model
    d = mujoco.MjData(m)
    d.time = float(t)
    fn = _as_base_fn(base)
    mj.set_state(d, q, qd, base=None if fn is None else fn(float(t)))
    loads = list(loads)
    tau_a = None if tau is None else np.asarray(tau, float)
    driver = PythonInputs(mj, m, d, base=fn, torques=None if tau_a is None else (lambda _t: tau_a),
                          loads=(lambda _t: loads) if loads else None)
    with driver.installed():
        mujoco.mj_forward(m, d)
    return np.array(d.qacc[mj.dof_index])


def robot_energy(mj: MjcfModel, m, d) -> tuple[float, float]:
    """``(E, V)`` of the robot in {0} from MuJoCo's ``d.energy`` (``mjENBL_ENERGY``), without the
    ``base_A`` body's own energies."""
    pot, kin = float(d.energy[0]), float(d.energy[1])  # MuJoCo's order: potential, kinetic
    if mj.moving_base:  # remove base_A's own energies
        b = mj.base_body
        mass = float(m.body_mass[b])
        vel = np.zeros(6)
        mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_BODY, b, vel, 1)  # local: (rot, lin) at COM
        I = np.asarray(m.body_inertia[b])
        kin -= 0.5 * mass * float(vel[3:] @ vel[3:]) + 0.5 * float(vel[:3] @ (I * vel[:3]))
        pot += mass * float(m.opt.gravity @ d.xipos[b])
    return kin, pot


def run_mujoco(mj: MjcfModel, scene=None, *, q0=None, qd0=None, t_end: float | None = None,
               timestep: float | None = None, integrator: str | None = None, samples: int | None = None,
               base=None, torques: Callable | None = None, loads: Callable | None = None,
               inputs: str = "compiled", ctrl: Callable | None = None) -> MujocoRun:
    """Integrate the route-1 model in MuJoCo and sample the trajectory (see module doc).

    Parameters
    ----------
    mj : MjcfModel from :func:`urdf2links.compare.mujoco_side.mjcf.mjcf_from_model` (or ``mjcf_from_scene``).
    scene : optional :class:`urdf2links.scenes.scene.Scene` or its compiled
        :class:`~urdf2links.scenes.plan.Plan` (then nothing is compiled again): supplies the initial state, ``t_end``,
        ``samples``, the base motion, joint torques and loads (through
        :func:`urdf2links.scenes.plan.compile_plan`) unless given explicitly here. Its gravity and springs
        must be the ones ``mj`` was built with (ValueError otherwise).
    q0, qd0 : (n,) initial state in the project's order (default: the scene's, else zeros).
    t_end, samples : run length (s) and number of samples (default the scene's, else 1 s, 101).
    timestep, integrator : override ``mj``'s (the model is copied; ``mj`` is not changed).
    base : BaseState or callable ``t -> BaseState`` of {A}; needs ``moving_base=True``.
    torques : callable ``t -> (n,)`` generalized joint forces.
    loads : callable ``t -> iterable`` of Wrench or ``(tree link index, force, moment, point, frame)``.
    ctrl : callable ``t -> (nu,)``: the actuators' controls (``d.ctrl``; MuJoCo applies its own law).
    inputs : ``"compiled"`` (the scene's inputs from the compiled callback) or ``"python"`` (the
        Python callback). Inputs given as callables (``base``, ``torques``, ``loads``, ``ctrl``) always run
        the Python callback (``notes`` says so). A scene's computed torque (E57) is the project's, applied
        through ``qfrc_applied`` at every stage (:mod:`urdf2links.compare.mujoco_side.mujoco_inputs`).
    """
    start = _clock()
    if inputs not in INPUTS:
        raise ValueError(f"inputs must be one of {INPUTS}, got {inputs!r}")
    notes: list[str] = []
    explicit = base is not None or torques is not None or loads is not None or ctrl is not None
    plan = None
    if scene is not None:
        plan, q0, qd0, t_end, samples, base, torques, loads, ctrl = _scene_inputs(mj, scene, q0, qd0, t_end, samples,
                                                                                  base, torques, loads, ctrl)
    n = mj.n
    q0 = np.zeros(n) if q0 is None else np.asarray(q0, float)
    qd0 = np.zeros(n) if qd0 is None else np.asarray(qd0, float)
    t_end = 1.0 if t_end is None else float(t_end)
    samples = 101 if samples is None else int(samples)
    if samples < 1 or not t_end >= 0:
        raise ValueError(f"need samples >= 1 and t_end >= 0, got {samples}, {t_end}")
    m, integ = _configured(mj, timestep, integrator, energy=False)
    dt = float(m.opt.timestep)
    t_req = np.linspace(0.0, t_end, samples)
    ks = np.rint(t_req / dt).astype(np.int64)
    offset = float(np.max(np.abs(ks * dt - t_req)))
    if offset > 1e-9 * dt:
        notes.append(f"timestep {dt:g} s does not divide the sample interval: samples taken at the nearest "
                     f"steps (largest offset {offset:.3g} s); MujocoRun.t holds the actual times")
    d = mujoco.MjData(m)
    base_fn = _as_base_fn(base)
    if mj.moving_base and base_fn is None:
        notes.append("the model has a base_A body but no base motion was given: base held at the origin")
        base_fn = _as_base_fn(_HELD)
    mj.set_state(d, q0, qd0, base=base_fn(0.0) if base_fn is not None else None)
    if mj.moving_base and integ not in ("RK4",):
        notes.append(f"integrator {integ}: the prescribed base is exact only when nothing changes the "
                     "acceleration after the control callback (RK4; Euler without dampers)")
    note = implicit_note(integ, m)
    if note:
        notes.append(note)
    driver = _inputs(mj, m, d, plan, inputs, explicit, base_fn, torques, loads, ctrl, notes)
    rec, wall = step_samples(m, d, driver, ks)
    blow_ups = blow_up_counts(d)
    if blow_ups:
        notes.append(instability_note(blow_ups, integ, dt))
        rec["t"] = ks * dt   # MuJoCo's reset also set d.time back to 0: the samples' times are the steps'
    out = _recorded(mj, m, rec, base_fn)
    if not np.all(np.isfinite(out["q"])):
        notes.append("MuJoCo's state became non-finite")
    used = "none" if driver is None else ("compiled" if isinstance(driver, CompiledInputs) else "python")
    return MujocoRun(t=rec["t"], q=out["q"], qd=out["qd"], energy=out["energy"], base_tracking_error=out["track"],
                     wall_time=wall, nsteps=int(ks[-1]), timestep=dt, integrator=integ, blow_ups=blow_ups,
                     coordinate_names=mj.coordinate_names, base_pose=out["base"], notes=notes,
                     harness_time=_clock() - start, inputs=used,
                     callback_calls=0 if driver is None else int(driver.calls),
                     compilation=driver.compilation if isinstance(driver, CompiledInputs) else Compilation())


def _inputs(mj, m, d, plan, inputs, explicit, base_fn, torques, loads, ctrl, notes):
    """The run's control callback: None without inputs, the compiled one for a scene's inputs,
    else the Python one."""
    contact = plan is not None and "contact" in plan.terms         # issue 37: the law runs in the compiled callback
    if contact and (inputs != "compiled" or explicit):
        raise ValueError(f"{plan.scene.name}: a [[contact]] scene runs its contact law in the compiled control callback "
                         "(inputs='compiled', the scene's own inputs); got inputs=" + repr(inputs)
                         + (" and inputs given as callables" if explicit else ""))
    if base_fn is None and torques is None and loads is None and ctrl is None and not contact:
        return None
    if inputs == "compiled" and plan is not None and not explicit:
        return CompiledInputs(mj, plan, m, d)
    if inputs == "compiled":
        notes.append("inputs given as Python callables: MuJoCo is driven from the Python control callback at every "
                     "stage (its wall time includes that harness)")
    return PythonInputs(mj, m, d, base=base_fn, torques=torques, loads=loads, ctrl=ctrl)


def _scene_inputs(mj, scene, q0, qd0, t_end, samples, base, torques, loads, ctrl):
    """The scene's plan, and what the scene supplies where the caller gave nothing: initial state,
    run length, samples, base motion, joint torques (with the computed torque), loads (without the
    gravcomp route 1 wrote into its bodies) and the actuators' controls (through the scene's plan)."""
    from urdf2links.scenes.plan import Plan, compile_plan

    plan = scene if isinstance(scene, Plan) else None     # a compiled run passed down is not compiled again
    scene = plan.scene if plan is not None else scene
    _check_scene(mj, scene)
    plan = plan or compile_plan(scene, mj.source)
    model = plan.model
    sq, sqd = scene.initial_state(model)
    q0 = sq if q0 is None else q0
    qd0 = sqd if qd0 is None else qd0
    t_end = scene.run.t_end if t_end is None else t_end
    samples = scene.run.samples if samples is None else samples
    if base is None and scene.base is not None:
        base = plan.base_state
    if torques is None and (plan.torque_funcs or plan.reference_funcs):
        torques = (lambda t: plan.torques(t) + plan.computed_torque(t)) if plan.reference_funcs else plan.torques
    nl = len(plan.loads) - (plan.n_gravcomp if mj.gravcomp_in_bodies else 0)
    if loads is None and nl:
        loads = plan.wrenches if nl == len(plan.loads) else (lambda t: plan.wrenches(t)[:nl])
    tas = tendon_actuators(plan)    # issue 43: the file's actuators on fixed tendons, after the scene's (with_constraints)
    if ctrl is None and (plan.actuator_set.actuators or tas):
        ctrl = (lambda t: np.r_[plan.ctrl(t), [ta.actuator.ctrl(t) for ta in tas]]) if tas else plan.ctrl
    return plan, q0, qd0, t_end, samples, base, torques, loads, ctrl


def _configured(mj, timestep, integrator, *, energy: bool):
    """A copy of ``mj``'s model with the timestep and integrator asked for and the energy flag on
    or off; the integrator's name."""
    m = copy.deepcopy(mj.model)
    set_stepping(m, timestep=timestep, integrator=integrator)
    integ = integrator_name(m)
    flag = int(mujoco.mjtEnableBit.mjENBL_ENERGY)
    m.opt.enableflags = (m.opt.enableflags | flag) if energy else (m.opt.enableflags & ~flag)
    return m, integ


def _recorded(mj, m, rec, base_fn) -> dict:
    """The project's ``q``, ``qd`` at the recorded states, MuJoCo's energies there (the untimed
    energy pass, see the module doc), the base's pose and its largest tracking error."""
    q, qd = rec["qpos"][:, mj.qpos_index], rec["qvel"][:, mj.dof_index]
    energy = recorded_energies(m, rec, lambda me, de: robot_energy(mj, me, de))
    out = {"q": q, "qd": qd, "energy": energy, "base": None, "track": 0.0}
    if mj.moving_base:
        bp = np.array(rec["qpos"][:, mj.base_qpos])
        want = np.array([np.asarray(base_fn(float(t)).pose, float) for t in rec["t"]])
        out["base"] = bp
        out["track"] = float(np.max(np.abs(bp - want))) if len(bp) else 0.0
    return out


def _check_scene(mj: MjcfModel, scene) -> None:
    g_scene = None if scene.gravity is None else np.asarray(scene.gravity, float)
    if (g_scene is None) != (mj.gravity is None) or (g_scene is not None and not np.allclose(g_scene, mj.gravity, rtol=0, atol=0)):
        raise ValueError(f"the scene's gravity {None if g_scene is None else g_scene.tolist()} is not the MJCF "
                         f"model's {None if mj.gravity is None else mj.gravity.tolist()}: build it with mjcf_from_scene")
    key = lambda s: (s.coordinate, s.stiffness, s.rest, s.damping)  # noqa: E731
    if sorted(map(key, scene.springs_for(mj.source).springs)) != sorted(map(key, mj.springs)):
        raise ValueError("the scene's springs are not the MJCF model's: build it with mjcf_from_scene")
    if (scene.base is not None) and not mj.moving_base:
        raise ValueError("the scene moves the base but the MJCF model has no base_A: build it with mjcf_from_scene")
    on_tendons = tendon_actuator_names(mj.source)   # issue 43: with_constraints writes those (tendon_controls)
    if [a.name for a in mj.actuators] != [a.name for a in scene.actuators if a.name not in on_tendons]:
        raise ValueError("the scene's actuators are not the MJCF model's: build it with mjcf_from_scene")


def energy_function(mj: MjcfModel, run: MujocoRun, plan) -> np.ndarray:
    """MuJoCo's energy function ``h = (E(qd) + E(-qd)) / 2 - 2 E(0) + V`` at its own states, with
    the prescribed base's pose and rate (moving base only)."""
    m = copy.deepcopy(mj.model)
    m.opt.enableflags |= int(mujoco.mjtEnableBit.mjENBL_ENERGY)
    d = mujoco.MjData(m)
    h = np.empty(len(run.t))
    for i, t in enumerate(run.t):
        bs = plan.base_state(float(t))
        kin = []
        for v in (-run.qd[i], np.zeros_like(run.qd[i])):
            mj.set_state(d, run.q[i], v, base=bs)
            mujoco.mj_forward(m, d)
            kin.append(robot_energy(mj, m, d)[0])
        h[i] = 0.5 * (run.kinetic[i] + kin[0]) - 2.0 * kin[1] + run.potential[i]
    return h

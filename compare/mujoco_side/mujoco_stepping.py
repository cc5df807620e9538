"""MuJoCo stepped from sample to sample, as both routes run it: its integrator and timestep, the timed
``mj_step`` calls, its blow-ups and the untimed energy pass over the recorded states.

Route 1 (:func:`~urdf2links.compare.mujoco_side.mujoco_run.run_mujoco`) and route 2 for an MJCF file
(:func:`~urdf2links.compare.mujoco_side.mujoco_mjcf.run_file`) run MuJoCo the same way (the module doc of
:mod:`~urdf2links.compare.mujoco_side.mujoco_run`): ``mujoco.mj_step(m, d, nstep=k)`` from one sample to the
next with the control callback installed (:func:`step_samples`, the time inside ``mj_step`` only), then
MuJoCo's energies at the recorded states with the energy flag on (:func:`recorded_energies`). MuJoCo's
warnings that its state blew up (:func:`blow_up_counts`) and what its integrator treats implicitly
(:func:`implicit_note`) become the run's notes.
"""

from __future__ import annotations

import contextlib
import copy
import time as _time

import mujoco
import numpy as np

from .mjcf import INTEGRATORS
from .mujoco_inputs import CompiledInputs

__all__ = ["INTEGRATOR_ENUM", "set_stepping", "integrator_name", "step_samples", "recorded_energies", "blow_up_counts",
           "instability_note", "implicit_note"]

#: MuJoCo's integrator of each name of :data:`~urdf2links.compare.mujoco_side.mjcf.INTEGRATORS`.
INTEGRATOR_ENUM = {
    "Euler": mujoco.mjtIntegrator.mjINT_EULER,
    "RK4": mujoco.mjtIntegrator.mjINT_RK4,
    "implicit": mujoco.mjtIntegrator.mjINT_IMPLICIT,
    "implicitfast": mujoco.mjtIntegrator.mjINT_IMPLICITFAST,
}


def set_stepping(m, *, timestep: float | None = None, integrator: str | None = None) -> None:
    """Model ``m`` steps with ``timestep`` and ``integrator`` (one of
    :data:`~urdf2links.compare.mujoco_side.mjcf.INTEGRATORS`), each when given."""
    if timestep is not None:
        m.opt.timestep = float(timestep)
    if integrator is not None:
        if integrator not in INTEGRATORS:
            raise ValueError(f"integrator must be one of {INTEGRATORS}, got {integrator!r}")
        m.opt.integrator = int(INTEGRATOR_ENUM[integrator])


def integrator_name(m) -> str:
    """The name of model ``m``'s integrator, spelled as :data:`~urdf2links.compare.mujoco_side.mjcf.INTEGRATORS`."""
    integ = mujoco.mjtIntegrator(int(m.opt.integrator)).name.removeprefix("mjINT_")
    return {"EULER": "Euler", "RK4": "RK4", "IMPLICIT": "implicit", "IMPLICITFAST": "implicitfast"}.get(integ, integ)


def step_samples(m, d, driver, ks):
    """``mj_step(m, d, nstep)`` from sample to sample (the steps ``ks``), the callback installed;
    the recorded ``t``, ``qpos``, ``qvel`` and the time spent inside ``mj_step`` (MuJoCo's engine)."""
    S = len(ks)
    rec = {"t": np.empty(S), "qpos": np.empty((S, m.nq)), "qvel": np.empty((S, m.nv))}
    engine = 0.0
    k_done = 0
    clock = _time.perf_counter    # inside mj_step nothing compiles: the plain clock, cheapest
    with (driver.installed() if driver is not None else contextlib.nullcontext()):
        for j in range(S):
            k = int(ks[j])
            if k > k_done:
                t0 = clock()
                mujoco.mj_step(m, d, nstep=k - k_done)
                engine += clock() - t0
                k_done = k
            rec["t"][j] = d.time
            rec["qpos"][j] = d.qpos
            rec["qvel"][j] = d.qvel
    if isinstance(driver, CompiledInputs):
        driver.check()
    return rec, engine


def recorded_energies(m, rec: dict, energy_of) -> np.ndarray:
    """(samples, 2) ``energy_of(me, de)`` (kinetic, potential) at each recorded state of ``rec`` (``t``, ``qpos``,
    ``qvel``: :func:`step_samples`), from an untimed pass on a copy of ``m`` with the energy flag on
    (``mj_energyPos``, ``mj_energyVel`` after the position and velocity stages)."""
    me = copy.deepcopy(m)
    me.opt.enableflags |= int(mujoco.mjtEnableBit.mjENBL_ENERGY)
    de = mujoco.MjData(me)
    energy = np.empty((len(rec["t"]), 2))
    for j in range(len(rec["t"])):
        de.time = rec["t"][j]
        de.qpos[:] = rec["qpos"][j]
        de.qvel[:] = rec["qvel"][j]
        mujoco.mj_fwdPosition(me, de)
        mujoco.mj_energyPos(me, de)
        mujoco.mj_fwdVelocity(me, de)
        mujoco.mj_energyVel(me, de)
        energy[j] = energy_of(me, de)
    return energy


#: MuJoCo's warnings that its state blew up (it then resets the state: ``mj_checkPos/Vel/Acc``).
_BLOW_UP = ("mjWARN_BADQPOS", "mjWARN_BADQVEL", "mjWARN_BADQACC")


def blow_up_counts(d) -> dict:
    """``{"BADQACC": count, ...}``: how often MuJoCo met NaN, Inf or huge values in the run (each time it
    resets its state: its automatic reset)."""
    counts = {w.removeprefix("mjWARN_"): int(d.warning[int(getattr(mujoco.mjtWarning, w))].number) for w in _BLOW_UP}
    return {w: k for w, k in counts.items() if k}


def instability_note(blow_ups: dict, integ: str, dt: float) -> str:
    """What a run's ``blow_ups`` mean, for the notes."""
    return (f"MuJoCo's simulation became unstable ({', '.join(f'{w} x{k}' for w, k in blow_ups.items())}: NaN, Inf or "
            f"huge values) and it reset its state each time: its trajectory is not a solution from the first reset "
            f"on. {integ} at dt {dt:g} s is likely unstable for this model (stiff: large damping or springs on small "
            f"inertias); a smaller --mujoco-dt or --mujoco-integrator implicit would tell")


def implicit_note(integ: str, m) -> str | None:
    """What MuJoCo's integrator ``integ`` treats implicitly in model ``m``, when that makes its trajectory
    another discretization than the explicit ODE both engines share (None for RK4, or when nothing is):
    Euler takes joint damping (``dof_damping``) implicitly; implicitfast and implicit take the derivative
    of every velocity-dependent force (damping, and the actuators' ``b2 gear^2`` and velocity gains;
    implicit also the Coriolis terms). Their step then converges to the ODE at first order in dt."""
    damped = bool(np.any(m.dof_damping > 0)) and not (m.opt.disableflags & int(mujoco.mjtDisableBit.mjDSBL_DAMPER))
    actuated = m.nu > 0 and not (m.opt.disableflags & int(mujoco.mjtDisableBit.mjDSBL_ACTUATION))
    vel = actuated and bool(np.any(m.actuator_biasprm[:, 2] != 0) or np.any(m.actuator_gainprm[:, 2] != 0))
    if integ == "Euler" and damped:
        return ("MuJoCo's Euler integrates joint damping implicitly ((M + dt D) qacc = f, mj_EulerSkip): a first-order "
                "discretization of the same ODE, converging as dt shrinks; the actuators' velocity terms stay explicit")
    if integ in ("implicit", "implicitfast") and (damped or vel):
        what = ", ".join(w for w, on in (("joint damping", damped), ("the actuators' velocity feedback (kv)", vel)) if on)
        return (f"MuJoCo's {integ} integrates {what} implicitly ((M - dt dF/dqvel) qacc = f): a first-order "
                "discretization of the same ODE, converging as dt shrinks")
    return None

"""The scene's ground contact in MuJoCo's loop: the same law, computed in the compiled control callback (issue 37).

MuJoCo's own contacts are off in route 1 (:mod:`urdf2links.compare.mujoco_side.mjcf`). At every stage of
MuJoCo's integrator the control callback (:func:`urdf2links.compare.mujoco_side.control_callback.control`) calls
:func:`add_contact`: MuJoCo's ``qpos``, ``qvel`` are the project's ``q``, ``q'`` (route 1 writes the same
coordinates, ``qpos_index`` / ``dof_index``), the project's kinematics pass and contact law
(:mod:`urdf2links.scenes.contact_kernels`, docs/equations.md (E77)-(E80)) give the contact's generalized
force ``Q``, and ``Q`` goes into ``qfrc_applied`` (E83). Both engines then integrate the same ODE; what is
compared is the rigid-body dynamics and the integrators under the same contact forces.

:func:`contact_energy` is the contact's elastic energy ``V_c`` (E81) at MuJoCo's states, which MuJoCo's own
energy (``mjENBL_ENERGY``) does not count, so that both energy balances hold the same quantity.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from urdf2links.dynamics.kernels import clear_wrenches, dynamics, kinematics
from urdf2links.dynamics.tree_arrays import W_Q, Tree, nonneg
from urdf2links.scenes.contact_kernels import contact_potential, contact_wrenches
from urdf2links.scenes.scene_inputs import _base_values

__all__ = ["add_contact", "contact_energy", "contact_index", "check_contact_route", "stiffest_mode", "contact_timestep",
           "STEP_LAMBDA"]


@njit(cache=True)
def add_contact(t, TI, TF, W, SI, SF, X, qpos, qvel, index, qfrc):
    """The contact's ``Q`` (E80) at MuJoCo's state added to ``qfrc`` (nv,): coordinate ``i`` is
    ``qpos[index[i]]``, ``qvel[index[n + i]]`` and its force goes to ``qfrc[index[n + i]]``; ``X`` the
    scene's scratch (its first ``2 n`` hold ``(q, q')``, then the base's values)."""
    n, nt = SI[0], SI[1]
    for i in range(n):
        X[i] = qpos[index[i]]
        X[n + i] = qvel[index[n + i]]
    has_base = SI[2] != 0
    xb = 2 * nt
    if has_base:
        _base_values(SI, SF, t, X, xb)
    tree = Tree(TI, TF, W)
    kinematics(tree, X, 0, X, n, True, X, xb, has_base, 0.0, 0.0, 0.0)
    clear_wrenches(tree)
    contact_wrenches(SI, SF, tree)
    dynamics(tree, False, True, False)
    wq = nonneg(TI[W_Q])
    for i in range(n):
        qfrc[index[n + i]] += W[wq + i]


@njit(cache=True)
def _potentials(ts, Q, TI, TF, W, SI, SF, X, out):
    n, nt = SI[0], SI[1]
    has_base = SI[2] != 0
    tree = Tree(TI, TF, W)
    for s in range(ts.size):
        for i in range(n):
            X[i] = Q[s, i]
            X[n + i] = 0.0
        if has_base:
            _base_values(SI, SF, ts[s], X, 2 * nt)
        kinematics(tree, X, 0, X, n, False, X, 2 * nt, has_base, 0.0, 0.0, 0.0)
        out[s] = contact_potential(SI, SF, tree)


def contact_energy(plan, t, q) -> np.ndarray:
    """``V_c`` (m,) (E81) at times ``t`` (m,) and the project's coordinates ``q`` (m, n) (e.g. MuJoCo's states)."""
    t = np.ascontiguousarray(t, float)
    out = np.zeros(t.size)
    if "contact" in plan.terms:
        TI, TF, W, SI, SF, X = plan.rhs.fresh_args()[:6]       # without FX, the effects' markers
        _potentials(t, np.ascontiguousarray(q, float), TI, TF, W, SI, SF, X, out)
    return out


def check_contact_route(plan, mj) -> None:
    """ValueError when the route-1 model cannot carry the scene's contact through the callback."""
    if plan.model.coupling is not None:
        raise ValueError(f"{plan.scene.name}: MuJoCo's run of a [[contact]] scene needs independent coordinates; "
                         f"{plan.model.name!r} has coupled (mimic) ones: load it with mimic='independent'")
    if mj.n != plan.model.n:
        raise ValueError(f"{plan.scene.name}: the MJCF model has {mj.n} coordinates, the scene's {plan.model.n}")


def contact_index(mj, plan) -> np.ndarray:
    """The index array ``(qpos index (n,), dof index (n,))`` of :func:`add_contact` for the route-1 model ``mj``."""
    check_contact_route(plan, mj)
    return np.ascontiguousarray(np.r_[mj.qpos_index, mj.dof_index], dtype=np.int64)


#: MuJoCo's RK4 step for a contact scene keeps ``dt |lambda|max <= STEP_LAMBDA`` (see :func:`contact_timestep`).
STEP_LAMBDA = 1.0


@njit(cache=True)
def _central_jacobian(t, y, h, J, yp, fp, fm, args):
    """``J`` (2n, 2n): central differences ``(F(y + h e_j) - F(y - h e_j)) / 2h`` of ``(q', q'')`` over
    ``(q, q')`` at ``(t, y)`` of the scene's compiled right-hand side (``args``: the scene's ``args``); False
    when an evaluation failed (A not positive definite)."""
    I, F, W, SI, SF, X, rhs = args
    m = J.shape[0]
    for i in range(y.size):
        yp[i] = y[i]
    for j in range(m):
        yp[j] = y[j] + h
        up = rhs(t, yp, fp, I, F, W, SI, SF, X)
        yp[j] = y[j] - h
        down = rhs(t, yp, fm, I, F, W, SI, SF, X)
        yp[j] = y[j]
        if up >= 0 or down >= 0:
            return False
        for i in range(m):
            J[i, j] = (fp[i] - fm[i]) / (2.0 * h)
    return True


def stiffest_mode(plan, t, q, qd, *, h: float = 1e-7) -> float:
    """The largest ``|lambda|`` of the Jacobian of ``(q', q'')`` along the states ``q``, ``qd`` (m, n) at ``t``
    (m,), by central differences of the compiled right-hand side (:func:`_central_jacobian`, in compiled code:
    thousands of evaluations per run): an impact's normal force and the friction's viscous slope
    ``mu f_n / v_s`` on a light foot make it spike (1e5 /s on go1)."""
    n = plan.n
    worst = 0.0
    J = np.zeros((2 * n, 2 * n))
    d = 2 * n + 1
    yp, fp, fm = np.empty(d), np.empty(d), np.empty(d)
    args = plan.rhs.fresh_args()
    for s in range(len(t)):
        y = np.r_[q[s], qd[s], 0.0]
        if not _central_jacobian(float(t[s]), y, h, J, yp, fp, fm, args):
            for j in range(2 * n):          # raises the model's named error where the evaluation failed
                e = np.zeros(d)
                e[j] = h
                plan.rhs(t[s], y + e)
                plan.rhs(t[s], y - e)
        worst = max(worst, float(np.max(np.abs(np.linalg.eigvals(J)))))
    return worst


def contact_timestep(plan, traj, dt: float) -> tuple[float, str | None]:
    """MuJoCo's step for a ``[[contact]]`` scene: ``dt`` halved until ``dt |lambda|max <= STEP_LAMBDA`` along
    the project's run (:func:`stiffest_mode`), so that RK4 resolves the contact's stiff modes (at 1e-4 s it
    may stay stable through a short impact yet land 1e-2 away); ``(dt, note)``, the note None when unchanged."""
    lam = stiffest_mode(plan, traj.t, traj.q, traj.qd)
    k = 0
    while dt / 2 ** k * lam > STEP_LAMBDA and k < 10:
        k += 1
    if k == 0:
        return dt, None
    return dt / 2 ** k, (f"[[contact]]: MuJoCo's step {dt:g} s halved {k} time(s) to {dt / 2 ** k:g} s: the contact's "
                         f"stiffest mode along the project's run is |lambda| = {lam:.3g} /s (impacts, friction's slope "
                         f"mu f_n / v_s on light feet); RK4 resolves it at dt |lambda| <= {STEP_LAMBDA:g}")

"""MuJoCo's control callback, compiled: a scene's time-dependent inputs applied with no Python per stage.

MuJoCo calls ``mjcb_control(m, d)`` inside every ``mj_forward``, after positions and velocities
and before the accelerations: at each of RK4's four stages, with ``d->time`` the stage's time.
:mod:`urdf2links.compare.mujoco_side.mujoco_run` explains what the callback must do (joint torques into
``qfrc_applied``, loads into ``xfrc_applied`` or through the host body's Jacobian, the prescribed
base {A} solved with the mass matrix); its Python :class:`~urdf2links.compare.mujoco_side.mujoco_run.PythonInputs`
does it with numpy and is the oracle this code is tested against (trajectories equal to 1e-12).

Here the same steps are numba code (:func:`control`), installed as a C function pointer through
``mujoco.set_mjcb_control`` (the bindings then call it directly; no Python runs during
``mj_step``). What it reads, all through the header of
:mod:`~urdf2links.compare.mujoco_side.callback_header`:

* the scene's time functions and loads as the project's own right-hand side compiled them
  (:func:`urdf2links.scenes.scene_arrays.compile_scene`, read once per run by
  :class:`~urdf2links.compare.mujoco_side.mujoco_inputs.CompiledInputs` into the flat sections of the
  header; evaluated by :func:`~urdf2links.scenes.scene_inputs.fn_data_eval`), so both engines
  evaluate literally the same functions;
* MuJoCo's arrays of the run's ``MjData`` at the addresses the bindings give, ``d->time`` at its
  checked offset (:mod:`~urdf2links.compare.mujoco_side.mjdata_layout`);
* MuJoCo's ``mj_fullM``, ``mj_applyFT``, ``mj_jac`` and ``mj_fwdActuation``, called through their
  addresses in the bundled ``libmujoco``.

Since issue 26 it also writes the actuators' controls into ``d->ctrl`` (MuJoCo then clamps them and
applies its own law after the callback; with a prescribed base it calls ``mj_fwdActuation`` first, so that
``qfrc_actuator`` is current), adds the scene's computed torque (the project's compiled
:func:`urdf2links.scenes.scene_kernels.computed_torque`, on the project's own arrays, into
``qfrc_applied``) and, for MuJoCo running an MJCF file
(:meth:`~urdf2links.compare.mujoco_side.mujoco_inputs.CompiledInputs.for_file`), the scene's
actuators on ball and free joints' ZYX angles (:func:`_ball_servos`).

The callback (:func:`callback_pointer`, one per combination of the effects it carries: only their code
is compiled) is compiled once and then loaded from numba's disk cache like the project's kernels.
One run is active at a time (MuJoCo's callback is process-global too); the callback leaves any
other ``MjData`` alone. A failed Cholesky factorization of the robot's block of the mass matrix
(prescribed base) is recorded in the header and raised after the step by
:meth:`~urdf2links.compare.mujoco_side.mujoco_inputs.CompiledInputs.check`.
"""

from __future__ import annotations

import numpy as np
from numba import carray, njit, types

from urdf2links.compilation import c_function
from urdf2links.dynamics.factor import cholesky, cholesky_solve
from urdf2links.integration.simulate import Compilation, record_compilation
from urdf2links.dynamics.tree_arrays import Tree
from urdf2links.scenes.scene_arrays import Scene
from urdf2links.scenes.scene_inputs import _actuators
from urdf2links.scenes.scene_kernels import computed_torque, ct_torque_at

from .callback_header import (
    A_F, A_I, ACTIVE, BASE_BODY, CALLS, CONTACT, CT, CTRL, DATA, ERROR, ERROR_COUNT, F_BALL_REF, F_END, F_FBALL,
    F_LOAD_POINT, F_LOAD_X, F_PARAMS, F_SCRATCH, F_YSTATE, FN_APPLYFT, FN_FULLM, FN_FWDACT, FN_JAC, I_ACT_CTRL, I_ACT_FN,
    I_BALL, I_BASE_FN, I_BDOF, I_BODY_OF, I_COORD_DOF, I_COORD_Q, I_COORD_QPOS, I_DOF, I_END, I_HOST, I_LOAD_FN,
    I_LOAD_KIND, I_LOAD_LINK, I_LOAD_LOCAL, I_MOVING, I_PARENT, I_TORQUE_DOF, I_TORQUE_FN, LOAD_SCRATCH, N_CI, N_SF,
    N_SI, NBODY, NCTRL, NHEADER, NL, NQ, NR, NV, P_CI, P_SF, P_SI, PRESCRIBE, QFRC_ACTUATOR, QFRC_APPLIED, QFRC_BIAS,
    QFRC_PASSIVE, QPOS, QVEL, TIME_OFF, XFRC_APPLIED, XIPOS, XMAT, XPOS, address_of, call_applyFT, call_fullM,
    call_fwdActuation, call_jac, float_section, header_symbol_address, int_section, mj_rows, pointer_at, scene_arrays,
    time_fn,
)
from .contact_inputs import add_contact     # issue 37

__all__ = ["control", "callback_pointer", "CALLBACK_EFFECTS"]

_CALLBACKS: dict = {}      # effects -> the compiled C callback (callback_pointer)


# --------------------------------------------------------------------------- the effects


@njit(cache=True)
def _link_pose(p, H, I, F, xpos, xmat, qpos, R, o, Rl):
    """{0}-pose ``(R (3, 3), o (3,))`` of tree link ``p``: its body's ``xmat``/``xpos``, or for a folded
    link (no body) the nearest ancestor with a body (or the base / the world) times ``T~`` of the
    folded links in between at MuJoCo's ``qpos`` (the qpos index of each link's six parameters,
    -1 for a constant one, and the parameters: the tree's)."""
    L = H[NL]
    body_of, parent = int_section(H, I, I_BODY_OF), int_section(H, I, I_PARENT)
    coord_q = int_section(H, I, I_COORD_Q).reshape((L, 6))
    params = float_section(H, F, F_PARAMS).reshape((L, 6))
    chain = np.empty(L, np.int64)
    k = 0
    a = p
    while a >= 0 and body_of[a] < 0:
        chain[k] = a
        k += 1
        a = parent[a]
    b = body_of[a] if a >= 0 else H[BASE_BODY]
    for r in range(3):
        o[r] = xpos[b, r] if b >= 0 else 0.0
        for c in range(3):
            R[r, c] = xmat[b, 3 * r + c] if b >= 0 else (1.0 if r == c else 0.0)
    v = np.empty(6)
    for j in range(k - 1, -1, -1):          # T = T_parent T1 T2 T3 T4 T5 T6 (5.5)
        f = chain[j]
        for s in range(6):
            v[s] = params[f, s] + (qpos[coord_q[f, s]] if coord_q[f, s] >= 0 else 0.0)
        for r in range(3):
            o[r] += R[r, 0] * v[0] + R[r, 1] * v[1] + R[r, 2] * v[2]
        cx, sx, cy, sy, cz, sz = np.cos(v[3]), np.sin(v[3]), np.cos(v[4]), np.sin(v[4]), np.cos(v[5]), np.sin(v[5])
        Rl[0, 0], Rl[0, 1], Rl[0, 2] = cy * cz, -cy * sz, sy          # Rx Ry Rz
        Rl[1, 0], Rl[1, 1], Rl[1, 2] = sx * sy * cz + cx * sz, -sx * sy * sz + cx * cz, -sx * cy
        Rl[2, 0], Rl[2, 1], Rl[2, 2] = -cx * sy * cz + sx * sz, cx * sy * sz + sx * cz, cx * cy
        for r in range(3):
            a0, a1, a2 = R[r, 0], R[r, 1], R[r, 2]
            for c in range(3):
                R[r, c] = a0 * Rl[0, c] + a1 * Rl[1, c] + a2 * Rl[2, c]


@njit(cache=True)
def _apply_loads(m, d, H, I, F, t, xfrc, qfrc):
    """Every load of the scene at ``t`` (see the module doc of mujoco_run): ``xfrc_applied`` of the
    link's body, or the host body's Jacobian on the dofs that move a folded link."""
    L, nv, nb = H[NL], H[NV], H[NBODY]
    xpos, xmat, xipos = mj_rows(H[XPOS], nb, 3), mj_rows(H[XMAT], nb, 9), mj_rows(H[XIPOS], nb, 3)
    qpos = carray(pointer_at(H[QPOS]), H[NQ], np.float64)
    body_of, host = int_section(H, I, I_BODY_OF), int_section(H, I, I_HOST)
    moving = int_section(H, I, I_MOVING).reshape((L, nv))
    link, kind, local = int_section(H, I, I_LOAD_LINK), int_section(H, I, I_LOAD_KIND), int_section(H, I, I_LOAD_LOCAL)
    k = link.size
    fns = int_section(H, I, I_LOAD_FN).reshape((k, 3))
    X = float_section(H, F, F_LOAD_X).reshape((k, 3, 4))
    point = float_section(H, F, F_LOAD_POINT).reshape((k, 3))
    scr = float_section(H, F, F_SCRATCH)
    jacp, jacr = scr[0:3 * nv], scr[3 * nv:6 * nv]
    R, Rl = scr[6 * nv:6 * nv + 9].reshape((3, 3)), scr[6 * nv + 9:6 * nv + 18].reshape((3, 3))
    o, val, pt, x = scr[6 * nv + 18:6 * nv + 21], scr[6 * nv + 21:6 * nv + 24], scr[6 * nv + 24:6 * nv + 27], \
        scr[6 * nv + 27:6 * nv + 30]
    w = scr[6 * nv + 30:6 * nv + LOAD_SCRATCH]
    for li in range(k):
        Xl = X[li]
        loc = local[li] == 1
        f0, f1, f2 = time_fn(H, I, F, fns[li, 0], t, 0), time_fn(H, I, F, fns[li, 1], t, 0), time_fn(H, I, F, fns[li, 2], t, 0)
        for r in range(3):   # URDF link axes -> tree link axes; the point into the tree link frame
            val[r] = (Xl[r, 0] * f0 + Xl[r, 1] * f1 + Xl[r, 2] * f2) if loc else (f0, f1, f2)[r]
            pt[r] = Xl[r, 0] * point[li, 0] + Xl[r, 1] * point[li, 1] + Xl[r, 2] * point[li, 2] + Xl[r, 3]
        p = link[li]
        _link_pose(p, H, I, F, xpos, xmat, qpos, R, o, Rl)
        F0 = F1 = F2 = M0 = M1 = M2 = 0.0
        for r in range(3):
            w[r] = (R[r, 0] * val[0] + R[r, 1] * val[1] + R[r, 2] * val[2]) if loc else val[r]
            x[r] = o[r] + R[r, 0] * pt[0] + R[r, 1] * pt[1] + R[r, 2] * pt[2]
        if kind[li] == 0:
            F0, F1, F2 = w[0], w[1], w[2]
        else:
            M0, M1, M2 = w[0], w[1], w[2]
        b = body_of[p]
        if b >= 0:
            r0, r1, r2 = x[0] - xipos[b, 0], x[1] - xipos[b, 1], x[2] - xipos[b, 2]
            xfrc[b, 0] += F0
            xfrc[b, 1] += F1
            xfrc[b, 2] += F2
            xfrc[b, 3] += M0 + (r1 * F2 - r2 * F1)
            xfrc[b, 4] += M1 + (r2 * F0 - r0 * F2)
            xfrc[b, 5] += M2 + (r0 * F1 - r1 * F0)
        else:   # folded massless link: its host body's Jacobian at the point
            call_jac(H[FN_JAC], address_of(m), address_of(d), jacp.ctypes.data, jacr.ctypes.data, x.ctypes.data,
                      host[p])
            for c in range(nv):
                if moving[p, c]:
                    qfrc[c] += (jacp[c] * F0 + jacp[nv + c] * F1 + jacp[2 * nv + c] * F2
                                + jacr[c] * M0 + jacr[nv + c] * M1 + jacr[2 * nv + c] * M2)


@njit(cache=True)
def _prescribe_base(m, d, H, I, F, t, xfrc, qfrc):
    """``qfrc_applied`` of the base's dofs such that MuJoCo's ``M qacc = f - bias`` gives the base
    its prescribed acceleration ``a_b`` and the robot ``a_r = M_rr^-1 (f_r - bias_r - M_rb a_b)``."""
    nv, n, nb = H[NV], H[NR], H[NBODY]
    dof, bdof, base_fn = int_section(H, I, I_DOF), int_section(H, I, I_BDOF), int_section(H, I, I_BASE_FN)
    scr = float_section(H, F, F_SCRATCH)
    o = 6 * nv + LOAD_SCRATCH
    M = scr[o:o + nv * nv].reshape((nv, nv))
    o += nv * nv
    f, fx, rhs_r, a_r = scr[o:o + nv], scr[o + nv:o + 2 * nv], scr[o + 2 * nv:o + 2 * nv + n], \
        scr[o + 2 * nv + n:o + 2 * nv + 2 * n]
    o += 2 * nv + 2 * n
    Mrr = scr[o:o + n * n].reshape((n, n))          # its factor L follows it in scr
    a_b = scr[o + 2 * n * n:o + 2 * n * n + 6]   # the scene's base motion, or a base held at the origin
    for j in range(6):
        a_b[j] = time_fn(H, I, F, base_fn[j], t, 2) if base_fn[j] >= 0 else 0.0
    call_fullM(H[FN_FULLM], address_of(m), address_of(d), M.ctypes.data)
    passive = carray(pointer_at(H[QFRC_PASSIVE]), nv, np.float64)
    actuator = carray(pointer_at(H[QFRC_ACTUATOR]), nv, np.float64)
    bias = carray(pointer_at(H[QFRC_BIAS]), nv, np.float64)
    for k in range(nv):
        fx[k] = 0.0
    if int_section(H, I, I_LOAD_LINK).size:   # the loads' generalized forces, J^T of every body's xfrc_applied
        for b in range(nb):
            if (xfrc[b, 0] != 0.0 or xfrc[b, 1] != 0.0 or xfrc[b, 2] != 0.0 or xfrc[b, 3] != 0.0
                    or xfrc[b, 4] != 0.0 or xfrc[b, 5] != 0.0):
                row = H[XFRC_APPLIED] + 48 * b
                call_applyFT(H[FN_APPLYFT], address_of(m), address_of(d), row, row + 24, H[XIPOS] + 24 * b, b,
                              fx.ctypes.data)
    for k in range(nv):     # every generalized force except the bias and the base's own qfrc_applied
        f[k] = (qfrc[k] + passive[k] + actuator[k] + fx[k]) - bias[k]
    for i in range(n):
        s = f[dof[i]]
        for j in range(6):
            s -= M[dof[i], bdof[j]] * a_b[j]
        rhs_r[i] = s
        for j in range(n):
            Mrr[i, j] = M[dof[i], dof[j]]
    if n:
        pivot = cholesky(scr, o, n, scr, o + n * n)       # Mrr = L L^T (E46)
        if pivot < 0:
            for i in range(n):
                a_r[i] = rhs_r[i]
            cholesky_solve(scr, o + n * n, n, a_r, 0)
        if pivot >= 0:
            H[ERROR] = pivot + 1
            H[ERROR_COUNT] += 1
            return
    for j in range(6):
        s = 0.0
        for k in range(6):
            s += M[bdof[j], bdof[k]] * a_b[k]
        for i in range(n):
            s += M[bdof[j], dof[i]] * a_r[i]
        qfrc[bdof[j]] += s - f[bdof[j]]


@njit(cache=True)
def _computed_torque(H, I, t, qfrc):
    """The project's computed torque at ``t`` (:func:`urdf2links.scenes.scene_kernels.computed_torque`, on
    the project's own compiled scene and tree arrays, with scratch of its own) into ``qfrc_applied``."""
    TI, TF, W, SI, SF, X = scene_arrays(H)
    computed_torque(t, Tree(TI, TF, W), Scene(SI, SF, X))
    xt = ct_torque_at(SI[0], SI[1])
    dof = int_section(H, I, I_DOF)
    for i in range(SI[0]):
        qfrc[dof[i]] += X[xt + i]


@njit(cache=True)
def _contact(H, t, qfrc):
    """Issue 37: the contact's Q at MuJoCo's state into ``qfrc_applied`` (:func:`contact_inputs.add_contact`)."""
    TI, TF, W, SI, SF, X = scene_arrays(H)
    qpos = carray(pointer_at(H[QPOS]), H[NQ], np.float64)
    qvel = carray(pointer_at(H[QVEL]), H[NV], np.float64)
    index = carray(pointer_at(H[P_CI]), H[N_CI], np.int64)
    add_contact(t, TI, TF, W, SI, SF, X, qpos, qvel, index, qfrc)


@njit(cache=True)
def _ball_servos(H, I, F, t, qfrc):
    """The scene's actuators on the ZYX angles of ball and free joints, for MuJoCo running an MJCF file
    (whose joints carry no such actuator): the project's state from MuJoCo's (hinges and slides as they
    are; a ball's quaternion to its ZYX angles by (E7), on the branch of the angles within pi of their
    reference ``ball_ref`` (their initial value), and its rates ``E(phi)^-1 omega``, E43), the project's
    law there (:func:`urdf2links.scenes.scene_inputs._actuators`, E55), and the torques ``tau`` of the
    angles applied as MuJoCo's generalized forces ``f = E^-T tau`` (``tau = E^T f``: the same power,
    E50); a free joint's translations as they are."""
    SI = carray(pointer_at(H[P_SI]), H[N_SI], np.int64)
    SF = carray(pointer_at(H[P_SF]), H[N_SF], np.float64)
    n = SI[0]
    qpos = carray(pointer_at(H[QPOS]), H[NQ], np.float64)
    qvel = carray(pointer_at(H[QVEL]), H[NV], np.float64)
    y, f, ref = float_section(H, F, F_YSTATE), float_section(H, F, F_FBALL), float_section(H, F, F_BALL_REF)
    cq, cd = int_section(H, I, I_COORD_QPOS), int_section(H, I, I_COORD_DOF)
    balls = int_section(H, I, I_BALL)
    for i in range(n):
        y[i] = qpos[cq[i]] if cq[i] >= 0 else 0.0
        y[n + i] = qvel[cd[i]] if cd[i] >= 0 else 0.0
        f[i] = 0.0
    nb = balls.size // 4
    for b in range(nb):
        kind, qa, da, c0 = balls[4 * b], balls[4 * b + 1], balls[4 * b + 2], balls[4 * b + 3]
        off = 3 if kind == 1 else 0
        for k in range(off):
            y[c0 + k] = qpos[qa + k]
            y[n + c0 + k] = qvel[da + k]
        w, x, yq, z = qpos[qa + off], qpos[qa + off + 1], qpos[qa + off + 2], qpos[qa + off + 3]
        s = 1.0 / np.sqrt(w * w + x * x + yq * yq + z * z)
        w, x, yq, z = w * s, x * s, yq * s, z * s
        r00, r01, r02 = 1 - 2 * (yq * yq + z * z), 2 * (x * yq - w * z), 2 * (x * z + w * yq)
        r12, r22 = 2 * (yq * z - w * x), 1 - 2 * (x * x + yq * yq)
        py = np.arctan2(r02, np.sqrt(r00 * r00 + r01 * r01))
        px, pz = np.arctan2(-r12, r22), np.arctan2(-r01, r00)
        px += 2 * np.pi * np.round((ref[3 * b] - px) / (2 * np.pi))
        pz += 2 * np.pi * np.round((ref[3 * b + 2] - pz) / (2 * np.pi))
        cy, sy, cz, sz = np.cos(py), np.sin(py), np.cos(pz), np.sin(pz)
        o1, o2, o3 = qvel[da + off], qvel[da + off + 1], qvel[da + off + 2]
        dx = (cz * o1 - sz * o2) / cy
        c = c0 + off
        y[c], y[c + 1], y[c + 2] = px, py, pz
        y[n + c], y[n + c + 1], y[n + c + 2] = dx, sz * o1 + cz * o2, o3 - sy * dx
    _actuators(SI, SF, t, y, 0, f, 0)
    for b in range(nb):
        kind, qa, da, c0 = balls[4 * b], balls[4 * b + 1], balls[4 * b + 2], balls[4 * b + 3]
        off = 3 if kind == 1 else 0
        for k in range(off):
            qfrc[da + k] += f[c0 + k]
        c = c0 + off
        py, pz = y[c + 1], y[c + 2]
        cy, sy, cz, sz = np.cos(py), np.sin(py), np.cos(pz), np.sin(pz)
        u = (f[c] - sy * f[c + 2]) / cy
        v = f[c + 1]
        qfrc[da + off] += cz * u + sz * v
        qfrc[da + off + 1] += -sz * u + cz * v
        qfrc[da + off + 2] += f[c + 2]


@njit(inline="always")
def control(m, d, header_address, ct, ball, loads, contact, prescribe):
    """The control callback's work for ``mjData* d`` (see the module doc): clear ``qfrc_applied``
    and ``xfrc_applied``, then joint torques, the actuators' controls (``d->ctrl``), the computed torque,
    loads and the prescribed base at ``d->time``. ``ct`` .. ``prescribe``: the markers of
    :data:`CALLBACK_EFFECTS` (``None``: that code is left out); inlined into each :func:`_callback_of`."""
    H = carray(pointer_at(header_address), NHEADER, np.int64)
    if H[ACTIVE] == 0 or H[DATA] != address_of(d):
        return
    H[CALLS] += 1
    t = carray(pointer_at(H[DATA] + H[TIME_OFF]), 1, np.float64)[0]
    I = carray(pointer_at(H[A_I]), H[I_END], np.int64)
    F = carray(pointer_at(H[A_F]), H[F_END], np.float64)
    nv, nb = H[NV], H[NBODY]
    qfrc = carray(pointer_at(H[QFRC_APPLIED]), nv, np.float64)
    xfrc = mj_rows(H[XFRC_APPLIED], nb, 6)
    for k in range(nv):
        qfrc[k] = 0.0
    for b in range(nb):
        for c in range(6):
            xfrc[b, c] = 0.0
    torque_dof, torque_fn = int_section(H, I, I_TORQUE_DOF), int_section(H, I, I_TORQUE_FN)
    for j in range(torque_dof.size):
        qfrc[torque_dof[j]] += time_fn(H, I, F, torque_fn[j], t, 0)
    act_fn, act_ctrl = int_section(H, I, I_ACT_FN), int_section(H, I, I_ACT_CTRL)
    if act_fn.size:     # the actuators' controls: MuJoCo clamps them and applies its own law
        ctrl = carray(pointer_at(H[CTRL]), H[NCTRL], np.float64)
        for k in range(act_fn.size):
            ctrl[act_ctrl[k]] = time_fn(H, I, F, act_fn[k], t, 0)
    if ct is not None:
        if H[CT]:
            _computed_torque(H, I, t, qfrc)
    if ball is not None:
        if int_section(H, I, I_BALL).size:
            _ball_servos(H, I, F, t, qfrc)
    if loads is not None:
        if int_section(H, I, I_LOAD_LINK).size:
            _apply_loads(m, d, H, I, F, t, xfrc, qfrc)
    if contact is not None:
        if H[CONTACT]:          # issue 37: the scene's contact law on MuJoCo's state (E83)
            _contact(H, t, qfrc)
    if prescribe is not None:
        if H[PRESCRIBE]:
            if act_fn.size:     # qfrc_actuator of these controls (MuJoCo computes it after this callback)
                call_fwdActuation(H[FN_FWDACT], address_of(m), address_of(d))
            _prescribe_base(m, d, H, I, F, t, xfrc, qfrc)


# --------------------------------------------------------------------------- compiled once per combination of effects


#: The effects the callback compiles only for the runs that have them, in the order of ``effects``
#: (:func:`callback_pointer`): the computed torque, ball and free joints' servos, loads, contact, a
#: prescribed base.
CALLBACK_EFFECTS = ("ct", "ball", "loads", "contact", "prescribe")


def _callback_of(ct, ball, loads, contact, prescribe):
    """The C callback of one combination of effects: :func:`control` with its markers fixed (the
    closure's constants: numba leaves out the code behind a None, and caches each combination apart)."""

    def urdf2links_control(m, d):
        control(m, d, header_symbol_address(), ct, ball, loads, contact, prescribe)

    return urdf2links_control


def callback_pointer(effects=(1, 1, 1, 1, 1)):
    """``(pointer, compilation)``: the C callback ``void(const mjModel*, mjData*)`` for
    ``mujoco.set_mjcb_control`` (a ctypes function pointer of a numba ``cfunc`` calling
    :func:`control` on :data:`HEADER`) with the code of ``effects`` only (one marker per
    :data:`CALLBACK_EFFECTS`, ``1`` or ``None``: a run without a computed torque does not compile it,
    issue 32), and the :class:`~urdf2links.integration.simulate.Compilation` of this call: its seconds
    (compiling, or loading from numba's cache; 0.0 after the first call of a process for these effects)
    and the callback's name when it was compiled rather than loaded."""
    effects = tuple(None if e is None else 1 for e in effects)
    done = _CALLBACKS.get(effects)
    if done is not None:
        return done.ctypes, Compilation()
    with record_compilation() as rec:      # c_function: its seconds count as compilation (numba raises no event for it)
        done = _CALLBACKS[effects] = c_function(_callback_of(*effects), types.void(types.voidptr, types.voidptr))
    if done.cache_hits == 0 and not rec.functions:
        named = ", ".join(k for k, e in zip(CALLBACK_EFFECTS, effects) if e is not None) or "none"
        rec.functions.append(f"urdf2links.compare.mujoco_side.control_callback._callback_of (C callback; effects: {named})")
    return done.ctypes, rec

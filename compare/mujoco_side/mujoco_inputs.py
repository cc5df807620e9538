"""A scene's time-dependent inputs applied by a COMPILED MuJoCo control callback: no Python per stage.

MuJoCo calls ``mjcb_control(m, d)`` inside every ``mj_forward``, after positions and velocities
and before the accelerations: at each of RK4's four stages, with ``d->time`` the stage's time.
:mod:`urdf2links.compare.mujoco_side.mujoco_run` explains what the callback must do (joint torques into
``qfrc_applied``, loads into ``xfrc_applied`` or through the host body's Jacobian, the prescribed
base {A} solved with the mass matrix); its Python :class:`~urdf2links.compare.mujoco_side.mujoco_run.PythonInputs`
does it with numpy and is the oracle this module is tested against (trajectories equal to 1e-12).

Here the same steps are numba code (:func:`control`), installed as a C function pointer through
``mujoco.set_mjcb_control`` (the bindings then call it directly; no Python runs during
``mj_step``). What it reads:

* the scene's time functions and loads as the project's own right-hand side compiled them
  (:func:`urdf2links.scenes.scene_arrays.compile_scene`, read once per run by
  :func:`~urdf2links.scenes.scene_arrays.scene_view` into the flat sections :data:`INT_SECTIONS` and
  :data:`FLOAT_SECTIONS`; evaluated by :func:`~urdf2links.scenes.scene_inputs.fn_data_eval`), so both engines
  evaluate literally the same functions;
* MuJoCo's arrays of the run's ``MjData`` (``qfrc_applied``, ``xfrc_applied``, ``xpos``, ``xmat``,
  ``xipos``, ``qfrc_passive``, ``qfrc_actuator``, ``qfrc_bias``, ``qpos``) at the addresses the
  Python bindings give (``d.qfrc_applied.ctypes.data``); ``d->time`` at its offset in ``mjData``,
  derived from MuJoCo's own struct description (``mujoco.introspect``, the field list of
  ``mjdata.h`` in order) laid out by ``ctypes`` and checked at run time against the bindings
  (the pointer fields at their derived offsets must hold the arrays' addresses, ``time`` a written
  sentinel): a disagreement refuses the run with :class:`LayoutError`;
* MuJoCo's ``mj_fullM``, ``mj_applyFT``, ``mj_jac`` and ``mj_fwdActuation``, called through their
  addresses in the bundled ``libmujoco`` (the library the bindings loaded).

Since issue 26 it also writes the actuators' controls into ``d->ctrl`` (MuJoCo then clamps them and
applies its own law after the callback; with a prescribed base it calls ``mj_fwdActuation`` first, so that
``qfrc_actuator`` is current), adds the scene's computed torque (the project's compiled
:func:`urdf2links.scenes.scene_kernels.computed_torque`, on the project's own arrays, into
``qfrc_applied``) and, for MuJoCo running an MJCF file (:meth:`CompiledInputs.for_file`), the scene's
actuators on ball and free joints' ZYX angles (:func:`_ball_servos`).

The callback finds its run through one process-wide header (:data:`HEADER`, int64 slots) whose
address the compiled code takes from an external symbol registered with LLVM's linker, so the
callback (:func:`callback_pointer`, one per combination of the effects it carries: only their code is
compiled) is compiled once and then loaded from numba's disk cache like
the project's kernels.
One run is active at a time (MuJoCo's callback is process-global too); the callback leaves any
other ``MjData`` alone. A failed Cholesky factorization of the robot's block of the mass matrix
(prescribed base) is recorded in the header and raised after the step by :meth:`CompiledInputs.check`.
"""

from __future__ import annotations

import ctypes
import glob
import os

import mujoco
import numpy as np
from llvmlite import binding as llvm
from llvmlite import ir
from numba import carray, njit, types
from numba.extending import intrinsic

from urdf2links.dynamics.factor import cholesky, cholesky_solve
from urdf2links.compilation import c_function
from urdf2links.integration.simulate import Compilation, record_compilation
from urdf2links.dynamics.tree_arrays import Tree
from urdf2links.scenes.scene_arrays import Scene, scene_view
from urdf2links.scenes.scene_inputs import _actuators, fn_data_eval
from urdf2links.scenes.scene_kernels import computed_torque, ct_torque_at

from .contact_inputs import add_contact, contact_index     # issue 37
from .tendon_controls import add_tendon_controls     # issue 43: actuators on fixed tendons

__all__ = ["CompiledInputs", "LayoutError", "mjdata_offsets", "check_offsets", "callback_pointer", "control", "CALLBACK_EFFECTS",
           "HEADER_FIELDS"]


class LayoutError(RuntimeError):
    """The ``mjData`` layout derived from ``mujoco.introspect`` disagrees with the running MuJoCo."""


# --------------------------------------------------------------------------- mjData's layout

_PRIMITIVES = {
    "mjtNum": ctypes.c_double, "double": ctypes.c_double, "float": ctypes.c_float, "int": ctypes.c_int,
    "unsigned int": ctypes.c_uint, "mjtBool": ctypes.c_ubyte, "mjtByte": ctypes.c_ubyte,
    "unsigned char": ctypes.c_ubyte, "char": ctypes.c_char, "mjtSize": ctypes.c_int64, "size_t": ctypes.c_size_t,
    "uintptr_t": ctypes.c_size_t, "int8_t": ctypes.c_int8, "uint8_t": ctypes.c_uint8, "int16_t": ctypes.c_int16,
    "uint16_t": ctypes.c_uint16, "int32_t": ctypes.c_int32, "uint32_t": ctypes.c_uint32,
    "int64_t": ctypes.c_int64, "uint64_t": ctypes.c_uint64,
}
_STRUCTS: dict = {}


def _ctype(t):
    from mujoco.introspect import enums, structs

    kind = type(t).__name__
    if kind == "PointerType":
        return ctypes.c_void_p
    if kind == "ArrayType":
        c = _ctype(t.inner_type)
        for extent in reversed(t.extents):
            c = c * extent
        return c
    name = t.name
    if name in _PRIMITIVES:
        return _PRIMITIVES[name]
    if name in structs.STRUCTS:
        return _struct(name)
    if name in enums.ENUMS:
        return ctypes.c_int
    raise LayoutError(f"mujoco.introspect: type {name!r} of MuJoCo {mujoco.__version__} has no known C layout")


def _struct(name: str):
    """A ``ctypes.Structure`` with the fields of MuJoCo's struct ``name``, in order (C layout rules)."""
    from mujoco.introspect import structs

    if name not in _STRUCTS:
        decl = structs.STRUCTS[name]
        _STRUCTS[name] = type(name, (ctypes.Structure,), {"_fields_": [(f.name, _ctype(f.type)) for f in decl.fields]})
    return _STRUCTS[name]


#: Pointer fields whose derived offsets are checked against the bindings' array addresses.
_CHECKED_POINTERS = ("qpos", "qvel", "qfrc_applied", "xfrc_applied", "xpos", "xmat", "xipos", "qfrc_passive",
                     "qfrc_bias", "qacc")


def mjdata_offsets(d: mujoco.MjData) -> dict[str, int]:
    """Byte offsets in ``mjData`` of ``time`` and the checked pointer fields, derived from
    ``mujoco.introspect`` and verified on ``d`` by :func:`check_offsets`."""
    layout = _struct("mjData")
    return check_offsets(d, {name: getattr(layout, name).offset for name in ("time",) + _CHECKED_POINTERS})


def check_offsets(d: mujoco.MjData, offsets: dict[str, int]) -> dict[str, int]:
    """``offsets`` when they hold on ``d``: each checked pointer field must hold the address of the
    bindings' array, and ``time`` must read back sentinels written through the bindings (``d.time``
    is restored). Raises :class:`LayoutError` naming the field that disagrees."""
    base = d._address
    for name in _CHECKED_POINTERS:
        arr = getattr(d, name)
        if arr.size == 0:
            continue
        found = ctypes.c_void_p.from_address(base + offsets[name]).value
        if found != arr.ctypes.data:
            raise LayoutError(f"mjData.{name}: the offset {offsets[name]} derived from mujoco.introspect (MuJoCo "
                              f"{mujoco.__version__}) holds {found!r}, not the address of d.{name} "
                              f"({arr.ctypes.data}): the compiled control callback cannot be used with this MuJoCo "
                              "(run_mujoco(..., inputs='python') still works)")
    saved = d.time
    try:
        for sentinel in (1234.5678125, -0.001953125):
            d.time = sentinel
            got = ctypes.c_double.from_address(base + offsets["time"]).value
            if got != sentinel:
                raise LayoutError(f"mjData.time: the offset {offsets['time']} derived from mujoco.introspect (MuJoCo "
                                  f"{mujoco.__version__}) reads {got!r} after d.time = {sentinel!r}: the compiled "
                                  "control callback cannot be used with this MuJoCo (run_mujoco(..., inputs='python') "
                                  "still works)")
    finally:
        d.time = saved
    return dict(offsets)


# --------------------------------------------------------------------------- raw pointers in numba

_VOIDP = ir.IntType(8).as_pointer()


@intrinsic
def _voidptr(typingctx, addr):
    """The integer ``addr`` as a ``void*``."""
    def codegen(context, builder, signature, args):
        return builder.inttoptr(args[0], _VOIDP)
    return types.voidptr(types.int64), codegen


@intrinsic
def _address(typingctx, ptr):
    """The address held by a ``void*``, as int64."""
    def codegen(context, builder, signature, args):
        return builder.ptrtoint(args[0], ir.IntType(64))
    return types.int64(types.voidptr), codegen


def _codegen(kinds: str):
    """Code calling ``void f(...)`` at an int64 address with int64 arguments, ``kinds`` one letter
    per argument: ``p`` passed as ``void*``, ``i`` as a C int."""
    def codegen(context, builder, signature, llargs):
        i32 = ir.IntType(32)
        fnty = ir.FunctionType(ir.VoidType(), [_VOIDP if k == "p" else i32 for k in kinds])
        f = builder.inttoptr(llargs[0], fnty.as_pointer())
        builder.call(f, [builder.inttoptr(v, _VOIDP) if k == "p" else builder.trunc(v, i32)
                         for k, v in zip(kinds, llargs[1:])])
        return context.get_dummy_value()
    return codegen


def _signature(k: int):
    return types.void(*([types.int64] * (k + 1)))


@intrinsic
def _call_fullM(typingctx, fn, m, d, dst):
    """``mj_fullM(m, d, dst)`` at address ``fn``."""
    return _signature(3), _codegen("ppp")


@intrinsic
def _call_applyFT(typingctx, fn, m, d, force, torque, point, body, target):
    """``mj_applyFT(m, d, force, torque, point, body, qfrc_target)`` at address ``fn``."""
    return _signature(7), _codegen("pppppip")


@intrinsic
def _call_fwdActuation(typingctx, fn, m, d):
    """``mj_fwdActuation(m, d)`` at address ``fn``."""
    return _signature(2), _codegen("pp")


@intrinsic
def _call_jac(typingctx, fn, m, d, jacp, jacr, point, body):
    """``mj_jac(m, d, jacp, jacr, point, body)`` at address ``fn``."""
    return _signature(6), _codegen("pppppi")


def _libmujoco_functions() -> dict[str, int]:
    """Addresses of the MuJoCo C functions the callback calls, from the bundled library."""
    here = os.path.dirname(mujoco.__file__)
    libs = sorted(glob.glob(os.path.join(here, "libmujoco.so*")) + glob.glob(os.path.join(here, "libmujoco*.dylib"))
                  + glob.glob(os.path.join(here, "mujoco.dll")))
    if not libs:
        raise LayoutError(f"no libmujoco shared library next to {mujoco.__file__}")
    lib = ctypes.CDLL(libs[0])
    return {name: ctypes.cast(getattr(lib, name), ctypes.c_void_p).value
            for name in ("mj_fullM", "mj_applyFT", "mj_jac", "mj_fwdActuation")}


# --------------------------------------------------------------------------- the header

#: The run's integer data (one int64 array), section by section: its start offsets are header slots
#: (a section ends where the next one starts; the slot after the last holds the total).
INT_SECTIONS = ("body_of", "parent", "coord_q", "host", "dof", "bdof", "moving", "base_fn", "torque_dof", "torque_fn",
                "load_link", "load_kind", "load_local", "load_fn", "fn_kind", "fn_ptr", "act_fn", "act_ctrl", "ball",
                "coord_qpos", "coord_dof")
#: The run's float data (one float64 array), likewise; ``scratch`` is the callback's work space.
FLOAT_SECTIONS = ("params", "load_X", "load_point", "fn_data", "scratch", "ball_ref", "ystate", "fball")
#: Slots of :data:`HEADER` (int64): the run the callback acts on.
HEADER_FIELDS = (
    "active", "data", "time_offset", "nv", "nq", "nbody", "n", "L", "base_body", "prescribe",
    "qfrc_applied", "xfrc_applied", "xpos", "xmat", "xipos", "qfrc_passive", "qfrc_actuator", "qfrc_bias", "qpos",
    "fullM", "applyFT", "jac", "I", "F",
    *(f"i_{k}" for k in INT_SECTIONS), "i_end", *(f"f_{k}" for k in FLOAT_SECTIONS), "f_end",
    "calls", "error", "error_count",
    # actuators' controls and the computed torque (issue 26): d->ctrl, and the project's compiled scene
    "ctrl", "nctrl", "fwdActuation", "qvel", "ct", "pTI", "nTI", "pTF", "nTF", "pW", "nW", "pSI", "nSI", "pSF", "nSF", "pX", "nX",
    "contact", "pCI", "nCI",        # issue 37: the scene's contact law (contact_inputs.add_contact), its index array
)
_H = {name: k for k, name in enumerate(HEADER_FIELDS)}
(ACTIVE, DATA, TIME_OFF, NV, NQ, NBODY, NR, NL, BASE_BODY, PRESCRIBE, QFRC_APPLIED, XFRC_APPLIED, XPOS, XMAT, XIPOS,
 QFRC_PASSIVE, QFRC_ACTUATOR, QFRC_BIAS, QPOS, FN_FULLM, FN_APPLYFT, FN_JAC, A_I, A_F) = range(24)
(I_BODY_OF, I_PARENT, I_COORD_Q, I_HOST, I_DOF, I_BDOF, I_MOVING, I_BASE_FN, I_TORQUE_DOF, I_TORQUE_FN, I_LOAD_LINK,
 I_LOAD_KIND, I_LOAD_LOCAL, I_LOAD_FN, I_FN_KIND, I_FN_PTR, I_ACT_FN, I_ACT_CTRL, I_BALL, I_COORD_QPOS, I_COORD_DOF,
 I_END) = range(24, 24 + len(INT_SECTIONS) + 1)
(F_PARAMS, F_LOAD_X, F_LOAD_POINT, F_FN_DATA, F_SCRATCH, F_BALL_REF, F_YSTATE, F_FBALL, F_END) = range(
    I_END + 1, I_END + 1 + len(FLOAT_SECTIONS) + 1)
CALLS, ERROR, ERROR_COUNT = F_END + 1, F_END + 2, F_END + 3
(CTRL, NCTRL, FN_FWDACT, QVEL, CT, P_TI, N_TI, P_TF, N_TF, P_W, N_W, P_SI, N_SI, P_SF, N_SF, P_X, N_X) = range(
    ERROR_COUNT + 1, ERROR_COUNT + 18)
CONTACT, P_CI, N_CI = N_X + 1, N_X + 2, N_X + 3       # issue 37
NHEADER = len(HEADER_FIELDS)
assert HEADER_FIELDS[A_F] == "F" and HEADER_FIELDS[I_END] == "i_end" and HEADER_FIELDS[ERROR_COUNT] == "error_count"
assert HEADER_FIELDS[CTRL] == "ctrl" and HEADER_FIELDS[N_X] == "nX" and NHEADER == N_CI + 1

#: The process-wide header the callback reads. Its address reaches the compiled code as the
#: external symbol :data:`HEADER_SYMBOL`, registered with LLVM's dynamic linker before the callback
#: is loaded, so that the callback's machine code is cached on disk like the project's kernels.
HEADER = np.zeros(NHEADER, dtype=np.int64)
HEADER_SYMBOL = "urdf2links_mjcb_control_header"
llvm.add_symbol(HEADER_SYMBOL, int(HEADER.ctypes.data))
_CALLBACKS: dict = {}      # effects -> the compiled C callback (callback_pointer)


@intrinsic
def _header_address(typingctx):
    """The address of :data:`HEADER` (the external symbol :data:`HEADER_SYMBOL`)."""
    def codegen(context, builder, signature, args):
        gv = builder.module.globals.get(HEADER_SYMBOL)
        if gv is None:
            gv = ir.GlobalVariable(builder.module, ir.IntType(64), name=HEADER_SYMBOL)
            gv.linkage = "external"
        return builder.ptrtoint(gv, ir.IntType(64))
    return types.int64(), codegen


#: The effects the callback compiles only for the runs that have them, in the order of ``effects``
#: (:func:`callback_pointer`): the computed torque, ball and free joints' servos, loads, contact, a
#: prescribed base.
CALLBACK_EFFECTS = ("ct", "ball", "loads", "contact", "prescribe")


def _callback_of(ct, ball, loads, contact, prescribe):
    """The C callback of one combination of effects: :func:`control` with its markers fixed (the
    closure's constants: numba leaves out the code behind a None, and caches each combination apart)."""

    def urdf2links_control(m, d):
        control(m, d, _header_address(), ct, ball, loads, contact, prescribe)

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
        rec.functions.append(f"urdf2links.compare.mujoco_side.mujoco_inputs._callback_of (C callback; effects: {named})")
    return done.ctypes, rec


# --------------------------------------------------------------------------- the callback


_LOAD_SCRATCH = 33      # scratch of the loads beyond the two Jacobians (6 nv): R, Rl (18), o, val, pt, x, w (15)


@njit(cache=True, inline="always")
def _rows(addr, rows, cols):
    return carray(_voidptr(addr), (rows, cols), np.float64)


@njit(cache=True, inline="always")
def _int(H, I, k):
    """Integer section ``k`` (a header slot of :data:`INT_SECTIONS`) of the run's data."""
    return I[H[k]:H[k + 1]]


@njit(cache=True, inline="always")
def _float(H, F, k):
    return F[H[k]:H[k + 1]]


@njit(cache=True, inline="always")
def _fn(H, I, F, j, t, order):
    """d^order f / dt^order at ``t`` of the scene's time function ``j``
    (:func:`urdf2links.scenes.scene_inputs.fn_data_eval` on the data the project's right-hand side uses)."""
    ptr = _int(H, I, I_FN_PTR)
    data = _float(H, F, F_FN_DATA)
    return fn_data_eval(_int(H, I, I_FN_KIND)[j], data, ptr[j], t, order)


@njit(cache=True)
def _link_pose(p, H, I, F, xpos, xmat, qpos, R, o, Rl):
    """{0}-pose ``(R (3, 3), o (3,))`` of tree link ``p``: its body's ``xmat``/``xpos``, or for a folded
    link (no body) the nearest ancestor with a body (or the base / the world) times ``T~`` of the
    folded links in between at MuJoCo's ``qpos`` (the qpos index of each link's six parameters,
    -1 for a constant one, and the parameters: the tree's)."""
    L = H[NL]
    body_of, parent = _int(H, I, I_BODY_OF), _int(H, I, I_PARENT)
    coord_q = _int(H, I, I_COORD_Q).reshape((L, 6))
    params = _float(H, F, F_PARAMS).reshape((L, 6))
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
    xpos, xmat, xipos = _rows(H[XPOS], nb, 3), _rows(H[XMAT], nb, 9), _rows(H[XIPOS], nb, 3)
    qpos = carray(_voidptr(H[QPOS]), H[NQ], np.float64)
    body_of, host = _int(H, I, I_BODY_OF), _int(H, I, I_HOST)
    moving = _int(H, I, I_MOVING).reshape((L, nv))
    link, kind, local = _int(H, I, I_LOAD_LINK), _int(H, I, I_LOAD_KIND), _int(H, I, I_LOAD_LOCAL)
    k = link.size
    fns = _int(H, I, I_LOAD_FN).reshape((k, 3))
    X = _float(H, F, F_LOAD_X).reshape((k, 3, 4))
    point = _float(H, F, F_LOAD_POINT).reshape((k, 3))
    scr = _float(H, F, F_SCRATCH)
    jacp, jacr = scr[0:3 * nv], scr[3 * nv:6 * nv]
    R, Rl = scr[6 * nv:6 * nv + 9].reshape((3, 3)), scr[6 * nv + 9:6 * nv + 18].reshape((3, 3))
    o, val, pt, x = scr[6 * nv + 18:6 * nv + 21], scr[6 * nv + 21:6 * nv + 24], scr[6 * nv + 24:6 * nv + 27], \
        scr[6 * nv + 27:6 * nv + 30]
    w = scr[6 * nv + 30:6 * nv + _LOAD_SCRATCH]
    for li in range(k):
        Xl = X[li]
        loc = local[li] == 1
        f0, f1, f2 = _fn(H, I, F, fns[li, 0], t, 0), _fn(H, I, F, fns[li, 1], t, 0), _fn(H, I, F, fns[li, 2], t, 0)
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
            _call_jac(H[FN_JAC], _address(m), _address(d), jacp.ctypes.data, jacr.ctypes.data, x.ctypes.data,
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
    dof, bdof, base_fn = _int(H, I, I_DOF), _int(H, I, I_BDOF), _int(H, I, I_BASE_FN)
    scr = _float(H, F, F_SCRATCH)
    o = 6 * nv + _LOAD_SCRATCH
    M = scr[o:o + nv * nv].reshape((nv, nv))
    o += nv * nv
    f, fx, rhs_r, a_r = scr[o:o + nv], scr[o + nv:o + 2 * nv], scr[o + 2 * nv:o + 2 * nv + n], \
        scr[o + 2 * nv + n:o + 2 * nv + 2 * n]
    o += 2 * nv + 2 * n
    Mrr = scr[o:o + n * n].reshape((n, n))          # its factor L follows it in scr
    a_b = scr[o + 2 * n * n:o + 2 * n * n + 6]   # the scene's base motion, or a base held at the origin
    for j in range(6):
        a_b[j] = _fn(H, I, F, base_fn[j], t, 2) if base_fn[j] >= 0 else 0.0
    _call_fullM(H[FN_FULLM], _address(m), _address(d), M.ctypes.data)
    passive = carray(_voidptr(H[QFRC_PASSIVE]), nv, np.float64)
    actuator = carray(_voidptr(H[QFRC_ACTUATOR]), nv, np.float64)
    bias = carray(_voidptr(H[QFRC_BIAS]), nv, np.float64)
    for k in range(nv):
        fx[k] = 0.0
    if _int(H, I, I_LOAD_LINK).size:   # the loads' generalized forces, J^T of every body's xfrc_applied
        for b in range(nb):
            if (xfrc[b, 0] != 0.0 or xfrc[b, 1] != 0.0 or xfrc[b, 2] != 0.0 or xfrc[b, 3] != 0.0
                    or xfrc[b, 4] != 0.0 or xfrc[b, 5] != 0.0):
                row = H[XFRC_APPLIED] + 48 * b
                _call_applyFT(H[FN_APPLYFT], _address(m), _address(d), row, row + 24, H[XIPOS] + 24 * b, b,
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


@njit(cache=True, inline="always")
def _scene_arrays(H):
    """The project's compiled scene and tree arrays of this run, with scratch of their own: (TI, TF, W, SI, SF, X)."""
    return (carray(_voidptr(H[P_TI]), H[N_TI], np.int64), carray(_voidptr(H[P_TF]), H[N_TF], np.float64),
            carray(_voidptr(H[P_W]), H[N_W], np.float64), carray(_voidptr(H[P_SI]), H[N_SI], np.int64),
            carray(_voidptr(H[P_SF]), H[N_SF], np.float64), carray(_voidptr(H[P_X]), H[N_X], np.float64))


@njit(cache=True)
def _computed_torque(H, I, t, qfrc):
    """The project's computed torque at ``t`` (:func:`urdf2links.scenes.scene_kernels.computed_torque`, on
    the project's own compiled scene and tree arrays, with scratch of its own) into ``qfrc_applied``."""
    TI, TF, W, SI, SF, X = _scene_arrays(H)
    computed_torque(t, Tree(TI, TF, W), Scene(SI, SF, X))
    xt = ct_torque_at(SI[0], SI[1])
    dof = _int(H, I, I_DOF)
    for i in range(SI[0]):
        qfrc[dof[i]] += X[xt + i]


@njit(cache=True)
def _contact(H, t, qfrc):
    """Issue 37: the contact's Q at MuJoCo's state into ``qfrc_applied`` (:func:`contact_inputs.add_contact`)."""
    TI, TF, W, SI, SF, X = _scene_arrays(H)
    qpos = carray(_voidptr(H[QPOS]), H[NQ], np.float64)
    qvel = carray(_voidptr(H[QVEL]), H[NV], np.float64)
    index = carray(_voidptr(H[P_CI]), H[N_CI], np.int64)
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
    SI = carray(_voidptr(H[P_SI]), H[N_SI], np.int64)
    SF = carray(_voidptr(H[P_SF]), H[N_SF], np.float64)
    n = SI[0]
    qpos = carray(_voidptr(H[QPOS]), H[NQ], np.float64)
    qvel = carray(_voidptr(H[QVEL]), H[NV], np.float64)
    y, f, ref = _float(H, F, F_YSTATE), _float(H, F, F_FBALL), _float(H, F, F_BALL_REF)
    cq, cd = _int(H, I, I_COORD_QPOS), _int(H, I, I_COORD_DOF)
    balls = _int(H, I, I_BALL)
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
    H = carray(_voidptr(header_address), NHEADER, np.int64)
    if H[ACTIVE] == 0 or H[DATA] != _address(d):
        return
    H[CALLS] += 1
    t = carray(_voidptr(H[DATA] + H[TIME_OFF]), 1, np.float64)[0]
    I = carray(_voidptr(H[A_I]), H[I_END], np.int64)
    F = carray(_voidptr(H[A_F]), H[F_END], np.float64)
    nv, nb = H[NV], H[NBODY]
    qfrc = carray(_voidptr(H[QFRC_APPLIED]), nv, np.float64)
    xfrc = _rows(H[XFRC_APPLIED], nb, 6)
    for k in range(nv):
        qfrc[k] = 0.0
    for b in range(nb):
        for c in range(6):
            xfrc[b, c] = 0.0
    torque_dof, torque_fn = _int(H, I, I_TORQUE_DOF), _int(H, I, I_TORQUE_FN)
    for j in range(torque_dof.size):
        qfrc[torque_dof[j]] += _fn(H, I, F, torque_fn[j], t, 0)
    act_fn, act_ctrl = _int(H, I, I_ACT_FN), _int(H, I, I_ACT_CTRL)
    if act_fn.size:     # the actuators' controls: MuJoCo clamps them and applies its own law
        ctrl = carray(_voidptr(H[CTRL]), H[NCTRL], np.float64)
        for k in range(act_fn.size):
            ctrl[act_ctrl[k]] = _fn(H, I, F, act_fn[k], t, 0)
    if ct is not None:
        if H[CT]:
            _computed_torque(H, I, t, qfrc)
    if ball is not None:
        if _int(H, I, I_BALL).size:
            _ball_servos(H, I, F, t, qfrc)
    if loads is not None:
        if _int(H, I, I_LOAD_LINK).size:
            _apply_loads(m, d, H, I, F, t, xfrc, qfrc)
    if contact is not None:
        if H[CONTACT]:          # issue 37: the scene's contact law on MuJoCo's state (E83)
            _contact(H, t, qfrc)
    if prescribe is not None:
        if H[PRESCRIBE]:
            if act_fn.size:     # qfrc_actuator of these controls (MuJoCo computes it after this callback)
                _call_fwdActuation(H[FN_FWDACT], _address(m), _address(d))
            _prescribe_base(m, d, H, I, F, t, xfrc, qfrc)


# --------------------------------------------------------------------------- one run's inputs


class CompiledInputs:
    """The inputs of a compiled plan (:class:`urdf2links.scenes.plan.Plan`) for one ``MjData`` of the
    route-1 model ``mj``: the arrays :func:`control` reads, and :meth:`installed`, the context in
    which MuJoCo's control callback is the compiled one (restored afterwards, also on errors). A
    model with ``base_A`` and a plan without base motion holds the base at the origin.

    ``compilation``: the :class:`~urdf2links.integration.simulate.Compilation` of the callback in this run
    (empty after the first run of a process); ``calls``: callback calls during the last
    installation."""

    def __init__(self, mj, plan, m: mujoco.MjModel, d: mujoco.MjData):
        if plan.base is not None and not mj.moving_base:
            raise ValueError("the scene moves the base but the MJCF model has no base_A: build it with mjcf_from_scene")
        self.mj, self.plan, self.m, self.d = mj, plan, m, d
        offsets = mjdata_offsets(d)
        tree = mj.source.tree
        L, nv, n = tree.n_links, m.nv, mj.n
        sc = scene_view(plan.rhs.SI, plan.rhs.SF)     # the project's compiled inputs, read once per run
        coord_q = np.full((L, 6), -1, dtype=np.int64)
        for p in range(L):
            for k in range(6):
                c = int(tree.coord[p, k])
                if c >= 0:
                    coord_q[p, k] = mj.qpos_index[c]
        moving = np.zeros((L, nv), dtype=np.int64)
        anc = tree.ancestor
        for p in range(L):
            for c in range(tree.n):
                if anc[p, tree.coord_link[c]]:
                    moving[p, mj.dof_index[c]] = 1
            moving[p, mj.base_dofs] = 1
        dof = np.asarray(mj.dof_index, np.int64)
        nl = len(plan.loads) - (plan.n_gravcomp if getattr(mj, "gravcomp_in_bodies", False) else 0)
        ints = {"body_of": mj.body_of_link, "parent": [int(tree.parent[p]) for p in range(L)], "coord_q": coord_q,
                "host": mj.host_body, "dof": dof, "bdof": mj.base_dofs if mj.moving_base else np.zeros(6),
                "moving": moving, "base_fn": sc.base_fn if sc.has_base else np.full(6, -1),
                "torque_dof": dof[sc.torque_idx], "torque_fn": sc.torque_fn, "load_link": sc.load_link[:nl],
                "load_kind": sc.load_kind[:nl], "load_local": sc.load_local[:nl], "load_fn": sc.load_fn[:nl],
                "fn_kind": sc.fn_kind, "fn_ptr": sc.fn_ptr, "act_fn": sc.act_fn,
                "act_ctrl": [int(m.actuator_ctrladr[k]) for k in range(len(sc.act_fn))], "ball": np.zeros(0),
                "coord_qpos": np.zeros(0), "coord_dof": np.zeros(0)}
        floats = {"params": np.asarray(tree.params, float), "load_X": sc.load_X[:nl], "load_point": sc.load_point[:nl],
                  "fn_data": sc.fn_data, "scratch": np.zeros(6 * nv + _LOAD_SCRATCH + nv * nv + 2 * nv + 2 * n + 2 * n * n + 6),
                  "ball_ref": np.zeros(0), "ystate": np.zeros(0), "fball": np.zeros(0)}
        if len(sc.act_fn) + len(add_tendon_controls(plan, m, ints, floats)) != m.nu:     # issue 43: tendons' too
            raise ValueError(f"the MJCF model has {m.nu} actuators, not the scene's: build it with mjcf_from_scene")
        self._build(plan, m, d, ints, floats, offsets, extra={
            "nv": nv, "nq": m.nq, "nbody": m.nbody, "n": n, "L": L, "base_body": mj.base_body,
            "prescribe": int(mj.moving_base)})

    @classmethod
    def for_file(cls, plan, m: mujoco.MjModel, d: mujoco.MjData, actuator_ids):
        """The inputs of MuJoCo running an MJCF file itself (:mod:`urdf2links.compare.mujoco_side.mujoco_mjcf`):
        the actuators' controls, the scene's actuator ``k`` being MuJoCo's actuator ``actuator_ids[k]``, and
        for ``-1`` (an actuator on a ball's or free joint's angles, which no MuJoCo joint actuator carries)
        the project's law applied through ``qfrc_applied`` (:func:`_ball_servos`). No torques, loads, computed
        torque or base: that route does not take them."""
        self = cls.__new__(cls)
        self.mj, self.plan, self.m, self.d = None, plan, m, d
        offsets = mjdata_offsets(d)
        sc = scene_view(plan.rhs.SI, plan.rhs.SF)
        carried = [k for k, a in enumerate(actuator_ids) if a >= 0]
        ints = {k: np.zeros(0) for k in INT_SECTIONS}
        ints.update({"base_fn": np.full(6, -1), "bdof": np.zeros(6), "fn_kind": sc.fn_kind, "fn_ptr": sc.fn_ptr,
                     "act_fn": sc.act_fn[carried], "act_ctrl": [int(m.actuator_ctrladr[actuator_ids[k]]) for k in carried]})
        floats = {"params": np.zeros(0), "load_X": np.zeros(0), "load_point": np.zeros(0), "fn_data": sc.fn_data,
                  "scratch": np.zeros(6 * m.nv + _LOAD_SCRATCH), "ball_ref": np.zeros(0), "ystate": np.zeros(0),
                  "fball": np.zeros(0)}
        if len(carried) < len(actuator_ids):
            model = plan.model
            qmap = model.info["mujoco"]
            q0, _ = plan.scene.initial_state(model)
            need = {a.index for k, a in enumerate(plan.actuator_set.actuators) if actuator_ids[k] < 0}
            balls = [j for j in qmap.joints if j.kind in ("ball", "free") and need & set(j.coordinates)]
            cq, cd = np.full(model.n, -1), np.full(model.n, -1)
            for j in qmap.joints:
                if j.kind in ("hinge", "slide"):
                    cq[j.coordinates[0]], cd[j.coordinates[0]] = j.qposadr, j.dofadr
            ints.update({"ball": [[int(j.kind == "free"), j.qposadr, j.dofadr, j.coordinates[0]] for j in balls],
                         "coord_qpos": cq, "coord_dof": cd})
            floats.update({"ball_ref": [q0[list(j.coordinates)[-3:]] for j in balls], "ystate": np.zeros(2 * model.n),
                           "fball": np.zeros(model.n)})
        add_tendon_controls(plan, m, ints, floats)     # issue 43: the file's actuators on fixed tendons
        self._build(plan, m, d, ints, floats, offsets, file=True, extra=dict(nv=m.nv, nq=m.nq, nbody=m.nbody, n=0, L=0,
                                                                            base_body=-1, prescribe=0))
        return self

    def _build(self, plan, m, d, ints, floats, offsets, *, extra: dict, file: bool = False):
        """The packed arrays and the header of this run (``extra``: its sizes)."""
        self.I, i_at = _packed([ints[k] for k in INT_SECTIONS], np.int64)
        self.F, f_at = _packed([floats[k] for k in FLOAT_SECTIONS], np.float64)
        fns = _libmujoco_functions()
        # the computed torque runs the project's compiled scene in the callback, with scratch of its own
        ct = bool(plan.reference_funcs) and not file
        contact = "contact" in plan.terms and not file      # issue 37
        self.arrays = plan.rhs.fresh_args() if ct or contact or len(ints["ball"]) else ()
        self.contact_index = contact_index(self.mj, plan) if contact else np.zeros(1, np.int64)
        values = {
            "active": 0, "data": d._address, "time_offset": offsets["time"], **extra,
            "qfrc_applied": d.qfrc_applied.ctypes.data, "xfrc_applied": d.xfrc_applied.ctypes.data,
            "xpos": d.xpos.ctypes.data, "xmat": d.xmat.ctypes.data, "xipos": d.xipos.ctypes.data,
            "qfrc_passive": d.qfrc_passive.ctypes.data, "qfrc_actuator": d.qfrc_actuator.ctypes.data,
            "qfrc_bias": d.qfrc_bias.ctypes.data, "qpos": d.qpos.ctypes.data, "fullM": fns["mj_fullM"],
            "applyFT": fns["mj_applyFT"], "jac": fns["mj_jac"], "I": self.I.ctypes.data, "F": self.F.ctypes.data,
            **{f"i_{k}": v for k, v in zip(INT_SECTIONS + ("end",), i_at)},
            **{f"f_{k}": v for k, v in zip(FLOAT_SECTIONS + ("end",), f_at)},
            "calls": 0, "error": 0, "error_count": 0,
            "ctrl": d.ctrl.ctypes.data if d.ctrl.size else 0, "nctrl": int(d.ctrl.size), "ct": int(ct),
            "fwdActuation": fns["mj_fwdActuation"], "qvel": d.qvel.ctypes.data,
            "contact": int(contact), "pCI": self.contact_index.ctypes.data, "nCI": self.contact_index.size,
        }
        for key, arr in zip(("TI", "TF", "W", "SI", "SF", "X"), self.arrays):
            values[f"p{key}"], values[f"n{key}"] = arr.ctypes.data, arr.size
        self.header = np.array([values.get(k, 0) for k in HEADER_FIELDS], dtype=np.int64)
        present = (ct, len(ints["ball"]) > 0, len(ints["load_link"]) > 0, contact, bool(extra["prescribe"]))
        self.effects = tuple(1 if p else None for p in present)     # the callback's (CALLBACK_EFFECTS)
        self.compilation, self.calls = Compilation(), 0

    def installed(self):
        return _Installed(self)

    def check(self) -> None:
        """Raise when the callback failed during the last installation (the robot's block of
        MuJoCo's mass matrix not positive definite while prescribing the base)."""
        if self.header[ERROR]:
            raise FloatingPointError(
                f"MuJoCo control callback: the robot's block of mj_fullM is not positive definite (Cholesky pivot "
                f"{int(self.header[ERROR]) - 1}, {int(self.header[ERROR_COUNT])} time(s)) while prescribing the base "
                f"of {self.plan.model.name!r}")


def _packed(parts, dtype) -> tuple[np.ndarray, list[int]]:
    """The arrays ``parts`` flattened into one, and the start offset of each (then the total)."""
    flat = [np.ascontiguousarray(np.asarray(x, dtype=dtype)).ravel() for x in parts]
    at = np.cumsum([0] + [a.size for a in flat]).tolist()
    return (np.concatenate(flat) if flat else np.zeros(0, dtype)), at


class _Installed:
    """Context: the run's header in :data:`HEADER`, the compiled callback installed; both restored."""

    def __init__(self, inputs: CompiledInputs):
        self.inputs = inputs
        self.previous = None

    def __enter__(self):
        pointer, self.inputs.compilation = callback_pointer(self.inputs.effects)
        if HEADER[ACTIVE]:
            raise RuntimeError("another run's compiled control callback is active in this process")
        HEADER[:] = self.inputs.header
        HEADER[ACTIVE] = 1
        self.previous = mujoco.get_mjcb_control()
        mujoco.set_mjcb_control(pointer)
        return self

    def __exit__(self, *exc):
        mujoco.set_mjcb_control(self.previous)
        self.inputs.header[:] = HEADER
        self.inputs.header[ACTIVE] = 0
        self.inputs.calls = int(HEADER[CALLS])
        HEADER[:] = 0
        return False

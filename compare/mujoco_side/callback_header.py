"""The compiled control callback's view of memory: the process-wide header, the run's packed sections,
MuJoCo's arrays and C functions at raw addresses.

The callback (:mod:`urdf2links.compare.mujoco_side.control_callback`) finds its run through one
process-wide header (:data:`HEADER`, int64 slots :data:`HEADER_FIELDS`) whose address the compiled code
takes from an external symbol registered with LLVM's linker (:func:`header_symbol_address`), so that the
callback is compiled once and then loaded from numba's disk cache like the project's kernels. The header
holds the addresses of MuJoCo's arrays of the run's ``MjData`` (``d.qfrc_applied.ctypes.data``, ...),
of MuJoCo's C functions (:func:`~urdf2links.compare.mujoco_side.mjdata_layout.libmujoco_functions`) and of
the run's data: one int64 and one float64 array, section by section (:data:`INT_SECTIONS`,
:data:`FLOAT_SECTIONS`; filled by :class:`~urdf2links.compare.mujoco_side.mujoco_inputs.CompiledInputs`),
read with :func:`int_section` and :func:`float_section`. Addresses become arrays with numba's
``carray`` on :func:`pointer_at`; MuJoCo's functions are called with the ``call_*`` intrinsics.
"""

from __future__ import annotations

import numpy as np
from llvmlite import binding as llvm
from llvmlite import ir
from numba import carray, njit, types
from numba.extending import intrinsic

from urdf2links.scenes.scene_inputs import fn_data_eval

__all__ = ["INT_SECTIONS", "FLOAT_SECTIONS", "HEADER_FIELDS", "HEADER", "HEADER_SYMBOL", "LOAD_SCRATCH", "pointer_at",
           "address_of", "header_symbol_address", "int_section", "float_section", "time_fn", "scene_arrays", "mj_rows"]


# --------------------------------------------------------------------------- raw pointers in numba

_VOIDP = ir.IntType(8).as_pointer()


@intrinsic
def pointer_at(typingctx, addr):
    """The integer ``addr`` as a ``void*``."""
    def codegen(context, builder, signature, args):
        return builder.inttoptr(args[0], _VOIDP)
    return types.voidptr(types.int64), codegen


@intrinsic
def address_of(typingctx, ptr):
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
def call_fullM(typingctx, fn, m, d, dst):
    """``mj_fullM(m, d, dst)`` at address ``fn``."""
    return _signature(3), _codegen("ppp")


@intrinsic
def call_applyFT(typingctx, fn, m, d, force, torque, point, body, target):
    """``mj_applyFT(m, d, force, torque, point, body, qfrc_target)`` at address ``fn``."""
    return _signature(7), _codegen("pppppip")


@intrinsic
def call_fwdActuation(typingctx, fn, m, d):
    """``mj_fwdActuation(m, d)`` at address ``fn``."""
    return _signature(2), _codegen("pp")


@intrinsic
def call_jac(typingctx, fn, m, d, jacp, jacr, point, body):
    """``mj_jac(m, d, jacp, jacr, point, body)`` at address ``fn``."""
    return _signature(6), _codegen("pppppi")


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


@intrinsic
def header_symbol_address(typingctx):
    """The address of :data:`HEADER` (the external symbol :data:`HEADER_SYMBOL`)."""
    def codegen(context, builder, signature, args):
        gv = builder.module.globals.get(HEADER_SYMBOL)
        if gv is None:
            gv = ir.GlobalVariable(builder.module, ir.IntType(64), name=HEADER_SYMBOL)
            gv.linkage = "external"
        return builder.ptrtoint(gv, ir.IntType(64))
    return types.int64(), codegen


# --------------------------------------------------------------------------- reading the header in compiled code


LOAD_SCRATCH = 33      # scratch of the loads beyond the two Jacobians (6 nv): R, Rl (18), o, val, pt, x, w (15)


@njit(cache=True, inline="always")
def mj_rows(addr, rows, cols):
    return carray(pointer_at(addr), (rows, cols), np.float64)


@njit(cache=True, inline="always")
def int_section(H, I, k):
    """Integer section ``k`` (a header slot of :data:`INT_SECTIONS`) of the run's data."""
    return I[H[k]:H[k + 1]]


@njit(cache=True, inline="always")
def float_section(H, F, k):
    return F[H[k]:H[k + 1]]


@njit(cache=True, inline="always")
def time_fn(H, I, F, j, t, order):
    """d^order f / dt^order at ``t`` of the scene's time function ``j``
    (:func:`urdf2links.scenes.scene_inputs.fn_data_eval` on the data the project's right-hand side uses)."""
    ptr = int_section(H, I, I_FN_PTR)
    data = float_section(H, F, F_FN_DATA)
    return fn_data_eval(int_section(H, I, I_FN_KIND)[j], data, ptr[j], t, order)


@njit(cache=True, inline="always")
def scene_arrays(H):
    """The project's compiled scene and tree arrays of this run, with scratch of their own: (TI, TF, W, SI, SF, X)."""
    return (carray(pointer_at(H[P_TI]), H[N_TI], np.int64), carray(pointer_at(H[P_TF]), H[N_TF], np.float64),
            carray(pointer_at(H[P_W]), H[N_W], np.float64), carray(pointer_at(H[P_SI]), H[N_SI], np.int64),
            carray(pointer_at(H[P_SF]), H[N_SF], np.float64), carray(pointer_at(H[P_X]), H[N_X], np.float64))

"""``mjData``'s layout as the compiled control callback needs it, and the addresses of MuJoCo's C functions.

The callback (:mod:`urdf2links.compare.mujoco_side.control_callback`) reads ``d->time`` at its offset in
``mjData``, derived here from MuJoCo's own struct description (``mujoco.introspect``, the field list of
``mjdata.h`` in order) laid out by ``ctypes`` and checked at run time against the bindings
(:func:`check_offsets`: the pointer fields at their derived offsets must hold the arrays' addresses,
``time`` a written sentinel); a disagreement refuses the run with :class:`LayoutError`. It calls MuJoCo's
``mj_fullM``, ``mj_applyFT``, ``mj_jac`` and ``mj_fwdActuation`` through their addresses in the bundled
``libmujoco`` (the library the bindings loaded, :func:`libmujoco_functions`).
"""

from __future__ import annotations

import ctypes
import glob
import os

import mujoco

__all__ = ["LayoutError", "mjdata_offsets", "check_offsets", "libmujoco_functions"]

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


def libmujoco_functions() -> dict[str, int]:
    """Addresses of the MuJoCo C functions the callback calls, from the bundled library."""
    here = os.path.dirname(mujoco.__file__)
    libs = sorted(glob.glob(os.path.join(here, "libmujoco.so*")) + glob.glob(os.path.join(here, "libmujoco*.dylib"))
                  + glob.glob(os.path.join(here, "mujoco.dll")))
    if not libs:
        raise LayoutError(f"no libmujoco shared library next to {mujoco.__file__}")
    lib = ctypes.CDLL(libs[0])
    return {name: ctypes.cast(getattr(lib, name), ctypes.c_void_p).value
            for name in ("mj_fullM", "mj_applyFT", "mj_jac", "mj_fwdActuation")}

"""A scene's time-dependent inputs for MuJoCo's compiled control callback: one run's tables, installed.

The callback itself (:mod:`urdf2links.compare.mujoco_side.control_callback`) is numba code that reads one
process-wide header (:mod:`urdf2links.compare.mujoco_side.callback_header`). :class:`CompiledInputs` fills
that header's tables for one run of the route-1 model (or, :meth:`CompiledInputs.for_file`, of MuJoCo
running an MJCF file): the scene's time functions, joint torques, loads, actuators' controls and base motion
as the project's own right-hand side compiled them (:func:`urdf2links.scenes.scene_arrays.scene_view`, read
once per run), the tree's links and MuJoCo's bodies, dofs and qpos, packed into one int64 and one float64
array, section by section, and the addresses of the run's ``MjData`` arrays (``mjData``'s layout checked by
:mod:`urdf2links.compare.mujoco_side.mjdata_layout`). :meth:`CompiledInputs.installed` copies them into the
header and installs the callback of the run's effects (compiled once per process, loaded from numba's disk
cache afterwards); the header and MuJoCo's previous callback are restored afterwards, also on errors.
"""

from __future__ import annotations

import mujoco
import numpy as np

from urdf2links.integration.simulate import Compilation
from urdf2links.scenes.scene_arrays import scene_view

from .callback_header import (ACTIVE, CALLS, ERROR, ERROR_COUNT, FLOAT_SECTIONS, HEADER, HEADER_FIELDS, INT_SECTIONS,
                              LOAD_SCRATCH)
from .contact_inputs import contact_index     # issue 37
from .control_callback import callback_pointer
from .mjdata_layout import libmujoco_functions, mjdata_offsets
from .tendon_controls import add_tendon_controls     # issue 43: actuators on fixed tendons

__all__ = ["CompiledInputs"]


class CompiledInputs:
    """The inputs of a compiled plan (:class:`urdf2links.scenes.plan.Plan`) for one ``MjData`` of the
    route-1 model ``mj``: the arrays :func:`~urdf2links.compare.mujoco_side.control_callback.control` reads, and :meth:`installed`, the context in
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
                  "fn_data": sc.fn_data, "scratch": np.zeros(6 * nv + LOAD_SCRATCH + nv * nv + 2 * nv + 2 * n + 2 * n * n + 6),
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
                  "scratch": np.zeros(6 * m.nv + LOAD_SCRATCH), "ball_ref": np.zeros(0), "ystate": np.zeros(0),
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
        fns = libmujoco_functions()
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

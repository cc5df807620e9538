"""MJCF -> tree of links: MuJoCo's own compiler reads the file, this module turns the compiled model into the document's form.

Data flow: the file -> ``mujoco.MjSpec`` (includes, defaults classes, angle units, ``fusestatic``,
inertia from geometry: resolved exactly as MuJoCo resolves them) -> ``mujoco.MjModel`` -> link specs
(frames, coordinates, ``H``, armature) -> :class:`~urdf2links.dynamics.tree.LinkTree` ->
:class:`~urdf2links.dynamics.model.Model`. MuJoCo is imported here, inside the functions only:
``import urdf2links`` never loads it.

Frames (docs/equations.md (E50)). Every MuJoCo body ``b`` lives in a tree link ``t`` at a constant
transform ``X`` (``r_t = X r_b``), like a URDF link (E9, E11). The body's frame starts at its
parent's times ``(body_pos, body_quat)`` (the compiled pose, at ``qpos0``); its joints then act in
order, each in the body's frame as moved by the joints before it (MuJoCo's ``mj_kinematics``):

- hinge about the unit axis ``u`` through the anchor ``a``: ``X Trans(a) Rot(u, q - ref) Trans(-a)``.
  One link with ``T~ = M Rz(q - ref)``, ``M = X Trans(a) Ra`` (``Ra e_z = u``, E8): its parameters are
  ``M``'s origin and ZYX angles (E7), with ``-ref`` added to ``phi_z``; the coordinate is MuJoCo's
  qpos. The body continues at ``X = Ra^T Trans(-a)``;
- slide along ``u``: ``X Trans(u (q - ref))``: a link ``Trans(M_o + (q - ref) e_z)`` with ``M = X Ra``
  (after a massless ``<joint>.frame`` carrying ``M`` when it rotates), then ``X = Ra^T``;
- ball about the anchor: ``X Trans(a) R(quat) Trans(-a)``: a link whose three angle slots are the
  coordinates, ``Rx Ry Rz(phi) = R(quat)``, after ``X Trans(a)`` (a massless frame when it rotates),
  then ``X = Trans(-a)``;
- free (top level only): the body's pose is qpos itself: a link with all six slots, under {A}.

A body's ``H`` (E10, from ``body_mass``, ``body_ipos``, ``body_iquat``, ``body_inertia``) is added to its
tree link as ``X H X^T`` (E11); a body without joints is welded into its parent's tree link. Each
link that carries a body's last joint is named after the body; a body with several joints gets
``<body>:<joint>`` links before it. Armature goes on the coordinates (E49); damping, stiffness with
``springref`` and ``gravcomp`` are recorded in ``model.info`` for scenes (effects), limits for
``inspect`` and the limit notes, and :mod:`urdf2links.parsers.mjcf_notes` lists everything else.
"""

from __future__ import annotations

import os
import sys
import tempfile
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from ..dynamics.inertia import pseudo_inertia
from ..dynamics.model import Model
from ..dynamics.rotations import axis_alignment, homogeneous, matrix_to_xyz_angles
from ..dynamics.transforms import PARAMETERS
from ..dynamics.tree import LinkSpec, build_tree
from ..errors import MJCFError
from ..ranges import out_of_range
from .mjcf_constraints import compiled_equalities, equality_rows, tendon_rows
from .mjcf_notes import inventory
from .mjcf_state import MujocoJoint, MujocoMap, quat_to_matrix

__all__ = ["load_mjcf", "load_mjcf_string", "compile_mjcf", "file_equalities", "is_mjcf_path", "MJCF_OPTIONS"]

#: Load options an MJCF file takes (the URDF-only ones are refused by name).
MJCF_OPTIONS = ("inertia", "strict")
_I4 = np.eye(4)
_KINDS = {0: "free", 1: "ball", 2: "slide", 3: "hinge"}     # mjtJoint


def is_mjcf_path(path) -> bool:
    """A path whose suffix says MJCF (``.xml``, ``.mjcf``)."""
    return Path(str(path)).suffix.lower() in (".xml", ".mjcf")


@contextmanager
def _captured(notes: list[str]):
    """What MuJoCo's C code prints (its compiler's warnings, on stdout or stderr) into ``notes``."""
    streams = []
    for fd, stream in ((1, sys.stdout), (2, sys.stderr)):
        try:
            stream.flush()
            streams.append((fd, os.dup(fd)))
        except (OSError, ValueError, AttributeError):
            pass
    with tempfile.TemporaryFile() as tmp:
        for fd, _ in streams:
            os.dup2(tmp.fileno(), fd)
        try:
            yield
        finally:
            for fd, saved in streams:
                os.dup2(saved, fd)
                os.close(saved)
            tmp.seek(0)
            for line in tmp.read().decode("utf-8", "replace").splitlines():
                if line.strip():
                    notes.append(f"MuJoCo said: {line.strip()}")


def compile_mjcf(source, notes: list[str] | None = None, *, edit=None):
    """``(MjModel, source name)`` of an MJCF file (or MJCF text) compiled by MuJoCo; :class:`MJCFError`
    with MuJoCo's own words and the file when it refuses. ``edit(spec)``, when given, changes the
    ``MjSpec`` before it is compiled (MuJoCo's run of a file adds a scene's actuators that way)."""
    import mujoco

    notes = [] if notes is None else notes
    text = isinstance(source, str) and source.lstrip().startswith("<")
    where = "<string>" if text else str(source)
    if not text and not Path(str(source)).is_file():
        raise MJCFError(f"MJCF file {where} does not exist (or is not a file)")
    import warnings

    try:
        with _captured(notes), warnings.catch_warnings(record=True) as said:
            warnings.simplefilter("always")
            spec = mujoco.MjSpec.from_string(source) if text else mujoco.MjSpec.from_file(str(source))
            if edit is not None:
                edit(spec)
            m = spec.compile()
        notes += [f"MuJoCo said: {w.message}" for w in said]
    except (ValueError, RuntimeError, mujoco.FatalError) as err:
        reason = " ".join(str(err).split())
        raise MJCFError(f"{where}: MuJoCo's compiler refused the file: {reason}", problem=reason) from None
    except UnicodeError as err:
        raise MJCFError(f"{where}: not readable text ({err}); an MJCF file is UTF-8 XML") from None
    return m, where



def file_equalities(path) -> list[dict]:
    """The equalities of an MJCF file compiled by MuJoCo alone, no tree built (a pair's files): one row each
    (:func:`~urdf2links.parsers.mjcf_constraints.equality_rows`)."""
    m, _ = compile_mjcf(path)
    return compiled_equalities(m)

def load_mjcf(source, *, inertia: str = "audit", strict: bool = False) -> Model:
    """Load an MJCF file (or MJCF text) as a :class:`~urdf2links.dynamics.model.Model` (module doc).

    ``model.to_mujoco(q, qd)`` / ``model.from_mujoco(qpos, qvel)`` convert states
    (:mod:`urdf2links.parsers.mjcf_state`); ``model.info`` holds ``notes`` (what the tree does not
    use, and what the comparison does about it), ``joints`` (type, coordinates, limits, armature,
    damping, stiffness, springref), ``gravcomp`` (body -> its fraction), ``frame_of`` (body ->
    tree link and ``X``), ``q0`` (MuJoCo's qpos0 in the model's coordinates), ``option`` (gravity,
    timestep, integrator, the ``<flag>`` s the file disables). Gravity is the file's ``<option gravity>``,
    or 0 when its ``<flag gravity="disable"/>``.

    ``inertia``: ``"audit"`` or ``"repair"`` (MuJoCo's compiler has checked every inertia, so nothing
    is found to repair), ``"strict"`` accepted likewise; ``strict``: MuJoCo's reading has nothing
    tolerated to refuse. Both exist so that every command passes its loading options alike.
    """
    if inertia not in ("audit", "strict", "repair"):
        raise ValueError(f"inertia must be one of ('audit', 'strict', 'repair'), got {inertia!r}")
    notes: list[str] = []
    m, where = compile_mjcf(source, notes)
    check_ranges(m, where)
    return _Builder(m, where, notes).model()


#: What :func:`check_ranges` reads from the compiled model: (object, MjModel array, quantity, what it is).
_CHECKED = (("body", "body_pos", "length", "position"), ("body", "body_mass", "mass", "mass"),
            ("body", "body_ipos", "length", "centre of mass"), ("body", "body_inertia", "inertia", "inertia"),
            ("body", "body_gravcomp", "scale", "gravcomp"), ("joint", "jnt_pos", "length", "anchor pos"),
            ("joint", "jnt_stiffness", "damping", "stiffness"), ("joint", "qpos0", "state", "ref / qpos0"),
            ("joint", "qpos_spring", "state", "springref"), ("dof", "dof_armature", "inertia", "armature"),
            ("dof", "dof_damping", "damping", "damping"))


def check_ranges(m, where: str) -> None:
    """Every number of the compiled model the dynamics uses within its physical range
    (:data:`urdf2links.ranges.RANGES`, as for a URDF): an :class:`MJCFError` names the file, the body or
    joint, the attribute, the value and the range. MuJoCo's compiler takes ``pos="1e300 0 0"``; the
    products of the equations of motion would overflow."""
    import mujoco

    for obj, attr, quantity, what in _CHECKED:
        values = np.asarray(getattr(m, attr), float)
        if values.size == 0:
            continue
        rows = values.reshape(values.shape[0], -1)
        for i, row in enumerate(rows):
            for v in row:
                problem = out_of_range(float(v), quantity)
                if problem is None:
                    continue
                if obj == "body":
                    name = f"body {mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, i) or i!r}"
                elif obj == "dof":
                    j = int(m.dof_jntid[i])
                    name = f"joint {mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, j) or j!r}"
                elif attr in ("qpos0", "qpos_spring"):
                    j = int(np.searchsorted(m.jnt_qposadr, i, side="right") - 1)
                    name = f"joint {mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, j) or j!r}"
                else:
                    name = f"joint {mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, i) or i!r}"
                raise MJCFError(f"{where}: {name}: {what} (MuJoCo's compiled {attr}) {problem}; correct the value in "
                                "the file", problem=f"{name}: {what} {problem}")
    for j in range(m.njnt):
        norm = float(np.linalg.norm(m.jnt_axis[j]))
        if int(m.jnt_type[j]) in (2, 3) and not abs(norm - 1.0) < 1e-6:     # slide, hinge: MuJoCo normalised it
            name = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, j) or j
            raise MJCFError(f"{where}: joint {name!r}: its axis has no direction after MuJoCo's compiler normalised it "
                            f"({np.asarray(m.jnt_axis[j]).tolist()}: the file's axis was zero or overflowed); give a "
                            "finite non-zero axis")
    g = np.asarray(m.opt.gravity, float)
    for v in g:
        problem = out_of_range(float(v), "acceleration")
        if problem:
            raise MJCFError(f"{where}: <option gravity>: {problem}; correct the value in the file")


def load_mjcf_string(text: str, **options) -> Model:
    """:func:`load_mjcf` for MJCF text (includes and meshes resolve against the working folder)."""
    if not isinstance(text, str) or not text.lstrip().startswith("<"):
        raise MJCFError("load_mjcf_string needs MJCF text starting with '<'; for a file use load_mjcf(path)")
    return load_mjcf(text, **options)


def _params(F) -> np.ndarray:
    return np.r_[F[:3, 3], matrix_to_xyz_angles(F[:3, :3])]


def _trans(v) -> np.ndarray:
    return homogeneous(np.eye(3), np.asarray(v, float))


class _Builder:
    def __init__(self, m, where: str, notes: list[str]):
        import mujoco

        self.mj, self.m, self.where, self.notes = mujoco, m, where, notes
        self.specs: list[LinkSpec] = []
        self.H: list[np.ndarray] = []
        self.frame_of: dict[str, tuple[int, np.ndarray]] = {}
        self.coord_info: list[dict] = []
        self.joint_rows: list[dict] = []
        self.mj_joints: list[tuple[str, str, int, int, list[str]]] = []
        self.taken: set[str] = set()

    def name(self, obj: str, i: int, fallback: str) -> str:
        return self.mj.mj_id2name(self.m, getattr(self.mj.mjtObj, obj), i) or fallback

    def unique(self, name: str) -> str:
        out = name
        while out in self.taken:
            out += "_"
        self.taken.add(out)
        return out

    def add(self, name, parent, params, coords=None, armature=None) -> int:
        parent_name = None if parent is None else self.specs[parent].name
        self.specs.append(LinkSpec(self.unique(name), parent_name, tuple(float(x) for x in params), coords or {},
                                   None, armature or {}))
        self.H.append(np.zeros((4, 4)))
        return len(self.specs) - 1

    def body_H(self, b: int) -> np.ndarray:
        m = self.m
        return pseudo_inertia(float(m.body_mass[b]), m.body_ipos[b], np.diag(m.body_inertia[b]),
                              rotation=quat_to_matrix(m.body_iquat[b]))

    # -- joints ---------------------------------------------------------------------------------
    def joint(self, j: int, body: str, t, X, last: bool):
        """One MuJoCo joint of ``body`` applied in tree link ``t`` at ``X``: the new ``(t, X)``."""
        m = self.m
        kind = _KINDS[int(m.jnt_type[j])]
        jname = self.name("mjOBJ_JOINT", j, f"{body}:{kind}{j}")
        if not self.name("mjOBJ_JOINT", j, ""):
            self.notes.append(f"joint {j} of body {body!r} has no name: its coordinates are called {jname!r}")
        link = body if last else f"{body}:{jname}"
        a_arm = float(m.dof_armature[m.jnt_dofadr[j]])
        u = np.asarray(m.jnt_axis[j], float)
        a = np.asarray(m.jnt_pos[j], float)
        ref = float(m.qpos0[m.jnt_qposadr[j]]) if kind in ("hinge", "slide") else 0.0
        if kind == "free":
            if t is not None:     # the body's own pos/quat are its qpos0: the free joint's qpos replaces them
                raise MJCFError(f"{self.where}: body {body!r}: free joint {jname!r} below a body that is not the "
                                "world cannot be a tree of links here (MuJoCo allows free joints at the top level only)")
            coords = {s: f"{jname}.{s}" for s in PARAMETERS}
            t = self.add(link, None, np.zeros(6), coords, {s: a_arm for s in PARAMETERS} if a_arm else None)
            names, X = [coords[s] for s in PARAMETERS], _I4
        elif kind == "ball":
            F = X @ _trans(a)
            coords = {s: f"{jname}.{s}" for s in PARAMETERS[3:]}
            arm = {s: a_arm for s in PARAMETERS[3:]} if a_arm else None
            if np.array_equal(F[:3, :3], np.eye(3)):
                t = self.add(link, t, np.r_[F[:3, 3], 0, 0, 0], coords, arm)
            else:
                t = self.add(f"{jname}.frame", t, _params(F))
                self.notes.append(f"ball joint {jname!r}: massless frame {jname + '.frame'!r} added (the joint's "
                                  "constant rotation needs a link of its own: the angles fill the angle slots)")
                t = self.add(link, t, np.zeros(6), coords, arm)
            names, X = [coords[s] for s in PARAMETERS[3:]], _trans(-a)
        else:
            Ra = homogeneous(axis_alignment(u), np.zeros(3))
            arm = {"phi_z" if kind == "hinge" else "z": a_arm} if a_arm else None
            if kind == "hinge":
                params = _params(X @ _trans(a) @ Ra)
                params[5] -= ref
                t = self.add(link, t, params, {"phi_z": jname}, arm)
                X = Ra.T @ _trans(-a)
            else:
                F = X @ Ra
                if np.array_equal(F[:3, :3], np.eye(3)):
                    t = self.add(link, t, np.r_[F[:3, 3], 0, 0, 0] - [0, 0, ref, 0, 0, 0],
                                 {"z": jname}, arm)
                else:
                    t = self.add(f"{jname}.frame", t, _params(F))
                    self.notes.append(f"slide joint {jname!r}: massless frame {jname + '.frame'!r} added so that its "
                                      "translation is along a link axis")
                    t = self.add(link, t, (0, 0, -ref, 0, 0, 0), {"z": jname}, arm)
                X = Ra.T
            names = [jname]
        self.mj_joints.append((jname, kind, int(m.jnt_qposadr[j]), int(m.jnt_dofadr[j]), names))
        self.joint_rows.append(self.joint_row(j, jname, kind, names))
        for k, nm in enumerate(names):
            slot = {"hinge": "phi_z", "slide": "z"}.get(kind) or (PARAMETERS[k] if kind == "free" else PARAMETERS[3 + k])
            self.coord_info.append(dict(name=nm, joint=jname, type=kind, slot=slot, sign=1.0, offset=0.0,
                                        axis=u.tolist() if kind in ("hinge", "slide") else None))
        return t, X

    def joint_row(self, j, jname, kind, names) -> dict:
        m = self.m
        dof = int(m.jnt_dofadr[j])
        limited = bool(m.jnt_limited[j])
        lo, hi = (float(m.jnt_range[j, 0]), float(m.jnt_range[j, 1])) if limited else (None, None)
        padr = int(m.jnt_qposadr[j])
        return {"name": jname, "type": kind, "coordinates": list(names), "lower": lo if kind in ("hinge", "slide") else None,
                "upper": hi, "effort": None, "velocity": None, "damping": float(m.dof_damping[dof]),
                "friction": float(m.dof_frictionloss[dof]), "armature": float(m.dof_armature[dof]),
                "stiffness": float(m.jnt_stiffness[j]),
                "springref": float(m.qpos_spring[padr]) if kind in ("hinge", "slide") else None,
                "ref": float(m.qpos0[padr]) if kind in ("hinge", "slide") else None, "mimic": None,
                "range_note": None if kind in ("hinge", "slide") or not limited else
                f"{kind} joint: range is the largest rotation angle {hi:g} rad"}

    def actuator_rows(self, kinds: dict, joint_coords: dict) -> list[dict]:
        """One dict per ``<actuator>`` of the file, MuJoCo's compiled numbers (a scene names it to set
        its ctrl: :mod:`urdf2links.scenes.actuators`): ``name``, the transmission (``trntype``, ``joint``,
        ``joint_type``, ``coordinates``), the ``general`` law (``gain``, ``bias`` (3,), ``gear``,
        ``ctrlrange``/``forcerange`` or None when not limited), its types, and what the law does not
        model (``delay``, ``damping``, ``armature``, the joint's ``actuatorfrcrange``)."""
        m, mj = self.m, self.mj
        rows = []
        for k in range(m.nu):
            trn = mj.mjtTrn(int(m.actuator_trntype[k])).name.removeprefix("mjTRN_").lower()
            j = int(m.actuator_trnid[k, 0])
            joint = self.name("mjOBJ_JOINT", j, f"joint{j}") if trn in ("joint", "jointinparent") and j >= 0 else None
            jtype = kinds.get(j) if joint else None
            gain, bias = float(m.actuator_gainprm[k, 0]), [float(x) for x in m.actuator_biasprm[k, :3]]
            gaintype = mj.mjtGain(int(m.actuator_gaintype[k])).name.removeprefix("mjGAIN_").lower()
            biastype = mj.mjtBias(int(m.actuator_biastype[k])).name.removeprefix("mjBIAS_").lower()
            if biastype == "none":
                bias = [0.0, 0.0, 0.0]
            kind, kp, kv = "general", None, None
            if gain == 1.0 and bias == [0.0, 0.0, 0.0]:
                kind = "motor"
            elif bias[0] == 0.0 and bias[1] == -gain and bias[2] <= 0.0:
                kind, kp, kv = "position", gain, -bias[2]
            elif bias[:2] == [0.0, 0.0] and bias[2] == -gain:
                kind, kv = "velocity", gain
            pos = self.mj_joints[j][4] if joint and j < len(self.mj_joints) else []
            rows.append({
                "name": self.name("mjOBJ_ACTUATOR", k, ""), "trntype": trn, "joint": joint, "joint_type": jtype,
                "coordinates": list(joint_coords.get(j, pos)) if joint else [], "kind": kind, "kp": kp, "kv": kv,
                "gain": gain, "bias": bias, "gear": float(m.actuator_gear[k, 0]),
                "ctrlrange": [float(x) for x in m.actuator_ctrlrange[k]] if m.actuator_ctrllimited[k] else None,
                "forcerange": [float(x) for x in m.actuator_forcerange[k]] if m.actuator_forcelimited[k] else None,
                "dyntype": mj.mjtDyn(int(m.actuator_dyntype[k])).name.removeprefix("mjDYN_").lower(),
                "gaintype": gaintype, "biastype": biastype,
                "delay": float(getattr(m, "actuator_delay", np.zeros(m.nu))[k]),
                "damping": float(np.ravel(getattr(m, "actuator_damping", np.zeros(m.nu)))[k]),
                "armature": float(np.ravel(getattr(m, "actuator_armature", np.zeros(m.nu)))[k]),
                "joint_actfrcrange": ([float(x) for x in m.jnt_actfrcrange[j]] if joint and m.jnt_actfrclimited[j]
                                      else None)})
        return rows

    # -- bodies ---------------------------------------------------------------------------------
    def build(self):
        m = self.m
        self.frame_of_id = {0: (None, _I4)}
        for b in range(1, m.nbody):
            bname = self.name("mjOBJ_BODY", b, f"body{b}")
            t, X = self.frame_of_id[int(m.body_parentid[b])]
            X = X @ homogeneous(quat_to_matrix(m.body_quat[b]), m.body_pos[b])
            first, count = int(m.body_jntadr[b]), int(m.body_jntnum[b])
            for k in range(count):
                t, X = self.joint(first + k, bname, t, X, last=k == count - 1)
            if t is None:       # welded to the world: a link of its own under {A}, no coordinates
                t = self.add(bname, None, _params(X))
                X = _I4
            self.frame_of_id[b] = (t, X)
            self.frame_of[bname] = (t, X)
            self.H[t] = self.H[t] + X @ self.body_H(b) @ X.T
        if not self.specs:
            raise MJCFError(f"{self.where}: the model has no body besides the world: nothing to simulate")
        specs = [LinkSpec(s.name, s.parent, s.params, s.coordinates, 0.5 * (H + H.T), s.armature)
                 for s, H in zip(self.specs, self.H)]
        try:
            return build_tree(specs)
        except ValueError as err:
            raise MJCFError(f"{self.where}: the tree of links cannot be built: {err}") from err

    def collision_spheres(self) -> list:
        """Issue 37: ``(body, centre in the body frame, radius)`` of every colliding sphere geom and of both
        ends of every colliding capsule geom (``contype`` or ``conaffinity`` non-zero), for ``[[contact]]``."""
        m, mj, out = self.m, self.mj, []
        for g in range(m.ngeom):
            kind = int(m.geom_type[g])
            if kind not in (int(mj.mjtGeom.mjGEOM_SPHERE), int(mj.mjtGeom.mjGEOM_CAPSULE)) or m.geom_bodyid[g] == 0 \
                    or not (m.geom_contype[g] or m.geom_conaffinity[g]):
                continue
            body, pos, r = self.name("mjOBJ_BODY", int(m.geom_bodyid[g]), f"body{int(m.geom_bodyid[g])}"), \
                np.array(m.geom_pos[g], float), float(m.geom_size[g, 0])
            if kind == int(mj.mjtGeom.mjGEOM_SPHERE):
                out.append((body, pos.tolist(), r))
                continue
            R = np.empty(9)
            mj.mju_quat2Mat(R, np.array(m.geom_quat[g], float))
            axis = R.reshape(3, 3)[:, 2] * float(m.geom_size[g, 1])
            out += [(body, (pos + axis).tolist(), r), (body, (pos - axis).tolist(), r)]
        return out

    def floors(self) -> list:
        """Issue 43: every colliding plane geom of the world body (the file's floor): ``{name, height, normal,
        friction}`` (``height`` along the unit ``normal``, ``friction`` its sliding friction), for ``--ground``."""
        m, mj, out = self.m, self.mj, []
        for g in range(m.ngeom):
            if int(m.geom_type[g]) != int(mj.mjtGeom.mjGEOM_PLANE) or m.geom_bodyid[g] != 0 \
                    or not (m.geom_contype[g] or m.geom_conaffinity[g]):
                continue
            R = np.empty(9)
            mj.mju_quat2Mat(R, np.array(m.geom_quat[g], float))
            normal = R.reshape(3, 3)[:, 2]
            out.append({"name": self.name("mjOBJ_GEOM", g, f"geom{g}"), "normal": normal.tolist(),
                        "height": float(normal @ np.array(m.geom_pos[g], float)), "friction": float(m.geom_friction[g, 0])})
        return out

    def model(self) -> Model:
        m, mj = self.m, self.mj
        tree = self.build()
        index = {nm: i for i, nm in enumerate(tree.coordinate_names)}
        joints = tuple(MujocoJoint(n, kind, qa, da, tuple(index[c] for c in names))
                       for n, kind, qa, da, names in self.mj_joints)
        qmap = MujocoMap(joints=joints, n=tree.n, nq=int(m.nq), nv=int(m.nv), qpos0=np.array(m.qpos0, float))
        q0, _ = qmap.from_mujoco(m.qpos0, None)
        keys = [k for k in range(m.nkey) if mj.mj_id2name(m, mj.mjtObj.mjOBJ_KEY, k) == "home"]
        home = qmap.from_mujoco(np.array(m.key_qpos[keys[0]], float), None, reference=q0)[0] if keys else None
        kinds = {j: _KINDS[int(m.jnt_type[j])] for j in range(m.njnt)}
        welded = [self.name("mjOBJ_BODY", b, f"body{b}") for b in range(1, m.nbody) if m.body_jntnum[b] == 0]
        if welded:
            self.notes.append(f"bodies without joints welded to their parent's link: {', '.join(welded[:8])}"
                              + (f", ... ({len(welded)} in all)" if len(welded) > 8 else ""))
        self.notes += inventory(m, kinds)
        integrator = mj.mjtIntegrator(int(m.opt.integrator)).name.removeprefix("mjINT_")
        disabled = [name.removeprefix("mjDSBL_").lower() for name in dir(mj.mjtDisableBit)
                    if name.startswith("mjDSBL_") and int(m.opt.disableflags) & int(getattr(mj.mjtDisableBit, name))]
        gravity = np.zeros(3) if "gravity" in disabled else np.array(m.opt.gravity, float)
        if disabled:
            self.notes.append(f"<option><flag> disables {', '.join(disabled)}: "
                              + ("the model's gravity is 0 (the file's gravity is off); " if "gravity" in disabled else "")
                              + ("its default scene applies no joint stiffness; " if "spring" in disabled else "")
                              + ("its default scene applies no joint damping; " if "damper" in disabled else "")
                              + "a scene's own effects are switched on in MuJoCo's run regardless")
        gravcomp = {self.name("mjOBJ_BODY", b, f"body{b}"): float(m.body_gravcomp[b])
                    for b in range(1, m.nbody) if m.body_gravcomp[b] != 0.0}
        frame_of = {k: (tree.link_names[t], X.tolist()) for k, (t, X) in self.frame_of.items()}
        equalities, eq_notes = equality_rows(self)      # issue 36: read, not dropped (scenes/file_constraints.py)
        tendons, tendon_notes = tendon_rows(self)
        self.notes += eq_notes + tendon_notes
        coms = {self.name("mjOBJ_BODY", b, f"body{b}"): (float(m.body_mass[b]), np.array(m.body_ipos[b]).tolist())
                for b in range(1, m.nbody)}
        info = {"format": "mjcf", "coordinates": self.coord_info, "notes": self.notes, "joints": self.joint_rows,
                "frame_of": frame_of, "equalities": equalities, "tendons": tendons, "mujoco": qmap, "q0": q0, "home": home,
                "closed": {"equalities": int(m.neq), "tendons": int(m.ntendon)}, "gravcomp": gravcomp, "body_mass_com": coms,
                "collision_spheres": self.collision_spheres(),      # issue 37: for [[contact]]
                "floors": self.floors(),        # issue 43: the file's floor, kept by the default scene
                "actuators": self.actuator_rows(kinds, {j: names for j, (_, _, _, _, names) in
                                                        enumerate(self.mj_joints)}),
                "option": {"gravity": gravity.tolist(), "timestep": float(m.opt.timestep), "integrator": integrator,
                           "disabled": disabled},
                "source_file": None if self.where == "<string>" else str(Path(self.where).resolve())}
        try:
            model_name = self.name("mjOBJ_MODEL", 0, "")
        except (AttributeError, TypeError, ValueError):
            model_name = ""
        model_name = model_name or (Path(self.where).stem if self.where != "<string>" else "mjcf")
        return Model(tree, gravity=gravity, name=model_name, source=self.where, info=info)

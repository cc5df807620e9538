"""Route 2 of the MuJoCo comparison: MuJoCo's OWN import of an original URDF file.

The file is handed to MuJoCo's URDF reader (``mujoco.MjSpec.from_string`` on URDF text,
the same reader ``MjModel.from_xml_string`` uses) after three edits that only remove what
we do not compare:

* every ``<visual>`` and ``<collision>`` is deleted (MuJoCo would otherwise need the mesh
  files; geometry plays no part in the terms we compare);
* MuJoCo's URDF extension ``<mujoco><compiler .../></mujoco>`` is inserted (or merged
  into an existing one) with ``discardvisual="true" balanceinertia="false"
  inertiafromgeom="false"`` and the requested ``fusestatic``: MuJoCo must use the file's
  inertias as written, never repair or recompute them;
* for a floating base, a free joint is added to the root body (MuJoCo adds none to a URDF).

After compiling, the physics is cut down to what we compare: the given gravity;
contacts, joint limits, equality constraints (URDF ``<mimic>``), friction loss, springs
and dampers disabled; ``dof_armature``, ``dof_damping``, joint stiffness and gravity
compensation set to zero -- except, with ``damping=True`` (a scene with ``[dampers] from_urdf``),
the dampers MuJoCo read from the URDF's ``<dynamics damping>``: then ``dof_damping`` is kept and
the damper flag stays on.

When MuJoCo refuses a file (a moving link with zero mass, an inertia violating the
triangle inequality, ...) :class:`MujocoRefused` carries MuJoCo's own words.

:func:`mujoco_terms` then evaluates ``M`` (``mj_fullM``) and ``bias`` (``qfrc_bias``,
which is ``e + G`` in the project's notation) at a state given by joint NAME, in the
coordinate order the caller chooses, so that another model can be compared coordinate
by coordinate.  MuJoCo's hinge/slide ``qpos`` is zero at the URDF zero configuration and
has the sign of the URDF axis (checked against yourdfpy in the tests).
"""

from __future__ import annotations

import os
import re
import sys
import tempfile
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Mapping, Sequence

import mujoco
import numpy as np
from lxml import etree

from .mjcf import add_spec_actuators

__all__ = [
    "MujocoRefused",
    "MujocoURDF",
    "Terms",
    "mujoco_from_urdf",
    "mujoco_data_at",
    "mujoco_terms",
    "FREE_DOF_LABELS",
]

#: Names of the six dofs of a MuJoCo free joint, in MuJoCo's order: linear velocity of
#: the body origin in the WORLD frame, then angular velocity in the BODY (local) frame.
FREE_DOF_LABELS = ("vx", "vy", "vz", "wx", "wy", "wz")

#: An XML declaration at the start of a text (dropped before lxml parses the decoded text).
_DECLARATION = re.compile(r"^\ufeff?\s*<\?xml[^>]*\?>")

#: Everything we do not compare, switched off on the compiled model.
_DISABLED = (
    "mjDSBL_CONTACT",
    "mjDSBL_LIMIT",
    "mjDSBL_EQUALITY",
    "mjDSBL_FRICTIONLOSS",
    "mjDSBL_SPRING",  # MuJoCo >= 3.3 splits the former mjDSBL_PASSIVE into SPRING + DAMPER
    "mjDSBL_DAMPER",
)


class MujocoRefused(RuntimeError):
    """MuJoCo's compiler refused to load a URDF file.

    ``reason`` is MuJoCo's own error text; ``source`` names the file (or ``<string>``).
    """

    def __init__(self, source: str, reason: str):
        self.source = source
        self.reason = reason
        super().__init__(f"MuJoCo refused to load URDF {source}: {reason}")


@dataclass(frozen=True)
class MujocoURDF:
    """A URDF compiled by MuJoCo's own importer, ready for term extraction.

    ``joint_names``: the hinge/slide joints, one per dof, in MuJoCo's dof order.
    ``dof_of_joint``: joint name -> dof index (index into ``qvel``/``qfrc_bias``/M).
    ``qpos_of_joint``: joint name -> index into ``qpos``.
    ``free_joint``: name of the added free joint (floating base) or ``None``;
    ``free_dofs``: its 6 dof indices (``FREE_DOF_LABELS`` order), ``free_qpos``: its qpos
    address (position xyz, then quaternion w x y z).
    ``notes``: everything that was changed or is worth knowing about the import.
    """

    model: mujoco.MjModel
    joint_names: tuple[str, ...]
    dof_of_joint: dict[str, int]
    qpos_of_joint: dict[str, int]
    source: str
    notes: list[str] = field(default_factory=list)
    free_joint: str | None = None
    free_dofs: tuple[int, ...] = ()
    free_qpos: int | None = None
    root_body: str | None = None

    @property
    def floating(self) -> bool:
        return self.free_joint is not None


@dataclass(frozen=True)
class Terms:
    """``M`` and ``bias`` (= ``qfrc_bias`` = e + G) at one state, in the order ``names``.

    For a floating base, ``M``/``bias`` are the joint block only; the whole system in
    MuJoCo's dof order is in ``M_full``/``bias_full`` with labels ``dof_labels``
    (the free joint's dofs are labelled ``"<free joint>:vx"`` ... ``":wz"``, see
    :data:`FREE_DOF_LABELS` for their frames).
    """

    names: tuple[str, ...]
    M: np.ndarray
    bias: np.ndarray
    M_full: np.ndarray
    bias_full: np.ndarray
    dof_labels: tuple[str, ...]


# --------------------------------------------------------------------------- loading


def _read(path_or_text) -> tuple[str, str, Path | None]:
    """Return (text, source name, directory of the file or None)."""
    if isinstance(path_or_text, Path):
        p = path_or_text
    elif isinstance(path_or_text, str) and path_or_text.lstrip().startswith("<"):
        return path_or_text, "<string>", None
    elif isinstance(path_or_text, str):
        p = Path(path_or_text)
    else:
        raise TypeError(f"expected a path or URDF text, got {type(path_or_text).__name__}")
    try:
        return p.read_text(encoding="utf-8"), str(p), p.parent.resolve()
    except OSError as err:
        raise FileNotFoundError(f"cannot read URDF file {p}: {err}") from err


def _prepare(text: str, source: str, *, strip_meshes: bool, fusestatic: bool,
             meshdir: Path | None, notes: list[str]) -> tuple[str, list[str]]:
    """Edit the URDF text for MuJoCo; return the new text and the list of link names."""
    parser = etree.XMLParser(remove_comments=True, resolve_entities=False)
    declaration = _DECLARATION.match(text)
    if declaration:  # the text is already decoded; lxml would also refuse an unusual version ("0.0")
        text = text[declaration.end():]
    try:
        root = etree.fromstring(text.encode("utf-8"), parser)
    except etree.XMLSyntaxError as err:
        raise ValueError(f"{source}: not well-formed XML: {err}") from err
    if root.tag != "robot":
        raise ValueError(f"{source}: root element is <{root.tag}>, expected <robot>")
    links = [el.get("name") for el in root.findall("link")]

    if strip_meshes:
        removed = 0
        for el in root.findall("link"):
            for child in el.findall("visual") + el.findall("collision"):
                el.remove(child)
                removed += 1
        notes.append(f"removed {removed} <visual>/<collision> elements (only dynamics is "
                     "compared; MuJoCo would otherwise need the mesh files)")

    ext = root.find("mujoco")
    if ext is None:
        ext = etree.Element("mujoco")
        root.insert(0, ext)
    else:
        notes.append("the file already had a <mujoco> extension; our compiler settings "
                     "override its attributes")
    comp = ext.find("compiler")
    if comp is None:
        comp = etree.SubElement(ext, "compiler")
    settings = {
        "discardvisual": "true" if strip_meshes else "false",
        "fusestatic": "true" if fusestatic else "false",
        "balanceinertia": "false",
        "inertiafromgeom": "false",
        "boundmass": "0",
        "boundinertia": "0",
        "angle": "radian",
    }
    if not strip_meshes and meshdir is not None and comp.get("meshdir") is None:
        settings["meshdir"] = str(meshdir)
    for k, v in settings.items():
        comp.set(k, v)
    notes.append("MuJoCo URDF extension: <compiler " + " ".join(
        f'{k}="{v}"' for k, v in settings.items()) + "/> (the file's inertias are used as "
        "written: no balancing, no bounds, none computed from geometry)")
    return etree.tostring(root, encoding="unicode"), links


@contextmanager
def _mujoco_warnings(notes: list[str]):
    """Collect what MuJoCo's C code writes to file descriptor 2 (its URDF reader's
    warnings, e.g. an ignored <mimic>) into ``notes`` instead of the terminal."""
    try:
        sys.stderr.flush()
        saved = os.dup(2)
    except (OSError, ValueError):  # no usable fd 2: let warnings go where they go
        yield
        return
    with tempfile.TemporaryFile() as tmp:
        os.dup2(tmp.fileno(), 2)
        try:
            yield
        finally:
            try:
                sys.stderr.flush()
            except ValueError:
                pass
            os.dup2(saved, 2)
            os.close(saved)
            tmp.seek(0)
            for line in tmp.read().decode("utf-8", "replace").splitlines():
                if line.strip():
                    notes.append(f"MuJoCo said: {line.strip()}")


def _compile(text: str, source: str, floating_base: bool, notes: list[str], actuators=()):
    """Run MuJoCo's URDF reader and compiler (warnings go to ``notes``)."""
    with _mujoco_warnings(notes):
        return _compile_quiet(text, source, floating_base, notes, actuators)


def _add_actuators(spec, actuators) -> None:
    """A scene's actuators added to MuJoCo's import as ``general`` actuators on the URDF joints of their
    coordinates (the coordinates of revolute and prismatic joints are those joints' positions), as route 1
    writes them (E55, :func:`~urdf2links.compare.mujoco_side.mjcf.add_spec_actuators`)."""
    add_spec_actuators(spec, actuators, target=lambda a: a.coordinate)


def _compile_quiet(text: str, source: str, floating_base: bool, notes: list[str], actuators=()):
    """Run MuJoCo's URDF reader and compiler; add a free joint if asked."""
    try:
        spec = mujoco.MjSpec.from_string(text)
    except ValueError as err:
        raise MujocoRefused(source, str(err).strip()) from None
    root_body = None
    free_name = None
    if floating_base:
        roots = list(spec.worldbody.bodies)
        if len(roots) != 1:
            raise ValueError(
                f"{source}: floating base needs exactly one root body under the world, "
                f"MuJoCo's import has {len(roots)}: {[b.name for b in roots]}")
        body = roots[0]
        if len(body.joints) or len(getattr(body, "freejoints", [])):
            raise ValueError(
                f"{source}: floating base requested but the root body {body.name!r} is "
                "already jointed to the world (a URDF 'world' link with a moving joint?)")
        existing = {j.name for j in spec.joints}
        free_name = "floating_base"
        while free_name in existing:
            free_name = "_" + free_name
        body.add_freejoint(name=free_name)
        root_body = body.name
        notes.append(f"floating base: free joint {free_name!r} added to root body "
                     f"{root_body!r} (MuJoCo adds none to a URDF)")
    if actuators:
        _add_actuators(spec, actuators)
        notes.append(f"{len(actuators)} actuator(s) of the scene added as MuJoCo general actuators on their joints")
    try:
        model = spec.compile()
    except ValueError as err:
        raise MujocoRefused(source, str(err).strip()) from None
    return model, free_name, root_body


def _restrict_physics(model: mujoco.MjModel, gravity, notes: list[str], *, damping: bool = False) -> None:
    model.opt.gravity[:] = np.asarray(gravity, dtype=float)
    disabled = tuple(n for n in _DISABLED if not (damping and n == "mjDSBL_DAMPER"))
    for name in disabled:
        model.opt.disableflags |= int(getattr(mujoco.mjtDisableBit, name))
    changed = []
    zeroed = ("dof_armature", "dof_frictionloss", "jnt_stiffness", "body_gravcomp") + (() if damping else ("dof_damping",))
    for attr in zeroed:
        arr = getattr(model, attr)
        if np.any(arr != 0):
            changed.append(attr)
        arr[:] = 0.0
    notes.append(f"gravity set to {tuple(float(g) for g in gravity)}; disabled: "
                 + ", ".join(n.removeprefix("mjDSBL_").lower() for n in disabled)
                 + "; " + ", ".join(a.removeprefix("dof_").removeprefix("jnt_").removeprefix("body_") for a in zeroed)
                 + " zeroed" + (f" (non-zero before: {', '.join(changed)})" if changed else "")
                 + ("; MuJoCo's own dof_damping from the URDF's <dynamics damping> kept (the scene asks for URDF "
                    "damping)" if damping else ""))
    if model.neq:       # issue 45: MuJoCo's import makes each <mimic> a joint equality; so does the project
        notes.append(f"{model.neq} equality constraint(s) of MuJoCo's import (each URDF <mimic> a joint equality, "
                     "the same as the project's mimic constraint, E70) are off for the terms at identical states (a "
                     "constraint does not enter A or e + G); the trajectory runs them on both engines")


def mujoco_from_urdf(path_or_text, *, strip_meshes: bool = True, fusestatic: bool = True,
                     gravity=(0.0, 0.0, -9.81), floating_base: bool = False,
                     repair_urdf_text: str | None = None, damping: bool = False, actuators=()) -> MujocoURDF:
    """Compile a URDF with MuJoCo's own importer, restricted to the dynamics we compare.

    ``damping``: keep the joint damping MuJoCo read from ``<dynamics damping>`` (module doc).
    ``actuators``: a scene's resolved actuators, added as ``general`` actuators on their joints.
    ``path_or_text``: a file path, or URDF text (anything starting with ``<``).
    ``repair_urdf_text``: if given, this text (the project's repaired inertias) is loaded
    INSTEAD of the original; ``notes`` records it and whether the original loads.
    Raises :class:`MujocoRefused` (MuJoCo's reason quoted) when MuJoCo refuses the file.
    """
    text, source, folder = _read(path_or_text)
    notes: list[str] = []
    prep = dict(strip_meshes=strip_meshes, fusestatic=fusestatic, meshdir=folder)

    if repair_urdf_text is not None:
        try:
            orig_text, _ = _prepare(text, source, notes=[], **prep)
            _compile(orig_text, source, floating_base, [])
            verdict = "MuJoCo would also have loaded the original"
        except MujocoRefused as err:
            verdict = f"the original is refused by MuJoCo: {err.reason!r}"
        notes.append(f"REPAIRED: loaded a caller-supplied repaired URDF text instead of "
                     f"{source} ({verdict})")
        text = repair_urdf_text
        source = f"{source} (repaired text)"

    new_text, links = _prepare(text, source, notes=notes, **prep)
    model, free_name, root_body = _compile(new_text, source, floating_base, notes, tuple(actuators))

    bodies = {model.body(i).name for i in range(model.nbody)}
    fused = [ln for ln in links if ln not in bodies]
    if "world" in links:
        notes.append("the URDF link named 'world' became MuJoCo's world body")
        if "world" in fused:
            fused.remove("world")
    if fused:
        notes.append(f"fusestatic merged {len(fused)} link(s) without a moving joint into "
                     f"their parents: {', '.join(fused)}")

    _restrict_physics(model, gravity, notes, damping=damping)
    if np.any(model.jnt_actfrclimited):     # MuJoCo reads each <limit effort> as the joint's actuatorfrcrange
        names = [model.joint(j).name for j in np.flatnonzero(model.jnt_actfrclimited)]
        model.jnt_actfrclimited[:] = 0
        if actuators:
            notes.append(f"the URDF's effort limits (MuJoCo's actuatorfrcrange on joints {', '.join(names[:6])}"
                         + (", ..." if len(names) > 6 else "") + ") switched off: a scene's forcerange says what "
                         "saturates, on both engines")
    if model.nv == 0:
        notes.append("the compiled model has no degrees of freedom (no moving joint; "
                     f"{len(links)} URDF link(s))")

    joint_names: list[str] = []
    dof_of_joint: dict[str, int] = {}
    qpos_of_joint: dict[str, int] = {}
    free_dofs: tuple[int, ...] = ()
    free_qpos = None
    # Walk dofs in MuJoCo's order.
    for dof in range(model.nv):
        j = int(model.dof_jntid[dof])
        jtype = mujoco.mjtJoint(int(model.jnt_type[j]))
        name = model.joint(j).name
        if jtype in (mujoco.mjtJoint.mjJNT_HINGE, mujoco.mjtJoint.mjJNT_SLIDE):
            joint_names.append(name)
            dof_of_joint[name] = dof
            qpos_of_joint[name] = int(model.jnt_qposadr[j])
        elif jtype == mujoco.mjtJoint.mjJNT_FREE and name == free_name:
            if dof == model.jnt_dofadr[j]:
                free_dofs = tuple(range(dof, dof + 6))
                free_qpos = int(model.jnt_qposadr[j])
        else:
            raise NotImplementedError(
                f"{source}: joint {name!r} became a MuJoCo "
                f"{jtype.name} joint (URDF floating/planar?); only "
                "hinge/slide joints and an added floating base are supported")
    return MujocoURDF(model=model, joint_names=tuple(joint_names), dof_of_joint=dof_of_joint,
                      qpos_of_joint=qpos_of_joint, source=source, notes=notes,
                      free_joint=free_name, free_dofs=free_dofs, free_qpos=free_qpos,
                      root_body=root_body)


# --------------------------------------------------------------------------- terms


def _check_names(what: str, given, expected: Sequence[str]) -> None:
    given = list(given)
    exp = set(expected)
    unknown = [n for n in given if n not in exp]
    missing = [n for n in expected if n not in set(given)]
    dup = sorted({n for n in given if given.count(n) > 1})
    if unknown or missing or dup:
        parts = []
        if unknown:
            parts.append(f"unknown joint name(s) {unknown}")
        if missing:
            parts.append(f"missing joint name(s) {missing}")
        if dup:
            parts.append(f"repeated joint name(s) {dup}")
        raise KeyError(f"{what}: " + "; ".join(parts)
                       + f" (MuJoCo's hinge/slide joints: {list(expected)})")


def mujoco_data_at(mj: MujocoURDF, qpos_by_joint: Mapping[str, float],
                   qvel_by_joint: Mapping[str, float] | None = None, *,
                   base_qpos=None, base_qvel=None) -> mujoco.MjData:
    """An ``MjData`` at the given state after ``mj_forward`` (positions, velocities)."""
    m = mj.model
    _check_names("qpos_by_joint", qpos_by_joint, mj.joint_names)
    if qvel_by_joint is not None:
        _check_names("qvel_by_joint", qvel_by_joint, mj.joint_names)
    d = mujoco.MjData(m)
    for name, q in qpos_by_joint.items():
        d.qpos[mj.qpos_of_joint[name]] = float(q)
    if qvel_by_joint is not None:
        for name, v in qvel_by_joint.items():
            d.qvel[mj.dof_of_joint[name]] = float(v)
    if mj.floating:
        a = mj.free_qpos
        if base_qpos is not None:
            bq = np.asarray(base_qpos, dtype=float)
            if bq.shape != (7,):
                raise ValueError("base_qpos must be 7 numbers: x y z qw qx qy qz")
            d.qpos[a:a + 7] = bq
        if base_qvel is not None:
            bv = np.asarray(base_qvel, dtype=float)
            if bv.shape != (6,):
                raise ValueError("base_qvel must be 6 numbers: v (world), w (body)")
            d.qvel[list(mj.free_dofs)] = bv
    elif base_qpos is not None or base_qvel is not None:
        raise ValueError(f"{mj.source}: base_qpos/base_qvel given but the base is fixed")
    mujoco.mj_forward(m, d)
    return d


def mujoco_terms(mj: MujocoURDF, qpos_by_joint: Mapping[str, float],
                 qvel_by_joint: Mapping[str, float], order: Sequence[str] | None = None, *,
                 base_qpos=None, base_qvel=None) -> Terms:
    """``M`` (``mj_fullM``) and ``bias`` (``qfrc_bias`` = e + G) at a named state.

    ``qpos_by_joint``/``qvel_by_joint`` must name every hinge/slide joint exactly once;
    ``order`` (default: MuJoCo's dof order) is the coordinate order of the result and
    must be a permutation of ``mj.joint_names``.  ``mj_forward`` fills both terms:
    the inertia matrix in ``mj_fwdPosition`` (composite rigid body), ``qfrc_bias`` in
    ``mj_fwdVelocity`` (RNE with zero acceleration: Coriolis/centrifugal + gravity).
    For a floating base, ``base_qpos`` (x y z qw qx qy qz, default origin/identity) and
    ``base_qvel`` (6, default 0) set the free joint.
    """
    names = tuple(mj.joint_names if order is None else order)
    _check_names("order", names, mj.joint_names)
    d = mujoco_data_at(mj, qpos_by_joint, qvel_by_joint, base_qpos=base_qpos,
                       base_qvel=base_qvel)
    m = mj.model
    M_full = np.zeros((m.nv, m.nv))
    mujoco.mj_fullM(m, d, M_full)
    bias_full = np.array(d.qfrc_bias, dtype=float)
    idx = [mj.dof_of_joint[n] for n in names]
    labels = []
    for dof in range(m.nv):
        if dof in mj.free_dofs:
            labels.append(f"{mj.free_joint}:{FREE_DOF_LABELS[dof - mj.free_dofs[0]]}")
        else:
            labels.append(m.joint(int(m.dof_jntid[dof])).name)
    return Terms(names=names, M=M_full[np.ix_(idx, idx)].copy(), bias=bias_full[idx].copy(),
                 M_full=M_full, bias_full=bias_full, dof_labels=tuple(labels))


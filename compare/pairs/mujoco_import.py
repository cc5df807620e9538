"""MuJoCo's own import of a URDF file, saved as MJCF: the conversion whose result teams then keep and edit.

:func:`save_mujoco_import` hands the URDF to MuJoCo's URDF reader the way route 2 prepares it
(:func:`urdf2links.compare.mujoco_side.mujoco_urdf._prepare`: the file's inertias used as written, no
balancing, no bounds, none from geometry; ``fusestatic`` as asked), compiles it
(``mujoco.MjModel.from_xml_string``) and writes what MuJoCo kept with ``mujoco.mj_saveLastXML``. MuJoCo's
writer prints 6 significant digits: that is the rounding a comparison of the two files must see
through. When MuJoCo refuses the file as written, ``balance=True`` lets its compiler repair the
inertias (``balanceinertia``, and ``boundmass``/``boundinertia`` of 1e-6 for massless moving links), as a
user's conversion would have to; the result says so, and the differences that follow are explained.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import mujoco
import numpy as np
from lxml import etree

from ..mujoco_side.mujoco_urdf import MujocoRefused, _mujoco_warnings, _prepare, _read

__all__ = ["ImportResult", "save_mujoco_import", "BOUND"]

#: ``boundmass`` and ``boundinertia`` of a balanced import: what MuJoCo gives a massless moving link.
BOUND = 1e-6


@dataclass(frozen=True)
class ImportResult:
    """``path`` of the saved MJCF, the compiler ``settings`` MuJoCo read it with, ``balanced`` (its
    compiler had to repair inertias), ``notes`` (what MuJoCo said and what was changed)."""

    path: Path
    settings: dict
    balanced: bool = False
    notes: list[str] = field(default_factory=list)


def _with_settings(text: str, extra: dict) -> str:
    root = etree.fromstring(text.encode("utf-8"))
    comp = root.find("mujoco").find("compiler")
    for k, v in extra.items():
        comp.set(k, v)
    return etree.tostring(root, encoding="unicode")


def _placed(prepared: str, source: str, *, floating_base: bool, root_pose,
            keep_frames: bool = False) -> tuple[mujoco.MjModel, str]:
    """MuJoCo's import through ``MjSpec`` with the top-level bodies placed: a free joint added to the one root
    body (``floating_base``), and ``root_pose`` ``(pos (3,), quat (4,) w x y z)`` composed onto every top-level
    body's pose (a mount, or a floating root's initial pose); with ``keep_frames`` a site named as each massless
    welded body (a URDF frame link that ``fusestatic`` fuses: the site moves with the fusion and keeps the frame).
    The compiled model and the written MJCF."""
    spec = mujoco.MjSpec.from_string(prepared)
    if keep_frames:
        for b in list(spec.bodies):
            if b.parent is not None and not b.joints and b.mass == 0 and not b.explicitinertial:
                b.add_site(name=b.name)
    tops = list(spec.worldbody.bodies)
    if floating_base:
        if len(tops) != 1:
            raise ValueError(f"{source}: a floating base needs one root body under the world, MuJoCo's import has "
                             f"{[b.name for b in tops]}")
        tops[0].add_freejoint(name="floating_base")
    if root_pose is not None:
        pos, quat = np.asarray(root_pose[0], float), np.asarray(root_pose[1], float)
        quat = quat / np.linalg.norm(quat)
        R = np.zeros(9)
        mujoco.mju_quat2Mat(R, quat)
        for b in tops:
            q = np.zeros(4)
            mujoco.mju_mulQuat(q, quat, np.asarray(b.quat, float))
            b.pos, b.quat = R.reshape(3, 3) @ np.asarray(b.pos, float) + pos, q
    m = spec.compile()
    return m, spec.to_xml()


def save_mujoco_import(urdf, out_path, *, fusestatic: bool = True, keep_geometry: bool = True,
                       balance: bool = False, floating_base: bool = False, root_pose=None,
                       keep_frames: bool = False) -> ImportResult:
    """MuJoCo's import of ``urdf`` written to ``out_path`` as MJCF (module doc). ``keep_geometry``: keep
    the ``<visual>``/``<collision>`` geometry (meshes must then resolve from the file's folder);
    ``balance``: let MuJoCo's compiler repair inertias it would refuse; ``floating_base``: a free joint on
    the root body; ``root_pose``: ``(pos, quat)`` (w x y z) composed onto the top-level bodies (the robot
    mounted, or its floating root started, elsewhere: what :mod:`urdf2links.compare.pairs.roots` takes
    out). :class:`MujocoRefused` carries MuJoCo's words when it refuses."""
    text, source, folder = _read(Path(urdf))
    notes: list[str] = []
    prepared, _links = _prepare(text, source, strip_meshes=not keep_geometry, fusestatic=fusestatic,
                                meshdir=folder, notes=notes)
    settings = {"fusestatic": "true" if fusestatic else "false", "balanceinertia": "false"}
    if balance:
        extra = {"balanceinertia": "true", "boundmass": f"{BOUND:g}", "boundinertia": f"{BOUND:g}"}
        prepared = _with_settings(prepared, extra)
        settings.update(extra)
        notes.append("MuJoCo's compiler may repair inertias: " + ", ".join(f'{k}="{v}"' for k, v in extra.items()))
    out = Path(out_path)
    out.parent.mkdir(parents=True, exist_ok=True)
    try:
        with _mujoco_warnings(notes):
            if floating_base or root_pose is not None or keep_frames:
                m, xml = _placed(prepared, source, floating_base=floating_base, root_pose=root_pose,
                                 keep_frames=keep_frames)
                out.write_text(xml)
            else:
                m = mujoco.MjModel.from_xml_string(prepared)
                mujoco.mj_saveLastXML(str(out), m)
    except ValueError as err:
        raise MujocoRefused(source, str(err).strip()) from None
    root = etree.parse(str(out)).getroot()
    comp = root.find("compiler")
    if comp is None:
        comp = etree.Element("compiler")
        root.insert(0, comp)
    if m.nmesh == 0:     # no mesh to find: the writer's absolute meshdir would only tie the file to this machine
        comp.attrib.pop("meshdir", None)
    if balance:          # the written values sit on the bounds, 6 digits: without these MuJoCo refuses its own file
        for k, v in extra.items():
            comp.set(k, v)
    out.write_text(etree.tostring(root, encoding="unicode") + "\n")
    return ImportResult(out, settings, balanced=balance, notes=notes)

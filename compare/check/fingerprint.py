"""Each robot file against its own accepted state: a fingerprint of its dynamic parameters, by name.

A pair's comparison and a scene's run cannot see an edit that both engines run alike (a scene runs the edited
file on both sides). So ``check --init`` and ``check --write-baselines`` record, per robot file, what its
dynamics is made of (:func:`fingerprint`, JSON with names, in the baselines file under ``fingerprints``):

* per body (a URDF link, an MJCF body): its parent, its frame at home in the parent's (``xyz`` m, ``rpy`` rad),
  ``mass`` (kg), ``com`` (m, body frame) and ``inertia`` about the COM (``[ixx, iyy, izz, ixy, ixz, iyz]``,
  kg m^2, body frame), as MuJoCo compiles an MJCF file (:func:`urdf2links.parsers.parts.robot_parts`);
* per joint: ``type``, ``axis``, ``anchor`` (m), ``range`` (``"unlimited"`` when none), ``home``, ``damping``,
  ``stiffness``, ``springref``, ``armature``, ``friction``, and the largest ``effort`` and ``velocity`` the file
  states;
* per MJCF actuator: its ``target``, ``gear``, ``ctrlrange``, ``forcerange``, ``gaintype`` and ``gain``,
  ``biastype`` and ``bias``, ``dyntype`` and ``dynamics`` (the first three parameters); and the file's ``gravity``.

:func:`changes` compares a fingerprint now with the accepted one and names every part and quantity that changed,
added or removed, with both values. A number is unchanged within ``ABS + REL * its size`` (a vector: the norm of
the change against the larger norm), a frame's rotation within :data:`ANGLE`: the fingerprint is written with 10
significant digits (5e-11 relative) and the same file compiles to the same bits, so ``REL = 1e-6`` only takes
up a platform's or MuJoCo version's last digits (its inertia diagonalisation, its quaternion products: 1e-15 to
1e-12 relative), and ``ABS = 1e-9`` (in the quantity's SI unit) the zeros that come out as 1e-17. The smallest
edits that matter -- a 1 cm move of a 0.1 m offset, a mass x 1.1, a halved damping -- are 1e-1 or more.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from urdf2links.dynamics.rotations import matrix_to_rpy, rpy_to_matrix

from ..pairs.differences import split_H

__all__ = ["fingerprint", "changes", "write_fingerprints", "Change", "REL", "ABS", "ANGLE", "UNITS", "ACCEPT"]

REL = 1e-6
ABS = 1e-9
#: Rotation (rad) within which a frame is unchanged.
ANGLE = 1e-6
#: The unit of each quantity, for the messages.
UNITS = {"xyz": "m", "rpy": "rad", "mass": "kg", "com": "m", "inertia": "kg m^2", "axis": "", "anchor": "m",
         "gravity": "m/s^2"}
#: How to accept a file as it is now.
ACCEPT = "`urdf2links check --write-baselines` accepts the file as it is now"


def _r(x: float) -> float:
    return float(f"{x:.10g}") if math.isfinite(x) else x


def _v(a) -> list[float]:
    return [_r(float(x)) + 0.0 for x in np.ravel(a)]


def _body(b, parent: str | None) -> dict:
    m, c, I = split_H(b.H)
    pose = np.asarray(b.pose, float)
    return {"parent": parent, "xyz": _v(pose[:3, 3]), "rpy": _v(matrix_to_rpy(pose[:3, :3])), "mass": _r(m),
            "com": _v(c), "inertia": _v([I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2]])}


def _joint(j, body: str) -> dict:
    rng = "unlimited" if j.lower is None else _v([j.lower, j.upper])
    return {"body": body, "type": j.source_type or j.kind, "axis": _v(j.axis), "anchor": _v(j.anchor), "range": rng,
            "home": _v(j.home), "damping": _r(j.damping), "stiffness": _r(j.stiffness), "springref": _r(j.springref),
            "armature": _r(j.armature), "friction": _r(j.friction),
            "effort": "none" if j.effort is None else _r(j.effort),
            "velocity": "none" if j.velocity is None else _r(j.velocity)}


def _word(enum, value) -> str:
    """MuJoCo's name of an enum value, as its XML writes it: ``mjGAIN_FIXED`` -> ``fixed``."""
    return enum(int(value)).name.split("_", 1)[1].lower()


def _actuators(path) -> dict:
    """An MJCF file's actuators by name (module doc), from MuJoCo's compiled model."""
    import mujoco

    from urdf2links.parsers.mjcf import compile_mjcf

    m, _ = compile_mjcf(str(path))
    out = {}
    for k in range(m.nu):
        name = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_ACTUATOR, k) or f"actuator{k}"
        trn = _word(mujoco.mjtTrn, m.actuator_trntype[k])
        obj = {"joint": mujoco.mjtObj.mjOBJ_JOINT, "tendon": mujoco.mjtObj.mjOBJ_TENDON,
               "site": mujoco.mjtObj.mjOBJ_SITE, "body": mujoco.mjtObj.mjOBJ_BODY}.get(trn.replace("inparent", ""))
        tid = int(m.actuator_trnid[k, 0])
        target = (mujoco.mj_id2name(m, obj, tid) if obj is not None and tid >= 0 else None) or str(tid)
        out[name] = {
            "target": f"{trn} {target}", "gear": _v(m.actuator_gear[k]),
            "ctrlrange": _v(m.actuator_ctrlrange[k]) if m.actuator_ctrllimited[k] else "unlimited",
            "forcerange": _v(m.actuator_forcerange[k]) if m.actuator_forcelimited[k] else "unlimited",
            "gaintype": _word(mujoco.mjtGain, m.actuator_gaintype[k]), "gain": _v(m.actuator_gainprm[k, :3]),
            "biastype": _word(mujoco.mjtBias, m.actuator_biastype[k]), "bias": _v(m.actuator_biasprm[k, :3]),
            "dyntype": _word(mujoco.mjtDyn, m.actuator_dyntype[k]), "dynamics": _v(m.actuator_dynprm[k, :3])}
    return out


def fingerprint(path, *, load: dict | None = None) -> dict:
    """The fingerprint of the robot file ``path`` (module doc); ``load``: its loading options (``floating_base``,
    ``package_dirs``, ``strict``, ``xacro_args`` of a URDF or xacro file)."""
    import warnings

    from urdf2links.parsers.parts import robot_parts

    opts = {k: v for k, v in (load or {}).items() if k in ("floating_base", "package_dirs", "strict", "xacro_args")}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        parts = robot_parts(path, **opts)
    out = {"format": parts.format, "gravity": _v(parts.gravity),
           "bodies": {b.name: _body(b, b.parent) for b in parts.bodies},
           "joints": {j.name: _joint(j, b.name) for j, b in parts.joints}}
    if parts.format == "mjcf":
        out["actuators"] = _actuators(path)
    return out


@dataclass(frozen=True)
class Change:
    """One change of a file's fingerprint: the ``part`` (``joint panda_joint1``), the ``quantity``, the ``old`` and
    ``new`` values (None: the part was added, or removed), ``moved`` and ``allowed`` (in the quantity's unit)."""

    part: str
    quantity: str
    old: object
    new: object
    moved: float = math.inf
    allowed: float = 0.0

    @property
    def ratio(self) -> float:
        return math.inf if self.allowed <= 0 else self.moved / self.allowed

    def text(self, file: str) -> str:
        if self.quantity == "":
            what = ("added (not in its accepted fingerprint)" if self.old is None
                    else "removed (in its accepted fingerprint)")
            return f"{file}: {self.part} {what}; {ACCEPT}"
        unit = UNITS.get(self.quantity, "")
        by = "" if not math.isfinite(self.moved) else f" (changed by {self.moved:.3g} > {self.allowed:.2g})"
        return (f"{file}: {self.part}: {self.quantity} was {_show(self.old)}, now {_show(self.new)}"
                f"{' ' + unit if unit else ''}{by}; {ACCEPT}")


def _show(v) -> str:
    if isinstance(v, list):
        return "[" + ", ".join(_show(x) for x in v) + "]"
    if isinstance(v, float):
        return f"{v:.6g}"
    return str(v)


def _distance(quantity: str, a, b) -> tuple[float, float]:
    """``(moved, allowed)`` of one quantity (module doc)."""
    if isinstance(a, (str, type(None))) or isinstance(b, (str, type(None))):
        return (0.0 if a == b else math.inf), 0.0
    x, y = np.atleast_1d(np.asarray(a, float)), np.atleast_1d(np.asarray(b, float))
    if x.shape != y.shape:
        return math.inf, 0.0
    if quantity == "rpy":
        R = rpy_to_matrix(x).T @ rpy_to_matrix(y)
        return float(np.arccos(np.clip((np.trace(R) - 1.0) / 2.0, -1.0, 1.0))), ANGLE
    moved = 0.0 if np.array_equal(x, y) else float(np.linalg.norm(x - y))
    return moved, ABS + REL * max(float(np.linalg.norm(x)), float(np.linalg.norm(y)))


def changes(old: dict, new: dict) -> list[Change]:
    """Every part and quantity of ``new`` that is not as in the accepted ``old`` (module doc)."""
    body = "link" if new.get("format") == "urdf" else "body"
    out = []
    moved, allowed = _distance("gravity", old.get("gravity"), new.get("gravity"))
    if moved > allowed:
        out.append(Change("the file", "gravity", old.get("gravity"), new.get("gravity"), moved, allowed))
    for section, word in (("bodies", body), ("joints", "joint"), ("actuators", "actuator")):
        a, b = old.get(section) or {}, new.get(section) or {}
        for name in [n for n in a if n not in b]:
            out.append(Change(f"{word} {name}", "", a[name], None))
        for name in [n for n in b if n not in a]:
            out.append(Change(f"{word} {name}", "", None, b[name]))
        for name in [n for n in b if n in a]:
            for q in dict.fromkeys([*a[name], *b[name]]):
                moved, allowed = _distance(q, a[name].get(q), b[name].get(q))
                if moved > allowed:
                    out.append(Change(f"{word} {name}", q, a[name].get(q), b[name].get(q), moved, allowed))
    return out


def write_fingerprints(path, fingerprints: dict) -> None:
    """Add ``{robot file: fingerprint}`` to the baselines file ``path`` (under ``fingerprints``; the other robots'
    are kept)."""
    import json
    from pathlib import Path

    path = Path(path)
    data = json.loads(path.read_text()) if path.is_file() else {"scenes": {}}
    data["fingerprints"] = dict(sorted({**data.get("fingerprints", {}), **fingerprints}.items()))
    path.write_text(json.dumps(data, indent=2) + "\n")

"""Why a difference is there, when a known conversion step makes it: the explanations a report attaches.

MuJoCo's own URDF import changes a few things on purpose, and an MJCF converted from a URDF carries
them; each is recognised from both descriptions as they are now -- the first's values, the second's values
and ``<compiler>`` settings -- so an explanation is said only while it holds (it says what MuJoCo does, not
that MuJoCo did it; a later edit of the second file that no longer fits it drops it):

- an inertia that is not physically consistent (a negative principal moment, a triangle inequality
  violated: the audit of :func:`urdf2links.dynamics.inertia.audit_pseudo_inertia`) is refused by MuJoCo's
  compiler unless it balances it (``balanceinertia``), which changes it;
- a moving body without mass is refused unless its mass and inertia are bounded (``boundmass``,
  ``boundinertia``); a mass difference larger than the second file's ``boundmass`` can make is not explained so;
- a body with zero mass but a rotational inertia, welded to its parent: MuJoCo's ``fusestatic`` merges
  masses and drops that inertia, which the project's folding keeps;
- a URDF ``<limit lower="0" upper="0">`` against an unlimited joint: MuJoCo's import leaves such a joint unlimited
  (said only while the second file's joint is unlimited: each explanation is computed from both files);
- armature where a URDF has none: a URDF cannot say it (an expected, deliberate difference);
- a massless URDF link on a fixed joint missing on the other side: MuJoCo's import fuses it (``fusestatic``) and
  keeps no frame of it.
"""

from __future__ import annotations

import numpy as np

from urdf2links.dynamics.inertia import audit_pseudo_inertia
from urdf2links.parsers.parts import RobotParts, parts_model

from .differences import Difference, split_H

__all__ = ["explain"]


def _folded(U: RobotParts, body: str) -> list:
    """The bodies folded into ``body``'s part (itself first)."""
    pm = parts_model(U)
    t = pm.frame_of[body][0]
    return [b for b in U.bodies if pm.frame_of[b.name][0] == t]


def _bodies_reason(U: RobotParts, body: str, compiler: dict, kind: str) -> str | None:
    """What makes MuJoCo change the bodies folded into ``body``'s part (module doc), given the second
    file's ``<compiler>`` settings (``boundmass``, ``boundinertia``, ``balanceinertia``), or None."""
    bound_m = float(compiler.get("boundmass", 0) or 0)
    bound_i = float(compiler.get("boundinertia", 0) or 0)
    balance = str(compiler.get("balanceinertia", "false")).lower() == "true"
    reasons = []
    for b in _folded(U, body):
        H = np.asarray(b.H, float)
        m, _c, I = split_H(H)
        if bound_m and H[3, 3] < bound_m:
            reasons.append(f"{b.name} has {H[3, 3]:.3g} kg, below the second file's boundmass={bound_m:g}, which MuJoCo "
                           "raises it to")
            continue
        if kind == "mass":
            continue
        if H[3, 3] <= 0.0 and np.any(H[:3, :3]):
            reasons.append(f"{b.name} has no mass but a rotational inertia: MuJoCo's fusestatic merges masses and drops "
                           "that inertia")
            continue
        if m <= 0.0:
            continue
        w = np.sort(np.linalg.eigvalsh(I))
        if bound_i and w[0] < bound_i:
            reasons.append(f"{b.name}'s smallest principal moment {w[0]:.3g} kg m^2 is below the second file's "
                           f"boundinertia={bound_i:g}, which MuJoCo raises it to")
        elif w[0] <= 0 or w[0] + w[1] <= w[2] * (1 + 1e-6):
            found = audit_pseudo_inertia(H, link=b.name)
            what = found[0].kind.replace("_", " ") if found else "at the triangle inequality's bound A + B = C"
            reasons.append(f"{b.name}'s inertia is not physically consistent ({what}): MuJoCo's compiler refuses it "
                           + ("and the second file balances it (balanceinertia), which changes it" if balance else
                              "unless it balances it (balanceinertia), which changes it"))
    return "; ".join(reasons) or None


def _bounds_give(d: Difference, U: RobotParts, body: str, compiler: dict) -> bool:
    """Whether a mass difference is no more than the second file's ``boundmass`` can make (each body folded into the
    part raised to it at most; to 6 written digits); True when the second file bounds no mass (no such claim)."""
    bound = float(compiler.get("boundmass", 0) or 0)
    if not bound:
        return True
    added = abs(float(d.mjcf_value or 0.0) - float(d.urdf_value or 0.0))
    return added <= bound * len(_folded(U, body)) * (1 + 1e-5) + 1e-5 * abs(float(d.mjcf_value or 0.0))


def explain(diffs: list[Difference], U: RobotParts, M: RobotParts | None = None) -> None:
    """Attach an ``explanation`` to every difference of ``diffs`` that a known conversion step makes (module doc)."""
    joints = {j.name: (j, b) for j, b in U.joints}
    for d in diffs:
        if d.explanation or d.urdf is None:
            continue
        if d.kind in ("inertia", "com", "mass") and d.links:
            body = d.links[0]
            compiler = dict(getattr(M, "compiler", None) or {})
            if d.kind == "mass" and not _bounds_give(d, U, body, compiler):
                continue                  # more mass than the second file's boundmass gives: not MuJoCo's doing
            if d.kind == "mass" and float(d.urdf_value or 0.0) <= 0.0 < float(d.mjcf_value or 0.0):
                d.explanation = (f"{body} moves and has no mass: MuJoCo refuses a massless moving body unless its mass "
                                 "and inertia are bounded (boundmass, boundinertia)")
            else:
                d.explanation = _bodies_reason(U, body, compiler, d.kind)
        elif d.kind == "armature" and U.format == "urdf" and float(d.urdf_value or 0.0) == 0.0:
            d.explanation = ("a URDF has no armature: the motor's rotor inertia reflected through its gears, which an "
                             "MJCF adds to the joint (E49) and the URDF's own dynamics leave out")
        elif d.kind == "frame_missing" and U.format == "urdf" and d.mjcf is None:
            d.explanation = (f"{d.links[0]} is a massless link on a fixed joint: MuJoCo's URDF import fuses it "
                             "(fusestatic) and keeps no frame of it; a site of its name keeps it "
                             "(save_mujoco_import(keep_frames=True))")
        elif d.kind == "limits" and d.urdf in joints and U.format == "urdf":
            j = joints[d.urdf][0]
            unlimited = d.mjcf_value is None or all(v is None for v in d.mjcf_value)
            if j.lower is not None and j.lower == j.upper and unlimited:
                d.explanation = (f"the URDF gives {d.urdf} <limit lower=upper={j.lower:g}>: MuJoCo's import leaves such "
                                 "a joint unlimited")

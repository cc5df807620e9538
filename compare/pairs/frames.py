"""Frames one description keeps and the other dropped: kind ``frame_missing``.

A massless body welded to its parent (a URDF link on a fixed joint with no ``<inertial>``: a sensor, tool or
camera frame) changes no term of the dynamics, and MuJoCo's import fuses it away (``fusestatic``) and keeps no
frame of it. Code that looks the frame up by name (a tool centre point, a camera) then finds nothing. Such a body
of the first description is a difference of kind ``frame_missing`` unless the second keeps its frame: a body of
the same name (compared as ``origin`` then) or a site of the same name at the same pose at home (within
``ROUNDING["frame_missing"]``, m or rad, after the roots' alignment, E63). ``difference``: 1 (no frame of that
name), else how far the site is (m, or rad when it turned more than it moved). Not a dynamic kind.
"""

from __future__ import annotations

import math

import numpy as np

from urdf2links.parsers.parts import RobotParts

from .kinds import ROUNDING, Difference

__all__ = ["frame_differences"]


def _angle(R) -> float:
    return float(np.arccos(np.clip((np.trace(R) - 1.0) / 2.0, -1.0, 1.0)))


def frame_differences(U: RobotParts, M: RobotParts, WU: dict, WM: dict) -> tuple[list[Difference], int]:
    """The ``frame_missing`` differences (module doc) and how many kept frames agree to rounding. ``WU``, ``WM``:
    each side's bodies' home poses (4, 4), the second's aligned to the first's (E63)."""
    names = {b.name for b in M.bodies}
    sites = {n: (body, P) for n, body, P in getattr(M, "sites", ())}
    out, kept = [], 0
    for b in U.bodies:
        if b.joints or b.parent is None or b.name in names or float(np.asarray(b.H)[3, 3]) > 0.0:
            continue
        label = b.fixed_joint or b.name
        site = sites.get(b.name)
        if site is None or site[0] not in WM:
            out.append(Difference("frame_missing", label, None, b.name, None, 1.0, "frame",
                                  f"massless frame {b.name!r} (welded to {b.parent}) has neither a body nor a site of "
                                  "its name on the other side", (b.name,)))
            continue
        P = np.linalg.inv(WU[b.name]) @ (WM[site[0]] @ site[1])
        dp, rot = float(np.linalg.norm(P[:3, 3])), _angle(P[:3, :3])
        d, unit = (rot, "rad") if rot > dp else (dp, "m")
        if d <= ROUNDING["frame_missing"]:
            kept += 1
            continue
        out.append(Difference("frame_missing", label, b.name, WU[b.name][:3, 3], (WM[site[0]] @ site[1])[:3, 3], d,
                              unit, f"massless frame {b.name!r} kept as a site of {site[0]} elsewhere: moved {dp:.4g} m, "
                              f"turned {rot:.4g} rad ({math.degrees(rot):.3g} deg)", (b.name, site[0])))
    return out, kept

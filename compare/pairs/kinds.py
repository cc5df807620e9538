"""The kinds of difference between two descriptions of one robot, and the record of one (docs/pairs.md).

:data:`ROUNDING` gives each kind's rounding level (its unit), :data:`PARTS` what the names of a kind's difference
name, and :class:`Difference` is one difference as every comparer writes it (differences.py, frames.py,
couplings.py, collisions.py, constraints.py) and every reader reads it (effects, explanations, reports, check).
It sits below all of them so that none imports another for it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

__all__ = ["Difference", "ROUNDING", "KINDS", "PARTS", "plain"]

#: Below these a difference is rounding (MuJoCo's XML writer prints 6 significant digits): relative for
#: mass and inertia, m for com and origin, rad for axis and turned frames, the joints' own units else.
ROUNDING = {"mass": 1e-5, "com": 1e-5, "inertia": 1e-5, "axis": 1e-5, "origin": 1e-5, "armature": 1e-9,
            "damping": 1e-9, "stiffness": 1e-9, "limits": 1e-5, "type": 0.0, "joint_missing": 0.0,
            "link_missing": 0.0, "constraint": 0.0,        # constraint: a loop closed on one side (issue 36)
            "root_pose": 1e-5, "friction": 1e-9, "effort": 1e-5, "velocity": 1e-5,
            "coupling": 1e-5,          # a URDF <mimic> against an MJCF joint equality (couplings.py)
            "frame_missing": 1e-5,     # a massless welded frame the other side dropped (frames.py)
            "collision": 1e-4}         # relative (collisions.py); MuJoCo's import measured 2.1e-6 (ur5_like's 6
#                                   written digits), 2.3e-8 (solo12's meshes, float32 vertices)
KINDS = tuple(ROUNDING)

#: What each kind's ``urdf`` and ``mjcf`` names are: a link's (a body's) differences name it by its link, a joint's
#: by its joint (each as its own file calls it).
PARTS = {"mass": "link", "com": "link", "inertia": "link", "link_missing": "link", "collision": "link",
         "root_pose": "link", "origin": "joint", "axis": "joint", "type": "joint", "limits": "joint",
         "armature": "joint", "damping": "joint", "stiffness": "joint", "friction": "joint", "effort": "joint",
         "velocity": "joint", "joint_missing": "joint", "coupling": "joint", "frame_missing": "frame",
         "constraint": "equality"}


@dataclass
class Difference:
    """One difference: ``kind`` (:data:`KINDS`), the ``urdf`` and ``mjcf`` names (joint, or body where no
    joint names it), both values, ``difference`` (a number in ``unit``), ``what`` it is in words,
    ``links`` (the bodies), ``through`` (fixed joints of the first description merged on the other side),
    ``explanation`` (why it is expected, when known), ``undo`` (second side -> second side with this one
    difference undone; None when it cannot be), ``effect`` (filled by the attribution), ``frames`` (an origin's
    frames (4, 4) on both sides, relative to the same reference: its move in m and its turn in rad apart)."""

    kind: str
    urdf: str | None
    mjcf: str | None
    urdf_value: object
    mjcf_value: object
    difference: float
    unit: str
    what: str
    links: tuple = ()
    through: tuple = ()
    explanation: str | None = None
    undo: Callable | None = None
    effect: dict | None = None
    frames: tuple | None = None

    @property
    def ratio(self) -> float:
        """How many times the rounding level it is (the order among differences of no effect)."""
        tol = ROUNDING.get(self.kind, 0.0)
        return math.inf if tol == 0 else self.difference / tol

    @property
    def part(self) -> str:
        """What ``urdf`` and ``mjcf`` name (:data:`PARTS`): ``link``, ``joint``, ``frame`` or ``equality``."""
        return PARTS.get(self.kind, "part")

    def label(self) -> str:
        names = " / ".join(n for n in (self.urdf, self.mjcf) if n) or "-"
        return f"{self.kind} {names}"

    def to_json(self) -> dict:
        out = {"kind": self.kind, "urdf": self.urdf, "mjcf": self.mjcf, "urdf_value": plain(self.urdf_value),
               "mjcf_value": plain(self.mjcf_value), "difference": float(self.difference), "unit": self.unit,
               "what": self.what, "part": self.part}
        if self.links:
            out["links"] = list(self.links)
        if self.through:
            out["through"] = list(self.through)
        if self.explanation:
            out["explanation"] = self.explanation
        if self.effect is not None:
            out["effect"] = self.effect
        if self.frames is not None:
            out["frames"] = {"urdf": plain(self.frames[0]), "mjcf": plain(self.frames[1])}
        return out


def plain(v):
    if v is None or isinstance(v, (str, bool)):
        return v
    a = np.asarray(v, float)
    return float(a) if a.ndim == 0 else a.round(12).tolist()

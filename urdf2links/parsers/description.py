"""Parsed robot description: a faithful, validated mirror of the URDF.

This is the first of the two data layers (the second is the tree of links,
:mod:`urdf2links.dynamics.tree`): it holds what the file says, in the file's own terms (URDF ``rpy``,
joint axes, inertials about the COM), after validation. Nothing here knows the trace method;
:mod:`urdf2links.parsers.importer` turns it into the tree of links.

Shapes: vectors are ``(3,)`` float arrays, inertia tensors ``(3, 3)``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = [
    "Origin",
    "Inertial",
    "Geometry",
    "Mimic",
    "LinkDescription",
    "JointDescription",
    "RobotDescription",
]

JOINT_TYPES = ("revolute", "continuous", "prismatic", "fixed", "floating", "planar", "spherical")
#: Joint types of URDF 1.0; ``spherical`` (three ZYX angles) is an extension urdfdom does not read.
URDF_JOINT_TYPES = JOINT_TYPES[:-1]


@dataclass(frozen=True)
class Origin:
    """An ``<origin xyz rpy>``: translation ``xyz`` (3,) and URDF ``rpy`` (3,), R = Rz(y) Ry(p) Rx(r)."""

    xyz: np.ndarray = field(default_factory=lambda: np.zeros(3))
    rpy: np.ndarray = field(default_factory=lambda: np.zeros(3))


@dataclass(frozen=True)
class Inertial:
    """An ``<inertial>``: ``mass``, COM frame ``origin``, tensor ``inertia`` (3, 3) about the COM in that frame.

    ``inertia`` is the URDF tensor: diagonal ``ixx, iyy, izz``, off-diagonal ``ixy, ixz, iyz``
    (which are minus the products of inertia ``integral(x y dm)``).
    """

    mass: float
    origin: Origin
    inertia: np.ndarray


@dataclass(frozen=True)
class Geometry:
    """One ``<collision>`` or ``<visual>`` geometry.

    ``kind`` is ``"box"`` (``size`` (3,)), ``"cylinder"`` (``radius``, ``length``, axis z),
    ``"sphere"`` (``radius``) or ``"mesh"`` (``filename`` as written, ``path`` resolved or
    None when it cannot be found, ``scale`` (3,)). Any other ``kind`` is a shape the importer
    does not know or could not read (``<capsule>``, ``<plane>``, a negative size, ...): kept so
    that an inertia computed from the link's geometry refuses it by name; ``problem`` says why.
    """

    kind: str
    origin: Origin
    size: np.ndarray | None = None
    radius: float | None = None
    length: float | None = None
    filename: str | None = None
    path: Path | None = None
    scale: np.ndarray | None = None
    problem: str = ""
    missing: str = ""
    """A mesh whose file was not found: the description file, link, element, filename and the paths looked for
    (:func:`urdf2links.parsers.mesh_paths.missing_mesh`); what needs the file raises it."""


@dataclass(frozen=True)
class Mimic:
    """``<mimic joint multiplier offset>``: q_follower = multiplier * q_leader + offset."""

    joint: str
    multiplier: float = 1.0
    offset: float = 0.0


@dataclass(frozen=True)
class LinkDescription:
    name: str
    inertial: Inertial | None
    collisions: tuple[Geometry, ...] = ()
    visuals: tuple[Geometry, ...] = ()


@dataclass(frozen=True)
class JointDescription:
    """A ``<joint>``; ``axis`` (3,) as written (not normalized), default (1, 0, 0).

    ``limit_*``: ``<limit lower upper effort velocity>`` (None where absent); ``damping`` (N m s/rad
    or N s/m) and ``friction`` (N m or N): ``<dynamics>``, None where absent.
    """

    name: str
    type: str
    parent: str
    child: str
    origin: Origin
    axis: np.ndarray
    mimic: Mimic | None = None
    limit_lower: float | None = None
    limit_upper: float | None = None
    limit_effort: float | None = None
    limit_velocity: float | None = None
    damping: float | None = None
    friction: float | None = None


@dataclass(frozen=True)
class RobotDescription:
    """A validated robot: links by name, joints in topological order (parents before children).

    ``source`` is the file's path, or ``"<string>"`` for text; ``root`` the one link that is no
    joint's child; ``directory`` where relative mesh paths start; ``notes``: what the reader
    tolerated, ignored or did not use (element, link or joint, and what was done).
    """

    name: str
    source: str
    links: dict[str, LinkDescription]
    joints: tuple[JointDescription, ...]
    root: str
    directory: Path | None = None
    notes: tuple[str, ...] = ()

    def joint_of_child(self, link: str) -> JointDescription | None:
        for j in self.joints:
            if j.child == link:
                return j
        return None

    def child_joints(self, link: str) -> tuple[JointDescription, ...]:
        return tuple(j for j in self.joints if j.parent == link)

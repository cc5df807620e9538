"""What the view draws of a robot: :class:`Shape` (one shape of a link, in its frame) and :class:`RobotShapes` (a
robot's shapes and the notes on them). URDF visuals (:mod:`.visuals`) and MJCF geoms (:mod:`.mjcf_visuals`) are
read into them; the animation and the thumbnails draw them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Shape", "RobotShapes"]


@dataclass(frozen=True, eq=False)
class Shape:
    """One shape of a link, in the link's frame through ``origin`` (4, 4).

    ``kind``: ``"box"`` (``size`` (3,)), ``"cylinder"`` (``radius``, ``length``, axis z),
    ``"sphere"`` (``radius``), ``"mesh"`` (``vertices`` (V, 3) float32 in the shape's frame,
    ``faces`` (F, 3) int32) or ``"frame"`` (the link's axes). ``source``: ``"visual"``,
    ``"collision"`` or ``"frame"``. ``color`` (3,) in 0..1, or None for the viewer's default.
    """

    link: str
    kind: str
    origin: np.ndarray
    source: str
    size: np.ndarray | None = None
    radius: float | None = None
    length: float | None = None
    vertices: np.ndarray | None = None
    faces: np.ndarray | None = None
    color: tuple | None = None

    def centre(self) -> np.ndarray:
        """The centre of the shape's bounding box, in the shape's frame (3,)."""
        if self.kind == "mesh":
            return 0.5 * (self.vertices.min(axis=0) + self.vertices.max(axis=0)).astype(float)
        return np.zeros(3)

    def extent(self) -> float:
        """Half the diagonal of the shape's bounding box (m): how far it reaches from :meth:`centre`."""
        if self.kind == "box":
            return 0.5 * float(np.linalg.norm(self.size))
        if self.kind == "cylinder":
            return float(np.hypot(self.radius, 0.5 * self.length))
        if self.kind == "sphere":
            return float(self.radius)
        if self.kind == "mesh":
            return 0.5 * float(np.linalg.norm(self.vertices.max(axis=0) - self.vertices.min(axis=0)))
        return 0.0


@dataclass(frozen=True, eq=False)
class RobotShapes:
    """The shapes of a robot: ``links`` (URDF links, file order), ``shapes``, ``notes`` (what was
    decimated, replaced or could not be read), ``faces`` (mesh triangles kept) and ``faces_read``
    (in the files)."""

    robot: str
    links: tuple[str, ...]
    shapes: tuple[Shape, ...]
    notes: tuple[str, ...] = ()
    faces: int = 0
    faces_read: int = 0

    def of(self, link: str) -> tuple[Shape, ...]:
        return tuple(s for s in self.shapes if s.link == link)

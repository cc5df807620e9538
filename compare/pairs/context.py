"""One pair of descriptions as everything downstream reads it, computed once: :class:`PairContext`.

Both files read as parts (:func:`urdf2links.parsers.parts.robot_parts`), each side's home poses
(:func:`urdf2links.parsers.parts.home_poses`), the joints matched (:func:`~urdf2links.compare.pairs.mapping.map_joints`,
E52), the bodies both sides have with the root pair among them (:func:`~urdf2links.compare.pairs.roots.paired_bodies`),
the roots' alignment ``D = W_urdf(root) W_mjcf(root)^-1`` (E63) and the second's home poses carried by it, the
joints' axes in the world at home, and each side's tree of links rebuilt from its parts
(:func:`urdf2links.parsers.parts.parts_model`, E51). :func:`pair_context` builds it once;
the differences part by part (:mod:`~urdf2links.compare.pairs.differences`), the collision geometry
(:mod:`~urdf2links.compare.pairs.collisions`), the effects on ``A`` and ``G``
(:mod:`~urdf2links.compare.pairs.effects`) and the motion (:mod:`~urdf2links.compare.pairs.motion`) read from it.

The second description changed by undoing a difference (E53) is a new :class:`~urdf2links.parsers.parts.RobotParts`;
:meth:`PairContext.home_of` gives its home poses: the context's own when the undo left every body where it was (an
armature, a mass, an axis: the same pose objects), computed only when it moved one (an origin, the roots' mount).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from urdf2links.parsers.parts import PartsModel, RobotParts, home_poses, parts_model

from .mapping import JointMapping, coordinate_map, map_joints, world_axes
from .roots import RootPair, match_bodies, paired_bodies, root_pair

__all__ = ["PairContext", "pair_context"]


def _free_root(b) -> bool:
    return b.parent is None and len(b.joints) == 1 and b.joints[0].kind == "free"


def _same_places(a: RobotParts, b: RobotParts) -> bool:
    """``a`` and ``b`` put every body at the same home pose (same bodies, parents and poses; a floating root's
    free joint at the same home): their home poses are equal."""
    if a is b:
        return True
    if len(a.bodies) != len(b.bodies):
        return False
    for x, y in zip(a.bodies, b.bodies):
        if x.name != y.name or x.parent != y.parent or _free_root(x) != _free_root(y):
            return False
        if not (x.pose is y.pose or np.array_equal(x.pose, y.pose)):
            return False
        if _free_root(x) and tuple(x.joints[0].home) != tuple(y.joints[0].home):
            return False
    return True


@dataclass(frozen=True, eq=False)
class PairContext:
    """Both descriptions and what is computed once about them (module doc): ``urdf`` (the first file's parts) and
    ``mjcf`` (the second's), their home poses ``home_urdf``, ``home_mjcf`` (body -> (4, 4), each in its own world),
    the joint ``mapping``, ``root`` (the root pair), ``bodies`` (the first's body -> the second's, for the bodies
    both have, the roots among them), ``alignment`` ``D`` (4, 4) (E63), ``aligned_mjcf`` (``D W_mjcf``), the joints'
    world axes at home ``axes_urdf`` and ``axes_mjcf`` (joint -> (axis, anchor); the second's aligned), and both
    trees of links ``model_urdf``, ``model_mjcf`` (E51)."""

    urdf: RobotParts
    mjcf: RobotParts
    home_urdf: dict
    home_mjcf: dict
    mapping: JointMapping
    root: RootPair
    bodies: dict
    alignment: np.ndarray
    aligned_mjcf: dict
    axes_urdf: dict
    axes_mjcf: dict
    model_urdf: PartsModel
    model_mjcf: PartsModel

    def home_of(self, parts: RobotParts) -> dict:
        """The home poses of ``parts``, a side as it is now (module doc): a side's own when ``parts`` places every
        body as that side does, else computed."""
        for side, home in ((self.mjcf, self.home_mjcf), (self.urdf, self.home_urdf)):
            if _same_places(parts, side):
                return home
        return home_poses(parts)

    def alignment_of(self, parts: RobotParts, home: dict | None = None) -> np.ndarray:
        """``D`` (E63) of the second description as it is now (``parts``; ``home``: its home poses when known)."""
        if self.root.urdf is None:
            return np.eye(4)
        home = self.home_of(parts) if home is None else home
        return self.home_urdf[self.root.urdf] @ np.linalg.inv(home[self.root.mjcf])

    def aligned(self, parts: RobotParts) -> dict:
        """The second description's (``parts``, as it is now) home poses carried by the roots' alignment (E63)."""
        if parts is self.mjcf:
            return self.aligned_mjcf
        W = self.home_of(parts)
        D = self.alignment_of(parts, W)
        return {k: D @ v for k, v in W.items()}

    def coordinate_map(self, parts: RobotParts | None = None, *, signs: bool = True):
        """:func:`~urdf2links.compare.pairs.mapping.coordinate_map` of the matched joints (E52), the second
        description as it is now (``parts``; None: as read)."""
        if parts is None or parts is self.mjcf:
            parts, axes = self.mjcf, self.axes_mjcf
        else:
            W = self.home_of(parts)
            axes = world_axes(parts, self.alignment_of(parts, W), W=W)
        return coordinate_map(self.urdf, parts, self.mapping, axes=(self.axes_urdf, axes), signs=signs)


def pair_context(urdf: RobotParts, mjcf: RobotParts, *, explicit_map: dict | None = None) -> PairContext:
    """The :class:`PairContext` of the parts ``urdf`` (the first description) and ``mjcf`` (the second), the joints
    matched by ``explicit_map`` (``{urdf joint: mjcf joint}``, ``--map``) first."""
    WU, WM = home_poses(urdf), home_poses(mjcf)
    mapping = map_joints(urdf, mjcf, explicit=explicit_map, homes=(WU, WM))
    pairs = [(m.urdf, m.mjcf) for m in mapping.matches]
    root = mapping.root if mapping.root is not None else root_pair(urdf, mjcf, match_bodies(urdf, mjcf, pairs))
    D = np.eye(4) if root.urdf is None else WU[root.urdf] @ np.linalg.inv(WM[root.mjcf])
    return PairContext(urdf=urdf, mjcf=mjcf, home_urdf=WU, home_mjcf=WM, mapping=mapping, root=root,
                       bodies=paired_bodies(urdf, mjcf, pairs, root), alignment=D,
                       aligned_mjcf={k: D @ v for k, v in WM.items()},
                       axes_urdf=world_axes(urdf, W=WU), axes_mjcf=world_axes(mjcf, D, W=WM),
                       model_urdf=parts_model(urdf), model_mjcf=parts_model(mjcf))

"""Which joint of one description is which joint of the other: by the user's map, by name, then by structure.

Two descriptions of one robot name their joints alike when one was converted from the other, and
differently when they come from different hands. :func:`map_joints` matches the moving joints of the
first description (``urdf``: the file given first) to those of the second (``mjcf``: the file given
with ``--against``): first the pairs ``--map urdf_joint=mjcf_joint`` gives, then equal names, then by
structure: an unmatched joint whose nearest moving ancestor joint is matched takes the unmatched joint
of the same kind under the matched ancestor whose axis and anchor at home are nearest (both
descriptions' home poses, in the world aligned at the root pair, :mod:`~urdf2links.compare.pairs.roots`),
rounds repeated until nothing more matches. Before any joint matches, the root pair is the fixed roots when
both sides have one, else the pair of top bodies whose alignment lets every joint match best.

A matched pair of one-coordinate joints maps its coordinate as ``q_mjcf = sign q_urdf + offset``
(docs/equations.md (E52)): ``sign`` -1 when the axes point opposite ways in the world at home (a negated
axis: the comparison reports it as kind ``axis``, and goes on in mapped coordinates), ``offset`` the
difference of the coordinates at home (an MJCF hinge's ``ref``: MuJoCo's qpos is the coordinate).
Joints with several coordinates (ball, free, planar) map slot by slot, sign 1.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from urdf2links.errors import DescriptionError
from urdf2links.parsers.parts import JOINT_KINDS, RobotParts, home_poses

from .roots import RootPair, alignment, match_bodies, root_pair

__all__ = ["JointMatch", "JointMapping", "map_joints", "moving_parent", "coordinate_map", "parse_map", "world_axes"]


@dataclass(frozen=True)
class JointMatch:
    """``urdf`` and ``mjcf`` joint names, how they were matched (``by``: ``map``, ``name``, ``structure``),
    their kinds, and the map of a one-coordinate pair ``q_mjcf = sign q_urdf + offset``."""

    urdf: str
    mjcf: str
    by: str
    kind_urdf: str
    kind_mjcf: str
    sign: float = 1.0
    offset: float = 0.0

    def to_json(self) -> dict:
        return {"urdf": self.urdf, "mjcf": self.mjcf, "by": self.by, "type": [self.kind_urdf, self.kind_mjcf],
                "sign": self.sign, "offset": self.offset}


@dataclass(frozen=True)
class JointMapping:
    """The matched joints, the unmatched of each side, and ``mapped_fraction`` (matched joints over the
    larger side's moving joints; 1 when every joint of both sides is matched)."""

    matches: tuple[JointMatch, ...]
    unmatched_urdf: tuple[str, ...]
    unmatched_mjcf: tuple[str, ...]
    root: RootPair | None = None

    @property
    def mapped_fraction(self) -> float:
        total = max(len(self.matches) + len(self.unmatched_urdf), len(self.matches) + len(self.unmatched_mjcf))
        return 1.0 if total == 0 else len(self.matches) / total

    def of_urdf(self, name: str) -> JointMatch | None:
        return next((m for m in self.matches if m.urdf == name), None)

    def of_mjcf(self, name: str) -> JointMatch | None:
        return next((m for m in self.matches if m.mjcf == name), None)

    def to_json(self) -> dict:
        by = {k: sum(m.by == k for m in self.matches) for k in ("map", "name", "structure")}
        return {"matched": [m.to_json() for m in self.matches], "unmatched_urdf": list(self.unmatched_urdf),
                "unmatched_mjcf": list(self.unmatched_mjcf), "mapped_fraction": self.mapped_fraction,
                "matched_by": by, "negated": [m.urdf for m in self.matches if m.sign < 0],
                "root": None if self.root is None else self.root.to_json()}


def parse_map(items) -> dict[str, str]:
    """``["a=b", ...]`` (``--map``) or ``{"a": "b"}`` (a pairs file's ``map``) as ``{urdf joint: mjcf joint}``."""
    if isinstance(items, dict):
        return {str(k): str(v) for k, v in items.items()}
    out = {}
    for item in items or ():
        left, eq, right = str(item).partition("=")
        if not eq or not left.strip() or not right.strip():
            raise ValueError(f"--map {item!r}: give urdf_joint=mjcf_joint (one pair per --map)")
        out[left.strip()] = right.strip()
    return out


def moving_parent(parts: RobotParts, joint: str) -> str | None:
    """The joint that moves ``joint``'s frame before it: the previous joint of its body, else the last
    joint of the nearest ancestor body with joints; None under the world."""
    bodies = {b.name: b for b in parts.bodies}
    for b in parts.bodies:
        names = [j.name for j in b.joints]
        if joint in names:
            k = names.index(joint)
            if k > 0:
                return names[k - 1]
            p = b.parent
            while p is not None:
                if bodies[p].joints:
                    return bodies[p].joints[-1].name
                p = bodies[p].parent
            return None
    raise KeyError(joint)


def world_axes(parts: RobotParts, D=None, W=None) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Joint -> (axis, anchor) in the world at home; ``D`` (4, 4): the world carried into the first
    description's by the roots' alignment (E63), so that neither depends on where a file puts its root."""
    W = home_poses(parts) if W is None else W
    D = np.eye(4) if D is None else D
    out = {}
    for j, b in parts.joints:
        F = D @ W[b.name]
        R, p = F[:3, :3], F[:3, 3]
        out[j.name] = (R @ np.asarray(j.axis, float), p + R @ np.asarray(j.anchor, float))
    return out


def _sign_offset(ju, jm, wu=None, wm=None) -> tuple[float, float]:
    """``(sign, offset)`` of a pair (E52): the sign of the axes' product in the world at home (``wu``, ``wm``: the
    joints' axes there; without them, in their body frames)."""
    if len(JOINT_KINDS[ju.kind]) != 1 or len(JOINT_KINDS[jm.kind]) != 1:
        return 1.0, 0.0
    u, v = (ju.axis, jm.axis) if wu is None or wm is None else (wu, wm)
    s = -1.0 if float(np.dot(u, v)) < 0 else 1.0
    return s, jm.ref - s * ju.ref


def map_joints(urdf: RobotParts, mjcf: RobotParts, *, explicit: dict | None = None,
               homes: tuple[dict, dict] | None = None) -> JointMapping:
    """Match the moving joints of ``urdf`` to those of ``mjcf`` (module doc); ``explicit`` ``{urdf joint:
    mjcf joint}`` first (a :class:`DescriptionError` names a joint that is not there); ``homes``: both sides'
    home poses when already computed (:class:`~urdf2links.compare.pairs.context.PairContext`)."""
    ju = {j.name: j for j, _ in urdf.joints}
    jm = {j.name: j for j, _ in mjcf.joints}
    pairs: dict[str, tuple[str, str]] = {}
    for a, b in (explicit or {}).items():
        if a not in ju:
            raise DescriptionError(f"--map {a}={b}: {urdf.source} has no moving joint {a!r}; its joints are "
                                   f"{list(ju)}")
        if b not in jm:
            raise DescriptionError(f"--map {a}={b}: {mjcf.source} has no moving joint {b!r}; its joints are "
                                   f"{list(jm)}")
        pairs[a] = (b, "map")
    taken = {b for b, _ in pairs.values()}
    for a in ju:
        if a not in pairs and a in jm and a not in taken:
            pairs[a] = (a, "name")
            taken.add(a)
    WU, WM = (home_poses(urdf), home_poses(mjcf)) if homes is None else homes
    root = root_pair(urdf, mjcf, match_bodies(urdf, mjcf, [(a, b) for a, (b, _) in pairs.items()]))
    parent_u = {a: moving_parent(urdf, a) for a in ju}
    parent_m = {b: moving_parent(mjcf, b) for b in jm}
    axes_u = world_axes(urdf, W=WU)
    if root.urdf is None:               # nothing matched yet, no fixed roots on both sides: the best top pair
        root = _top_alignment(urdf, mjcf, (pairs, taken), ju, jm, parent_u, parent_m, axes_u, WU, WM)
    axes_m = world_axes(mjcf, alignment(urdf, mjcf, root, WU, WM), W=WM)
    _by_structure(pairs, taken, ju, jm, parent_u, parent_m, axes_u, axes_m)
    final = root_pair(urdf, mjcf, match_bodies(urdf, mjcf, [(a, b) for a, (b, _) in pairs.items()]))
    if final != root:
        axes_m = world_axes(mjcf, alignment(urdf, mjcf, final, WU, WM), W=WM)
    matches = []
    for a in ju:                       # in the first description's tree order
        if a in pairs:
            b, by = pairs[a]
            s, c = _sign_offset(ju[a], jm[b], axes_u[a][0], axes_m[b][0])
            matches.append(JointMatch(a, b, by, ju[a].kind, jm[b].kind, s, c))
    return JointMapping(tuple(matches), tuple(a for a in ju if a not in pairs), tuple(b for b in jm if b not in taken),
                        final)


def _by_structure(pairs: dict, taken: set, ju, jm, parent_u, parent_m, axes_u, axes_m) -> float:
    """Match by structure, rounds repeated until nothing more matches (module doc): ``pairs`` and ``taken`` are
    filled in; the summed score of the matches made (angle between the axes + anchors' distance over the reach)."""
    reach = max([float(np.linalg.norm(p)) for _, p in axes_u.values()] + [1e-3])
    total, changed = 0.0, True
    while changed:
        changed = False
        for a in ju:
            if a in pairs or (parent_u[a] is not None and parent_u[a] not in pairs):
                continue
            target = None if parent_u[a] is None else pairs[parent_u[a]][0]
            cands = [b for b in jm if b not in taken and parent_m[b] == target and jm[b].kind == ju[a].kind]
            if not cands:
                continue
            ua, pa = axes_u[a]

            def score(b):
                ub, pb = axes_m[b]
                angle = float(np.arccos(np.clip(abs(float(np.dot(ua, ub))), -1.0, 1.0)))
                return angle + float(np.linalg.norm(pa - pb)) / reach

            best = min(cands, key=score)
            total += score(best)
            pairs[a] = (best, "structure")
            taken.add(best)
            changed = True
    return total


def _top_alignment(urdf, mjcf, matched, ju, jm, parent_u, parent_m, axes_u, WU, WM) -> RootPair:
    """With nothing matched and no fixed root on both sides (MuJoCo's import fuses a hand's static palm into the
    world: its fingers hang from the world), the pair of bodies of the first description's first top joint and
    one of the second's top joints whose alignment (E63) lets every joint match by structure best (``matched``:
    the pairs and taken joints so far, copied for each trial)."""
    tops = [a for a in ju if parent_u[a] is None]
    if not tops:
        return RootPair(None, None)
    body_u, body_m = {j.name: b.name for j, b in urdf.joints}, {j.name: b.name for j, b in mjcf.joints}
    best, best_score = RootPair(None, None), np.inf
    for b in (b for b in jm if parent_m[b] is None and jm[b].kind == ju[tops[0]].kind):
        trial = RootPair(body_u[tops[0]], body_m[b])
        axes_m = world_axes(mjcf, alignment(urdf, mjcf, trial, WU, WM), W=WM)
        score = _by_structure(dict(matched[0]), set(matched[1]), ju, jm, parent_u, parent_m, axes_u, axes_m)
        if score < best_score:
            best, best_score = trial, score
    return best


def coordinate_map(urdf: RobotParts, mjcf: RobotParts, mapping: JointMapping, *, axes: tuple[dict, dict],
                   signs: bool = True):
    """``[(urdf coordinate, mjcf coordinate, sign, offset)]`` of the matched joints (E52), signs and
    offsets from the joints as they are in ``urdf`` and ``mjcf`` now (``axes``: both sides' :func:`world_axes`,
    the second's aligned, E63; ``signs=False``: every sign 1, the coordinates taken as equal by name). Pairs of
    different kinds map the slots they share. :meth:`~urdf2links.compare.pairs.context.PairContext.coordinate_map`
    gives the axes."""
    ju = {j.name: j for j, _ in urdf.joints}
    jm = {j.name: j for j, _ in mjcf.joints}
    wu, wm = axes
    out = []
    for m in mapping.matches:
        a, b = ju[m.urdf], jm[m.mjcf]
        if len(JOINT_KINDS[a.kind]) == 1 and len(JOINT_KINDS[b.kind]) == 1:
            s, c = _sign_offset(a, b, wu[a.name][0], wm[b.name][0])
            if not signs:
                s, c = 1.0, b.ref - a.ref
            out.append((a.coordinates[0], b.coordinates[0], s, c))
            continue
        slots_b = dict(zip(JOINT_KINDS[b.kind], zip(b.coordinates, b.home)))
        state = a.kind == b.kind == "free"            # a floating root's pose is a state: the same one (E63)
        for slot, name, home in zip(JOINT_KINDS[a.kind], a.coordinates, a.home):
            if slot in slots_b:
                out.append((name, slots_b[slot][0], 1.0, 0.0 if state else float(slots_b[slot][1]) - float(home)))
    return out

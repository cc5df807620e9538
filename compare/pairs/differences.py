"""Two descriptions of one robot compared part by part: every difference, in the file's own terms.

Both descriptions are read as bodies and joints (:func:`urdf2links.parsers.parts.robot_parts`) and
folded the same way: every body welded to another (a URDF fixed joint, an MJCF body without joints,
or bodies MuJoCo's ``fusestatic`` merged) counts in the part of the moving joint that carries it
(:func:`urdf2links.parsers.parts.parts_model`, E51). So a conversion that merged bodies compares equal
to the file it came from, unless it merged them wrongly. Compared, for each matched joint
(:mod:`urdf2links.compare.pairs.mapping`):

- its part's ``mass`` (relative), ``com`` (metres) and ``inertia`` about the COM (relative, or radians when
  only the principal axes turned: an inertial frame whose ``rpy`` was lost), in the joint's body frame;
- its ``axis`` (radians; pi for a negated axis, which the mapping's sign absorbs), ``type``, ``limits``
  (in the first description's coordinates), ``armature``, ``damping`` and ``stiffness``;
- the ``origin`` of every body both sides have: its frame at home relative to the nearest ancestor body
  both sides have (metres, or radians when it turned more than it moved), so that a moved joint origin is
  named at that joint, and a fixed joint's lost ``rpy`` at that fixed joint (or, where the other side
  merged its child, at the next joint, ``through`` it);
- ``joint_missing`` and ``link_missing``: what one side has and the other does not;
- ``effort`` and ``velocity``: the largest joint force and speed each file states (``parts._actuator_limits``);
- ``frame_missing``: a massless welded frame the other side keeps neither as a body nor as a site
  (:mod:`~urdf2links.compare.pairs.frames`). ``coupling`` (:mod:`~urdf2links.compare.pairs.couplings`),
  ``constraint`` and ``collision`` (:mod:`~urdf2links.compare.pairs.collisions`) are read from the files
  by :func:`~urdf2links.compare.pairs.pair.compare_descriptions_of`.

Each :class:`Difference` carries how to undo it in the second description (copy the first
description's value in), which :mod:`urdf2links.compare.pairs.effects` uses to say what it does to
``A`` and ``G``. Differences below :data:`ROUNDING` (MuJoCo's XML writer prints 6 significant digits)
are counted, not listed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from urdf2links.dynamics.inertia import pseudo_inertia
from urdf2links.parsers.parts import JOINT_KINDS, RobotParts, parts_model

from .context import PairContext
from .frames import frame_differences
from .kinds import KINDS, PARTS, ROUNDING, Difference
from .roots import align_second, pose_words

__all__ = ["Difference", "Side", "side_model", "compare_descriptions", "ROUNDING", "KINDS", "PARTS", "split_H"]

# -- the second description as it is, or with differences undone --------------------------------------
@dataclass(frozen=True)
class Side:
    """The second description's parts as they are, or with differences undone (each undo returns a new Side)."""

    parts: RobotParts


def split_H(H) -> tuple[float, np.ndarray, np.ndarray]:
    """``H`` (4, 4) (E10) -> mass, COM (3,), inertia tensor about the COM (3, 3) (URDF convention)."""
    H = np.asarray(H, float)
    m = float(H[3, 3])
    if m <= 0.0:
        return 0.0, np.zeros(3), np.zeros((3, 3))
    c = H[:3, 3] / m
    Sc = H[:3, :3] - m * np.outer(c, c)
    return m, c, np.trace(Sc) * np.eye(3) - Sc


def side_model(side: Side, *, gravity=None):
    """The :class:`~urdf2links.parsers.parts.PartsModel` of ``side``, with ``gravity`` (3,) when given."""
    parts = side.parts if gravity is None else replace(side.parts, gravity=np.asarray(gravity, float))
    return parts_model(parts)


def group_H(parts: RobotParts, keep, W: dict) -> dict[str, np.ndarray]:
    """Body -> the pseudo-inertia (4, 4), in its frame, of itself and every welded body folded onto it: a body
    is folded onto its parent unless it has joints or is in ``keep`` (the bodies both descriptions have), so
    both sides fold what only one side has, and compare the rest body by body (E11 at home). ``W``: the home
    poses of ``parts``."""
    target, out = {}, {}
    for b in parts.bodies:
        own = b.joints or b.name in keep or b.parent is None
        target[b.name] = b.name if own else target[b.parent]
        t = target[b.name]
        X = np.linalg.inv(W[t]) @ W[b.name]
        out[t] = out.get(t, np.zeros((4, 4))) + X @ np.asarray(b.H, float) @ X.T
    return out


# -- helpers ---------------------------------------------------------------------------------------------
def _angle(R) -> float:
    return float(np.arccos(np.clip((np.trace(R) - 1.0) / 2.0, -1.0, 1.0)))


def _frame_turn(I1, I2) -> float | None:
    """The rotation (rad) that turns the principal axes of ``I1`` into those of ``I2`` when both have the
    same principal moments (to 1e-6 of the largest), else None."""
    w1, V1 = np.linalg.eigh(I1)
    w2, V2 = np.linalg.eigh(I2)
    scale = max(float(w1.max()), 1e-300)
    if np.max(np.abs(w1 - w2)) > 1e-6 * scale:
        return None
    gaps = np.abs(np.diff(w1)) <= 1e-6 * scale
    if gaps.all():
        return 0.0                                   # isotropic: no axes to turn
    if gaps.any():                                   # symmetric top: only the unique axis counts
        k = 2 if gaps[0] else 0
        return float(np.arccos(np.clip(abs(float(V1[:, k] @ V2[:, k])), -1.0, 1.0)))
    best = math.pi
    for s in ((1, 1, 1), (1, -1, -1), (-1, 1, -1), (-1, -1, 1)):
        R = V2 @ np.diag(s) @ V1.T
        if np.linalg.det(R) < 0:
            R = V2 @ np.diag([-x for x in s]) @ V1.T
        best = min(best, _angle(R))
    return best


def _vec(v) -> str:
    """A vector as a file writes it: ``(0 0 1)``, 4 significant digits, no ``-0``."""
    a = np.asarray(v, float)
    return "(" + " ".join(f"{x:.4g}" for x in np.where(np.abs(a) < 5e-7, 0.0, a)) + ")"


def _body_of(parts: RobotParts) -> dict[str, str]:
    return {j.name: b.name for j, b in parts.joints}


def _joint_label(b) -> str:
    """The name a body is known by in a difference: its (last) joint, its fixed joint, or itself."""
    if b.joints:
        return b.joints[-1].name
    return b.fixed_joint or b.name


# -- the comparison --------------------------------------------------------------------------------------
class _Comparer:
    """The differences of one pair (:func:`compare_descriptions`), read from its context."""

    def __init__(self, ctx: PairContext):
        self.ctx = ctx
        self.U, self.M, self.mapping = ctx.urdf, ctx.mjcf, ctx.mapping
        self.root, self.bodies = ctx.root, ctx.bodies          # the root pair among the bodies (structure, E63)
        self.pmU, self.pmM = ctx.model_urdf, ctx.model_mjcf
        self.WU = ctx.home_urdf
        self.WM = ctx.aligned_mjcf          # the second's world carried into the first's (E63)
        self.bu = {b.name: b for b in self.U.bodies}
        self.bm = {b.name: b for b in self.M.bodies}
        self.out: list[Difference] = []
        self.below = {k: 0 for k in KINDS}

    def add(self, d: Difference) -> None:
        if d.difference > ROUNDING[d.kind] or (ROUNDING[d.kind] == 0 and d.difference > 0):
            self.out.append(d)
        else:
            self.below[d.kind] += 1

    # joints ------------------------------------------------------------------------------------------
    def joints(self):
        ju = {j.name: j for j, _ in self.U.joints}
        jm = {j.name: j for j, _ in self.M.joints}
        bu, bm = _body_of(self.U), _body_of(self.M)
        for mt in self.mapping.matches:
            a, b = ju[mt.urdf], jm[mt.mjcf]
            links = (bu[a.name], bm[b.name])
            if a.kind != b.kind:
                self.add(Difference("type", a.name, b.name, a.source_type or a.kind, b.source_type or b.kind, 1.0,
                                    "", f"joint type {a.kind} against {b.kind}", links))
                continue
            if a.kind in ("hinge", "slide", "planar"):
                self._axis(a, b, mt, links, bu[a.name], bm[b.name])
            if len(JOINT_KINDS[a.kind]) == 1:
                self._limits(a, b, mt, links)
                self._effort(a, b, links)
                self._velocity(a, b, links)
            unit = {"hinge": ("N m s/rad", "N m/rad", "kg m^2", "N m"), "slide": ("N s/m", "N/m", "kg", "N")}.get(
                a.kind, ("", "", "", ""))
            for kind, attr, u in (("damping", "damping", unit[0]), ("stiffness", "stiffness", unit[1]),
                                  ("armature", "armature", unit[2]), ("friction", "friction", unit[3])):
                va, vb = float(getattr(a, attr)), float(getattr(b, attr))
                undo = (lambda s, n=b.name, v=va, at=attr: replace(s, parts=s.parts.with_joint(n, **{at: v})))
                self.add(Difference(kind, a.name, b.name, va, vb, abs(va - vb), u,
                                    f"{attr} {va:.6g} against {vb:.6g} {u}".rstrip(), links, undo=undo))

    def _axis(self, a, b, mt, links, bU, bM):
        """The axes compared in the frame of the nearest body both sides have above them (the roots' poses taken
        out, E63; a body frame placed differently is not an axis difference; a turned origin above the joint is
        one, beside the origin's)."""
        refU, refM, _ = self._reference(bU)
        RU, RM = self._rel(self.WU, refU, bU)[:3, :3], self._rel(self.WM, refM, bM)[:3, :3]
        ua, ub = RU @ np.asarray(a.axis, float), RM @ np.asarray(b.axis, float)
        ang = float(np.arccos(np.clip(float(np.dot(ua, ub)), -1.0, 1.0)))
        where = f"in the frame of {refU or 'the root'}"
        if mt.sign < 0 and ang > math.pi - 1e-5:
            what = f"axis negated: {_vec(ua)} against {_vec(ub)} {where}; q maps with sign -1"
        else:
            what = (f"axis turned by {ang:.4g} rad ({math.degrees(ang):.3g} deg): {_vec(ua)} against {_vec(ub)} {where}"
                    + (" (q maps with sign -1)" if mt.sign < 0 else ""))
        what += f"; as written: axis {_vec(a.axis)} in {bU}, {_vec(b.axis)} in {bM}"

        def undo(s, n=b.name, bM=bM, refM=refM, u=np.array(ua, float)):
            """The second's axis made the first's, in the frame of the body above as the second is now."""
            RM = self._rel(self.ctx.aligned(s.parts), refM, bM)[:3, :3]
            return replace(s, parts=s.parts.with_joint(n, axis=RM.T @ u))
        self.add(Difference("axis", a.name, b.name, a.axis, b.axis, ang, "rad", what, links, undo=undo))

    def _limits(self, a, b, mt, links):
        lu = (a.lower, a.upper)
        if b.lower is None:
            lm = (None, None)
        else:
            ends = sorted([mt.sign * (b.lower - mt.offset), mt.sign * (b.upper - mt.offset)])
            lm = (ends[0], ends[1])
        if lu == (None, None) and lm == (None, None):
            return
        if None in lu or None in lm:
            d, what = math.inf, "limited on one side only"
        else:
            d = max(abs(lu[0] - lm[0]), abs(lu[1] - lm[1]))
            what = f"range [{lu[0]:.6g}, {lu[1]:.6g}] against [{lm[0]:.6g}, {lm[1]:.6g}] (mapped)"
        self.add(Difference("limits", a.name, b.name, list(lu), list(lm), d, "rad" if a.kind == "hinge" else "m",
                            what, links))

    def _effort(self, a, b, links):
        """The largest joint force: URDF ``<limit effort>`` against what the MJCF states (``actuatorfrcrange``,
        an actuator's ``forcerange`` times its gear, a motor's ``ctrlrange`` times its gear, through a joint or
        a fixed tendon's coefficient: the smallest; ``parts._actuator_limits``), relative; inf when one side only."""
        if a.effort is None and b.effort is None:
            return
        u = "N m" if a.kind == "hinge" else "N"
        if a.effort is None or b.effort is None:
            d, what = math.inf, f"joint force limited on one side only: {a.effort} against {b.effort} {u}"
        else:
            d = abs(a.effort - b.effort) / max(a.effort, b.effort, 1e-300)
            src = " against ".join(f"{j.effort_source}" for j in (a, b) if j.effort_source) or "<limit effort>"
            what = f"effort {a.effort:.6g} {u} against +-{b.effort:.6g} {u} ({src})"
        self.add(Difference("effort", a.name, b.name, a.effort, b.effort, d, "relative", what, links))

    def _velocity(self, a, b, links):
        """The largest joint speed: URDF ``<limit velocity>`` against an MJCF velocity actuator's ``ctrlrange`` over
        its gear (relative). One side only is inf when the side without states speeds elsewhere (a URDF, or an
        MJCF with a velocity actuator on some joint); an MJCF without any velocity actuator cannot state one,
        and that is counted, not listed (MuJoCo's import keeps no speed limit)."""
        if a.velocity is None and b.velocity is None:
            return
        u = "rad/s" if a.kind == "hinge" else "m/s"
        if a.velocity is None or b.velocity is None:
            mute = [p for p, v in ((self.U, a.velocity), (self.M, b.velocity)) if v is None][0]
            if mute.format == "mjcf" and not mute.velocity_actuators:
                self.below["velocity"] += 1
                return
            d, what = math.inf, f"joint speed limited on one side only: {a.velocity} against {b.velocity} {u}"
        else:
            d = abs(a.velocity - b.velocity) / max(a.velocity, b.velocity, 1e-300)
            what = f"velocity {a.velocity:.6g} {u} against a velocity actuator's ctrlrange +-{b.velocity:.6g} {u}"
        self.add(Difference("velocity", a.name, b.name, a.velocity, b.velocity, d, "relative", what, links))

    # parts: mass, COM, inertia -----------------------------------------------------------------------
    def parts(self):
        self.keep_u, self.keep_m = set(self.bodies), set(self.bodies.values())
        gu, gm = group_H(self.U, self.keep_u, self.WU), group_H(self.M, self.keep_m, self.ctx.home_mjcf)
        for bU, bM in self.bodies.items():
            if bU not in gu or bM not in gm:
                continue
            moving = self.bu[bU].joints or self.bm[bM].joints
            if not moving and self._welded_to_world(bU):
                continue                  # on a fixed base: no term depends on it
            mu, cu, Iu = split_H(gu[bU])
            mm, cm, Im = split_H(gm[bM])
            folded = [b.name for b in self.U.bodies if b.name != bU and not b.joints and b.name not in self.keep_u
                      and self._onto(b.name) == bU]
            names = links = (bU, bM)          # a link's mass, COM and inertia: named by its link on each side
            rel = abs(mu - mm) / max(mu, mm, 1e-300)
            self.add(Difference("mass", *names, mu, mm, rel if abs(mu - mm) > 1e-12 else 0.0, "relative",
                                f"mass {mu:.6g} against {mm:.6g} kg" + (f" (with {', '.join(folded)} folded in)"
                                                                        if folded else ""), links,
                                undo=self._fix(bM, "mass", mu)))
            if mu <= 0.0 or mm <= 0.0:
                continue
            self.add(Difference("com", *names, cu, cm, float(np.linalg.norm(cu - cm)), "m",
                                "centre of mass in the body frame", links, undo=self._fix(bM, "com", cu)))
            scale = max(float(np.linalg.norm(Iu)), float(np.linalg.norm(Im)), 1e-300)
            rel = float(np.linalg.norm(Iu - Im)) / scale
            turn = _frame_turn(Iu, Im) if rel > ROUNDING["inertia"] else None
            if turn is not None and turn > ROUNDING["inertia"]:
                d, unit, what = turn, "rad", (f"inertial frame turned by {turn:.4g} rad (principal moments equal): "
                                              "as when an inertial's rpy is dropped")
            else:
                d, unit, what = rel, "relative", "inertia tensor about the COM, in the body frame"
            self.add(Difference("inertia", *names, Iu, Im, d, unit, what, links, undo=self._fix(bM, "inertia", Iu)))

    def _onto(self, body: str) -> str:
        b = self.bu[body]
        while not b.joints and b.name not in self.keep_u and b.parent is not None:
            b = self.bu[b.parent]
        return b.name

    def _welded_to_world(self, body: str) -> bool:
        b = self.bu[body]
        while b is not None:
            if b.joints:
                return False
            b = self.bu.get(b.parent) if b.parent is not None else None
        return True

    def _fix(self, body, key, value):
        keep, ctx = set(self.keep_m), self.ctx

        def undo(s, body=body, key=key, value=np.array(value, float) if np.ndim(value) else float(value)):
            """Set the group's ``key`` to ``value``: the body's own H is the new group's minus what is folded onto it."""
            group = group_H(s.parts, keep, ctx.home_of(s.parts))[body]
            m, c, I = split_H(group)
            new = {"mass": m, "com": c, "inertia": I}
            new[key] = value
            own = np.asarray(s.parts.body(body).H, float)
            H = pseudo_inertia(new["mass"], new["com"], new["inertia"]) - (group - own)
            return replace(s, parts=s.parts.replaced(body, H=0.5 * (H + H.T)))
        return undo

    # origins -----------------------------------------------------------------------------------------
    def _reference(self, bU: str) -> tuple[str | None, str | None, list[str]]:
        """The nearest ancestor body both sides have (None: the world), its name on each side, and the
        fixed joints of the first description between them whose child the other side does not have."""
        through = []
        p = self.bu[bU].parent
        while p is not None and p not in self.bodies:
            b = self.bu[p]
            if b.fixed_joint:
                through.append(b.fixed_joint)
            elif b.joints:
                through.append(b.joints[-1].name)
            p = b.parent
        return p, (None if p is None else self.bodies[p]), through[::-1]

    def origins(self):
        mj_last = {b.joints[-1].name: b.name for b in self.M.bodies if b.joints}
        lm = {v: k for k, v in mj_last.items()}
        for bU, bM in self.bodies.items():
            if (bU, bM) == (self.root.urdf, self.root.mjcf):
                continue                  # the roots' pose: root_pose, once
            refU, refM, through = self._reference(bU)
            if refM is not None and not self._is_ancestor(refM, bM):
                continue
            PU = self._rel(self.WU, refU, bU)
            PM = self._rel(self.WM, refM, bM)
            dp = float(np.linalg.norm(PU[:3, 3] - PM[:3, 3]))
            rot = _angle(PU[:3, :3].T @ PM[:3, :3])
            line = self._axis_line(bU, bM, PU, PM)
            dist = max(dp, line)
            d, unit = (rot, "rad") if rot > dist else (dist, "m")
            what = (f"frame at home relative to {refU or 'the world'}: moved {dp:.4g} m, turned {rot:.4g} rad"
                    + (f", joint axis line {line:.4g} m apart" if line > ROUNDING["origin"] else "")
                    + (f" (through {', '.join(through)}, merged on the other side)" if through else ""))
            self.add(Difference("origin", _joint_label(self.bu[bU]), lm.get(bM, self.bm[bM].fixed_joint or bM),
                                PU[:3, 3], PM[:3, 3], d, unit, what, (bU, bM), tuple(through),
                                undo=self._undo_origin(bU, bM, refU, refM), frames=(PU, PM)))

    def _is_ancestor(self, anc: str, body: str) -> bool:
        p = self.bm[body].parent
        while p is not None:
            if p == anc:
                return True
            p = self.bm[p].parent
        return False

    @staticmethod
    def _rel(W, ref, body):
        return W[body] if ref is None else np.linalg.inv(W[ref]) @ W[body]

    def _axis_line(self, bU, bM, PU, PM) -> float:
        """Distance between the joint axis lines of two matched bodies' last hinges, in the reference frame."""
        ju, jm = self.bu[bU].joints, self.bm[bM].joints
        if not ju or not jm or ju[-1].kind != "hinge" or jm[-1].kind != "hinge":
            return 0.0
        pu = PU[:3, :3] @ ju[-1].anchor + PU[:3, 3]
        pm = PM[:3, :3] @ jm[-1].anchor + PM[:3, 3]
        u = PU[:3, :3] @ ju[-1].axis
        d = pm - pu
        return float(np.linalg.norm(d - (d @ u) * u))

    def _undo_origin(self, bU, bM, refU, refM):
        PU = self._rel(self.WU, refU, bU)
        anchor = self.bu[bU].joints[-1].anchor if self.bu[bU].joints else None

        def undo(s):
            W = self.ctx.home_of(s.parts)
            parent = s.parts.body(bM).parent
            WP = np.eye(4) if parent is None else W[parent]
            WR = np.linalg.inv(self.ctx.alignment_of(s.parts, W)) if refM is None else W[refM]
            parts = s.parts.replaced(bM, pose=np.linalg.inv(WP) @ WR @ PU)
            b = parts.body(bM)
            if anchor is not None and b.joints and b.joints[-1].kind == "hinge":
                parts = parts.with_joint(b.joints[-1].name, anchor=np.array(anchor, float))
            return replace(s, parts=parts)
        return undo

    # the roots ----------------------------------------------------------------------------------------
    def root_pose(self):
        """The roots' pose difference, once (module :mod:`~urdf2links.compare.pairs.roots`, E63)."""
        rU, rM = self.root.urdf, self.root.mjcf
        if rU is None:
            return
        WU, WM = self.WU[rU], self.ctx.home_mjcf[rM]
        D = self.ctx.alignment
        dp, rot = float(np.linalg.norm(D[:3, 3])), _angle(D[:3, :3])
        floating = all(self.root.floating)
        d, unit = (rot, "rad") if rot > dp else (dp, "m")
        what = (f"root {rU} at {pose_words(WU, self.U.format)} against {rM} at {pose_words(WM, self.M.format)}: "
                f"moved {dp:.4g} m, turned {rot:.4g} rad ({math.degrees(rot):.3g} deg); "
                + ("a floating root's pose at home is a state (both start from the first's), not a description "
                   "difference" if floating else "the mount: where the robot is fixed in the world"))
        undo = None if floating else (lambda s: replace(s, parts=align_second(s.parts, self.ctx.alignment_of(s.parts))))
        self.add(Difference("root_pose", rU, rM, WU, WM, d, unit, what, (rU, rM), undo=undo))

    # missing -----------------------------------------------------------------------------------------
    def missing(self):
        bu, bm = _body_of(self.U), _body_of(self.M)
        for side, names, owner, pm, label in ((self.U, self.mapping.unmatched_urdf, bu, self.pmU, "urdf"),
                                              (self.M, self.mapping.unmatched_mjcf, bm, self.pmM, "mjcf")):
            ju = {j.name: j for j, _ in side.joints}
            for n in names:
                other = "mjcf" if label == "urdf" else "urdf"
                kw = {label: n, other: None}
                self.add(Difference("joint_missing", kw["urdf"], kw["mjcf"], n if label == "urdf" else None,
                                    n if label == "mjcf" else None, float(len(ju[n].coordinates)), "coordinates",
                                    f"joint {n!r} ({ju[n].kind}) of the {label} side has no match on the {other} side",
                                    (owner[n],)))
                body = owner[n]
                matched = body in self.bodies if label == "urdf" else body in self.bodies.values()
                last = side.body(body).joints[-1].name == n
                if not matched and last:
                    m = split_H(pm.part_H(body))[0]
                    kw = {label: body, other: None}
                    self.add(Difference("link_missing", kw["urdf"], kw["mjcf"], m if label == "urdf" else None,
                                        m if label == "mjcf" else None, m if m > 0 else 1e-300, "kg",
                                        f"body {body!r} ({m:.6g} kg with what is folded into it) moved by the unmatched "
                                        f"joint {n!r}", (body,)))


def compare_descriptions(ctx: PairContext) -> tuple[list[Difference], dict]:
    """Every difference between the pair's first description (``ctx.urdf``) and its second (``ctx.mjcf``) above
    :data:`ROUNDING` (module doc), in no order yet, and ``{kind: how many were below rounding}``."""
    c = _Comparer(ctx)
    c.root_pose()
    c.joints()
    c.parts()
    c.origins()
    c.missing()

    frames, kept = frame_differences(ctx.urdf, ctx.mjcf, c.WU, c.WM)
    c.out += frames
    c.below["frame_missing"] += kept
    return c.out, c.below

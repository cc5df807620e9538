"""A scene's constraints: ``[[constraint]]`` blocks, an MJCF file's equalities, resolved on the model's tree.

Scene form (docs/equations.md (E68)-(E70); every key checked, errors name the block and the key)::

    [[constraint]]
    name = "loop"                         # optional (constraint0, constraint1, ...)
    kind = "connect"                      # connect | weld | joint
    links = ["rocker", "world"]           # link 1, link 2 ("world", or omitted: the world)
    points = [[0.25, 0, 0], [0.3, 0, 0]]  # in each link's axes (URDF link axes; world axes for the world)
    # weld: points (default the origins) and rpy = [[r, p, y], [r, p, y]] (the welded frames; default none)
    # joint: coordinates = ["a", "b"], coefficients = [c0, c1, c2, c3, c4],
    #        reference = [qa0, qb0]  ->  q_a - qa0 = sum c_k (q_b - qb0)^k

For ``connect`` a single point (``points = [[...]]``) takes the second as MuJoCo does: the point of
link 2 (or of the world) where the first one is at the scene's initial state. An MJCF file's own
``<equality>`` elements (connect, weld, joint) are read too and act by default, as in MuJoCo (issue 45;
``[constraints] from_file = false`` or ``--open-loops`` drops them).

:class:`SceneConstraints` is what the plan carries: the :class:`~urdf2links.dynamics.constraints.ConstraintSet`
on the model, the fixed tendons (E76), and notes. A constrained scene runs through
:mod:`urdf2links.integration.constrained`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..dynamics.constraints import WORLD, Constraint, ConstraintSet
from ..dynamics.rotations import rpy_to_matrix
from ..errors import SceneError

__all__ = ["ConstraintSpec", "parse_constraints", "SceneConstraints", "scene_constraints", "describe_constraints",
           "constraint_toml"]

_KEYS = {"connect": ("name", "kind", "links", "points"), "weld": ("name", "kind", "links", "points", "rpy"),
         "joint": ("name", "kind", "coordinates", "coefficients", "reference")}


@dataclass(frozen=True)
class ConstraintSpec:
    """A ``[[constraint]]`` block as read (names not yet checked against a robot)."""

    name: str
    kind: str
    links: tuple = ()
    points: tuple = ()
    rpy: tuple = ()
    coordinates: tuple = ()
    coefficients: tuple = (0.0, 1.0, 0.0, 0.0, 0.0)
    reference: tuple = (0.0, 0.0)
    source: str = "scene"
    frames: tuple = ()
    """A weld's two frame rotations (3, 3) in the links' axes, instead of ``rpy`` (an MJCF weld's ``relpose``)."""
    lengths: tuple = ()
    """A ``tendon`` equality's (an MJCF file's only) one or two tendon lengths ``l = c . q`` as (n,) vectors of
    the model's coordinates; ``reference`` their lengths at the reference state."""


def constraint_options(r, data: dict) -> dict:
    """``[constraints]``: ``from_file`` (an MJCF file's equalities and fixed tendons act), ``mimic`` (a
    URDF's ``<mimic>`` joints as joint constraints, when loaded with ``mimic = "independent"``); both default true
    (issue 45: as in MuJoCo); and ``change_point`` (issue 45: ``"continue"``, the default, drops a row that loses
    its independence there and goes on, the event named; ``"stop"`` stops with the named DynamicsError)."""
    t = data.get("constraints", {})
    r.keys(t, ("from_file", "mimic", "change_point"), "constraints")
    out = {"change_point": r.choice(t.get("change_point", "continue"), "constraints.change_point",
                                    ("continue", "stop"))}        # issue 45: at a loop's change point
    for key, field_ in (("from_file", "file_constraints"), ("mimic", "mimic_constraints")):
        v = t.get(key, True)        # issue 45: the file's own equalities and mimic act unless the scene says not
        if not isinstance(v, bool):
            r.fail(f"constraints.{key}", f"must be true or false, got {v!r}")
        out[field_] = v
    return out


def mimic_specs(model, where, notes: list | None = None) -> list[ConstraintSpec]:
    """A URDF's ``<mimic>`` joints as joint constraints ``q_f = k q_l + offset`` (E70): MuJoCo's URDF import makes
    each the same joint equality (``joint1`` the follower, ``polycoef [offset, multiplier]``; issue 45)."""
    if model.coupling is not None:      # mimic = "coupled": the coupling is already exact (E42)
        return []
    joints = {j["name"]: j for j in model.info.get("joints", [])}
    out = []
    for j in joints.values():
        if j.get("mimic") is None:
            continue
        lead = joints.get(j["mimic"])
        if not j["coordinates"] or lead is None or not lead["coordinates"]:
            if notes is not None:   # a fixed joint's (or a missing leader's): MuJoCo's
                notes.append(f"<mimic> of joint {j['name']!r} (on {j['mimic']!r}): one of them has no coordinate "
                             "(fixed or missing): no coupling, as MuJoCo's URDF import adds none")   # import adds none
            continue
        out.append(ConstraintSpec(f"mimic_{j['name']}", "joint", coordinates=(j["coordinates"][0], lead["coordinates"][0]),
                                  coefficients=(j.get("mimic_offset", 0.0), j.get("mimic_multiplier", 1.0), 0.0, 0.0,
                                                0.0), source="URDF <mimic>"))
    return out      # none: no <mimic>, or mimic = "coupled" (the coupling is already exact, E42)


def parse_constraints(r, data: dict) -> tuple[ConstraintSpec, ...]:
    """``[[constraint]]`` blocks; ``r`` the scene's reader (its ``fail``, ``keys``, ``number``, ``vector``,
    ``choice``, ``items``, ``strings``)."""
    out, names = [], set()
    for k, item in enumerate(r.items(data, "constraint")):
        key = f"constraint[{k}]"
        if not isinstance(item, dict):
            r.fail(key, f"must be a table, got {item!r}")
        kind = r.choice(item.get("kind"), f"{key}.kind", tuple(_KEYS))
        r.keys(item, _KEYS[kind], key)
        name = item.get("name", f"constraint{k}")
        if not isinstance(name, str) or name in names:
            r.fail(f"{key}.name", f"must be a string not used by another constraint, got {name!r}")
        names.add(name)
        if kind == "joint":
            coords = r.strings(item.get("coordinates"), f"{key}.coordinates")
            if len(coords) not in (1, 2):
                r.fail(f"{key}.coordinates", f"must name one or two coordinates, got {list(coords)}")
            coef = item.get("coefficients", [0.0, 1.0])
            if not isinstance(coef, list) or not 1 <= len(coef) <= 5:
                r.fail(f"{key}.coefficients", f"must be a list of 1 to 5 numbers (c0 .. c4), got {coef!r}")
            coef = [r.number(c, f"{key}.coefficients[{i}]") for i, c in enumerate(coef)] + [0.0] * (5 - len(coef))
            ref = item.get("reference", [0.0, 0.0])
            if not isinstance(ref, list) or len(ref) != 2:
                r.fail(f"{key}.reference", f"must be two numbers [qa0, qb0], got {ref!r}")
            out.append(ConstraintSpec(name, kind, coordinates=coords, coefficients=tuple(coef),
                                      reference=tuple(r.number(v, f"{key}.reference[{i}]") for i, v in enumerate(ref))))
            continue
        links = r.strings(item.get("links"), f"{key}.links")
        if len(links) not in (1, 2):
            r.fail(f"{key}.links", f"must name one or two links (the second 'world' when omitted), got {list(links)}")
        pts = item.get("points", [] if kind == "weld" else None)
        if not isinstance(pts, list) or len(pts) > 2 or (kind == "connect" and not pts):
            r.fail(f"{key}.points", f"must be a list of one or two points [x, y, z] (m), got {pts!r}")
        points = tuple(r.vector(p, f"{key}.points[{i}]", quantity="length") for i, p in enumerate(pts))
        rpy = item.get("rpy", [])
        if not isinstance(rpy, list) or len(rpy) not in (0, 2):
            r.fail(f"{key}.rpy", f"must be two [roll, pitch, yaw] (rad), got {rpy!r}")
        out.append(ConstraintSpec(name, kind, links=links if len(links) == 2 else (*links, "world"), points=points,
                                  rpy=tuple(r.vector(v, f"{key}.rpy[{i}]") for i, v in enumerate(rpy))))
    return tuple(out)


@dataclass
class SceneConstraints:
    """The plan's constraints: ``cset`` (its ``constraints``, ``rows``), ``tendons`` (E76) and ``notes``."""

    cset: ConstraintSet
    tendons: tuple = ()
    notes: list = field(default_factory=list)

    def tendon_forces(self, t, q, qd):
        """Generalized forces (n,) of the fixed tendons and their power (dampers, actuators) (E76)."""
        f, P = np.zeros(q.size), 0.0
        for td in self.tendons:
            ft, pt = td.force(t, q, qd)
            f += ft
            P += pt
        return f, P

    def tendon_energy(self, q) -> float:
        return float(sum(td.energy(q) for td in self.tendons))


def _link(model, name, where, key):
    """``(tree link index, X)`` of a scene link name; the world is ``(-1, I)``."""
    frame_of = model.info.get("frame_of") or {nm: (nm, np.eye(4).tolist()) for nm in model.tree.link_names}
    if name in frame_of:
        tname, X = frame_of[name]
        return model.tree.link_index(tname), np.asarray(X, float)
    if name == "world":
        return WORLD, np.eye(4)
    raise SceneError(f"{where}: {key} names {name!r}, not a link of robot {model.name!r}; links are "
                     f"{sorted(frame_of)} (or 'world')")


def _resolve(spec: ConstraintSpec, model, q0, where, k) -> Constraint:
    key = f"[[constraint]] {spec.name!r}"
    if spec.kind == "tendon":
        c1, c2 = (tuple(np.asarray(v, float) for v in spec.lengths) + (None,))[:2]
        return Constraint(spec.name, "tendon", poly=np.array(spec.coefficients, float), ref1=spec.reference[0],
                          ref2=spec.reference[1], coef1=c1, coef2=c2, source=spec.source)
    if spec.kind == "joint":
        names = model.coordinate_names
        for c in spec.coordinates:
            if c not in names:
                raise SceneError(f"{where}: {key} coordinates names {c!r}, not a coordinate of robot {model.name!r}; "
                                 f"coordinates are {list(names)}")
        idx = [names.index(c) for c in spec.coordinates]
        return Constraint(spec.name, "joint", coord1=idx[0], coord2=idx[1] if len(idx) > 1 else -1,
                          poly=np.array(spec.coefficients, float), ref1=spec.reference[0], ref2=spec.reference[1],
                          source=spec.source)
    (l1, X1), (l2, X2) = (_link(model, nm, where, f"{key} links") for nm in spec.links)
    pts = list(spec.points) + [None] * (2 - len(spec.points))
    p1 = np.zeros(3) if pts[0] is None else pts[0]
    r1 = X1[:3, :3] @ p1 + X1[:3, 3]
    if pts[1] is None and spec.kind == "connect":      # MuJoCo's rule: where point 1 is at the initial state
        T = model.link_poses(q0)
        world = (T[l1] @ np.r_[r1, 1.0])[:3] if l1 != WORLD else r1
        r2 = world if l2 == WORLD else (np.linalg.inv(T[l2]) @ np.r_[world, 1.0])[:3]
    else:
        r2 = X2[:3, :3] @ (np.zeros(3) if pts[1] is None else pts[1]) + X2[:3, 3]
    R1, R2 = spec.frames or ((rpy_to_matrix(v) for v in spec.rpy) if spec.rpy else (np.eye(3), np.eye(3)))
    return Constraint(spec.name, spec.kind, link1=l1, link2=l2, point1=r1, point2=r2, frame1=X1[:3, :3] @ R1,
                      frame2=X2[:3, :3] @ R2, source=spec.source)


def scene_constraints(scene, model, specs=None) -> SceneConstraints | None:
    """The scene's constraints on ``model`` (``specs``: the scene's and the file's), or None without any."""
    specs = tuple(scene.constraints if specs is None else specs)
    tendons = tuple(getattr(scene, "tendons", ()))
    if not specs and not tendons:
        return None
    where = str(scene.path or scene.name)
    if scene.base is not None and specs:
        raise SceneError(f"{where}: [[constraint]] with a moving [base] is not modelled (the constraint rows of a "
                         "moving base depend on time); remove [base] or the constraints")
    q0, _ = scene.initial_state(model)
    cons = [_resolve(s, model, q0, where, k) for k, s in enumerate(specs)]
    return SceneConstraints(ConstraintSet(model, cons), tendons)


def describe_constraints(sc: SceneConstraints | None, model) -> list[str]:
    """The plan's lines about the constraints and tendons."""
    if sc is None:
        return []
    links = ("world",) + tuple(model.tree.link_names)
    lines = []
    for c in sc.cset.constraints:
        if c.kind == "joint":
            names = model.coordinate_names
            b = f", {names[c.coord2]}" if c.coord2 >= 0 else ""
            lines.append(f"  constraint {c.name!r} (joint, {c.source}): {names[c.coord1]}{b}, coefficients "
                         f"{np.round(c.poly, 9).tolist()}, 1 row")
        elif c.kind == "tendon":
            ls = [" + ".join(f"{v:g} {nm}" for v, nm in zip(u, model.coordinate_names) if v)
                  for u in (c.coef1, c.coef2) if u is not None]
            lines.append(f"  constraint {c.name!r} (tendon, {c.source}): lengths {' / '.join(ls)}, coefficients "
                         f"{np.round(c.poly, 9).tolist()}, 1 row")
        else:
            lines.append(f"  constraint {c.name!r} ({c.kind}, {c.source}): {links[c.link1 + 1]} point "
                         f"{np.round(c.point1, 9).tolist()} on {links[c.link2 + 1]} point {np.round(c.point2, 9).tolist()}"
                         f", {3 if c.kind == 'connect' else 6} rows")
    for td in sc.tendons:
        lines.append(f"  tendon {td.describe()}")
    lines += [f"  note: {n}" for n in sc.notes]
    lines.append("  constraints: solved with multipliers (E72), projected after every step (E74); the run takes the "
                 "scene's method in the compiled loops (urdf2links.integration.constrained); at a change point "
                 "[constraints] change_point decides (continue: the dependent row dropped there, the event named; stop: "
                 "the named error); points in the tree "
                 "links' axes (urdf2links inspect ROBOT shows them)")
    return lines


def constraint_toml(scene, value) -> list[str]:
    """The scene's ``[constraints]`` options and ``[[constraint]]`` blocks as TOML lines (``value`` formats a
    value), for :func:`~urdf2links.scenes.scene_toml.scene_toml`."""
    out = []
    stop = getattr(scene, "change_point", "continue") == "stop"
    if not getattr(scene, "file_constraints", True) or not getattr(scene, "mimic_constraints", True) or stop:
        out += ["[constraints]", f"from_file = {value(scene.file_constraints)}",
                f"mimic = {value(scene.mimic_constraints)}"] + ([f"change_point = {value('stop')}"] if stop else []) + [""]
    for c in scene.constraints:
        out += ["[[constraint]]", f"name = {value(c.name)}", f"kind = {value(c.kind)}"]
        if c.kind == "joint":
            out += [f"coordinates = {value(list(c.coordinates))}",
                    f"coefficients = {value([float(x) for x in c.coefficients])}",
                    f"reference = {value([float(x) for x in c.reference])}"]
        else:
            out += [f"links = {value(list(c.links))}"]
            if c.points:
                out += [f"points = {value([[float(x) for x in p] for p in c.points])}"]
            if c.rpy:
                out += [f"rpy = {value([[float(x) for x in r] for r in c.rpy])}"]
        out += [""]
    return out

"""Read a URDF into a validated :class:`~urdf2links.parsers.description.RobotDescription`.

The values are read from the XML tree itself (lxml) rather than from yourdfpy's model: yourdfpy
composes every ``<origin>`` into a 4x4 matrix (the ``rpy`` as written is lost), fills missing
inertia attributes with 1.0, accepts NaN, unknown joint types and dangling links without a word,
and falls back to a *recovering* XML parser on malformed files. Every number is checked where it
is read, so each error names the file, the line, the element, the attribute and the value, and
says what would fix it. The test suite cross-checks the result against yourdfpy on the corpus.

Reading like urdfdom (the ROS parser Pinocchio uses), ``strict=False`` (the default): what
urdfdom tolerates is read, and each tolerated thing is a note (``RobotDescription.notes``):
an unusual XML declaration version (:mod:`urdf2links.parsers.source`); visual/collision geometry
that cannot be used -- an unknown shape (``<capsule>``, ``<plane>``), a negative size, extra
elements in ``<geometry>`` (the first shape is read), unreadable numbers -- kept as an unusable
:class:`~urdf2links.parsers.description.Geometry` (ignored for the dynamics, refused by name only when
an inertia must be computed from it); a negative mass (left to the inertia audit); the ``<axis>``
of a fixed or floating joint (urdfdom does not read it); a ``<mimic>`` naming no joint (no effect
with ``mimic="independent"``). Every element the dynamics does not use is listed
(:mod:`urdf2links.parsers.inventory`). ``strict=True`` refuses all of these, as before. Files that truly
cannot be read stay errors in both modes: malformed XML, no links, a cycle, two roots, a link with
two parents, an unknown joint type, and non-numbers (or NaN, or a wrong count) where the
dynamics needs numbers (origins, axes, inertials, limits). docs/importing.md has the full table,
with urdfdom's behaviour for each case.

Public API: :func:`parse_urdf`, :func:`resolve_mesh_path`, :func:`require_mesh`.
"""

from __future__ import annotations

import difflib
import logging
import math

import numpy as np
from lxml import etree

from ..dynamics.rotations import matrix_to_rpy
from ..errors import MeshError, URDFError, URDFStructureError, URDFValueError
from ..ranges import out_of_range
from .description import (
    JOINT_TYPES,
    Geometry,
    Inertial,
    JointDescription,
    LinkDescription,
    Mimic,
    Origin,
    RobotDescription,
)
from .inventory import inventory_notes, joint_value_notes
from .mesh_paths import missing_mesh, require_mesh, resolve_mesh_path
from .source import read_source
from .xacro_input import is_xacro_path

__all__ = ["parse_urdf", "resolve_mesh_path", "require_mesh", "JOINT_TYPES"]

_log = logging.getLogger(__name__)

#: Joint types whose axis must be a nonzero vector.
AXIS_JOINT_TYPES = ("revolute", "continuous", "prismatic", "planar")
GEOMETRY_KINDS = ("box", "cylinder", "sphere", "mesh")
_INERTIA_ATTRS = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
_TOLERATED = " (or load with strict=False)"


def _children(el, tag: str) -> list:
    """Children of ``el`` named ``tag`` (without namespace or in the document's default one)."""
    default = el.nsmap.get(None)
    names = {tag, f"{{{default}}}{tag}"} if default else {tag}
    return [c for c in el if isinstance(c.tag, str) and c.tag in names]


def _child(el, tag: str):
    found = _children(el, tag)
    return found[0] if found else None


# --------------------------------------------------------------------------- numbers


class _Reader:
    """Reads attributes of one file; every error names the file, line, element and value.
    ``notes`` collects what was tolerated (``strict=False``)."""

    def __init__(self, label: str, *, strict: bool = False, version: tuple[int, int] = (1, 0)):
        self.label = label
        self.strict = strict
        self.version = version
        self.notes: list[str] = []

    def fail(self, el, what: str, problem: str, fix: str, cls=URDFValueError):
        line = f", line {el.sourceline}" if el is not None and el.sourceline else ""
        raise cls(f"{self.label}{line}: {what}: {problem}; {fix}", problem=problem)

    def note(self, el, what: str, text: str) -> None:
        line = f" (line {el.sourceline})" if el is not None and el.sourceline else ""
        self.notes.append(f"{what}{line}: {text}")

    def tolerate(self, el, what: str, problem: str, done: str, fix: str, cls=URDFValueError) -> None:
        """Strict: the error of :meth:`fail`. Otherwise a note that says what was done."""
        if self.strict:
            self.fail(el, what, problem, fix + _TOLERATED, cls)
        self.note(el, what, f"{problem}; {done}")

    def misspelt(self, el, attr: str, what: str) -> None:
        """When ``el`` lacks the required ``attr`` but has an unknown attribute spelt like it (``valeu`` for
        ``value``), the error names that attribute with a did-you-mean (issue 43)."""
        if el is None:
            return
        near = difflib.get_close_matches(attr, [a for a in el.attrib if a != attr], n=1, cutoff=0.6)
        if near:
            self.fail(el, f"{what} {near[0]}=\"{el.get(near[0])}\"", f"{near[0]}: did you mean {attr}? (the "
                      f"'{attr}' attribute is missing)", f"rename {near[0]} to {attr}")

    def text(self, el, attr: str, what: str) -> str:
        value = el.get(attr)
        if value is None or not value.strip():
            self.misspelt(el, attr, what)
            self.fail(el, what, f"the '{attr}' attribute is missing or empty",
                      f"add {attr}=\"...\"")
        return value.strip()

    def floats(self, el, attr: str, n: int, what: str, default=None, *, allow_one=False,
               quantity: str | None = None) -> np.ndarray:
        """``n`` finite numbers (``default`` when the attribute is absent; required if None), each
        within the physical range of ``quantity`` (:data:`urdf2links.ranges.RANGES`) when given."""
        raw = el.get(attr) if el is not None else None
        if raw is None:
            if default is None:
                self.misspelt(el, attr, what)
                self.fail(el, f"{what} {attr}", "the attribute is missing",
                          f"add {attr}=\"{' '.join(['0'] * n)}\" ({n} numbers)")
            return np.array(default, dtype=float)
        where = f"{what} {attr}=\"{raw}\""
        values = []
        for tok in raw.split():
            try:
                if "_" in tok:
                    raise ValueError(tok)
                values.append(float(tok))
            except ValueError:
                self.fail(el, where, f"'{tok}' is not a number",
                          f"write {n} decimal number{'s' if n > 1 else ''} separated by spaces"
                          " (leftover xacro ${...} or a comma?)")
        if allow_one and len(values) == 1 and n > 1:
            self.note(el, where, f"one number read as {n} equal ones (urdfdom reads exactly {n})")
            values = values * n
        if len(values) != n:
            self.fail(el, where, f"expected {n} number{'s' if n > 1 else ''}, found {len(values)}",
                      f"write exactly {n} numbers separated by spaces")
        for v in values:
            if not math.isfinite(v):
                self.fail(el, where, f"the value {v} is not finite",
                          "replace NaN/inf by a finite number")
            problem = out_of_range(v, quantity) if quantity else None
            if problem:
                self.fail(el, where, problem, "check the units and the number (docs/importing.md, "
                          "\"Physical ranges\")")
        return np.array(values, dtype=float)

    def scalar(self, el, attr: str, what: str, default=None, *, quantity: str | None = None) -> float:
        """One finite number; ``default`` when the attribute is absent (required if None)."""
        return float(self.floats(el, attr, 1, what, None if default is None else (default,), quantity=quantity)[0])

    def optional(self, el, attr: str, what: str, *, quantity: str | None = None) -> float | None:
        """One finite number, or None when ``el`` or the attribute is absent."""
        return None if el is None or el.get(attr) is None else self.scalar(el, attr, what, quantity=quantity)

    def direction(self, el, attr: str, n: int, what: str, default) -> np.ndarray:
        """``n`` numbers within +-1e6 whose norm is not below 1e-12 (a direction to normalize), or all
        zeros (the caller says whether a zero vector is allowed)."""
        v = self.floats(el, attr, n, what, default, quantity="multiplier")
        norm = math.hypot(*v)
        if v.any() and not (math.isfinite(norm) and norm >= 1e-12):
            self.fail(el, f"{what} {attr}=\"{el.get(attr)}\"", f"the vector's length {norm:g} cannot be "
                      "normalized", "give a direction of length about 1")
        return v

    def origin(self, parent, what: str) -> Origin:
        el = _child(parent, "origin")
        if el is None:
            return Origin()
        what = f"{what} <origin>"
        xyz = self.floats(el, "xyz", 3, what, (0.0, 0.0, 0.0), quantity="length")
        rpy = self.floats(el, "rpy", 3, what, (0.0, 0.0, 0.0))
        if el.get("quat_xyzw") is not None:
            rpy = self._quaternion(el, what, rpy)
        return Origin(xyz=xyz, rpy=rpy)

    def _quaternion(self, el, what: str, rpy) -> np.ndarray:
        """URDF 1.1's ``quat_xyzw`` (read for ``<robot version>`` >= 1.1, ignored before, as urdfdom)."""
        if self.version < (1, 1):
            self.tolerate(el, what, "quat_xyzw needs <robot version=\"1.1\"> or later",
                          "ignored, as urdfdom does (the rotation is rpy)", "declare version=\"1.1\" or use rpy")
            return rpy
        if el.get("rpy") is not None:
            self.fail(el, what, "both rpy and quat_xyzw are given", "give one of them")
        x, y, z, w = self.direction(el, "quat_xyzw", 4, what, None)
        norm = math.hypot(x, y, z, w)
        if norm == 0.0:
            self.fail(el, f"{what} quat_xyzw", "the quaternion is zero", "give a unit quaternion x y z w")
        x, y, z, w = x / norm, y / norm, z / norm, w / norm
        R = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                      [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                      [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
        return np.array(matrix_to_rpy(R))


# --------------------------------------------------------------------------- links


def _inertial(r: _Reader, el, what: str) -> Inertial:
    what = f"{what} <inertial>"
    mass_el = _child(el, "mass")
    if mass_el is None:
        r.fail(el, what, "there is no <mass> element", "add <mass value=\"...\"/> (kg) or remove "
               "the <inertial> to make the link massless")
    mass = r.scalar(mass_el, "value", f"{what} <mass>", quantity="mass")
    if mass < 0:
        r.tolerate(mass_el, f"{what} <mass value=\"{mass_el.get('value')}\">", "the mass is negative",
                   "kept as written (urdfdom reads it); the inertia audit reports it, inertia='repair' fixes it",
                   "give a mass >= 0 (kg)")
    inertia_el = _child(el, "inertia")
    if inertia_el is None:
        r.fail(el, what, "there is no <inertia> element",
               "add <inertia ixx=... ixy=... ixz=... iyy=... iyz=... izz=.../>")
    v = {a: r.scalar(inertia_el, a, f"{what} <inertia>", quantity="inertia") for a in _INERTIA_ATTRS}
    inertia = np.array([[v["ixx"], v["ixy"], v["ixz"]],
                        [v["ixy"], v["iyy"], v["iyz"]],
                        [v["ixz"], v["iyz"], v["izz"]]], dtype=float)
    return Inertial(mass=mass, origin=r.origin(el, what), inertia=inertia)


def _shape(r: _Reader, el, what: str):
    """The shape element of ``el``'s ``<geometry>``: the first known one; extras noted (strict: refused)."""
    geo = _child(el, "geometry")
    shapes = [c for c in geo if isinstance(c.tag, str)] if geo is not None else []
    known = [c for c in shapes if etree.QName(c).localname in GEOMETRY_KINDS]
    if geo is None or not shapes or (r.strict and len(shapes) != 1):
        problem = ("there is no <geometry>" if geo is None else
                   f"<geometry> holds {len(shapes)} shapes"
                   + (f" ({', '.join(etree.QName(c).localname for c in shapes)})" if shapes else ""))
        r.fail(geo if geo is not None else el, what, problem,
               f"give <geometry> exactly one of {', '.join(GEOMETRY_KINDS)}")
    shape = known[0] if known else shapes[0]
    extra = [etree.QName(c).localname for c in shapes if c is not shape]
    if extra:
        r.note(geo, f"{what} <geometry>", f"extra element(s) {', '.join(f'<{x}>' for x in extra)} ignored; "
               f"the shape read is <{etree.QName(shape).localname}> (urdfdom reads the first element)")
    return shape


def _geometry_strict(r: _Reader, el, what: str, directory, package_dirs) -> Geometry:
    origin = r.origin(el, what)
    shape = _shape(r, el, what)
    kind = etree.QName(shape).localname
    element, what = what, f"{what} <geometry><{kind}>"
    if kind not in GEOMETRY_KINDS:
        r.fail(shape, what, f"unknown shape <{kind}>", f"use one of {', '.join(GEOMETRY_KINDS)}")

    def positive(value, attr):
        if value < 0:
            r.fail(shape, f"{what} {attr}=\"{shape.get(attr)}\"", "a dimension is negative",
                   "give dimensions >= 0 (m)")
        return value

    if kind == "box":
        size = r.floats(shape, "size", 3, what, quantity="length")
        positive(size.min(), "size")
        return Geometry(kind, origin, size=size)
    if kind == "cylinder":
        return Geometry(kind, origin, radius=positive(r.scalar(shape, "radius", what, quantity="length"), "radius"),
                        length=positive(r.scalar(shape, "length", what, quantity="length"), "length"))
    if kind == "sphere":
        return Geometry(kind, origin, radius=positive(r.scalar(shape, "radius", what, quantity="length"), "radius"))
    filename = r.text(shape, "filename", what)
    scale = r.floats(shape, "scale", 3, what, (1.0, 1.0, 1.0), allow_one=True, quantity="scale")
    path = resolve_mesh_path(filename, directory=directory, package_dirs=package_dirs)
    missing = ""
    if path is None:     # issue 42: named (file, link, element, paths looked for); strict: refused
        m = missing_mesh(filename, source=r.label, directory=directory, package_dirs=package_dirs)
        r.tolerate(shape, what, m.problem, "kept without its file: the dynamics does not use it, and what does (an "
                   "inertia from geometry, a drawing, compare --against) refuses it by name", m.fix, MeshError)
        missing = m.text(f"{r.label}: {element}")
    return Geometry(kind, origin, filename=filename, path=path, scale=scale, missing=missing)


def _geometry(r: _Reader, el, what: str, directory, package_dirs) -> Geometry:
    """A ``<visual>``/``<collision>``. Not strict: one that cannot be used is kept as unusable
    (``problem`` set; its kind the shape's name) with a note, since the dynamics does not need it."""
    if r.strict:
        return _geometry_strict(r, el, what, directory, package_dirs)
    try:
        return _geometry_strict(r, el, what, directory, package_dirs)
    except URDFValueError as err:
        geo = _child(el, "geometry")
        shapes = [c for c in geo if isinstance(c.tag, str)] if geo is not None else []
        known = [c for c in shapes if etree.QName(c).localname in GEOMETRY_KINDS]
        kind = etree.QName((known or shapes)[0]).localname if shapes else "none"
        problem = err.problem
        r.note(el, f"{what} <geometry><{kind}>" if shapes else what,
               f"{problem}: ignored for the dynamics (a geometry is used only when a link's inertia is computed "
               "from it, and then this one is refused by name)")
        return Geometry(kind, Origin(), problem=f"{what}: {problem}")


def _link(r: _Reader, el, directory, package_dirs) -> LinkDescription:
    name = r.text(el, "name", "a <link>")
    what = f"link '{name}'"
    inertial_el = _child(el, "inertial")
    inertial = _inertial(r, inertial_el, what) if inertial_el is not None else None
    geoms = {}
    for kind in ("collision", "visual"):
        items = _children(el, kind)
        geoms[kind] = tuple(
            _geometry(r, g, f"{what} <{kind}>" + (f" #{i + 1}" if len(items) > 1 else ""),
                      directory, package_dirs)
            for i, g in enumerate(items))
    return LinkDescription(name, inertial, collisions=geoms["collision"], visuals=geoms["visual"])


# --------------------------------------------------------------------------- joints


def _axis(r: _Reader, el, what: str, jtype: str) -> np.ndarray:
    axis_el = _child(el, "axis")
    if axis_el is not None and axis_el.get("xyz") is None:
        r.note(axis_el, f"{what} <axis>", "no xyz attribute: the default axis (1, 0, 0) is used (urdfdom leaves "
               "the axis zero)")
    if jtype not in AXIS_JOINT_TYPES and not r.strict and axis_el is not None:
        try:
            return r.direction(axis_el, "xyz", 3, f"{what} <axis>", (1.0, 0.0, 0.0))
        except URDFValueError as err:
            r.note(axis_el, f"{what} <axis>", f"{err.problem}: ignored, a {jtype} joint has "
                   "no axis (urdfdom does not read it)")
            return np.array([1.0, 0.0, 0.0])
    axis = r.direction(axis_el, "xyz", 3, f"{what} <axis>", (1.0, 0.0, 0.0))
    if jtype in AXIS_JOINT_TYPES and not np.any(axis):
        r.fail(axis_el, f"{what} <axis xyz=\"{axis_el.get('xyz')}\">",
               f"a {jtype} joint needs a nonzero axis", "give a direction such as \"0 0 1\"")
    return axis


def _limits(r: _Reader, el, what: str, jtype: str) -> dict:
    """``<limit>`` (lower, upper, effort, velocity) and ``<dynamics>`` (damping, friction) as numbers."""
    limit_el, dyn_el = _child(el, "limit"), _child(el, "dynamics")
    lw, dw = f"{what} <limit>", f"{what} <dynamics>"
    out = {f"limit_{a}": r.optional(limit_el, a, lw) for a in ("lower", "upper", "effort", "velocity")}
    out.update({a: r.optional(dyn_el, a, dw, quantity="damping") for a in ("damping", "friction")})
    if limit_el is None and jtype in ("revolute", "prismatic"):
        r.note(el, what, f"a {jtype} joint without <limit>: its range is unbounded (urdfdom refuses the file)")
    lo, hi = out["limit_lower"], out["limit_upper"]
    if lo is not None and hi is not None and lo > hi:
        r.note(limit_el, lw, f"lower {lo:g} > upper {hi:g}: no limit check for this joint")
        out["limit_lower"] = out["limit_upper"] = None
    if dyn_el is not None and out["damping"] is None and out["friction"] is None:
        r.note(dyn_el, dw, "neither damping nor friction is given: ignored (urdfdom refuses the file)")
    return out


def _joint(r: _Reader, el) -> JointDescription:
    name = r.text(el, "name", "a <joint>")
    what = f"joint '{name}'"
    jtype = el.get("type")
    if jtype not in JOINT_TYPES:
        problem = "there is no type attribute" if jtype is None else f"the type '{jtype}' is unknown"
        r.fail(el, what, problem, f"use one of: {', '.join(JOINT_TYPES)}")
    if jtype == "spherical":
        r.note(el, what, "type 'spherical' is an extension of URDF (urdfdom refuses it): three coordinates, "
               f"the ZYX angles '{name}.phi_x', '{name}.phi_y', '{name}.phi_z'")
    ends = {}
    for end in ("parent", "child"):
        end_el = _child(el, end)
        if end_el is None:
            r.fail(el, what, f"there is no <{end}> element", f"add <{end} link=\"...\"/>",
                   URDFStructureError)
        ends[end] = r.text(end_el, "link", f"{what} <{end}>")
    axis = _axis(r, el, what, jtype)
    mimic = None
    mimic_el = _child(el, "mimic")
    if mimic_el is not None:
        mw = f"{what} <mimic>"
        mimic = Mimic(joint=r.text(mimic_el, "joint", mw).strip(),
                      multiplier=r.scalar(mimic_el, "multiplier", mw, default=1.0, quantity="multiplier"),
                      offset=r.scalar(mimic_el, "offset", mw, default=0.0, quantity="state"))
    return JointDescription(name=name, type=jtype, parent=ends["parent"], child=ends["child"],
                            origin=r.origin(el, what), axis=axis, mimic=mimic, **_limits(r, el, what, jtype))


# --------------------------------------------------------------------------- tree


def _hint(name: str, names) -> str:
    close = difflib.get_close_matches(name, list(names), n=3)
    return f" (did you mean {', '.join(repr(c) for c in close)}?)" if close else ""


def _check_unique(r: _Reader, elements, names, kind: str) -> None:
    seen = {}
    for el, name in zip(elements, names):
        if name in seen:
            r.fail(el, f"{kind} '{name}'", f"the name is already used by the {kind} on line "
                   f"{seen[name]}", f"give every {kind} a unique name", URDFStructureError)
        seen[name] = el.sourceline


def _cycle(r: _Reader, links: dict, by_child: dict, unreached: list) -> None:
    """Raise the error that names the cycle through ``unreached[0]``."""
    link, cycle = unreached[0], []
    while link not in cycle:
        cycle.append(link)
        link = by_child[link].parent
    chain = cycle[cycle.index(link):][::-1]  # each link is the parent of the next
    first = min(range(len(chain)), key=lambda i: list(links).index(chain[i]))
    chain = chain[first:] + chain[:first]  # start where the file does
    path = " -> ".join([f"'{chain[0]}'"] + [f"[{by_child[c].name}] '{c}'" for c in chain[1:] + chain[:1]])
    names = ", ".join(f"'{by_child[c].name}'" for c in chain[1:] + chain[:1])
    r.fail(None, f"joints {names}", f"they form a cycle {path}",
           "a URDF is a tree: remove one joint of the cycle", URDFStructureError)


def _build_tree(r: _Reader, links: dict, joints: list, joint_els: list) -> tuple[str, list]:
    """Check the tree; return (root, joints in depth-first order, parents first)."""
    by_child: dict[str, JointDescription] = {}
    for j, el in zip(joints, joint_els):
        for end in ("parent", "child"):
            link = getattr(j, end)
            if link not in links:
                r.fail(el, f"joint '{j.name}' <{end} link=\"{link}\">",
                       f"there is no link named '{link}'{_hint(link, links)}",
                       "define that <link> or correct the name", URDFStructureError)
        if j.child in by_child:
            r.fail(el, f"link '{j.child}'", f"it is the child of two joints, '{by_child[j.child].name}'"
                   f" and '{j.name}'", "a URDF is a tree: give each link at most one parent joint "
                   "(closed loops are not supported)", URDFStructureError)
        by_child[j.child] = j
    children: dict[str, list] = {name: [] for name in links}
    for j in joints:
        children[j.parent].append(j)
    roots = [name for name in links if name not in by_child]
    order, seen = [], set()
    for root in roots:
        stack = [root]
        while stack:
            link = stack.pop()
            seen.add(link)
            for j in reversed(children[link]):
                stack.append(j.child)
            if link in by_child:
                order.append(by_child[link])
    unreached = [name for name in links if name not in seen]
    if unreached:  # every link has <= 1 parent, so the rest lie on cycles
        _cycle(r, links, by_child, unreached)
    if len(roots) > 1:
        r.fail(None, "links", f"they form {len(roots)} separate trees with roots "
               f"{', '.join(repr(x) for x in roots)}", "connect them with joints (e.g. a fixed "
               "joint) so that exactly one link is no joint's child, or delete stray links",
               URDFStructureError)
    # depth-first order, children in document order: parents come before children
    return roots[0], order


def _check_mimics(r: _Reader, joints: list, joint_els: list) -> None:
    """A ``<mimic>`` naming no joint (or its own): strict, an error; otherwise a note (no effect with
    ``mimic="independent"``; ``load_urdf(mimic="coupled")`` refuses it)."""
    joint_names = {j.name for j in joints}
    for j, el in zip(joints, joint_els):
        if j.mimic is not None and (j.mimic.joint not in joint_names or j.mimic.joint == j.name):
            problem = ("it mimics itself" if j.mimic.joint == j.name else
                       f"there is no joint named '{j.mimic.joint}'{_hint(j.mimic.joint, joint_names)}")
            r.tolerate(_child(el, "mimic"), f"joint '{j.name}' <mimic joint=\"{j.mimic.joint}\">", problem,
                       "no effect with mimic='independent' (urdfdom reads the file); mimic='coupled' refuses it",
                       "name an existing joint to follow, or remove <mimic>", URDFStructureError)


def _robot_version(root, label: str, notes: list[str]) -> tuple[int, int]:
    """``<robot version="x.y">`` (default 1.0); one urdfdom does not know is read as 1.0, with a note."""
    raw = (root.get("version") or "1.0").strip()
    try:
        major, minor = (int(p) for p in raw.split("."))
    except ValueError:
        major = minor = -1
    if (major, minor) not in ((1, 0), (1, 1), (1, 2)):
        notes.append(f"<robot version=\"{raw}\">: not a URDF version urdfdom knows (1.0 to 1.2); read as 1.0")
        return (1, 0)
    return (major, minor)


def parse_urdf(source, *, package_dirs=(), strict: bool = False, xacro_args=None) -> RobotDescription:
    """Parse and validate a URDF.

    ``source`` is a path (``str`` or ``Path``) to a ``.urdf`` file (or a ``.xacro`` file, expanded
    with ``xacro_args`` by :mod:`urdf2links.parsers.xacro_input`), or the URDF text itself (a string whose
    first non-blank character is ``<``). ``package_dirs`` are extra folders searched for
    ``package://`` meshes and ``$(find pkg)`` (see :func:`resolve_mesh_path`). ``strict=True``
    refuses what ``strict=False`` tolerates with a note (module doc).

    Returns a :class:`RobotDescription` with links in topological order (root first), joints in
    depth-first order (parents before children) and the reader's ``notes``. Raises a
    :class:`~urdf2links.errors.URDFError` subclass for every defect it does not tolerate.
    """
    package_dirs = tuple(package_dirs)
    src = read_source(source, strict=strict, xacro_args=xacro_args, package_dirs=package_dirs)
    root, label, directory = src.root, src.label, src.directory
    notes = list(src.notes)
    r = _Reader(label, strict=strict, version=_robot_version(root, label, notes))
    try:
        name = (root.get("name") or "").strip()
        if not name:
            name = src.stem
            _log.info("%s: <robot> has no name attribute; using %r", label, name)
            notes.append(f"<robot> has no name attribute: named {name!r} after the file (urdfdom refuses this)")
        link_els, joint_els = _children(root, "link"), _children(root, "joint")
        if not link_els:
            r.fail(root, f"robot '{name}'", "there are no <link> elements",
                   "a URDF needs at least one <link name=\"...\"/>" + (
                       " (a xacro file that only defines macros? load the file that calls them)"
                       if is_xacro_path(source) else ""), URDFStructureError)
        links = [_link(r, el, directory, package_dirs) for el in link_els]
        _check_unique(r, link_els, [l.name for l in links], "link")
        joints = [_joint(r, el) for el in joint_els]
        _check_unique(r, joint_els, [j.name for j in joints], "joint")
        link_map = {l.name: l for l in links}
        root_link, ordered = _build_tree(r, link_map, joints, joint_els)
        _check_mimics(r, joints, joint_els)
        order = [root_link] + [j.child for j in ordered]
        notes += r.notes + inventory_notes(root) + joint_value_notes(ordered)
        return RobotDescription(name=name, source=label, links={n: link_map[n] for n in order},
                                joints=tuple(ordered), root=root_link, directory=directory, notes=tuple(notes))
    except URDFError:
        raise
    except (KeyError, AttributeError, IndexError, TypeError, ValueError) as err:
        raise URDFValueError(f"{label}: cannot read the description ({type(err).__name__}: {err}); "
                             "check the file against the URDF specification") from err

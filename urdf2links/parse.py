"""Read a URDF into a validated :class:`~urdf2links.description.RobotDescription`.

The values are read from the XML tree itself (lxml, strict parser) rather than from
yourdfpy's model: yourdfpy composes every ``<origin>`` into a 4x4 matrix (the ``rpy`` as
written is lost), fills missing inertia attributes with 1.0, accepts NaN, unknown joint
types and dangling links without a word, and falls back to a *recovering* XML parser on
malformed files. Every number here is checked where it is read, so each error names the
file, the line, the element, the attribute and the value, and says what would fix it.
The test suite cross-checks the result against yourdfpy on the installed corpus.

Public API: :func:`parse_urdf`, :func:`resolve_mesh_path`, :func:`require_mesh`.
"""

from __future__ import annotations

import difflib
import logging
import math
import os
from pathlib import Path
from urllib.parse import unquote

import numpy as np
from lxml import etree

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
from .errors import MeshError, URDFError, URDFStructureError, URDFSyntaxError, URDFValueError

__all__ = ["parse_urdf", "resolve_mesh_path", "require_mesh", "JOINT_TYPES"]

_log = logging.getLogger(__name__)

#: Joint types whose axis must be a nonzero vector.
AXIS_JOINT_TYPES = ("revolute", "continuous", "prismatic", "planar")
GEOMETRY_KINDS = ("box", "cylinder", "sphere", "mesh")
_INERTIA_ATTRS = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")


# --------------------------------------------------------------------------- source


def _read_source(source) -> tuple[etree._Element, str, Path | None, str]:
    """Return (root element, label for messages, directory, fallback robot name)."""
    if isinstance(source, bytes):
        source = source.decode("utf-8")
    if isinstance(source, str) and source.lstrip().startswith("<"):
        label, directory, stem = "<string>", None, "robot"
        data = source.encode("utf-8")
        parser = etree.XMLParser(remove_comments=True, resolve_entities=False,
                                 no_network=True, encoding="utf-8")
    elif isinstance(source, (str, os.PathLike)):
        path = Path(source)
        label, stem = str(path), path.stem
        try:
            is_file, is_dir = path.is_file(), path.is_dir()
        except OSError as err:  # e.g. a name too long to be a path
            raise URDFError(f"{label[:80]}: not a readable path ({err.strerror}); pass the path "
                            "of a .urdf file or the URDF text itself (starting with '<')") from err
        if not is_file:
            why = "is a directory" if is_dir else "does not exist"
            raise URDFError(f"{label}: the URDF file {why}; pass the path of a .urdf file "
                            "or the URDF text itself (starting with '<')")
        directory = path.resolve().parent
        try:
            data = path.read_bytes()
        except OSError as err:
            raise URDFError(f"{label}: cannot read the URDF file ({err})") from err
        parser = etree.XMLParser(remove_comments=True, resolve_entities=False, no_network=True)
    else:
        raise TypeError(f"parse_urdf: source must be a path or URDF text, not {type(source).__name__}")
    try:
        root = etree.fromstring(data, parser=parser)
    except etree.XMLSyntaxError as err:
        line = f", line {err.lineno}" if getattr(err, "lineno", None) else ""
        raise URDFSyntaxError(f"{label}{line}: malformed XML: {err.msg}; fix the XML "
                              "(unclosed or mismatched tag, stray '&' or '<', truncated file?)") from err
    except ValueError as err:  # e.g. lxml refusing some encodings
        raise URDFSyntaxError(f"{label}: cannot parse the XML: {err}") from err
    if root is None:
        raise URDFSyntaxError(f"{label}: the document is empty; a URDF needs a <robot> element")
    tag = etree.QName(root).localname if isinstance(root.tag, str) else str(root.tag)
    if tag != "robot":
        raise URDFSyntaxError(f"{label}, line {root.sourceline}: the root element is <{tag}>, "
                              "not <robot>; a URDF file must have <robot name=\"...\"> as its "
                              "root (is this a xacro, SDF or MJCF file?)")
    return root, label, directory, stem


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
    """Reads attributes of one file; every error names the file, line, element and value."""

    def __init__(self, label: str):
        self.label = label

    def fail(self, el, what: str, problem: str, fix: str, cls=URDFValueError):
        line = f", line {el.sourceline}" if el is not None and el.sourceline else ""
        raise cls(f"{self.label}{line}: {what}: {problem}; {fix}")

    def text(self, el, attr: str, what: str) -> str:
        value = el.get(attr)
        if value is None or not value.strip():
            self.fail(el, what, f"the '{attr}' attribute is missing or empty",
                      f"add {attr}=\"...\"")
        return value.strip()

    def floats(self, el, attr: str, n: int, what: str, default=None, *, allow_one=False) -> np.ndarray:
        raw = el.get(attr) if el is not None else None
        if raw is None:
            if default is None:
                self.fail(el, f"{what} {attr}", "the attribute is missing",
                          f"add {attr}=\"{' '.join(['0'] * n)}\" ({n} numbers)")
            return np.array(default, dtype=float)
        where = f"{what} {attr}=\"{raw}\""
        tokens = raw.split()
        values = []
        for tok in tokens:
            try:
                if "_" in tok:
                    raise ValueError(tok)
                values.append(float(tok))
            except ValueError:
                self.fail(el, where, f"'{tok}' is not a number",
                          f"write {n} decimal number{'s' if n > 1 else ''} separated by spaces"
                          " (leftover xacro ${...} or a comma?)")
        if allow_one and len(values) == 1:
            values = values * n
        if len(values) != n:
            self.fail(el, where, f"expected {n} number{'s' if n > 1 else ''}, found {len(values)}",
                      f"write exactly {n} numbers separated by spaces")
        for v in values:
            if not math.isfinite(v):
                self.fail(el, where, f"the value {v} is not finite",
                          "replace NaN/inf by a finite number")
        return np.array(values, dtype=float)

    def scalar(self, el, attr: str, what: str, default=None) -> float:
        """One finite number; ``default`` when the attribute is absent (required if None)."""
        return float(self.floats(el, attr, 1, what, None if default is None else (default,))[0])

    def origin(self, parent, what: str) -> Origin:
        el = _child(parent, "origin")
        if el is None:
            return Origin()
        what = f"{what} <origin>"
        return Origin(xyz=self.floats(el, "xyz", 3, what, (0.0, 0.0, 0.0)),
                      rpy=self.floats(el, "rpy", 3, what, (0.0, 0.0, 0.0)))


# --------------------------------------------------------------------------- links


def _inertial(r: _Reader, el, what: str) -> Inertial:
    what = f"{what} <inertial>"
    mass_el = _child(el, "mass")
    if mass_el is None:
        r.fail(el, what, "there is no <mass> element", "add <mass value=\"...\"/> (kg) or remove "
               "the <inertial> to make the link massless")
    mass = r.scalar(mass_el, "value", f"{what} <mass>")
    if mass < 0:
        r.fail(mass_el, f"{what} <mass value=\"{mass_el.get('value')}\">", "the mass is negative",
               "give a mass >= 0 (kg)")
    inertia_el = _child(el, "inertia")
    if inertia_el is None:
        r.fail(el, what, "there is no <inertia> element",
               "add <inertia ixx=... ixy=... ixz=... iyy=... iyz=... izz=.../>")
    v = {a: r.scalar(inertia_el, a, f"{what} <inertia>") for a in _INERTIA_ATTRS}
    inertia = np.array([[v["ixx"], v["ixy"], v["ixz"]],
                        [v["ixy"], v["iyy"], v["iyz"]],
                        [v["ixz"], v["iyz"], v["izz"]]], dtype=float)
    return Inertial(mass=mass, origin=r.origin(el, what), inertia=inertia)


def _geometry(r: _Reader, el, what: str, directory, package_dirs) -> Geometry:
    origin = r.origin(el, what)
    geo = _child(el, "geometry")
    shapes = [c for c in geo if isinstance(c.tag, str)] if geo is not None else []
    if len(shapes) != 1:
        problem = ("there is no <geometry>" if geo is None else
                   f"<geometry> holds {len(shapes)} shapes"
                   + (f" ({', '.join(etree.QName(c).localname for c in shapes)})" if shapes else ""))
        r.fail(geo if geo is not None else el, what, problem,
               f"give <geometry> exactly one of {', '.join(GEOMETRY_KINDS)}")
    shape = shapes[0]
    kind = etree.QName(shape).localname
    what = f"{what} <geometry><{kind}>"
    if kind not in GEOMETRY_KINDS:
        r.fail(shape, what, f"unknown shape <{kind}>", f"use one of {', '.join(GEOMETRY_KINDS)}")

    def positive(value, attr):
        if value < 0:
            r.fail(shape, f"{what} {attr}=\"{shape.get(attr)}\"", "a dimension is negative",
                   "give dimensions >= 0 (m)")
        return value

    if kind == "box":
        size = r.floats(shape, "size", 3, what)
        positive(size.min(), "size")
        return Geometry(kind, origin, size=size)
    if kind == "cylinder":
        return Geometry(kind, origin, radius=positive(r.scalar(shape, "radius", what), "radius"),
                        length=positive(r.scalar(shape, "length", what), "length"))
    if kind == "sphere":
        return Geometry(kind, origin, radius=positive(r.scalar(shape, "radius", what), "radius"))
    filename = r.text(shape, "filename", what)
    scale = r.floats(shape, "scale", 3, what, (1.0, 1.0, 1.0), allow_one=True)
    path = resolve_mesh_path(filename, directory=directory, package_dirs=package_dirs)
    return Geometry(kind, origin, filename=filename, path=path, scale=scale)


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


def _joint(r: _Reader, el) -> JointDescription:
    name = r.text(el, "name", "a <joint>")
    what = f"joint '{name}'"
    jtype = el.get("type")
    if jtype not in JOINT_TYPES:
        problem = "there is no type attribute" if jtype is None else f"the type '{jtype}' is unknown"
        r.fail(el, what, problem, f"use one of: {', '.join(JOINT_TYPES)}")
    ends = {}
    for end in ("parent", "child"):
        end_el = _child(el, end)
        if end_el is None:
            r.fail(el, what, f"there is no <{end}> element", f"add <{end} link=\"...\"/>",
                   URDFStructureError)
        ends[end] = r.text(end_el, "link", f"{what} <{end}>")
    axis_el = _child(el, "axis")
    axis = r.floats(axis_el, "xyz", 3, f"{what} <axis>", (1.0, 0.0, 0.0))
    if jtype in AXIS_JOINT_TYPES and not np.any(axis):
        r.fail(axis_el, f"{what} <axis xyz=\"{axis_el.get('xyz')}\">",
               f"a {jtype} joint needs a nonzero axis", "give a direction such as \"0 0 1\"")
    lower = upper = None
    limit_el = _child(el, "limit")
    if limit_el is not None:
        lw = f"{what} <limit>"
        values = {a: r.scalar(limit_el, a, lw) if limit_el.get(a) is not None else None
                  for a in ("lower", "upper", "effort", "velocity")}  # effort, velocity: checked only
        lower, upper = values["lower"], values["upper"]
    mimic = None
    mimic_el = _child(el, "mimic")
    if mimic_el is not None:
        mw = f"{what} <mimic>"
        mimic = Mimic(joint=r.text(mimic_el, "joint", mw).strip(),
                      multiplier=r.scalar(mimic_el, "multiplier", mw, default=1.0),
                      offset=r.scalar(mimic_el, "offset", mw, default=0.0))
    return JointDescription(name=name, type=jtype, parent=ends["parent"], child=ends["child"],
                            origin=r.origin(el, what), axis=axis, mimic=mimic,
                            limit_lower=lower, limit_upper=upper)


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
        link, cycle = unreached[0], []
        while link not in cycle:
            cycle.append(link)
            link = by_child[link].parent
        chain = cycle[cycle.index(link):][::-1]  # each link is the parent of the next
        first = min(range(len(chain)), key=lambda i: list(links).index(chain[i]))
        chain = chain[first:] + chain[:first]  # start where the file does
        path = " -> ".join([f"'{chain[0]}'"] + [f"[{by_child[c].name}] '{c}'"
                                                 for c in chain[1:] + chain[:1]])
        names = ", ".join(f"'{by_child[c].name}'" for c in chain[1:] + chain[:1])
        r.fail(None, f"joints {names}", f"they form a cycle {path}",
               "a URDF is a tree: remove one joint of the cycle", URDFStructureError)
    if len(roots) > 1:
        r.fail(None, "links", f"they form {len(roots)} separate trees with roots "
               f"{', '.join(repr(x) for x in roots)}", "connect them with joints (e.g. a fixed "
               "joint) so that exactly one link is no joint's child, or delete stray links",
               URDFStructureError)
    # depth-first order, children in document order: parents come before children
    return roots[0], order


# --------------------------------------------------------------------------- entry point


def parse_urdf(source, *, package_dirs=()) -> RobotDescription:
    """Parse and validate a URDF.

    ``source`` is a path (``str`` or ``Path``) to a ``.urdf`` file, or the URDF text itself
    (a string whose first non-blank character is ``<``). ``package_dirs`` are extra folders
    searched for ``package://`` meshes (see :func:`resolve_mesh_path`).

    Returns a :class:`RobotDescription` with links in topological order (root first) and
    joints in depth-first order (parents before children). Raises a
    :class:`~urdf2links.errors.URDFError` subclass for every defect it detects.
    """
    root, label, directory, stem = _read_source(source)
    package_dirs = tuple(Path(p) for p in package_dirs)
    r = _Reader(label)
    try:
        name = (root.get("name") or "").strip()
        if not name:
            name = stem
            _log.info("%s: <robot> has no name attribute; using %r", label, name)
        link_els, joint_els = _children(root, "link"), _children(root, "joint")
        if not link_els:
            r.fail(root, f"robot '{name}'", "there are no <link> elements",
                   "a URDF needs at least one <link name=\"...\"/>", URDFStructureError)
        links = [_link(r, el, directory, package_dirs) for el in link_els]
        _check_unique(r, link_els, [l.name for l in links], "link")
        joints = [_joint(r, el) for el in joint_els]
        _check_unique(r, joint_els, [j.name for j in joints], "joint")
        link_map = {l.name: l for l in links}
        root_link, ordered = _build_tree(r, link_map, joints, joint_els)
        joint_names = {j.name for j in joints}
        for j, el in zip(joints, joint_els):
            if j.mimic is not None and (j.mimic.joint not in joint_names or j.mimic.joint == j.name):
                problem = ("it mimics itself" if j.mimic.joint == j.name else
                           f"there is no joint named '{j.mimic.joint}'{_hint(j.mimic.joint, joint_names)}")
                r.fail(_child(el, "mimic"), f"joint '{j.name}' <mimic joint=\"{j.mimic.joint}\">",
                       problem, "name an existing joint to follow, or remove <mimic>",
                       URDFStructureError)
        order = [root_link] + [j.child for j in ordered]
        return RobotDescription(name=name, source=label, links={n: link_map[n] for n in order},
                                joints=tuple(ordered), root=root_link, directory=directory)
    except URDFError:
        raise
    except (KeyError, AttributeError, IndexError, TypeError, ValueError) as err:
        raise URDFValueError(f"{label}: cannot read the description ({type(err).__name__}: {err}); "
                             "check the file against the URDF specification") from err


# --------------------------------------------------------------------------- meshes


def _package_bases(directory, package_dirs) -> list[Path]:
    bases = []
    if directory is not None:
        directory = Path(directory)
        bases += [directory, *directory.parents]
    bases += [Path(p) for p in package_dirs]
    bases += [Path(p) for p in os.environ.get("ROS_PACKAGE_PATH", "").split(os.pathsep) if p]
    return bases


def resolve_mesh_path(filename: str, *, directory=None, package_dirs=()) -> Path | None:
    """Find the file a ``<mesh filename>`` names; ``None`` when it cannot be found.

    - ``package://pkg/rest`` (also ``model://``): for each base folder -- the URDF's
      ``directory`` and its ancestors, then each of ``package_dirs``, then ``ROS_PACKAGE_PATH``
      -- try ``base/pkg/rest`` (and ``base/rest`` when ``base`` is itself named ``pkg``);
      then, as a fallback, ``base/rest`` for each base.
    - ``file:///abs/path`` is that path; ``file://rel`` is relative to ``directory``.
    - Otherwise an absolute path, or a path relative to ``directory`` (then ``package_dirs``).
    """
    candidates: list[Path] = []
    for scheme in ("package://", "model://"):
        if filename.startswith(scheme):
            pkg, _, rest = unquote(filename[len(scheme):]).partition("/")
            bases = _package_bases(directory, package_dirs)
            for base in bases:
                candidates.append(base / pkg / rest)
                if base.name == pkg:
                    candidates.append(base / rest)
            candidates += [base / rest for base in bases]
            break
    else:
        name = unquote(filename[len("file://"):]) if filename.startswith("file://") else filename
        path = Path(name).expanduser()
        if path.is_absolute():
            candidates.append(path)
        else:
            bases = ([Path(directory)] if directory is not None else []) + [Path(p) for p in package_dirs]
            candidates += [b / path for b in bases]
    for c in candidates:
        if c.is_file():
            return c.resolve()
    return None


def require_mesh(geometry: Geometry, *, link: str, source: str) -> Path:
    """The resolved path of a mesh geometry, or a :class:`MeshError` naming file, link and mesh."""
    if geometry.kind != "mesh":
        raise MeshError(f"{source}: link '{link}': the geometry is a {geometry.kind}, not a mesh")
    if geometry.path is not None and Path(geometry.path).is_file():
        return Path(geometry.path)
    fix = "correct the filename"
    if geometry.filename and geometry.filename.startswith(("package://", "model://")):
        pkg = geometry.filename.split("://", 1)[1].split("/", 1)[0]
        fix = (f"pass package_dirs=[<folder that contains '{pkg}'>] to parse_urdf, "
               "or correct the filename")
    raise MeshError(f"{source}: link '{link}': mesh '{geometry.filename}' was not found; {fix}")

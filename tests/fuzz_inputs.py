"""Inputs for the fuzz tests (tests/test_fuzz.py): random valid URDF trees, mutated URDF and scene text.

Everything is drawn through hypothesis (``data.draw``), so a failing example shrinks to a small one and
a fixed seed replays it. Three kinds of input:

- :func:`robot_text`: a random valid tree as URDF text (1-6 moving or fixed joints of every type, random
  origins, axes and consistent inertias, massless links, boxes, spheres and a real STL mesh);
- :func:`mutate_urdf`: such a text (or a shipped robot) changed the way a careless hand or a broken
  tool changes it: a number replaced by ``nan``, ``inf``, ``1e308``, ``-1``, a subnormal, garbage;
  an attribute or element deleted or duplicated; names duplicated; a parent swapped into a cycle; a
  joint type garbled; mesh paths such as ``../../etc/passwd``, ``/dev/zero``, a directory, a
  ``package://`` path climbing out of its package; the text truncated; an entity bomb or an
  external entity in front;
- :func:`mutate_scene`: a shipped scene (robots/*.toml) changed the same way, value by value, and
  written back as TOML (or truncated and garbled as text).
"""

from __future__ import annotations

import copy
import math
from pathlib import Path

import numpy as np
from hypothesis import strategies as st
from lxml import etree

ROOT = Path(__file__).resolve().parent.parent
ROBOTS = ROOT / "robots"
SHIPPED_URDF = sorted(p.name for p in ROBOTS.glob("*.urdf"))
SHIPPED_SCENES = sorted(p.name for p in ROBOTS.glob("*.toml"))
MESH = "meshes/tetra.stl"          # written by write_mesh_folder next to every mutant

# ---------------------------------------------------------------------------------------------- files


def write_mesh_folder(folder: Path) -> None:
    """``folder/meshes/tetra.stl`` (a closed tetrahedron, ASCII STL), ``folder/pkg/meshes/tetra.stl``
    (for ``package://pkg/meshes/tetra.stl``) and a directory named like a mesh."""
    facets = [((0, 0, 0), (0, 0.1, 0), (0.1, 0, 0)), ((0, 0, 0), (0.1, 0, 0), (0, 0, 0.1)),
              ((0, 0, 0), (0, 0, 0.1), (0, 0.1, 0)), ((0.1, 0, 0), (0, 0.1, 0), (0, 0, 0.1))]
    lines = ["solid tetra"]
    for f in facets:
        lines += ["facet normal 0 0 0", "outer loop", *(f"vertex {x} {y} {z}" for x, y, z in f), "endloop", "endfacet"]
    text = "\n".join(lines + ["endsolid tetra", ""])
    for sub in ("meshes", "pkg/meshes"):
        (folder / sub).mkdir(parents=True, exist_ok=True)
        (folder / sub / "tetra.stl").write_text(text)
    (folder / "meshes" / "folder.stl").mkdir(exist_ok=True)


# ------------------------------------------------------------------------------------ a valid tree

JOINT_TYPES = ("revolute", "continuous", "prismatic", "fixed", "floating", "planar", "spherical")


def _num(x: float) -> str:
    return repr(float(x))


def _vec(draw, lo, hi, n=3):
    return [draw(st.floats(lo, hi, allow_nan=False, allow_infinity=False)) for _ in range(n)]


def _angles(draw):
    """rpy: random, or with a pitch of exactly +-pi/2 (common in real files)."""
    rpy = _vec(draw, -math.pi, math.pi)
    if draw(st.integers(0, 4)) == 0:
        rpy[1] = draw(st.sampled_from([math.pi / 2, -math.pi / 2]))
    return rpy


def _inertial(draw) -> str:
    """A physically consistent inertial: positive principal moments meeting the triangle inequality,
    rotated by a random rpy, at a random COM."""
    m = draw(st.floats(0.05, 20.0))
    sigma = _vec(draw, 1e-4, 0.5)                     # second moments along the principal axes
    lam = [sigma[1] + sigma[2], sigma[0] + sigma[2], sigma[0] + sigma[1]]
    R = _rotation(_angles(draw))
    I = m * R @ np.diag(lam) @ R.T
    com = _vec(draw, -0.5, 0.5)
    return (f'<inertial><origin xyz="{" ".join(map(_num, com))}"/><mass value="{_num(m)}"/>'
            f'<inertia ixx="{_num(I[0, 0])}" ixy="{_num(I[0, 1])}" ixz="{_num(I[0, 2])}" iyy="{_num(I[1, 1])}" '
            f'iyz="{_num(I[1, 2])}" izz="{_num(I[2, 2])}"/></inertial>')


def _rotation(rpy):
    r, p, y = rpy
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


def _geometry(draw) -> str:
    kind = draw(st.sampled_from(["box", "sphere", "cylinder", "mesh", "none"]))
    if kind == "none":
        return ""
    shape = {"box": '<box size="0.1 0.2 0.3"/>', "sphere": '<sphere radius="0.05"/>',
             "cylinder": '<cylinder radius="0.04" length="0.3"/>',
             "mesh": f'<mesh filename="{draw(st.sampled_from([MESH, "package://pkg/" + MESH]))}"/>'}[kind]
    return f'<collision><origin xyz="0 0 0.05"/><geometry>{shape}</geometry></collision>'


@st.composite
def robot_text(draw, *, max_joints: int = 6) -> str:
    """URDF text of a random valid tree: ``link0`` the root (massless or not), each further link hanging
    from an earlier one by a joint of a random type. At least one moving joint; every link a joint moves
    has a consistent inertia, so ``A`` is positive definite (with a floating base too when the root has
    an inertia)."""
    n = draw(st.integers(1, max_joints))
    types = [draw(st.sampled_from(JOINT_TYPES)) for _ in range(n)]
    if all(t == "fixed" for t in types):
        types[0] = "revolute"
    links = [f'<link name="link0">{_inertial(draw) if draw(st.booleans()) else ""}</link>']
    joints = []
    for k, jtype in enumerate(types, start=1):
        parent = draw(st.integers(0, k - 1))
        axis = draw(st.one_of(st.sampled_from([[1, 0, 0], [0, 1, 0], [0, 0, 1], [0, 0, -1]]),
                              st.lists(st.floats(-1, 1), min_size=3, max_size=3).filter(
                                  lambda a: math.hypot(*a) > 0.1)))
        limit = '<limit lower="-2" upper="2" effort="10" velocity="3"/>' if jtype in ("revolute", "prismatic") else ""
        joints.append(f'<joint name="j{k}" type="{jtype}"><parent link="link{parent}"/><child link="link{k}"/>'
                      f'<origin xyz="{" ".join(map(_num, _vec(draw, -1, 1)))}" rpy="{" ".join(map(_num, _angles(draw)))}"/>'
                      f'<axis xyz="{" ".join(map(_num, axis))}"/>{limit}'
                      f'<dynamics damping="{_num(draw(st.floats(0, 1)))}"/></joint>')
        # a link a joint moves carries a full inertia (A is then positive definite: no velocity moves
        # nothing with mass); a link on a fixed joint may be massless (it folds into its parent)
        massless = jtype == "fixed" and draw(st.booleans())
        links.append(f'<link name="link{k}">{"" if massless else _inertial(draw)}{_geometry(draw)}</link>')
    body = "\n  ".join(links + joints)
    return f'<?xml version="1.0"?>\n<robot name="random">\n  {body}\n</robot>\n'


# ---------------------------------------------------------------------------------------- mutations

BAD_NUMBERS = ("nan", "NaN", "inf", "-inf", "1e308", "-1e308", "1e999", "-1", "0", "-0", "1e-320", "5e-324",
               "1e9", "1e15", "1e4", "2e4", "abc", "", " ", "1,5", "0x10", "${x}", "1_000", "1e", "--1",
               "1 2", "1 2 3 4", "nan nan nan", "1e308 1e308 1e308", "1e-320 0 0", "-1 -1 -1", "0 0 0")
#: finite numbers whose products overflow float64 (m c c^T, T H T^T, the audit's eigenvalues)
OVERFLOWING = ("1e308", "-1e308", "1.7e308", "1e200", "1e160", "3e154", "1e300 1e300 1e300", "0 0 1e200")
BAD_PATHS = ("../../etc/passwd", "/etc/passwd", "/dev/zero", "/dev/null", "/", "/proc/self/environ",
             "package://pkg/../../etc/passwd", "package://../etc/passwd", "package://pkg/%2e%2e/%2e%2e/etc/passwd",
             "file:///dev/zero", "meshes/folder.stl", "meshes/missing.stl", "~nobody_here/x.stl", "package://",
             "package:///etc/passwd", "C:\\meshes\\x.stl", "meshes/../meshes/tetra.stl", "tetra.stl")
BAD_TYPES = ("revolut", "REVOLUTE", "", "ball", "fixed ", "spherical", "planar", "floating")
ENTITY_BOMB = ('<?xml version="1.0"?>\n<!DOCTYPE robot [<!ENTITY a "aaaaaaaaaa"><!ENTITY b "&a;&a;&a;&a;&a;&a;&a;'
               '&a;&a;&a;"><!ENTITY c "&b;&b;&b;&b;&b;&b;&b;&b;&b;&b;"><!ENTITY d "&c;&c;&c;&c;&c;&c;&c;&c;&c;&c;">]>\n')
EXTERNAL_ENTITY = '<?xml version="1.0"?>\n<!DOCTYPE robot [<!ENTITY x SYSTEM "file:///etc/passwd">]>\n'


def _elements(root):
    return [el for el in root.iter() if isinstance(el.tag, str)]


def _mutate_tree(draw, root) -> None:
    """One structural mutation of the parsed URDF ``root`` (in place)."""
    els = _elements(root)
    op = draw(st.sampled_from(["number", "number", "number", "delete_attr", "delete_el", "duplicate_el",
                               "dup_name", "cycle", "type", "mesh", "unknown_el", "swap_child"]))
    if op in ("number", "delete_attr"):
        owners = [(el, a) for el in els for a in el.attrib]
        numeric = [(el, a) for el, a in owners if a in ("value", "xyz", "ixx", "ixy", "ixz", "iyy", "iyz", "izz",
                                                         "size", "radius", "length", "scale", "damping", "multiplier")]
        if not owners:
            return
        el, attr = draw(st.sampled_from(numeric if numeric and draw(st.booleans()) else owners))
        if op == "delete_attr":
            del el.attrib[attr]
        else:
            el.set(attr, draw(st.sampled_from(OVERFLOWING if draw(st.integers(0, 2)) == 0 else BAD_NUMBERS)))
    elif op in ("delete_el", "duplicate_el"):
        el = draw(st.sampled_from(els[1:] or els))
        parent = el.getparent()
        if parent is None:
            return
        if op == "delete_el":
            parent.remove(el)
        else:
            parent.insert(parent.index(el), etree.fromstring(etree.tostring(el)))
    elif op == "dup_name":
        named = [el for el in els if el.get("name") is not None and el.tag in ("link", "joint")]
        if len(named) >= 2:
            a, b = draw(st.sampled_from(named)), draw(st.sampled_from(named))
            a.set("name", b.get("name"))
    elif op in ("cycle", "swap_child"):
        joints = [el for el in els if el.tag == "joint" and el.find("parent") is not None and el.find("child") is not None]
        links = [el.get("name") for el in els if el.tag == "link" and el.get("name")]
        if joints and links:
            j = draw(st.sampled_from(joints))
            end = "parent" if op == "cycle" else "child"
            j.find(end).set("link", draw(st.sampled_from(links)))
    elif op == "type":
        joints = [el for el in els if el.tag == "joint"]
        if joints:
            draw(st.sampled_from(joints)).set("type", draw(st.sampled_from(BAD_TYPES)))
    elif op == "mesh":
        meshes = [el for el in els if el.tag == "mesh"]
        target = draw(st.sampled_from(meshes)) if meshes else None
        if target is None:
            links = [el for el in els if el.tag == "link"]
            if not links:
                return
            coll = etree.SubElement(draw(st.sampled_from(links)), "collision")
            target = etree.SubElement(etree.SubElement(coll, "geometry"), "mesh")
        target.set("filename", draw(st.sampled_from(BAD_PATHS)))
    else:
        el = draw(st.sampled_from(els))
        tag = draw(st.sampled_from(["{http://www.ros.org/wiki/xacro}macro", "gazebo", "capsule", "origin", "inertial",
                                    "mass", "limit", "mimic", "axis"]))
        etree.SubElement(el, tag)


def _text_mutation(draw, text: str) -> str:
    op = draw(st.sampled_from(["none", "none", "none", "truncate", "bomb", "external", "garbage", "bom"]))
    if op == "truncate":
        return text[:draw(st.integers(0, max(0, len(text) - 1)))]
    if op == "bomb":
        return ENTITY_BOMB + text.replace("<robot", '<robot note="&d;"', 1).split("?>", 1)[-1]
    if op == "external":
        return EXTERNAL_ENTITY + text.replace('name="link0"', 'name="&x;"', 1).split("?>", 1)[-1]
    if op == "garbage":
        i = draw(st.integers(0, len(text)))
        return text[:i] + draw(st.sampled_from(["<", "&", "\x00", "]]>", "<!--", "\ufeff", "<link>"])) + text[i:]
    if op == "bom":
        return "\ufeff" + text
    return text


@st.composite
def mutated_urdf(draw) -> str:
    """A random valid tree or a shipped robot, with 1-3 structural mutations and maybe one textual one."""
    if draw(st.booleans()):
        base = draw(robot_text(max_joints=4))
    else:
        base = (ROBOTS / draw(st.sampled_from(SHIPPED_URDF))).read_text()
    root = etree.fromstring(base.encode())
    for _ in range(draw(st.integers(1, 3))):
        _mutate_tree(draw, root)
    text = '<?xml version="1.0"?>\n' + etree.tostring(root, encoding="unicode")
    return _text_mutation(draw, text)


# ------------------------------------------------------------------------------------------- scenes

BAD_VALUES = (float("nan"), float("inf"), float("-inf"), 1e308, -1e308, -1, 0, -0.0, 1e-320, 1e9, 1e7, 1e12,
              2 ** 62, -(2 ** 62), 10 ** 30, 1e-16, 1e-300, 0.5, 3, True, "abc", "", [], [1, 2], {}, {"sines": 1},
              {"sines": [[1e308, 1e308]]}, {"times": [0, 1e-300], "values": [0, 1]}, {"constant": float("nan")}, "/dev/zero", "/",
              "../../etc/passwd")
#: numbers that are valid somewhere and extreme there (stiff springs, tight tolerances, violent base motions)
EXTREME_NUMBERS = (1e-12, 2.3e-14, 1e-3, 0.5, 2.0, 100.0, 1e3, 1e4, 1e5, 1e6, 1e9, -1e3, -1e6, 1, 7, 1000)
_KEYS = ("t_end", "rtol", "atol", "dt", "samples", "method", "magnitude", "direction", "stiffness", "damping",
         "rest", "value", "point", "z", "phi_y", "q", "qd", "link", "coordinate", "frame", "floating_base",
         "inertia", "mimic", "shipped", "urdf", "recharting", "link_poses", "from_urdf", "strict", "zz")


def _paths(obj, prefix=()):
    """Every (path, value) in a nested dict/list of parsed TOML."""
    out = [(prefix, obj)] if prefix else []
    if isinstance(obj, dict):
        for k, v in obj.items():
            out += _paths(v, prefix + (k,))
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            out += _paths(v, prefix + (i,))
    return out


def _set(obj, path, value, *, delete=False):
    for k in path[:-1]:
        obj = obj[k]
    if delete:
        del obj[path[-1]]
    else:
        obj[path[-1]] = value


def mutate_scene_data(draw, data: dict) -> dict:
    """1-3 mutations of a parsed scene: a value replaced (nan, inf, 1e308, negative, huge, wrong type),
    a key deleted, an unknown or known key added somewhere, a [run] setting pushed to an extreme."""
    for _ in range(draw(st.integers(1, 3))):
        paths = _paths(data)
        op = draw(st.sampled_from(["number", "number", "number", "value", "value", "delete", "add", "run"]))
        if op == "number":
            numbers = [p for p, v in paths if isinstance(v, (int, float)) and not isinstance(v, bool)]
            if numbers:
                _set(data, draw(st.sampled_from(numbers)), draw(st.sampled_from(EXTREME_NUMBERS + BAD_VALUES[:12])))
            continue
        if op == "run":
            run = data.setdefault("run", {})
            if isinstance(run, dict):
                run[draw(st.sampled_from(["t_end", "rtol", "atol", "dt", "samples", "method"]))] = copy.deepcopy(draw(
                    st.sampled_from(BAD_VALUES + ("RK4", "midpoint", "Radau", "BDF", "LSODA", 1e-30, 1e6, 10 ** 9))))
            continue
        if not paths:
            continue
        path, _ = draw(st.sampled_from(paths))
        if op == "value":
            _set(data, path, copy.deepcopy(draw(st.sampled_from(BAD_VALUES))))
        elif op == "delete" and isinstance(path[-1], str):
            _set(data, path, None, delete=True)
        else:
            target = data
            for k in path[:-1]:
                target = target[k]
            if isinstance(target, dict):
                target[draw(st.sampled_from(_KEYS))] = copy.deepcopy(draw(st.sampled_from(BAD_VALUES)))
    return data


def toml_text(data: dict) -> str:
    """A minimal TOML writer for parsed scenes: top-level values, then tables, then arrays of tables."""
    scalars = {k: v for k, v in data.items() if not isinstance(v, dict) and not _table_array(v)}
    lines = [f"{_key(k)} = {_value(v)}" for k, v in scalars.items()]
    for k, v in data.items():
        if isinstance(v, dict):
            lines += ["", f"[{_key(k)}]"] + [f"{_key(kk)} = {_value(vv)}" for kk, vv in v.items()]
        elif _table_array(v):
            for item in v:
                lines += ["", f"[[{_key(k)}]]"] + [f"{_key(kk)} = {_value(vv)}" for kk, vv in item.items()]
    return "\n".join(lines) + "\n"


def _table_array(v) -> bool:
    return isinstance(v, list) and bool(v) and all(isinstance(x, dict) for x in v)


def _key(k) -> str:
    k = str(k)
    return k if k.replace("_", "").replace("-", "").isalnum() else '"' + k.replace('"', '\\"') + '"'


def _value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return "nan" if math.isnan(v) else ("inf" if v > 0 else "-inf") if math.isinf(v) else repr(v)
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, list):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{_key(k)} = {_value(x)}" for k, x in v.items()) + "}"
    raise TypeError(v)


@st.composite
def mutated_scene(draw) -> tuple[str, str]:
    """(name, TOML text) of a shipped scene with 1-3 mutations of its values, or its text truncated or
    garbled."""
    import tomllib

    name = draw(st.sampled_from(SHIPPED_SCENES))
    text = (ROBOTS / name).read_text()
    if draw(st.integers(0, 5)) == 0:
        i = draw(st.integers(0, len(text)))
        return name, text[:i] + draw(st.sampled_from(["", "=", "[", "\x00", "]]", "nan", "\n[run]\nt_end = -1\n"]))
    return name, toml_text(mutate_scene_data(draw, tomllib.loads(text)))


# ------------------------------------------------------------------------- the known failures

def known_bad_urdf() -> list[tuple[str, dict]]:
    """(text, load options) of the failure classes issue 15 found by hand, run as explicit examples in every
    profile: finite values whose products overflow (before: a bare LinAlgError "Eigenvalues did not
    converge", ValueError "H must be a finite symmetric (4, 4) matrix", or NaN terms), device and escaping
    mesh paths read by a repair, an entity bomb and an external entity."""
    text = (ROBOTS / "pendulum.urdf").read_text()
    massless = text.replace('<mass value="1.3"/>', '<mass value="0"/>').replace(
        'ixx="0.05" iyy="0.05" izz="0.005"', 'ixx="0" iyy="0" izz="0"')
    cases = [(text.replace('<mass value="1.3"/>', f'<mass value="{v}"/>'), {}) for v in ("1e308", "-1e308", "1e200")]
    cases += [(text.replace('ixx="0.05"', f'ixx="{v}"'), {}) for v in ("1e308", "1e200")]
    cases += [(text.replace('<origin xyz="0 0 -0.7"', f'<origin xyz="{v}"'), {}) for v in ("0 0 1e200", "1e308 0 0")]
    cases += [(text.replace('<axis xyz="1 0 0"/>', '<axis xyz="1 0 0"/><origin xyz="1e200 0 0"/>'), {})]
    cases += [(text.replace('<axis xyz="1 0 0"/>', f'<axis xyz="{v}"/>'), {}) for v in ("1e308 1e308 0", "1e-320 0 0")]
    for path in ("/dev/zero", "package://pkg/../../etc/passwd", "../../../../../../etc/passwd", "meshes/folder.stl"):
        mesh = f'<collision><geometry><mesh filename="{path}"/></geometry></collision>'
        cases.append((massless.replace("</visual>\n  </link>", f"</visual>{mesh}\n  </link>"), {"inertia": "repair"}))
    cases.append((ENTITY_BOMB + text.split("?>", 1)[1].replace("<robot", '<robot note="&d;"', 1), {}))
    cases.append((EXTERNAL_ENTITY + text.split("?>", 1)[1].replace('name="rod"', 'name="&x;"', 1), {}))
    return cases

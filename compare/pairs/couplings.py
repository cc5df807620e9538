"""Coupled joints of two descriptions of one robot: kind ``coupling``.

A URDF couples a joint to another with ``<mimic joint= multiplier= offset=>`` (``q_f = m q_l + o``); an MJCF
with a joint equality (``<equality><joint joint1= joint2= polycoef=>``: ``q_1 - q_1,0 = c_0 + c_1 (q_2 - q_2,0)
+ ...``, read by :mod:`urdf2links.parsers.mjcf_constraints`). Both become ``(follower, leader) -> (multiplier,
offset)`` (``polycoef[1]``, ``polycoef[0]``; the higher terms are reported when nonzero), the second side's joint
names carried into the first's by the joint mapping. A coupling one side has and the other does not is a
difference of 1 row (it removes a coordinate); a matched one differs by the larger of ``|m_1 - m_2|`` and
``|o_1 - o_2|`` (1 and rad or m). A coupling changes the motion: ``coupling`` is a dynamic kind.
"""

from __future__ import annotations

from urdf2links.parsers.mjcf import is_mjcf_path
from urdf2links.parsers.mjcf_constraints import file_equalities
from urdf2links.parsers.urdf import parse_urdf

from .differences import ROUNDING, Difference
from .mapping import JointMapping

__all__ = ["couplings", "coupling_differences"]


def couplings(path, *, package_dirs=(), xacro_args=None) -> dict:
    """``{(follower, leader): (multiplier, offset, higher terms)}`` of a robot file (module doc)."""
    if is_mjcf_path(path):
        out = {}
        for r in file_equalities(path):
            if r["kind"] == "joint" and r["supported"] and r["active"] and r.get("joint2"):
                c = [float(x) for x in r["polycoef"]]
                out[(r["joint1"], r["joint2"])] = (c[1], c[0], tuple(c[2:]))
        return out
    desc = parse_urdf(path, package_dirs=package_dirs, xacro_args=xacro_args)
    moving = {j.name for j in desc.joints if j.type in ("revolute", "continuous", "prismatic")}
    return {(j.name, j.mimic.joint): (float(j.mimic.multiplier), float(j.mimic.offset), ())  # a mimic of a fixed
            for j in desc.joints if j.mimic is not None and j.name in moving               # joint, or naming no
            and j.mimic.joint in moving - {j.name}}                                         # joint, couples nothing


def _words(key, c) -> str:
    extra = f" + {list(c[2])} higher terms" if any(c[2]) else ""
    return f"{key[0]} = {c[0]:.6g} {key[1]} + {c[1]:.6g}{extra}"


def coupling_differences(first, second, mapping: JointMapping, *, load: dict | None = None) -> list[Difference]:
    """The ``coupling`` differences between the robot files ``first`` and ``second`` (module doc)."""
    load = {k: v for k, v in (load or {}).items() if k in ("package_dirs", "xacro_args")}
    a, b = couplings(first, **load), couplings(second, **load)
    back = {m.mjcf: m.urdf for m in mapping.matches}
    fwd = {m.urdf: m.mjcf for m in mapping.matches}
    b = {(back.get(f, f), back.get(l, l)): (c, (f, l)) for (f, l), c in b.items()}
    out = []
    for key, c in a.items():
        hit = b.pop(key, None)
        if hit is None:
            out.append(Difference("coupling", key[0], fwd.get(key[0]), list(c[:2]), None, 1.0, "rows",
                                  f"{_words(key, c)} couples the first description only", key))
            continue
        o, names = hit
        d = max(abs(c[0] - o[0]), abs(c[1] - o[1]), *(abs(x) for x in o[2] + c[2]))
        if d <= ROUNDING["coupling"]:
            continue
        out.append(Difference("coupling", key[0], names[0], list(c[:2]), list(o[:2]), float(d), "1",
                              f"multiplier, offset {c[0]:.6g}, {c[1]:.6g} against {o[0]:.6g}, {o[1]:.6g}: "
                              f"{_words(key, c)} against {_words(names, o)}", key))
    for key, (o, names) in b.items():
        out.append(Difference("coupling", back.get(names[0]), names[0], None, list(o[:2]), 1.0, "rows",
                              f"{_words(names, o)} couples the second description only", key))
    return out

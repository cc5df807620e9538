"""Coupled joints of two descriptions of one robot: kind ``coupling``.

A URDF couples a joint to another with ``<mimic joint= multiplier= offset=>`` (``q_f = m q_l + o``); an MJCF
with a joint equality (``<equality><joint joint1= joint2= polycoef=>``: ``q_1 - q_1,0 = c_0 + c_1 (q_2 - q_2,0)
+ ...``, read by :mod:`urdf2links.parsers.mjcf_constraints`). Both become ``(follower, leader) -> (multiplier,
offset)`` (``polycoef[1]``, ``polycoef[0]``; the higher terms are reported when nonzero), the second side's joint
names carried into the first's by the joint mapping. A coupling is one relation between two joints whichever
file calls which the follower: the second side's ``q_l = m q_f + o`` with the roles swapped is read as
``q_f = q_l / m - o / m`` (a Menagerie panda's ``finger_joint1 = finger_joint2`` against a URDF's
``panda_finger_joint2`` mimicking ``panda_finger_joint1``), and it is ONE difference that names both files' joints.
A coupling one side has and the other does not is a difference of 1 row (it removes a coordinate); a matched one
differs by the larger of ``|m_1 - m_2|`` and ``|o_1 - o_2|`` (1 and rad or m), in the first file's form. A
coupling changes the motion: ``coupling`` is a dynamic kind.
"""

from __future__ import annotations

from urdf2links.parsers.mjcf import is_mjcf_path
from urdf2links.parsers.mjcf import file_equalities
from urdf2links.parsers.urdf import parse_urdf

from .kinds import ROUNDING, Difference
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


def _swapped(c):
    """``q_f = m q_l + o`` read as ``q_l = q_f / m - o / m`` (None when it cannot be: m = 0 or higher terms)."""
    if c[0] == 0.0 or any(c[2]):
        return None
    return (1.0 / c[0], -c[1] / c[0], ())


def _pair_up(a: dict, b: dict, back: dict) -> tuple[list, list, list]:
    """``([(first's key, its coefficients, second's key as written, its coefficients in the first's form)], first
    only, second only)``: the second's couplings matched to the first's by the mapped joints, roles as written or
    swapped."""
    pairs, left = [], dict(b)
    for key, c in a.items():
        hit = None
        for kb, cb in left.items():
            fb, lb = back.get(kb[0], kb[0]), back.get(kb[1], kb[1])
            if (fb, lb) == key:
                hit = (kb, cb)
                break
            if (lb, fb) == key and _swapped(cb) is not None:
                hit = (kb, _swapped(cb))
                break
        if hit is not None:
            pairs.append((key, c, hit[0], hit[1]))
            del left[hit[0]]
    matched = {p[0] for p in pairs}
    return pairs, [(k, c) for k, c in a.items() if k not in matched], list(left.items())


def coupling_differences(first, second, mapping: JointMapping, *, load: dict | None = None) -> list[Difference]:
    """The ``coupling`` differences between the robot files ``first`` and ``second`` (module doc)."""
    load = {k: v for k, v in (load or {}).items() if k in ("package_dirs", "xacro_args")}
    a, b = couplings(first, **load), couplings(second, **load)
    back = {m.mjcf: m.urdf for m in mapping.matches}
    fwd = {m.urdf: m.mjcf for m in mapping.matches}
    pairs, first_only, second_only = _pair_up(a, b, back)
    out = []
    for key, c, kb, o in pairs:
        d = max(abs(c[0] - o[0]), abs(c[1] - o[1]), *(abs(x) for x in o[2] + c[2]))
        if d <= ROUNDING["coupling"]:
            continue
        written = b[kb]
        out.append(Difference("coupling", key[0], fwd.get(key[0], kb[0]), list(c[:2]), list(o[:2]), float(d), "1",
                              f"multiplier, offset {c[0]:.6g}, {c[1]:.6g} against {o[0]:.6g}, {o[1]:.6g} (the second's "
                              f"in the first's form): {_words(key, c)} against {_words(kb, written)}", key))
    for key, c in first_only:
        out.append(Difference("coupling", key[0], fwd.get(key[0]), list(c[:2]), None, 1.0, "rows",
                              f"{_words(key, c)} couples the first description only"
                              + (f" (its joints there: {fwd.get(key[0])}, {fwd.get(key[1])})"
                                 if key[0] in fwd and key[1] in fwd else ""), key))
    for kb, o in second_only:
        out.append(Difference("coupling", back.get(kb[0]), kb[0], None, list(o[:2]), 1.0, "rows",
                              f"{_words(kb, o)} couples the second description only"
                              + (f" (its joints there: {back.get(kb[0])}, {back.get(kb[1])})"
                                 if kb[0] in back and kb[1] in back else ""), kb))
    return out

"""The corrected description: ``--write-urdf OUT`` (and the list of every change, nothing changed silently).

A tree link's identified ``H`` goes back to the body that carries it (the first body folded into that tree
link, :class:`urdf2links.parsers.parts.PartsModel` ``frame_of``: ``r_t = X r_b``): ``H_b' = H_b + X^-1 (H_t' -
H_t) X^-T``, so the bodies folded with it keep their own. From ``H_b'`` (E10 inverted): ``m = H[3, 3]``, ``c =
H[:3, 3] / m``, ``S_C = H[:3, :3] - m c c^T`` and the inertia about the center of mass ``I = tr(S_C) 1 - S_C``,
written as ``<inertial>`` with ``rpy="0 0 0"``. A joint's damping and Coulomb friction go to ``<dynamics>``
(a negative value is written as 0, and its change says so). The armature has no URDF element: where the data cannot tell an
armature from the links' inertias the change goes to the inertias (:func:`urdf_values`, a move along the
unidentifiable directions, no torque changes); an armature identified by itself is listed as not written.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from lxml import etree

__all__ = ["Change", "planned_changes", "write_urdf", "write_mjcf", "inertial_of", "urdf_values",
           "inconsistent_bodies"]


@dataclass(frozen=True)
class Change:
    """One change: ``element`` (``link panda_link3`` / ``joint panda_joint2``), ``what`` (mass, com, inertia,
    damping, friction, armature), ``before``, ``after`` (numbers or lists), ``written`` (False: no place for it
    in the file's format, ``note`` says why)."""

    element: str
    what: str
    before: object
    after: object
    written: bool = True
    note: str = ""

    def line(self) -> str:
        def fmt(v):
            return "[" + ", ".join(f"{x:.6g}" for x in v) + "]" if isinstance(v, (list, tuple)) else f"{v:.6g}"
        return (f"{self.element} {self.what}: {fmt(self.before)} -> {fmt(self.after)}"
                + (f" (not written: {self.note})" if not self.written else f" ({self.note})" if self.note else ""))

    def to_json(self) -> dict:
        return {"element": self.element, "what": self.what, "before": self.before, "after": self.after,
                "written": self.written, "note": self.note}


def inertial_of(H) -> tuple[float, np.ndarray, np.ndarray]:
    """``(m, c (3,), I (3, 3) about the center of mass)`` of a pseudo-inertia ``H`` (module doc)."""
    H = np.asarray(H, float)
    m = float(H[3, 3])
    c = H[:3, 3] / m
    S = H[:3, :3] - m * np.outer(c, c)
    return m, c, np.trace(S) * np.eye(3) - S


def _carriers(built) -> dict:
    out = {}
    for body, (t, X) in built.frame_of.items():
        if t is not None and t not in out:
            out[t] = (body, X)
    return out


def _move_armature(params, N, v, fixed: dict, scale):
    """``v + N z`` with the entries of ``fixed`` ({index: value}) at their values, every link's H positive definite (margin 1e-9 of its mass),
    the least scaled move: a small semidefinite program (cvxpy, the identify extra); None when there is none."""
    import cvxpy as cp

    from urdf2links.identification import link_matrix

    z = cp.Variable(N.shape[1])
    x = v + N @ z
    E = [link_matrix(np.eye(10)[k]) for k in range(10)]
    cons = [x[i] == t for i, t in fixed.items()]
    for c in params.link_col:
        if c >= 0:
            H = sum(x[c + k] * E[k] for k in range(10))
            cons.append(H >> 1e-9 * max(v[c + 9], 1e-3) * np.eye(4))
    prob = cp.Problem(cp.Minimize(cp.sum_squares(cp.multiply(1.0 / scale, N @ z))), cons)
    try:
        prob.solve(solver="CLARABEL")
    except cp.error.SolverError:
        return None
    if prob.status != "optimal":
        return None
    out = v + N @ z.value
    for i, t in fixed.items():
        out[i] = t
    return out if all(np.linalg.eigvalsh(H)[0] > 0 for H in params.H(out)[params.link_col >= 0]) else None


def urdf_values(fit) -> np.ndarray:
    """The identified values moved along the unidentifiable directions (the base parameters' null space: no
    torque changes) so that each armature the data cannot tell from the links' inertias is back at the
    description's value, one joint at a time, every link's H kept positive definite (the least such move): a
    URDF has no armature element, its links' inertias carry the change instead. An armature identified by itself
    (or with no consistent move) keeps its value, and is listed as not written."""
    params, v = fit.parameters, fit.identified.copy()
    N = fit.base.null_space
    if N.size == 0:
        return v
    scale = np.maximum(np.abs(fit.described), 1e-3)
    fixed = {}
    for i in (i for i, k in enumerate(params.kind) if k == "armature"):
        if v[i] == fit.described[i] or np.max(np.abs(N[i])) <= 1e-12:
            continue                            # unchanged, or identified by itself: no unidentifiable direction
        try:
            moved = _move_armature(params, N, v, {**fixed, i: fit.described[i]}, scale)
        except ImportError:                     # without cvxpy: the armature stays, listed as not written
            moved = None
        if moved is not None:
            v, fixed[i] = moved, fit.described[i]
    size = np.maximum(np.abs(fit.described), np.abs(v))
    keep = np.abs(v - fit.described) <= np.maximum(1e-6 * size, 1e-9)      # fitting.CHANGED, NEGLIGIBLE
    return np.where(keep, fit.described, v)


def planned_changes(ident, values=None) -> tuple[list[Change], dict]:
    """Every change the fit asks for (``values``: the vector written, default the identified one), and the new
    ``H`` of each carrying body (body -> (4, 4) in its frame)."""
    f, pair = ident.fit, ident.pair
    params = f.parameters
    values = f.identified if values is None else values
    changed = values != f.described
    H0, H1 = f.link_H("described"), params.H(values)
    changes, new_H = [], {}
    for t, (body, X) in sorted(_carriers(pair.built).items()):
        if np.array_equal(H0[t], H1[t]):          # no entry of this link changed (fitting.CHANGED)
            continue
        Xi = np.linalg.inv(X)
        Hb = pair.parts.body(body).H + Xi @ (H1[t] - H0[t]) @ Xi.T
        new_H[body] = Hb
        m0, c0, I0 = inertial_of(pair.parts.body(body).H) if pair.parts.body(body).H[3, 3] > 0 else (0.0, np.zeros(3), np.zeros((3, 3)))
        m1, c1, I1 = inertial_of(Hb)
        changes += [Change(f"link {body}", "mass", m0, m1), Change(f"link {body}", "com", c0.tolist(), c1.tolist()),
                    Change(f"link {body}", "inertia (ixx iyy izz ixy ixz iyz)", _six(I0), _six(I1))]
    for i, name in enumerate(params.names):
        kind = params.kind[i]
        if kind in ("damping", "friction", "armature") and changed[i]:
            written = kind != "armature" or pair.parts.format == "mjcf"
            changes.append(Change(f"joint {params.owner[i]}", kind, float(f.described[i]), float(values[i]),
                                  written, "" if written else "a URDF has no armature element, and the links' "
                                  "inertias cannot carry this one (identified by itself, or only with an "
                                  "inconsistent inertia)"))
        elif kind == "offset" and changed[i]:
            changes.append(Change(f"joint {params.owner[i]}", "offset", float(f.described[i]),
                                  float(values[i]), False, "a constant torque has no element in a description"))
    return changes, new_H


def _six(I) -> list:
    return [float(I[0, 0]), float(I[1, 1]), float(I[2, 2]), float(I[0, 1]), float(I[0, 2]), float(I[1, 2])]


def _g(x) -> str:
    return repr(float(x))


def _clamped(changes, new_H):
    """A negative damping, friction or armature is written as 0, and its change says so."""
    out = []
    for c in changes:
        if c.element.startswith("joint ") and c.what in ("damping", "friction", "armature") and c.after < 0:
            import dataclasses

            c = dataclasses.replace(c, note=(c.note + "; " if c.note else "") + f"fitted {c.after:.3g} < 0: written as 0")
        out.append(c)
    return out, new_H


def inconsistent_bodies(new_H: dict) -> list[str]:
    """The bodies whose new H is not positive definite (a file MuJoCo refuses: the consistent fit is needed)."""
    return [b for b, H in new_H.items() if np.linalg.eigvalsh(H)[0] <= 0]


def write_urdf(ident, out) -> list[Change]:
    """DESCRIPTION (a URDF) with the identified values written to ``out`` (module doc); returns the changes."""
    pair = ident.pair
    if pair.parts.format != "urdf":
        raise ValueError(f"--write-urdf: {pair.description} is not a URDF; use --write-mjcf")
    changes, new_H = _clamped(*planned_changes(ident, urdf_values(ident.fit)))
    root = etree.parse(str(pair.description), etree.XMLParser(remove_comments=False)).getroot()
    links = {el.get("name"): el for el in root.findall("link")}
    for body, H in new_H.items():
        m, c, I = inertial_of(H)
        link = links[body]
        old = link.find("inertial")
        inertial = etree.Element("inertial")
        etree.SubElement(inertial, "origin", xyz=" ".join(_g(x) for x in c), rpy="0 0 0")
        etree.SubElement(inertial, "mass", value=_g(m))
        six = _six(I)
        etree.SubElement(inertial, "inertia", **{k: _g(v) for k, v in zip(("ixx", "iyy", "izz", "ixy", "ixz", "iyz"), six)})
        if old is not None:
            inertial.tail = old.tail
            link.replace(old, inertial)
        else:
            link.insert(0, inertial)
    joints = {el.get("name"): el for el in root.findall("joint")}
    for ch in changes:
        if ch.element.startswith("joint ") and ch.written and ch.what in ("damping", "friction"):
            el = joints[ch.element[6:]]
            dyn = el.find("dynamics")
            if dyn is None:
                dyn = etree.SubElement(el, "dynamics")
            dyn.set(ch.what, _g(max(ch.after, 0.0)))
    Path(out).parent.mkdir(parents=True, exist_ok=True)
    Path(out).write_text(etree.tostring(root, encoding="unicode") + "\n")
    return changes


def write_mjcf(ident, out) -> list[Change]:
    """DESCRIPTION (an MJCF file) with the identified values written to ``out``: each carrying body's ``<inertial>``
    (``pos``, ``mass``, ``fullinertia`` about the centre of mass, no ``quat``; added when the body took its inertia
    from its geoms), each joint's ``damping``, ``frictionloss`` and ``armature`` set on the ``<joint>`` (over its
    defaults); every number at full precision. Raises ValueError naming the body or joint the file does not hold
    itself (an ``<include>``d part)."""
    pair = ident.pair
    if pair.parts.format != "mjcf":
        raise ValueError(f"--write-mjcf: {pair.description} is not an MJCF file; use --write-urdf")
    changes, new_H = _clamped(*planned_changes(ident, urdf_values(ident.fit)))
    tree = etree.parse(str(pair.description), etree.XMLParser(remove_comments=False))
    root = tree.getroot()
    bodies = {el.get("name"): el for el in root.iter("body")}
    joints = {el.get("name"): el for el in root.iter("joint") if el.get("name")}
    for body, H in new_H.items():
        if body not in bodies:
            raise ValueError(f"--write-mjcf: body {body!r} is not written in {pair.description} itself (an include?); "
                             "write the change listed by hand")
        m, c, I = inertial_of(H)
        el = bodies[body]
        old = el.find("inertial")
        inertial = etree.Element("inertial", pos=" ".join(_g(x) for x in c), mass=_g(m),
                                 fullinertia=" ".join(_g(x) for x in _six(I)))
        if old is not None:
            inertial.tail = old.tail
            el.replace(old, inertial)
        else:
            el.insert(0, inertial)
    attribute = {"damping": "damping", "friction": "frictionloss", "armature": "armature"}
    for ch in changes:
        if ch.element.startswith("joint ") and ch.what in attribute:
            name = ch.element[6:]
            if name not in joints:
                raise ValueError(f"--write-mjcf: joint {name!r} is not written in {pair.description} itself")
            joints[name].set(attribute[ch.what], _g(max(ch.after, 0.0)))
    Path(out).parent.mkdir(parents=True, exist_ok=True)
    Path(out).write_text(etree.tostring(root, encoding="unicode") + "\n")
    return changes

"""Actuators as scene effects: MuJoCo's actuator law, exactly (docs/equations.md (E55)).

A scene's ``[[actuator]]`` block drives one coordinate through a joint transmission, with MuJoCo's
``general`` actuator (dynamics ``none``, gain ``fixed``, bias ``affine``) or one of its shortcuts::

    [[actuator]]
    coordinate = "elbow_joint"
    kind = "position"            # motor | position | velocity | general
    kp = 300.0                   # position: force = kp (ctrl - gear q) - kv gear q'
    kv = 30.0                    # position (optional) and velocity: force = kv (ctrl - gear q')
    gear = 1.0                   # every kind; motor: force = ctrl (gainprm 1)
    ctrl = { sines = [[0.8, 1.0, 0.0]] }   # a function of time (urdf2links.scenes.functions)
    ctrlrange = [-2.0, 2.0]      # optional: ctrl is clamped (ctrllimited)
    forcerange = [-20.0, 20.0]   # optional: the actuator's force is clamped (forcelimited)
    name = "elbow_servo"         # optional (default "<kind>:<coordinate>")
    # general: gainprm = [k], biasprm = [b0, b1, b2] as MuJoCo's

An MJCF robot's own actuators are named instead, and the scene sets only their control::

    [[actuator]]
    name = "shoulder_motor"      # an <actuator> of the file
    ctrl = 0.3

The law, per actuator, as MuJoCo's ``mj_transmission`` and ``mj_fwdActuation`` compute it for a
hinge or slide joint (``length = gear q``, ``velocity = gear q'``, ``moment = gear``)::

    c = clamp(ctrl(t), ctrlrange)                 when ctrlrange is given
    f = gain c + b0 + b1 gear q + b2 gear q'
    f = clamp(f, forcerange)                      when forcerange is given
    tau_i += gear f

Shortcuts, as MuJoCo's compiler expands them: ``motor`` gain 1, bias 0; ``position`` gain ``kp``,
bias ``(0, -kp, -kv)``; ``velocity`` gain ``kv``, bias ``(0, 0, -kv)``. :func:`hold_actuators` is
``--hold``: a position servo on every coordinate holding ``q0`` with gains from the mass matrix.
Only scenes that name actuators compute them (the plan's ``actuator`` term).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import SceneError
from .functions import Constant, TimeFunction

__all__ = ["ActuatorSpec", "Actuator", "ActuatorSet", "KINDS", "parse_actuators", "resolve_actuators",
           "actuator_forces", "hold_actuators", "HOLD_BANDWIDTH_HZ", "file_actuator", "describe_actuator"]

KINDS = ("motor", "position", "velocity", "general")
#: ``--hold``'s default bandwidth (Hz): slow enough that any robot's servos stay far from stiff, fast
#: enough that a robot held against gravity sags by ``g / (2 pi f)^2`` ~ 6 cm of lever arm at most.
HOLD_BANDWIDTH_HZ = 2.0
_KEYS = {"motor": ("gear",), "position": ("kp", "kv", "gear"), "velocity": ("kv", "gear"),
         "general": ("gainprm", "biasprm", "gear")}
_COMMON = ("coordinate", "kind", "ctrl", "ctrlrange", "forcerange", "name")


@dataclass(frozen=True)
class ActuatorSpec:
    """One ``[[actuator]]`` block as read from a scene: a scene actuator (``coordinate`` and the
    MuJoCo ``general`` numbers) or a file actuator (``coordinate`` None: ``name`` is an actuator of the
    MJCF robot, resolved by :func:`resolve_actuators`)."""

    name: str
    coordinate: str | None
    kind: str
    ctrl: TimeFunction
    gain: float = 1.0
    bias: tuple = (0.0, 0.0, 0.0)
    gear: float = 1.0
    ctrlrange: tuple | None = None
    forcerange: tuple | None = None
    source: str = "scene"           # scene | hold | file
    kp: float | None = None
    kv: float | None = None


@dataclass(frozen=True)
class Actuator:
    """An actuator resolved on a model: ``index`` the coordinate it drives, the ``general`` numbers,
    ``ctrl(t)``; ``joint`` the joint name MuJoCo's model gives it (route 1: the coordinate; an MJCF
    file: its joint)."""

    name: str
    coordinate: str
    index: int
    kind: str
    gain: float
    bias: tuple
    gear: float
    ctrl: TimeFunction
    ctrlrange: tuple | None
    forcerange: tuple | None
    source: str
    joint: str
    kp: float | None = None
    kv: float | None = None

    def force(self, t, q, qd) -> float:
        """The actuator's scalar force ``f`` (after both clamps) at ``t`` for the coordinate's ``q``,
        ``q'`` (E55)."""
        c = float(self.ctrl(t))
        if self.ctrlrange is not None:
            c = min(max(c, self.ctrlrange[0]), self.ctrlrange[1])
        b0, b1, b2 = self.bias
        f = self.gain * c + b0 + b1 * (self.gear * q) + b2 * (self.gear * qd)
        if self.forcerange is not None:
            f = min(max(f, self.forcerange[0]), self.forcerange[1])
        return f

    @property
    def velocity_gain(self) -> float:
        """``d tau / d q'`` of the unclamped law: ``b2 gear^2`` (negative for a damping servo)."""
        return self.bias[2] * self.gear * self.gear


@dataclass(frozen=True)
class ActuatorSet:
    actuators: tuple[Actuator, ...] = ()
    notes: tuple[str, ...] = ()


def describe_actuator(a) -> str:
    """One line: the law with its numbers."""
    if a.kind == "position":
        law = f"position kp {a.kp:g}" + (f", kv {a.kv:g}" if a.kv else "")
    elif a.kind == "velocity":
        law = f"velocity kv {a.kv:g}"
    elif a.kind == "motor":
        law = "motor"
    else:
        law = f"general gain {a.gain:g}, bias {list(a.bias)}"
    parts = [law, f"gear {a.gear:g}"]
    if a.ctrlrange is not None:
        parts.append(f"ctrlrange [{a.ctrlrange[0]:g}, {a.ctrlrange[1]:g}]")
    if a.forcerange is not None:
        parts.append(f"forcerange [{a.forcerange[0]:g}, {a.forcerange[1]:g}]")
    return ", ".join(parts) + f"; ctrl {a.ctrl.describe()}"


# -- reading ---------------------------------------------------------------------------------------
def _range(r, value, key) -> tuple[float, float]:
    if not isinstance(value, list) or len(value) != 2:
        r.fail(key, f"must be [low, high], got {value!r}")
    lo, hi = (r.number(v, f"{key}[{i}]", quantity="value") for i, v in enumerate(value))
    if not lo < hi:
        r.fail(key, f"low {lo:g} must be below high {hi:g} (MuJoCo's compiler refuses it too)")
    return lo, hi


def _params(r, value, key, size) -> list[float]:
    if not isinstance(value, list) or not 1 <= len(value) <= 10:
        r.fail(key, f"must be a list of 1 to 10 numbers (MuJoCo's {key.rsplit('.', 1)[-1]}), got {value!r}")
    out = [r.number(v, f"{key}[{i}]", quantity="damping") for i, v in enumerate(value)]
    if any(out[size:]):
        r.fail(key, f"only the first {size} entries act (gain 'fixed'{', bias affine' if size == 3 else ''}); "
                    f"the others must be 0, got {value!r}")
    return out[:size] + [0.0] * (size - len(out[:size]))


def parse_actuators(r, data: dict) -> tuple[ActuatorSpec, ...]:
    """``[[actuator]]`` blocks (module doc) as :class:`ActuatorSpec`; ``r`` the scene's reader (its
    ``fail``, ``keys``, ``number``, ``choice``, ``function``, ``items``). Every error names the block
    and the key."""
    out, names = [], set()
    for k, item in enumerate(r.items(data, "actuator")):
        key = f"actuator[{k}]"
        if not isinstance(item, dict):
            r.fail(key, f"must be a table, got {item!r}")
        if "ctrl" not in item:
            r.fail(f"{key}.ctrl", "missing: the actuator's control, a function of time (a number, {sines = ...}, ...)")
        if "coordinate" not in item:        # an actuator of the MJCF file, by name
            r.keys(item, ("name", "ctrl"), key)
            if not isinstance(item.get("name"), str):
                r.fail(key, "name the coordinate it drives (coordinate = '...', a scene actuator) or an actuator of "
                            "the MJCF file (name = '...'; the scene then sets only its ctrl)")
            spec = ActuatorSpec(item["name"], None, "file", r.function(item["ctrl"], f"{key}.ctrl"), source="file")
        else:
            spec = _scene_actuator(r, item, key)
        if spec.name in names:
            r.fail(f"{key}.name", f"{spec.name!r} is named twice: give each actuator its own name")
        names.add(spec.name)
        out.append(spec)
    return tuple(out)


def _scene_actuator(r, item, key) -> ActuatorSpec:
    if not isinstance(item["coordinate"], str):
        r.fail(f"{key}.coordinate", f"must name a coordinate, got {item['coordinate']!r}")
    kind = r.choice(item.get("kind", "motor"), f"{key}.kind", KINDS)
    r.keys(item, _COMMON + _KEYS[kind], key)
    gear = r.number(item.get("gear", 1.0), f"{key}.gear", quantity="multiplier")
    if gear == 0.0:
        r.fail(f"{key}.gear", "must not be 0 (the actuator would act on nothing)")
    kp = kv = None
    if kind == "motor":
        gain, bias = 1.0, (0.0, 0.0, 0.0)
    elif kind == "position":
        if "kp" not in item:
            r.fail(f"{key}.kp", "missing: a position servo's stiffness (N m/rad or N/m)")
        kp = r.number(item["kp"], f"{key}.kp", nonnegative=True, quantity="damping")
        kv = r.number(item.get("kv", 0.0), f"{key}.kv", nonnegative=True, quantity="damping")
        gain, bias = kp, (0.0, -kp, -kv)
    elif kind == "velocity":
        if "kv" not in item:
            r.fail(f"{key}.kv", "missing: a velocity servo's gain (N m s/rad or N s/m)")
        kv = r.number(item["kv"], f"{key}.kv", nonnegative=True, quantity="damping")
        gain, bias = kv, (0.0, 0.0, -kv)
    else:
        gain = _params(r, item.get("gainprm", [1.0]), f"{key}.gainprm", 1)[0]
        bias = tuple(_params(r, item.get("biasprm", [0.0]), f"{key}.biasprm", 3))
    return ActuatorSpec(
        name=item.get("name") if isinstance(item.get("name"), str) else f"{kind}:{item['coordinate']}",
        coordinate=item["coordinate"], kind=kind, ctrl=r.function(item["ctrl"], f"{key}.ctrl"), gain=gain,
        bias=tuple(float(b) for b in bias), gear=gear,
        ctrlrange=_range(r, item["ctrlrange"], f"{key}.ctrlrange") if "ctrlrange" in item else None,
        forcerange=_range(r, item["forcerange"], f"{key}.forcerange") if "forcerange" in item else None,
        kp=kp, kv=kv)


# -- resolving on a model -------------------------------------------------------------------------
def file_actuator(row: dict) -> str | None:
    """Why an actuator of an MJCF file (a row of ``model.info['actuators']``) cannot be a scene effect,
    or None when it can: a joint transmission on a hinge or slide, no activation dynamics, a fixed
    gain, an affine (or no) bias, no delay, no damping or armature of its own."""
    why = []
    if row["trntype"] == "tendon":      # a fixed tendon's acts through it (resolve_actuators): this one is spatial
        why.append("its transmission is a spatial tendon (only joints and fixed tendons are modelled)")
    elif row["trntype"] not in ("joint", "jointinparent"):
        why.append(f"its transmission is a {row['trntype']} (only joints and fixed tendons are modelled)")
    elif row["joint_type"] not in ("hinge", "slide"):
        why.append(f"it drives a {row['joint_type']} joint, whose MuJoCo transmission (length = the rotation's "
                   "axis-angle . gear) is not a linear map of the ZYX angles: out of scope; drive the joint's "
                   "coordinates with scene actuators (coordinate = ...) instead")
    if row["dyntype"] != "none":
        why.append(f"it has activation dynamics ({row['dyntype']}: a state of its own, not modelled)")
    if row["gaintype"] != "fixed" or row["biastype"] not in ("none", "affine"):
        why.append(f"its gain is {row['gaintype']} and its bias {row['biastype']} (only fixed gain, affine bias)")
    for what in ("delay", "damping", "armature"):
        if row.get(what):
            why.append(f"it has a {what} of {row[what]:g} (not modelled)")
    if row.get("joint_actfrcrange") is not None:
        why.append(f"its joint {row['joint']!r} clamps the sum of its actuators' forces (actuatorfrcrange, not "
                   "modelled)")
    return "; ".join(why) or None


def resolve_actuators(specs, model, *, where="<scene>", file_tendons: bool | None = None) -> ActuatorSet:
    """The scene's actuators on ``model`` (:class:`ActuatorSet`): scene actuators on their coordinates,
    file actuators from ``model.info['actuators']`` (SceneError naming the actuator when the file has
    none of that name, or when it cannot be modelled: :func:`file_actuator` says why). A file actuator on a
    fixed tendon acts through its tendon (E76, :mod:`urdf2links.scenes.file_constraints`), which needs
    ``[constraints] from_file``: with ``file_tendons`` False (a scene without it) such an actuator is refused
    by name, never dropped (issue 43)."""
    names = model.coordinate_names
    table = {row["name"]: row for row in model.info.get("actuators", []) if row.get("name")}
    out, notes = [], []
    for s in specs:
        if s.coordinate is not None:
            if s.coordinate not in names:
                raise SceneError(f"{where}: [[actuator]] {s.name!r}: coordinate {s.coordinate!r} is not a coordinate "
                                 f"of robot {model.name!r}; coordinates are {list(names)}")
            out.append(Actuator(s.name, s.coordinate, names.index(s.coordinate), s.kind, s.gain, s.bias, s.gear,
                                s.ctrl, s.ctrlrange, s.forcerange, s.source, s.coordinate, s.kp, s.kv))
            continue
        row = table.get(s.name)
        if row is None:
            have = sorted(table)
            raise SceneError(f"{where}: [[actuator]] name = {s.name!r} is not an actuator of {model.name!r}"
                             + (f"; its actuators are {have}" if have else " (the robot file declares no named "
                                "actuator: give coordinate = '...' and the law instead)"))
        fixed = [t["name"] for t in model.info.get("tendons", []) if s.name in t["actuators"] and t["fixed"]]
        if row["trntype"] == "tendon" and fixed:
            if file_tendons is False:
                raise SceneError(f"{where}: [[actuator]] {s.name!r} drives the file's fixed tendon {fixed[0]!r}: a "
                                 "tendon acts only in a scene with [constraints] from_file = true (the default; "
                                 "not with from_file = false or --open-loops: the file's equalities and tendons act "
                                 "with it); remove from_file = false or --open-loops, or drive the joints with scene "
                                 "actuators (coordinate = ...)")
            continue        # issue 36: an actuator on a fixed tendon acts through its tendon (scenes/file_constraints.py)
        why = file_actuator(row)
        if why:
            raise SceneError(f"{where}: [[actuator]] {s.name!r}: the file's actuator cannot be a scene effect: {why}")
        coord = row["coordinates"][0]
        out.append(Actuator(s.name, coord, names.index(coord), row["kind"], row["gain"], tuple(row["bias"]),
                            row["gear"], s.ctrl, row["ctrlrange"], row["forcerange"], "file", row["joint"],
                            row.get("kp"), row.get("kv")))
    named = {s.name for s in specs}
    unused = [row["name"] or f"#{k}" for k, row in enumerate(model.info.get("actuators", [])) if row["name"] not in named]
    if unused:
        notes.append(f"actuators of the file the scene does not name ({', '.join(unused[:8])}"
                     + (f", ... ({len(unused)} in all)" if len(unused) > 8 else "") + "): no control, and MuJoCo's run "
                     "of the file switches them off")
    return ActuatorSet(tuple(out), tuple(notes))


def actuator_forces(actuators, t, q, qd, n) -> np.ndarray:
    """The actuators' generalized forces (n,) at ``t``, ``q``, ``qd`` (E55), in numpy: the oracle of the
    compiled right-hand side."""
    tau = np.zeros(n)
    for a in actuators:
        tau[a.index] += a.gear * a.force(t, float(q[a.index]), float(qd[a.index]))
    return tau


def hold_actuators(model, q0, *, bandwidth: float = HOLD_BANDWIDTH_HZ) -> tuple[ActuatorSpec, ...]:
    """``--hold``: a position servo on every coordinate, ``ctrl = q0_i``, critically damped at
    ``bandwidth`` Hz on its own inertia (E56): ``kp_i = A_ii (2 pi f)^2``, ``kv_i = 2 A_ii (2 pi f)``, with
    ``A = A(q0)`` (armature included)."""
    if not (isinstance(bandwidth, (int, float)) and math.isfinite(bandwidth) and 0.0 < bandwidth <= 1e4):
        raise SceneError(f"--hold-bandwidth must be a frequency in (0, 1e4] Hz, got {bandwidth!r}")
    q0 = np.asarray(q0, float)
    A = model.mass_matrix(q0)
    w = 2.0 * math.pi * float(bandwidth)
    out = []
    for i, name in enumerate(model.coordinate_names):
        a = float(A[i, i])
        kp, kv = a * w * w, 2.0 * a * w
        out.append(ActuatorSpec(f"hold:{name}", name, "position", Constant(float(q0[i])), gain=kp,
                                bias=(0.0, -kp, -kv), gear=1.0, source="hold", kp=kp, kv=kv))
    return tuple(out)


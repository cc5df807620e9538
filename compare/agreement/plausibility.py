"""The plausibility gate: what no robot does, checked on both engines' runs before any verdict (issue 43).

Two engines that agree about a robot falling through its floor have checked nothing. Before the
verdict says "agree" or "DIVERGE", :func:`plausibility` checks each engine's run (urdf2links' at
MuJoCo's sample times, and MuJoCo's) for (docs/reports.md, "The plausibility gate"):

* **penetration**: a ``[[contact]]`` sphere deeper in its ground than :data:`PENETRATION_FRACTION` of
  its radius (E77's depth ``d = h + r - n . x_c``);
* **base below the ground**: a floating root's origin below the scene's ground plane, or, in a scene
  without contact, below the floor of its MJCF file (a plane geom on the world, normal up), by more than
  :data:`BASE_MARGIN`; a robot that floats with neither has no such test;
* **joint limits**: a joint past its limit by more than :data:`LIMIT_MARGIN` of its range (neither engine
  enforces limits: :mod:`urdf2links.scenes.limits`);
* **speeds**: a joint's or the floating base's angular speed (``|E(phi) phi'|`` for the base, E43) past
  :func:`speed_bounds`' angular bound, a prismatic joint's or the base's linear speed past the linear one;
* **energy growth** in a passive scene (nothing that does work but dampers, springs, gravity and the
  contact): urdf2links' power balance ``max (h - h(0) - W)`` (``W`` its own dampers' and contact's work),
  MuJoCo's ``max (h - h(0))`` (its dissipated work is not measured; in a passive scene it is never positive,
  so ``h`` never rises above ``h(0)``), above :data:`ENERGY_GROWTH_BOUND` times the motion's energy scale.

A run that fails gets the verdict "implausible run: <reasons>", each reason naming the engine, the part,
the value and its bound (:mod:`urdf2links.compare.agreement.verdict`). Public API: :func:`plausibility`,
:func:`file_floors`, :func:`speed_bounds`, :class:`Plausibility`, :class:`Finding` and the bounds.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field

import numpy as np

from urdf2links.parsers.mjcf_state import rate_matrix
from urdf2links.scenes.contact import floating_root
from urdf2links.scenes.limits import limit_excursions

__all__ = ["Finding", "Plausibility", "plausibility", "file_floors", "speed_bounds", "passive_scene",
           "PENETRATION_FRACTION", "BASE_MARGIN", "LIMIT_MARGIN", "ANGULAR_SPEED_BOUND", "LINEAR_SPEED_BOUND",
           "SPEED_FACTOR", "ENERGY_GROWTH_BOUND", "INPUT_TERMS"]

#: A contact sphere deeper in the ground than this share of its radius fails: at 1 its centre is below the
#: plane, where one sphere touching a plane (E77) no longer describes the foot. The shipped contact scenes
#: reach at most 0.63 (quad12_drop's landing from 8 cm; 0.38 biped10_stand, 0.34 quad12_stand, measured).
PENETRATION_FRACTION = 1.0
#: A floating root's origin more than this (m) below its ground or floor fails: deeper than the 5 mm a
#: default ground settles (``urdf2links.scenes.contact.ground_contact``) with four times that to spare.
BASE_MARGIN = 0.02
#: A joint more than this share of its range past a limit fails (the limits being left out of both
#: engines): a real joint meets its hard stop at the limit; a quarter of the range past it (1.57 rad on a
#: +-pi joint) is a link through its neighbour, not a compliant stop.
LIMIT_MARGIN = 0.25
#: rad/s: no joint of a real robot turns this fast (about 950 rpm at the joint; a quadruped's direct-drive
#: knee reaches ~30 rad/s, an industrial arm's joints ~6 rad/s); nor does a robot's base spin this fast.
ANGULAR_SPEED_BOUND = 100.0
#: m/s: a prismatic joint or a floating base faster than this plus the free fall of the run (``|g| t_end``).
LINEAR_SPEED_BOUND = 10.0
#: A scene that starts faster than the bounds is allowed this multiple of its own largest initial speed.
SPEED_FACTOR = 10.0
#: Relative energy growth ``max (h - h(0) - W) / scale`` that fails a passive scene: a hundred times the
#: largest drift of a sound run measured (6.7e-5, tiago_no_hand in MuJoCo, reports/corpus), far below a
#: gain of the whole motion's energy that a wrong integration (a too-large step) produces.
ENERGY_GROWTH_BOUND = 0.01
#: The scene terms that are inputs doing work: a scene with none of them is passive.
INPUT_TERMS = ("Q", "tau", "base", "gravcomp", "actuator", "computed_torque")
#: Findings per check and engine shown in the verdict (all of them are in the JSON).
SHOWN = 3


@dataclass(frozen=True)
class Finding:
    """One thing a run did that no robot does: ``engine`` (``"urdf2links"`` or ``"MuJoCo"``), ``check``
    (``penetration``, ``base_below_ground``, ``joint_limit``, ``speed``, ``energy_growth``), ``part`` (the
    link, joint or coordinate), ``value`` and ``bound`` (``units``), at ``t`` (s), and ``what`` (the words,
    the part named in them)."""

    engine: str
    check: str
    part: str
    value: float
    bound: float
    units: str
    t: float
    what: str

    def text(self) -> str:
        units = f" {self.units}" if self.units else ""
        return (f"{self.engine}: {self.what} {self.value:.3g}{units} at t = {self.t:.4g} s "
                f"(bound {self.bound:.3g}{units})")

    def as_dict(self) -> dict:
        return dict(asdict(self), text=self.text())


@dataclass(frozen=True)
class Plausibility:
    """The gate's outcome: ``findings`` (empty when the runs are plausible), ``checks`` (what was checked, in
    words) and ``bounds`` (the thresholds used)."""

    findings: tuple[Finding, ...] = ()
    checks: tuple[str, ...] = ()
    bounds: dict = field(default_factory=dict)

    @property
    def plausible(self) -> bool:
        return not self.findings

    def reasons(self) -> list[str]:
        """The findings in words, at most :data:`SHOWN` per check and engine (the worst first), with a count
        of the rest."""
        out, groups = [], {}
        engines = {}
        for f in self.findings:     # a finding of both engines is said once, with the larger value
            engines.setdefault((f.check, f.part, f.what), []).append(f)
        for fs in engines.values():
            worst = max(fs, key=lambda f: f.value)
            both = " and ".join(dict.fromkeys(f.engine for f in fs))
            groups.setdefault(worst.check, []).append(Finding(both, *list(asdict(worst).values())[1:]))
        for check, fs in groups.items():
            fs = sorted(fs, key=lambda f: -f.value / f.bound if f.bound else -np.inf)
            out += [f.text() for f in fs[:SHOWN]]
            if len(fs) > SHOWN:
                out.append(f"{len(fs) - SHOWN} more of {check} (the JSON's plausibility.findings)")
        return out

    def text(self) -> str:
        """``"implausible run: ..."`` with the reasons, or ``"plausible run"``."""
        return "implausible run: " + "; ".join(self.reasons()) if self.findings else "plausible run"

    def summary(self) -> dict:
        return {"plausible": self.plausible, "text": self.text(), "findings": [f.as_dict() for f in self.findings],
                "checks": list(self.checks), "bounds": dict(self.bounds)}


def passive_scene(plan) -> bool:
    """No input does work (:data:`INPUT_TERMS`, and no actuator on a tendon (E76)): only gravity, springs,
    dampers and the contact act."""
    tendons = plan.constraints.tendons if plan.constraints is not None else ()
    return not (any(term in plan.terms for term in INPUT_TERMS) or any(t.actuators for t in tendons))


def file_floors(m) -> list[tuple[str, np.ndarray, float]]:
    """``(name, normal (3,), height)`` of every floor of a compiled MJCF file ``m`` (``mujoco.MjModel``): a
    plane geom on the world or a body welded to it, its normal within 25 degrees of +z; the plane is
    ``normal . x = height``."""
    import mujoco

    d = mujoco.MjData(m)
    mujoco.mj_kinematics(m, d)
    out = []
    for g in range(m.ngeom):
        if int(m.geom_type[g]) != int(mujoco.mjtGeom.mjGEOM_PLANE) or m.body_weldid[m.geom_bodyid[g]] != 0:
            continue
        n = np.array(d.geom_xmat[g], float).reshape(3, 3)[:, 2]
        if n[2] < np.cos(np.radians(25.0)):
            continue        # a wall or a ramp, not the floor
        out.append((mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_GEOM, g) or f"geom {g}", n,
                    float(n @ np.array(d.geom_xpos[g], float))))
    return out


def _slots(model) -> tuple[np.ndarray, tuple[str, ...]]:
    """``(angular (n,) bool, root)``: which coordinates are angles (a link's slots 3-5), the floating root's six."""
    coord = np.asarray(model.tree.coord)
    angular = np.zeros(model.n, bool)
    for p in range(coord.shape[0]):
        for s in range(6):
            if coord[p, s] >= 0:
                angular[int(coord[p, s])] = s >= 3
    return angular, floating_root(model)


def speed_bounds(plan, qd0, t_end: float) -> tuple[float, float]:
    """``(angular rad/s, linear m/s)``: :data:`ANGULAR_SPEED_BOUND` and :data:`LINEAR_SPEED_BOUND` plus the
    run's free fall ``|g| t_end``, each raised to :data:`SPEED_FACTOR` times the largest initial speed of
    its kind when the scene starts faster."""
    angular, _ = _slots(plan.model)
    qd0 = np.abs(np.asarray(qd0, float))
    g = 0.0 if plan.scene.gravity is None else float(np.linalg.norm(plan.scene.gravity))
    ang = max(ANGULAR_SPEED_BOUND, SPEED_FACTOR * float(qd0[angular].max(initial=0.0)))
    lin = max(LINEAR_SPEED_BOUND + g * t_end, SPEED_FACTOR * float(qd0[~angular].max(initial=0.0)))
    return ang, lin


def _worst(engine, check, part, values, bound, t, units, what) -> list[Finding]:
    """A finding at the sample where ``values`` is largest, when that passes ``bound``."""
    values = np.asarray(values, float)
    values = np.where(np.isfinite(values), values, np.inf)
    if not values.size or not values.max() > bound:
        return []
    k = int(np.argmax(values))
    return [Finding(engine, check, part, float(values[k]), float(bound), units, float(t[k]), what)]


def _base_name(model, root) -> str:
    """The floating root's link (the tree link whose coordinates are ``root``)."""
    coord, names = np.asarray(model.tree.coord), list(model.coordinate_names)
    first = names.index(root[0])
    return next((model.link_names[p] for p in range(coord.shape[0]) if first in coord[p]), root[0])


def _poses(model, scene, t, q) -> np.ndarray:
    """(m, L, 4, 4) link poses along a run (the scene's moving base at each time)."""
    base = scene.base
    return np.stack([model.link_poses(qi, t=float(ti), base=base) if base is not None else model.link_poses(qi)
                     for ti, qi in zip(t, q)])


def _contact(plan, engine, t, q) -> list[Finding]:
    """Penetration of every contact sphere (E77: ``d = h + r - n . x_c``) past its radius' share."""
    rows, spheres = plan.contact_set.rows, plan.contact_set.spheres
    if not rows:
        return []
    finite = np.all(np.isfinite(q), axis=1)
    T = _poses(plan.model, plan.scene, t[finite], q[finite])
    out = []
    for (link, c, r, spec, h), s in zip(rows, spheres):
        x = T[:, link, :3, :3] @ np.asarray(c, float) + T[:, link, :3, 3]
        depth = h + r - x @ spec.normal
        out += _worst(engine, "penetration", s.link, depth, PENETRATION_FRACTION * r, t[finite], "m",
                      f"the contact sphere on {s.link} (r {r:g} m) sinks into the ground by")
    return out


def _base(plan, engine, t, q, floors) -> list[Finding]:
    """The floating root's origin below the scene's ground, else below the file's floors."""
    _, root = _slots(plan.model)
    if not root or plan.scene.base is not None:
        return []
    names = list(plan.model.coordinate_names)
    p = q[:, [names.index(c) for c in root[:3]]]
    grounds = {id(r[3]): (r[3].normal, r[4]) for r in plan.contact_set.rows}
    planes = ([("its ground (the scene's contact)", n, h) for n, h in grounds.values()] if grounds
              else [(f"the file's floor {name!r} (no contact in the scene)", n, h) for name, n, h in floors])
    base = _base_name(plan.model, root)
    out = []
    for where, n, h in planes:
        below = h - p @ np.asarray(n, float)
        out += _worst(engine, "base_below_ground", base, below, BASE_MARGIN, t, "m",
                      f"the floating base {base} falls below {where} by")
    return out


def _limits(plan, engine, t, q) -> list[Finding]:
    """Joints past a limit by more than :data:`LIMIT_MARGIN` of their range (limits are left out)."""
    out = []
    for x in limit_excursions(plan.model, t, q):
        bound = LIMIT_MARGIN * (x.upper - x.lower)
        if x.worst > bound:
            limit = x.lower if x.side == "lower" else x.upper
            out.append(Finding(engine, "joint_limit", x.joint, float(x.worst), float(bound), x.units,
                               float(x.t_worst), f"joint {x.joint!r} passes its {x.side} limit {limit:.4g} {x.units} by"))
    return out


def _speeds(plan, engine, t, q, qd, bounds) -> list[Finding]:
    """Joint speeds and the floating base's twist (``|p'|``, ``|E(phi) phi'|``) past their bounds."""
    angular, root = _slots(plan.model)
    names = list(plan.model.coordinate_names)
    ang, lin = bounds
    out = []
    for k, name in enumerate(names):
        if name in root:
            continue
        out += _worst(engine, "speed", name, np.abs(qd[:, k]), ang if angular[k] else lin, t,
                      "rad/s" if angular[k] else "m/s", f"coordinate {name!r} reaches the speed")
    if root:
        i = [names.index(c) for c in root]
        v = np.linalg.norm(qd[:, i[:3]], axis=1)
        w = np.array([np.linalg.norm(rate_matrix(phi) @ phid) if np.all(np.isfinite(phi)) else np.inf
                      for phi, phid in zip(q[:, i[3:]], qd[:, i[3:]])])
        base = _base_name(plan.model, root)
        out += _worst(engine, "speed", base, v, lin, t, "m/s", f"the floating base {base} reaches the linear speed")
        out += _worst(engine, "speed", base, w, ang, t, "rad/s", f"the floating base {base} spins at")
    return out


def plausibility(plan, *, t, runs: dict, balances: dict, energy_scale: float, t_end: float, qd0,
                 floors=()) -> Plausibility:
    """The gate (module doc) on ``runs`` (``{engine: (q, qd)}``, (m, n) each at times ``t``) and the energy
    each may not gain, ``balances`` (``{engine: (values (m,), what)}``: urdf2links' ``h - h(0) - W``, MuJoCo's
    ``h - h(0)``, ``what`` their formula); ``energy_scale`` (J) the drifts' scale; ``qd0`` the initial rates
    (the speed bounds); ``floors`` the file's (:func:`file_floors`)."""
    t = np.asarray(t, float)
    bounds = speed_bounds(plan, qd0, t_end)
    passive = passive_scene(plan)
    checks = ["joint limits (left out on both engines): past by more than "
              f"{LIMIT_MARGIN:g} of the range", f"speeds: joints and base below {bounds[0]:.3g} rad/s, {bounds[1]:.3g} m/s"]
    if plan.contact_set:
        checks.append(f"contact spheres no deeper than {PENETRATION_FRACTION:g} of their radius")
    if floating_root(plan.model) and plan.scene.base is None and (plan.contact_set or floors):
        checks.append(f"the floating base no more than {BASE_MARGIN:g} m below "
                      + ("its ground" if plan.contact_set else "the file's floor"))
    if passive:
        checks.append(f"energy growth in a passive scene: max(h - h(0) - W), MuJoCo's max(h - h(0)), at most "
                      f"{ENERGY_GROWTH_BOUND:g} of {energy_scale:.3g} J")
    findings = []
    for engine, (q, qd) in runs.items():
        q, qd = np.asarray(q, float), np.asarray(qd, float)
        findings += _contact(plan, engine, t, q) + _base(plan, engine, t, q, floors) + _limits(plan, engine, t, q)
        findings += _speeds(plan, engine, t, q, qd, bounds)
        if passive and engine in balances:
            values, what = balances[engine]
            growth = np.asarray(values, float) / max(energy_scale, 1e-300)
            findings += _worst(engine, "energy_growth", "energy", growth, ENERGY_GROWTH_BOUND, t, "",
                               f"the energy grows in a passive scene: max ({what}) over {energy_scale:.3g} J is")
    return Plausibility(findings=tuple(findings), checks=tuple(checks), bounds={
        "penetration_fraction": PENETRATION_FRACTION, "base_margin_m": BASE_MARGIN, "limit_margin": LIMIT_MARGIN,
        "angular_speed_rad_s": bounds[0], "linear_speed_m_s": bounds[1], "energy_growth": ENERGY_GROWTH_BOUND,
        "passive": passive})

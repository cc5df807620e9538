"""A floating robot standing on its feet (issue 43): ``--ground``'s and a file's floor's default start.

A robot put on a ground in its excited default scene (E65) tumbles: random joint angles leave one foot
lowest, a passive leg folds, a random base twist throws it over. :func:`standing_start` makes the start a
stance instead (docs/contact.md, "--ground"):

- **the stance** (:func:`stance_pose`): the joints at the file's home keyframe, else its qpos0 (MJCF) or
  0 (URDF), each kept :data:`STANCE_MARGIN` of its range inside its limits; the floating base level
  (roll and pitch 0), its yaw and x, y as the file puts them;
- **the feet** (:func:`choose_feet`): of the robot's collision spheres and capsule ends, and spheres of
  ``FALLBACK_RADIUS`` at the origins of its links named ``foot`` or ``toe`` that carry none (else at the
  origins of its leaf links),
  those that can reach the ground within the run's reach: whose lowest point, over the stance and
  :data:`REACH_SAMPLES` seeded configurations within the joints' sway (:func:`sway_amplitudes`), comes
  within :data:`FOOT_BAND` of the lowest point at the stance;
- **the base placed** so that the lowest foot sinks the law's static depth into the ground;
- **servos holding the stance** (MuJoCo's position actuator, E55): ``kp = STAND_STIFFNESS (W / n) L`` on
  every joint (W the weight, n the feet, L the base's height above the ground: the stiffness that keeps a
  leg of length L under its share of the weight from folding, with a factor 10 to spare), ``kv`` for a
  damping ratio :data:`STAND_DAMPING` of the body on that stiffness; the setpoint carries the static
  torque (the weight shared by the feet, least squares on the base's six equations), so the stance is an
  equilibrium;
- **the excitation** (``q0 = "excite"``): each joint's setpoint sways ``a_k sin(2 pi f_k t)`` with
  ``a_k`` up to :data:`SWAY` rad (and half the distance to the nearer limit), ``f_k`` in :data:`SWAY_HZ`,
  and the base starts with a twist, each angle's rate up to :data:`TWIST` rad/s. Every draw comes from
  one seeded generator.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..dynamics.loads import Wrench
from ..errors import SceneError
from .actuators import ActuatorSpec
from .contact import FALLBACK_RADIUS, SETTLE, ContactSphere, _link_poses, _robot_spheres, floating_root, ground_contact
from .excitation import coordinate_ranges
from .functions import Constant, Sines

__all__ = ["StandingStart", "stance_pose", "choose_feet", "sway_amplitudes", "standing_start", "with_ground",
           "ground_for", "file_floor", "STANCE_MARGIN",
           "FOOT_BAND", "REACH_SAMPLES", "SWAY", "SWAY_HZ", "TWIST", "STAND_STIFFNESS", "STAND_DAMPING",
           "FOOT_NAMES", "StanceFigures", "stance_figures"]

#: The stance keeps each limited joint this fraction of its range inside its limits.
STANCE_MARGIN = 0.1
#: A sphere is a foot when its lowest point can come within this (m) of the lowest point at the stance.
FOOT_BAND = 0.01
#: Configurations drawn within the joints' sway to find what can reach the ground.
REACH_SAMPLES = 128
#: The joints' sway: at most this amplitude (rad or m) about the stance, and half the distance to a limit.
SWAY = 0.1
#: The sway's frequencies (Hz), drawn uniformly between these.
SWAY_HZ = (1.0, 2.0)
#: The base's initial twist: each of its angles' rates drawn within +- this (rad/s).
TWIST = 0.3
#: Servo stiffness in units of (W / n) L per rad: 10 times what keeps a leg from folding under its load.
STAND_STIFFNESS = 10.0
#: Damping ratio of the body on the servos' stiffness.
STAND_DAMPING = 0.5
#: The stance's balance: metres of centre-of-mass offset worth one radian (or metre) of joint motion.
BALANCE_WEIGHT = 0.01
#: Parts of a link's name that make it a foot, for a robot without collision spheres.
FOOT_NAMES = ("foot", "toe")


@dataclass(frozen=True)
class StandingStart:
    """The standing start of :func:`standing_start`: ``q0``, ``qd0`` (dicts by coordinate), the feet
    (:class:`~urdf2links.scenes.contact.ContactSphere`), the servos, the static foot loads (N, one per
    foot), ``text`` (a phrase for the scene's description) and ``notes``."""

    q0: dict
    qd0: dict
    feet: tuple
    actuators: tuple
    loads: np.ndarray
    text: str
    notes: tuple[str, ...]


def _root_slots(model) -> dict:
    """``{slot: coordinate index}`` of the floating root's six coordinates (x, y, z, phi_x, phi_y, phi_z)."""
    names = floating_root(model)
    index = {nm: i for i, nm in enumerate(model.coordinate_names)}
    return dict(zip(("x", "y", "z", "phi_x", "phi_y", "phi_z"), (index[nm] for nm in names)))


def stance_pose(model) -> np.ndarray:
    """The stance (n,): the file's start (home keyframe, qpos0, or 0) with every limited joint kept
    :data:`STANCE_MARGIN` of its range inside its limits, the floating base level (module doc)."""
    r = coordinate_ranges(model)
    root = _root_slots(model)
    q = np.array(r.start, float)
    joints = np.ones(len(q), bool)
    joints[list(root.values())] = False
    margin = STANCE_MARGIN * r.width
    lim = joints & r.limited
    q[lim] = np.clip(q[lim], r.lower[lim] + margin[lim], r.upper[lim] - margin[lim])
    q[root["phi_x"]] = q[root["phi_y"]] = 0.0
    return q


def sway_amplitudes(model, q_stance) -> np.ndarray:
    """Each joint's largest sway (n,; 0 on the floating root): :data:`SWAY`, and at most half the distance
    from the stance to the nearer limit."""
    r = coordinate_ranges(model)
    amp = np.full(len(q_stance), SWAY)
    near = np.minimum(q_stance - r.lower, r.upper - q_stance)
    amp = np.where(r.limited, np.minimum(amp, 0.5 * np.maximum(near, 0.0)), amp)
    amp[list(_root_slots(model).values())] = 0.0
    return amp


def _candidates(model):
    """The spheres a foot is chosen from (the robot's collision spheres and capsule ends, and spheres at the
    origins of its links named foot or toe that carry none; else at its leaf links), and how they were found."""
    spheres = _robot_spheres(model)
    frame_of = model.info.get("frame_of") or {nm: (nm, None) for nm in model.link_names}
    own = {s.link for s in spheres}
    named = [k for k in frame_of if any(w in k.lower() for w in FOOT_NAMES) and k not in own]
    extra = [ContactSphere(k, np.zeros(3), FALLBACK_RADIUS, f"foot link origin (r = {FALLBACK_RADIUS:g} m)")
             for k in named]
    hows = (["its collision spheres and capsule ends"] if spheres else ["no collision spheres"]) + (
        [f"spheres of {FALLBACK_RADIUS:g} m at its links named {' or '.join(FOOT_NAMES)} without one"] if extra else [])
    if spheres or extra:
        return spheres + extra, "; ".join(hows)
    tree = model.tree
    has_child = {int(p) for p in tree.parent if p >= 0}
    leaves = [k for k, (t, _) in frame_of.items() if tree.link_index(t) not in has_child]
    return ([ContactSphere(k, np.zeros(3), FALLBACK_RADIUS, f"leaf link origin (r = {FALLBACK_RADIUS:g} m)")
             for k in leaves], f"no collision spheres: spheres of {FALLBACK_RADIUS:g} m at its leaf links")


def _bottoms(model, q, spheres) -> np.ndarray:
    poses = _link_poses(model, q)
    return np.array([(poses[s.link][:3, :3] @ s.centre + poses[s.link][:3, 3])[2] - s.radius for s in spheres])


def choose_feet(model, q_stance, *, seed: int = 0) -> tuple[list, float, str]:
    """``(feet, lowest, how)``: the spheres that can reach the ground within the run's reach (module doc),
    the height of the lowest point at the stance, and how the candidates were found."""
    cands, how = _candidates(model)
    if not cands:
        return [], 0.0, how
    at_stance = _bottoms(model, q_stance, cands)
    low = float(at_stance.min())
    amp = sway_amplitudes(model, q_stance)
    rng = np.random.default_rng(seed)
    reach = at_stance.copy()
    for _ in range(REACH_SAMPLES if np.any(amp) else 0):
        reach = np.minimum(reach, _bottoms(model, q_stance + rng.uniform(-amp, amp), cands))
    return [s for s, b in zip(cands, reach) if b <= low + FOOT_BAND], low, how


def _feet_points(model, q, feet) -> np.ndarray:
    """(k, 3): the feet's lowest points in the world at ``q``."""
    poses = _link_poses(model, q)
    return np.array([poses[s.link][:3, :3] @ s.centre + poses[s.link][:3, 3] - [0.0, 0.0, s.radius] for s in feet])


def _com(model, q) -> np.ndarray:
    """The robot's centre of mass (3,) at ``q``: ``sum T_l H_l e4 / m`` (E21)."""
    H = np.asarray(model.tree.H)
    moments = np.einsum("lij,lj->i", model.link_poses(q), H[:, :, 3])
    return moments[:3] / moments[3]


def balance(model, q, feet) -> np.ndarray:
    """The stance ``q`` (n,) moved least (:data:`BALANCE_WEIGHT` m per rad or m) within the joints' limits (less
    :data:`STANCE_MARGIN`) to put the centre of mass over the feet's centroid and every foot at one height, so
    that all of them carry the weight (least squares, scipy)."""
    from scipy.optimize import least_squares

    r = coordinate_ranges(model)
    joints = np.ones(len(q), bool)
    joints[list(_root_slots(model).values())] = False
    margin = np.where(r.limited, STANCE_MARGIN * r.width, np.inf)
    lo = np.where(r.limited, r.lower + margin, -np.inf)[joints]
    hi = np.where(r.limited, r.upper - margin, np.inf)[joints]
    x0 = np.clip(q[joints], lo, hi)

    def residual(x):
        qq = q.copy()
        qq[joints] = x
        p = _feet_points(model, qq, feet)
        return np.r_[_com(model, qq)[:2] - p[:, :2].mean(axis=0), p[:, 2] - p[:, 2].mean(), BALANCE_WEIGHT * (x - x0)]

    if not joints.any() or len(feet) < 3:
        return q
    fit = least_squares(residual, x0, bounds=(lo, hi), xtol=1e-10, ftol=1e-12, max_nfev=200)
    out = q.copy()
    out[joints] = fit.x
    return out


def _static_loads(model, q, feet) -> tuple[np.ndarray, np.ndarray]:
    """``(f (k,), tau (n,))``: vertical foot loads that hold the base's six equations in least squares
    (at least 0), and the joint torques ``G - Q_feet`` of that equilibrium (E22, E23)."""
    frame_of = model.info.get("frame_of") or {nm: (nm, np.eye(4).tolist()) for nm in model.link_names}
    T = model.link_poses(q)
    cols = []
    for s in feet:
        tname, X = frame_of[s.link]
        X = np.asarray(X, float)
        R = T[model.tree.link_index(tname)][:3, :3]
        point = X[:3, :3] @ s.centre + X[:3, 3] - R.T @ np.array([0.0, 0.0, s.radius])
        cols.append(model.generalized_forces(q, [Wrench(tname, force=np.array([0.0, 0.0, 1.0]), point=point,
                                                        frame="world")]))
    Qf = np.array(cols).T
    G = model.gravity(q)
    root = list(_root_slots(model).values())
    f = np.linalg.lstsq(Qf[root], G[root], rcond=None)[0]
    f = np.maximum(f, 0.0)
    return f, G - Qf @ f


def standing_start(model, *, height: float, depth: float, excite: bool, seed: int) -> StandingStart:
    """The standing start on a ground at ``height`` (m, normal +z), the lowest foot ``depth`` (m) into it
    (the law's static depth); ``excite``: the joints' sway and the base's twist (module doc)."""
    q = stance_pose(model)
    feet, _, how = choose_feet(model, q, seed=seed)
    q = balance(model, q, feet)
    low = float(_bottoms(model, q, feet).min()) if feet else 0.0
    root = _root_slots(model)
    q[root["z"]] += height - depth - low
    names = model.coordinate_names
    rng = np.random.default_rng(seed)
    f, tau = _static_loads(model, q, feet)
    mass = float(np.sum(np.asarray(model.tree.H)[:, 3, 3]))
    weight, n = mass * float(np.linalg.norm(model.gravity_vector)), max(len(feet), 1)
    leg = max(float(q[root["z"]]) - height, 0.05)
    kp = STAND_STIFFNESS * weight / n * leg
    kv = 2.0 * STAND_DAMPING * np.sqrt(kp * mass / n * leg * leg)
    amp = sway_amplitudes(model, q) * rng.uniform(0.5, 1.0, len(q)) * rng.choice((-1.0, 1.0), len(q))
    hz = rng.uniform(*SWAY_HZ, len(q))
    servos = []
    for i, name in enumerate(names):
        if i in root.values():
            continue
        offset = float(q[i] + tau[i] / kp)
        ctrl = Sines(offset=offset, terms=((float(amp[i]), float(hz[i]), 0.0),)) if excite and amp[i] else Constant(offset)
        servos.append(ActuatorSpec(f"stand:{name}", name, "position", ctrl, gain=kp, bias=(0.0, -kp, -kv), gear=1.0,
                                   source="stand", kp=kp, kv=kv))
    qd = np.zeros(len(q))
    if excite:
        for slot in ("phi_x", "phi_y", "phi_z"):
            qd[root[slot]] = rng.uniform(-TWIST, TWIST)
    feet_names = ", ".join(s.link for s in feet)
    text = (f"standing on {len(feet)} feet ({feet_names}), the lowest {depth * 1e3:.3g} mm into the ground at the "
            f"stance, its joints held by servos (kp {kp:.4g}, kv {kv:.4g}, with the static torques)"
            + (f", swaying up to {SWAY:g} rad at {SWAY_HZ[0]:g}..{SWAY_HZ[1]:g} Hz, the base twisting up to "
               f"{TWIST:g} rad/s (seed {seed})" if excite else ", at rest"))
    notes = (f"feet: {len(feet)} of the robot's contact candidates ({how}) can reach the ground within the run's "
             f"reach: {feet_names}",
             f"standing start: static foot loads {np.round(f, 3).tolist()} N (weight {weight:.4g} N)")
    return StandingStart(dict(zip(names, q.tolist())), dict(zip(names, qd.tolist())), tuple(feet), tuple(servos),
                         f, text, notes)


def file_floor(model) -> dict | None:
    """The file's floor: its first horizontal colliding plane geom of the world body (MJCF; ``{name, height,
    normal, friction}``), or None."""
    for plane in model.info.get("floors", ()):
        if abs(float(plane["normal"][2]) - 1.0) < 1e-9:
            return plane
    return None


def _state_free(description: str) -> str:
    """The default scene's description without its phrase for the initial state (which the stance replaces)."""
    cut = min((description.find(w) for w in ("q0 random", "at rest") if w in description), default=len(description))
    return description[:cut].rstrip(", ;")


def with_ground(scene, model=None, *, q0: str = "excite", seed: int = 0, floor: bool = True):
    """``--ground``: the default scene ``scene`` of a floating robot standing on a flat ground (module doc):
    the file's floor when it has one (``floor``), else a ground at height 0; its feet the contact spheres
    (:func:`~urdf2links.scenes.contact.ground_contact`), its start :func:`standing_start` (``q0`` "excite"
    sways and twists, else at rest), named ``<name>-ground``. ``--hold``'s servos are replaced by the stance's
    and the default scene's damper torques dropped (the joints start at rest); both noted."""
    import dataclasses

    if scene.path is not None:
        raise SceneError(f"{scene.path}: --ground applies to a robot file run in its default scene; a scene file "
                         "names its ground in [[contact]] blocks")
    model = scene.model() if model is None else model
    root = floating_root(model)
    if not root:
        raise SceneError(f"--ground: robot {model.name!r} has a fixed base ({scene.robot}); ground contact is for "
                         "floating robots: add --floating (a URDF), or use an MJCF file with a free joint")
    plane = file_floor(model) if floor else None
    height = plane["height"] if plane else 0.0
    if not np.any(model.gravity_vector):
        raise SceneError(f"ground contact (--ground, or the file's floor): robot {model.name!r} ({scene.robot}) has no "
                         "gravity (the file's is off or 0): nothing would hold it on the ground; --no-floor drops a "
                         "file's floor")
    start = standing_start(model, height=height, depth=SETTLE, excite=q0 == "excite", seed=seed)
    if not start.feet:
        raise SceneError(f"--ground: robot {model.name!r} ({scene.robot}) has no link to stand on")
    spheres, notes = start.feet, list(start.notes)
    if len(start.feet) < 3:     # no support polygon: the robot cannot stand unaided; whatever it falls on touches
        spheres = tuple(_candidates(model)[0])
        notes.append(f"on the ground: {len(start.feet)} feet cannot carry the robot unaided (a stance needs 3 not in a "
                     f"line): all its {len(spheres)} contact candidates touch the ground, so that it falls onto them")
    spec = ground_contact(model, spheres, height=height, sharing=len(start.feet),
                          **({"friction": plane["friction"]} if plane else {}))
    if any(a.source == "hold" for a in scene.actuators):
        notes.append("on the ground: --hold's servos replaced by the stance's servos (the ground carries the base)")
    if scene.torques:
        notes.append("on the ground: the default scene's damper torques dropped (the joints start at rest on their feet)")
    where = (f"the file's floor {plane['name']!r} (height {height:g} m, friction {plane['friction']:g}; --no-floor "
             "drops it)" if plane else "--ground")
    servos = tuple(a for a in scene.actuators if a.source not in ("hold", "stand")) + start.actuators
    return dataclasses.replace(
        scene, name=f"{scene.name}-ground", contacts=tuple(scene.contacts) + (spec,), actuators=servos, torques=(),
        q0=start.q0, qd0=start.qd0, notes=tuple(scene.notes) + tuple(notes),
        description=f"{_state_free(scene.description)}; on the ground ({where}): {start.text}; {spec.describe()}")


def ground_for(scene, model, *, ground: bool = False, floor: bool = True, q0: str = "excite", seed: int = 0):
    """The scene a command runs: ``--ground`` (:func:`with_ground`); a floating MJCF robot's default scene on
    its file's floor unless ``floor`` is False (``--no-floor``); else ``scene``, with a note when the file's
    floor is dropped or unused."""
    import dataclasses

    if scene.path is not None and not ground:
        return scene
    plane = file_floor(model)
    weighty = bool(np.any(model.gravity_vector))
    if ground or (plane and floor and floating_root(model) and weighty):
        return with_ground(scene, model, q0=q0, seed=seed, floor=floor)
    if plane is None:
        return scene
    why = ("--no-floor: the file's floor {!r} dropped: the robot has no ground" if not floor else
           "the file's floor {!r} is not used: the robot has no floating base (a free joint) for it to carry"
           if not floating_root(model) else "the file's floor {!r} is not used: without gravity nothing holds the "
           "robot on it")
    return dataclasses.replace(scene, notes=tuple(scene.notes) + (why.format(plane["name"]),))


@dataclass(frozen=True)
class StanceFigures:
    """How a run on the ground kept its stance (:func:`stance_figures`): the base's height above the ground at
    the start and its lowest (m), the base's largest tilt (rad: roll or pitch), and the joints' largest
    excursion past their limits (rad or m; negative: within them by that much)."""

    start_height: float
    min_height: float
    max_tilt: float
    max_past_limit: float

    def standing(self, *, margin: float, keep: float = 0.5, tilt: float = 0.5) -> bool:
        """On its feet: the base above ``keep`` of its starting height, tilted less than ``tilt`` rad, no joint
        past a limit by more than ``margin``."""
        return (self.min_height > keep * self.start_height and self.max_tilt < tilt
                and self.max_past_limit <= margin)


def stance_figures(model, q, *, ground: float) -> StanceFigures:
    """:class:`StanceFigures` of the samples ``q`` (m, n) of a floating robot on a ground at height ``ground``."""
    root = _root_slots(model)
    r = coordinate_ranges(model)
    q = np.asarray(q, float)
    z = q[:, root["z"]] - ground
    past = np.maximum(q - r.upper, r.lower - q)[:, r.limited]
    return StanceFigures(float(z[0]), float(z.min()), float(np.abs(q[:, [root["phi_x"], root["phi_y"]]]).max()),
                         float(past.max()) if past.size else -np.inf)

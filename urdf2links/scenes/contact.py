"""Ground contact as a scene effect (issue 37): ``[[contact]]`` read, its spheres found on the robot, packed.

A ``[[contact]]`` block is one ground plane ``n . x = height`` (``normal`` n, made unit) touched by contact
spheres, with one compliant law (docs/equations.md (E77)-(E80)):

- the spheres: ``spheres = [{link, centre, radius}, ...]`` given in the scene (centre in the link's frame),
  and/or ``links = [...]``: the robot's own collision spheres on those links (URDF ``<collision>`` spheres,
  MJCF sphere geoms and both ends of capsule geoms), and/or ``lowest = true``: the robot's collision spheres
  lowest at the initial state (within :data:`LOWEST_BAND` of the lowest), or, for a robot without any,
  spheres of :data:`FALLBACK_RADIUS` at the origins of its lowest leaf links (``--ground`` gives its feet
  instead, as ``spheres``: :mod:`urdf2links.scenes.stance`);
- ``height``: a number (m), or ``"touching"``: the plane through the lowest point of the spheres at the
  initial state (the robot starts touching the ground, whatever its initial state);
- the law: ``law = "hunt_crossley"`` (``f_n = d^e (k + c d')``) or ``"spring_damper"``
  (``f_n = k d^e + c d'``), both clamped at 0 (the ground never pulls); ``stiffness`` k, ``damping`` c,
  ``exponent`` e; regularised Coulomb friction ``mu`` (``friction``) and ``slip_speed`` v_s.

:class:`ContactSet` is the resolution on a model: every sphere on its tree link (centre in the tree link's
frame, through ``frame_of``), with its block's plane and law, and the notes (what was taken from where).
:func:`contact_arrays` packs it for the compiled law (:mod:`urdf2links.scenes.contact_kernels`), appended to
the scene's ``(SI, SF)`` (:func:`urdf2links.scenes.scene_arrays.compile_scene`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import SceneError

__all__ = ["ContactSphere", "ContactSpec", "ContactSet", "parse_contacts", "resolve_contacts", "contact_arrays",
           "ground_contact", "floating_root", "contact_toml", "LAWS", "KC", "LOWEST_BAND", "FALLBACK_RADIUS",
           "SETTLE"]

LAWS = ("hunt_crossley", "spring_damper")
#: floats per sphere in the packed block: centre (3, tree link frame), radius, normal (3), height, k, c, e,
#: mu, v_s, law (0 Hunt-Crossley, 1 spring-damper)
KC = 14
#: ``lowest = true`` takes the spheres whose lowest point is within this of the lowest one (m).
LOWEST_BAND = 0.01
#: radius (m) of the spheres put at the lowest leaf links of a robot without collision spheres.
FALLBACK_RADIUS = 0.02
#: ``--ground``'s static depth (m): the law's stiffness puts the robot's weight on its feet at this depth.
SETTLE = 0.005
_KEYS = ("height", "normal", "law", "stiffness", "damping", "exponent", "friction", "slip_speed", "links",
         "spheres", "lowest")


@dataclass(frozen=True)
class ContactSphere:
    """A contact sphere on robot link (URDF link, MJCF body) ``link``: ``centre`` (3,) in its frame,
    ``radius`` (m); ``source`` says where it comes from."""

    link: str
    centre: np.ndarray
    radius: float
    source: str = "scene"


@dataclass(frozen=True)
class ContactSpec:
    """One ``[[contact]]`` block as read (its spheres resolved on a model by :func:`resolve_contacts`)."""

    height: float | str = 0.0
    normal: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, 1.0]))
    law: str = "hunt_crossley"
    stiffness: float = 1e5
    damping: float = 0.0
    exponent: float = 1.5
    friction: float = 0.0
    slip_speed: float = 0.01
    spheres: tuple[ContactSphere, ...] = ()
    links: tuple[str, ...] = ()
    lowest: bool = False

    def describe(self) -> str:
        k, c, e = self.stiffness, self.damping, self.exponent
        law = (f"Hunt-Crossley f_n = d^{e:g} ({k:g} + {c:g} d')" if self.law == "hunt_crossley"
               else f"spring-damper f_n = {k:g} d^{e:g} + {c:g} d'")
        h = self.height if isinstance(self.height, str) else f"{self.height:g} m"
        return (f"plane n.x = {h} (n = {np.round(self.normal, 6).tolist()}), {law} (clamped at 0), "
                f"friction mu {self.friction:g}, slip speed {self.slip_speed:g} m/s")


@dataclass(frozen=True)
class ContactSet:
    """The scene's contact on a model: ``rows`` one per sphere ``(tree link index, centre (3,) in the tree
    link's frame, radius, spec, height)``, ``spheres`` the matching :class:`ContactSphere`, and ``notes``."""

    rows: tuple = ()
    spheres: tuple[ContactSphere, ...] = ()
    notes: tuple[str, ...] = ()

    def __bool__(self) -> bool:
        return bool(self.rows)


def parse_contacts(r, data: dict) -> tuple[ContactSpec, ...]:
    """The scene's ``[[contact]]`` blocks (``r`` the scene's reader: errors name the file and key)."""
    out = []
    for i, item in enumerate(r.items(data, "contact")):
        key = f"contact[{i}]"
        r.keys(item, _KEYS, key)
        height = item.get("height", 0.0)
        if height != "touching":
            height = r.number(height, f"{key}.height", quantity="length")
        normal = r.vector(item.get("normal", [0.0, 0.0, 1.0]), f"{key}.normal")
        if np.linalg.norm(normal) < 1e-9:
            r.fail(f"{key}.normal", f"must not be zero, got {normal.tolist()}")
        law = r.choice(item.get("law", "hunt_crossley"), f"{key}.law", LAWS)
        spheres = []
        for j, s in enumerate(item.get("spheres", [])):
            sk = f"{key}.spheres[{j}]"
            r.keys(s, ("link", "centre", "radius"), sk)
            if not isinstance(s.get("link"), str):
                r.fail(f"{sk}.link", "must name a link")
            spheres.append(ContactSphere(s["link"], r.vector(s.get("centre", [0.0, 0.0, 0.0]), f"{sk}.centre",
                                                             quantity="length"),
                                         r.number(s.get("radius", 0.0), f"{sk}.radius", nonnegative=True,
                                                  quantity="length")))
        lowest = item.get("lowest", False)
        if not isinstance(lowest, bool):
            r.fail(f"{key}.lowest", f"must be true or false, got {lowest!r}")
        links = r.strings(item.get("links", []), f"{key}.links")
        if not spheres and not links and not lowest:
            r.fail(key, "names no contact sphere: give spheres = [{link, centre, radius}], links = [...] (the "
                        "robot's collision spheres on those links) or lowest = true")
        out.append(ContactSpec(
            height=height, normal=normal / np.linalg.norm(normal), law=law,
            stiffness=r.number(item.get("stiffness", 1e5), f"{key}.stiffness", positive=True, quantity="damping"),
            damping=r.number(item.get("damping", 0.0), f"{key}.damping", nonnegative=True, quantity="damping"),
            exponent=r.number(item.get("exponent", 1.5 if law == "hunt_crossley" else 1.0), f"{key}.exponent",
                              low=1.0, high=3.0),
            friction=r.number(item.get("friction", 0.0), f"{key}.friction", nonnegative=True, high=10.0),
            slip_speed=r.number(item.get("slip_speed", 0.01), f"{key}.slip_speed", positive=True, high=100.0),
            spheres=tuple(spheres), links=links, lowest=lowest))
    return tuple(out)


def _robot_spheres(model) -> list[ContactSphere]:
    return [ContactSphere(link, np.asarray(c, float), float(r), "collision sphere")
            for link, c, r in model.info.get("collision_spheres", [])]


def _link_poses(model, q0) -> dict:
    """{0}-pose (4, 4) of every robot link at ``q0`` (its tree link's pose times ``frame_of``'s ``X``)."""
    T = model.link_poses(q0)
    frame_of = model.info.get("frame_of") or {nm: (nm, np.eye(4).tolist()) for nm in model.link_names}
    index = {nm: i for i, nm in enumerate(model.link_names)}
    return {k: T[index[t]] @ np.asarray(X) for k, (t, X) in frame_of.items()}


def _bottom(poses, s: ContactSphere, normal) -> float:
    """``n . x - r``: the height along ``normal`` of the sphere's lowest point."""
    T = poses[s.link]
    return float(normal @ (T[:3, :3] @ s.centre + T[:3, 3])) - s.radius


def _lowest(model, poses, normal) -> tuple[list[ContactSphere], str]:
    """The robot's lowest collision spheres at the initial state, or its lowest leaf links' origins."""
    cands = _robot_spheres(model)
    how = "its collision spheres"
    if not cands:
        frame_of = model.info.get("frame_of") or {nm: (nm, None) for nm in model.link_names}
        tree = model.tree
        has_child = {int(p) for p in tree.parent if p >= 0}
        leaves = [k for k, (t, _) in frame_of.items() if tree.link_index(t) not in has_child]
        cands = [ContactSphere(k, np.zeros(3), FALLBACK_RADIUS, f"leaf link origin (r = {FALLBACK_RADIUS:g} m)")
                 for k in leaves]
        how = (f"no collision spheres: spheres of {FALLBACK_RADIUS:g} m at the origins of its leaf links")
    if not cands:
        return [], how
    low = min(_bottom(poses, s, normal) for s in cands)
    return [s for s in cands if _bottom(poses, s, normal) <= low + LOWEST_BAND], how


def resolve_contacts(specs, model, q0, *, where: str = "<scene>") -> ContactSet:
    """Every ``[[contact]]`` block's spheres on ``model`` at the initial configuration ``q0`` (n,), each on
    its tree link; ``"touching"`` heights placed. SceneError names a link that is not the robot's, or
    ``links`` that carry no collision sphere."""
    if not specs:
        return ContactSet()
    frame_of = model.info.get("frame_of") or {nm: (nm, np.eye(4).tolist()) for nm in model.link_names}
    poses = _link_poses(model, q0)
    robot = _robot_spheres(model)
    rows, spheres, notes = [], [], []
    # the choice of spheres and the "touching" height, made once per model and initial state: a re-charted
    # model (urdf2links.integration.charts) shares info with its original but not the meaning of q0's angles
    cache = model.info.setdefault("contact_resolution", {})
    for i, spec in enumerate(specs):
        key = (spec.describe(), spec.links, spec.lowest, repr([(s.link, s.centre.tolist(), s.radius) for s in spec.spheres]),
               np.asarray(q0, float).tobytes())
        if key not in cache:
            cache[key] = _choose(spec, i, model, frame_of, poses, robot, where)
        chosen, height, more = cache[key]
        notes += more
        for s in chosen:
            tname, X = frame_of[s.link]
            X = np.asarray(X, float)
            rows.append((model.tree.link_index(tname), X[:3, :3] @ s.centre + X[:3, 3], s.radius, spec, float(height)))
            spheres.append(s)
    return ContactSet(tuple(rows), tuple(spheres), tuple(notes))


def _choose(spec, i, model, frame_of, poses, robot, where) -> tuple[list, float, list]:
    """One block's spheres, its height and notes (:func:`resolve_contacts`)."""
    notes = []
    chosen = list(spec.spheres)
    for link in spec.links:
        if link not in frame_of:
            raise SceneError(f"{where}: contact[{i}].links names {link!r}, not a link of robot {model.name!r}; "
                             f"links are {sorted(frame_of)}")
        own = [s for s in robot if s.link == link]
        if not own:
            raise SceneError(f"{where}: contact[{i}].links: link {link!r} of {model.name!r} has no collision sphere "
                             "(URDF <collision><sphere>, MJCF sphere or capsule geom); give its sphere with "
                             "spheres = [{link, centre, radius}]")
        chosen += own
    if spec.lowest:
        low, how = _lowest(model, poses, spec.normal)
        chosen += [s for s in low if not any(s.link == c.link and np.allclose(s.centre, c.centre) for c in chosen)]
        notes.append(f"contact[{i}]: the robot's lowest spheres ({how}): "
                     + ", ".join(sorted({s.link for s in low})))
    for s in chosen:
        if s.link not in frame_of:
            raise SceneError(f"{where}: contact[{i}] sphere on {s.link!r}, not a link of robot {model.name!r}; "
                             f"links are {sorted(frame_of)}")
    height = spec.height
    if height == "touching":
        height = min(_bottom(poses, s, spec.normal) for s in chosen)
        notes.append(f"contact[{i}]: ground height {height:.6g} m, touching the lowest sphere at the initial state")
    return chosen, height, notes


def contact_arrays(cset: ContactSet) -> tuple[np.ndarray, np.ndarray]:
    """``(links (k,) int64, data (k * KC,) float64)`` of the compiled law (see :data:`KC`)."""
    links = np.array([r[0] for r in cset.rows], dtype=np.int64)
    data = np.zeros((len(cset.rows), KC))
    for j, (_, c, radius, spec, height) in enumerate(cset.rows):
        data[j] = [*c, radius, *spec.normal, height, spec.stiffness, spec.damping, spec.exponent, spec.friction,
                   spec.slip_speed, float(LAWS.index(spec.law))]
    return links, data.ravel()


def ground_contact(model, feet, *, height: float = 0.0, settle: float = SETTLE, damping_ratio: float = 0.5,
                   friction: float = 0.8, slip_speed: float = 0.1, sharing: int | None = None) -> ContactSpec:
    """``--ground``: a ``[[contact]]`` block on a flat ground (normal +z) at ``height`` under the spheres ``feet``
    (:func:`urdf2links.scenes.stance.choose_feet`), Hunt-Crossley with exponent 1.5, stiffness and damping from
    the robot's weight shared by those spheres (E84): static depth ``settle`` (m), ``damping_ratio`` of the
    linearised contact at that depth. The defaults (a soft ground, 5 mm, and a slip speed of 0.1 m/s) keep the
    contact's stiff modes below ~5e3 /s on the shipped quadruped, where MuJoCo's RK4 at 1e-4 s is accurate;
    ``friction`` is a file floor's own; ``sharing`` the number of spheres that carry the weight (all of them
    when None)."""
    g = float(np.linalg.norm(model.gravity_vector)) or 9.81
    mass = float(np.sum(np.asarray(model.tree.H)[:, 3, 3]))
    n = max(len(feet) if sharing is None else sharing, 1)
    e = 1.5
    f_s = mass * g / n
    k = f_s / settle ** e
    k_lin = e * f_s / settle
    b = 2.0 * damping_ratio * np.sqrt(k_lin * mass / n)
    return ContactSpec(height=float(height), law="hunt_crossley", stiffness=float(k), damping=float(b / settle ** e),
                       exponent=e, friction=float(friction), slip_speed=slip_speed, spheres=tuple(feet))


def floating_root(model) -> tuple[str, ...]:
    """The six coordinates of a floating root link (x, y, z and the three angles), or () for a fixed base."""
    coord = np.asarray(model.tree.coord)
    roots = [p for p in range(model.tree.n_links) if model.tree.parent[p] < 0 and np.all(coord[p] >= 0)]
    return tuple(model.coordinate_names[int(i)] for i in coord[roots[0]]) if roots else ()


def contact_toml(specs, value) -> list[str]:
    """``[[contact]]`` blocks of ``specs`` as TOML lines (``value`` spells one TOML value), for --write-scene."""
    out = []
    for spec in specs:
        out += ["[[contact]]  # ground contact (docs/equations.md (E77)-(E80))",
                f"height = {value(spec.height if isinstance(spec.height, str) else float(spec.height))}",
                f"normal = {value([float(x) for x in spec.normal])}", f"law = {value(spec.law)}",
                f"stiffness = {value(float(spec.stiffness))}", f"damping = {value(float(spec.damping))}",
                f"exponent = {value(float(spec.exponent))}", f"friction = {value(float(spec.friction))}",
                f"slip_speed = {value(float(spec.slip_speed))}"]
        out += [f"links = {value(list(spec.links))}"] if spec.links else []
        out += ["lowest = true"] if spec.lowest else []
        if spec.spheres:
            out.append("spheres = [" + ", ".join(
                f"{{ link = {value(s.link)}, centre = {value([float(x) for x in s.centre])}, radius = "
                f"{value(float(s.radius))} }}" for s in spec.spheres) + "]")
        out.append("")
    return out

"""Test robots built in code: the closed-form models and random trees.

The same closed-form robots are shipped as URDF in ``robots/`` (the importer's tests compare both).
Inertias are given as H directly (point masses, rods) so that these builders do not depend on
the importer's inertia conversion.
"""

from __future__ import annotations

import numpy as np

from urdf2links import LinkSpec, Model, build_tree
from urdf2links.dynamics.transforms import PARAMETERS


def rod_H(mass, com, Ixx=0.0, Iyy=0.0, Izz=0.0, *, roll=0.0):
    """H (4, 4) of a body with COM ``com`` and diagonal inertia (about its COM) in axes rolled by
    ``roll`` about x relative to the link's (the URDF ``<inertial><origin rpy="roll 0 0">``)."""
    c_, s_ = np.cos(roll), np.sin(roll)
    R = np.array([[1, 0, 0], [0, c_, -s_], [0, s_, c_]])
    I = R @ np.diag([Ixx, Iyy, Izz]) @ R.T
    c = np.asarray(com, float)
    S = 0.5 * np.trace(I) * np.eye(3) - I + mass * np.outer(c, c)
    H = np.zeros((4, 4))
    H[:3, :3] = S
    H[:3, 3] = H[3, :3] = mass * c
    H[3, 3] = mass
    return H


PENDULUM = dict(m=1.3, c=0.7, I=0.05)
DOUBLE = dict(m1=1.0, m2=0.8, l1=1.0, c1=0.45, c2=0.55, I1=0.08, I2=0.05)
PRISMATIC_REVOLUTE = dict(m1=2.0, m2=0.7, c=0.4, I=0.03)
FREE_BODY = dict(m=3.0, Ixx=0.2, Iyy=0.35, Izz=0.5)


def pendulum(**kw):
    """Single pendulum about x: COM at (0, 0, -c), inertia I about the COM's x axis."""
    p = {**PENDULUM, **kw}
    return Model(build_tree([
        LinkSpec("rod", None, coordinates={"phi_x": "hinge"}, H=rod_H(p["m"], (0, 0, -p["c"]), p["I"], p["I"], 0.1 * p["I"])),
    ]), name="pendulum")


def double_pendulum(**kw):
    p = {**DOUBLE, **kw}
    return Model(build_tree([
        LinkSpec("upper", None, coordinates={"phi_x": "shoulder"}, H=rod_H(p["m1"], (0, 0, -p["c1"]), p["I1"], p["I1"], 0.1 * p["I1"])),
        LinkSpec("lower", "upper", params=(0, 0, -p["l1"], 0, 0, 0), coordinates={"phi_x": "elbow"},
                 H=rod_H(p["m2"], (0, 0, -p["c2"]), p["I2"], p["I2"], 0.1 * p["I2"], roll=0.3)),
    ]), name="double_pendulum")


def prismatic_revolute(**kw):
    """A carriage sliding along x (mass m1) carrying an arm about y, COM at (c, 0, 0)."""
    p = {**PRISMATIC_REVOLUTE, **kw}
    return Model(build_tree([
        LinkSpec("carriage", None, coordinates={"x": "slide"}, H=rod_H(p["m1"], (0, 0, 0), 0.01, 0.01, 0.01)),
        LinkSpec("arm", "carriage", coordinates={"phi_y": "swing"}, H=rod_H(p["m2"], (p["c"], 0, 0), 0.1 * p["I"], p["I"], p["I"])),
    ]), name="prismatic_revolute")


def free_body(**kw):
    """One rigid body with all six coordinates, COM at its origin, principal axes along its axes."""
    p = {**FREE_BODY, **kw}
    coords = {s: f"body.{s}" for s in PARAMETERS}
    return Model(build_tree([
        LinkSpec("body", None, coordinates=coords, H=rod_H(p["m"], (0, 0, 0), p["Ixx"], p["Iyy"], p["Izz"])),
    ]), name="free_body", gravity=(0, 0, 0))


def random_H(rng, *, points=5):
    """A physically consistent H: a cloud of point masses (sum of m r r^T is PD for >= 4 points)."""
    r = np.c_[rng.normal(size=(points, 3)) * 0.3 + rng.normal(size=3) * 0.2, np.ones(points)]
    m = rng.uniform(0.2, 2.0, points)
    return np.einsum("k,ka,kb->ab", m, r, r)


def random_tree(seed, *, links=7, massless=(), max_coords=3, min_coords=0, gravity=(0, 0, -9.81)):
    """A random tree: branching parents, random constant parameters, a random subset of the six
    slots as coordinates per link, massless links at the indices in ``massless``."""
    rng = np.random.default_rng(seed)
    specs, names = [], []
    for p in range(links):
        parent = None if p == 0 else names[rng.integers(len(names))]
        slots = rng.choice(6, size=rng.integers(min_coords, max_coords + 1), replace=False)
        coords = {PARAMETERS[k]: f"{p}.{PARAMETERS[k]}" for k in sorted(slots)}
        H = None if p in massless else random_H(rng)
        specs.append(LinkSpec(f"link{p}", parent, rng.normal(size=6), coords, H))
        names.append(f"link{p}")
    return Model(build_tree(specs), name=f"random{seed}", gravity=gravity)

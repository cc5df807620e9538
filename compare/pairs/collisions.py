"""Collision geometry of two descriptions of one robot: kind ``collision``.

Per body both sides have (and the world), the collision geometry folded onto it as the dynamics is (every body
welded to it that only one side has): its volume and its bounding box in the body's frame at home. A URDF's
``<collision>`` elements (box, cylinder, sphere; a mesh read through :func:`urdf2links.parsers.meshes.load_mesh`);
an MJCF file's geoms that collide (``contype`` or ``conaffinity`` nonzero: MuJoCo's URDF import writes the URDF's
``<visual>`` elements as geoms with both 0), from MuJoCo's compiled model (a mesh as MuJoCo stored it). A
primitive's volume is its own; a mesh's is its convex hull's (what MuJoCo collides with; a non-watertight mesh
has no volume of its own). Volumes of one body add up (overlaps counted twice, on both sides alike).

Both values are ``[volume, x_min, y_min, z_min, x_max, y_max, z_max]``. ``difference`` (relative) is the larger of the volumes' relative difference and the bounding boxes' largest
corner distance over the larger box's largest extent: a collision mesh written 10 times too large shows as
0.999. A file without any collision geometry (a dynamics-only conversion: ``save_mujoco_import(keep_geometry=
False)``) states none: nothing is compared. Not a dynamic kind.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from urdf2links.dynamics.rotations import homogeneous, rpy_to_matrix
from urdf2links.parsers.mjcf import is_mjcf_path
from urdf2links.parsers.mjcf_state import quat_to_matrix
from urdf2links.parsers.parts import RobotParts

from .context import PairContext
from .kinds import ROUNDING, Difference

__all__ = ["Solid", "collision_solids", "collision_differences"]

_SECTIONS = 64          # a cylinder's or capsule's outline: its bounding box to 1 - cos(pi/64) = 0.12 %, alike


@dataclass(frozen=True)
class Solid:
    """One collision shape: its ``volume`` (m^3) and ``points`` (n, 3) in its body's frame (its bounding box)."""

    volume: float
    points: np.ndarray


def _shape(kind: str, dims, pose) -> Solid:
    import trimesh

    if kind == "box":
        e = np.asarray(dims, float)
        mesh, vol = trimesh.creation.box(extents=e), float(np.prod(e))
    elif kind == "sphere":
        r = float(dims[0])
        mesh, vol = trimesh.creation.icosphere(subdivisions=3, radius=r), 4.0 / 3.0 * math.pi * r ** 3
    elif kind == "cylinder":
        r, h = float(dims[0]), float(dims[1])
        mesh, vol = trimesh.creation.cylinder(radius=r, height=h, sections=_SECTIONS), math.pi * r * r * h
    elif kind == "capsule":
        r, h = float(dims[0]), float(dims[1])
        mesh = trimesh.creation.capsule(height=h, radius=r, count=[_SECTIONS, _SECTIONS])
        vol = math.pi * r * r * h + 4.0 / 3.0 * math.pi * r ** 3
    else:
        raise ValueError(kind)
    return Solid(vol, trimesh.transform_points(mesh.vertices, pose))


def _hull(points, pose) -> Solid:
    import trimesh

    p = trimesh.transform_points(np.asarray(points, float), pose)
    return Solid(float(trimesh.convex.convex_hull(p).volume), p)


def _urdf_solids(path, load) -> dict[str, list[Solid]]:
    from urdf2links.parsers.meshes import load_mesh
    from urdf2links.parsers.urdf import parse_urdf

    desc = parse_urdf(path, **{k: v for k, v in load.items() if k in ("package_dirs", "xacro_args")})
    out = {}
    for name, link in desc.links.items():
        for g in link.collisions:
            pose = homogeneous(rpy_to_matrix(g.origin.rpy), np.asarray(g.origin.xyz, float))
            if g.kind == "mesh":
                solid = _hull(load_mesh(g)[0].vertices, pose)
            elif g.kind in ("box", "sphere", "cylinder"):
                dims = g.size if g.kind == "box" else (g.radius, g.length)
                solid = _shape(g.kind, dims, pose)
            else:
                continue
            out.setdefault(name, []).append(solid)
    return out


def _mjcf_solids(path) -> dict[str | None, list[Solid]]:
    import mujoco

    from urdf2links.parsers.mjcf import compile_mjcf

    m, _ = compile_mjcf(str(path))
    kinds = {int(mujoco.mjtGeom.mjGEOM_BOX): "box", int(mujoco.mjtGeom.mjGEOM_SPHERE): "sphere",
             int(mujoco.mjtGeom.mjGEOM_CYLINDER): "cylinder", int(mujoco.mjtGeom.mjGEOM_CAPSULE): "capsule"}
    out = {}
    for g in range(m.ngeom):
        if not (m.geom_contype[g] or m.geom_conaffinity[g]):
            continue
        b = int(m.geom_bodyid[g])
        body = None if b == 0 else (mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, b) or f"body{b}")
        pose = homogeneous(quat_to_matrix(m.geom_quat[g]), np.asarray(m.geom_pos[g], float))
        t, s = int(m.geom_type[g]), np.asarray(m.geom_size[g], float)
        if t == int(mujoco.mjtGeom.mjGEOM_MESH):
            k = int(m.geom_dataid[g])
            a, n = int(m.mesh_vertadr[k]), int(m.mesh_vertnum[k])
            solid = _hull(m.mesh_vert[a:a + n], pose)
        elif t in kinds:            # MuJoCo's sizes are half-sizes
            dims = 2 * s if kinds[t] == "box" else ((s[0],) if kinds[t] == "sphere" else (s[0], 2 * s[1]))
            solid = _shape(kinds[t], dims, pose)
        else:
            continue                # a plane, an ellipsoid, a height field: no volume compared
        out.setdefault(body, []).append(solid)
    return out


def collision_solids(parts: RobotParts, *, load: dict | None = None) -> dict:
    """``{body (None: the world): [Solid]}`` of the file ``parts`` was read from (module doc)."""
    if parts.format == "mjcf" or is_mjcf_path(parts.source):
        return _mjcf_solids(parts.source)
    return _urdf_solids(parts.source, dict(load or {}))


def _folded(parts: RobotParts, solids: dict, keep, W: dict) -> dict:
    """``{target: points (n, 3) in its frame, volume}``: each body's solids on the nearest body in ``keep`` or with
    joints above it (itself included), or on the world (None) when only welds lead there (``W``: the home poses of
    ``parts``)."""
    bodies = {b.name: b for b in parts.bodies}
    out = {}
    for body, group in solids.items():
        t = body
        while t is not None and not bodies[t].joints and t not in keep:
            t = bodies[t].parent
        X = (W[body] if t is None else np.linalg.inv(W[t]) @ W[body]) if body is not None else np.eye(4)
        pts = [np.c_[s.points, np.ones(len(s.points))] @ X.T for s in group]
        vol, old = sum(s.volume for s in group), out.get(t, (np.zeros((0, 3)), 0.0))
        out[t] = (np.vstack([old[0], *(p[:, :3] for p in pts)]), old[1] + vol)
    return out


def _box(v) -> str:
    lo, hi = v[0].min(axis=0), v[0].max(axis=0)
    return "[" + " ".join(f"{x:.4g}" for x in lo) + "]..[" + " ".join(f"{x:.4g}" for x in hi) + "]"


def collision_differences(ctx: PairContext, *, load: dict | None = None) -> tuple[list[Difference], int]:
    """The ``collision`` differences of the pair ``ctx`` (module doc) and how many bodies agree to rounding, per body
    both descriptions have (``ctx.bodies``)."""
    U, M, bodies = ctx.urdf, ctx.mjcf, ctx.bodies
    first = (M, U) if M.format == "mjcf" else (U, M)          # a compiled MJCF is quick: a file without any first
    solids = {}
    for p in first:
        solids[id(p)] = collision_solids(p, load=load if p is U else None)
        if not solids[id(p)]:
            return [], 0
    fu = _folded(U, solids[id(U)], set(bodies), ctx.home_urdf)
    fm = _folded(M, solids[id(M)], set(bodies.values()), ctx.home_mjcf)
    pairs = [(None, None)] + list(bodies.items())
    out, agree = [], 0
    for bU, bM in pairs:
        a, b = fu.get(bU), fm.get(bM)
        if a is None and b is None:
            continue
        if a is None or b is None:
            d, what = 1.0, f"collision geometry on one side only: {_box(a or b)} ({(a or b)[1]:.4g} m^3)"
        else:
            dv = abs(a[1] - b[1]) / max(a[1], b[1], 1e-300)
            corners = np.r_[a[0].min(0) - b[0].min(0), a[0].max(0) - b[0].max(0)]
            size = max(float(np.ptp(a[0], axis=0).max()), float(np.ptp(b[0], axis=0).max()), 1e-300)
            d = max(dv, float(np.abs(corners).max()) / size)
            what = (f"collision volume {a[1]:.4g} against {b[1]:.4g} m^3 (x{b[1] / max(a[1], 1e-300):.4g}); "
                    f"bounding box {_box(a)} against {_box(b)} m in {bU or 'the world'}")
        if d <= ROUNDING["collision"]:
            agree += 1
            continue
        vals = [(None if v is None else [v[1], *v[0].min(0), *v[0].max(0)]) for v in (a, b)]   # m^3, box (m)
        out.append(Difference("collision", bU or "world", bM or "world", vals[0], vals[1], d, "relative", what,
                              tuple(x for x in (bU, bM) if x)))
    return out, agree

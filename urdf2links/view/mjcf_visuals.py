"""The visible geometry of an MJCF model: MuJoCo's compiled geoms as the animation's and thumbnail's shapes.

Each body's geoms (``geom_type``, ``geom_size``, ``geom_pos``, ``geom_quat``, ``geom_rgba`` of the
compiled model) become :class:`~urdf2links.view.shapes.Shape` s in the body's frame (the frame
``model.info["frame_of"]`` places, like a URDF link's): boxes, cylinders and spheres as such; capsules
and ellipsoids tessellated; meshes from MuJoCo's own vertices (``mesh_vert``, ``mesh_face``). Planes and
height fields (floors), the world body's geoms and invisible geoms (alpha 0) are left out.
"""

from __future__ import annotations

import numpy as np

from ..dynamics.rotations import homogeneous
from ..parsers.mjcf import compile_mjcf
from ..parsers.mjcf_state import quat_to_matrix
from .shapes import RobotShapes, Shape

__all__ = ["mjcf_shapes"]

_PLANE, _HFIELD, _SPHERE, _CAPSULE, _ELLIPSOID, _CYLINDER, _BOX, _MESH = range(8)


def _mesh_shape(body, origin, v, f, color) -> Shape:
    return Shape(body, "mesh", origin, "geom", vertices=np.ascontiguousarray(v, np.float32),
                 faces=np.ascontiguousarray(f, np.int32), color=color)


def mjcf_shapes(model) -> RobotShapes:
    """The shapes of a model loaded from an MJCF file (``model.info["source_file"]``), by body name."""
    import mujoco
    import trimesh

    notes: list[str] = []
    m, _ = compile_mjcf(model.info["source_file"], [])
    bodies = tuple(model.info["frame_of"])
    shapes, skipped = [], 0
    for g in range(m.ngeom):
        b = int(m.geom_bodyid[g])
        kind, size, rgba = int(m.geom_type[g]), np.asarray(m.geom_size[g], float), np.asarray(m.geom_rgba[g], float)
        if b == 0 or kind in (_PLANE, _HFIELD) or rgba[3] == 0.0:
            skipped += 1
            continue
        body = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, b) or f"body{b}"
        origin = homogeneous(quat_to_matrix(m.geom_quat[g]), m.geom_pos[g])
        color = tuple(float(c) for c in rgba[:3])
        if kind == _BOX:
            shapes.append(Shape(body, "box", origin, "geom", size=2 * size, color=color))
        elif kind == _SPHERE:
            shapes.append(Shape(body, "sphere", origin, "geom", radius=float(size[0]), color=color))
        elif kind == _CYLINDER:
            shapes.append(Shape(body, "cylinder", origin, "geom", radius=float(size[0]), length=2 * float(size[1]),
                                color=color))
        elif kind == _CAPSULE:
            c = trimesh.creation.capsule(radius=float(size[0]), height=2 * float(size[1]), count=[12, 12])
            shapes.append(_mesh_shape(body, origin, c.vertices, c.faces, color))
        elif kind == _ELLIPSOID:
            s = trimesh.creation.uv_sphere(radius=1.0, count=[12, 12])
            shapes.append(_mesh_shape(body, origin, s.vertices * size, s.faces, color))
        elif kind == _MESH and m.geom_dataid[g] >= 0:
            k = int(m.geom_dataid[g])
            va, vn, fa, fn = (int(m.mesh_vertadr[k]), int(m.mesh_vertnum[k]), int(m.mesh_faceadr[k]),
                              int(m.mesh_facenum[k]))
            shapes.append(_mesh_shape(body, origin, m.mesh_vert[va:va + vn], m.mesh_face[fa:fa + fn], color))
        else:
            skipped += 1
    if skipped:
        notes.append(f"{skipped} geom(s) not drawn (floors, the world's own geoms, invisible or other kinds)")
    drawn = {s.link for s in shapes}
    shapes += [Shape(b, "frame", np.eye(4), "frame") for b in bodies if b not in drawn]
    return RobotShapes(model.name or "robot", bodies, tuple(shapes), tuple(notes),
                       faces=sum(len(s.faces) for s in shapes if s.kind == "mesh"))

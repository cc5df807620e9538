"""The robot's visible geometry, for the animation (:mod:`urdf2links.view.animation`) and thumbnails
(:mod:`urdf2links.view.thumbnail`).

Every URDF link gets shapes in its own frame (the frame :func:`urdf2links.urdf_link_poses` places):

* its ``<visual>`` geometries: boxes, cylinders (axis z) and spheres as such; meshes read with
  trimesh (:func:`urdf2links.parsers.meshes.load_mesh_parts`: URDF scale and COLLADA unit applied, each part
  of a file keeping its own colour) and decimated (quadric decimation, ``fast-simplification``) so
  that the robot's meshes hold at most ``max_faces`` triangles in all;
* a link without ``<visual>`` shows its ``<collision>`` geometries instead (``source="collision"``;
  the shipped robots describe their solids there);
* a link with neither is a small frame (``kind="frame"``, its axes; the viewer sizes it).

A mesh that cannot be read becomes a frame and a note; nothing fails for want of a picture.
The colour of a ``<visual>`` is the mesh file's own (URDF ``<material>`` colours are not parsed).
"""

from __future__ import annotations

import numpy as np

from ..dynamics.rotations import homogeneous, rpy_to_matrix
from ..errors import MeshError, URDFError
from ..parsers.description import Geometry, RobotDescription
from .mjcf_visuals import mjcf_shapes
from .shapes import RobotShapes, Shape

__all__ = ["Shape", "RobotShapes", "robot_shapes", "model_shapes", "scene_shapes", "decimate", "tessellate",
           "DEFAULT_MAX_FACES", "MIN_PART_FACES"]

#: Triangle budget of a robot's meshes in all (the UR5's visual meshes hold ~96 000).
DEFAULT_MAX_FACES = 40_000
#: Mesh parts of at most this many triangles are kept whole (decimating small parts, thin rings and
#: caps, loses whole pieces of them); larger ones are decimated to at least this many.
MIN_PART_FACES = 400


def _origin(geometry: Geometry) -> np.ndarray:
    return homogeneous(rpy_to_matrix(geometry.origin.rpy), np.asarray(geometry.origin.xyz, float))


def _part_color(part) -> tuple | None:
    """A mesh part's own colour (3,) in 0..1: its material's main colour, else its colours when the
    file sets them; None when the file has none."""
    visual = part.visual
    color = None
    if getattr(visual, "kind", None) == "texture" and getattr(visual, "material", None) is not None:
        color = getattr(visual.material, "main_color", None)
    elif getattr(visual, "kind", None) in ("face", "vertex"):
        color = visual.main_color
    if color is None:
        return None
    return tuple(float(c) / 255.0 for c in np.asarray(color)[:3])


def _read_parts(geometry: Geometry) -> tuple[list, list[str]]:
    """The file's parts merged by colour: ``[(vertices (V, 3), faces (F, 3), colour)]`` and notes."""
    import trimesh

    from ..parsers.meshes import load_mesh_parts

    parts, notes = load_mesh_parts(geometry)
    by_color: dict = {}
    for p in parts:
        by_color.setdefault(_part_color(p), []).append(p)
    merged = []
    for color, group in by_color.items():
        mesh = group[0] if len(group) == 1 else trimesh.util.concatenate(group)
        mesh.merge_vertices(merge_tex=True, merge_norm=True)  # seams split for textures: not needed here
        merged.append((np.asarray(mesh.vertices, float), np.asarray(mesh.faces, np.int64), color))
    return merged, notes


def decimate(vertices, faces, target: int) -> tuple[np.ndarray, np.ndarray]:
    """One part reduced to about ``target`` triangles (unchanged when smaller): quadric decimation,
    then vertex clustering where the quadric collapses stall (open, non-manifold files)."""
    if len(faces) <= target:
        return vertices, faces
    import fast_simplification

    v, f = fast_simplification.simplify(np.asarray(vertices, np.float32), np.asarray(faces, np.int32),
                                        target_reduction=1.0 - target / len(faces))
    if len(f) == 0:  # collapsed entirely (tiny part): keep the original
        v, f = vertices, faces
    if len(f) > 1.5 * target:
        v, f = _cluster(np.asarray(v, float), np.asarray(f, np.int64), target)
    return v, f


def _cluster(vertices: np.ndarray, faces: np.ndarray, target: int) -> tuple[np.ndarray, np.ndarray]:
    """Vertex clustering: vertices merged per cell of a grid (their mean), faces that collapse or
    repeat dropped; the coarsest grid of a bisection that keeps at most ``target`` triangles."""
    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    span = float(np.max(hi - lo)) or 1.0
    best = None
    a, b = 1.0, 4096.0  # cells along the longest side
    for _ in range(14):
        k = np.sqrt(a * b)
        cells = np.floor((vertices - lo) / (span / k)).astype(np.int64)
        _, inverse = np.unique(cells, axis=0, return_inverse=True)
        inverse = inverse.reshape(-1)
        f = inverse[faces]
        f = f[(f[:, 0] != f[:, 1]) & (f[:, 1] != f[:, 2]) & (f[:, 0] != f[:, 2])]
        f = np.unique(f, axis=0) if len(f) else f
        if len(f) <= target:
            a, best = k, (inverse, f)
        else:
            b = k
    if best is None or len(best[1]) == 0:
        return vertices, faces
    inverse, f = best
    counts = np.bincount(inverse)
    v = np.stack([np.bincount(inverse, weights=vertices[:, j]) for j in range(3)], axis=1) / counts[:, None]
    used = np.unique(f)
    remap = np.full(len(v), -1, np.int64)
    remap[used] = np.arange(len(used))
    return v[used], remap[f]


def _shape_of(link: str, g: Geometry, source: str, parts_of) -> list[Shape]:
    origin = _origin(g)
    if g.kind == "box":
        return [Shape(link, "box", origin, source, size=np.asarray(g.size, float))]
    if g.kind == "cylinder":
        return [Shape(link, "cylinder", origin, source, radius=float(g.radius), length=float(g.length))]
    if g.kind == "sphere":
        return [Shape(link, "sphere", origin, source, radius=float(g.radius))]
    return [Shape(link, "mesh", origin, source, vertices=v, faces=f, color=c) for v, f, c in parts_of(g)]


def robot_shapes(description: RobotDescription, *, max_faces: int = DEFAULT_MAX_FACES) -> RobotShapes:
    """The shapes of every link of ``description`` (module doc), meshes decimated so that they hold at
    most ``max_faces`` triangles in all (each part shares the budget in proportion to its size, at
    least :data:`MIN_PART_FACES`)."""
    if max_faces <= 0:
        raise ValueError(f"max_faces must be a positive number of triangles, got {max_faces!r}")
    notes: list[str] = []
    cache: dict = {}

    def parts_of(g: Geometry):
        key = (str(g.path), None if g.scale is None else tuple(np.asarray(g.scale, float).tolist()))
        if key not in cache:
            cache[key], more = _read_parts(g)
            notes.extend(f"{g.filename}: {n}" for n in more)
        return cache[key]

    raw: list[Shape] = []
    for name, link in description.links.items():
        source, geoms = ("visual", link.visuals) if link.visuals else ("collision", link.collisions)
        shapes: list[Shape] = []
        for g in geoms:
            try:
                shapes += _shape_of(name, g, source, parts_of)
            except (MeshError, URDFError) as exc:
                notes.append(f"link {name!r}: {source} mesh not shown ({exc})")
        raw += shapes or [Shape(name, "frame", np.eye(4), "frame")]
    read = sum(len(s.faces) for s in raw if s.kind == "mesh")
    shapes = _within_budget(raw, read, max_faces)
    kept = sum(len(s.faces) for s in shapes if s.kind == "mesh")
    if kept < read:
        notes.append(f"meshes decimated from {read} to {kept} triangles (budget {max_faces})")
    return RobotShapes(description.name, tuple(description.links), tuple(shapes), tuple(notes), kept, read)


def _within_budget(raw: list[Shape], read: int, max_faces: int) -> list[Shape]:
    """The shapes with each mesh part decimated to its share of ``max_faces``: parts of at most
    :data:`MIN_PART_FACES` triangles kept whole, the rest of the budget shared by the larger parts
    in proportion to their size (a part shared by several links is decimated once)."""
    if read <= max_faces:
        return [s if s.kind != "mesh" else _as_float32(s, s.vertices, s.faces) for s in raw]
    parts = {id(s.faces): len(s.faces) for s in raw if s.kind == "mesh"}
    small = sum(f for f in parts.values() if f <= MIN_PART_FACES)
    large = sum(f for f in parts.values() if f > MIN_PART_FACES)
    share = max(max_faces - small, 0) / large if large else 1.0
    done: dict = {}
    out = []
    for s in raw:
        if s.kind != "mesh":
            out.append(s)
            continue
        key = id(s.faces)
        if key not in done:
            target = len(s.faces) if len(s.faces) <= MIN_PART_FACES else max(MIN_PART_FACES, int(len(s.faces) * share))
            done[key] = decimate(s.vertices, s.faces, target)
        out.append(_as_float32(s, *done[key]))
    return out


def _as_float32(s: Shape, vertices, faces) -> Shape:
    return Shape(s.link, s.kind, s.origin, s.source, vertices=np.ascontiguousarray(vertices, np.float32),
                 faces=np.ascontiguousarray(faces, np.int32), color=s.color)


def model_shapes(model, *, description: RobotDescription | None = None, package_dirs=(), xacro_args=None,
                 max_faces: int = DEFAULT_MAX_FACES) -> RobotShapes:
    """The shapes of an imported model: of ``description`` when given, else of the URDF (or xacro) file
    the model was loaded from (``model.source``, meshes searched in ``package_dirs`` too, xacro
    expanded with ``xacro_args``); a model built in code or from URDF text gets a frame per link (its
    tree links, or its URDF links when known)."""
    from ..parsers.urdf import parse_urdf

    if description is None and model.info.get("format") == "mjcf" and model.info.get("source_file"):
        return mjcf_shapes(model)
    if description is None and model.source and model.source != "<string>":
        try:
            description = parse_urdf(model.source, package_dirs=package_dirs, xacro_args=xacro_args)
        except (OSError, URDFError) as exc:
            links = _frame_links(model)
            return RobotShapes(model.name or "robot", links, tuple(Shape(k, "frame", np.eye(4), "frame") for k in links),
                               (f"{model.source}: no geometry shown ({exc})",))
    if description is not None:
        return robot_shapes(description, max_faces=max_faces)
    links = _frame_links(model)
    return RobotShapes(model.name or "robot", links, tuple(Shape(k, "frame", np.eye(4), "frame") for k in links),
                       ("no URDF file: links shown as frames",))


def scene_shapes(scene, model, *, max_faces: int = DEFAULT_MAX_FACES) -> RobotShapes:
    """:func:`model_shapes` of a scene's model, its file read with the scene's ``package_dirs`` and
    ``xacro_args``."""
    opts = scene.load_options
    return model_shapes(model, package_dirs=opts.get("package_dirs", ()), xacro_args=opts.get("xacro_args"),
                        max_faces=max_faces)


def _frame_links(model) -> tuple[str, ...]:
    frame_of = model.info.get("frame_of") or {}
    return tuple(frame_of) if frame_of else tuple(model.link_names)


def tessellate(shape: Shape, *, sections: int = 24) -> tuple[np.ndarray, np.ndarray]:
    """Triangles of a shape in the link frame: ``(vertices (V, 3), faces (F, 3))`` (primitives
    tessellated by trimesh with ``sections`` around; a frame has none)."""
    import trimesh

    if shape.kind == "mesh":
        v = np.asarray(shape.vertices, float)
        f = np.asarray(shape.faces)
    elif shape.kind == "box":
        m = trimesh.creation.box(extents=shape.size)
        v, f = m.vertices, m.faces
    elif shape.kind == "cylinder":
        m = trimesh.creation.cylinder(radius=shape.radius, height=shape.length, sections=sections)
        v, f = m.vertices, m.faces
    elif shape.kind == "sphere":
        m = trimesh.creation.uv_sphere(radius=shape.radius, count=[sections // 2, sections])
        v, f = m.vertices, m.faces
    else:
        return np.zeros((0, 3)), np.zeros((0, 3), int)
    v = np.asarray(v, float) @ shape.origin[:3, :3].T + shape.origin[:3, 3]
    return v, np.asarray(f, int)

"""Mesh files of URDF geometries read with trimesh: one place that opens them, applies the URDF
``scale`` and the COLLADA ``<unit>``, and names the file when that fails.

Used by :mod:`urdf2links.dynamics.inertia` (inertia of a mesh, one concatenated :class:`trimesh.Trimesh`)
and :mod:`urdf2links.view.visuals` (the visible geometry: the file's parts with their own colours).
``.dae`` files are read through pycollada (a core dependency). Only regular files with a mesh suffix
are opened (:func:`urdf2links.parsers.mesh_paths.check_mesh_file`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import MeshError, URDFValueError
from .description import Geometry
from .mesh_paths import check_mesh_file, unresolved_mesh_problem

__all__ = ["load_mesh", "load_mesh_parts"]


def _name(geometry: Geometry) -> str:
    return geometry.filename or (str(geometry.path) if geometry.path else "<unnamed>")


def _read(geometry: Geometry, *, force_mesh: bool):
    """``(trimesh object, path)``: the file as trimesh loads it (a Trimesh, or a Scene of parts)."""
    import trimesh

    name = _name(geometry)
    if geometry.path is None:     # the description file, link, element and paths looked for, when parsed from a file
        raise MeshError(geometry.missing or f"mesh {name!r}: {unresolved_mesh_problem(geometry.filename or '')}")
    path = check_mesh_file(geometry.path, name=name)   # a regular file with a mesh suffix, or MeshError: never
    try:                                               # a device, a FIFO or a directory (urdf2links.parsers.mesh_paths)
        loaded = trimesh.load(str(path), force="mesh") if force_mesh else trimesh.load(str(path))
    except Exception as exc:  # trimesh raises many types for bad files
        raise MeshError(f"mesh {name!r}: cannot read {str(path)!r}: {type(exc).__name__}: {exc}") from exc
    return loaded, path


def _scale(geometry: Geometry, units, path: Path) -> tuple[np.ndarray, list[str]]:
    """The URDF ``scale`` (3,) times the COLLADA unit factor, and a note when the unit applied."""
    import trimesh

    scale = np.ones(3) if geometry.scale is None else np.asarray(geometry.scale, dtype=float).reshape(3)
    if not np.all(np.isfinite(scale)) or np.any(scale == 0.0):
        raise URDFValueError(f"mesh {_name(geometry)!r}: scale {scale.tolist()} must be finite and non-zero")
    notes = []
    if path.suffix.lower() == ".dae" and units and units not in ("meters", "meter", "m"):
        # COLLADA <unit meter="...">: trimesh records it in mesh.units but does not apply it.
        factor = float(trimesh.units.unit_conversion(units, "meters"))
        scale = scale * factor
        notes.append(f"COLLADA unit {units!r} applied (factor {factor:g})")
    return scale, notes


def load_mesh(geometry: Geometry):
    """``(mesh, notes)``: the geometry's file as one :class:`trimesh.Trimesh` (``force="mesh"``: a
    file's parts concatenated), scaled by the URDF ``scale`` and the COLLADA unit. Raises
    :class:`~urdf2links.errors.MeshError` naming the file when it is unresolved, missing,
    unreadable or holds no triangles; URDFValueError for a zero or non-finite scale."""
    import trimesh

    mesh, path = _read(geometry, force_mesh=True)
    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
        raise MeshError(f"mesh {_name(geometry)!r}: {str(path)!r} contains no triangles")
    scale, notes = _scale(geometry, getattr(mesh, "units", None), path)
    mesh.apply_transform(np.diag([*scale, 1.0]))  # flips the faces itself when det < 0
    return mesh, notes


def load_mesh_parts(geometry: Geometry) -> tuple[list, list[str]]:
    """``(parts, notes)``: the geometry's file as a list of :class:`trimesh.Trimesh` parts (a scene's
    geometries with their placement in the file applied, each keeping its own material or colours),
    scaled like :func:`load_mesh`. Same errors as :func:`load_mesh`."""
    import trimesh

    loaded, path = _read(geometry, force_mesh=False)
    if isinstance(loaded, trimesh.Scene):
        parts = [p for p in loaded.dump(concatenate=False) if isinstance(p, trimesh.Trimesh) and len(p.faces)]
    elif isinstance(loaded, trimesh.Trimesh) and len(loaded.faces):
        parts = [loaded]
    else:
        parts = []
    if not parts:
        raise MeshError(f"mesh {_name(geometry)!r}: {str(path)!r} contains no triangles")
    scale, notes = _scale(geometry, getattr(loaded, "units", None), path)
    for p in parts:
        p.apply_transform(np.diag([*scale, 1.0]))
    return parts, notes

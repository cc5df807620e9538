"""Inertia from geometry: boxes, cylinders, spheres and meshes (trimesh) as pseudo-inertia matrices H.

A link without an ``<inertial>`` (or with ``inertia="geometry"``) gets ``H`` (docs/equations.md (E10))
from its collision or visual shapes at a density or a given mass; meshes are read by
:mod:`urdf2links.parsers.meshes`, open ones closed by their convex hull (noted).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..dynamics.inertia import pseudo_inertia, transform_pseudo_inertia
from ..dynamics.rotations import homogeneous, rpy_to_matrix
from ..errors import MeshError, URDFValueError
from .description import Geometry
from .meshes import load_mesh

__all__ = ["GeometryInertia", "geometry_inertia", "combined_geometry_inertia"]


# --------------------------------------------------------------------------- geometry


@dataclass(frozen=True)
class GeometryInertia:
    """Inertia of geometry: ``H`` (4, 4) in the LINK frame, ``mass`` (kg), ``volume`` (m^3).

    ``method`` is ``"box"``, ``"cylinder"``, ``"sphere"``, ``"mesh"`` or ``"mesh-convex-hull"``
    (:func:`combined_geometry_inertia` joins its parts' with ``"+"``); ``note`` says what was
    assumed (density or given mass, units, fallbacks and why).
    """

    H: np.ndarray
    mass: float
    volume: float
    method: str
    note: str = ""


def _positive(value, name: str) -> float:
    if value is None:
        raise URDFValueError(f"{name} is missing")
    try:
        v = float(value)
    except (TypeError, ValueError):
        v = float("nan")
    if not np.isfinite(v) or v <= 0.0:
        raise URDFValueError(f"{name} must be a positive finite number, got {v if v == v else value!r}")
    return v


def _mass(mass) -> float | None:
    if mass is None:
        return None
    m = float(mass)
    if not (np.isfinite(m) and m >= 0.0):
        raise URDFValueError(f"mass must be a non-negative finite number, got {m}")
    return m


def _mesh_unit_H(geometry: Geometry) -> tuple[float, np.ndarray, str, list[str]]:
    """``(volume, H per unit mass, method, notes)`` of a mesh in its own (scaled) frame."""
    mesh, notes = load_mesh(geometry)
    name, path = geometry.filename or str(geometry.path), Path(geometry.path)
    # Loaders keep vertices split along texture / normal seams (typical of DAE and some STL),
    # which makes a closed surface look open; merge by position only (geometry unchanged).
    mesh.merge_vertices(merge_tex=True, merge_norm=True)
    reason = None
    if not mesh.is_watertight:
        reason = "it is not watertight (open or non-manifold)"
    elif not mesh.is_winding_consistent:
        reason = "its face winding is inconsistent"
    elif mesh.volume < 0.0:  # closed and consistently inside-out: flipping is exact
        mesh.invert()
        notes.append("faces were inside-out (negative volume); flipped")
    if reason is None and not mesh.volume > 0.0:
        reason = f"its volume is {mesh.volume:.3g}"
    method = "mesh"
    if reason is not None:
        try:
            with np.errstate(invalid="ignore", divide="ignore"):  # flat input: reported below
                method, mesh = "mesh-convex-hull", mesh.convex_hull
        except Exception as exc:  # qhull on degenerate (flat, collinear) input
            raise MeshError(f"mesh {name!r}: {str(path)!r} is open ({reason}) and has no convex "
                            f"hull ({type(exc).__name__}); cannot estimate an inertia") from exc
        notes.append(f"convex hull used because {reason}")
    if not mesh.volume > 0.0:
        raise MeshError(f"mesh {name!r}: {str(path)!r} encloses no volume (convex hull volume "
                        f"{mesh.volume:.3g}); cannot estimate an inertia")
    props = mesh.mass_properties  # inertia: standard tensor about center_mass, mesh axes
    H1 = pseudo_inertia(1.0, props.center_mass, np.asarray(props.inertia) / props.mass)
    return float(props.volume), H1, method, notes


def geometry_inertia(geometry: Geometry, *, mass: float | None = None,
                     density: float = 1000.0) -> GeometryInertia:
    """Inertia of a uniform solid filling one URDF geometry, in the link frame.

    Parameters
    ----------
    geometry : Geometry
        ``box`` / ``cylinder`` (axis z) / ``sphere`` by closed form; ``mesh`` (STL, OBJ, DAE, ...
        via ``trimesh.load(..., force="mesh")``, ``scale`` and COLLADA ``<unit>`` applied) by
        trimesh's mass properties. A mesh that is not watertight or has inconsistent winding
        is replaced by its convex hull (``method="mesh-convex-hull"``, ``note`` says why); a
        closed mesh that is inside-out everywhere (negative volume) is flipped, which is exact.
    mass : float, optional
        Keep this mass (density becomes ``mass / volume``). Default ``density * volume``.
    density : float
        kg/m^3, used when ``mass`` is None (default 1000, water).

    Returns
    -------
    GeometryInertia
        ``H`` (4, 4) re-expressed from the geometry's origin (``xyz``, URDF ``rpy``) to the link.

    Raises
    ------
    MeshError
        Mesh path unresolved, missing, unreadable, empty or without volume (names the file).
    URDFValueError
        Unknown kind, missing or non-positive dimensions, bad ``mass`` / ``density`` / ``scale``.
    """
    mass, density = _mass(mass), _positive(density, "density")
    kind, notes, method = geometry.kind, [], geometry.kind
    if kind == "box":
        size = np.asarray(_positive(None, "box size") if geometry.size is None else geometry.size, float)
        a, b, h = (_positive(x, f"box size {size.tolist()}: each side") for x in size.reshape(3))
        volume, sigma1 = a * b * h, np.array([a * a, b * b, h * h]) / 12.0
    elif kind == "cylinder":
        r = _positive(geometry.radius, "cylinder radius")
        h = _positive(geometry.length, "cylinder length")
        volume, sigma1 = np.pi * r * r * h, np.array([r * r / 4.0, r * r / 4.0, h * h / 12.0])
    elif kind == "sphere":
        r = _positive(geometry.radius, "sphere radius")
        volume, sigma1 = 4.0 / 3.0 * np.pi * r**3, np.full(3, r * r / 5.0)
    elif kind == "mesh":
        volume, H1, method, notes = _mesh_unit_H(geometry)
    else:
        raise URDFValueError(f"unknown geometry kind {kind!r} (expected box, cylinder, sphere or mesh)")
    if kind != "mesh":
        H1 = np.diag([*sigma1, 1.0])  # sigma_k = integral(x_k^2 dm) per unit mass, centred
    if mass is None:
        m = density * volume
        notes.insert(0, f"uniform density {density:g} kg/m^3")
    else:
        m = mass
        notes.insert(0, f"mass {mass:g} kg given, uniform density {mass / volume:g} kg/m^3")
    T = homogeneous(rpy_to_matrix(geometry.origin.rpy), np.asarray(geometry.origin.xyz, dtype=float))
    return GeometryInertia(H=transform_pseudo_inertia(m * H1, T), mass=float(m), volume=float(volume),
                           method=method, note="; ".join(notes))


def combined_geometry_inertia(geometries, *, mass: float | None = None,
                              density: float = 1000.0) -> GeometryInertia:
    """Inertia of several geometries of one link, as one uniform-density body.

    Each geometry is computed with ``density``; the ``H`` are summed (rigid union) in the link
    frame. If ``mass`` is given, the sum is scaled so the total is ``mass`` (one common density).
    Overlapping geometries are counted twice (no boolean union). ``method`` joins the parts'
    with ``"+"``, ``note`` joins theirs with ``" | "``.
    """
    geometries, mass = tuple(geometries), _mass(mass)
    if not geometries:
        raise URDFValueError("no geometry to compute an inertia from")
    parts = [geometry_inertia(g, density=density) for g in geometries]
    H, total = sum(p.H for p in parts), sum(p.mass for p in parts)
    volume = sum(p.volume for p in parts)
    note = " | ".join(p.note for p in parts)
    if mass is not None:
        H, total = H * (mass / total), mass
        note = f"mass {mass:g} kg given, uniform density {mass / volume:g} kg/m^3 | " + note
    return GeometryInertia(H=H, mass=float(total), volume=float(volume),
                           method="+".join(p.method for p in parts), note=note)

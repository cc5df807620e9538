"""Tests of urdf2links.dynamics.inertia: pseudo-inertia H, audit, repair, geometry inertia."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
import trimesh

from urdf2links.parsers.description import Geometry, Origin
from urdf2links.errors import InertiaError, MeshError, URDFValueError
from urdf2links.dynamics.inertia import (
    Finding, audit_pseudo_inertia, axis_inertia, inertial_from_pseudo, nearest_consistent, principal_moments,
    pseudo_inertia, transform_pseudo_inertia,
)
from urdf2links.parsers.geometry_inertia import GeometryInertia, combined_geometry_inertia, geometry_inertia
from urdf2links.dynamics.rotations import homogeneous, rpy_to_matrix

# ------------------------------------------------------------------ independent references


def box_quadrature_H(size, mass, T=np.eye(4)):
    """integral(r r^T dm) of a uniform box, by 2-point Gauss-Legendre per axis.

    The integrand is quadratic in the body coordinates, and 2-point Gauss is exact for
    cubics, so this is exact; it does not use any formula of the module. ``T`` (4, 4) places
    the box (centred at its own origin) in the frame where H is wanted.
    """
    g = np.array([-1.0, 1.0]) / math.sqrt(3.0)
    half = np.asarray(size, dtype=float) / 2
    H = np.zeros((4, 4))
    for i, j, k in itertools.product(g, g, g):
        r = T @ np.array([i * half[0], j * half[1], k * half[2], 1.0])
        H += (mass / 8) * np.outer(r, r)
    return H


def urdf_box_inertia(size, mass):
    a, b, c = size
    return mass / 12 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])


def origin(xyz=(0, 0, 0), rpy=(0, 0, 0)):
    return Origin(xyz=np.array(xyz, dtype=float), rpy=np.array(rpy, dtype=float))


def mesh_geometry(path, *, scale=None, org=None):
    return Geometry(kind="mesh", origin=org or origin(), filename=path.name, path=path,
                    scale=None if scale is None else np.array(scale, dtype=float))


SIZE = (0.3, 0.5, 0.9)
# Binary STL (and trimesh's COLLADA export) store float32 vertices: meshes compared to
# 1e-10 use dimensions that float32 holds exactly.
MESH_SIZE = (0.25, 0.5, 0.875)
XYZ = (0.1, -0.2, 0.35)
RPY = (0.4, -1.1, 2.3)


# ------------------------------------------------------------------ pseudo-inertia algebra


def test_box_H_from_urdf_inertial_equals_integral():
    m = 2.5
    H = pseudo_inertia(m, [0, 0, 0], urdf_box_inertia(SIZE, m))
    np.testing.assert_allclose(H, box_quadrature_H(SIZE, m), rtol=0, atol=1e-15)
    np.testing.assert_allclose(H, np.diag([m * s * s / 12 for s in SIZE] + [m]), atol=1e-15)


def test_rotated_inertial_origin_gives_positive_products():
    """URDF ixy = -integral(xy dm); H holds +integral(xy dm). Box rotated and shifted in space."""
    m = 1.7
    Rc = rpy_to_matrix(RPY)
    I_urdf = urdf_box_inertia(SIZE, m)
    H = pseudo_inertia(m, XYZ, I_urdf, rotation=Rc)
    H_ref = box_quadrature_H(SIZE, m, homogeneous(Rc, XYZ))
    np.testing.assert_allclose(H, H_ref, rtol=0, atol=1e-14)
    # the same body given by its URDF tensor in link axes (off-diagonals non-zero)
    I_link = Rc @ I_urdf @ Rc.T
    assert np.all(np.abs(I_link[np.triu_indices(3, 1)]) > 1e-3)
    np.testing.assert_allclose(pseudo_inertia(m, XYZ, I_link), H_ref, atol=1e-14)


def test_sign_of_products_with_point_masses():
    # two point masses 0.5 kg at (1, 2, 0) and (-1, -2, 0): integral(x y dm) = 2
    pts, mi = np.array([[1.0, 2.0, 0.0], [-1.0, -2.0, 0.0]]), 0.5
    I = sum(mi * (p @ p * np.eye(3) - np.outer(p, p)) for p in pts)
    assert I[0, 1] == -2.0  # URDF ixy
    H = pseudo_inertia(1.0, [0, 0, 0], I)
    assert H[0, 1] == pytest.approx(2.0)
    np.testing.assert_allclose(H[:3, :3], sum(mi * np.outer(p, p) for p in pts), atol=1e-15)


def test_round_trip_pseudo_inertial():
    rng = np.random.default_rng(5)
    for _ in range(50):
        m = rng.uniform(0.1, 10)
        size = rng.uniform(0.01, 2, 3)
        c = rng.normal(size=3)
        Rc = rpy_to_matrix(rng.uniform(-3, 3, 3))
        H = pseudo_inertia(m, c, urdf_box_inertia(size, m), rotation=Rc)
        m2, c2, I2 = inertial_from_pseudo(H)
        assert m2 == pytest.approx(m, rel=1e-15)
        np.testing.assert_allclose(c2, c, rtol=0, atol=1e-14)
        np.testing.assert_allclose(I2, Rc @ urdf_box_inertia(size, m) @ Rc.T, rtol=0, atol=1e-13 * m * (1 + c @ c))
        np.testing.assert_allclose(pseudo_inertia(m2, c2, I2), H, rtol=0, atol=1e-13 * m * (1 + c @ c))
    m0, c0, I0 = inertial_from_pseudo(np.zeros((4, 4)))
    assert m0 == 0.0 and not c0.any() and not I0.any()


def test_transform_and_union():
    T1 = homogeneous(rpy_to_matrix(RPY), XYZ)
    T2 = homogeneous(rpy_to_matrix([0.1, 0.2, -0.3]), [-1.0, 0.5, 0.0])
    H1 = transform_pseudo_inertia(box_quadrature_H(SIZE, 1.0), T1)
    np.testing.assert_allclose(H1, box_quadrature_H(SIZE, 1.0, T1), atol=1e-15)
    # chaining frames, and the union of two bodies is the sum
    H12 = transform_pseudo_inertia(transform_pseudo_inertia(box_quadrature_H(SIZE, 2.0), T1), T2)
    np.testing.assert_allclose(H12, box_quadrature_H(SIZE, 2.0, T2 @ T1), atol=1e-14)
    union = H1 + box_quadrature_H((1, 1, 1), 3.0, T2)
    m, c, _ = inertial_from_pseudo(union)
    assert m == pytest.approx(4.0)
    np.testing.assert_allclose(c, (np.array(XYZ) + 3 * np.array([-1.0, 0.5, 0.0])) / 4, atol=1e-15)


def test_axis_inertia_parallel_axis():
    m, d = 2.0, np.array([0.3, -0.4, 7.0])
    H = box_quadrature_H(SIZE, m, homogeneous(np.eye(3), d))
    a, b, _ = SIZE
    expected = m * (a * a + b * b) / 12 + m * (d[0] ** 2 + d[1] ** 2)
    assert axis_inertia(H, [0, 0, 1]) == pytest.approx(expected, rel=1e-14)
    assert axis_inertia(H, [0, 0, -3]) == pytest.approx(expected, rel=1e-14)
    # point mass on the axis has zero inertia about it
    assert axis_inertia(pseudo_inertia(1.0, [0, 0, 2], np.zeros((3, 3))), [0, 0, 1]) == 0.0
    with pytest.raises(URDFValueError):
        axis_inertia(H, [0, 0, 0])


def test_principal_moments():
    Rc = rpy_to_matrix(RPY)
    np.testing.assert_allclose(principal_moments(Rc @ np.diag([3.0, 1.0, 2.0]) @ Rc.T), [1, 2, 3], atol=1e-14)


# ------------------------------------------------------------------ audit


def kinds(findings):
    return {f.kind for f in findings}


def test_audit_passes_valid_inertias():
    rng = np.random.default_rng(11)
    for _ in range(100):
        m = 10 ** rng.uniform(-4, 3)
        size = 10 ** rng.uniform(-4, 1) * 10 ** rng.uniform(0, 3, 3)  # aspect ratios up to 1000
        H = pseudo_inertia(m, rng.normal(size=3), urdf_box_inertia(size, m), rotation=rpy_to_matrix(rng.uniform(-3, 3, 3)))
        assert audit_pseudo_inertia(H, link="l") == []


def test_audit_rounded_urdf_values_pass():
    # a thin-ish cylinder written with 4 significant digits, as URDF exporters do
    I = np.diag([0.0021, 0.0021, 0.0003])
    assert audit_pseudo_inertia(pseudo_inertia(0.8, [0, 0, 0.1], I), link="l") == []


def test_audit_triangle_inequality():
    H = pseudo_inertia(1.0, [0.1, 0, 0], np.diag([1.0, 1.0, 3.0]), rotation=rpy_to_matrix(RPY))
    found = audit_pseudo_inertia(H, link="forearm")
    assert kinds(found) == {"triangle_inequality", "not_positive_definite"}
    tri = next(f for f in found if f.kind == "triangle_inequality")
    assert isinstance(tri, Finding) and tri.link == "forearm" and "forearm" in tri.message
    assert tri.values["excess"] == pytest.approx(1.0)
    npd = next(f for f in found if f.kind == "not_positive_definite")
    assert min(npd.values["eigenvalues"]) < 0


def test_audit_negative_principal_moment():
    found = audit_pseudo_inertia(pseudo_inertia(1.0, [0, 0, 0], np.diag([-0.1, 1.0, 1.0])), link="x")
    assert "negative_principal_moment" in kinds(found) and "not_positive_definite" in kinds(found)


@pytest.mark.parametrize("mass", [0.0, -1.0])
def test_audit_non_positive_mass(mass):
    found = audit_pseudo_inertia(pseudo_inertia(mass, [0, 0, 0], np.eye(3)), link="base")
    assert kinds(found) == {"non_positive_mass", "not_positive_definite"}
    assert next(f for f in found if f.kind == "non_positive_mass").values["mass"] == mass


def test_audit_nan():
    H = pseudo_inertia(1.0, [0, 0, 0], np.eye(3))
    H[0, 1] = np.nan
    found = audit_pseudo_inertia(H, link="hand")
    assert kinds(found) == {"nan"} and "hand" in found[0].message


def test_audit_zero_thickness_is_degenerate_not_triangle():
    # a flat plate: Izz = Ixx + Iyy exactly; H is singular
    H = pseudo_inertia(1.0, [0, 0, 0], np.diag([1.0, 2.0, 3.0]))
    assert kinds(audit_pseudo_inertia(H, link="plate")) == {"not_positive_definite"}


# ------------------------------------------------------------------ repair


def test_nearest_consistent_leaves_valid_H_unchanged():
    H = pseudo_inertia(1.7, XYZ, urdf_box_inertia(SIZE, 1.7), rotation=rpy_to_matrix(RPY))
    out = nearest_consistent(H)
    np.testing.assert_array_equal(out, H)
    assert out is not H


@pytest.mark.parametrize("I", [np.diag([1.0, 1.0, 3.0]), np.diag([-0.1, 1.0, 1.0]), np.diag([1.0, 2.0, 3.0]), np.diag([1e-3, 1e-3, 0.5])])
def test_nearest_consistent_repairs(I):
    m, c, Rc = 2.0, np.array(XYZ), rpy_to_matrix(RPY)
    H = pseudo_inertia(m, c, I, rotation=Rc)
    out = nearest_consistent(H, link="l")
    assert np.all(np.linalg.eigvalsh(out) > 0)
    assert audit_pseudo_inertia(out, link="l") == []
    m2, c2, I2 = inertial_from_pseudo(out)
    assert m2 == m
    np.testing.assert_allclose(c2, c, atol=1e-14)
    # second moments sigma = eig(0.5 tr(I) 1 - I): those above the floor are kept, the others
    # are raised to the floor 1e-6 * max(sigma)
    sig_before = np.linalg.eigvalsh(0.5 * np.trace(I) * np.eye(3) - I)
    sig_after = np.linalg.eigvalsh(0.5 * np.trace(I2) * np.eye(3) - I2)
    floor = 1e-6 * sig_before[2]
    np.testing.assert_allclose(sig_after, np.maximum(sig_before, floor), rtol=1e-9, atol=1e-12 * sig_before[2])


def test_nearest_consistent_refuses_what_it_cannot_repair():
    with pytest.raises(InertiaError, match="wheel"):
        nearest_consistent(pseudo_inertia(-1.0, [0, 0, 0], np.eye(3)), link="wheel")
    with pytest.raises(InertiaError, match="geometry"):
        nearest_consistent(pseudo_inertia(1.0, [0, 0, 0], np.zeros((3, 3))), link="wheel")
    H = np.eye(4)
    H[1, 1] = np.inf
    with pytest.raises(InertiaError, match="wheel"):
        nearest_consistent(H, link="wheel")


# ------------------------------------------------------------------ geometry: closed forms


def test_primitive_geometries():
    box = geometry_inertia(Geometry("box", origin(XYZ, RPY), size=np.array(SIZE)), density=500.0)
    m = 500.0 * np.prod(SIZE)
    assert isinstance(box, GeometryInertia) and box.method == "box"
    assert box.mass == pytest.approx(m) and box.volume == pytest.approx(np.prod(SIZE))
    np.testing.assert_allclose(box.H, box_quadrature_H(SIZE, m, homogeneous(rpy_to_matrix(RPY), XYZ)), atol=1e-14)

    cyl = geometry_inertia(Geometry("cylinder", origin(), radius=0.2, length=0.6), mass=3.0)
    np.testing.assert_allclose(cyl.H, np.diag([3 * 0.04 / 4, 3 * 0.04 / 4, 3 * 0.36 / 12, 3.0]), atol=1e-15)
    assert cyl.mass == 3.0 and "3 kg given" in cyl.note
    _, _, I = inertial_from_pseudo(cyl.H)
    np.testing.assert_allclose(np.diag(I), [3 * (3 * 0.04 + 0.36) / 12] * 2 + [3 * 0.04 / 2], atol=1e-15)

    sph = geometry_inertia(Geometry("sphere", origin([0, 0, 1]), radius=0.1))
    ms = 1000 * 4 / 3 * math.pi * 1e-3
    assert sph.mass == pytest.approx(ms)
    _, c, I = inertial_from_pseudo(sph.H)
    np.testing.assert_allclose(c, [0, 0, 1], atol=1e-15)
    np.testing.assert_allclose(I, 0.4 * ms * 0.01 * np.eye(3), atol=1e-15)


def test_geometry_errors():
    with pytest.raises(URDFValueError, match="capsule"):
        geometry_inertia(Geometry("capsule", origin()))
    with pytest.raises(URDFValueError, match="radius"):
        geometry_inertia(Geometry("cylinder", origin(), length=1.0))
    with pytest.raises(URDFValueError, match="density"):
        geometry_inertia(Geometry("sphere", origin(), radius=1.0), density=0.0)


# ------------------------------------------------------------------ geometry: meshes


@pytest.mark.parametrize("ext", ["stl", "obj", "dae"])
def test_mesh_box_exact(tmp_path, ext):
    path = tmp_path / f"box.{ext}"
    trimesh.creation.box(extents=MESH_SIZE).export(path)
    gi = geometry_inertia(mesh_geometry(path), density=700.0)
    ref = geometry_inertia(Geometry("box", origin(), size=np.array(MESH_SIZE)), density=700.0)
    assert gi.method == "mesh", gi.note
    assert gi.volume == pytest.approx(ref.volume, rel=1e-12)
    np.testing.assert_allclose(gi.H, ref.H, rtol=0, atol=1e-10 * np.abs(ref.H).max())


@pytest.mark.parametrize("ext", ["obj", "dae"])
def test_mesh_with_texture_seams_is_closed(tmp_path, ext):
    """Loaders keep vertices split where UVs differ, so a closed box looks open to trimesh;
    merging by position must make it watertight again (no convex-hull fallback)."""
    box = trimesh.creation.box(extents=MESH_SIZE)
    box.unmerge_vertices()
    box.visual = trimesh.visual.TextureVisuals(uv=np.random.default_rng(0).uniform(size=(len(box.vertices), 2)))
    path = tmp_path / f"seams.{ext}"
    box.export(path)
    assert not trimesh.load(path, force="mesh").is_watertight  # the trimesh behaviour handled here
    gi = geometry_inertia(mesh_geometry(path), mass=1.0)
    assert gi.method == "mesh", gi.note
    np.testing.assert_allclose(np.diag(gi.H), [s * s / 12 for s in MESH_SIZE] + [1.0], rtol=1e-10)


def test_mesh_scale_and_origin(tmp_path):
    path = tmp_path / "unit.stl"
    trimesh.creation.box(extents=(1.0, 1.0, 1.0)).export(path)
    scale = (0.3, -0.5, 0.9)  # a negative (mirroring) scale must not flip the volume's sign
    gi = geometry_inertia(mesh_geometry(path, scale=scale, org=origin(XYZ, RPY)), mass=2.0)
    assert gi.method == "mesh" and gi.volume == pytest.approx(0.135, rel=1e-12)
    ref = box_quadrature_H(np.abs(scale), 2.0, homogeneous(rpy_to_matrix(RPY), XYZ))
    np.testing.assert_allclose(gi.H, ref, rtol=0, atol=1e-12)


def test_mesh_cylinder_within_faceting_error(tmp_path):
    """A trimesh cylinder is a prism over a regular n-gon inscribed in the circle.

    With the mass fixed, the prism's transverse second moment is that of the ideal cylinder
    times (2 + cos t)/3 with t = 2 pi/n (polygon: J/A = R^2 (2 + cos t)/6, circle R^2/2),
    i.e. a relative error of about t^2/6 = 1.6e-3 for n = 64. So: against the polygon
    formula to the file's precision (binary STL holds float32 vertices, relative error
    6e-8 per coordinate, so 1e-6 on moments), and within t^2/6 of the cylinder's closed
    form (and not much closer: the comparison does see the faceting).
    """
    n, r, h, m = 64, 0.2, 0.6, 3.0
    path = tmp_path / "cyl.stl"
    trimesh.creation.cylinder(radius=r, height=h, sections=n).export(path)
    gi = geometry_inertia(mesh_geometry(path), mass=m)
    ideal = geometry_inertia(Geometry("cylinder", origin(), radius=r, length=h), mass=m)
    t = 2 * math.pi / n
    assert gi.volume == pytest.approx(n / 2 * r * r * math.sin(t) * h, rel=1e-6)
    sig_xy = m * r * r * (2 + math.cos(t)) / 12  # = m (J/A) / 2
    np.testing.assert_allclose(np.diag(gi.H), [sig_xy, sig_xy, m * h * h / 12, m], rtol=1e-6)
    assert np.abs(gi.H - np.diag(np.diag(gi.H))).max() < 1e-6 * sig_xy
    rel = np.abs(np.diag(gi.H) - np.diag(ideal.H)) / np.diag(ideal.H)
    assert rel.max() <= t * t / 6 and rel[0] > 0.5 * t * t / 6


def test_open_mesh_falls_back_to_convex_hull(tmp_path):
    box = trimesh.creation.box(extents=MESH_SIZE)
    open_box = trimesh.Trimesh(box.vertices, box.faces[:-2], process=False)  # one side removed
    assert not open_box.is_watertight
    path = tmp_path / "open.stl"
    open_box.export(path)
    gi = geometry_inertia(mesh_geometry(path), density=700.0)
    assert gi.method == "mesh-convex-hull"
    assert "convex hull" in gi.note and "not watertight" in gi.note
    ref = geometry_inertia(Geometry("box", origin(), size=np.array(MESH_SIZE)), density=700.0)
    np.testing.assert_allclose(gi.H, ref.H, rtol=0, atol=1e-10 * np.abs(ref.H).max())


def test_inconsistent_winding_falls_back_to_convex_hull(tmp_path):
    box = trimesh.creation.box(extents=SIZE)
    faces = box.faces.copy()
    faces[0] = faces[0][::-1]
    path = tmp_path / "bad.obj"
    trimesh.Trimesh(box.vertices, faces, process=False).export(path)
    gi = geometry_inertia(mesh_geometry(path))
    assert gi.method == "mesh-convex-hull" and "winding" in gi.note
    assert gi.volume == pytest.approx(np.prod(SIZE), rel=1e-12)


def test_inside_out_mesh_is_flipped_exactly(tmp_path):
    ring = trimesh.creation.annulus(r_min=0.5, r_max=1.0, height=0.4)  # closed, not convex
    ring.invert()
    path = tmp_path / "ring.stl"
    ring.export(path)
    gi = geometry_inertia(mesh_geometry(path))
    assert gi.method == "mesh" and "flipped" in gi.note
    # float32 STL: 1e-6; the hull would be 1.33 times larger
    assert gi.volume == pytest.approx(-ring.volume, rel=1e-6)


def test_dae_units_are_applied(tmp_path):
    text = trimesh.exchange.dae.export_collada(trimesh.creation.box(extents=(100.0, 200.0, 300.0)))
    text = text.decode() if isinstance(text, bytes) else text
    assert "<asset>" in text
    path = tmp_path / "mm.dae"
    path.write_text(text.replace("<asset>", '<asset><unit meter="0.001" name="millimeter"/>', 1))
    gi = geometry_inertia(mesh_geometry(path), mass=1.0)
    assert gi.volume == pytest.approx(6e-3, rel=1e-12) and "unit" in gi.note
    np.testing.assert_allclose(np.diag(gi.H), [0.01 / 12, 0.04 / 12, 0.09 / 12, 1.0], rtol=1e-10)


def test_mesh_errors_name_the_file(tmp_path):
    with pytest.raises(MeshError, match="nowhere.stl"):
        geometry_inertia(mesh_geometry(tmp_path / "nowhere.stl"))
    with pytest.raises(MeshError, match="package://robot/meshes/x.stl"):
        geometry_inertia(Geometry("mesh", origin(), filename="package://robot/meshes/x.stl", path=None))
    junk = tmp_path / "junk.stl"
    junk.write_bytes(b"\x00garbage" * 3)
    with pytest.raises(MeshError, match="junk.stl"):
        geometry_inertia(mesh_geometry(junk))
    flat = tmp_path / "flat.stl"
    trimesh.Trimesh([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], [[0, 1, 2], [1, 3, 2]]).export(flat)
    with pytest.raises(MeshError, match="flat.stl.*(no volume|no convex hull)"):
        geometry_inertia(mesh_geometry(flat))


def test_combined_geometry_inertia(tmp_path):
    g1 = Geometry("box", origin(XYZ, RPY), size=np.array(SIZE))
    g2 = Geometry("sphere", origin([0, 0, -0.5]), radius=0.1)
    parts = [geometry_inertia(g, density=800.0) for g in (g1, g2)]
    both = combined_geometry_inertia([g1, g2], density=800.0)
    np.testing.assert_allclose(both.H, parts[0].H + parts[1].H, atol=1e-15)
    assert both.method == "box+sphere" and both.mass == pytest.approx(parts[0].mass + parts[1].mass)
    scaled = combined_geometry_inertia([g1, g2], mass=5.0)
    assert scaled.mass == 5.0 and scaled.H[3, 3] == pytest.approx(5.0)
    np.testing.assert_allclose(scaled.H, both.H * 5.0 / both.mass, rtol=1e-14)
    with pytest.raises(URDFValueError):
        combined_geometry_inertia([])

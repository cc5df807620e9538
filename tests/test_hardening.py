"""Hardened inputs (issue 15), case by case: the physical ranges of URDF and scene numbers, mesh paths that
are never read, run settings checked where they are given, runs that cannot progress ending in an
IntegrationError that says why. The random side of the same promises is tests/test_fuzz.py."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
import time
import warnings
from pathlib import Path

import numpy as np
import pytest

from urdf2links import load_urdf, load_urdf_string
from urdf2links.parsers.description import Geometry, Origin
from urdf2links.errors import IntegrationError, MeshError, SceneError, URDFSyntaxError, URDFValueError
from urdf2links.parsers.geometry_inertia import geometry_inertia
from urdf2links.integration.integrators import integrate
from urdf2links.scenes.plan import compile_plan
from urdf2links.parsers.mesh_paths import require_mesh, resolve_mesh_path
from urdf2links.ranges import MAX_SAMPLES, MAX_STEPS, RANGES, RTOL_FLOOR
from urdf2links.scenes.scene_read import load_scene, scene_from_dict
from urdf2links.integration.simulate import simulate, warm_up

ROOT = Path(__file__).resolve().parent.parent
ROBOTS = ROOT / "robots"

TWO_LINKS = """<robot name="r">
  <link name="base"/>
  <link name="arm"><inertial><origin xyz="{com} 0 0"/><mass value="{mass}"/>
    <inertia ixx="{I}" ixy="0" ixz="0" iyy="{I}" iyz="0" izz="{I}"/></inertial>{geometry}</link>
  <joint name="j" type="revolute"><parent link="base"/><child link="arm"/><origin xyz="{x} 0 0"/>
    <axis xyz="{axis}"/><limit lower="-1e16" upper="1e16" effort="1e9" velocity="1e9"/>
    <dynamics damping="{damping}"/></joint>
</robot>"""
OK = dict(com=0.5, mass=2.0, I=0.1, x=0.0, axis="0 0 1", damping=0.1, geometry="")


def two_links(**kw) -> str:
    return TWO_LINKS.format(**{**OK, **kw})


# ---------------------------------------------------------------------------------------- URDF ranges

@pytest.mark.parametrize("field, value, element, quantity", [
    ("mass", "1e308", "<mass>", "mass"),
    ("mass", "-2e9", "<mass>", "mass"),
    ("I", "1e200", "<inertia>", "inertia"),
    ("com", "1e5", "<inertial> <origin>", "length"),
    ("x", "-3e300", "joint 'j' <origin>", "length"),
    ("damping", "1e300", "<dynamics>", "damping"),
])
def test_urdf_values_outside_the_physical_range_are_refused_by_name(field, value, element, quantity):
    """Before: 1e308 values loaded and made A non-finite, or numpy's eigensolver failed ("Eigenvalues did
    not converge"). Now the reader refuses them where they are read: file, line, element, value, range."""
    with pytest.raises(URDFValueError) as info:
        load_urdf_string(two_links(**{field: value}))
    msg = str(info.value)
    bound, _ = RANGES[quantity]
    assert "<string>, line" in msg and element in msg and f"{float(value):g}" in msg, msg
    assert f"|{quantity}| <= {bound:g}" in msg and "Physical ranges" in msg, msg


def test_values_at_the_edge_of_the_ranges_give_finite_terms():
    """The largest values allowed everywhere at once (1e9 kg, 1e15 kg m^2, 1e4 m, damping 1e12) load, and
    the terms stay finite (module doc of urdf2links.ranges: no product overflows)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")          # such a body breaks the triangle inequality: audited
        model = load_urdf_string(two_links(mass="1e9", I="1e15", com="1e4", x="-1e4", damping="1e12"))
    q, qd = np.array([0.7]), np.array([1e3])
    for term in (model.mass_matrix(q), model.bias(q, qd), model.gravity(q), model.forward_dynamics(q, qd)):
        assert np.all(np.isfinite(term))


@pytest.mark.parametrize("axis", ["1e-320 0 0", "1e308 1e308 0", "nan 0 1"])
def test_axes_that_cannot_be_normalized_are_refused(axis):
    with pytest.raises(URDFValueError, match=r"axis|not finite"):
        load_urdf_string(two_links(axis=axis))


def test_joint_limits_need_only_be_finite():
    """The corpus writes 1e16 for "no limit": read as written (the limits are never used in the dynamics)."""
    model = load_urdf_string(two_links())
    assert model.info["joints"][0]["lower"] == -1e16


@pytest.mark.parametrize("prolog", [
    '<!DOCTYPE robot [<!ENTITY a "aaaaaaaaaa"><!ENTITY b "&a;&a;&a;&a;&a;&a;&a;&a;&a;&a;">]>',
    '<!DOCTYPE robot [<!ENTITY x SYSTEM "file:///etc/passwd">]>',
    '<!DOCTYPE robot [\n <!ENTITY x SYSTEM "http://example.invalid/x">\n]>',
])
def test_entity_declarations_stay_refused(prolog):
    """Entity bombs and external entities: refused before parsing, naming the line (nothing expanded)."""
    text = f'<?xml version="1.0"?>\n{prolog}\n<robot name="r"><link name="a"/></robot>'
    with pytest.raises(URDFSyntaxError, match=r"<string>, line 2: the document declares XML entities"):
        load_urdf_string(text)


# ---------------------------------------------------------------------------------------- mesh paths

@pytest.fixture
def mesh_folder(tmp_path):
    (tmp_path / "pkg" / "meshes").mkdir(parents=True)
    cube = "solid c\n" + "".join(
        f"facet normal 0 0 0\nouter loop\nvertex {a}\nvertex {b}\nvertex {c}\nendloop\nendfacet\n"
        for a, b, c in [("0 0 0", "0 0.1 0", "0.1 0 0"), ("0 0 0", "0.1 0 0", "0 0 0.1"),
                        ("0 0 0", "0 0 0.1", "0 0.1 0"), ("0.1 0 0", "0 0.1 0", "0 0 0.1")]) + "endsolid c\n"
    (tmp_path / "pkg" / "meshes" / "tetra.stl").write_text(cube)
    (tmp_path / "pkg" / "meshes" / "folder.stl").mkdir()
    (tmp_path / "secret.stl").write_text(cube)       # a regular mesh file outside the package
    return tmp_path


@pytest.fixture
def never_read(monkeypatch):
    """trimesh.load fails the test if it is called: the paths below must be refused before any read."""
    import trimesh

    def forbidden(*args, **kwargs):
        raise AssertionError(f"trimesh.load called on {args[:1]}")
    monkeypatch.setattr(trimesh, "load", forbidden)


@pytest.mark.parametrize("filename, words", [
    ("/dev/zero", "a character device"),
    ("file:///dev/zero", "a character device"),
    ("/", "a directory"),
    ("package://pkg/../../etc/passwd", "leaves its package folder"),
    ("package://pkg/../secret.stl", "leaves its package folder"),
    ("package://../secret.stl", "leaves its package folder"),
    ("package:///etc/passwd", "leaves its package folder"),
    ("/etc/passwd", "not a mesh file"),
    ("meshes/folder.stl", "not found"),              # a directory is skipped while resolving
])
def test_mesh_paths_that_are_not_regular_files_inside_their_roots_are_never_read(filename, words, mesh_folder,
                                                                                  never_read):
    """Before: /dev/zero or a FIFO named as a mesh could be opened by trimesh (and /dev/zero never ends),
    and package://pkg/../../etc/passwd resolved outside every package folder. Now resolve_mesh_path does not
    resolve them (only regular files, inside the package folders), and require_mesh raises MeshError saying
    why; nothing is opened."""
    path = resolve_mesh_path(filename, directory=mesh_folder / "pkg", package_dirs=[mesh_folder])
    assert path is None or filename == "/etc/passwd"
    with pytest.raises(MeshError, match=words):
        require_mesh(Geometry("mesh", Origin(), filename=filename, path=path, scale=np.ones(3)), link="arm",
                     source="robot.urdf")


def test_a_fifo_or_a_directory_given_as_a_mesh_is_not_opened(mesh_folder, never_read):
    """A FIFO would block the reader forever: it is not a regular file, so it is never opened; nor is a
    directory named like a mesh (geometry_inertia checks the path it is handed, resolved or not)."""
    fifo = mesh_folder / "pkg" / "meshes" / "pipe.stl"
    os.mkfifo(fifo)
    assert resolve_mesh_path("meshes/pipe.stl", directory=mesh_folder / "pkg") is None
    for path, words in ((fifo, "a FIFO"), (mesh_folder / "pkg" / "meshes" / "folder.stl", "a directory"),
                        (Path("/dev/zero"), "a character device")):
        with pytest.raises(MeshError, match=words):
            geometry_inertia(Geometry("mesh", Origin(), filename=path.name, path=path, scale=np.ones(3)))


def test_repair_from_a_device_mesh_falls_back_and_says_why(mesh_folder, never_read):
    """A massless moving link whose only geometry is /dev/zero: inertia='repair' cannot use the mesh
    (MeshError, never read), says so in the audit, and repairs with a small sphere instead."""
    text = two_links(geometry='<collision><geometry><mesh filename="/dev/zero"/></geometry></collision>')
    text = text.replace('<inertial><origin xyz="0.5 0 0"/><mass value="2.0"/>\n    <inertia ixx="0.1" ixy="0" '
                        'ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial>', "")
    model = load_urdf_string(text, inertia="repair")
    fixes = " ".join(r.fix for r in model.audit)
    assert "sphere" in fixes and "a character device, not a regular file" in fixes, fixes


def test_a_good_package_mesh_still_resolves_and_reads(mesh_folder):
    path = resolve_mesh_path("package://pkg/meshes/tetra.stl", package_dirs=[mesh_folder])
    assert path == (mesh_folder / "pkg" / "meshes" / "tetra.stl").resolve()
    gi = geometry_inertia(Geometry("mesh", Origin(), filename="x", path=path, scale=np.ones(3)), mass=1.0)
    assert gi.mass == 1.0 and np.all(np.isfinite(gi.H))


# ---------------------------------------------------------------------------------------- scene values

def write(tmp_path, body: str) -> Path:
    """A scene of the double pendulum with ``body`` (top-level keys, then tables)."""
    p = tmp_path / "scene.toml"
    top, _, tables = body.partition("[") if not body.startswith("[") else ("", "", body[1:])
    p.write_text(top + "[robot]\nshipped = 'double_pendulum'\n" + ("[" + tables if tables else ""))
    return p


@pytest.mark.parametrize("body, key, words", [
    ("[gravity]\nmagnitude = nan\n", "gravity.magnitude", "must be a finite number in [0, 10000] m/s^2, got nan"),
    ("[gravity]\nmagnitude = 1e308\n", "gravity.magnitude", "1e+308 is outside the valid range [0, 10000] m/s^2"),
    ("[gravity]\ndirection = [1e308, 1e308, 0]\n", "gravity.direction[0]", "outside the valid range"),
    ("[run]\nt_end = -1.0\n", "run.t_end", "-1.0 is outside the valid range [1e-09, 1e+06] s"),
    ("[run]\nt_end = inf\n", "run.t_end", "must be a finite number in [1e-09, 1e+06] s, got inf"),
    # found by the slow fuzz profile: a subnormal t_end gave sample times out of order
    ("[run]\nt_end = 1e-320\n", "run.t_end", "1e-320 is outside the valid range [1e-09, 1e+06] s"),
    ("[run]\natol = 1e-320\n", "run.atol", "1e-320 is outside the valid range [1e-30, 1000]"),   # slow fuzz profile
    ("[run]\nrtol = 1e-20\n", "run.rtol", "1e-20 is outside the valid range [2.22045e-14, 0.999]"),
    ("[run]\nsamples = 10000000000\n", "run.samples", f"must be a whole number in [1, {MAX_SAMPLES}]"),
    ("[run]\nsamples = 2.5\n", "run.samples", "must be a whole number"),
    ("[run]\nmethod = 'RK4'\ndt = 1e-12\n", "run.dt", f"more than the {MAX_STEPS:g} a run may take"),
    ("[initial]\nq = { shoulder = 1e300 }\n", "initial.q.shoulder", "outside the valid range [-1e+06, 1e+06]"),
    ("[[spring]]\ncoordinate = 'elbow'\nstiffness = 1e300\n", "spring[0].stiffness", "valid range [0, 1e+12]"),
    ("[base]\nz = { sines = [[1e308, 1.0]] }\n", "base.z", "amplitude: 1e+308 is outside the physical range"),
    ("[base]\nz = { sines = [[1.0, 1e300]] }\n", "base.z", "frequency_hz: 1e+300 is outside the physical range"),
    ("[base]\nz = { times = [0, 1e-300], values = [0, 1] }\n", "base.z", "closer than 1e-06 s"),
    ("[[torque]]\ncoordinate = 'elbow'\nvalue = -1e308\n", "torque[0].value", "outside the physical range"),
    ("[record]\nlink_poses = 3\n", "record.link_poses", "must be a list of strings, got 3"),
    ("torque = 3\n", "[[torque]]", "must be an array of tables"),
    ("[initial]\nq = 3\n", "initial.q", "must be a table"),
])
def test_scene_numbers_are_checked_where_they_are_read(tmp_path, body, key, words):
    """Before: nan/inf/1e308 were accepted until the first evaluation failed with "rhs(t0, y0) is not
    finite" and an array dump; a huge sample count reached numpy's "Maximum allowed size exceeded". Now
    a SceneError names the file, the key, the value and the valid range."""
    p = write(tmp_path, body)
    with pytest.raises(SceneError) as info:
        load_scene(p)
    msg = str(info.value)
    assert str(p) in msg and key in msg and words in msg, msg


def test_simulate_overrides_are_checked_like_the_scene():
    scene = load_scene(ROBOTS / "double_pendulum_chaos.toml")
    with pytest.raises(SceneError, match=r"simulate\(\): rtol: 1e-16 is outside the valid range"):
        simulate(scene, rtol=1e-16, progress=False)
    with pytest.raises(SceneError, match=r"samples: must be a whole number in \[1, 1000000\], got 100000000"):
        simulate(scene, samples=10**8, progress=False)


# ---------------------------------------------------------------------------------- runs that cannot end

def test_rtol_below_what_float64_delivers_is_raised_to_the_floor_with_a_note():
    with pytest.warns(RuntimeWarning, match=r"rtol=1e-18 is below what float64 can deliver; raised to 2\.22e-14"):
        res = integrate(lambda t, y: -y, (0.0, 1.0), [1.0], method="RK45", rtol=1e-18)
    assert res.rtol == RTOL_FLOOR and res.success


@pytest.mark.parametrize("atol", [0.0, 1e-320, [1e-12, 0.0, 1e-12, 1e-12, 1e-12]])
def test_an_atol_that_leaves_a_component_without_a_scale_is_refused(atol):
    """Found by the slow fuzz profile (``atol = 1e-320`` in a scene): the compiled controller divided by zero
    on the work W, which starts at 0. integrate() refuses such an atol by name; scenes have the same floor."""
    scene = load_scene(ROBOTS / "double_pendulum_chaos.toml")
    model = scene.model()
    plan = compile_plan(scene, model)
    q, qd = scene.initial_state(model)
    with pytest.raises(ValueError, match=r"atol must be finite, >= 1e-30, a scalar or of shape \(5,\), got"):
        integrate(plan.rhs, (0.0, 1.0), np.r_[q, qd, 0.0], method="DOP853", atol=atol)


def test_a_fixed_step_run_of_too_many_steps_is_refused_before_it_starts():
    with pytest.raises(IntegrationError, match=r"dt=1e-09 .* makes 1e\+09 steps, more than the 1e\+07"):
        integrate(lambda t, y: -y, (0.0, 1.0), [1.0], method="RK4", dt=1e-9)


@pytest.mark.parametrize("method", ["DOP853", "RK4", "Radau"])
def test_the_wall_clock_budget_ends_a_run_and_says_so(method):
    """A run longer than its budget stops after it (checked per step or per chunk of compiled steps)."""
    scene = load_scene(ROBOTS / "double_pendulum_chaos.toml")
    warm_up(scene, methods=(method,))       # numba's compilation (70 s cold on a loaded machine) is set-up
    start = time.perf_counter()
    with pytest.raises(IntegrationError, match=r"could not finish the run to t_end = 10000 s: max_wall=0\.3 s of "
                                               r"wall time reached at t=.* after \d+ steps"):
        simulate(scene, t_end=1e4, samples=11, method=method, dt=1e-2 if method == "RK4" else None, rtol=1e-10,
                 progress=False, max_wall=0.3)
    assert time.perf_counter() - start < 30      # the budget (0.3 s), a chunk and the set-up; never the run


def test_more_steps_than_the_limit_end_the_run():
    scene = load_scene(ROBOTS / "double_pendulum_chaos.toml")
    with pytest.raises(IntegrationError, match=r"max_steps=50 reached at t="):
        simulate(scene, t_end=10.0, progress=False, max_steps=50)


def test_a_stiffness_at_the_top_of_its_range_ends_in_an_integration_error_not_a_hang():
    """A 1e12 N m/rad spring (allowed: the range is a physical one) makes an explicit method crawl at
    steps ~1e-7 s: with a budget the run ends, saying where it got to."""
    scene = scene_from_dict({"robot": {"shipped": "double_pendulum"}, "gravity": {},
                             "spring": [{"coordinate": "elbow", "stiffness": 1e12}],
                             "initial": {"q": {"elbow": 0.5}}, "run": {"t_end": 100.0}})
    with pytest.raises(IntegrationError, match="max_wall=0.5 s"):
        simulate(scene, progress=False, max_wall=0.5)


def test_cli_max_wall_ends_simulate_with_a_clean_error(tmp_path):
    out = subprocess.run([sys.executable, "-m", "urdf2links.cli", "simulate", str(ROBOTS / "double_pendulum_chaos.toml"),
                          "--t-end", "1e6", "--max-wall", "0.5", "--quiet", "--out", str(tmp_path)],
                         capture_output=True, text=True, timeout=300)
    assert out.returncode == 2, out.stderr
    assert "IntegrationError" not in out.stderr and "Traceback" not in out.stderr
    assert "max_wall=0.5 s of wall time reached" in out.stderr
    bad = subprocess.run([sys.executable, "-m", "urdf2links.cli", "simulate", "x.toml", "--max-wall", "-1"],
                         capture_output=True, text=True, timeout=300)
    assert bad.returncode == 2 and "--max-wall '-1': must be a finite number of seconds > 0" in bad.stderr


@pytest.mark.parametrize("mujoco_dt", [1e-12, 0.0, -1e-3, float("nan")])
def test_a_mujoco_run_of_too_many_steps_is_refused_before_it_starts(mujoco_dt):
    """compare: MuJoCo's run is t_end / timestep steps, known in advance: beyond the step limit (or with a
    timestep that is not positive) it is refused with an IntegrationError before anything runs."""
    from urdf2links.compare.agreement.trajectory import compare_scene

    with pytest.raises(IntegrationError, match=r"MuJoCo timestep .* more than the 1e\+07 a run may take"):
        compare_scene(ROBOTS / "double_pendulum_chaos.toml", t_end=1.0, mujoco_dt=mujoco_dt, progress=False)


def test_the_budget_bounds_a_run_that_re_charts_at_every_step():
    """Found by the slow fuzz profile (a mutant of free_body_gimbal.toml ran past 60 s with a 2 s budget): a free
    body spinning at 1e3 rad/s about y passes phi_y = +-pi/2 every ~3 ms, so its 4 s run is ~1300 short
    segments, each re-charted and compiled, and each stopped by the angle guard before the loop asked the
    clock: every segment kept a budget of its own and the run went on (measured: over 100 s with a 1 s
    budget). Now the budget bounds the whole run."""
    import tomllib

    data = tomllib.loads((ROBOTS / "free_body_gimbal.toml").read_text())
    data["initial"]["qd"] = {"body.phi_x": 0.05, "body.phi_y": 1e3}   # phi_y = +-pi/2 every 3 ms
    scene = scene_from_dict(data, directory=ROBOTS)
    start = time.perf_counter()
    with pytest.raises(IntegrationError, match=r"wall time reached at t=.*\(max_wall 1 s for the whole run\)"):
        simulate(scene, progress=False, max_wall=1.0)
    assert time.perf_counter() - start < 30

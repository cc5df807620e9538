"""The animation of a run (urdf2links.view.animation, visuals, svgplot, thumbnail) and ``simulate --animate``.

Structural: the page holds the frames (at most 30 per simulated second), the links, every run's
poses (decoded and compared with the model's own link poses), the shapes the URDF describes, the
moving base; it references nothing on the network. In a real browser (the player running, the robot
drawn, play and the slider): tests/test_browser.py. Real meshes: example-robot-data (test extra).
"""

from __future__ import annotations

import re
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

import corpus
from pages import assert_offline, poses_4x4
from urdf2links import load_urdf, urdf_link_poses
from urdf2links.view.animation import (
    DEFAULT_FPS, Motion, Panel, frame_indices, read_animation_data, render_animation, trajectory_page, viewer_script,
)
from urdf2links.parsers.urdf import parse_urdf
from urdf2links.scenes.scene_read import load_scene
from urdf2links.integration.simulate import simulate
from urdf2links.view.thumbnail import render_thumbnail
from urdf2links.view.visuals import decimate, robot_shapes, tessellate

ROOT = Path(__file__).resolve().parent.parent
ROBOTS = ROOT / "robots"


@pytest.fixture(scope="module")
def pendulum_run():
    scene = load_scene(ROBOTS / "double_pendulum_chaos.toml")
    model = scene.model()
    return scene, model, simulate(scene, model=model, t_end=2.0, progress=False)


@pytest.fixture(scope="module")
def crane_run():
    scene = load_scene(ROBOTS / "ship_crane.toml")
    model = scene.model()
    return scene, model, simulate(scene, model=model, t_end=3.0, progress=False)


# --------------------------------------------------------------------------- frames


def test_frame_indices_keep_at_most_fps_per_second_and_the_last_sample():
    t = np.linspace(0.0, 10.0, 1001)  # 100 samples per second
    idx = frame_indices(t, 30.0)
    assert idx[0] == 0 and idx[-1] == 1000
    assert np.all(np.diff(t[idx])[:-1] >= 1 / 30 - 1e-12)  # every step but the last one to t_end
    assert len(idx) <= 30 * 10 + 2
    coarse = np.linspace(0.0, 1.0, 11)  # 10 per second: all kept
    assert np.array_equal(frame_indices(coarse, 30.0), np.arange(11))
    assert len(frame_indices(t, 5.0)) <= 5 * 10 + 2
    with pytest.raises(ValueError, match="fps"):
        frame_indices(t, 0.0)


# --------------------------------------------------------------------------- shapes


def test_shipped_crane_shows_its_collision_solids_and_frames():
    desc = parse_urdf(ROBOTS / "deck_crane.urdf")
    shapes = robot_shapes(desc)
    kinds = {(s.link, s.kind) for s in shapes.shapes}
    # the file has no <visual>: its <collision> solids are shown, the links with none are axes
    assert kinds == {("world", "frame"), ("pedestal", "cylinder"), ("column", "box"), ("boom", "box"),
                     ("sway_gimbal", "frame"), ("load", "cylinder"), ("load", "sphere"), ("load", "box")}
    assert {s.source for s in shapes.shapes} == {"collision", "frame"}
    box = next(s for s in shapes.shapes if s.link == "load" and s.kind == "box")
    assert np.allclose(box.size, [1.0, 1.0, 0.8]) and np.allclose(box.origin[:3, 3], [0, 0, -4.8])
    v, f = tessellate(box)  # 12 triangles of the crate, 4.4..5.2 m below the sheave
    assert len(f) == 12 and np.isclose(v[:, 2].min(), -5.2) and np.isclose(v[:, 2].max(), -4.4)


def test_vertex_clustering_reaches_the_budget_where_quadric_decimation_stalls():
    rng = np.random.default_rng(0)
    # a soup of 3000 separate triangles: no edge to collapse
    centres = rng.uniform(-1, 1, (3000, 3))
    v = (centres[:, None, :] + 0.01 * rng.standard_normal((3000, 3, 3))).reshape(-1, 3)
    f = np.arange(len(v)).reshape(-1, 3)
    vv, ff = decimate(v, f, 500)
    assert 0 < len(ff) <= 500
    assert ff.max() < len(vv) and np.all(np.abs(vv) <= 1.1)  # the cloud keeps its place and size


@corpus.needs_corpus
def test_ur5_meshes_are_read_coloured_and_decimated_to_the_budget():
    desc = parse_urdf(corpus.path(corpus.NAMED["ur5"]))
    shapes = robot_shapes(desc, max_faces=20_000)
    meshes = [s for s in shapes.shapes if s.kind == "mesh"]
    assert {s.link for s in meshes} >= {"base_link", "shoulder_link", "upper_arm_link", "forearm_link",
                                         "wrist_1_link", "wrist_2_link", "wrist_3_link"}
    assert shapes.faces_read > 90_000  # the DAE files as shipped
    # the budget holds to the slack of the decimator (it stops a little above its target)
    assert shapes.faces <= 1.05 * 20_000
    assert all(s.color is not None for s in meshes)  # the DAE materials' colours
    full = robot_shapes(desc, max_faces=10**7)
    for a, b in zip(full.shapes, shapes.shapes):  # decimation keeps each part's size and place
        if a.kind == "mesh":
            assert np.allclose(a.vertices.min(axis=0), b.vertices.min(axis=0), atol=0.01)
            assert np.allclose(a.vertices.max(axis=0), b.vertices.max(axis=0), atol=0.01)


# --------------------------------------------------------------------------- the page


def test_trajectory_page_holds_frames_links_and_poses(pendulum_run):
    scene, model, traj = pendulum_run
    page, anim = trajectory_page(traj, model)
    data = read_animation_data(page)
    assert_offline(page)
    assert "MeshCat.Viewer" in page and "u2l-motion" in page and viewer_script()[:200] in page
    t = np.array(data["t"])
    assert t[0] == 0.0 and t[-1] == pytest.approx(2.0) and len(t) <= DEFAULT_FPS * 2.0 + 2
    assert data["links"] == ["world", "upper", "lower"] and list(anim.links) == data["links"]
    (run,) = data["runs"]
    assert run["name"] == "urdf2links" and not run["ghost"]
    # decoded poses are the model's link poses at the frames' q (float32: 1e-6)
    k = np.searchsorted(traj.t, t)
    for i in (0, len(t) // 2, len(t) - 1):
        want = urdf_link_poses(model, traj.q[k[i]])
        got = poses_4x4(run["poses"][i])
        for link, P in zip(data["links"], got):
            assert np.allclose(P, want[link], atol=2e-6)
    assert [s["kind"] for s in data["shapes"]] == ["frame", "box", "box"]
    assert data["base"] is None
    assert "coordinates q" in page and "energy balance" in page and "u2l-cursor" in page


def test_ghost_run_is_a_second_trajectory_drawn_translucent(pendulum_run):
    scene, model, traj = pendulum_run
    q2 = traj.q + 0.1
    anim = render_animation(model, [Motion("urdf2links", traj.t, traj.q), Motion("MuJoCo", traj.t, q2, ghost=True)],
                            panels=[Panel("difference", traj.t, {"max |dq|": np.full(len(traj.t), 0.1)}, log=True)])
    data = read_animation_data(anim.html)
    assert [r["name"] for r in data["runs"]] == ["urdf2links", "MuJoCo"]
    assert [r["ghost"] for r in data["runs"]] == [False, True]
    a, b = (r["poses"] for r in data["runs"])
    assert np.allclose(a[0, 0], b[0, 0]) and not np.allclose(a[:, 2], b[:, 2])  # world still, lower link apart
    assert data["readout"][0]["label"] == "max |dq|" and np.allclose(data["readout"][0]["values"], 0.1)
    with pytest.raises(ValueError, match="times differ"):
        render_animation(model, [Motion("a", traj.t, traj.q), Motion("b", traj.t[:-1], traj.q[:-1])])


def test_moving_base_moves(crane_run):
    scene, model, traj = crane_run
    page, _ = trajectory_page(traj, model, base=scene.base_state)
    data = read_animation_data(page)
    t = np.array(data["t"])
    B = data["base"]["poses"]
    # the scene: heave z = 1.0 sin(2 pi 0.08 t), roll phi_x = 0.1 sin(2 pi 0.1 t) (float32: 1e-6)
    assert np.allclose(B[:, 2], np.sin(2 * np.pi * 0.08 * t), atol=1e-6)
    R = poses_4x4(B)[:, :3, :3]  # R = Rx(roll) Ry(pitch): -R[1, 2] / R[2, 2] = tan(roll)
    roll = np.arctan2(-R[:, 1, 2], R[:, 2, 2])
    assert np.allclose(roll, 0.1 * np.sin(2 * np.pi * 0.1 * t), atol=1e-5)
    (run,) = data["runs"]
    pedestal = run["poses"][:, data["links"].index("pedestal")]
    assert np.allclose(pedestal[:, :3], B[:, :3], atol=1e-6)  # bolted to the deck
    assert data["base"]["plate"][0] > 8.0  # the deck spans the 8 m boom


def test_svg_panels_are_drawn_without_scripts():
    from urdf2links.view.svgplot import panel_svg

    t = np.linspace(0, 5, 5001)
    svg = panel_svg(Panel("error", t, {"e": np.r_[0.0, 1e-12 * np.exp(t[1:])]}, log=True,
                          lines={"threshold 1e-3": 1e-3}))
    assert svg.startswith("<svg") and svg.count("<polyline") == 1 and "u2l-cursor" in svg
    pts = re.search(r"points='([^']*)'", svg).group(1).split()
    assert len(pts) <= 810  # long series reduced to a min/max envelope
    assert "1e-3" in svg and "threshold 1e-3" in svg
    assert "data-t0='0.0'" in svg and "data-t1='5.0'" in svg


def test_simulate_cli_writes_the_animation(tmp_path):
    out = subprocess.run([sys.executable, "-m", "urdf2links.cli", "simulate", str(ROBOTS / "ship_crane.toml"),
                          "--t-end", "1", "--animate", "--animation-fps", "10", "--quiet", "--out", str(tmp_path)],
                         capture_output=True, text=True, cwd=ROOT)
    assert out.returncode == 0, out.stderr
    page = (tmp_path / "ship_crane.html").read_text()
    data = read_animation_data(page)
    assert len(data["t"]) == 11 and data["base"] is not None  # 10 per second over 1 s, the deck moving
    assert "animation" in out.stdout and "ship_crane.html" in out.stdout


def test_simulate_a_robot_without_scene_writes_the_animation(tmp_path):
    out = subprocess.run([sys.executable, "-m", "urdf2links.cli", "simulate", str(ROBOTS / "pendulum.urdf"),
                          "--t-end", "0.5", "--animate", "--quiet", "--out", str(tmp_path)],
                         capture_output=True, text=True, cwd=ROOT)
    assert out.returncode == 0, out.stderr
    pages = list(tmp_path.glob("*.html"))
    assert len(pages) == 1 and pages[0].name.startswith("pendulum")
    data = read_animation_data(pages[0].read_text())
    assert {s["source"] for s in data["shapes"]} >= {"visual"}  # pendulum.urdf has a <visual>
    assert data["t"][-1] == pytest.approx(0.5)


# --------------------------------------------------------------------------- thumbnails


def png_pixels(png: bytes) -> np.ndarray:
    import io

    from matplotlib.image import imread

    return imread(io.BytesIO(png), format="png")


def test_thumbnail_is_a_picture_of_the_pose():
    model = load_urdf(ROBOTS / "double_pendulum.urdf")
    a = render_thumbnail(model, size=(200, 150))
    b = render_thumbnail(model, [1.2, -0.8], size=(200, 150))
    assert a[:8] == b"\x89PNG\r\n\x1a\n"
    pa, pb = png_pixels(a), png_pixels(b)
    assert pa.shape[:2] == (150, 200)
    ink = (pa[..., :3] < 0.9).any(axis=-1).mean()
    assert 0.005 < ink < 0.5  # the robot is drawn, on a white background
    assert np.abs(pa - pb).max() > 0.5  # another pose, another picture


@corpus.needs_corpus
def test_thumbnail_of_a_meshed_robot(tmp_path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = load_urdf(corpus.path(corpus.NAMED["ur5"]), inertia="repair")
    png = render_thumbnail(model, path=tmp_path / "ur5.png")
    assert (tmp_path / "ur5.png").read_bytes() == png
    px = png_pixels(png)
    assert 0.01 < (px[..., :3] < 0.9).any(axis=-1).mean() < 0.6

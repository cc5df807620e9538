"""The motion of a robot as a self-contained, offline HTML animation.

:func:`render_animation` takes a model, one or more runs (:class:`Motion`: times and ``q`` in the
model's coordinates; a run marked ``ghost`` is drawn translucent) and side panels
(:class:`~urdf2links.view.svgplot.Panel`) and returns an HTML fragment: the robot's shapes
(:mod:`urdf2links.view.visuals`), the link poses of every frame, a viewer, play/pause, a time slider,
a speed choice, a toggle per extra run and the panels with a cursor at the shown time. The
scene report (``urdf2links.compare.reports.motion``) animates urdf2links and MuJoCo in it;
:func:`trajectory_page` and :func:`write_trajectory_page` make a whole page of one
:class:`~urdf2links.integration.simulate.Trajectory` (``urdf2links simulate --animate``).

The viewer is meshcat's (``MeshCat.Viewer``, three.js r132), whose bundle ships in the ``meshcat``
Python package (``meshcat/viewer/dist/main.min.js``, ~0.85 MB); it is inlined in the page with the
player (``urdf2links/view/web/player.js``), so the page works from a file with no network and no
server. The meshcat Python package itself is not imported (it would start a zmq server).

Frames: the runs' own samples, every k-th so that there are at most ``fps`` frames per second of
simulated time (the player interpolates between them: positions linearly, rotations by normalized
quaternions). Poses: :meth:`~urdf2links.dynamics.model.Model.link_poses` at each frame's ``q``, ``t`` and
``base`` times each URDF link's placement (``model.info["frame_of"]``), sent as position and
quaternion (float32). A moving base also draws {A} (its axes and a translucent deck).
"""

from __future__ import annotations

import base64
import functools
import html
import json
from dataclasses import dataclass, field
from importlib import resources
from importlib.metadata import PackageNotFoundError, distribution
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from ..dynamics.transforms import base_state_at, link_transform
from .svgplot import Panel, panel_svg
from .visuals import RobotShapes, model_shapes

__all__ = ["Motion", "Animation", "Panel", "render_animation", "animation_page", "trajectory_page",
           "write_trajectory_page", "read_animation_data", "frame_indices", "link_poses_over", "viewer_script",
           "DEFAULT_FPS"]

#: Default frames per second of simulated time.
DEFAULT_FPS = 30.0
_FOV_DEG = 75.0  # meshcat's default camera
_DATA_TAG = "<script type='application/json' class='u2l-data'>"


@dataclass(frozen=True)
class Motion:
    """One run to animate: ``t`` (m,) and ``q`` (m, n) in the model's coordinates; ``ghost`` draws
    it translucent (the reference an eye compares against); ``label`` says what it is. ``model``: the
    run's own robot when it is not the animation's (another description of it: both robots drawn,
    each run with its own model's shapes, ``shapes`` or :func:`~urdf2links.view.visuals.model_shapes`)."""

    name: str
    t: np.ndarray
    q: np.ndarray
    ghost: bool = False
    label: str = ""
    model: object = None
    shapes: RobotShapes | None = None


@dataclass(frozen=True, eq=False)
class Animation:
    """The fragment (``html``) and what it holds: ``frames`` (times), ``links``, ``runs`` (names),
    ``data_bytes`` (the embedded JSON), ``notes`` (from the shapes)."""

    html: str
    frames: np.ndarray
    links: tuple[str, ...]
    runs: tuple[str, ...]
    fps: float
    data_bytes: int
    notes: tuple[str, ...] = field(default_factory=tuple)


@functools.lru_cache(maxsize=1)
def viewer_script() -> str:
    """meshcat's viewer bundle (``MeshCat.Viewer``, ``MeshCat.THREE``) from the installed ``meshcat``
    package, without importing it."""
    try:
        path = Path(distribution("meshcat").locate_file("meshcat/viewer/dist/main.min.js"))
    except PackageNotFoundError as exc:
        raise RuntimeError("the animation needs the meshcat package (its viewer script): pip install meshcat "
                           "(a dependency of urdf2links)") from exc
    if not path.is_file():
        raise RuntimeError(f"the meshcat package has no viewer script at {path}; reinstall it: pip install "
                           "--force-reinstall meshcat")
    text = path.read_text(encoding="utf-8")
    # inlined in <script>: nothing in it may close the element or open an HTML comment
    return text.replace("</script", "<\\/script").replace("<!--", "<\\!--")


@functools.lru_cache(maxsize=2)
def _asset(name: str) -> str:
    return (resources.files("urdf2links.view") / "web" / name).read_text(encoding="utf-8")


def frame_indices(t, fps: float = DEFAULT_FPS) -> np.ndarray:
    """Indices of the samples ``t`` (m,) shown as frames: every k-th, k the smallest step that keeps
    at most ``fps`` frames per second of simulated time, and always the last sample."""
    t = np.asarray(t, float)
    if fps <= 0:
        raise ValueError(f"fps must be positive (frames per second of simulated time), got {fps!r}")
    if t.size < 2:
        return np.arange(t.size)
    dt = float(np.median(np.diff(t)))
    step = max(1, int(np.ceil((1.0 / fps) / dt - 1e-9))) if dt > 0 else 1
    idx = np.arange(0, t.size, step)
    return idx if idx[-1] == t.size - 1 else np.r_[idx, t.size - 1]


def _placements(model, links) -> tuple[np.ndarray, np.ndarray]:
    """Tree-link index (L,) and constant placement X (L, 4, 4) of each URDF link (identity for a tree link)."""
    frame_of = model.info.get("frame_of") or {}
    names = list(model.link_names)
    idx, X = [], []
    for link in links:
        tname, x = frame_of.get(link, (link, None))
        idx.append(names.index(tname))
        X.append(np.eye(4) if x is None else np.asarray(x, float))
    return np.array(idx), np.array(X)


def _link_masses(model, links) -> np.ndarray:
    """Mass (L,) of each link's tree link (links folded into one share its mass), plus a small floor
    so that massless links count a little."""
    idx, _ = _placements(model, links)
    m = np.asarray(model.tree.H[:, 3, 3], float)[idx]
    return m + 1e-6 * max(float(m.sum()), 1e-9) + 1e-12


def link_poses_over(model, links, t, q, base=None) -> np.ndarray:
    """{0}-poses (F, L, 4, 4) of ``links`` (URDF links or tree links) at times ``t`` (F,) and ``q`` (F, n)."""
    idx, X = _placements(model, links)
    out = np.empty((len(t), len(links), 4, 4))
    for k, (tk, qk) in enumerate(zip(t, q)):
        out[k] = model.link_poses(qk, t=float(tk), base=base)[idx] @ X
    return out


def _pose7(P: np.ndarray) -> np.ndarray:
    """(..., 4, 4) -> (..., 7): position and quaternion (x, y, z, w), float32."""
    flat = P.reshape(-1, 4, 4)
    quat = Rotation.from_matrix(flat[:, :3, :3]).as_quat()
    return np.concatenate([flat[:, :3, 3], quat], axis=1).reshape(*P.shape[:-2], 7).astype(np.float32)


def _b64(a: np.ndarray, dtype) -> str:
    return base64.b64encode(np.ascontiguousarray(a, dtype=dtype).tobytes()).decode("ascii")


def _shape_data(s, li: int) -> dict:
    d = {"link": li, "kind": s.kind, "source": s.source, "origin": [round(float(v), 7) for v in s.origin.T.ravel()],
         "color": None if s.color is None else [round(c, 4) for c in s.color]}
    if s.kind == "box":
        d["size"] = [float(v) for v in s.size]
    elif s.kind == "cylinder":
        d.update(radius=s.radius, length=s.length)
    elif s.kind == "sphere":
        d["radius"] = s.radius
    elif s.kind == "mesh":
        small = len(s.vertices) < 65536
        d.update(vertices=_b64(s.vertices, "<f4"), faces=_b64(s.faces, "<u2" if small else "<u4"),
                 index="u16" if small else "u32")
    return d


def _weighted_range(points: np.ndarray, weights: np.ndarray, tail: float) -> tuple[np.ndarray, np.ndarray]:
    """Per axis, the values below which ``tail`` and above which ``tail`` of the weight lies (3,), (3,)."""
    lo, hi = np.empty(3), np.empty(3)
    for k in range(3):
        order = np.argsort(points[:, k])
        c = np.cumsum(weights[order]) / np.sum(weights)
        lo[k] = points[order[min(np.searchsorted(c, tail), len(c) - 1)], k]
        hi[k] = points[order[min(np.searchsorted(c, 1.0 - tail), len(c) - 1)], k]
    return lo, hi


def _camera(points: np.ndarray, weights: np.ndarray, first: np.ndarray, reach: float) -> tuple[dict, float]:
    """Target (centre of the motion), offset (where the camera sits from it, world z up) and the
    motion's radius. The motion is where the mass goes: ``points`` (k, 3) weighted by their links'
    masses ``weights`` (k,), without the lightest 0.5 % at either end of each axis (a finger sliding
    out of an unlimited joint does not shrink the robot to a dot), and the whole first frame
    ``first`` (j, 3). Of the views from 20 degrees above, every 15 degrees around, the one in which
    the motion covers the largest area (a planar motion is seen square on; ties go to the front
    right), at the distance that fits the motion into the pane (vertical field of view 75 degrees,
    width 1.3 times the height, a margin of 15 %)."""
    lo, hi = _weighted_range(points, weights, 0.005)
    lo, hi = np.minimum(lo, first.min(axis=0)), np.maximum(hi, first.max(axis=0))
    centre = 0.5 * (lo + hi)
    p = np.clip(points, lo, hi) - centre
    radius = max(0.5 * float(np.linalg.norm(hi - lo)) + reach, 1e-3)
    el = np.radians(20.0)
    best = None
    for deg in np.arange(0.0, 360.0, 15.0):
        az = np.radians(deg)
        d = np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])  # towards the camera
        right = np.array([-np.sin(az), np.cos(az), 0.0])
        up = np.cross(d, right)
        uv = np.c_[p @ right, p @ up]
        area = float(np.linalg.det(np.cov(uv.T) + 1e-12 * np.eye(2))) if len(p) > 2 else 0.0
        front_right = np.cos(az - np.radians(-35.0))  # prefer looking from +x, -y
        score = area * (1.0 + 0.02 * front_right)
        if best is None or score > best[0] * (1.0 + 1e-9):
            best = (score, d, np.abs(uv).max(axis=0) + reach, float(np.max(p @ d, initial=0.0)))
    _, d, (u_ext, v_ext), near = best
    half = np.tan(np.radians(_FOV_DEG / 2))
    distance = near + 1.15 * max(v_ext / half, u_ext / (1.3 * half), 1e-3)
    return {"target": [float(v) for v in centre], "offset": [float(v) for v in distance * d]}, radius


def _base_data(base, t: np.ndarray, poses0: np.ndarray, frame_size: float) -> dict | None:
    """{A}'s poses (F, 7) and a deck under the robot (size and centre in {A}'s x-y plane)."""
    if base is None:
        return None
    B = np.array([link_transform(base_state_at(base, float(tk)).pose) for tk in t])
    pts = (np.linalg.inv(B[0]) @ np.c_[poses0[:, :3, 3], np.ones(len(poses0))].T).T[:, :3]
    lo, hi = pts[:, :2].min(axis=0), pts[:, :2].max(axis=0)
    size = np.maximum(1.3 * (hi - lo), 6 * frame_size)
    centre = 0.5 * (lo + hi)
    return {"poses": _b64(_pose7(B), "<f4"), "plate": [float(size[0]), float(size[1]), float(centre[0]),
                                                         float(centre[1])]}


def _motion_points(model, shapes: RobotShapes, poses: np.ndarray):
    """What the camera frames (:func:`_camera`'s arguments): link origins and shape centres over the
    frames (k, 3), their links' masses (k,), the first frame's points, the largest shape's reach."""
    index = {k: i for i, k in enumerate(shapes.links)}
    F = len(poses)
    centres = [poses[:, index[s.link]] @ (s.origin @ np.r_[s.centre(), 1.0]) for s in shapes.shapes]  # (F, 4)
    points = np.concatenate([poses[:, :, :3, 3].reshape(-1, 3)] + [c[:, :3] for c in centres])
    mass = _link_masses(model, shapes.links)
    weights = np.concatenate([np.tile(mass, F)] + [np.full(F, mass[index[s.link]]) for s in shapes.shapes])
    first = np.concatenate([poses[0, :, :3, 3]] + [c[:1, :3] for c in centres])
    return points, weights, first, max((s.extent() for s in shapes.shapes), default=0.0)


def _groups(model, shapes: RobotShapes, motions) -> list[tuple]:
    """``[(model, shapes, link prefix, run indices)]``: the animation's model first, then each other model
    a run brings (its links prefixed ``<k>:`` so that two descriptions' links never share a node)."""
    groups = [(model, shapes, "", [])]
    for k, m in enumerate(motions):
        if m.model is None or m.model is model:
            groups[0][3].append(k)
            continue
        for g in groups[1:]:
            if g[0] is m.model:
                g[3].append(k)
                break
        else:
            groups.append((m.model, m.shapes or model_shapes(m.model), f"{len(groups)}:", [k]))
    return groups


def _payload(model, shapes: RobotShapes, motions, panels, base, fps) -> tuple[dict, np.ndarray]:
    ref = motions[0]
    t_all = np.asarray(ref.t, float)
    for m in motions[1:]:
        if np.asarray(m.t).shape != t_all.shape or np.max(np.abs(np.asarray(m.t, float) - t_all), initial=0) > 1e-9:
            raise ValueError(f"motion {m.name!r}: its times differ from {ref.name!r}'s; give every run the same "
                             "sample times")
    idx = frame_indices(t_all, fps)
    t = t_all[idx]
    groups = _groups(model, shapes, motions)
    links, shape_rows, columns = [], [], []
    for gmodel, gshapes, prefix, runs in groups:
        first = len(links)
        links += [prefix + k for k in gshapes.links]
        columns.append(slice(first, len(links)))
        index = {k: first + i for i, k in enumerate(gshapes.links)}
        for s in gshapes.shapes:
            row = _shape_data(s, index[s.link])
            if len(groups) > 1:
                row["runs"] = list(runs)
            shape_rows.append(row)
    poses = []
    for k, m in enumerate(motions):
        P = np.tile(np.eye(4), (len(t), len(links), 1, 1))
        for (gmodel, gshapes, _prefix, runs), cols in zip(groups, columns):
            if k in runs:
                P[:, cols] = link_poses_over(gmodel, list(gshapes.links), t, np.asarray(m.q, float)[idx], base)
        poses.append(P)
    camera, radius = _camera(*_motion_points(model, shapes, poses[groups[0][3][0] if groups[0][3] else 0][:, columns[0]]))
    frame_size = 0.08 * radius
    readout = []
    for p in panels:
        if len(p.series) <= 2:
            readout += [{"label": label, "unit": p.unit if p.log else "", "log": p.log, "values": values}
                        for label, values in p.at(t).items()]
    data = {"version": 1, "t": [float(v) for v in t], "links": links, "frame_size": frame_size,
            "shapes": shape_rows,
            "runs": [{"name": m.name, "path": _run_path(k, m),
                      "label": m.label, "ghost": bool(m.ghost), "poses": _b64(_pose7(P), "<f4")}
                     for k, (m, P) in enumerate(zip(motions, poses))],
            "base": _base_data(base, t, poses[0][0][columns[0]], frame_size), "camera": camera, "readout": readout}
    return data, t


def _run_path(k: int, m: Motion) -> str:
    """The run's node in the viewer's scene tree (letters, digits and underscores)."""
    return f"run{k}_" + "".join(ch if ch.isalnum() else "_" for ch in m.name)


def _controls(motions) -> str:
    e = html.escape
    speeds = "".join(f"<option value='{v:g}'{' selected' if v == 1 else ''}>{v:g}&times;</option>"
                     for v in (0.1, 0.25, 0.5, 1.0, 2.0, 4.0))
    toggles = "".join(f"<label><input type='checkbox' class='u2l-run' value='{_run_path(k, m)}' checked> "
                      f"{e(m.name)}</label>" for k, m in enumerate(motions))
    return (f"<div class='u2l-controls'><button type='button' class='u2l-play'>Play</button>"
            f"<input type='range' class='u2l-slider' min='0' max='{float(motions[0].t[-1])!r}' step='any' value='0' "
            f"aria-label='time'><span class='u2l-time'>t = 0 s</span>"
            f"<label>speed <select class='u2l-speed'>{speeds}</select></label></div>"
            f"<div class='u2l-controls'><span class='u2l-readout'></span>"
            + (f"<span class='u2l-toggles'>show {toggles}</span>" if len(motions) > 1 else "") + "</div>")


def _legend(motions, shapes: RobotShapes, n_frames: int, fps: float, base) -> str:
    e = html.escape
    items = []
    for m in motions:
        swatch = "#ff7a00; opacity: 0.45" if m.ghost else "#8a95a8"
        items.append(f"<span class='u2l-swatch' style='background: {swatch}'></span><b>{e(m.name)}</b>"
                     + (" (translucent)" if m.ghost else "") + (f": {e(m.label)}" if m.label else ""))
    sources = sorted({s.source for s in shapes.shapes} | {s.source for m in motions if m.shapes for s in m.shapes.shapes})
    what = {"visual": "URDF &lt;visual&gt; geometry", "geom": "MJCF geoms (MuJoCo's compiled ones)", "collision": "&lt;collision&gt; geometry where a link has no "
            "&lt;visual&gt;", "frame": "axes (x red, y green, z blue) for links with no geometry"}
    text = "<br>".join(items) + "<br>Shown: " + "; ".join(what[s] for s in sources if s in what)
    if shapes.faces_read > shapes.faces:
        text += f"; meshes decimated from {shapes.faces_read} to {shapes.faces} triangles"
    if base is not None:
        text += "; the moving base {A}: its axes and a translucent deck"
    text += (f". {n_frames} frames, at most {fps:g} per simulated second, interpolated between. "
             "Drag to turn, scroll to zoom; <code>#t=1.5</code> after the page's address opens it at t = 1.5 s.")
    return f"<div class='u2l-legend'>{text}</div>"


def render_animation(model, motions, *, shapes: RobotShapes | None = None, panels=(), base=None,
                     fps: float = DEFAULT_FPS, package_dirs=(), dom_id: str = "u2l-motion") -> Animation:
    """The animation of ``motions`` (a list of :class:`Motion`, the same sample times) of ``model`` as
    an HTML fragment (module doc). ``shapes`` defaults to :func:`~urdf2links.view.visuals.model_shapes`
    (the model's URDF file; ``package_dirs`` for its meshes); ``base`` is the moving base as
    :meth:`~urdf2links.dynamics.model.Model.link_poses` takes it (None, a BaseState, a callable ``t ->
    BaseState``; a callable that says None, like a fixed-base scene's ``base_state``, is a fixed base);
    ``panels`` are plotted beside the viewer."""
    motions = list(motions)
    if not motions:
        raise ValueError("render_animation needs at least one Motion")
    if callable(base) and base(float(np.asarray(motions[0].t, float)[0])) is None:
        base = None          # a scene's base_state of a fixed base (it says None): nothing moves {A}
    base_state_at(base, 0.0)         # refuse anything else here, naming what it got
    shapes = shapes or model_shapes(model, package_dirs=package_dirs)
    data, t = _payload(model, shapes, motions, panels, base, fps)
    text = json.dumps(data, separators=(",", ":")).replace("</", "<\\/")
    e = html.escape
    side = "".join(panel_svg(p) for p in panels)
    fragment = (f"<style>{_asset('player.css')}</style>"
                f"<div class='u2l-motion' id='{e(dom_id)}'>"
                f"<div class='u2l-stage'><div class='u2l-viewer'></div>"
                f"<div class='u2l-status'>Loading the 3D view&hellip;</div>{_controls(motions)}"
                f"{_legend(motions, shapes, len(t), fps, base)}</div>"
                f"<div class='u2l-side'>{side}</div>"
                f"{_DATA_TAG}{text}</script></div>"
                f"<!-- 3D viewer: meshcat (MIT) with three.js r132 (MIT), from the meshcat Python package -->"
                f"<script>{viewer_script()}</script><script>{_asset('player.js')}</script>")
    return Animation(html=fragment, frames=t, links=tuple(shapes.links), runs=tuple(m.name for m in motions),
                     fps=float(fps), data_bytes=len(text), notes=tuple(shapes.notes))


def read_animation_data(page: str) -> dict:
    """The data an animation page embeds (frames, links, shapes, runs, base, camera, readout), with
    each run's ``poses`` and the base's decoded to float arrays (F, L, 7) and (F, 7): position and
    quaternion (x, y, z, w). ValueError when the page holds no animation."""
    start = page.find(_DATA_TAG)
    if start < 0:
        raise ValueError("the page holds no animation data (no <script class='u2l-data'>)")
    start += len(_DATA_TAG)
    data = json.loads(page[start:page.index("</script>", start)])
    F, L = len(data["t"]), len(data["links"])
    for run in data["runs"]:
        run["poses"] = np.frombuffer(base64.b64decode(run["poses"]), "<f4").reshape(F, L, 7)
    if data["base"]:
        data["base"]["poses"] = np.frombuffer(base64.b64decode(data["base"]["poses"]), "<f4").reshape(F, 7)
    return data


def animation_page(animation: Animation, *, title: str, intro: str = "") -> str:
    """A whole page around an animation fragment."""
    e = html.escape
    return ("<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>"
            f"<title>{e(title)}</title><style>body {{ font-family: -apple-system, 'Segoe UI', Helvetica, Arial, "
            "sans-serif; margin: 0 auto; max-width: 1180px; padding: 12px 20px 30px; color: #1d2330; }"
            " h1 { font-size: 1.4em; } .sub { color: #5a6272; }</style></head><body>"
            f"<h1>{e(title)}</h1>" + (f"<p class='sub'>{intro}</p>" if intro else "")
            + animation.html + "</body></html>")


def trajectory_page(traj, model, *, base=None, shapes: RobotShapes | None = None, package_dirs=(),
                    fps: float = DEFAULT_FPS, title: str | None = None) -> tuple[str, Animation]:
    """A page animating one :class:`~urdf2links.integration.simulate.Trajectory` of ``model`` (its coordinates and
    its energy balance plotted beside it): ``(html, animation)``."""
    s = traj.stats
    label = f"{s.get('method', '')}" + (f", rtol {s['rtol']:g}" if s.get("rtol") and s.get("method") not in
                                        ("RK4", "midpoint") else (f", dt {s['dt']:g} s" if s.get("dt") else ""))
    names = list(traj.coordinate_names)
    panels = [Panel("coordinates q", traj.t, {c: traj.q[:, i] for i, c in enumerate(names)},
                    unit="rad, m", legend=len(names) <= 8),
              Panel("energy balance |h - h(0) - W|", traj.t, {"|h - h(0) - W|": np.abs(traj.energy["error"])},
                    log=True, unit="J")]
    anim = render_animation(model, [Motion("urdf2links", traj.t, traj.q, label=label)], shapes=shapes,
                            panels=panels, base=base, fps=fps, package_dirs=package_dirs)
    title = title or f"{traj.scene or model.name}: urdf2links"
    intro = html.escape(f"{model.name}, {model.n} coordinates, t = 0..{traj.t[-1]:g} s, {label}")
    return animation_page(anim, title=title, intro=intro), anim


def write_trajectory_page(path, traj, model, **options) -> Path:
    """Write :func:`trajectory_page` to ``path`` (keyword arguments as there); returns the path."""
    page, _ = trajectory_page(traj, model, **options)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(page, encoding="utf-8")
    return path

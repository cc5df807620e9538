"""A still picture of a robot in one pose, drawn without a GPU or a display (matplotlib's Agg
canvas, 3D axes): the thumbnail of a robot in a corpus report.

The shapes are those of the animation (:mod:`urdf2links.view.visuals`: URDF visuals, collision shapes
where a link has none, axes where it has neither), meshes decimated harder (``max_faces``,
default 4000: matplotlib sorts and fills every triangle in Python), each triangle shaded by a
fixed light (Lambert, plus an ambient part). Links are placed by
:func:`urdf2links.view.animation.link_poses_over` at ``q`` (default the zero configuration).
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from .animation import link_poses_over
from .visuals import RobotShapes, model_shapes, tessellate

__all__ = ["render_thumbnail", "THUMBNAIL_MAX_FACES"]

#: Triangle budget of a thumbnail's meshes.
THUMBNAIL_MAX_FACES = 4000
_LIGHT = np.array([0.45, -0.35, 0.82]) / np.linalg.norm([0.45, -0.35, 0.82])
_DEFAULT = {"visual": (0.70, 0.73, 0.77), "collision": (0.44, 0.56, 0.72)}


def _triangles(shapes: RobotShapes, poses: np.ndarray) -> tuple[np.ndarray, np.ndarray, list]:
    """World triangles (T, 3, 3), their shaded colours (T, 3) and the frames' poses (links with no shape)."""
    index = {k: i for i, k in enumerate(shapes.links)}
    tris, cols, frames = [], [], []
    for s in shapes.shapes:
        P = poses[index[s.link]]
        if s.kind == "frame":
            frames.append(P)
            continue
        v, f = tessellate(s)
        if not len(f):
            continue
        w = v @ P[:3, :3].T + P[:3, 3]
        t = w[f]
        n = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
        n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
        shade = 0.35 + 0.65 * np.abs(n @ _LIGHT)  # two-sided: mesh windings are not to be trusted
        base = np.array(s.color if s.color is not None else _DEFAULT.get(s.source, _DEFAULT["visual"]))
        tris.append(t)
        cols.append(np.clip(shade[:, None] * np.maximum(base, 0.12), 0.0, 1.0))
    if not tris:
        return np.zeros((0, 3, 3)), np.zeros((0, 3)), frames
    return np.concatenate(tris), np.concatenate(cols), frames


def render_thumbnail(model, q=None, *, shapes: RobotShapes | None = None, base=None, t: float = 0.0,
                     package_dirs=(), size=(320, 240), max_faces: int = THUMBNAIL_MAX_FACES,
                     elev: float = 20.0, azim: float = -55.0, path=None) -> bytes:
    """PNG bytes of ``model`` at ``q`` (default zeros), ``size`` pixels (width, height); also written to
    ``path`` when given. ``shapes`` default to :func:`~urdf2links.view.visuals.model_shapes` with
    ``max_faces``; ``base``/``t`` place a moving base; ``elev``/``azim`` the view (degrees)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from mpl_toolkits.mplot3d.art3d import Line3DCollection, Poly3DCollection

    q = np.zeros(model.n) if q is None else model.vector(q, "q")
    shapes = shapes or model_shapes(model, package_dirs=package_dirs, max_faces=max_faces)
    poses = link_poses_over(model, shapes.links, [t], q[None, :], base)[0]
    tris, cols, frames = _triangles(shapes, poses)
    pts = np.concatenate([tris.reshape(-1, 3), poses[:, :3, 3]])
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    half = max(0.5 * float(np.max(hi - lo)), 1e-3)
    span = np.maximum(hi - lo, 0.05 * half)  # equal scale on the three axes, each as long as the robot
    lo, hi = 0.5 * (lo + hi) - 0.5 * span, 0.5 * (lo + hi) + 0.5 * span

    fig = Figure(figsize=(size[0] / 100, size[1] / 100), dpi=100)
    FigureCanvasAgg(fig)
    ax = fig.add_axes((0, 0, 1, 1), projection="3d")
    if len(tris):
        ax.add_collection3d(Poly3DCollection(tris, facecolors=cols, edgecolors="none", linewidths=0))
    a = 0.12 * half
    for P in frames:
        o = P[:3, 3]
        segs = [[o, o + a * P[:3, k]] for k in range(3)]
        ax.add_collection3d(Line3DCollection(segs, colors=["#d62728", "#2ca02c", "#1f77b4"], linewidths=1.2))
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_zlim(lo[2], hi[2])
    ax.set_box_aspect(tuple(span), zoom=0.95)
    ax.view_init(elev=elev, azim=azim)
    ax.set_axis_off()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100)
    png = buf.getvalue()
    if path is not None:
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        Path(path).write_bytes(png)
    return png

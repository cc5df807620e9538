"""The motion section of a scene report: the robot moving as urdf2links ran it, MuJoCo's run as a
translucent ghost over it, and their difference plotted beside the viewer.

Both runs are drawn from their ``q`` at MuJoCo's sample times (:class:`SceneComparison` ``t``,
``q_ours``, ``q_mujoco``: the same coordinates, also for a re-charted run, whose ``q`` are in the
loaded model's coordinates) through the same model's link poses, with the scene's prescribed base
motion for both (MuJoCo's base follows it to ~1e-12, ``base.tracking_error``). The page is
:func:`urdf2links.view.animation.render_animation`'s (module doc there: viewer, frames, budget).
"""

from __future__ import annotations

import html

from urdf2links.view.animation import DEFAULT_FPS, Motion, Panel, render_animation
from urdf2links.view.visuals import scene_shapes

__all__ = ["motion_section", "comparison_animation"]


def comparison_animation(c, *, fps: float = DEFAULT_FPS):
    """The :class:`~urdf2links.view.animation.Animation` of comparison ``c`` (both engines, the difference)."""
    scene, model = c.scene, c.model
    stats, run = c.traj.stats, c.run
    label = stats["method"] + (f", dt {stats['dt']:g} s" if stats["method"] in ("RK4", "midpoint")
                               else f", rtol {stats['rtol']:g}")
    motions = [Motion("urdf2links", c.t, c.q_ours, label=label),
               Motion("MuJoCo", c.t, c.q_mujoco, ghost=True,
                      label=f"{run.integrator}, dt {run.timestep:g} s ({c.summary_route()}), at the same times")]
    err_max = c.error.max(axis=1) if c.error.size else c.t * 0.0
    names = c.coordinate_names
    panels = [Panel("|q urdf2links - q MuJoCo|, largest coordinate", c.t, {"max |dq|": err_max},
                    log=True, unit="rad or m", lines={f"divergence threshold {c.threshold:g}": c.threshold}),
              Panel("|q urdf2links - q MuJoCo| per coordinate", c.t, {nm: c.error[:, i] for i, nm in enumerate(names)}, log=True,
                    unit="rad or m", legend=len(names) <= 8)]
    shapes = scene_shapes(scene, model)
    base = scene.base_state if scene.base is not None else None
    return render_animation(model, motions, shapes=shapes, panels=panels, base=base, fps=fps)


def motion_section(c, *, fps: float = DEFAULT_FPS) -> list[str]:
    """The report's "Motion" section (HTML parts) for comparison ``c``; nothing when ``fps`` is 0."""
    if not fps:
        return []
    anim = comparison_animation(c, fps=fps)
    notes = "".join(f"<li>{html.escape(n)}</li>" for n in anim.notes)
    return ["<h2>Motion</h2>",
            "<p>The robot as urdf2links integrated it (solid) and as MuJoCo did (translucent orange), from the same "
            "initial state, drawn at the same times; the plots beside it are the engines' difference, with a cursor "
            "at the time shown. Where the difference is far below a millimetre or a milliradian the ghost sits "
            "exactly on the robot.</p>",
            anim.html] + ([f"<details><summary class='small'>geometry notes</summary><ul class='notes'>{notes}</ul>"
                           "</details>"] if notes else [])

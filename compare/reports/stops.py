"""Hard cases that stop by design in ``urdf2links report``: the scene's ``[expect]``
(:mod:`urdf2links.scenes.expect`) against what its run did, and the index's section that lists them.

A scene whose run stops with the error its ``[expect]`` names (class and words of the message) is listed as
stopping by design, with the error's message; it is not a failure. A stop with another error is a failure as
for any scene, and so is a run that reaches the scene's own ``t_end`` without the stop (the harness no longer
catches what the case is there to show). A run shortened by ``--t-end`` or ``--cap`` may end before the stop:
it is reported, not failed.
"""

from __future__ import annotations

import html

from urdf2links.console import shown_path

__all__ = ["Stopped", "expected_stop", "missed_stop", "stops_html", "stops_md"]


class Stopped(dict):
    """One scene that stopped by design: ``robot``, ``scene``, ``file``, ``error`` (class name), ``message``,
    ``expected`` (the ``[expect]`` in words), ``t_end`` (what the run was asked for)."""


def expected_stop(scene, robot: str, exc: BaseException, *, t_end: float) -> Stopped | None:
    """The index's entry when ``exc`` is the stop ``scene``'s ``[expect]`` names; None otherwise (a failure)."""
    stop = getattr(scene, "expected_stop", None)
    if stop is None or not stop.matches(exc):
        return None
    file = shown_path(scene.path) if scene.path else scene.name
    message = str(exc).replace(str(scene.path), file) if scene.path else str(exc)   # the path as the user gave it
    return Stopped(robot=robot, scene=scene.name, file=file, error=type(exc).__name__, message=message,
                   expected=stop.text(), t_end=float(t_end))


def missed_stop(scene, *, t_end: float) -> str | None:
    """A failure's text when ``scene`` expects a stop and its run reached its own ``t_end`` (``t_end``: the
    run's); None when nothing was expected, or the run was shortened (``--t-end``, ``--cap``)."""
    stop = getattr(scene, "expected_stop", None)
    if stop is None or t_end < scene.run.t_end:
        return None
    where = shown_path(scene.path) if scene.path else scene.name
    return (f"{where}: its [expect] says the run {stop.text()}, and it ran to t_end = {t_end:g} s without stopping: "
            "the hard case is no longer caught (or the scene changed: correct its [expect])")


def stops_md(stopped: list) -> list[str]:
    """The index.md section of the scenes that stopped by design (empty without any)."""
    if not stopped:
        return []
    out = ["", "## Hard cases that stop by design", "",
           "Each scene's `[expect]` names the error its run stops with; it stopped with that error (not a failure).",
           "", "| robot | scene | t_end asked | stopped with | message |", "|---|---|---|---|---|"]
    for s in stopped:
        out.append(f"| {s['robot']} | {s['scene']} ({s['file']}) | {s['t_end']:g} s | {s['error']} | "
                   + s["message"].replace("|", "\\|").replace("\n", " ") + " |")
    return out


def stops_html(stopped: list) -> str:
    """The index.html section of the scenes that stopped by design (empty without any)."""
    if not stopped:
        return ""
    e = html.escape
    rows = "".join(f"<tr><td>{e(s['scene'])}<br><span class='small'>{e(s['robot'])}</span></td>"
                   f"<td>{s['t_end']:g} s</td><td>{e(s['error'])}</td><td class='small'>{e(s['message'])}</td></tr>"
                   for s in stopped)
    return ("<h2>Hard cases that stop by design</h2><p class='small'>Each scene's <code>[expect]</code> names the "
            "error its run stops with (urdf2links.scenes.expect); it stopped with that error, which is not a failure."
            "</p><table><tr><th>scene<br><span class='small'>robot</span></th><th>t<sub>end</sub> asked</th>"
            f"<th>stopped with</th><th>message</th></tr>{rows}</table>")

"""``identify --design OUT.toml``: an excitation trajectory that lowers the condition number of the base regressor,
written as a scene both engines run (docs/identify.md, "The command").

The trajectory is a periodic Fourier series per coordinate (:class:`.excitation.FourierTrajectory`) within the
joint limits and velocity limits (:func:`.excitation.fit_within`) and, where the file states one, within
``SAFETY`` of the joint's effort limit (the description's inverse dynamics along it, checked on one period). The search: ``candidates`` seeded random series, the best kept, then ``rounds`` of seeded
perturbations of its coefficients, each kept when it lowers the condition number of the column-scaled base
regressor (:func:`urdf2links.identification.base.base_parameters`, on ``samples`` points of one period). A
derivative-free search in ~10 n dimensions: it lowers the condition number, it does not prove a minimum.

The scene: the description, gravity, and per coordinate a ``[[computed_torque]]`` whose reference is the series
as ``sines`` (``a sin x + b cos x = A sin(x + phi)``, ``A = hypot(a, b)``, ``phi = atan2(b, a)``, frequency
``k w / 2 pi``), the initial state on the reference, one period long: the scene's inverse dynamics follow the
reference on urdf2links and in MuJoCo alike (E57).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from urdf2links.identification import ParameterSet, regressor
from urdf2links.identification.base import base_parameters

from .excitation import SAFETY, FourierTrajectory, JointBounds, fit_within, random_trajectory

__all__ = ["Design", "design_trajectory", "scene_toml"]


@dataclass(frozen=True)
class Design:
    """The designed ``trajectory``, its ``condition`` number, the first random candidate's ``start_condition``,
    the number of ``evaluations``, ``peak_effort`` (n,) the largest |tau| along it (N m or N)."""

    trajectory: FourierTrajectory
    condition: float
    start_condition: float
    evaluations: int
    peak_effort: np.ndarray


def _score(params, model, tr: FourierTrajectory, bounds: JointBounds, samples: int) -> tuple[float, np.ndarray]:
    t = np.linspace(0.0, tr.period, samples, endpoint=False)
    q, qd, qdd = tr.evaluate(t)
    tau = model.inverse_dynamics(q, qd, qdd)
    peak = np.max(np.abs(tau), axis=0)
    if np.any(peak > SAFETY * bounds.effort):
        return math.inf, peak
    Y = regressor(params, q, qd, qdd)
    return float(base_parameters(params, Y=Y, samples=None).condition_number), peak


def design_trajectory(model, bounds: JointBounds, *, seed: int = 0, harmonics: int = 5, period: float = 10.0,
                      candidates: int = 12, rounds: int = 40, samples: int = 400) -> Design:
    """The search of the module doc on ``model`` (the description's Model) within ``bounds``."""
    params = ParameterSet.from_model(model, slip_speed=1e-2)
    rng = np.random.default_rng(seed)
    best, best_c, best_peak, first, evals = None, math.inf, None, None, 0
    for k in range(candidates):
        tr = random_trajectory(bounds, seed=seed * 1000 + k, harmonics=harmonics, period=period)
        c, peak = _score(params, model, tr, bounds, samples)
        evals += 1
        first = c if first is None else first
        if c < best_c:
            best, best_c, best_peak = tr, c, peak
    if best is None:
        raise ValueError(f"{model.name}: no candidate trajectory stays within {SAFETY:g} of the effort limits "
                         f"{bounds.effort.tolist()}; lower the period or the harmonics")
    step = 0.3
    for _ in range(rounds):
        a = best.a + step * rng.standard_normal(best.a.shape) * np.abs(best.a).mean()
        b = best.b + step * rng.standard_normal(best.b.shape) * np.abs(best.b).mean()
        tr = fit_within(best.names, best.w, a, b, bounds)
        c, peak = _score(params, model, tr, bounds, samples)
        evals += 1
        if c < best_c:
            best, best_c, best_peak = tr, c, peak
        else:
            step *= 0.95
    return Design(best, best_c, first, evals, best_peak)


def scene_toml(design: Design, description, *, out) -> str:
    """The scene of the module doc as TOML text; ``description``'s path written relative to ``out``'s folder."""
    tr = design.trajectory
    rel = Path(description).resolve()
    try:
        rel = Path(rel).relative_to(Path(out).resolve().parent)
    except ValueError:
        pass
    key = "mjcf" if str(description).endswith(".xml") else "urdf"
    q0, qd0, _ = tr.evaluate([0.0])
    lines = [f'description = "Excitation designed by urdf2links identify --design: periodic Fourier series, '
             f'condition number of the base regressor {design.condition:.4g} (first candidate {design.start_condition:.4g})"',
             "", "[robot]", f'{key} = "{rel}"', "", "[gravity]", "magnitude = 9.81", ""]
    k = np.arange(1, tr.a.shape[1] + 1)
    for i, name in enumerate(tr.names):
        terms = ", ".join(f"[{float(math.hypot(a, b))!r}, {float(kk * tr.w / (2 * math.pi))!r}, {float(math.atan2(b, a))!r}]"
                          for a, b, kk in zip(tr.a[i], tr.b[i], k))
        lines += ["[[computed_torque]]", f'coordinate = "{name}"',
                  f"reference = {{ sines = [{terms}], offset = {float(tr.c[i])!r} }}", ""]
    lines += ["[initial]", "q = { " + ", ".join(f'"{n}" = {float(v)!r}' for n, v in zip(tr.names, q0[0])) + " }",
              "qd = { " + ", ".join(f'"{n}" = {float(v)!r}' for n, v in zip(tr.names, qd0[0])) + " }", "",
              "[run]", f"t_end = {float(tr.period)!r}", 'method = "DOP853"', "rtol = 1e-10", "atol = 1e-12", ""]
    return "\n".join(lines)

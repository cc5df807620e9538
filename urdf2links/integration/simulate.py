"""Simulation: a scene (or a bare model) integrated in time, with its own energy bookkeeping.

``simulate(scene_or_model, ...) -> Trajectory``. The right-hand side is the compiled
:class:`~urdf2links.scenes.plan.Plan` (only the scene's terms); the integrator is any of
:data:`urdf2links.integration.integrators.METHODS`. The trajectory records coordinates, velocities, energies,
the work of non-potential forces, and the power-balance error ``h - h(0) - W`` at every sample.

Timing: ``stats["wall_time"]`` is the integration only (:data:`TIMED_REGION`);
``stats["run_s"]`` the whole call, both without numba's compilation. numba compiles the kernels and
loops at their first call in a process (or loads them from its disk cache); the integration compiles
(or loads) what it calls before its clock starts, and a compilation inside it (Radau5 when ``auto``
turns stiff) stops the clock (:func:`urdf2links.compilation.clock`); ``stats["compile_s"]`` is the
compilation the call saw. :func:`warm_up` compiles a scene's run ahead, and :func:`record_compilation`
says whether anything was compiled and how long it took.
"""

from __future__ import annotations

import contextlib
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import compilation
from ..console import Progress
from ..dynamics.model import Model
from ..errors import IntegrationError
from ..ranges import MAX_STEPS
from ..scenes.limits import limit_excursions
from ..scenes.plan import Plan, as_plan, compile_plan
from ..scenes.scene import RunSettings, Scene
from ..scenes.scene_checks import check_run
from .charts import integrate_charted, link_poses
from .constrained import constraint_stats, initial_state, project_samples, refresh_rhs
from .constrained_steps import check_constrained_method
from .trajectory import TIMED_REGION, Trajectory

__all__ = ["Trajectory", "simulate", "Progress", "warm_up", "record_compilation", "Compilation", "TIMED_REGION",
           "describe_stretches", "methods_used"]

def simulate(scene_or_model, *, t_end: float | None = None, method: str | None = None, rtol: float | None = None,
             atol: float | None = None, dt: float | None = None, samples: int | None = None, q0=None, qd0=None,
             progress: bool | None = None, model: Model | None = None, recharting: bool | None = None,
             max_wall: float | None = None, max_steps: int = MAX_STEPS) -> Trajectory:
    """Integrate a scene (a :class:`~urdf2links.scenes.scene.Scene`, its compiled
    :class:`~urdf2links.scenes.plan.Plan`, a path to a scene file) or a bare
    :class:`~urdf2links.dynamics.model.Model` (gravity as the model says, nothing else acting). A Plan
    is run as it is: nothing is loaded or compiled again (:func:`~urdf2links.scenes.plan.as_plan`).

    Keyword arguments override the scene's ``[run]`` and ``[initial]``; ``model`` reuses an already
    loaded model of the scene's robot; ``progress`` forces the progress bar on or off (default: on
    for a terminal).

    Floating links (three angle coordinates) are re-charted when they approach ``phi_y = +-pi/2``
    (:mod:`urdf2links.integration.charts`; ``recharting`` overrides the scene's ``[run] recharting``, default
    on): the run is then integrated in segments, ``q``/``qd`` are reported in the loaded model's
    coordinates, the re-charted links' poses are recorded, and ``stats['recharts']`` lists the
    switches. Without re-charting, reaching the singularity raises a DynamicsError.

    A run that cannot finish raises :class:`~urdf2links.errors.IntegrationError` saying why: the step
    size fell below the spacing of floating-point numbers, more than ``max_steps`` accepted steps
    (default :data:`~urdf2links.ranges.MAX_STEPS`), more than ``max_wall`` seconds of wall time
    (default: no budget; ``--max-wall`` on the command line), a non-finite state. Overrides are checked
    like a scene's ``[run]`` (:func:`~urdf2links.scenes.scene_checks.check_run`: SceneError naming the value and its range).
    """
    scene, model, plan = _scene_and_model(scene_or_model, model)
    run = _run_settings(scene, t_end=t_end, method=method, rtol=rtol, atol=atol, dt=dt, samples=samples,
                        recharting=recharting)
    plan = plan or compile_plan(scene, model)
    refresh_rhs(plan)       # issue 45: constraints replaced on a compiled plan are compiled in again
    q, qd = scene.initial_state(model)
    if q0 is not None:
        q = model.vector(q0, "q0").copy()
    if qd0 is not None:
        qd = model.vector(qd0, "qd0").copy()
    started, compiled0 = compilation.clock(), compilation.seconds()
    if plan.constraints is None:
        res = _integrate(plan, run, np.r_[q, qd, 0.0], progress=progress, max_wall=max_wall, max_steps=max_steps)
        return _trajectory(plan, run, res, started=started, compiled0=compiled0, max_wall=max_wall)
    # issue 45: constraints and fixed tendons in the compiled loops (E72)-(E77): the start projected, every
    # accepted step projected inside the loops, the samples projected here (integration.constrained)
    check_constrained_method(run, str(scene.path or scene.name))     # refused by name before any work
    y0, initial = initial_state(plan, q, qd)
    res = _integrate(plan, run, y0, progress=progress, max_wall=max_wall, max_steps=max_steps)
    project_samples(plan, res.t, res.y)
    if not res.recharts:
        res.y_chart[:] = res.y
    return _constrained_trajectory(plan, run, res, initial, started=started, compiled0=compiled0, max_wall=max_wall)


def _constrained_trajectory(plan, run, res, initial, *, started, compiled0, max_wall) -> Trajectory:
    """:func:`_trajectory` with the fixed tendons' springs in ``V`` and ``h`` (E76) and
    ``stats["constraints"]`` (:func:`~urdf2links.integration.constrained.constraint_stats`)."""
    traj = _trajectory(plan, run, res, started=started, compiled0=compiled0, max_wall=max_wall)
    closure, n = plan.constraints, plan.n
    if closure.tendons:
        Vt = np.array([closure.tendon_energy(q) for q in traj.q])
        for key in ("potential", "function"):
            traj.energy[key] = traj.energy[key] + Vt
        traj.energy["error"] = traj.energy["function"] - traj.energy["function"][0] - traj.energy["work"]
    method = (f"{methods_used(run.method, res.stretches)} + projection after every step (E74), compiled "
              f"(change point: {getattr(plan.scene, 'change_point', 'continue') or 'continue'})")
    info = constraint_stats(plan, traj.t, np.c_[traj.q, traj.qd, traj.energy["work"]], initial=initial, method=method)
    traj.stats["constraints"] = info
    traj.stats["integrator"] = f"{run.method}+projection"
    traj.stats["scene_method"] = plan.scene.run.method
    traj.stats["wall_time"] = res.wall_time
    return traj


def _run_settings(scene: Scene, *, t_end, method, rtol, atol, dt, samples, recharting) -> RunSettings:
    """The scene's ``[run]`` with the settings :func:`simulate` was given in its place, checked like a scene's
    (:func:`~urdf2links.scenes.scene_checks.check_run`)."""
    run = scene.run
    return check_run(RunSettings(t_end=run.t_end if t_end is None else t_end, method=method or run.method,
                                 rtol=run.rtol if rtol is None else rtol, atol=run.atol if atol is None else atol,
                                 dt=run.dt if dt is None else dt, samples=run.samples if samples is None else samples,
                                 recharting=run.recharting if recharting is None else bool(recharting)),
                     f"{scene.path or scene.name}: simulate()", prefix="")


def _integrate(plan: Plan, run: RunSettings, y0: np.ndarray, *, progress, max_wall, max_steps):
    """The plan's right-hand side integrated from ``y0 = (q, q', 0)`` over the run, re-charted where a floating
    link's angles ask (:func:`~urdf2links.integration.charts.integrate_charted`); an IntegrationError says why a run
    could not finish."""
    scene, model = plan.scene, plan.model
    t_eval = np.linspace(0.0, run.t_end, max(run.samples, 2))
    bar = Progress(run.t_end, label=f"{scene.name} {run.method}", enabled=progress)
    # torques, springs, actuators and a computed torque (its reference: every coordinate) act on coordinates:
    # their links keep their chart
    exclude = ({c for c, _ in scene.torques} | {sp.coordinate for sp in plan.spring_set.springs}
               | {a.coordinate for a in plan.actuator_set.actuators}
               | (set(model.coordinate_names) if plan.reference_funcs else set()))
    try:
        res = integrate_charted(model, lambda m: plan if m is model else compile_plan(scene, m), y0,
                                (0.0, run.t_end), t_eval=t_eval, method=run.method, rtol=run.rtol, atol=run.atol,
                                dt=run.dt if run.method in ("RK4", "midpoint") else None, callback=bar,
                                recharting=run.recharting, exclude=exclude, base_state=plan.base_state,
                                max_steps=max_steps, max_wall=max_wall)
    finally:
        bar.close()
    if not res.success:
        raise IntegrationError(f"{scene.path or scene.name}: {run.method} (rtol {run.rtol:g}"
                               + (f", dt {run.dt:g}" if run.dt and run.method in ("RK4", "midpoint") else "")
                               + f") could not finish the run to t_end = {run.t_end:g} s: {res.message}"
                               + (f" (max_wall {max_wall:g} s for the whole run)" if max_wall is not None else ""))
    return res


def _trajectory(plan: Plan, run: RunSettings, res, *, started: float, compiled0: float, max_wall) -> Trajectory:
    """The :class:`Trajectory` of an integration ``res``: coordinates, energies and the power balance (E37, E39),
    the recorded link poses, the run's figures and notes (``stats``)."""
    scene, model, n = plan.scene, plan.model, plan.model.n
    t = res.t
    qs, qds, W = res.y[:, :n], res.y[:, n:2 * n], res.y[:, 2 * n]
    E, V, h = _energies(res, n)
    recorded = list(dict.fromkeys([*scene.link_poses, *(r["link"] for r in res.recharts)]))
    poses = _record_poses(res, n, recorded, started=started, max_wall=max_wall, where=scene.path or scene.name)
    stats = {"method": run.method, "rtol": run.rtol, "atol": run.atol, "dt": run.dt, "nfev": res.nfev,
             "nsteps": res.nsteps, "njev": res.njev, "stretches": list(res.stretches),
             "methods_used": methods_used(run.method, res.stretches), "wall_time": res.wall_time, "terms": plan.terms, "success": res.success,
             "message": res.message, "recharting": run.recharting, "n_recharts": len(res.recharts),
             "recharts": res.recharts, "segments": len(res.segments),
             "limit_excursions": [e.as_dict() for e in limit_excursions(model, t, qs)],
             "spring_notes": list(plan.spring_set.notes), "run_s": compilation.clock() - started,
             "compile_s": compilation.seconds() - compiled0}
    return Trajectory(t=t, q=qs, qd=qds, coordinate_names=model.coordinate_names,
                      energy={"kinetic": E, "potential": V, "work": W, "function": h, "error": h - h[0] - W},
                      poses=poses, stats=stats, scene=scene.name, robot=model.name, sol=res.sol,
                      charts=res if res.recharts else None)


def methods_used(method: str, stretches) -> str:
    """``"DOP853"``, ``"DOP853 then Radau5"``, ... for ``auto``'s stretches in order (``method`` itself
    for the other methods)."""
    names = [s["method"] for s in stretches]
    if not names:
        return method
    return " then ".join(n for i, n in enumerate(names) if i == 0 or n != names[i - 1])


def describe_stretches(stretches) -> list[str]:
    """One line per stretch of an ``auto`` run: method, interval, steps, evaluations, Jacobians, why it
    started (the stiffness test's or the cost comparison's figures)."""
    out = []
    for s in stretches:
        seg = f" (chart segment {s['segment']})" if s.get("segment") else ""
        out.append(f"{s['method']} t = {s['t0']:.6g}..{s['t1']:.6g} s{seg}: {s['steps']} steps, {s['nfev']} evaluations"
                   + (f", {s['njev']} Jacobians" if s["njev"] else "") + f"; {s['started']}")
    return out


def _scene_and_model(scene_or_model, model: Model | None) -> tuple[Scene, Model, Plan | None]:
    """The scene to run (a bare Model runs in a scene of gravity alone), its model, and its compiled
    run when the caller passed one (a :class:`~urdf2links.scenes.plan.Plan`: nothing is loaded or
    compiled again)."""
    from ..scenes.scene_read import load_scene

    if isinstance(scene_or_model, Plan):
        plan = as_plan(scene_or_model, model=model)
        return plan.scene, plan.model, plan
    if isinstance(scene_or_model, (str, Path)):
        scene_or_model = load_scene(scene_or_model)
    if isinstance(scene_or_model, Model):
        model = scene_or_model
        return Scene(name=model.name or "model", path=None, robot=Path(model.source or "."), load_options={},
                     gravity=np.asarray(model.gravity_vector)), model, None
    if isinstance(scene_or_model, Scene):
        return scene_or_model, scene_or_model.model() if model is None else model, None
    raise TypeError(f"simulate takes a Scene, its Plan, a scene file path or a Model; got "
                    f"{type(scene_or_model).__name__}")


def _energies(res, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(S,) kinetic and potential energies (E37) and the function h (E39) at the samples, each in the
    chart that computed it (regular there), compiled."""
    t, qc, qdc = res.t, res.y_chart[:, :n], res.y_chart[:, n:2 * n]
    E, V, h = np.empty(len(t)), np.empty(len(t)), np.empty(len(t))
    segment_of = np.asarray(res.segment_of)
    for k, segment in enumerate(res.segments):
        idx = np.nonzero(segment_of == k)[0]
        if idx.size:
            E[idx], V[idx], h[idx] = segment.plan.rhs.energies(t[idx], qc[idx], qdc[idx])
    return E, V, h


def _record_poses(res, n: int, recorded: list[str], *, started: float, max_wall: float | None, where) -> dict:
    """(S, 4, 4) world poses of the ``recorded`` links at the samples, each from the chart that
    computed the sample; the wall-clock budget bounds this too."""
    qc = res.y_chart[:, :n]
    poses = {link: np.empty((len(res.t), 4, 4)) for link in recorded}
    for i, (k, ti, a) in enumerate(zip(res.segment_of, res.t, qc)):
        if recorded and max_wall is not None and i % 1000 == 0 and compilation.clock() - started > max_wall:
            raise IntegrationError(f"{where}: max_wall={max_wall:g} s spent while recording the poses "
                                   f"of {', '.join(recorded)} at sample {i} of {len(res.t)} (fewer samples would do)")
        p = res.segments[k].plan
        P = link_poses(p.model, recorded, a, t=ti, base=p.base_state(ti))
        for link in recorded:
            poses[link][i] = P[link]
    return poses


@dataclass
class Compilation:
    """What :func:`record_compilation` saw: ``seconds`` the block's duration, ``functions`` the
    numba functions compiled in it (not loaded from the disk cache)."""

    seconds: float = 0.0
    functions: list = field(default_factory=list)

    @property
    def happened(self) -> bool:
        return bool(self.functions)

    def describe(self, what: str) -> str:
        return (f"{what}: numba compiled {len(self.functions)} function(s) in {self.seconds:.1f} s (once; cached on disk "
                "for the next runs; not in the timed runs)")


@contextlib.contextmanager
def record_compilation():
    """Context yielding a :class:`Compilation`, filled on exit: the block's seconds and the numba
    functions it compiled (numba's ``numba:compile`` events; a function loaded from the cache
    raises none)."""
    from numba.core import event

    out = Compilation()
    start = time.perf_counter()
    with event.install_recorder("numba:compile") as rec:
        yield out
    out.seconds = time.perf_counter() - start
    names = []
    for _, ev in rec.buffer:
        if ev.is_start:
            fn = getattr(ev.data.get("dispatcher"), "py_func", None)
            names.append(getattr(fn, "__qualname__", str(fn)))
    out.functions.extend(sorted(set(names)))


def warm_up(scene, *, model: Model | None = None, methods=None, t_end: float | None = None) -> Compilation:
    """Run ``scene`` (a Scene, its compiled :class:`~urdf2links.scenes.plan.Plan`, or a scene file) once with each of ``methods`` over a few steps, so that every compiled function
    a run of it calls is compiled (or loaded from numba's cache) here and not inside a timed run
    (``methods`` default: the scene's own; ``auto`` warms DOP853: Radau5 is compiled when a run turns
    stiff, outside its timed region too, :mod:`urdf2links.compilation`).
    ``t_end`` defaults to the shorter of the scene's and 0.01 s. Returns the
    :class:`Compilation` of the whole warm-up. A method that fails here is left to fail (and be
    reported) in the real run."""
    plan = as_plan(scene, model=model)
    scene = plan.scene
    T = min(scene.run.t_end, 0.01) if t_end is None else float(t_end)
    methods = (scene.run.method,) if methods is None else tuple(methods)
    # auto's Radau5 is not warmed: it is compiled only if a run turns stiff, and that compilation is
    # kept out of the run's wall_time anyway (urdf2links.compilation.clock)
    with record_compilation() as rec:
        for m in methods:
            kw = {"dt": T / 4} if m in ("RK4", "midpoint") else {"rtol": 1e-6, "atol": 1e-8}
            try:
                simulate(plan, t_end=T, samples=3, progress=False, method=m, **kw)
            except Exception:  # noqa: BLE001 -- a method that fails here fails (and is reported) in the run
                pass
    return rec

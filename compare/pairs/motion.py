"""The two descriptions in motion: each file run from the same state in its default scene, by the project and
by MuJoCo running the file as written, and how far the two descriptions move apart.

Both descriptions run their own default scene (:func:`urdf2links.scenes.default_scenes.default_scene`: gravity,
fixed base unless ``floating_base``, each file's own damping, and for an MJCF file its stiffness and
gravcomp), from the first description's initial state (at rest, ``q0`` zero or seeded random) mapped
into the second's coordinates (E52; its unmatched joints at home). Four runs over the same times:

- the project's, of each description (:func:`urdf2links.integration.simulate.simulate`);
- MuJoCo's, of each file as written: an MJCF file compiled and run by MuJoCo with only the scene's
  effects (route 2, :mod:`urdf2links.compare.mujoco_side.mujoco_mjcf`), a URDF through MuJoCo's own URDF
  import (:func:`~urdf2links.compare.mujoco_side.mujoco_urdf.mujoco_from_urdf`, limits, contacts and
  friction off, the file's damping kept), ``mj_step(nstep)`` from sample to sample.

The divergence between the descriptions is ``|q_urdf - sign (q_mjcf - offset)|`` per matched coordinate
(in the first description's coordinates), for each engine; the divergence time is its first crossing
of :data:`~urdf2links.compare.agreement.trajectory.DIVERGENCE_THRESHOLD`. Each file's two engines are
also compared (``engines``), so that the descriptions moving apart is told from the engines moving apart. The animation draws both robots: the first solid, the
second translucent (:func:`urdf2links.view.animation.render_animation` with a run of another model).
"""

from __future__ import annotations

import dataclasses
import time
import warnings
from dataclasses import dataclass, field

import mujoco
import numpy as np

from urdf2links.integration.simulate import simulate, warm_up
from urdf2links.dynamics.rotations import matrix_to_xyz_angles, xyz_angles_to_matrix
from urdf2links.parsers.mjcf_state import _nearest, matrix_to_quat, quat_to_matrix, rate_matrix
from urdf2links.parsers.robot_file import is_mjcf_path
from urdf2links.scenes.functions import Constant
from urdf2links.scenes.plan import as_plan
from urdf2links.scenes.default_scenes import default_scene
from urdf2links.view.animation import DEFAULT_FPS, Motion, Panel, render_animation
from urdf2links.view.visuals import scene_shapes

from ..agreement.trajectory import DIVERGENCE_THRESHOLD, divergence_time
from ..mujoco_side.mujoco_mjcf import file_runner, mujoco_from_mjcf
from ..mujoco_side.mujoco_stepping import INTEGRATOR_ENUM
from ..mujoco_side.mujoco_urdf import MujocoRefused, mujoco_from_urdf
from ..mujoco_side.stable_run import stable_run

__all__ = ["PairMotion", "run_pair_motion", "pair_animation"]


@dataclass(eq=False)
class PairMotion:
    """The four runs at the times ``t`` (m,): ``q_urdf``, ``q_mjcf`` (m, n_each) by the project;
    ``mj_urdf``, ``mj_mjcf`` by MuJoCo (None when it could not run the file: ``notes`` says why); the
    divergences (m, k) over the ``mapped`` coordinates (first description's names); the models, scenes."""

    t: np.ndarray
    q_urdf: np.ndarray
    q_mjcf: np.ndarray
    mj_urdf: np.ndarray | None
    mj_mjcf: np.ndarray | None
    mapped: list[str]
    div_project: np.ndarray
    div_mujoco: np.ndarray | None
    models: tuple
    scenes: tuple
    settings: dict
    notes: list[str] = field(default_factory=list)

    def summary(self) -> dict:
        """The ``description_motion`` part of the summary JSON."""
        def block(div):
            if div is None:
                return None
            mx = div.max(axis=1) if div.size else np.zeros(len(self.t))
            return {"max_divergence": float(mx.max()) if mx.size else 0.0,
                    "divergence_time": divergence_time(self.t, mx, DIVERGENCE_THRESHOLD),
                    "final_divergence": float(mx[-1]) if mx.size else 0.0,
                    "by_coordinate": {c: float(v) for c, v in zip(self.mapped, div.max(axis=0))} if div.size else {}}

        su, sm = self.scenes
        q0, _ = su.initial_state(self.models[0])
        engines = {}
        for label, ours, theirs in (("urdf", self.q_urdf, self.mj_urdf), ("mjcf", self.q_mjcf, self.mj_mjcf)):
            engines[label] = None if theirs is None else float(np.max(np.abs(ours - theirs), initial=0.0))
        return {"scene": {"urdf": su.description, "mjcf": sm.description}, "t_end": float(self.t[-1]),
                "samples": int(len(self.t)), "initial_q": dict(zip(self.models[0].coordinate_names, q0.tolist())),
                "threshold": DIVERGENCE_THRESHOLD, "project": block(self.div_project), "mujoco": block(self.div_mujoco),
                "engines_max_abs_difference": engines, "mujoco_settings": dict(self.settings),
                "units": "rad for angles, m for translations; in the first description's coordinates",
                "notes": list(self.notes)}


def _mujoco_urdf_run(plan, *, t_end, samples, timestep, integrator) -> tuple[np.ndarray, list[str]]:
    """MuJoCo's own import of the scene's URDF run from the scene's initial state: ``q`` (samples, n). A floating
    base is MuJoCo's free joint added to the root (route 2's), its pose read back as the root's six coordinates
    (ZYX angles on the branch nearest the previous sample's, E7)."""
    scene, model = plan.scene, plan.model
    if str(scene.robot).endswith(".xacro"):
        raise ValueError("a .xacro file: MuJoCo reads URDF only; not run")
    floating = bool(scene.load_options.get("floating_base"))
    g = np.zeros(3) if scene.gravity is None else np.asarray(scene.gravity, float)
    mj = mujoco_from_urdf(scene.robot, gravity=g, damping=bool(scene.urdf_damping), floating_base=floating)
    m = mj.model
    m.opt.timestep = float(timestep)
    m.opt.integrator = int(INTEGRATOR_ENUM[integrator])
    names = list(model.coordinate_names)
    root = [i for i, n in enumerate(names) if n not in mj.qpos_of_joint]
    if (len(root) != 6 if floating else root):
        raise ValueError(f"MuJoCo's import has no joint for {[names[i] for i in root][:4]}")
    joints = [i for i in range(len(names)) if i not in root]
    adr = [mj.qpos_of_joint[names[i]] for i in joints]
    dof = [mj.dof_of_joint[names[i]] for i in joints]
    q0, qd0 = scene.initial_state(model)
    d = mujoco.MjData(m)
    d.qpos[adr], d.qvel[dof] = q0[joints], qd0[joints]
    for coord, f in scene.torques:      # constant joint torques (the excited default scene's damper torques, E65)
        if isinstance(f, Constant) and coord in mj.dof_of_joint:
            d.qfrc_applied[mj.dof_of_joint[coord]] += float(f.value)
    if floating:
        a, f = mj.free_qpos, list(mj.free_dofs)
        phi = q0[root[3:]]
        d.qpos[a:a + 3] = q0[root[:3]]
        d.qpos[a + 3:a + 7] = matrix_to_quat(xyz_angles_to_matrix(phi))
        d.qvel[f[:3]] = qd0[root[:3]]
        d.qvel[f[3:]] = rate_matrix(phi) @ qd0[root[3:]]
    ks = np.rint(np.linspace(0.0, t_end, samples) / timestep).astype(np.int64)
    out, done, prev = np.empty((samples, len(names))), 0, q0[root[3:]] if floating else None
    for j, k in enumerate(ks):
        if k > done:
            mujoco.mj_step(m, d, nstep=int(k - done))
            done = int(k)
        out[j, joints] = d.qpos[adr]
        if floating:
            a = mj.free_qpos
            out[j, root[:3]] = d.qpos[a:a + 3]
            prev = _nearest(matrix_to_xyz_angles(quat_to_matrix(d.qpos[a + 3:a + 7])), prev)
            out[j, root[3:]] = prev
    return out, [f"MuJoCo's URDF import: {n}" for n in mj.notes[-1:]]


def _mujoco_run(plan, *, t_end, samples, timestep, integrator, reference):
    if is_mjcf_path(plan.scene.robot):     # a blow-up falls back to a stable setting, as in compare_scene
        mf = mujoco_from_mjcf(plan, timestep=timestep, integrator=integrator)
        run, _ = stable_run(None, plan, t_end=t_end, samples=samples, integrator=integrator, timestep=timestep,
                            runner=file_runner(mf, plan, t_end=t_end, samples=samples, reference=reference))
        return run.q, [f"MuJoCo runs the MJCF file: {n}" for n in mf.notes + run.notes]
    return _mujoco_urdf_run(plan, t_end=t_end, samples=samples, timestep=timestep, integrator=integrator)


def _mapped_initial(scene_m, model_u, model_m, q0_u, qd0_u, cmap, torques_u=()) -> object:
    """The second description's scene started at the first one's state, mapped (E52); the first one's
    constant torques (the excited default scene's damper torques, E65) mapped onto it too."""
    from urdf2links.scenes.functions import Constant

    q = np.asarray(model_m.info.get("q0", np.zeros(model_m.n)), float).copy()
    qd = np.zeros(model_m.n)
    iu = {n: i for i, n in enumerate(model_u.coordinate_names)}
    im = {n: i for i, n in enumerate(model_m.coordinate_names)}
    to_m = {a: (b, s) for a, b, s, c in cmap}
    for a, b, s, c in cmap:
        q[im[b]] = s * q0_u[iu[a]] + c
        qd[im[b]] = s * qd0_u[iu[a]]
    torques = tuple((to_m[a][0], Constant(to_m[a][1] * f.value)) for a, f in torques_u if a in to_m)
    head = scene_m.description.split("; at rest at")[0]
    return dataclasses.replace(scene_m, q0=dict(zip(model_m.coordinate_names, q.tolist())),
                               qd0=dict(zip(model_m.coordinate_names, qd.tolist())), torques=torques,
                               description=head + "; the first description's initial state and constant torques, mapped")


def run_pair_motion(pair, *, q0: str = "zero", seed: int = 0, t_end: float = 1.0, load: dict | None = None,
                    mujoco_dt: float = 1e-4, mujoco_integrator: str = "RK4", log=None) -> PairMotion:
    """Run both descriptions of ``pair`` (a :class:`~urdf2links.compare.pairs.pair.PairComparison`) as the
    module doc says; ``load`` the first file's loading options."""
    say = log or (lambda _m: None)
    load = dict(load or {})
    opts_u = {k: v for k, v in load.items() if k in ("floating_base", "package_dirs", "xacro_args", "inertia", "strict")}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene_u = default_scene(pair.urdf_path, q0=q0, seed=seed, t_end=t_end, floating=bool(opts_u.pop("floating_base",
                                False)), **opts_u)
        model_u = scene_u.model()
        scene_m = default_scene(pair.mjcf_path, t_end=t_end, q0="rest")   # its state: the first one's, mapped
        model_m = scene_m.model()
    cmap = pair.context.coordinate_map()
    q0u, qd0u = scene_u.initial_state(model_u)
    scene_m = _mapped_initial(scene_m, model_u, model_m, q0u, qd0u, cmap, scene_u.torques)
    plans = (as_plan(scene_u, model=model_u), as_plan(scene_m, model=model_m))
    samples = scene_u.run.samples
    runs, notes = [], []
    for label, plan in zip(("urdf", "mjcf"), plans):
        warm_up(plan, methods=(plan.scene.run.method,))
        say(f"{label}: urdf2links, t = 0..{t_end:g} s")
        runs.append(simulate(plan, t_end=t_end, samples=samples, progress=False))
    t = np.asarray(runs[0].t, float)
    mj = []
    for label, plan, traj in zip(("urdf", "mjcf"), plans, runs):
        say(f"{label}: MuJoCo running the file, {mujoco_integrator} dt {mujoco_dt:g}")
        try:
            q, more = _mujoco_run(plan, t_end=t_end, samples=samples, timestep=mujoco_dt, integrator=mujoco_integrator,
                                  reference=traj.q)
            mj.append(q)
            notes += [f"{label}: {n}" for n in more]
        except (ValueError, MujocoRefused, NotImplementedError) as exc:
            mj.append(None)
            notes.append(f"{label}: MuJoCo's run of the file skipped: {exc}")
    iu = [model_u.coordinate_names.index(a) for a, *_ in cmap]
    im = [model_m.coordinate_names.index(b) for _, b, *_ in cmap]
    s = np.array([x[2] for x in cmap], float)
    c = np.array([x[3] for x in cmap], float)

    def divergence(qu, qm):
        if qu is None or qm is None:
            return None
        return np.abs(qu[:, iu] - s * (qm[:, im] - c))

    notes += [f"urdf scene: {n}" for n in plans[0].spring_set.notes] + [f"mjcf scene: {n}" for n in plans[1].spring_set.notes]
    if any(b.parent is None and any(j.kind == "free" for j in b.joints) for b in pair.urdf.bodies) and not np.any(qd0u):
        notes.insert(0, "a floating base at rest under gravity alone falls as one rigid body (no contact here): its joints "
                        "do not move, whatever the descriptions' differences, so this divergence says little of them; "
                        "the differences' effect on A and G does")
    return PairMotion(t, runs[0].q, runs[1].q, mj[0], mj[1], [a for a, *_ in cmap], divergence(runs[0].q, runs[1].q),
                      divergence(mj[0], mj[1]), (model_u, model_m), (scene_u, scene_m),
                      {"integrator": mujoco_integrator, "timestep": mujoco_dt}, notes)


def pair_animation(pm: PairMotion, *, fps: float = DEFAULT_FPS, labels=("first description", "second description")):
    """Both robots moving as the project ran them (the second translucent), the divergence beside."""
    (model_u, model_m), (scene_u, scene_m) = pm.models, pm.scenes
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        shapes_u, shapes_m = scene_shapes(scene_u, model_u), scene_shapes(scene_m, model_m)
    motions = [Motion(labels[0], pm.t, pm.q_urdf, label=f"{model_u.name} ({scene_u.robot.name}), urdf2links"),
               Motion(labels[1], pm.t, pm.q_mjcf, ghost=True, model=model_m, shapes=shapes_m,
                      label=f"{model_m.name} ({scene_m.robot.name}), urdf2links, from the same state")]
    series = {"urdf2links": pm.div_project.max(axis=1) if pm.div_project.size else pm.t * 0}
    if pm.div_mujoco is not None:
        series["MuJoCo"] = pm.div_mujoco.max(axis=1) if pm.div_mujoco.size else pm.t * 0
    series = {k: np.maximum(v, 1e-16) for k, v in series.items()}
    panels = [Panel("the descriptions apart: max |q_urdf - q_mjcf mapped|", pm.t, series, log=True, unit="rad or m",
                    lines={f"threshold {DIVERGENCE_THRESHOLD:g}": DIVERGENCE_THRESHOLD}),
              Panel("per coordinate (urdf2links)", pm.t,
                    {n: np.maximum(pm.div_project[:, i], 1e-16) for i, n in enumerate(pm.mapped)}, log=True,
                    unit="rad or m", legend=len(pm.mapped) <= 8)]
    return render_animation(model_u, motions, shapes=shapes_u, panels=panels, fps=fps, dom_id="u2l-pair-motion")

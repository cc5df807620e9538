"""Terms at identical states for one scene: ``A`` against ``mj_fullM`` and ``e + G`` against
``qfrc_bias`` at seeded random states, on both routes (the first level of :func:`~urdf2links.compare.
trajectory.compare_scene`).

Route 1 (:func:`route1_terms`): the project's own tree written as MJCF for the scene (its gravity,
springs, moving base; with a moving base also a random base pose and rate at each state). Route 2
(:func:`route2_terms`): MuJoCo's own URDF import of the robot's file
(:func:`urdf2links.compare.agreement.terms.compare_terms_urdf`), fixed-base robots only; when MuJoCo refuses
the file, its reason is recorded and the comparison is repeated with the project's repair (a
:data:`MASSLESS_SPHERE_KG` sphere on each massless moving link on BOTH sides when MuJoCo refuses
those), labelled as such.
"""

from __future__ import annotations

import math
import tempfile
import warnings
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from urdf2links.compilation import clock  # durations without numba's compilation
from urdf2links.dynamics.transforms import BaseState
from urdf2links.parsers.xacro_input import expand_xacro, is_xacro_path
from urdf2links.scenes.excitation import coordinate_ranges
from urdf2links.scenes.scene import Scene, robot_stem

from ..mujoco_side.mjcf_model import MjcfModel
from ..mujoco_side.mujoco_urdf import MujocoRefused
from .terms import compare_terms_urdf

__all__ = ["route1_terms", "route2_terms", "MASSLESS_SPHERE_KG", "ROUTE1_LABEL"]

#: Mass (kg) of the sphere put on each massless moving link when MuJoCo refuses them (route 2).
MASSLESS_SPHERE_KG = 1e-3
ROUTE1_LABEL = "route 1: the project's tree as MJCF (same frames, H, coordinates; only the scene's effects)"



def _rel(ours, theirs, floor: float = 0.0) -> float:
    theirs = np.asarray(theirs, float)
    if theirs.size == 0:
        return 0.0
    diff = float(np.max(np.abs(np.asarray(ours, float) - theirs)))
    scale = float(np.max(np.abs(theirs)))
    if scale <= 1e-12 * floor:
        scale = floor
    if scale == 0.0:
        return 0.0 if diff == 0.0 else math.inf
    return diff / scale


def _with_gravity(model, gravity):
    """``model`` under the scene's gravity ``gravity`` (zero when None): :meth:`Model.with_gravity`."""
    return model.with_gravity(np.zeros(3) if gravity is None else gravity)


def _route1_model(model):
    """``model`` as route 1 writes it: without the shared armature of a ball's three angles
    (:func:`~urdf2links.compare.mujoco_side.mjcf_bodies.route1_armature`)."""
    from urdf2links.dynamics.model import Model
    from urdf2links.dynamics.tree import LinkTree

    from ..mujoco_side.mjcf_bodies import route1_armature

    arm, balls = route1_armature(model.tree)
    if not balls:
        return model
    t = model.tree
    tree = LinkTree(link_names=t.link_names, parent=t.parent, params=t.params, coord=t.coord, H=t.H,
                    coordinate_names=t.coordinate_names, armature=arm)
    coupling = None if model.coupling is None else (*model.coupling, model.coordinate_names)
    return Model(tree, gravity=model.gravity_vector, coupling=coupling, name=model.name, source=model.source,
                 info=model.info)


def route1_terms(mj: MjcfModel, model, scene: Scene, *, states: int = 8, seed: int = 0) -> dict:
    """Route 1: ``A`` vs ``mj_fullM`` and ``e + G`` vs ``qfrc_bias`` of the scene's MJCF model at
    seeded random states (see the module doc). Returns a JSON-ready dict."""
    ours = _with_gravity(_route1_model(model), scene.gravity)
    rng = np.random.default_rng(seed)
    n = model.n
    err_A = err_b = 0.0
    per_state = []
    start = clock()
    span = coordinate_ranges(model)     # the states span the joints' limits (a +-1 window where none)
    for _ in range(states):
        q = rng.uniform(span.lower, span.upper)
        qd = rng.standard_normal(n)
        bs = None
        if mj.moving_base:
            bs = BaseState(rng.uniform(-1.0, 1.0, 6), rng.standard_normal(6), np.zeros(6))
        M, bias = mj.terms(q, qd, base=bs)
        A = ours.mass_matrix(q, base=bs)
        eG = ours.bias(q, qd, base=bs)
        if scene.gravity is not None:
            eG = eG + ours.gravity(q, base=bs)
        floor = float(np.max(np.abs(M))) * max(1.0, float(np.max(np.abs(qd))) ** 2) if n else 0.0
        ra, rb = _rel(A, M), _rel(eG, bias, floor)
        per_state.append([ra, rb])
        err_A, err_b = max(err_A, ra), max(err_b, rb)
    return {
        "label": ROUTE1_LABEL,
        "route": "mjcf",
        "max_rel_error_A": err_A,
        "max_rel_error_bias": err_b,
        "max_rel_error": max(err_A, err_b),
        "states": states,
        "seed": seed,
        "moving_base": bool(mj.moving_base),
        "per_state": per_state,
        "wall_time_s": clock() - start,
        "notes": list(mj.notes),
    }


#: The project's load options route 2 compares with (MuJoCo's URDF import: a fixed base, mimic joints
#: as independent joints), besides the inertia policy of each attempt.
_ROUTE2_LOAD = {"floating_base": False, "mimic": "independent", "density": 1000.0}


def _reusable(model, opts: dict, inertia: str) -> bool:
    """The scene's already loaded ``model`` is route 2's own import for the ``inertia`` attempt: the
    same file, loaded with route 2's options."""
    if model is None:
        return False
    same = {k: opts.get(k, v) for k, v in _ROUTE2_LOAD.items()} == _ROUTE2_LOAD and opts.get("inertia", "audit") == inertia
    return same and set(opts) <= {"floating_base", "mimic", "density", "inertia", "package_dirs", "strict"}


def route2_terms(scene: Scene, *, states: int = 8, seed: int = 0, model=None) -> dict:
    """Route 2: MuJoCo's own URDF import of the scene's robot file against the project's import.

    Tried in order until MuJoCo accepts a text: the file as the scene loads it; the project's
    repair (``inertia="repair"``) written into the text; that plus a
    :data:`MASSLESS_SPHERE_KG` sphere on each massless moving link on both sides. Every refusal
    is recorded (``refusals``); ``label`` says which route produced the figures. A floating-base
    robot is skipped (``skipped`` says why); so is a file MuJoCo refuses in every form
    (``error``). ``model``: the scene's model, taken instead of a second import where route 2 would
    load the file with the same options. Returns a JSON-ready dict."""
    opts = dict(scene.load_options)
    if opts.get("floating_base"):
        return {"route": None, "label": "route 2: skipped", "skipped":
                "floating base: route 2 (MuJoCo's URDF import) is compared for fixed-base robots only"}
    base_opts = {k: v for k, v in opts.items() if k in ("package_dirs", "strict")}
    inertia = opts.get("inertia", "audit")
    attempts = [(inertia, None)]
    if inertia != "repair":
        attempts.append(("repair", None))
    attempts.append(("repair", MASSLESS_SPHERE_KG))
    refusals: list[dict] = []
    start = clock()
    result = None
    given = None if is_xacro_path(scene.robot) else model     # an expanded xacro is another file: load it
    with _urdf_file(scene) as robot:
        for how, sphere in attempts:
            try:
                model = given if _reusable(given, opts, how) else _import(robot, how, base_opts)
            except Exception as err:  # strict import refuses: try the next form
                refusals.append({"attempt": _attempt(how, sphere), "by": "urdf2links", "reason": str(err)})
                continue
            model = _with_gravity(model, scene.gravity)
            try:
                result = compare_terms_urdf(robot, model, states=states, seed=seed, massless_moving=sphere,
                                            dampers=_urdf_dampers(model) if scene.urdf_damping else None)
                break
            except MujocoRefused as err:
                refusals.append({"attempt": _attempt(how, sphere), "by": "MuJoCo", "reason": err.reason})
            except ValueError as err:
                return {"route": None, "label": "route 2: not applicable", "skipped": str(err),
                        "wall_time_s": clock() - start}
    if result is None:
        return {"route": None, "label": "route 2: MuJoCo refuses the file", "error": refusals[-1]["reason"] if refusals
                else "no attempt", "refusals": refusals, "wall_time_s": clock() - start}
    if result.route == "mujoco-urdf":
        label = "route 2: MuJoCo's own URDF import of the file as written"
    elif sphere is None:
        label = "route 2, REPAIRED: MuJoCo refused the file; compared on the project's repaired text"
    else:
        label = (f"route 2, REPAIRED: MuJoCo refused the file; compared on the project's repaired text with a "
                 f"{sphere * 1e3:g} g sphere on each massless moving link on both sides")
    return {
        "label": label,
        "route": result.route,
        "refusal": result.refusal,
        "refusals": refusals,
        "max_rel_error_A": result.max_rel_error_A,
        "max_rel_error_bias": result.max_rel_error_bias,
        "max_rel_error": result.max_rel_error,
        "max_rel_error_damping": result.max_rel_error_damping,
        "states": result.states,
        "seed": seed,
        "notes": list(result.notes),
        "wall_time_s": clock() - start,
    }


def _import(robot, inertia: str, base_opts: dict):
    """The project's import of ``robot`` with route 2's options (:data:`_ROUTE2_LOAD`)."""
    from urdf2links.parsers.importer import load_urdf

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return load_urdf(robot, floating_base=False, inertia=inertia, mimic="independent", **base_opts)


@contextmanager
def _urdf_file(scene: Scene):
    """The scene's robot as a URDF file for MuJoCo's own import: the file itself, or a ``.xacro``
    robot expanded (with the scene's ``xacro_args``) into a temporary file."""
    if not is_xacro_path(scene.robot):
        yield Path(scene.robot)
        return
    opts = scene.load_options
    text = expand_xacro(scene.robot, xacro_args=opts.get("xacro_args"), package_dirs=opts.get("package_dirs", ()))
    with tempfile.TemporaryDirectory(prefix="urdf2links_route2_") as folder:
        path = Path(folder) / f"{robot_stem(scene.robot)}.urdf"
        path.write_text(text)
        yield path


def _urdf_dampers(model) -> dict:
    """``{coordinate: c}``: the URDF damping of the model's one-coordinate joints (what MuJoCo's own
    URDF import reads as ``dof_damping``)."""
    return {j["coordinates"][0]: float(j["damping"]) for j in model.info.get("joints", [])
            if j.get("damping") and j["type"] in ("revolute", "continuous", "prismatic") and len(j["coordinates"]) == 1}


def _attempt(how: str, sphere: float | None) -> str:
    if sphere is not None:
        return (f"the project's repair (inertia='repair') plus a {sphere * 1e3:g} g sphere on each massless "
                "moving link, on both sides")
    return "the file as written" if how != "repair" else "the project's repair written into the text (inertia='repair')"

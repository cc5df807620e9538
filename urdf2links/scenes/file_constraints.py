"""An MJCF file's equalities and fixed tendons as a scene's constraints (E68)-(E70) and tendons (E76).

Every scene of an MJCF robot (issue 45: on by default, as in MuJoCo; ``[constraints] from_file = false`` or
``--open-loops`` says otherwise, :func:`open_loops`) makes the file's active ``connect``,
``weld``, ``joint`` and ``tendon`` (of fixed tendons: E70 on their lengths) equalities (``model.info["equalities"]``, read by
:mod:`urdf2links.parsers.mjcf_constraints`) constraints of the run, and its fixed tendons forces, with the
actuators whose transmission is a tendon when the scene names them (``[[actuator]] name = ...``,
``ctrl = ...``; MuJoCo's law (E55) on the tendon's length). A joint equality in MuJoCo's ``qpos`` becomes
one in the model's coordinates ``q = s qpos + o``: ``q_a - r_a = s_a sum_k c_k s_b^-k (q_b - r_b)^k`` with
``r = o + s qpos0``. :func:`plan_constraints` joins them with the scene's own ``[[constraint]]`` blocks and a URDF's
mimic couplings (:mod:`urdf2links.scenes.constraints`): the plan's constraints.
"""

from __future__ import annotations

import numpy as np

from ..errors import SceneError
from .actuators import Actuator
from ..dynamics.constraints import ConstraintSet
from .constraints import ConstraintSpec, SceneConstraints, mimic_specs, scene_constraints
from .tendons import FixedTendon, limit_tendon

__all__ = ["file_constraints", "plan_constraints", "tendon_actuator_names", "open_loops"]


def _coordinate(model, joint, where, eq):
    rows = [c for c in model.info.get("coordinates", []) if c.get("joint") == joint]
    if len(rows) != 1:
        raise SceneError(f"{where}: [constraints] from_file: equality {eq!r} names joint {joint!r}, which has "
                         f"{len(rows)} coordinates here (a hinge or slide has one)")
    c = rows[0]
    return c["name"], float(c.get("sign", 1.0)), float(c.get("offset", 0.0))


def _length(model, row, where, eq=None):
    """A fixed tendon ``row``'s length in the model's coordinates: ``(c (n,), o)`` with ``l = c . q + o``
    (``qpos = (q - offset) / sign``, E76)."""
    coef, offset = np.zeros(model.n), 0.0
    for joint, c in row["joints"]:
        name, s, o = _coordinate(model, joint, where, eq or row["name"])
        coef[model.coordinate_names.index(name)] += c / s
        offset -= c * o / s
    return coef, offset


def _tendon_equality(model, row, where) -> ConstraintSpec:
    """MuJoCo's tendon equality ``l_1 - l0_1 = sum_k c_k (l_2 - l0_2)^k`` as E70 on ``l = c . q + o``."""
    table = {t["name"]: t for t in model.info.get("tendons", [])}
    pairs = [(_length(model, table[t], where, row["name"]), l0)
             for t, l0 in ((row["tendon1"], row["length0_1"]), (row["tendon2"], row["length0_2"])) if t is not None]
    return ConstraintSpec(row["name"], "tendon", lengths=tuple(c for (c, _), _ in pairs),
                          coefficients=tuple(float(x) for x in row["polycoef"]),
                          reference=tuple(l0 - o for (_, o), l0 in pairs) + (0.0,) * (2 - len(pairs)),
                          source=f"MJCF <tendon> equality {row['name']!r}")


def _equality(model, row, where) -> ConstraintSpec:
    src = f"MJCF <{row['kind']}> {row['name']!r}"
    if row["kind"] == "tendon":
        return _tendon_equality(model, row, where)
    if row["kind"] == "joint":
        a, sa, oa = _coordinate(model, row["joint1"], where, row["name"])
        c = np.asarray(row["polycoef"], float)
        if row["joint2"] is None:
            return ConstraintSpec(row["name"], "joint", coordinates=(a,), coefficients=tuple(sa * c),
                                  reference=(oa + sa * row["qpos0_1"], 0.0), source=src)
        b, sb, ob = _coordinate(model, row["joint2"], where, row["name"])
        coef = tuple(sa * c[k] / sb ** k for k in range(5))
        return ConstraintSpec(row["name"], "joint", coordinates=(a, b), coefficients=coef,
                              reference=(oa + sa * row["qpos0_1"], ob + sb * row["qpos0_2"]), source=src)
    points = (np.asarray(row["anchor1"], float), np.asarray(row["anchor2"], float))
    if row["kind"] == "connect":
        return ConstraintSpec(row["name"], "connect", links=(row["body1"], row["body2"]), points=points, source=src)
    return ConstraintSpec(row["name"], "weld", links=(row["body1"], row["body2"]), points=points,
                          frames=(np.asarray(row["rel"], float), np.eye(3)), source=src)


def tendon_actuator_names(model) -> set:
    """The names of the file's actuators whose transmission is a tendon."""
    return {a for t in model.info.get("tendons", []) for a in t["actuators"]}


def _tendon(model, row, scene, where) -> FixedTendon:
    coef, offset = _length(model, row, where)      # the offset only shifts the length
    table = {a["name"]: a for a in model.info.get("actuators", [])}
    acts = []
    for spec in scene.actuators:
        if spec.coordinate is None and spec.name in row["actuators"]:
            a = table[spec.name]
            acts.append(Actuator(spec.name, row["name"], -1, a["kind"], a["gain"], tuple(a["bias"]), a["gear"],
                                 spec.ctrl, a["ctrlrange"], a["forcerange"], "file", row["name"], a.get("kp"),
                                 a.get("kv")))
    a, b = row["lengthspring"]
    return FixedTendon(row["name"], coef, row["stiffness"], row["damping"], (a - offset, b - offset), tuple(acts))


def _limit(model, row, td, scene, where) -> FixedTendon:
    """Issue 45: a limited tendon's limit law (E87) as the tendon ``<name>__limit`` (:func:`limit_tendon`)."""
    _, offset = _length(model, row, where)
    lo, hi = row["range"]
    try:
        return limit_tendon(model, td, (lo - offset, hi - offset), scene.initial_state(model)[0],
                            row.get("solref_lim", (0.02, 1.0)))
    except ValueError as err:
        raise SceneError(f"{where}: tendon {row['name']!r}: {err}") from None


def file_constraints(model, scene, where) -> tuple[list[ConstraintSpec], list[FixedTendon], list[str]]:
    """``(constraint specs, tendons, notes)`` of the file's active equalities and fixed tendons (none for a
    robot that is not an MJCF file: a URDF has no ``<equality>``; its ``<mimic>`` is ``[constraints] mimic``)."""
    if model.info.get("format") != "mjcf":
        return [], [], []
    specs, tendons, notes = [], [], []
    for row in model.info.get("equalities", []):
        if not row["supported"]:
            notes.append(f"equality {row['name']!r} ({row['kind']}) not modelled: {row['why']}")
        elif not row["active"]:
            notes.append(f"equality {row['name']!r} is inactive in the file (active=\"false\"): off on both engines")
        else:
            specs.append(_equality(model, row, where))
    for row in model.info.get("tendons", []):
        if not row["fixed"]:
            notes.append(f"tendon {row['name']!r} is spatial: not modelled")
            continue
        if row["frictionloss"]:
            notes.append(f"tendon {row['name']!r}: friction loss not modelled")
        td = _tendon(model, row, scene, where)
        if td.stiffness or td.damping or td.actuators:
            tendons.append(td)
        if row["limited"]:      # issue 45: the project's limit law on both engines (E87)
            tendons.append(_limit(model, row, td, scene, where))
            notes.append(f"tendon limit of {row['name']}: the project's law on both engines (E87: a one-sided "
                         f"spring past [{row['range'][0]:g}, {row['range'][1]:g}], tendon {row['name']}__limit; "
                         "MuJoCo's own soft limit disabled)")
    return specs, tendons, notes


def open_loops(scene, *, why: str = "--open-loops"):
    """``scene`` with the file's equalities and fixed tendons dropped and a URDF's mimic constraints off
    (``--open-loops``, the same as ``[constraints] from_file = false``), said in its notes (issue 45)."""
    import dataclasses

    if not scene.file_constraints and not scene.mimic_constraints:
        return scene
    note = (f"{why}: the file's own equalities and fixed tendons (and a URDF's mimic constraints) dropped on both "
            "engines; the verdict's scope says 'loops open'")
    return dataclasses.replace(scene, file_constraints=False, mimic_constraints=False,
                               notes=tuple(scene.notes) + (note,))


def _singular(scene, model) -> bool:
    """Whether the robot's own loops (the file's equalities, a URDF's mimic) cannot be solved: its mass matrix at
    the scene's initial state is not positive definite (massless links: the multipliers' solve, E72, and the
    projection, E74, need ``A^-1``). Then they are dropped on both engines and the verdict's scope counts them."""
    has = bool(model.info.get("equalities") or any(t.get("fixed") for t in model.info.get("tendons", []))
               or any(j.get("mimic") for j in model.info.get("joints", [])))
    if not has or model.n == 0:
        return False
    try:
        np.linalg.cholesky(model.mass_matrix(scene.initial_state(model)[0]))
    except np.linalg.LinAlgError:
        return True
    return False


def plan_constraints(scene, model) -> SceneConstraints | None:
    """The scene's ``[[constraint]]`` blocks and, unless the scene opens them (``[constraints] from_file =
    false``, ``--open-loops``), the file's equalities and fixed tendons (:func:`file_constraints`), on
    ``model``; None without any that act (the notes on what is not modelled are the model's own then)."""
    specs, tendons, notes = list(scene.constraints), [], []
    where = str(scene.path or scene.name)
    own = getattr(scene, "mimic_constraints", False) or getattr(scene, "file_constraints", False)
    if scene.base is not None and own:      # constraints with a moving base are not modelled: the file's own
        return scene_constraints(scene, model, specs)      # are dropped on both engines (the scope counts them)
    mimic_notes = []
    if own and not scene.constraints and _singular(scene, model):      # E72 needs A positive definite
        return None
    if getattr(scene, "mimic_constraints", False):
        specs = mimic_specs(model, where, mimic_notes) + specs
    if getattr(scene, "file_constraints", False):
        fs, tendons, notes = file_constraints(model, scene, where)
        specs = fs + specs
    notes = mimic_notes + list(notes)
    sc = scene_constraints(scene, model, specs)
    if tendons:
        sc = SceneConstraints(ConstraintSet(model, [] if sc is None else sc.cset.constraints), tuple(tendons),
                              list(notes))
    elif sc is not None:
        sc.notes = list(notes)
    return sc

"""Route 1 of the MuJoCo comparison: the project's OWN tree of links written as an MJCF model.

Same frames, same ``H``, same coordinates in the same order (through ``qpos_index`` /
``dof_index``), so that MuJoCo and the trace method integrate literally the same model and any
difference is the solver's or the integrator's (route 2, :mod:`urdf2links.compare.mujoco_side.mujoco_urdf`,
checks the importer instead).

The tree's links become nested ``<body>`` elements with joints and inertials
(:mod:`urdf2links.compare.mujoco_side.mjcf_bodies`: how a link's ``T~`` becomes a body with joints, massless
links, the moving base {A}); this module assembles the file around them, has MuJoCo compile it and returns
the :class:`~urdf2links.compare.mujoco_side.mjcf_model.MjcfModel` with MuJoCo's indices of the coordinates.

Physics switched off (everything the project does not model): contacts, limits, equality
constraints, friction loss; springs and dampers unless a spring/damper is given (then as joint
``stiffness``/``springref``/``damping``); armature the model's own on each coordinate's joint (E49;
not the shared armature of a ball's three angles,
:func:`~urdf2links.compare.mujoco_side.mjcf_bodies.route1_armature`); no geoms, inertias exactly as given
(``inertiafromgeom="false" balanceinertia="false" boundmass="0" boundinertia="0"``).

The scene's actuators are MuJoCo ``general`` actuators on their coordinates' joints (E55): written into the
MJCF here, and added to an ``MjSpec`` in the same form by route 2 (:func:`add_spec_actuators`).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Iterable
from xml.sax.saxutils import quoteattr

import mujoco
import numpy as np

from .mjcf_bodies import TINY_MASS_FRACTION, Bodies, fold_links, fold_notes, num, vec
from .mjcf_model import MjcfModel

__all__ = ["MjcfRefused", "mjcf_from_model", "mjcf_from_scene", "INTEGRATORS", "body_gravcomp", "add_spec_actuators"]


class MjcfRefused(ValueError):
    """MuJoCo's compiler refused the route-1 MJCF of a model (most often an inertia it will not take:
    a link whose principal moments are negative or break the triangle inequality, which the project's
    audit reports and ``inertia="repair"`` fixes). ``reason`` is MuJoCo's own text."""

    def __init__(self, model_name: str, reason: str):
        self.model_name, self.reason = model_name, reason
        super().__init__(f"MuJoCo refused the MJCF of model {model_name!r}: {reason}")


#: MJCF integrator names accepted (MuJoCo's spelling).
INTEGRATORS = ("Euler", "RK4", "implicit", "implicitfast")


def add_spec_actuators(spec, actuators, *, target) -> None:
    """The scene's actuators added to an ``MjSpec`` (route 2: MuJoCo's import of a URDF, an MJCF file as
    written) as route 1 writes them (:func:`_actuator_lines`): ``general``, dynamics none, gain fixed, bias
    affine, the gear, and both clamps when given (E55); actuator ``a`` on the joint named ``target(a)``."""
    for a in actuators:
        kw = dict(name=a.name, target=target(a), trntype=mujoco.mjtTrn.mjTRN_JOINT,
                  dyntype=mujoco.mjtDyn.mjDYN_NONE, gaintype=mujoco.mjtGain.mjGAIN_FIXED,
                  biastype=mujoco.mjtBias.mjBIAS_AFFINE, gainprm=[a.gain] + [0.0] * 9,
                  biasprm=list(a.bias) + [0.0] * 7, gear=[a.gear, 0, 0, 0, 0, 0],
                  ctrllimited=int(a.ctrlrange is not None), forcelimited=int(a.forcerange is not None))
        if a.ctrlrange is not None:
            kw["ctrlrange"] = list(a.ctrlrange)
        if a.forcerange is not None:
            kw["forcerange"] = list(a.forcerange)
        spec.add_actuator(**kw)


def _actuator_lines(actuators) -> list[str]:
    """The scene's actuators (:mod:`urdf2links.scenes.actuators`) as MuJoCo ``general`` actuators on their
    coordinates' joints: dynamics none, gain fixed, bias affine, the gear, and both clamps when given (E55)."""
    if not actuators:
        return []
    out = ["  <actuator>"]
    for a in actuators:
        rng = ""
        if a.ctrlrange is not None:
            rng += f' ctrllimited="true" ctrlrange="{vec(a.ctrlrange)}"'
        else:
            rng += ' ctrllimited="false"'
        if a.forcerange is not None:
            rng += f' forcelimited="true" forcerange="{vec(a.forcerange)}"'
        else:
            rng += ' forcelimited="false"'
        out.append(f'    <general name={quoteattr(a.name)} joint={quoteattr(a.coordinate)} dyntype="none" gaintype="fixed" '
                   f'biastype="affine" gainprm="{num(a.gain)}" biasprm="{vec(a.bias)}" gear="{num(a.gear)}"{rng}/>')
    return out + ["  </actuator>"]


def _document(model, body_lines, g, springs, timestep, integrator, actuators=(), gravcomp=False) -> tuple[str, str]:
    """The whole MJCF text around the bodies (only the scene's physics enabled) and its note. With
    ``gravcomp`` the spring flag stays on (every stiffness 0): MuJoCo's ``mj_passive``, which applies body
    gravcomp, does nothing when springs and dampers are both disabled."""
    has_spring = any(s.stiffness > 0 for s in springs) or gravcomp
    has_damper = any(s.damping > 0 for s in springs)
    flags = ['contact="disable"', 'limit="disable"', 'equality="disable"', 'frictionloss="disable"']
    if not has_spring:
        flags.append('spring="disable"')
    if not has_damper:
        flags.append('damper="disable"')
    gtxt = "0 0 0" if g is None else vec(g)
    head = [
        f"<mujoco model={quoteattr('route1_' + (model.name or 'robot'))}>",
        '  <compiler angle="radian" inertiafromgeom="false" balanceinertia="false" boundmass="0" '
        'boundinertia="0" autolimits="false"/>',
        f'  <option timestep="{num(timestep)}" integrator="{integrator}" gravity="{gtxt}">',
        f"    <flag {' '.join(flags)}/>",
        "  </option>",
        "  <default>",
        '    <joint armature="0" damping="0" stiffness="0" frictionloss="0" limited="false"/>',
        "  </default>",
        "  <worldbody>",
    ]
    xml = "\n".join(head + body_lines + ["  </worldbody>"] + _actuator_lines(actuators) + ["</mujoco>", ""])
    note = ("gravity " + ("off (0 0 0)" if g is None else f"{g.tolist()} m/s^2")
            + "; disabled: contact, limit, equality, frictionloss"
            + ("" if has_spring else ", spring") + ("" if has_damper else ", damper")
            + "; armature " + ("the model's (E49)" if model.tree.has_armature else "0")
            + f"; no geoms; integrator {integrator}, timestep {timestep:g} s"
            + (f"; {len(actuators)} general actuator(s) on their coordinates' joints (MuJoCo's law, E55)" if actuators
               else ""))
    return xml, note


def _spring_map(names, springs) -> dict:
    spring_of: dict[str, object] = {}
    for s in springs:
        if s.coordinate not in names:
            raise KeyError(f"spring on unknown coordinate {s.coordinate!r}; coordinates are {list(names)}")
        spring_of[s.coordinate] = s
    return spring_of


def _check_model(model, integrator, timestep, moving_base: bool = False) -> tuple[list[bool], list[str]]:
    """Refuse what route 1 cannot write; returns which links are written massless, and notes.

    A link with zero mass but non-zero second moments is no physical body, and MuJoCo has no such
    body. When no coordinate moves it and the base is fixed, it has no effect on the equations
    (A, e and G involve moving links only): it is written without inertia, and noted. When it moves,
    :class:`MjcfRefused` names it and the fix."""
    if model.coupling is not None:
        raise ValueError(f"model {model.name!r} has coupled coordinates (mimic='coupled'); route 1 "
                         "builds the tree's own coordinates only: load with mimic='independent'")
    if integrator not in INTEGRATORS:
        raise ValueError(f"integrator must be one of {INTEGRATORS}, got {integrator!r}")
    if not (timestep > 0 and math.isfinite(timestep)):
        raise ValueError(f"timestep must be a positive number, got {timestep!r}")
    tree = model.tree
    mass = tree.H[:, 3, 3]
    massless = [bool(np.all(tree.H[p] == 0.0)) for p in range(tree.n_links)]
    moves = [False] * tree.n_links          # a coordinate on the path from {A} to the link
    for p in range(tree.n_links):           # parents come before their children
        par = int(tree.parent[p])
        moves[p] = bool(np.any(tree.coord[p] >= 0)) or (par >= 0 and moves[par])
    notes, static = [], []
    for p in range(tree.n_links):
        if mass[p] == 0.0 and not massless[p]:
            if not moves[p] and not moving_base:
                massless[p] = True
                static.append(tree.link_names[p])
                continue
            raise MjcfRefused(model.name, f"link {tree.link_names[p]!r} has zero mass but non-zero second moments: "
                              "no physical body has that, and MuJoCo cannot represent it. Load the robot with "
                              "--inertia repair (inertia='repair': its inertia from its geometry, noted in the "
                              "audit), or give the link a mass in the file")
    if static:
        notes.append(f"links with zero mass but non-zero second moments that nothing moves (welded to a fixed base; "
                     f"no effect on A, e or G) written without inertia: {', '.join(static)}")
    return massless, notes



def mjcf_from_model(model, *, gravity=None, springs: Iterable = (), moving_base: bool = False,
                    timestep: float = 1e-4, integrator: str = "RK4", actuators: Iterable = (),
                    gravcomp: dict | None = None) -> MjcfModel:
    """The project's tree of ``model`` as an MJCF model compiled by MuJoCo (see module doc).

    Parameters
    ----------
    model : urdf2links.dynamics.model.Model (uncoupled: mimic joints as independent coordinates)
    gravity : None (no gravity: ``0 0 0``) or (3,) m/s^2 in {0}; e.g. ``model.gravity_vector``.
    springs : iterable of :class:`urdf2links.scenes.scene.Spring` (coordinate, stiffness, rest, damping):
        joint ``stiffness``/``springref``/``damping``; MuJoCo's spring (damper) flag stays enabled
        only when some stiffness (damping) is positive.
    moving_base : add the ``base_A`` body carrying the six base parameters as joints.
    timestep, integrator : MuJoCo's ``<option>``; integrator one of :data:`INTEGRATORS`.
    actuators : resolved actuators (:class:`urdf2links.scenes.actuators.Actuator`), written as ``<general>``
        on their coordinates' joints, in order (MuJoCo's actuator ``k`` is ``actuators[k]``).
    gravcomp : ``{tree link index: factor}`` written as the bodies' ``gravcomp`` (:func:`body_gravcomp`).
    """
    massless, check_notes = _check_model(model, integrator, timestep, moving_base)
    tree = model.tree
    names = tuple(model.coordinate_names)
    g = None if gravity is None else np.asarray(gravity, float).reshape(3)
    springs = tuple(springs)
    total_mass = float(tree.H[:, 3, 3].sum())
    folded, too_many = fold_links(tree, massless)
    tiny = TINY_MASS_FRACTION * max(total_mass, 1.0)
    bodies = Bodies(model, names, _spring_map(names, springs), folded, massless, tiny)
    bodies.gravcomp = dict(gravcomp or {})
    actuators = tuple(actuators)
    for a in actuators:
        if a.coordinate not in names:
            raise KeyError(f"actuator {a.name!r} on unknown coordinate {a.coordinate!r}; coordinates are {list(names)}")
    base_joint_names, bname = bodies.write(moving_base=moving_base, total_mass=total_mass)
    notes = bodies.notes
    notes += check_notes + fold_notes(tree, folded, too_many, bodies.tiny_links, tiny)
    if bodies.ball_armature:
        notes.append("armature of the three angles of " + ", ".join(bodies.ball_armature) + " (on their angular "
                     "velocity, E49) left out: route 1 writes them as three hinges, where it has no equivalent; "
                     "route 1's terms are compared without it")
    xml, note = _document(model, bodies.lines, g, springs, timestep, integrator, actuators, bool(gravcomp))
    notes.append(note)
    try:
        mm = mujoco.MjModel.from_xml_string(xml)
    except ValueError as err:
        raise MjcfRefused(model.name, str(err).strip()) from None
    out = _compiled(mm, xml, model, names, base_joint_names, bname, bodies, folded, g, springs, notes)
    return dataclasses.replace(out, actuators=actuators, gravcomp_in_bodies=bool(gravcomp))


def _compiled(mm, xml, model, names, base_joint_names, bname, bodies, folded, g, springs, notes) -> MjcfModel:
    """The :class:`MjcfModel`: MuJoCo's indices of the coordinates, the base and the bodies."""
    tree = model.tree
    L, n = tree.n_links, tree.n

    def jid(name):
        return mujoco.mj_name2id(mm, mujoco.mjtObj.mjOBJ_JOINT, name)

    qpos_index = np.array([mm.jnt_qposadr[jid(nm)] for nm in names], dtype=np.int64)
    dof_index = np.array([mm.jnt_dofadr[jid(nm)] for nm in names], dtype=np.int64)
    if bname is not None:
        base_qpos = np.array([mm.jnt_qposadr[jid(nm)] for nm in base_joint_names], dtype=np.int64)
        base_dofs = np.array([mm.jnt_dofadr[jid(nm)] for nm in base_joint_names], dtype=np.int64)
        base_body = mujoco.mj_name2id(mm, mujoco.mjtObj.mjOBJ_BODY, bname)
    else:
        base_qpos = base_dofs = np.zeros(0, dtype=np.int64)
        base_body = -1
    body_of_link = np.full(L, -1, dtype=np.int64)
    for p, bn in bodies.body_name_of.items():
        body_of_link[p] = mujoco.mj_name2id(mm, mujoco.mjtObj.mjOBJ_BODY, bn)
    host = body_of_link.copy()
    for p in range(L - 1, -1, -1):  # a folded link's only child comes after it
        if folded[p]:
            host[p] = host[tree.children[p][0]]
    if mm.nv != n + (6 if bname is not None else 0):
        raise AssertionError(f"MJCF has {mm.nv} dofs, expected {n}")
    for a in (qpos_index, dof_index, base_qpos, base_dofs, body_of_link, host):
        a.setflags(write=False)
    folded_names = tuple(tree.link_names[p] for p in range(L) if folded[p])
    return MjcfModel(
        xml=xml, model=mm, qpos_index=qpos_index, dof_index=dof_index, base_dofs=base_dofs,
        base_qpos=base_qpos, body_of_link=body_of_link, host_body=host, coordinate_names=names,
        source=model, gravity=g, springs=springs, folded_links=folded_names,
        tiny_mass_links=tuple(bodies.tiny_links), base_body=int(base_body), notes=notes,
    )


def mjcf_from_scene(scene, model, *, timestep: float | None = None, integrator: str | None = None) -> MjcfModel:
    """:func:`mjcf_from_model` with a scene's gravity, springs and dampers (URDF damping included when
    the scene asks, :meth:`~urdf2links.scenes.scene.Scene.springs_for`) and base; ``timestep`` defaults to
    the scene's ``run.dt`` (else 1e-4 s), ``integrator`` to RK4 when the scene names none of
    MuJoCo's."""
    from urdf2links.scenes.actuators import resolve_actuators

    scene.check_names(model)
    dt = timestep if timestep is not None else (scene.run.dt or 1e-4)
    integ = integrator if integrator is not None else (scene.run.method if scene.run.method in INTEGRATORS else "RK4")
    actuators = resolve_actuators(scene.actuators, model, where=str(scene.path or scene.name)).actuators
    gravcomp, note = body_gravcomp(model, scene.gravcomp_table(model) if scene.gravity is not None else {})
    mj = mjcf_from_model(model, gravity=scene.gravity, springs=scene.springs_for(model).springs,
                         moving_base=scene.base is not None, timestep=dt, integrator=integ, actuators=actuators,
                         gravcomp=gravcomp)
    if note:
        mj.notes.append(note)
    return mj


def body_gravcomp(model, table: dict) -> tuple[dict, str | None]:
    """``({tree link index: factor}, note)``: a scene's gravcomp (``{body: factor}``, URDF links or MJCF
    bodies) as route 1's bodies' own ``gravcomp`` (MuJoCo applies ``-gravcomp m g`` at each body's COM
    through ``qfrc_passive``). A route-1 body is a tree link, the union of the bodies folded into it: its
    own gravcomp is exact when every body of it with mass has the same factor (the parallel forces then
    sum to ``-f M g`` at the union's COM). Otherwise none is written (empty dict) and the note says the
    scene's gravcomp is applied as loads through the control callback instead."""
    if not table:
        return {}, None
    frame_of = model.info.get("frame_of") or {}
    masses = model.info.get("body_mass_com", {})
    index = {nm: i for i, nm in enumerate(model.tree.link_names)}
    factors: dict[int, set] = {}
    for body, (m, _) in masses.items():
        if m > 0.0 and body in frame_of:
            factors.setdefault(index[frame_of[body][0]], set()).add(float(table.get(body, 0.0)))
    mixed = [model.tree.link_names[t] for t, f in factors.items() if len(f) > 1]
    if mixed:
        return {}, (f"gravcomp: the bodies folded into tree link(s) {', '.join(mixed[:6])} have different factors, "
                    "which no single MuJoCo body gravcomp represents: route 1 applies the scene's gravcomp as loads "
                    "(xfrc_applied from the control callback)")
    out = {t: f.pop() for t, f in factors.items()}
    return {t: f for t, f in out.items() if f != 0.0}, ("gravcomp written as the bodies' own gravcomp (MuJoCo's "
                                                        "qfrc_passive, as body gravcomp acts in MuJoCo)")

"""The inventory of an MJCF model: every element the tree of links does not use, and what the comparison does about it.

Nothing is dropped silently (docs/importing.md, "MJCF"): :func:`inventory` lists, from MuJoCo's
compiled model, the geoms and contacts, tendons, equality constraints, actuators, sensors, sites,
cameras, lights, flex objects and skins, plugins, keyframes, mocap bodies, joint limits and friction
loss, the fluid forces of ``<option>``, and the joint effects the tree cannot carry (springs and dampers
of ball and free joints). Each note says what the comparison does: MuJoCo's run of the file switches
the same thing off (:data:`MUJOCO_OFF`), so both engines run the same physics.
"""

from __future__ import annotations

import numpy as np

__all__ = ["inventory", "MUJOCO_OFF"]

#: What MuJoCo's run of an MJCF file switches off (``mjtDisableBit`` names): contacts, every constraint
#: (equality, limits, friction loss), and actuation unless the scene names actuators (then the ones it
#: does not name are switched off one by one). The file's own equalities and fixed tendons are switched back on
#: (issue 45: by default; :func:`urdf2links.compare.mujoco_side.mujoco_constraints.route2_constraints`).
MUJOCO_OFF = ("mjDSBL_CONTACT", "mjDSBL_CONSTRAINT", "mjDSBL_EQUALITY", "mjDSBL_LIMIT", "mjDSBL_FRICTIONLOSS",
              "mjDSBL_ACTUATION")


def _keyframes(m) -> str:
    """How the runs use the file's keyframes (issue 43): the default scene starts around the one named ``home``
    (urdf2links.scenes.excitation, E65); the others are not used."""
    import mujoco

    names = [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_KEY, k) for k in range(m.nkey)]
    scene = "a scene file's [initial] starts where it says"
    if "home" in names:
        others = "; the other keyframes are not used" if m.nkey > 1 else ""
        return ("keyframe 'home' centres the default scene's start: its q0 is drawn within a quarter of each joint's "
                f"range around home's qpos and its q' excites the joints (E65); --q0 random draws within the limits "
                f"and --q0 rest starts at MuJoCo's qpos0, not at home{others}; {scene}")
    return ("not used: none is named 'home' (the keyframe the default scene starts around); the default scene starts "
            f"within the joint limits or around MuJoCo's qpos0; {scene}")


def _names(m, kind, count, limit=8) -> str:
    import mujoco

    obj = getattr(mujoco.mjtObj, kind)
    names = [mujoco.mj_id2name(m, obj, i) or f"#{i}" for i in range(count)]
    shown = ", ".join(names[:limit])
    return shown + (f", ... ({count} in all)" if count > limit else "")


def inventory(m, joint_kinds: dict) -> list[str]:
    """Notes on the compiled ``mujoco.MjModel`` ``m`` (see the module doc); ``joint_kinds`` maps a
    joint id to ``hinge``, ``slide``, ``ball`` or ``free``."""
    notes = []

    def add(count, what, doing):
        if count:
            notes.append(f"{what}: {doing}")

    add(m.ngeom, f"{m.ngeom} geom(s) ({_names(m, 'mjOBJ_GEOM', m.ngeom)})",
        "not part of the dynamics (their mass and inertia are in the bodies' compiled inertia when the "
        "compiler took inertia from geometry); contacts are not modelled and MuJoCo's run disables them")
    add(m.npair + m.nexclude, f"{m.npair} contact pair(s), {m.nexclude} exclude(s)", "contacts are disabled on both sides")
    add(m.ntendon, f"{m.ntendon} tendon(s) ({_names(m, 'mjOBJ_TENDON', m.ntendon)})",
        "fixed tendons are read (stiffness, damping, spring length, actuators on them; E76) and act in every scene, as in "
        "MuJoCo (issue 45); a limited one gets the project's limit law on both engines (E87: a one-sided spring past "
        "its range, MuJoCo's own soft limit disabled); --open-loops or [constraints] from_file = false drops them "
        "(MuJoCo's run then zeroes their stiffness and damping); spatial tendons and tendon friction loss are not "
        "modelled")
    add(m.neq, f"{m.neq} equality constraint(s) ({_names(m, 'mjOBJ_EQUALITY', m.neq)})",
        "connect, weld and joint are read (E68-E70; tendon equalities of fixed tendons too: E70 on their lengths) and "
        "act in every scene on both engines, as in MuJoCo (issue 45; urdf2links inspect --scene shows them); an "
        "inactive one (active=\"false\") is off on both and listed in the verdict's scope; --open-loops or "
        "[constraints] from_file = false drops them (the joints stay independent, MuJoCo's run disables them, the "
        "scope says 'loops open')")
    add(m.nu, f"{m.nu} actuator(s) ({_names(m, 'mjOBJ_ACTUATOR', m.nu)})",
        "scene effects when a scene names them ([[actuator]] name = '...', ctrl = ...: MuJoCo's law on both engines; "
        "one on a fixed tendon through its tendon, unless the loops are open; one on a site or a spatial tendon is "
        "refused); "
        "the others act on neither engine (MuJoCo's run switches them off)")
    add(m.nsensor, f"{m.nsensor} sensor(s)", "not used (they do not change the dynamics)")
    add(m.nsite, f"{m.nsite} site(s)", "not used (frames only)")
    add(m.ncam + m.nlight, f"{m.ncam} camera(s), {m.nlight} light(s)", "not used")
    add(m.nflex, f"{m.nflex} flex object(s)", "their vertices' bodies and joints are read as links; the flex's "
        "elasticity and collisions are not modelled (MuJoCo's run disables contacts; its passive flex forces "
        "remain MuJoCo's own: compare such a model with care)")
    add(m.nskin, f"{m.nskin} skin(s)", "visual only, not used")
    add(m.nplugin, f"{m.nplugin} plugin instance(s)", "not modelled: a plugin's forces are MuJoCo's alone")
    add(m.nkey, f"{m.nkey} keyframe(s) ({_names(m, 'mjOBJ_KEY', m.nkey)})", _keyframes(m))
    add(m.nmocap, f"{m.nmocap} mocap body(ies)", "welded to the world where the file puts them")
    limited = [j for j in range(m.njnt) if m.jnt_limited[j]]
    add(len(limited), f"{len(limited)} joint(s) with limits ({_names(m, 'mjOBJ_JOINT', 0) or ''}"
        + ", ".join(_joint_name(m, j) for j in limited[:8]) + (", ..." if len(limited) > 8 else "") + ")",
        "limits are not enforced (runs note when a joint leaves them), and MuJoCo's run disables them")
    friction = [j for j in range(m.njnt) if np.any(m.dof_frictionloss[m.jnt_dofadr[j]:m.jnt_dofadr[j] + _ndof(joint_kinds[j])])]
    add(len(friction), f"friction loss on joint(s) {', '.join(_joint_name(m, j) for j in friction[:8])}",
        "Coulomb friction is not modelled; MuJoCo's run disables it")
    fluid = [f"{k} {v}" for k, v in (("density", m.opt.density), ("viscosity", m.opt.viscosity)) if v != 0.0]
    if np.any(m.opt.wind):
        fluid.append(f"wind {m.opt.wind.tolist()}")
    add(len(fluid), f"<option> fluid forces ({', '.join(fluid)})",
        "not modelled; MuJoCo's run sets density, viscosity and wind to 0")
    for j, kind in joint_kinds.items():
        if kind not in ("ball", "free"):
            continue
        dofs = slice(m.jnt_dofadr[j], m.jnt_dofadr[j] + _ndof(kind))
        effects = [w for w, on in (("stiffness", m.jnt_stiffness[j] != 0.0), ("damping", np.any(m.dof_damping[dofs])))
                   if on]
        add(len(effects), f"{kind} joint {_joint_name(m, j)!r} has {' and '.join(effects)}",
            "not modelled on a ball or free joint (only on hinges and slides); MuJoCo's run zeroes it")
    return notes


def _ndof(kind: str) -> int:
    return {"hinge": 1, "slide": 1, "ball": 3, "free": 6}[kind]


def _joint_name(m, j: int) -> str:
    import mujoco

    return mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, j) or f"joint{j}"

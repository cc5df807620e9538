"""MuJoCo's own contact as a reference for a ``[[contact]]`` scene (issue 37, docs/equations.md (E84)).

The route-1 model with contacts switched on: a plane geom (the scene's ground) and a sphere geom at every
contact sphere (on the body of its tree link; ``contype``/``conaffinity`` so that only spheres and planes
collide), ``condim 3``, friction ``mu``, ``solimp (0.99, 0.99, 0.001)`` and a direct ``solref``
``(-k_lin / m_c, -c_lin / m_c)`` from the law linearised at the static depth of the weight shared by the
spheres (:func:`native_parameters`). MuJoCo's friction is hard Coulomb and its normal force a soft
constraint: the run is another model of the ground, not an error; :func:`native_run` runs it and
:func:`native_figures` says how far it lands from the project's compliant law (base height, feet positions and
slip, time to settle).
"""

from __future__ import annotations

import dataclasses
import xml.etree.ElementTree as ET
from dataclasses import dataclass

import mujoco
import numpy as np

from .mujoco_run import run_mujoco

__all__ = ["NativeParameters", "native_parameters", "native_mjcf", "native_run", "contact_points", "native_figures",
           "settle_time", "SOLIMP", "SETTLE_FRACTION"]

SOLIMP = (0.99, 0.99, 0.001)
#: A run has settled when its kinetic energy stays below this fraction of its largest.
SETTLE_FRACTION = 1e-3
#: the spheres' contype is the plane's conaffinity (and neither has the other bit): spheres touch planes only
_CONTACT_BIT = 2


@dataclass(frozen=True)
class NativeParameters:
    """MuJoCo's contact parameters for one ``[[contact]]`` block (E84), and the linearisation they come from."""

    solref: tuple[float, float]
    solimp: tuple[float, float, float]
    friction: float
    static_depth: float
    k_lin: float
    c_lin: float
    mass_per_sphere: float

    def describe(self) -> str:
        return (f"solref ({self.solref[0]:.4g}, {self.solref[1]:.4g}) (direct: -k_lin/m_c, -c_lin/m_c), solimp "
                f"{self.solimp}, condim 3, friction {self.friction:g}; from the law at its static depth "
                f"{self.static_depth * 1e3:.3g} mm (k_lin {self.k_lin:.4g} N/m, c_lin {self.c_lin:.4g} N s/m, "
                f"m_c {self.mass_per_sphere:.4g} kg per sphere)")


def native_parameters(plan, spec, n_spheres: int, g: float = 9.81) -> NativeParameters:
    """(E84): the static depth ``d_s`` where ``k d_s^e = m g / N``, ``k_lin = e k d_s^(e-1)``, ``c_lin`` the
    damping there (``c d_s^e`` Hunt-Crossley, ``c`` spring-damper), ``m_c = m / N``."""
    mass = float(np.sum(np.asarray(plan.model.tree.H)[:, 3, 3]))
    m_c = mass / max(n_spheres, 1)
    e, k, c = spec.exponent, spec.stiffness, spec.damping
    d_s = (m_c * g / k) ** (1.0 / e)
    k_lin = e * k * d_s ** (e - 1.0)
    c_lin = c * d_s ** e if spec.law == "hunt_crossley" else c
    return NativeParameters((-k_lin / m_c, -c_lin / m_c), SOLIMP, spec.friction, d_s, k_lin, c_lin, m_c)


def _plane_axes(normal) -> str:
    return " ".join(f"{float(x):.17g}" for x in normal)


def native_mjcf(mj, plan):
    """``(MjcfModel, notes)``: route 1 ``mj`` with MuJoCo's contacts on, the plane and the spheres as geoms."""
    root = ET.fromstring(mj.xml)
    flag = root.find("option/flag")
    if flag is not None and "contact" in flag.attrib:
        del flag.attrib["contact"]
    world = root.find("worldbody")
    bodies = {b.get("name"): b for b in root.iter("body")}
    rows, notes = plan.contact_set.rows, []
    specs = list({id(r[3]): r[3] for r in rows}.values())
    for i, spec in enumerate(specs):
        mine = [r for r in rows if r[3] is spec]
        prm = native_parameters(plan, spec, len(mine))
        attrs = dict(condim="3", friction=f"{spec.friction:.17g} 0.005 0.0001", solimp=" ".join(map(str, prm.solimp)),
                     solref=f"{prm.solref[0]:.17g} {prm.solref[1]:.17g}", margin="0")
        h = mine[0][4]
        ET.SubElement(world, "geom", dict(name=f"ground{i}", type="plane", size="0 0 1",
                                          pos=" ".join(f"{h * x:.17g}" for x in spec.normal), zaxis=_plane_axes(spec.normal),
                                          contype="0", conaffinity=str(_CONTACT_BIT), **attrs))
        for j, (link, centre, radius, _, _) in enumerate(mine):
            b = int(mj.body_of_link[link])
            if b < 0:
                raise ValueError(f"{plan.scene.name}: contact sphere on link {plan.model.tree.link_names[link]!r}, "
                                 "which route 1 folded into its child (no MuJoCo body): no native contact for it")
            body = bodies[mujoco.mj_id2name(mj.model, mujoco.mjtObj.mjOBJ_BODY, b)]
            ET.SubElement(body, "geom", dict(name=f"contact{i}_{j}", type="sphere", size=f"{max(radius, 1e-4):.17g}",
                                             pos=" ".join(f"{x:.17g}" for x in centre), contype=str(_CONTACT_BIT),
                                             conaffinity="0", rgba="0.9 0.3 0.2 1", **attrs))
        notes.append(f"contact[{i}]: {prm.describe()}")
    xml = ET.tostring(root, encoding="unicode")
    return dataclasses.replace(mj, xml=xml, model=mujoco.MjModel.from_xml_string(xml), notes=list(mj.notes) + notes), notes


def native_run(mj, plan, *, t_end=None, samples=None):
    """``(MujocoRun, notes)``: the scene with MuJoCo's own contact instead of the law (the other inputs as in
    the comparison: the scene's plan without its ``[[contact]]``, compiled)."""
    from urdf2links.scenes.plan import compile_plan

    native, notes = native_mjcf(mj, plan)
    bare = compile_plan(dataclasses.replace(plan.scene, contacts=()), plan.model)
    return run_mujoco(native, bare, t_end=t_end, samples=samples), notes


def contact_points(plan, q) -> np.ndarray:
    """(m, k, 3): every contact sphere's lowest point (E77) at the states ``q`` (m, n)."""
    rows = plan.contact_set.rows
    out = np.empty((len(q), len(rows), 3))
    for s, qs in enumerate(q):
        T = plan.model.link_poses(qs)
        for j, (link, centre, radius, spec, _) in enumerate(rows):
            out[s, j] = T[link, :3, :3] @ centre + T[link, :3, 3] - radius * spec.normal
    return out


def settle_time(t, kinetic) -> float | None:
    """The first time after which the kinetic energy stays below :data:`SETTLE_FRACTION` of its largest
    (None when it never does)."""
    kinetic = np.asarray(kinetic, float)
    low = kinetic <= SETTLE_FRACTION * max(float(kinetic.max()), 1e-300)
    if not low[-1]:
        return None
    k = len(low) - 1
    while k > 0 and low[k - 1]:
        k -= 1
    return float(t[k])


def native_figures(plan, ours_t, ours_q, ours_kinetic, run) -> dict:
    """How far MuJoCo's native contact lands from the compliant law: the root link's height, every contact
    point's final position and its slip (horizontal travel while the sphere touches, summed), the settle
    times; the project's trajectory sampled at MuJoCo's times."""
    p_o, p_m = contact_points(plan, ours_q), contact_points(plan, run.q)
    T_o = np.array([plan.model.link_poses(q)[0, :3, 3] for q in ours_q])
    T_m = np.array([plan.model.link_poses(q)[0, :3, 3] for q in run.q])
    heights = np.array([r[4] for r in plan.contact_set.rows])
    normals = np.array([r[3].normal for r in plan.contact_set.rows])

    def slip(p):
        touch = (heights - np.einsum("skj,kj->sk", p, normals))[1:] > -1e-4     # in contact (within 0.1 mm)
        step = np.diff(p, axis=0)
        tang = step - np.einsum("skj,kj->sk", step, normals)[..., None] * normals
        return np.sum(np.linalg.norm(tang, axis=2) * touch, axis=0)
    s_o, s_m = slip(p_o), slip(p_m)
    return {
        # issue 43: the root link's z in the world (each engine's own), its lowest, and the ground's height under it
        "base_height": {"ours_final": float(T_o[-1, 2]), "native_final": float(T_m[-1, 2]),
                        "ours_min": float(T_o[:, 2].min()), "native_min": float(T_m[:, 2].min()),
                        "ground": float(heights[0]) if np.allclose(normals, [0.0, 0.0, 1.0]) else None,
                        "max_difference": float(np.max(np.abs(T_o[:, 2] - T_m[:, 2])))},
        "feet": {"final_max_distance": float(np.max(np.linalg.norm(p_o[-1] - p_m[-1], axis=1))),
                 "slip_ours_max": float(s_o.max()), "slip_native_max": float(s_m.max()),
                 "links": [plan.model.tree.link_names[r[0]] for r in plan.contact_set.rows]},
        "settle_time": {"ours": settle_time(ours_t, ours_kinetic), "native": settle_time(run.t, run.kinetic)},
        "max_abs_q_difference": float(np.max(np.abs(ours_q - run.q))),
        "native_blow_ups": dict(run.blow_ups),
    }

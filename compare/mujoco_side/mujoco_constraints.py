"""The scene's constraints and fixed tendons in MuJoCo (issue 36): route 1 writes them as MJCF equalities.

:func:`with_constraints` takes the route-1 model (:func:`~urdf2links.compare.mujoco_side.mjcf.mjcf_from_scene`:
the project's tree, equality disabled) and adds, through MuJoCo's ``MjSpec``:

- a ``connect`` (E68) as two sites at the two points and ``<connect site1 site2>`` (site semantic: the sites
  coincide; no anchor computed at ``qpos0``, where a loop need not be closed);
- a ``weld`` (E69) as two sites carrying the two frames and ``<weld site1 site2>``;
- a ``joint`` coupling (E70) as ``<joint joint1 joint2 polycoef>``: route 1's ``qpos`` is ``q`` and its
  ``qpos0`` is 0, so the polynomial ``q_a = r_a + p(q_b - r_b)`` is re-expanded about 0;
- a ``tendon`` equality the same way on two fixed tendons written for it (``<tendon tendon1 tendon2>``);
- a fixed tendon (E76) as ``<tendon><fixed>`` with its stiffness, damping and spring length, and its
  actuators as ``<general tendon=...>`` (MuJoCo's law, E55);

with ``solref`` and ``solimp`` given, and the equality flag switched on. MuJoCo's constraints are soft
(its reference acceleration ``-b Phi' - k Phi``, ``b = 2 / (d_max tau)``, ``k = 1 / (d_max tau zeta)^2``, and a
regularizer ``(1 - d) / d`` times the diagonal of ``J M^-1 J^T``): its run approaches the exact one as
``tau`` shrinks and ``d`` tends to 1 (:mod:`urdf2links.compare.agreement.constraint_agreement`).

An MJCF file's own equalities run in MuJoCo as written (route 2): :func:`route2_constraints` switches its
equality flag on, restores its fixed tendons and sets the same ``solref``/``solimp`` on every equality.
"""

from __future__ import annotations

import dataclasses

import mujoco
import numpy as np
from numpy.polynomial import polynomial as P

from urdf2links.dynamics.constraints import WORLD

from .mjcf_model import MjcfModel

__all__ = ["with_constraints", "shifted_polycoef", "equality_rows", "route2_constraints",
           "SOLIMP", "COMPARE_SOLREF"]

#: MuJoCo's largest impedance: the regularizer (1 - d) / d is 1e-4 of the constraint's own inertia.
SOLIMP = (0.9999, 0.9999, 0.001, 0.5, 2.0)
#: solref of a comparison (``urdf2links compare``): 10 steps of its RK4 at 1e-4 s per time constant; the solref
#: study (:mod:`urdf2links.compare.agreement.constraint_agreement`) shows how far that is from the exact run.
COMPARE_SOLREF = (1e-3, 1.0)


def _quat(R) -> np.ndarray:
    q = np.empty(4)
    mujoco.mju_mat2Quat(q, np.ascontiguousarray(R, float).ravel())
    return q


def shifted_polycoef(c, r_a: float, r_b: float) -> np.ndarray:
    """``q_a = r_a + sum_k c_k (q_b - r_b)^k`` as ``q_a = sum_k a_k q_b^k`` (5,)."""
    out = np.zeros(5)
    for k, ck in enumerate(c):
        out[:k + 1] += ck * P.polypow([-r_b, 1.0], k)
    out[0] += r_a
    return out


def _site(spec, mj: MjcfModel, d, p, point, frame, name):
    """A site on link ``p``'s host body (the world for -1) at ``point`` with axes ``frame`` (link axes)."""
    if p == WORLD:
        return spec.worldbody.add_site(name=name, pos=point, quat=_quat(frame))
    b = int(mj.body_of_link[p])
    if b < 0:
        raise ValueError(f"link {mj.source.tree.link_names[p]!r} is folded into another body in route 1: a "
                         "constraint on it is not written")
    Tb = np.eye(4)
    Tb[:3, :3], Tb[:3, 3] = np.asarray(d.xmat[b]).reshape(3, 3), d.xpos[b]
    X = np.linalg.solve(Tb, mj.link_pose(d, p))
    body = spec.body(mujoco.mj_id2name(mj.model, mujoco.mjtObj.mjOBJ_BODY, b))
    return body.add_site(name=name, pos=X[:3, :3] @ point + X[:3, 3], quat=_quat(X[:3, :3] @ frame))


def _tendon_equality(spec, e, c, names):
    """A ``tendon`` equality as two route-1 fixed tendons ``{name}__l1``, ``{name}__l2`` (their
    ``tendon_length0`` is 0 at route 1's ``qpos0 = 0``) and ``<tendon tendon1 tendon2 polycoef>``."""
    tendons = []
    for k, u in enumerate((c.coef1, c.coef2)):
        if u is not None:
            t = spec.add_tendon(name=f"{c.name}__l{k + 1}")
            for i, v in enumerate(u):
                if v:
                    t.wrap_joint(names[i], float(v))
            tendons.append(t.name)
    e.type, e.objtype = mujoco.mjtEq.mjEQ_TENDON, mujoco.mjtObj.mjOBJ_TENDON
    e.name1 = tendons[0]
    if len(tendons) > 1:
        e.name2 = tendons[1]
        e.data[:5] = shifted_polycoef(c.poly, c.ref1, c.ref2)
    else:
        e.data[:5] = [c.ref1 + c.poly[0], 0, 0, 0, 0]


def with_constraints(mj: MjcfModel, closure, *, solref=COMPARE_SOLREF, solimp=SOLIMP) -> MjcfModel:
    """Route 1 (``mj``) with the plan's constraints and tendons (``closure``:
    :class:`~urdf2links.scenes.constraints.SceneConstraints`) as MuJoCo equalities and tendons (module doc)."""
    spec = mujoco.MjSpec.from_string(mj.xml)
    d = mj.data(np.zeros(mj.n))
    names = mj.coordinate_names
    for c in closure.cset.constraints:
        e = spec.add_equality(name=c.name)
        e.solref, e.solimp = list(solref), list(solimp)
        if c.kind == "joint":
            e.type, e.objtype = mujoco.mjtEq.mjEQ_JOINT, mujoco.mjtObj.mjOBJ_JOINT
            e.name1 = names[c.coord1]
            if c.coord2 >= 0:
                e.name2 = names[c.coord2]
                e.data[:5] = shifted_polycoef(c.poly, c.ref1, c.ref2)
            else:
                e.data[:5] = [c.ref1 + c.poly[0], 0, 0, 0, 0]
            continue
        if c.kind == "tendon":
            _tendon_equality(spec, e, c, names)
            continue
        s1 = _site(spec, mj, d, c.link1, c.point1, c.frame1, f"{c.name}__1")
        s2 = _site(spec, mj, d, c.link2, c.point2, c.frame2, f"{c.name}__2")
        e.type = mujoco.mjtEq.mjEQ_CONNECT if c.kind == "connect" else mujoco.mjtEq.mjEQ_WELD
        e.objtype = mujoco.mjtObj.mjOBJ_SITE
        e.name1, e.name2 = s1.name, s2.name
        if c.kind == "weld":
            e.data[10] = 1.0        # torquescale
    for td in closure.tendons:
        t = spec.add_tendon(name=td.name, stiffness=td.stiffness, damping=td.damping,
                            springlength=list(td.lengthspring))
        for i, coef in enumerate(td.coef):
            if coef:
                t.wrap_joint(names[i], coef)
        for a in td.actuators:
            act = spec.add_actuator(name=a.name, trntype=mujoco.mjtTrn.mjTRN_TENDON, target=td.name)
            act.gainprm[0], act.biastype = a.gain, mujoco.mjtBias.mjBIAS_AFFINE
            act.biasprm[:3], act.gear[0] = list(a.bias), a.gear
            if a.ctrlrange is not None:
                act.ctrllimited, act.ctrlrange = True, list(a.ctrlrange)
            if a.forcerange is not None:
                act.forcelimited, act.forcerange = True, list(a.forcerange)
    spec.option.disableflags &= ~int(mujoco.mjtDisableBit.mjDSBL_EQUALITY)
    if any(td.stiffness for td in closure.tendons):
        spec.option.disableflags &= ~int(mujoco.mjtDisableBit.mjDSBL_SPRING)
    if any(td.damping for td in closure.tendons):
        spec.option.disableflags &= ~int(mujoco.mjtDisableBit.mjDSBL_DAMPER)
    m = spec.compile()
    note = (f"equality switched back on: the scene's constraints as MuJoCo equalities (site semantic), solref "
            f"{list(solref)}, solimp {list(solimp)}; {len(closure.tendons)} fixed tendon(s)"
            + (" (spring/damper back on for them)" if closure.tendons else ""))
    return dataclasses.replace(mj, xml=spec.to_xml(), model=m, notes=[*mj.notes, note])


def equality_rows(m, d, eq: int) -> np.ndarray:
    """The indices of ``d.efc_*`` rows of equality ``eq`` (after ``mj_forward``)."""
    return np.nonzero((np.asarray(d.efc_type) == int(mujoco.mjtConstraint.mjCNSTR_EQUALITY))
                      & (np.asarray(d.efc_id) == eq))[0]


def route2_constraints(m, plan, tendons, notes, *, solref=COMPARE_SOLREF, solimp=SOLIMP) -> list[str]:
    """Route 2 of a scene with ``[constraints] from_file``: the file's equalities on (those the plan models;
    the others off), its fixed tendons' stiffness and damping back (``tendons``: the file's arrays), the
    constraint flags on; ``solref``/``solimp`` set when given. Returns what stays zeroed (spatial tendons)."""
    modelled = {c.name for c in plan.constraints.cset.constraints}
    names = [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_EQUALITY, i) or f"equality{i}" for i in range(m.neq)]
    for i, nm in enumerate(names):
        m.eq_active0[i] = nm in modelled
        if solref is not None:
            m.eq_solref[i] = solref
        if solimp is not None:
            m.eq_solimp[i] = solimp
    fixed = {td.name for td in plan.constraints.tendons}
    for t in range(m.ntendon):
        if (mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_TENDON, t) or f"tendon{t}") in fixed:
            m.tendon_stiffness[t], m.tendon_damping[t] = tendons[0][t], tendons[1][t]
    for flag in ("mjDSBL_EQUALITY", "mjDSBL_CONSTRAINT") + (("mjDSBL_SPRING",) if np.any(m.tendon_stiffness) else ()) \
            + (("mjDSBL_DAMPER",) if np.any(m.tendon_damping) else ()):
        m.opt.disableflags &= ~int(getattr(mujoco.mjtDisableBit, flag))
    notes.append(f"equality and constraint switched back on: the file's equalities act ({', '.join(n for n in names if n in modelled) or 'none'}; "
                 f"[constraints] from_file; solref {list(solref)}, solimp {list(solimp)}) and its fixed tendons "
                 f"({', '.join(sorted(fixed)) or 'none'})")
    return [] if fixed else ["tendon_stiffness", "tendon_damping"]

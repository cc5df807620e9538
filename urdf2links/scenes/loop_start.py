"""An excited (or random) start moved onto the robot's closed loops (issue 45): the default scene's ``q0``, ``q'0``.

A default scene's random start (:func:`~urdf2links.scenes.excitation.excited_state`, E65) draws every coordinate
on its own; a closed loop (a ``connect`` of a four-bar, a ``weld``, a joint equality) is then open by centimetres,
and the constrained run's projection (E74) starts from a state where the Gauss-Newton step is meaningless. Here
the start is carried onto ``Phi = 0`` by continuation from the file's reference configuration ``q_r`` (MuJoCo's
qpos0, where an MJCF file's loops are closed: its compiler puts the anchors there):

    q_s = q_r + s (q_rand - q_r),  s = 1/N, 2/N, ..., 1      (N = :data:`STEPS`)

each ``q_s`` predicted from the last point on the loops plus the step, and corrected by Gauss-Newton in the
least change (``q <- q - J^T (J J^T)^-1 Phi``, the independent rows of (E73) at ``q_r``) to ``max |Phi| <=``
:data:`TOL`. Every point must lie in the regular region of every loop: the smallest singular value of the
unit-row ``J`` at least :data:`REGULAR` (a change point, where a loop's rows lose their independence, is
below it). Where the continuation stops (a corrector that does not converge, or a point outside the regular
region) the start is the last regular point, at the fraction ``s`` reached, and the scene's description says
so. A start the projection cannot reach at all (the loops open or singular at ``q_r`` itself) is refused with
a :class:`~urdf2links.errors.SceneError` naming the loop (the constraint whose rows are worst) and the reason.
The rates are then projected onto the tangent space in the metric of ``A`` (E74's velocity step):
``q' <- q' - A^-1 J^T S^-1 J q'``.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from ..errors import SceneError

__all__ = ["LoopStart", "start_on_loops", "project_start", "STEPS", "TOL", "REGULAR"]

#: Continuation steps from the reference configuration to the random one.
STEPS = 16
#: The corrector's target: max |Phi| (m, rad) at every continuation point.
TOL = 1e-12
#: Smallest singular value of ``J`` with unit rows that counts as regular: below it a loop is near a change point
#: (rows nearly dependent: the multipliers of (E72) grow like its inverse).
REGULAR = 1e-3


@dataclass(frozen=True)
class LoopStart:
    """``q`` (n,), ``qd`` (n,) on the loops; ``reached`` the fraction ``s`` of the random offset kept (1: all),
    ``residual`` max |Phi| there, ``regularity`` the smallest singular value of unit-row ``J``, ``moved`` max |dq|
    from the random start, ``text`` a phrase for the scene's description."""

    q: np.ndarray
    qd: np.ndarray
    reached: float
    residual: float
    regularity: float
    moved: float
    text: str


def _regularity(J) -> float:
    if J.shape[0] == 0:
        return 1.0
    Jn = J / np.maximum(np.linalg.norm(J, axis=1), 1e-300)[:, None]
    return float(np.linalg.svd(Jn, compute_uv=False)[-1])


def _correct(cset, q, keep):
    """Gauss-Newton in the least change onto ``Phi = 0`` (rows ``keep``); ``(q, residual, regularity)``."""
    for _ in range(30):
        T = cset.terms(q)
        res = float(np.max(np.abs(T.phi)))
        J = T.J[keep]
        reg = _regularity(J)
        if res <= TOL or reg < REGULAR or not np.isfinite(res):
            return q, res, reg
        q = q - J.T @ np.linalg.solve(J @ J.T, T.phi[keep])
    T = cset.terms(q)
    return q, float(np.max(np.abs(T.phi))), _regularity(T.J[keep])


def _worst_loop(cset, q) -> str:
    T = cset.terms(q)
    k = int(np.argmax(np.abs(T.phi)))
    return T.rows[k].rsplit(".", 1)[0]


def project_start(cset, model, q_ref, q_rand, qd_rand, *, where: str) -> LoopStart:
    """The random start ``(q_rand, qd_rand)`` carried onto the loops of ``cset`` from ``q_ref`` (module doc)."""
    from ..dynamics.constrained import independent_rows, project_velocity

    q_ref, q_rand = np.asarray(q_ref, float), np.asarray(q_rand, float)
    T0 = cset.terms(q_ref)
    keep = independent_rows(T0.J, T0.rows).keep
    q, res, reg = _correct(cset, q_ref, keep)
    if res > 1e3 * TOL or reg < REGULAR:
        loop = _worst_loop(cset, q)
        why = (f"its residual is {res:.3g} at the file's reference configuration (qpos0) after Gauss-Newton: the loop "
               "does not close there" if res > 1e3 * TOL else
               f"its rows are nearly dependent at the reference configuration (smallest singular value of the "
               f"unit-row Jacobian {reg:.2g} < {REGULAR:g}): a change point")
        raise SceneError(f"{where}: the excited start cannot be projected onto the closed loops: loop {loop!r}: {why}; "
                         "start at rest (--q0 rest), or drop the file's loops ([constraints] from_file = false)")
    reached = 0.0
    for k in range(1, STEPS + 1):
        s = k / STEPS
        guess = q + (q_rand - q_ref) / STEPS
        q2, res2, reg2 = _correct(cset, guess, keep)
        if res2 > 1e3 * TOL or reg2 < REGULAR:
            stop = (f"loop {_worst_loop(cset, guess)!r} " + ("left its regular region" if reg2 < REGULAR
                                                            else "could not be closed"))
            break
        q, res, reg, reached = q2, res2, reg2, s
    else:
        stop = ""
    T = cset.terms(q)
    qd = project_velocity(np.asarray(qd_rand, float), T.J[keep], model.mass_matrix(q),
                          rows=[T.rows[i] for i in keep], where=where)
    moved = float(np.max(np.abs(q - q_rand)))
    text = (f"the start projected onto the closed loops ({', '.join(c.name for c in cset.constraints)}): "
            f"residual {res:.1g}, q moved by up to {moved:.3g}, the rates onto the tangent space")
    if reached < 1.0:
        text += f"; only {reached:.3g} of the random offset from qpos0 kept ({stop} beyond it)"
    return LoopStart(q=q, qd=qd, reached=reached, residual=res, regularity=reg, moved=moved, text=text)


def start_on_loops(scene, model):
    """``scene`` (a default scene with a random or excited start) with ``q0``, ``q'0`` projected onto its
    constraints (the file's when ``[constraints] from_file``, its own ``[[constraint]]`` blocks) and the
    projection said in its description; ``scene`` itself without constraints or without a random start."""
    from .file_constraints import plan_constraints

    if not (scene.q0 or scene.qd0):
        return scene
    where = str(scene.path or scene.name)
    sc = plan_constraints(scene, model)
    if sc is None or sc.cset.m == 0:
        return scene
    names = list(model.coordinate_names)
    q_rand, qd_rand = scene.initial_state(model)
    from .excitation import coordinate_ranges

    q_ref = coordinate_ranges(model).start        # qpos0, or the file's home keyframe
    ls = project_start(sc.cset, model, q_ref, q_rand, qd_rand, where=where)
    return dataclasses.replace(scene, q0=dict(zip(names, ls.q.tolist())), qd0=dict(zip(names, ls.qd.tolist())),
                               description=scene.description + "; " + ls.text)

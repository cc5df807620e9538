"""The armature's terms written out (docs/equations.md (E49)): the oracle of the compiled world-twist form.

For a coordinate ``q_k`` of its own, the armature ``a_k`` adds ``0.5 a_k q_k'^2`` to the kinetic
energy: ``a_k`` on ``a_kk`` and nothing in ``e``. For the three angles of a link whose angle slots
are all coordinates (a ball or a free body), the armature ``a`` acts on the link's angular velocity
relative to its parent, in its own axes, ``omega = J(phi) phi'`` with the columns
``J_i = vee(R~^T dR~/dphi_i)`` (``R~ = Rx Ry Rz`` of the link's slot values, E3, E43):
``0.5 a |omega|^2``, so ``a J^T J`` joins ``A`` and ``a J^T J' phi'`` joins ``e``, with
``dJ_l/dt = sum_j vee(dR~^T/dphi_j dR~/dphi_l + R~^T d2R~/dphi_j dphi_l) phi_j'``. Everything is
formed from the elementary matrices and their derivatives (E1, E2), term by term.
"""

from __future__ import annotations

import numpy as np

from ..transforms import elementary, elementary_derivative, elementary_second_derivative

__all__ = ["armature_terms"]


def _vee(S: np.ndarray) -> np.ndarray:
    return np.array([S[2, 1], S[0, 2], S[1, 0]])


def _angle_factors(values, d1=(), d2=()):
    """``R~`` (3, 3) of the angle slots' values, with the factors in ``d1`` differentiated once and a
    factor listed in ``d2`` twice (slot indices 0..2 for phi_x..phi_z)."""
    R = np.eye(4)
    for j in range(3):
        k = 3 + j
        if j in d2:
            F = elementary_second_derivative(k, values[j])
        elif j in d1:
            F = elementary_derivative(k, values[j])
        else:
            F = elementary(k, values[j])
        R = R @ F
    return R[:3, :3]


def armature_terms(tree, q, qd) -> dict:
    """``A`` (n, n), ``e`` (n,) and the kinetic energy ``E`` of the armature of ``tree`` at the tree
    state ``(q, qd)`` (E49), term by term (see the module doc)."""
    n = tree.n
    A, e, E = np.zeros((n, n)), np.zeros(n), 0.0
    arm = np.asarray(tree.armature, float)
    q, qd = np.asarray(q, float), np.asarray(qd, float)
    done = set()
    for p in range(tree.n_links):
        tri = tree.coord[p, 3:6]
        if not np.all(tri >= 0):
            continue
        done.update(int(i) for i in tri)
        a = arm[tri[0]]
        if a == 0.0:
            continue
        v = tree.params[p, 3:6] + q[tri]
        w = qd[tri]
        R = _angle_factors(v)
        J = np.column_stack([_vee(R.T @ _angle_factors(v, d1=(i,))) for i in range(3)])
        Jdot = np.zeros((3, 3))
        for l in range(3):
            for j in range(3):
                dRl = _angle_factors(v, d1=(l,))
                dRj = _angle_factors(v, d1=(j,))
                second = _angle_factors(v, d2=(l,)) if j == l else _angle_factors(v, d1=(l, j))
                Jdot[:, l] += _vee(dRj.T @ dRl + R.T @ second) * w[j]
        A[np.ix_(tri, tri)] += a * J.T @ J
        e[tri] += a * J.T @ (Jdot @ w)
        omega = J @ w
        E += 0.5 * a * float(omega @ omega)
    for i in range(n):
        if i not in done and arm[i] != 0.0:
            A[i, i] += arm[i]
            E += 0.5 * arm[i] * qd[i] ** 2
    return {"A": A, "e": e, "E": E}

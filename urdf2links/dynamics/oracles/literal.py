"""The literal trace form: the equations term by term, no reuse between links; the oracle of the other forms.

Everything here follows the trace form as written (docs/equations.md §4-§5), with no reuse
between links: for each link ``p`` the chain of elementary matrices from {A} to ``p`` is multiplied
out, ``Tbar_i`` and ``Tbar_{l,j}`` are formed by replacing the factors of ``q_i`` (and ``q_j``) by
their derivatives (E14), (E15), and the sums (E17), (E19), (E20), (E22), (E23) are taken term by
term and assembled over the tree as in (E25). Cost O(n^3) to O(n^4); it exists to check
:mod:`urdf2links.dynamics.oracles.recursive` and the compiled kernels.
"""

from __future__ import annotations

from functools import reduce

import numpy as np

from ..transforms import elementary, elementary_derivative, elementary_second_derivative
from .armature import armature_terms

__all__ = ["LiteralTerms", "literal_terms"]

_E4 = np.array([0.0, 0.0, 0.0, 1.0])


class LiteralTerms:
    """Per-link derivative matrices of one configuration, kept for the sums.

    For link ``p``: ``T[p]`` (4, 4) the transform {p} -> {0}; ``Tbar[p]``; ``dTbar[p]`` dict
    coordinate -> ``Tbar_i`` (4, 4); ``ddTbar[p]`` dict (l, j) -> ``Tbar_{l,j}`` (4, 4).
    """

    def __init__(self, tree, q, base_T):
        self.tree = tree
        self.B, self.Bd, self.Bdd = base_T if base_T is not None else (np.eye(4), np.zeros((4, 4)), np.zeros((4, 4)))
        self.Tbar, self.dTbar, self.ddTbar = [], [], []
        for p in range(tree.n_links):
            factors = self._chain(p, q)  # list of (k, value, coordinate or -1)
            mats = [elementary(k, v) for k, v, _ in factors]
            pos = {i: a for a, (_, _, i) in enumerate(factors) if i >= 0}
            self.Tbar.append(reduce(np.matmul, mats, np.eye(4)))
            d1 = {}
            for i, a in pos.items():
                m = list(mats)
                m[a] = elementary_derivative(factors[a][0], factors[a][1])
                d1[i] = reduce(np.matmul, m, np.eye(4))
            d2 = {}
            for l, a in pos.items():
                for j, b in pos.items():
                    m = list(mats)
                    if a == b:
                        m[a] = elementary_second_derivative(factors[a][0], factors[a][1])
                    else:
                        m[a] = elementary_derivative(factors[a][0], factors[a][1])
                        m[b] = elementary_derivative(factors[b][0], factors[b][1])
                    d2[(l, j)] = reduce(np.matmul, m, np.eye(4))
            self.dTbar.append(d1)
            self.ddTbar.append(d2)

    def _chain(self, p, q):
        tree = self.tree
        path = []
        while p >= 0:
            path.append(p)
            p = tree.parent[p]
        factors = []
        for s in reversed(path):  # N_p (E5): from the first link to p
            for k in range(6):
                i = int(tree.coord[s, k])
                v = tree.params[s, k] + (q[i] if i >= 0 else 0.0)
                factors.append((k, v, i))
        return factors


def literal_terms(tree, q, qd, *, base_T=None, gravity_vector=(0.0, 0.0, -9.81), wrenches=()):
    """A, e, G, Q, E, V of the trace form (E17)-(E23), literally.

    Parameters
    ----------
    tree : LinkTree
    q, qd : (n,) coordinates and velocities.
    base_T : ``(0_A T, its first, its second derivative)`` (4, 4) each, or None for a fixed base.
    gravity_vector : (3,) gravitational acceleration in {0}; ``(0, 0, -g)`` gives ``m g z_C`` in (E21), (E22).
    wrenches : iterable of ``(link index, force (3,), moment (3,), point (3,), frame)``.

    Returns
    -------
    dict with ``A`` (n, n) (E19), ``e`` (n,) (E20), ``G`` (n,) (E22), ``Q`` (n,) (E23),
    ``E`` kinetic energy (E17), ``V`` potential energy of gravity (E21); the armature's terms (E49)
    are in ``A``, ``e`` and ``E``.
    """
    n = tree.n
    q = np.asarray(q, float)
    qd = np.asarray(qd, float)
    gvec = np.asarray(gravity_vector, float)
    lt = LiteralTerms(tree, q, base_T)
    B, Bd, Bdd = lt.B, lt.Bd, lt.Bdd
    A = np.zeros((n, n))
    e = np.zeros(n)
    G = np.zeros(n)
    E = 0.0
    V = 0.0
    for p in range(tree.n_links):
        H = tree.H[p]
        Tbar = lt.Tbar[p]
        T = B @ Tbar
        Ti = {i: B @ M for i, M in lt.dTbar[p].items()}            # T_i^(p) (E14); link(i) in N_p (E25)
        Tbar_dot = sum((M * qd[i] for i, M in lt.dTbar[p].items()), np.zeros((4, 4)))  # (E14)
        second = sum((M * qd[l] * qd[j] for (l, j), M in lt.ddTbar[p].items()), np.zeros((4, 4)))
        inner = Bdd @ Tbar + 2.0 * Bd @ Tbar_dot + B @ second     # T''_0 of (E15), (E20)
        for i, Tk in Ti.items():
            for l, Tl in Ti.items():
                A[i, l] += np.trace(Tk @ H @ Tl.T)                   # a_il of (E19)
            e[i] += np.trace(Tk @ H @ inner.T)                       # e_i of (E20)
            # (E22) g_i = m g e3^T T_i r_C, with m r_C = H e4; general direction of gravity.
            G[i] += -gvec @ (Tk @ H @ _E4)[:3]
        Tdot = Bd @ Tbar + B @ Tbar_dot                              # (E14)
        E += 0.5 * np.trace(Tdot @ H @ Tdot.T)                       # (E17)
        V += -gvec @ (T @ H @ _E4)[:3]                               # (E21): m g z_C
    Q = np.zeros(n)
    for link, force, moment, point, frame in wrenches:
        T = B @ lt.Tbar[link]
        R = T[:3, :3]
        r = np.append(point, 1.0)
        F4 = np.append(force, 0.0)                                    # (F, 0) in link or world axes (E23)
        Mloc = moment if frame == "link" else R.T @ moment            # M~ (link axes) of (E23)
        for i, M in lt.dTbar[link].items():
            Tk = B @ M
            if frame == "link":
                Q[i] += F4 @ T.T @ Tk @ r                             # F~^T T^T T_i rho_N (E23)
            else:
                Q[i] += F4 @ Tk @ r                                   # F^T T_i rho_N (E23)
            t, ti = T, Tk                                             # moment term of (E23), 0-based
            Q[i] += (
                Mloc[0] * sum(t[l, 2] * ti[l, 1] for l in range(3))
                + Mloc[1] * sum(t[l, 0] * ti[l, 2] for l in range(3))
                + Mloc[2] * sum(t[l, 1] * ti[l, 0] for l in range(3))
            )
    if tree.has_armature:                                             # (E49), term by term
        arm = armature_terms(tree, q, qd)
        A, e, E = A + arm["A"], e + arm["e"], E + arm["E"]
    return {"A": A, "e": e, "G": G, "Q": Q, "E": E, "V": V}

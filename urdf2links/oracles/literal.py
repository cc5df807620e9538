"""The literal trace form: the equations term by term, no reuse between links; the oracle of the other forms.

Everything here follows the equations as printed, with no reuse between links:
for each link ``p`` the chain of elementary matrices from {A} to ``p`` is multiplied out,
``Tbar_i`` and ``Tbar_{l,j}`` are formed by replacing the factors of ``q_i`` (and ``q_j``) by their
derivatives (5.14), (5.17.2), and the sums (5.18), (5.22), (5.27), (5.28), (5.35) are taken
term by term and assembled over the tree as in (5.36)-(5.49). Cost O(n^3) to O(n^4); it exists
to check :mod:`urdf2links.recursive`.
"""

from __future__ import annotations

from functools import reduce

import numpy as np

from ..transforms import elementary, elementary_derivative, elementary_second_derivative

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
        for s in reversed(path):  # N_p of (5.31): from the first link to p
            for k in range(6):
                i = int(tree.coord[s, k])
                v = tree.params[s, k] + (q[i] if i >= 0 else 0.0)
                factors.append((k, v, i))
        return factors


def literal_terms(tree, q, qd, *, base_T=None, gravity_vector=(0.0, 0.0, -9.81), wrenches=()):
    """A, e, G, Q, E, V of the reference, literally.

    Parameters
    ----------
    tree : LinkTree
    q, qd : (n,) coordinates and velocities.
    base_T : ``(0_A T, its first, its second derivative)`` (4, 4) each, or None for a fixed base.
    gravity_vector : (3,) gravitational acceleration in {0}; ``(0, 0, -g)`` gives (5.21)-(5.22).
    wrenches : iterable of ``(link index, force (3,), moment (3,), point (3,), frame)``.

    Returns
    -------
    dict with ``A`` (n, n) (5.19), ``e`` (n,) (5.18), ``G`` (n,) (5.22), ``Q`` (n,) (5.27)+(5.28),
    ``E`` kinetic energy (5.35)+(5.46), ``V`` potential energy of gravity (5.21)+(5.47).
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
        Ti = {i: B @ M for i, M in lt.dTbar[p].items()}            # T_k^(p) of (5.36)
        Tbar_dot = sum((M * qd[i] for i, M in lt.dTbar[p].items()), np.zeros((4, 4)))  # (5.14)
        second = sum((M * qd[l] * qd[j] for (l, j), M in lt.ddTbar[p].items()), np.zeros((4, 4)))
        inner = Bdd @ Tbar + 2.0 * Bd @ Tbar_dot + B @ second     # bracket of (5.18)/(5.36)
        for i, Tk in Ti.items():
            for l, Tl in Ti.items():
                A[i, l] += np.trace(Tk @ H @ Tl.T)                   # a_il of (5.18)
            e[i] += np.trace(Tk @ H @ inner.T)                       # e_i of (5.18)
            # (5.22) g_i = m g theta_3 T_i r_C, with m r_C = H e4; general direction of gravity.
            G[i] += -gvec @ (Tk @ H @ _E4)[:3]
        Tdot = Bd @ Tbar + B @ Tbar_dot                              # (5.13)
        E += 0.5 * np.trace(Tdot @ H @ Tdot.T)                       # (5.35)
        V += -gvec @ (T @ H @ _E4)[:3]                               # (5.21): m g z_C
    Q = np.zeros(n)
    for link, force, moment, point, frame in wrenches:
        T = B @ lt.Tbar[link]
        R = T[:3, :3]
        r = np.append(point, 1.0)
        F4 = np.append(force, 0.0)                                    # (5.23)
        Mloc = moment if frame == "link" else R.T @ moment            # M~ of (5.24)
        for i, M in lt.dTbar[link].items():
            Tk = B @ M
            if frame == "link":
                Q[i] += F4 @ T.T @ Tk @ r                             # (5.27)
            else:
                Q[i] += F4 @ Tk @ r                                   # (5.26)
            t, ti = T, Tk                                             # (5.28), 0-based indices
            Q[i] += (
                Mloc[0] * sum(t[l, 2] * ti[l, 1] for l in range(3))
                + Mloc[1] * sum(t[l, 0] * ti[l, 2] for l in range(3))
                + Mloc[2] * sum(t[l, 1] * ti[l, 0] for l in range(3))
            )
    return {"A": A, "e": e, "G": G, "Q": Q, "E": E, "V": V}

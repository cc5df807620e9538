"""The recursive form in numpy (an oracle): the traces of docs/equations.md (E19)-(E23) over the tree.

Every elementary factor satisfies ``dE_k/dv = E_k D_k`` (E2, :mod:`urdf2links.dynamics.transforms`), so the
derivative of the transform of any link ``p`` that follows coordinate ``q_i`` is (E26)

    T_i^(p) = W_i T^(p),   W_i = F_i D_k F_i^{-1}   (4, 4), the same for every such p,

where ``F_i`` is the {0}-pose of the frame right after ``q_i``'s factor (the base motion included).
``W_i = [[w^, v], [0, 0]]`` is the twist of the coordinate's unit motion in {0}. Then the sums
over links collapse onto composite matrices (E30) accumulated from leaves to root (E38):

- (E19) ``a_il = sum_p tr(T_i H T_l^T) = tr(W_i Hc W_l^T)``, ``Hc = sum_{p >= deeper} T H T^T``;
- (E20) ``e_i = sum_p tr(T_i H T''^T) = tr(W_i Mc)``, ``Mc = sum_{p >= link(i)} T H T''_0^T``,
  with ``T''_0`` the acceleration of ``T`` at ``q'' = 0`` (base terms of (E15) included);
- (E22) ``g_i = -g . (W_i Hc e4)``: the last column of ``Hc`` is the subtree's first moment;
- (E23), (E36) ``Q_i = v_i . f + w_i . n`` with ``f``, ``n`` the subtree's force and moment about {0}.

``T``, ``T'``, ``T''_0`` are propagated from root to leaves through the elementary factors by
the product rule. A costs O(n^2); e, G and Q cost O(n).
"""

from __future__ import annotations

import numpy as np

from ..transforms import GENERATORS, elementary
from .armature import armature_terms

__all__ = ["RecursivePlan", "Kinematics", "numpy_terms", "numpy_mass_matrix"]

_I4 = np.eye(4)


class Kinematics:
    """Poses and their rates at one state.

    ``T``, ``Td``, ``Tdd0`` (L, 4, 4): {0}-poses of the links, their first derivative, their second
    derivative at ``q'' = 0`` (None when not asked for); ``twist`` (n, 6): ``(w_i, v_i)`` of ``W_i``.
    """

    __slots__ = ("T", "Td", "Tdd0", "twist")

    def __init__(self, T, Td, Tdd0, twist):
        self.T, self.Td, self.Tdd0, self.twist = T, Td, Tdd0, twist

    def W(self) -> np.ndarray:
        """(n, 4, 4) twist matrices ``W_i``."""
        n = self.twist.shape[0]
        W = np.zeros((n, 4, 4))
        w, v = self.twist[:, :3], self.twist[:, 3:]
        W[:, 0, 1], W[:, 0, 2] = -w[:, 2], w[:, 1]
        W[:, 1, 0], W[:, 1, 2] = w[:, 2], -w[:, 0]
        W[:, 2, 0], W[:, 2, 1] = -w[:, 1], w[:, 0]
        W[:, :3, 3] = v
        return W


class RecursivePlan:
    """Precomputed structure of a :class:`~urdf2links.dynamics.tree.LinkTree` for the recursive form.

    Each link's ``T~`` is stored as segments: constant (4, 4) products of consecutive constant
    factors (identity factors dropped), and variable factors ``(k, coordinate, offset)``.
    """

    def __init__(self, tree):
        self.tree = tree
        self.segments = []
        for p in range(tree.n_links):
            segs = []
            C = None
            for k in range(6):
                i = int(tree.coord[p, k])
                v = float(tree.params[p, k])
                if i < 0:
                    if v != 0.0:
                        E = elementary(k, v)
                        C = E if C is None else C @ E
                else:
                    if C is not None:
                        segs.append(("c", C))
                        C = None
                    segs.append(("v", k, i, v))
            if C is not None:
                segs.append(("c", C))
            self.segments.append(segs)
        self.parent = tree.parent
        self.coord_link = tree.coord_link
        self.anc = tree.coordinate_ancestor()
        self.H = tree.H

    # -- root to leaves ------------------------------------------------------------------------
    def kinematics(self, q, qd=None, base_T=None, *, acceleration=False) -> Kinematics:
        """Propagate ``T`` (and ``T'``, ``T''_0`` when ``qd`` is given) from {A} to every link."""
        tree = self.tree
        L, n = tree.n_links, tree.n
        velocity = qd is not None
        T = np.empty((L, 4, 4))
        Td = np.empty((L, 4, 4)) if velocity else None
        Tdd = np.empty((L, 4, 4)) if acceleration else None
        twist = np.empty((n, 6))
        if base_T is None:
            B, Bd, Bdd = _I4, None, None
        else:
            B, Bd, Bdd = base_T
        for p in range(L):
            s = self.parent[p]
            if s >= 0:
                P = T[s]
                Pd = Td[s] if velocity else None
                Pdd = Tdd[s] if acceleration else None
            else:
                P, Pd, Pdd = B, Bd, Bdd
            for seg in self.segments[p]:
                if seg[0] == "c":
                    C = seg[1]
                    P = P @ C
                    if velocity and Pd is not None:
                        Pd = Pd @ C
                    if acceleration and Pdd is not None:
                        Pdd = Pdd @ C
                    continue
                _, k, i, off = seg
                E = elementary(k, off + q[i])
                D = GENERATORS[k]
                if velocity:
                    ED = E @ D
                    vd = qd[i]
                    if acceleration:
                        # (P E)'' = P'' E + 2 P' E' + P E'',  E' = E D v',  E'' = E D D v'^2 (q'' = 0)
                        acc = P @ (ED @ D) * (vd * vd)
                        if Pd is not None:
                            acc = acc + 2.0 * (Pd @ ED) * vd
                        if Pdd is not None:
                            acc = acc + Pdd @ E
                        Pdd = acc
                    vel = P @ ED * vd
                    Pd = vel if Pd is None else Pd @ E + vel
                P = P @ E
                R, o = P[:3, :3], P[:3, 3]
                if k < 3:  # translation: W = [[0, R e_k], [0, 0]]
                    twist[i, :3] = 0.0
                    twist[i, 3:] = R[:, k]
                else:      # rotation: W = [[w^, o x w], [0, 0]], w = R e_{k-3}
                    w = R[:, k - 3]
                    twist[i, :3] = w
                    twist[i, 3:] = np.cross(o, w)
            T[p] = P
            if velocity:
                Td[p] = Pd if Pd is not None else 0.0
            if acceleration:
                Tdd[p] = Pdd if Pdd is not None else 0.0
        return Kinematics(T, Td, Tdd, twist)

    # -- leaves to root ------------------------------------------------------------------------
    def subtree_sum(self, X: np.ndarray) -> np.ndarray:
        """``Xc[p] = X[p] + sum over children c of Xc[c]`` along axis 0 (a new array)."""
        Xc = X.copy()
        parent = self.parent
        for p in range(len(parent) - 1, -1, -1):
            s = parent[p]
            if s >= 0:
                Xc[s] += Xc[p]
        return Xc

    def composite_inertia(self, kin: Kinematics) -> np.ndarray:
        """``Hc`` (L, 4, 4): sum over each subtree of ``T H T^T`` in {0}."""
        return self.subtree_sum(np.einsum("pab,pbc,pdc->pad", kin.T, self.H, kin.T))

    def mass_matrix(self, kin: Kinematics, Hc: np.ndarray | None = None) -> np.ndarray:
        """A (n, n), (E38): ``a_il = tr(W_i Hc[deeper] W_l^T)`` on ancestor pairs, 0 elsewhere."""
        if Hc is None:
            Hc = self.composite_inertia(kin)
        W = kin.W()
        Y = np.einsum("iab,ibc->iac", W, Hc[self.coord_link])
        Afull = np.einsum("iab,lab->il", Y, W)
        anc = self.anc
        return np.where(anc, Afull, np.where(anc.T, Afull.T, 0.0))

    def bias(self, kin: Kinematics) -> np.ndarray:
        """e (n,), (E38): ``e_i = tr(W_i Mc[link(i)])``, ``Mc = subtree sum of T H T''_0^T``."""
        M = np.einsum("pab,pbc,pdc->pad", kin.T, self.H, kin.Tdd0)
        Mc = self.subtree_sum(M)
        W = kin.W()
        return np.einsum("iab,iba->i", W, Mc[self.coord_link])

    def gravity(self, kin: Kinematics, gravity_vector, Hc: np.ndarray | None = None) -> np.ndarray:
        """G (n,), (E38): ``g_i = -g . (w_i x c + v_i m)`` with ``(c, m)`` = last column of Hc."""
        if Hc is None:
            first = np.einsum("pab,pb->pa", kin.T, self.H[:, :, 3])  # T H e4 (L, 4)
            hc = self.subtree_sum(first)
        else:
            hc = Hc[:, :, 3]
        h = hc[self.coord_link]
        w, v = kin.twist[:, :3], kin.twist[:, 3:]
        motion = np.cross(w, h[:, :3]) + v * h[:, 3:4]
        return -motion @ np.asarray(gravity_vector, float)

    def generalized_forces(self, kin: Kinematics, wrenches) -> np.ndarray:
        """Q (n,), (E36): ``Q_i = v_i . f_c + w_i . n_c`` over the subtree of ``link(i)``."""
        L = self.tree.n_links
        fn = np.zeros((L, 6))
        for link, force, moment, point, frame in wrenches:
            T = kin.T[link]
            R = T[:3, :3]
            r = T[:3, :3] @ point + T[:3, 3]
            F = R @ force if frame == "link" else np.asarray(force, float)
            M = R @ moment if frame == "link" else np.asarray(moment, float)
            fn[link, :3] += F
            fn[link, 3:] += M + np.cross(r, F)
        fc = self.subtree_sum(fn)[self.coord_link]
        return np.einsum("ij,ij->i", kin.twist[:, 3:], fc[:, :3]) + np.einsum("ij,ij->i", kin.twist[:, :3], fc[:, 3:])

    def explicit_time_rates(self, kin: Kinematics, base_T, gravity_vector) -> tuple[float, float]:
        """``(dE/dt, dV/dt)`` at fixed ``(q, qd)``: the rates due to the base motion alone (E41).

        With ``T = B Tbar``: ``dT/dt = W1 T`` and ``dT'/dt = (W2 - W1 W1) T + W1 T'``, where
        ``W1 = B' B^-1``, ``W2 = B'' B^-1``; then ``dE/dt = sum tr(dT'/dt H T'^T)`` (from E17) and
        ``dV/dt = -g . sum (W1 T H e4)`` (from E21). Needs ``kin.Td``.
        """
        B, Bd, Bdd = base_T
        Binv = np.eye(4)
        Binv[:3, :3] = B[:3, :3].T
        Binv[:3, 3] = -B[:3, :3].T @ B[:3, 3]
        W1, W2 = Bd @ Binv, Bdd @ Binv
        THTd = np.einsum("pab,pbc,pdc->ad", kin.T, self.H, kin.Td)      # sum T H T'^T
        TdHTd = np.einsum("pab,pbc,pdc->ad", kin.Td, self.H, kin.Td)    # sum T' H T'^T
        dE = float(np.trace((W2 - W1 @ W1) @ THTd) + np.trace(W1 @ TdHTd))
        dV = 0.0
        if gravity_vector is not None:
            first = np.einsum("pab,pb->a", kin.T, self.H[:, :, 3])     # sum T H e4
            dV = -float(np.asarray(gravity_vector, float) @ (W1 @ first)[:3])
        return dE, dV

    def kinetic_energy(self, kin: Kinematics) -> float:
        """E (E17): ``0.5 sum_p tr(T' H T'^T)``."""
        return 0.5 * float(np.einsum("pab,pbc,pac->", kin.Td, self.H, kin.Td))

    def potential_energy(self, kin: Kinematics, gravity_vector) -> float:
        """V (E21): ``-sum_p m_p g . r_C``."""
        first = np.einsum("pab,pb->pa", kin.T, self.H[:, :, 3])
        return -float(first[:, :3].sum(axis=0) @ np.asarray(gravity_vector, float))


def numpy_terms(plan: RecursivePlan, q, qd, *, base_T=None, gravity_vector=(0.0, 0.0, -9.81), wrenches=()) -> dict:
    """A, e, G, Q, E, V of the numpy recursive form at a tree state, as
    :func:`urdf2links.dynamics.oracles.literal.literal_terms` returns them (same arguments)."""
    kin = plan.kinematics(np.asarray(q, float), np.asarray(qd, float), base_T, acceleration=True)
    Hc = plan.composite_inertia(kin)
    out = {"A": plan.mass_matrix(kin, Hc), "e": plan.bias(kin), "G": plan.gravity(kin, gravity_vector, Hc),
           "Q": plan.generalized_forces(kin, list(wrenches)), "E": plan.kinetic_energy(kin),
           "V": plan.potential_energy(kin, gravity_vector)}
    if plan.tree.has_armature:          # (E49)
        arm = armature_terms(plan.tree, q, qd)
        out["A"], out["e"], out["E"] = out["A"] + arm["A"], out["e"] + arm["e"], out["E"] + arm["E"]
    return out


def numpy_mass_matrix(plan: RecursivePlan, q) -> np.ndarray:
    """A (E19) alone, armature included (E49), at a tree configuration ``q``: what a check of A needs
    (the importer's), without the other terms and without compiling anything."""
    q = np.asarray(q, float)
    kin = plan.kinematics(q)
    A = plan.mass_matrix(kin, plan.composite_inertia(kin))
    if plan.tree.has_armature:
        A = A + armature_terms(plan.tree, q, np.zeros_like(q))["A"]
    return A

"""Holonomic constraints ``Phi(q) = 0`` on the tree: residual, Jacobian and bias from one kinematics pass.

docs/equations.md (E68)-(E71). A :class:`Constraint` is one of MuJoCo's equality kinds, in the tree's
links and the model's coordinates:

- ``connect`` (E68): a point ``rho_1`` of link 1 on a point ``rho_2`` of link 2 (or of the world):
  ``Phi = r_1 - r_2`` (3 rows), ``r = T rho~``;
- ``weld`` (E69): a frame of link 1 on a frame of link 2: the origins as ``connect``, and the
  orientation error ``Phi_R = 0.5 vee(R_e - R_e^T)`` of ``R_e = R_1 X_1 (R_2 X_2)^T`` (3 rows; zero
  exactly when the frames agree, near the manifold);
- ``joint`` (E70): ``q_a - q_a0 = sum_k c_k (q_b - q_b0)^k`` (k = 0..4; 1 row), MuJoCo's polynomial
  coupling of two coordinates (without ``q_b``: ``q_a - q_a0 = c_0``);
- ``tendon``: the same polynomial law on two fixed tendons' lengths ``l = c . q`` (E76) instead of two
  coordinates, ``l_1 - l_10 = sum_k c_k (l_2 - l_20)^k`` (1 row), MuJoCo's tendon equality: a joint
  coupling is the case ``c_1 = e_a``, ``c_2 = e_b``.

One call of the compiled :func:`~urdf2links.dynamics.kernels.kinematics` (without gravity) gives every
link's pose ``(R, o)``, twist ``(omega, v)``, spatial acceleration at ``q'' = 0`` ``(alpha, a)``
(E32), and every coordinate's unit twist ``s_i = (w_i, v_i)`` (E27); nothing else is recomputed:

- Jacobian rows (E71): the velocity of a world point ``r`` of link ``p`` per unit ``q_i'`` is
  ``u_i(r) = w_i x r + v_i`` (E27) when ``link(i)`` is ``p`` or one of its ancestors, else 0; an
  orientation row is ``w_i``. Coupled coordinates (E42): ``Phi_q = Phi_{q_tree} C``.
- bias ``gamma = Phi_q' q'`` (E71): the part of ``Phi''`` that does not depend on ``q''``, the
  point acceleration at ``q'' = 0``, ``a_0(r) = alpha x r + a + omega x (omega x r + v)`` (E32), so
  that ``Phi'' = Phi_q q'' + gamma``; an orientation row's is ``alpha_1 - alpha_2``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numba import njit

from .model_kernels import _state, coupled_size
from .rows import base_rows
from .kernels import poses
from .tree_arrays import AC, KL, W_COORD, W_LINK, W_SIZE, WV, Tree, nonneg

__all__ = ["Constraint", "ConstraintSet", "ConstraintTerms", "KINDS", "ROWS", "link_motion"]

KINDS = ("connect", "weld", "joint", "tendon")
ROWS = {"connect": ("x", "y", "z"), "weld": ("x", "y", "z", "rx", "ry", "rz"), "joint": ("q",), "tendon": ("l",)}
POLYNOMIAL = ("joint", "tendon")
WORLD = -1


@njit(cache=True)
def link_motion(TI, TF, q, qd, base, has_base, C, d, coupled, R, o, V, Acc, S):
    """One kinematics pass (E33) at ``(q, qd)`` without gravity: every link's rotation ``R`` (L, 3, 3),
    origin ``o`` (L, 3), twist ``V`` (L, 6) and acceleration at ``q'' = 0`` ``Acc`` (L, 6); the tree
    coordinates' unit twists ``S`` (6, n_tree)."""
    W = np.empty(TI[W_SIZE])
    X = np.empty(coupled_size(C.shape[0], C.shape[1]) if coupled else 0)
    tree = Tree(TI, TF, W)
    _state(tree, X, q, qd, True, base, has_base, 0.0, 0.0, 0.0, C, d, coupled)
    poses(tree, R, o)
    wl, wc, nt = nonneg(TI[W_LINK]), nonneg(TI[W_COORD]), nonneg(TI[1])
    for p in range(TI[0]):
        a = wl + KL * p
        for j in range(6):
            V[p, j] = W[a + WV + j]
            Acc[p, j] = W[a + AC + j]
    for j in range(6):
        for i in range(nt):
            S[j, i] = W[wc + j * nt + i]


@dataclass(frozen=True)
class Constraint:
    """One equality. ``link1``/``link2``: tree link indices (``-1`` the world); ``point1``/``point2``
    (3,) in those links' axes (world axes for the world); ``frame1``/``frame2`` (3, 3) the welded
    frames' rotations in the links' axes; ``coord1``/``coord2``: model coordinates of a ``joint``
    (``coord2`` -1: none), ``poly`` (5,) its coefficients, ``ref1``/``ref2`` the reference values
    ``q_a0``, ``q_b0``; ``coef1``/``coef2`` (n,) a ``tendon`` equality's lengths ``l = c . q`` (``coef2`` None:
    none), ``ref1``/``ref2`` then their reference lengths; ``source`` where it was read (a scene key, an MJCF
    element)."""

    name: str
    kind: str
    link1: int = WORLD
    link2: int = WORLD
    point1: np.ndarray = field(default_factory=lambda: np.zeros(3))
    point2: np.ndarray = field(default_factory=lambda: np.zeros(3))
    frame1: np.ndarray = field(default_factory=lambda: np.eye(3))
    frame2: np.ndarray = field(default_factory=lambda: np.eye(3))
    coord1: int = -1
    coord2: int = -1
    poly: np.ndarray = field(default_factory=lambda: np.array([0.0, 1.0, 0.0, 0.0, 0.0]))
    ref1: float = 0.0
    ref2: float = 0.0
    coef1: np.ndarray | None = None
    coef2: np.ndarray | None = None
    source: str = ""

    @property
    def rows(self) -> tuple[str, ...]:
        return tuple(f"{self.name}.{r}" for r in ROWS[self.kind])


@dataclass(frozen=True)
class ConstraintTerms:
    """``phi`` (m,) the residual, ``J`` (m, n) ``Phi_q``, ``gamma`` (m,) ``Phi_q' q'`` (E71), ``rate``
    (m,) ``Phi' = Phi_q q'``; rows named by ``rows``."""

    phi: np.ndarray
    J: np.ndarray
    gamma: np.ndarray
    rate: np.ndarray
    rows: tuple[str, ...]


class ConstraintSet:
    """The constraints of a model: :meth:`terms` at a state, :meth:`residual` alone."""

    def __init__(self, model, constraints):
        self.model = model
        self.constraints = tuple(constraints)
        tree = model.tree
        for c in self.constraints:
            if c.kind not in KINDS:
                raise ValueError(f"constraint {c.name!r}: kind must be one of {KINDS}, got {c.kind!r}")
        self.rows = tuple(r for c in self.constraints for r in c.rows)
        self.m = len(self.rows)
        # moves[i, p]: tree coordinate i moves link p (link(i) is p or an ancestor of p) (E25)
        L, nt = tree.n_links, tree.n
        anc = np.eye(L, dtype=bool)
        for p in range(L):
            s = int(tree.parent[p])
            if s >= 0:
                anc[:, p] |= anc[:, s]
        self._moves = anc[np.asarray(tree.coord_link, int)] if nt else np.zeros((0, L), bool)
        self._shapes = (L, nt)

    def __len__(self):
        return len(self.constraints)

    def _motion(self, q, qd, t, base):
        model = self.model
        L, nt = self._shapes
        R, o, V, Acc, S = np.empty((L, 3, 3)), np.empty((L, 3)), np.empty((L, 6)), np.empty((L, 6)), np.empty((6, nt))
        BASE, has_base = base_rows(base, t, 1, batched=False)
        q = np.ascontiguousarray(model.vector(q, "q"))
        qd = np.ascontiguousarray(np.zeros(model.n) if qd is None else model.vector(qd, "qd"))
        link_motion(model.compiled.TI, model.compiled.TF, q, qd, BASE[0], has_base, model._Ck, model._dk,
                    model._C is not None, R, o, V, Acc, S)
        return R, o, V, Acc, S

    def _point(self, p, rho, motion):
        """World point, its Jacobian (3, n_tree), velocity and acceleration at q'' = 0 (E71)."""
        R, o, V, Acc, S = motion
        nt = S.shape[1]
        if p == WORLD:
            return rho.copy(), np.zeros((3, nt)), np.zeros(3), np.zeros(3)
        r = R[p] @ rho + o[p]
        w, v = S[:3], S[3:]
        J = np.array([w[1] * r[2] - w[2] * r[1], w[2] * r[0] - w[0] * r[2], w[0] * r[1] - w[1] * r[0]]) + v
        J *= self._moves[:, p]
        om, vl, al, aa = V[p, :3], V[p, 3:], Acc[p, :3], Acc[p, 3:]
        vel = _cross(om, r) + vl
        acc = _cross(al, r) + aa + _cross(om, vel)
        return r, J, vel, acc

    def _angular(self, p, motion):
        R, o, V, Acc, S = motion
        nt = S.shape[1]
        if p == WORLD:
            return np.eye(3), np.zeros((3, nt)), np.zeros(3), np.zeros(3)
        return R[p], S[:3] * self._moves[:, p], V[p, :3], Acc[p, :3]

    def terms(self, q, qd=None, *, t: float = 0.0, base=None) -> ConstraintTerms:
        """``Phi``, ``Phi_q``, ``Phi_q' q'`` and ``Phi'`` at ``(q, qd)`` (E68)-(E71), model coordinates."""
        model = self.model
        q = model.vector(q, "q")
        qd = np.zeros(model.n) if qd is None else model.vector(qd, "qd")
        nt = self._shapes[1]
        motion = self._motion(q, qd, t, base) if any(c.kind not in POLYNOMIAL for c in self.constraints) else None
        phi, Jt, gam = np.zeros(self.m), np.zeros((self.m, nt)), np.zeros(self.m)
        Jm = np.zeros((self.m, model.n))       # joint rows, already in model coordinates
        k = 0
        for c in self.constraints:
            if c.kind in POLYNOMIAL:
                phi[k], Jm[k], gam[k] = _polynomial_row(c, q, qd, model.n)
            else:
                r1, J1, v1, a1 = self._point(c.link1, c.point1, motion)
                r2, J2, v2, a2 = self._point(c.link2, c.point2, motion)
                phi[k:k + 3], Jt[k:k + 3], gam[k:k + 3] = r1 - r2, J1 - J2, a1 - a2
                if c.kind == "weld":            # (E69)
                    R1, W1, w1, al1 = self._angular(c.link1, motion)
                    R2, W2, w2, al2 = self._angular(c.link2, motion)
                    Re = (R1 @ c.frame1) @ (R2 @ c.frame2).T
                    X = 0.5 * (Re - Re.T)
                    phi[k + 3:k + 6] = X[2, 1], X[0, 2], X[1, 0]
                    Jt[k + 3:k + 6], gam[k + 3:k + 6] = W1 - W2, al1 - al2
            k += len(ROWS[c.kind])
        C = model.coupling
        J = (Jt if C is None else Jt @ C[0]) + Jm
        return ConstraintTerms(phi=phi, J=J, gamma=gam, rate=J @ qd, rows=self.rows)

    def residual(self, q, *, t: float = 0.0, base=None) -> np.ndarray:
        """``Phi(q)`` (m,)."""
        return self.terms(q, None, t=t, base=base).phi


def _cross(a, b):
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def _lengths(c: Constraint, n):
    """The two linear functions ``u . q`` a polynomial row couples (n,): unit rows of the coordinates (joint)
    or the tendons' coefficients (tendon, E76); the second None without one."""
    if c.kind == "tendon":
        return np.asarray(c.coef1, float), None if c.coef2 is None else np.asarray(c.coef2, float)
    u1 = np.zeros(n)
    u1[c.coord1] = 1.0
    if c.coord2 < 0:
        return u1, None
    u2 = np.zeros(n)
    u2[c.coord2] = 1.0
    return u1, u2


def _polynomial_row(c: Constraint, q, qd, n):
    """``Phi = l_a - l_a0 - p(l_b - l_b0)``, its row ``u_a - p'(x) u_b`` and ``-p''(x) l_b'^2`` (E70), with
    ``l = u . q`` a coordinate (joint) or a fixed tendon's length (tendon)."""
    a = c.poly
    u1, u2 = _lengths(c, n)
    if u2 is None:
        return u1 @ q - c.ref1 - a[0], u1, 0.0
    x, xd = u2 @ q - c.ref2, u2 @ qd
    p = a[0] + x * (a[1] + x * (a[2] + x * (a[3] + x * a[4])))
    dp = a[1] + x * (2 * a[2] + x * (3 * a[3] + x * 4 * a[4]))
    ddp = 2 * a[2] + x * (6 * a[3] + x * 12 * a[4])
    return u1 @ q - c.ref1 - p, u1 - dp * u2, -ddp * xd * xd

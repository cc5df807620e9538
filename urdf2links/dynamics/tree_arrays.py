"""The tree flattened for the compiled kernels: two arrays, their layout, and the scratch size.

:func:`flat_tree` turns a :class:`~urdf2links.dynamics.tree.LinkTree` into one int64 array ``TI`` and one
float64 array ``TF``: runs of constant factors are multiplied into one rigid transform (identity
factors dropped), variable factors are kept with their slot. The kernels index these arrays (and
their scratch ``W``, one float64 array per thread) at offsets stored in the header of ``TI``,
never through views: building a view costs reference counting (and a reshape a library call) on
every call, which was a third of a small robot's evaluation.

Layout (the names are module constants, folded into the compiled code):

- ``TI[:HEADER]``: ``L, n, S, P`` (links, coordinates, segments, ancestor pairs), then the offsets of
  the blocks of ``TI`` (``I_*``), of ``TF`` (``F_*``) and of the scratch ``W`` (``W_*``, ``W_SIZE``).
- ``TI`` blocks: ``parent`` (L,), ``seg_ptr`` (L + 1,) (link p's factors are ``seg_ptr[p]:seg_ptr[p + 1]``),
  ``seg_slot`` (S,) (0..5 a variable slot, :data:`CONSTANT` a constant transform), ``seg_coord`` (S,),
  ``coord_link`` (n,), ``anc_ptr`` (n + 1,) and ``anc_idx`` (P,): for coordinate ``i`` the coordinates
  ``l <= i`` whose link is ``link(i)`` or an ancestor, ascending (the last one is ``i``); ``anc_row``
  (P,): ``anc_ptr[anc_idx[j]]``, where the row of that ancestor starts; ``run_ptr`` (n + 1,) and
  ``runs`` (2 R,): the same rows as runs of consecutive coordinates ``(first, length)`` (a chain's
  row is one run), so that the loops over a row index coordinates directly.
- ``TF`` blocks: per segment ``KS`` floats (offset, R (3, 3) row-major, p (3,)); per link ``KF`` floats
  (mass, first moment ``m r_C`` (3,) and ``J = tr(S) 1 - S`` (6,: xx yy zz xy xz yz) about the link
  origin, in the link's axes, with ``S = H[:3, :3]``); the armature items' values.
- armature (docs/equations.md (E49)): ``TI[N_ARM]`` items, each ``(kind, coordinate, link)`` in the
  ``I_ARM`` block and its value in the ``F_ARM`` block: :data:`ARM_ONE` a coordinate's own
  ``0.5 a q'^2``, :data:`ARM_BALL` the three angle coordinates (the first given) of a link whose
  three angle slots are coordinates, ``0.5 a |omega - omega_parent|^2``. No item: no armature work.
- ``W`` blocks: per link a record of ``KL`` floats (pose, twist, acceleration, subtree sums, wrenches;
  offsets ``R_ .. FX``), the coordinates' unit twists ``s = (w, v)`` by component (6, n): ``s_i[j]``
  at ``W[W_COORD + j n + i]``, the mass matrix packed by
  rows of ``anc_idx`` (P,) (factorized in place, :mod:`urdf2links.dynamics.factor`), ``b``, ``Q``, ``x`` (n,),
  the base record (``BASE_*``), and the tree's rates ``q'`` (n,) (written by the kinematics, for the
  armature's energy).
- The hot single-state entries (:mod:`urdf2links.dynamics.model_kernels`) take ``TF`` with the gravity
  appended as its last three entries (:func:`tf_with_gravity`, :func:`gravity_of`): one array argument fewer.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np
from numba import njit

from ..compilation import kernel, one_signature

from .transforms import elementary

__all__ = ["Tree", "flat_tree", "tf_with_gravity", "gravity_of", "HEADER", "CONSTANT", "KS", "KF", "KL", "workspace_size",
           "nonneg", "scratches", "armature_items", "ARM_ONE", "ARM_BALL"]

CONSTANT = 6        # seg_slot of a constant transform
KS = 13             # floats per segment in TF: offset, R (9), p (3)
KF = 10             # floats per link in TF: m, m r_C (3), J (6)
KL = 48             # floats per link record in W

Tree = namedtuple("Tree", ["TI", "TF", "W"])
"""The tree's arrays as one record, the first argument of every pass of
:mod:`urdf2links.dynamics.kernels`: ``TI`` (int64) the layout and the indices, ``TF`` (float64) the
constants, ``W`` (float64) the scratch of one thread (module doc). Built inside compiled code, where it
costs nothing (docs/speed.md); the Python-facing entries take the arrays."""

# TI header
I_PARENT, I_SEGPTR, I_SEGSLOT, I_SEGCOORD, I_COORDLINK, I_ANCPTR, I_ANCIDX, I_ANCROW, I_RUNPTR, I_RUNS = range(4, 14)
F_SEG, F_LINK = 14, 15
W_LINK, W_COORD, W_A, W_B, W_Q, W_X, W_BASE, W_QD, W_SIZE = range(16, 25)
I_ARM, F_ARM, N_ARM = 25, 26, 27    # armature items (E49): TI (kind, coordinate, link) per item, TF its value
HEADER = 28
ARM_ONE, ARM_BALL = 0, 1            # an item's kind: one coordinate (0.5 a q'^2); a link's three angles (0.5 a |omega|^2)

# the link record in W (offsets from the record's start)
R_ = 0      # rotation (9,) row-major
O_ = 9      # origin (3,)
WV = 12     # twist: omega (3,), v (3,)
AC = 18     # spatial acceleration at q'' = 0: alpha (3,), a (3,) (a includes -g)
CM = 24     # subtree mass, first moment c (3,), J about {0} (6,): the link alone until summed
CC = 25
CJ = 28
FI = 34     # inertial wrench (f, n) of the subtree, gravity included (6,)
FX = 40     # external wrench (f, n) of the subtree (6,)

# the base record in W: a link record's pose, twist and acceleration (24,), then
BASE_TWIST = 24     # the base's own twist (6,) and spatial acceleration without gravity (6,)
BASE_ACC = 30
BASE_MOM = 36       # total momentum (P, H about {0}) of the links (6,) when asked for
BASE_S = 42         # scratch unit twist of a base factor (6,)
KB = 48


@one_signature
@kernel
def nonneg(k):
    """``max(k, 0)``: an offset or index that is never negative, said so to the compiler. An integer
    index of unknown sign makes numba wrap negative values around on every access (three
    instructions, and no vectorization); one ``nonneg`` where an offset is loaded removes that from
    every access derived from it."""
    return max(k, 0)


def tf_with_gravity(TF, g) -> np.ndarray:
    """The hot entries' ``TF`` (m + 3,): the tree's ``TF`` (m,) 
    with the gravity ``g`` (3,) appended, read by :func:`gravity_of`; the kernels index ``TF`` at header
    offsets only, so the three entries at its end change nothing else. A model keeps one with its
    gravity and one with zeros: one array argument fewer per hot call."""
    return np.concatenate((TF, np.asarray(g, float)))


@njit(cache=True, inline="always")
def gravity_of(TF):
    """``(gx, gy, gz)``: the last three entries of a hot entry's ``TF`` (:func:`tf_with_gravity`)."""
    k = TF.size - 3
    return TF[k], TF[k + 1], TF[k + 2]


@njit(cache=True)
def scratches(TI, chunks, nx):
    """A batch's scratch, one row per chunk of rows: the tree's ``W`` (chunks, W_SIZE) and a caller's ``X``
    (chunks, nx) (coupled coordinates)."""
    return np.empty((chunks, TI[W_SIZE])), np.empty((chunks, nx))


def _segments(tree):
    """Per link: a list of ``(slot, coordinate, offset, R, p)``, constant runs multiplied out."""
    out = []
    for p in range(tree.n_links):
        segs, C = [], None
        for k in range(6):
            i, v = int(tree.coord[p, k]), float(tree.params[p, k])
            if i < 0:
                if v != 0.0:
                    E = elementary(k, v)
                    C = E if C is None else C @ E
                continue
            if C is not None:
                segs.append((CONSTANT, -1, 0.0, C[:3, :3], C[:3, 3]))
                C = None
            segs.append((k, i, v, np.eye(3), np.zeros(3)))
        if C is not None:
            segs.append((CONSTANT, -1, 0.0, C[:3, :3], C[:3, 3]))
        out.append(segs)
    return out


def workspace_size(L: int, n: int, P: int) -> int:
    return KL * L + 6 * n + P + 3 * n + KB + n


def armature_items(tree) -> list[tuple[int, int, int, float]]:
    """``(kind, coordinate, link, a)`` of every non-zero armature of ``tree`` (E49): a link whose
    three angle slots are coordinates gives one :data:`ARM_BALL` item (its ``phi_x`` coordinate),
    every other coordinate with an armature one :data:`ARM_ONE` item."""
    arm = np.asarray(tree.armature, float)
    items, done = [], set()
    for p in range(tree.n_links):
        tri = tree.coord[p, 3:6]
        if np.all(tri >= 0):
            done.update(int(i) for i in tri)
            if arm[tri[0]] != 0.0:
                items.append((ARM_BALL, int(tri[0]), p, float(arm[tri[0]])))
    for i in range(tree.n):
        if i not in done and arm[i] != 0.0:
            items.append((ARM_ONE, i, int(tree.coord_link[i]), float(arm[i])))
    return items


def flat_tree(tree) -> tuple[np.ndarray, np.ndarray]:
    """``(TI, TF)`` of a :class:`~urdf2links.dynamics.tree.LinkTree` (see the module doc)."""
    L, n = tree.n_links, tree.n
    segs = _segments(tree)
    ptr = np.cumsum([0] + [len(s) for s in segs])
    flat = [s for link in segs for s in link]
    S = len(flat)
    anc = tree.coordinate_ancestor()
    anc_ptr, anc_idx = [0], []
    for i in range(n):
        anc_idx += [l for l in range(i + 1) if anc[i, l]]
        anc_ptr.append(len(anc_idx))
    P = len(anc_idx)
    anc_row = [anc_ptr[l] for l in anc_idx]
    run_ptr, runs = [0], []
    for i in range(n):      # row i's coordinates as runs of consecutive ones: (first, length)
        row = anc_idx[anc_ptr[i]:anc_ptr[i + 1]]
        for j, l in enumerate(row):
            if j > 0 and l == row[j - 1] + 1:
                runs[-1] += 1
            else:
                runs += [l, 1]
        run_ptr.append(len(runs) // 2)
    blocks = [np.asarray(tree.parent), ptr, [s[0] for s in flat], [s[1] for s in flat],
              np.asarray(tree.coord_link), anc_ptr, anc_idx, anc_row, run_ptr, runs]
    arm = armature_items(tree)
    blocks.append([x for item in arm for x in item[:3]])
    head = np.zeros(HEADER, np.int64)
    head[:4] = L, n, S, P
    o = HEADER
    for k, b in enumerate(blocks):
        head[I_PARENT + k if k < 10 else I_ARM] = o
        o += len(b)
    head[N_ARM] = len(arm)
    H = np.asarray(tree.H, float)
    seg_f = np.zeros((S, KS))
    for j, (_, _, off, R, p) in enumerate(flat):
        seg_f[j, 0], seg_f[j, 1:10], seg_f[j, 10:13] = off, np.ravel(R), p
    link_f = np.zeros((L, KF))
    for p in range(L):
        Sm = H[p, :3, :3]
        J = np.trace(Sm) * np.eye(3) - Sm
        link_f[p, 0], link_f[p, 1:4] = H[p, 3, 3], H[p, :3, 3]
        link_f[p, 4:10] = J[0, 0], J[1, 1], J[2, 2], J[0, 1], J[0, 2], J[1, 2]
    head[F_SEG], head[F_LINK], head[F_ARM] = 0, S * KS, S * KS + L * KF
    w = [KL * L, 6 * n, P, n, n, n, KB, n]
    head[W_LINK:W_SIZE + 1] = np.cumsum([0] + w)
    assert head[W_SIZE] == workspace_size(L, n, P)
    TI = np.concatenate([head] + [np.asarray(b, np.int64).ravel() for b in blocks])
    TF = np.concatenate([seg_f.ravel(), link_f.ravel(), np.array([item[3] for item in arm], float)])
    return np.ascontiguousarray(TI), np.ascontiguousarray(TF)

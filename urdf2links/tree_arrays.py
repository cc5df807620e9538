"""The tree flattened for the compiled kernels: arrays, their packing, and views into them.

:func:`pack_tree` turns a :class:`~urdf2links.tree.LinkTree` into :data:`TreeArrays` (runs of
constant factors multiplied into one rigid transform, variable factors kept); :func:`flat_tree`
packs those into one int64 and one float64 array, so that a compiled call unboxes two arrays
instead of a tuple of fourteen; :func:`tree_view` and :func:`workspace_view` rebuild named views
inside numba at no cost.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np
from numba import njit

from .transforms import elementary

__all__ = ["TreeArrays", "Workspace", "pack_tree", "flat_tree", "flat_workspace", "workspace_size",
           "tree_view", "workspace_view"]

TreeArrays = namedtuple("TreeArrays", [
    "parent",      # (L,) int64
    "seg_ptr",     # (L + 1,) int64: link p's factors are seg_ptr[p]:seg_ptr[p + 1]
    "seg_kind",    # (S,) int64: 0 constant (seg_R, seg_p), 1 variable (slot, coord, offset)
    "seg_slot",    # (S,) int64 0..5
    "seg_coord",   # (S,) int64
    "seg_off",     # (S,) float
    "seg_R",       # (S, 3, 3)
    "seg_p",       # (S, 3)
    "mass",        # (L,)  H[3, 3]
    "moment",      # (L, 3) H[:3, 3] = m r_C in the link frame
    "second",      # (L, 3, 3) H[:3, :3] = int r r^T dm in the link frame
    "coord_link",  # (n,) int64
    "anc_ptr",     # (n + 1,) int64: coordinates l <= i whose link is link(i) or an ancestor of it
    "anc_idx",     # (P,) int64
])

Workspace = namedtuple("Workspace", [
    "R", "o", "V", "Acc",         # (L, 3, 3), (L, 3), (L, 6), (L, 6): pose, twist (w, v), acc.
    "s",                          # (n, 6) unit twists (w_i, v_i)
    "cm", "cc", "cS",             # (L,), (L, 3), (L, 3, 3): subtree m, c, S in {0}
    "fi", "fx",                   # (L, 6): subtree inertial (with gravity) / external wrench (f, n)
    "A", "b", "Q", "Lf",          # (n, n), (n,), (n,), (n, n) tree-sized
    "cur",                        # (24,) scratch: R (9), o (3), V (6), Acc (6)
    "tmp",                        # (30,) scratch
    "base_twist", "base_acc",     # (6,), (6,): twist and spatial acceleration of {A} (no gravity)
])

_INT_FIELDS = ("parent", "seg_ptr", "seg_kind", "seg_slot", "seg_coord", "coord_link", "anc_ptr", "anc_idx")
_FLOAT_FIELDS = ("seg_off", "seg_R", "seg_p", "mass", "moment", "second")


def pack_tree(tree) -> TreeArrays:
    """Flatten a :class:`~urdf2links.tree.LinkTree` for the kernels: runs of constant factors are
    multiplied into one rigid transform (identity factors dropped), variable factors are kept."""
    kinds, slots, coords, offs, Rs, ps, ptr = [], [], [], [], [], [], [0]
    for p in range(tree.n_links):
        C = None
        for k in range(6):
            i, v = int(tree.coord[p, k]), float(tree.params[p, k])
            if i < 0:
                if v != 0.0:
                    E = elementary(k, v)
                    C = E if C is None else C @ E
                continue
            if C is not None:
                kinds.append(0), slots.append(0), coords.append(-1), offs.append(0.0)
                Rs.append(C[:3, :3]), ps.append(C[:3, 3])
                C = None
            kinds.append(1), slots.append(k), coords.append(i), offs.append(v)
            Rs.append(np.eye(3)), ps.append(np.zeros(3))
        if C is not None:
            kinds.append(0), slots.append(0), coords.append(-1), offs.append(0.0)
            Rs.append(C[:3, :3]), ps.append(C[:3, 3])
        ptr.append(len(kinds))
    anc = tree.coordinate_ancestor()
    anc_ptr, anc_idx = [0], []
    for i in range(tree.n):
        anc_idx += [l for l in range(i + 1) if anc[i, l]]
        anc_ptr.append(len(anc_idx))
    i64 = lambda x: np.ascontiguousarray(x, dtype=np.int64)
    f64 = lambda x, shape: np.ascontiguousarray(np.reshape(np.asarray(x, dtype=float), shape))
    S = len(kinds)
    H = np.asarray(tree.H, float)
    return TreeArrays(
        parent=i64(tree.parent), seg_ptr=i64(ptr), seg_kind=i64(kinds), seg_slot=i64(slots),
        seg_coord=i64(coords), seg_off=f64(offs, (S,)), seg_R=f64(Rs, (S, 3, 3)), seg_p=f64(ps, (S, 3)),
        mass=f64(H[:, 3, 3], (-1,)), moment=f64(H[:, :3, 3], (-1, 3)), second=f64(H[:, :3, :3], (-1, 3, 3)),
        coord_link=i64(tree.coord_link), anc_ptr=i64(anc_ptr), anc_idx=i64(anc_idx if anc_idx else [0])[:len(anc_idx)],
    )


def flat_tree(ta: TreeArrays) -> tuple[np.ndarray, np.ndarray]:
    """``(I, F)``: the tree as one int64 and one float64 array (header ``L, n, S, P``), so that a
    compiled call unboxes two arrays instead of a tuple of fourteen (the dispatch cost of a
    namedtuple argument is microseconds); :func:`tree_view` rebuilds the views inside numba."""
    L, n, S, P = ta.parent.size, ta.coord_link.size, ta.seg_kind.size, ta.anc_idx.size
    I = np.concatenate([np.array([L, n, S, P], dtype=np.int64)] + [getattr(ta, f).ravel() for f in _INT_FIELDS])
    F = np.concatenate([np.asarray(getattr(ta, f), float).ravel() for f in _FLOAT_FIELDS])
    return np.ascontiguousarray(I), np.ascontiguousarray(F)


def workspace_size(L: int, n: int) -> int:
    return 9 * L + 3 * L + 6 * L + 6 * L + 6 * n + L + 3 * L + 9 * L + 6 * L + 6 * L + 2 * n * n + 2 * n + 24 + 30


def flat_workspace(I: np.ndarray) -> np.ndarray:
    """Scratch for one evaluation at a time (one per thread), as one float64 array."""
    return np.zeros(workspace_size(int(I[0]), int(I[1])))


@njit(cache=True, inline="always")
def tree_view(I, F):
    """:class:`TreeArrays` of views into the flat arrays of :func:`flat_tree`."""
    L, n, S, P = I[0], I[1], I[2], I[3]
    o = 4
    parent = I[o:o + L]
    o += L
    seg_ptr = I[o:o + L + 1]
    o += L + 1
    seg_kind = I[o:o + S]
    o += S
    seg_slot = I[o:o + S]
    o += S
    seg_coord = I[o:o + S]
    o += S
    coord_link = I[o:o + n]
    o += n
    anc_ptr = I[o:o + n + 1]
    o += n + 1
    anc_idx = I[o:o + P]
    f = 0
    seg_off = F[f:f + S]
    f += S
    seg_R = F[f:f + 9 * S].reshape((S, 3, 3))
    f += 9 * S
    seg_p = F[f:f + 3 * S].reshape((S, 3))
    f += 3 * S
    mass = F[f:f + L]
    f += L
    moment = F[f:f + 3 * L].reshape((L, 3))
    f += 3 * L
    second = F[f:f + 9 * L].reshape((L, 3, 3))
    return TreeArrays(parent, seg_ptr, seg_kind, seg_slot, seg_coord, seg_off, seg_R, seg_p,
                      mass, moment, second, coord_link, anc_ptr, anc_idx)


@njit(cache=True, inline="always")
def workspace_view(I, Wf):
    """:class:`Workspace` of views into the flat scratch of :func:`flat_workspace`."""
    L, n = I[0], I[1]
    o = 0
    R = Wf[o:o + 9 * L].reshape((L, 3, 3))
    o += 9 * L
    ov = Wf[o:o + 3 * L].reshape((L, 3))
    o += 3 * L
    V = Wf[o:o + 6 * L].reshape((L, 6))
    o += 6 * L
    Acc = Wf[o:o + 6 * L].reshape((L, 6))
    o += 6 * L
    s = Wf[o:o + 6 * n].reshape((n, 6))
    o += 6 * n
    cm = Wf[o:o + L]
    o += L
    cc = Wf[o:o + 3 * L].reshape((L, 3))
    o += 3 * L
    cS = Wf[o:o + 9 * L].reshape((L, 3, 3))
    o += 9 * L
    fi = Wf[o:o + 6 * L].reshape((L, 6))
    o += 6 * L
    fx = Wf[o:o + 6 * L].reshape((L, 6))
    o += 6 * L
    A = Wf[o:o + n * n].reshape((n, n))
    o += n * n
    b = Wf[o:o + n]
    o += n
    Q = Wf[o:o + n]
    o += n
    Lf = Wf[o:o + n * n].reshape((n, n))
    o += n * n
    cur = Wf[o:o + 24]
    o += 24
    tmp = Wf[o:o + 30]
    return Workspace(R, ov, V, Acc, s, cm, cc, cS, fi, fx, A, b, Q, Lf, cur, tmp, tmp[0:6], tmp[6:12])

"""A plan's constraints and fixed tendons as flat arrays for the compiled right-hand side (issue 45).

:func:`constraint_arrays` packs the plan's :class:`~urdf2links.scenes.constraints.SceneConstraints` (rows,
links, points, frames, polynomial couplings, tendon coefficients, the tendons' springs, dampers and actuators)
into one int block appended to the scene's ``SI`` (its start at ``SI[S_CON]``) and one float block appended to
``SF``; :mod:`urdf2links.scenes.constraint_kernels` reads them (docs/equations.md (E68)-(E72), (E76)).

Int block (offsets relative to its start ``c0``): the header :data:`KCH` (``CM`` rows, ``CNC`` constraints,
``CNT`` tendons, ``CNA`` tendon actuators, ``CMODE`` the change point's rule (0 continue, 1 stop), ``CX`` the
scratch's start in ``X``, ``CX_SIZE`` its size, ``CF`` the float block's start in ``SF``, ``CKEEP``,
``CREC``, ``CACT`` the offsets of the blocks below, ``CNPOINT`` the constraints that need the kinematics);
``keep`` (m,) 1 for a row solved, 0 for a redundant one (E73, set at the run's start); per constraint
``KCI + 2 nt`` ints: kind (0 connect, 1 weld, 2 polynomial), link1, link2, first row, has a second length, and
the masks (nt,) of the tree coordinates that move link1 and link2 (E25); per tendon actuator: its tendon, its
control's function index, its flags (ctrlrange, forcerange).

Float block: per constraint ``KCF + 2 n``: point1, point2 (3,), frame1, frame2 (9,) row-major, the polynomial
(5,), ref1, ref2, the two lengths' coefficients u1, u2 (n,) (a joint row: unit vectors); per tendon ``n + 4``:
its coefficients c (n,), stiffness, damping, the spring's dead band (l_a, l_b); per tendon actuator the
actuators' :data:`KA` numbers.

Scratch (:func:`x_layout`, from ``CX``): Phi, gamma (m,), J (m, n), Z = L^-T J^T stored as rows (m, n), S and
its pivoted factor (m, m), lambda, the Schur right-hand side, the rows solved and at the evaluation before (m,),
a vector (n,), the :data:`KST` statistics (smallest pivot of the rows solved, its time, events recorded, the
failing row, the largest |Phi| before a projection, projections, 1 while a projection evaluates, the times the
rows solved were chosen again) and :data:`KEV` events (time, row, pivot), the pivot order (m,), one point's
Jacobian rows in the tree's coordinates (3, nt), the rows chosen for the solves (m,) (the start's ``keep``; on a
floating base a planar loop's plane turns with the base, and the rows are chosen again among all where they
lose rank: :func:`urdf2links.scenes.constraint_kernels.kkt`).
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["S_CON", "S_XSIZE", "KA", "constraint_arrays", "x_layout", "KCH", "KCI", "KCF", "KEV", "KST", "CM", "CNC", "CNT",
           "CNA", "CMODE", "CX",
           "CX_SIZE", "CF", "CKEEP", "CREC", "CACT", "CNPOINT", "KIND_CONNECT", "KIND_WELD", "KIND_POLY", "MODES",
           "reset_constraint_stats", "set_keep", "kept", "change_point_error"]

(S_CON, S_XSIZE) = (40, 41)    # the scene's SI header slots (urdf2links.scenes.scene_arrays): this block's start,
                               # the scratch's size
KA = 9                         # floats per actuator (scene_arrays' actuators and the tendons' here)
(CM, CNC, CNT, CNA, CMODE, CX, CX_SIZE, CF, CKEEP, CREC, CACT, CNPOINT) = range(12)
KCH = 12
KCI = 5          # ints per constraint before its two masks (nt,) each
KCF = 31         # floats per constraint before its two coefficient vectors (n,) each
KEV = 32         # events kept (the count goes on)
KST = 8          # the statistics' slots in the scratch (module doc)
KIND_CONNECT, KIND_WELD, KIND_POLY = 0, 1, 2
MODES = ("continue", "stop")
"""``[constraints] change_point``: at a Schur pivot below the tolerance, drop the row there and go on, or stop."""


@njit(cache=True, inline="always")
def x_layout(m, n, nt):
    """Offsets in the constraints' scratch (relative to ``CX``): ``(phi, gam, J, Y, S, L, lam, b, act, prev,
    tmp, stats, events, perm, jt, sel, size)``; ``jt`` one point's Jacobian rows in the tree's coordinates (3, nt),
    ``sel`` (m,) the rows chosen for the solves (flags: the start's ``keep``, chosen again where they lose rank)."""
    m, n, nt = max(m, 0), max(n, 0), max(nt, 0)     # never negative, said so to the compiler (no wraparound)
    phi = 0
    gam = phi + m
    J = gam + m
    Y = J + m * n
    S = Y + m * n
    L = S + m * m
    lam = L + m * m
    b = lam + m
    act = b + m
    prev = act + m
    tmp = prev + m
    stats = tmp + max(n, 9)     # a vector (n,), or one point's r, v, a (9,)
    events = stats + KST
    perm = events + 3 * KEV
    jt = perm + m
    sel = jt + 3 * nt
    size = sel + m
    return phi, gam, J, Y, S, L, lam, b, act, prev, tmp, stats, events, perm, jt, sel, size


def reset_constraint_stats(SI, X):
    """A run's start in the scratch ``X``: no smallest pivot yet (inf), no event, no row dropped before, no row
    chosen again; the rows solved are the start's ``keep`` (E73)."""
    c0 = int(SI[S_CON])
    if c0 <= 0:
        return
    m, n, nt = int(SI[c0 + CM]), int(SI[0]), int(SI[1])
    lay = x_layout(m, n, nt)
    xc = int(SI[c0 + CX])
    X[xc + lay[11]:xc + lay[11] + KST] = (np.inf, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 0.0)
    X[xc + lay[9]:xc + lay[9] + m] = 0.0
    X[xc + lay[15]:xc + lay[15] + m] = kept(SI)


def _moves(model):
    """``moves[i, p]``: tree coordinate ``i`` moves link ``p`` (E25), (nt, L) ints."""
    tree = model.tree
    L = tree.n_links
    anc = np.eye(L, dtype=bool)
    for p in range(L):
        s = int(tree.parent[p])
        if s >= 0:
            anc[:, p] |= anc[:, s]
    return anc[np.asarray(tree.coord_link, int)].astype(np.int64) if tree.n else np.zeros((0, L), np.int64)


def _lengths(c, n):
    if c.kind == "tendon":
        u2 = np.zeros(n) if c.coef2 is None else np.asarray(c.coef2, float)
        return np.asarray(c.coef1, float), u2, c.coef2 is not None
    u1, u2 = np.zeros(n), np.zeros(n)
    u1[c.coord1] = 1.0
    if c.coord2 >= 0:
        u2[c.coord2] = 1.0
    return u1, u2, c.coord2 >= 0


def constraint_arrays(plan, tendon_fn, *, sf_at: int, x_at: int, rows: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """``(int block, float block)`` of the plan's constraints (module doc); ``tendon_fn`` the tendon actuators'
    control functions' indices, ``sf_at`` where the float block will start in ``SF``, ``x_at`` where the
    constraints' scratch starts in ``X``; ``rows`` False: the fixed tendons alone (no constraint row)."""
    closure, model = plan.constraints, plan.model
    n, nt = model.n, model.tree.n
    cons = closure.cset.constraints if rows else ()
    m = closure.cset.m if rows else 0
    moves = _moves(model)
    ints, floats, recs = [], [], []
    row = 0
    for c in cons:
        if c.kind in ("joint", "tendon"):
            u1, u2, has2 = _lengths(c, n)
            kind, l1, l2 = KIND_POLY, -1, -1
        else:
            u1, u2, has2 = np.zeros(n), np.zeros(n), False
            kind, l1, l2 = (KIND_CONNECT if c.kind == "connect" else KIND_WELD), int(c.link1), int(c.link2)
        masks = [moves[:, p] if p >= 0 else np.zeros(nt, np.int64) for p in (l1, l2)]
        recs += [kind, l1, l2, row, int(has2), *masks[0], *masks[1]]
        floats += [*np.asarray(c.point1, float), *np.asarray(c.point2, float), *np.ravel(c.frame1), *np.ravel(c.frame2),
                   *np.asarray(c.poly, float), c.ref1, c.ref2, *u1, *u2]
        row += len(c.rows)
    acts, aprm = [], []
    fn = iter(tendon_fn)
    for k, td in enumerate(closure.tendons):
        floats += [*np.asarray(td.coef, float), td.stiffness, td.damping, *td.lengthspring]
        for a in td.actuators:
            acts += [k, next(fn), (1 if a.ctrlrange is not None else 0) | (2 if a.forcerange is not None else 0)]
            aprm += [a.gain, *a.bias, a.gear, *(a.ctrlrange or (0.0, 0.0)), *(a.forcerange or (0.0, 0.0))]
    assert len(aprm) == KA * (len(acts) // 3)
    keep = np.zeros(m, np.int64)
    if m:       # the redundant rows at the scene's initial state (E73) are left out of every solve
        from ..dynamics.constrained import independent_rows

        q0 = plan.scene.initial_state(model)[0]
        keep[independent_rows(closure.cset.terms(q0).J, closure.cset.rows).keep] = 1
    mode = MODES.index(getattr(plan.scene, "change_point", "continue") or "continue")
    size = int(x_layout(m, n, nt)[-1])
    head = [m, len(cons), len(closure.tendons), len(acts) // 3, mode, x_at, size, sf_at, KCH, KCH + m,
            KCH + m + len(recs), sum(c.kind not in ("joint", "tendon") for c in cons)]
    ints = np.asarray(head + list(keep) + recs + acts, np.int64)
    return ints, np.asarray(floats + aprm, float)


def set_keep(SI, keep) -> None:
    """The rows solved (E73): ``keep`` the indices of the independent rows; the others left out."""
    c0 = int(SI[S_CON])
    m = int(SI[c0 + CM])
    flags = np.zeros(m, np.int64)
    flags[np.asarray(keep, int)] = 1
    SI[c0 + SI[c0 + CKEEP]:c0 + SI[c0 + CKEEP] + m] = flags


def kept(SI) -> np.ndarray:
    """The rows solved (E73) as flags (m,) of ints."""
    c0 = int(SI[S_CON])
    m = int(SI[c0 + CM])
    return SI[c0 + SI[c0 + CKEEP]:c0 + SI[c0 + CKEEP] + m].copy()


def change_point_error(plan, t: float, y, row: int):
    """The named :class:`~urdf2links.errors.DynamicsError` of a run that stops at a change point (``[constraints]
    change_point = "stop"``): the rows that lost their independence at ``(t, y)``, the pivot, what to do."""
    from ..dynamics.constrained import kkt_solve
    from ..errors import DynamicsError

    model, cset = plan.model, plan.constraints.cset
    n = model.n
    q, qd = np.asarray(y[:n], float), np.asarray(y[n:2 * n], float)
    where = f"{plan.scene.path or plan.scene.name}: t = {t:.6g} s, q = {np.round(q, 6).tolist()}"
    base = plan.base_state(t)
    T = cset.terms(q, qd, t=t, base=base)
    A = model.mass_matrix(q, t=t, base=base)
    k = list(np.nonzero(kept(plan.rhs.SI))[0])
    try:
        kkt_solve(A, np.zeros(n), T.J[k], T.gamma[k], rows=[cset.rows[i] for i in k], where=where)
    except DynamicsError as e:
        return DynamicsError(f"{e} (the scene stops here: [constraints] change_point = \"stop\"; \"continue\" "
                             "drops the row there and goes on)")
    return DynamicsError(f"{where}: the constraint rows {cset.rows[row]} are not independent here (a pivot of "
                         "J A^-1 J^T at or below 1e-12 of its largest diagonal): a singular configuration of "
                         "the loop, a change point; the scene stops here ([constraints] change_point = \"stop\"; "
                         "\"continue\" drops the row there and goes on)")

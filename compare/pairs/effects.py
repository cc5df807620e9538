"""What the differences do: ``A`` and ``G`` of both descriptions at seeded states in common coordinates,
and which difference explains most of their difference.

Both descriptions are evaluated by the project's own equations (their trees rebuilt from the parts,
:func:`urdf2links.parsers.parts.parts_model`, E51) with the first description's gravity, at ``states``
seeded states of the first description's coordinates (each joint uniform within its limits and
within [-1, 1] of home; the joints with no match at home), mapped into the second's
(:func:`~urdf2links.compare.pairs.mapping.coordinate_map`, E52: ``q_mjcf = sign q_urdf + offset``; its
joints with no match at home), and back: ``A_mapped[i, k] = s_i s_k A_mjcf[i', k']``,
``G_mapped[i] = s_i G_mjcf[i']``. The figures are ``max |A_urdf - A_mapped| / max |A_urdf|`` and the same
for ``G``, over all states and matched coordinates (the largest entry named).

Attribution (E53): each difference is undone alone in the second description (the first
description's value copied in, :attr:`Difference.undo`) and the terms recomputed; a difference explains
the share of the squared difference ``sum |A_urdf - A_mapped|^2`` over states and entries (and the same
for ``G``) that undoing it removes: shares of differences that touch different entries add up to 1
(three equal armatures explain a third each), where the largest entry alone would credit none of them. Then every difference is undone at once: what is
left is what the listed differences do not account for (unmatched joints, or a difference below
rounding that adds up). When a joint maps with sign -1 the same is done with the coordinates taken as
equal by name (sign 1: what a user who believes the files agree sees), where a negated axis shows.
"""

from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np

from urdf2links.parsers.parts import JOINT_KINDS, RobotParts

from .context import PairContext
from .differences import Difference, Side, side_model

__all__ = ["evaluate_effects", "seeded_states", "Terms", "effect_size", "order_differences", "ORDER_WORDS",
           "EFFECT_ROUNDING", "NOT_IN_A_G", "UNSEEN_CANDIDATES", "unseen_group"]


def seeded_states(parts: RobotParts, coordinate_names, mapped: set, *, states: int = 8, seed: int = 0) -> np.ndarray:
    """``(states, n)`` configurations of the first description (module doc)."""
    rng = np.random.default_rng(seed)
    index = {n: i for i, n in enumerate(coordinate_names)}
    Q = np.zeros((states, len(coordinate_names)))
    for j, _b in parts.joints:
        for k, name in enumerate(j.coordinates):
            home = float(j.home[k]) if k < len(j.home) else 0.0
            if name not in mapped:
                Q[:, index[name]] = home
                continue
            lo, hi = home - 1.0, home + 1.0
            if len(JOINT_KINDS[j.kind]) == 1 and j.lower is not None and j.upper is not None and j.lower < j.upper:
                lo, hi = max(lo, j.lower), min(hi, j.upper)
                if lo >= hi:
                    lo, hi = j.lower, j.upper
            Q[:, index[name]] = rng.uniform(lo, hi, states)
    return Q


class Terms:
    """``A`` (S, n, n) and ``G`` (S, n) of the first description, and the machinery to compare another
    side's against them (module doc)."""

    def __init__(self, ctx: PairContext, *, states: int, seed: int):
        self.ctx = ctx
        U = ctx.urdf
        self.model = ctx.model_urdf.model
        self.names = self.model.coordinate_names
        ju = {m.urdf for m in ctx.mapping.matches}
        mapped = {c for j, _ in U.joints if j.name in ju for c in j.coordinates}
        self.Q = seeded_states(U, self.names, mapped, states=states, seed=seed)
        self.A = np.array([self.model.mass_matrix(q) for q in self.Q])
        self.G = np.array([self.model.gravity(q) for q in self.Q])
        self.gravity = np.asarray(U.gravity, float)

    def compare(self, side: Side, *, signs: bool = True) -> dict:
        """``{"A": rel, "G": rel, "worst_A": ..., "worst_G": ...}`` of ``side`` against the first description."""
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            pm = side_model(side, gravity=self.gravity)
        m = pm.model
        cmap = self.ctx.coordinate_map(side.parts, signs=signs)
        iu = np.array([self.names.index(a) for a, *_ in cmap], dtype=int)
        im = np.array([m.coordinate_names.index(b) for _, b, *_ in cmap], dtype=int)
        s = np.array([x[2] for x in cmap], float)
        c = np.array([x[3] for x in cmap], float)
        q0 = _home(side.parts, m.coordinate_names)
        dA = dG = 0.0
        sA = sG = 0.0
        worst_A = worst_G = None
        mapped_A, mapped_G = [], []
        for k, q in enumerate(self.Q):
            qm = q0.copy()
            qm[im] = s * q[iu] + c
            Am = m.mass_matrix(qm)[np.ix_(im, im)] * np.outer(s, s)
            Gm = m.gravity(qm)[im] * s
            mapped_A.append(Am)
            mapped_G.append(Gm)
            Au, Gu = self.A[k][np.ix_(iu, iu)], self.G[k][iu]
            sA += float(np.sum((Au - Am) ** 2))
            sG += float(np.sum((Gu - Gm) ** 2))
            if Au.size:
                i, j = np.unravel_index(int(np.argmax(np.abs(Au - Am))), Au.shape)
                if abs(Au[i, j] - Am[i, j]) > dA or worst_A is None:
                    dA = max(dA, float(abs(Au[i, j] - Am[i, j])))
                    worst_A = {"entry": [self.names[iu[i]], self.names[iu[j]]], "urdf": float(Au[i, j]),
                               "mjcf": float(Am[i, j]), "state": k}
                i = int(np.argmax(np.abs(Gu - Gm)))
                if abs(Gu[i] - Gm[i]) > dG or worst_G is None:
                    dG = max(dG, float(abs(Gu[i] - Gm[i])))
                    worst_G = {"coordinate": self.names[iu[i]], "urdf": float(Gu[i]), "mjcf": float(Gm[i]), "state": k}
        scale_A = float(np.max(np.abs(self.A[:, iu][:, :, iu]))) if iu.size else 0.0
        scale_G = float(np.max(np.abs(self.G[:, iu]))) if iu.size else 0.0
        return {"A": dA / scale_A if scale_A > 0 else (0.0 if dA == 0 else np.inf),
                "G": dG / scale_G if scale_G > 0 else (0.0 if dG == 0 else np.inf),
                "worst_A": worst_A, "worst_G": worst_G, "scale_A": scale_A, "scale_G": scale_G,
                "sq_A": sA, "sq_G": sG, "terms": (np.array(mapped_A), np.array(mapped_G), tuple(im)),
                "first_coordinates": tuple(iu)}


def _home(parts: RobotParts, names) -> np.ndarray:
    q = np.zeros(len(names))
    index = {n: i for i, n in enumerate(names)}
    for j, _ in parts.joints:
        for k, n in enumerate(j.coordinates):
            if k < len(j.home):
                q[index[n]] = float(j.home[k])
    return q


def _explained(before: float, after: float) -> float:
    """The share of the squared difference (E53) that an undo removes: shares of independent differences add up."""
    if before <= 0 or not np.isfinite(before):
        return 0.0
    return float((before - after) / before)


def _attribute(terms: Terms, diffs: list[Difference], *, signs: bool) -> tuple[dict, list[dict]]:
    M = terms.ctx.mjcf
    base = terms.compare(Side(M), signs=signs)
    rows = []
    for i, d in enumerate(diffs):
        if d.undo is None:
            continue
        after = terms.compare(d.undo(Side(M)), signs=signs)
        rows.append({"index": i, "A_after": after["A"], "G_after": after["G"],
                     "explains_A": _explained(base["sq_A"], after["sq_A"]),
                     "explains_G": _explained(base["sq_G"], after["sq_G"]),
                     "changes_A": _change(base, after, 0), "changes_G": _change(base, after, 1)})
    return base, rows


def _change(base: dict, after: dict, k: int) -> float:
    """What undoing one difference alone changes in ``A`` (``k`` 0) or ``G`` (1): the largest change of an entry
    over the states, relative to the first description's largest entry (as the figures of :meth:`Terms.compare`);
    inf when the undo changes which coordinates map."""
    (b, a), scale = (base["terms"][k], after["terms"][k]), base["scale_A" if k == 0 else "scale_G"]
    if base["terms"][2] != after["terms"][2] or b.shape != a.shape:
        return np.inf
    d = float(np.max(np.abs(b - a))) if b.size else 0.0
    return d / scale if scale > 0 else (0.0 if d == 0 else np.inf)


#: The order in which every difference is undone at once: frames before what is expressed in them (an axis is
#: set relative to the body above as the body is then placed).
_UNDO_ORDER = {"root_pose": 0, "origin": 1, "axis": 2}


def _undo_all(terms: Terms, diffs: list[Difference], *, signs: bool) -> dict:
    side = Side(terms.ctx.mjcf)
    for d in sorted(diffs, key=lambda d: _UNDO_ORDER.get(d.kind, 3)):
        if d.undo is not None:
            side = d.undo(side)
    r = terms.compare(side, signs=signs)
    return {"A": r["A"], "G": r["G"]}


#: The groups of kinds tried, in turn, as "values differ, dynamics equal" (:func:`unseen_group`): the links'
#: inertial values with the joints' armatures (an armature and the inertia of the link it turns can trade, E49),
#: then the inertial values alone. ``A`` and ``G`` are linear in each link's ``H`` (E10, E89): only combinations
#: of the ``H`` (the base parameters, E91) are seen by the equations of motion, so single values can differ while
#: ``A`` and ``G`` agree.
UNSEEN_CANDIDATES = (("mass", "com", "inertia", "armature"), ("mass", "com", "inertia"))


def unseen_group(terms: Terms, diffs: list[Difference], *, signs: bool = True) -> dict | None:
    """The largest group of differences (of the kinds of :data:`UNSEEN_CANDIDATES`, tried in turn, at least two not
    at rounding alone) that together change neither ``A`` nor ``G`` beyond :data:`EFFECT_ROUNDING`: every other
    difference undone in the second description, the terms still agree at every seeded state. None when there is
    none, or when a difference outside the group that acts on ``A`` or ``G`` cannot be undone (then the group's own
    effect cannot be told apart). ``{"indices", "kinds", "A", "G", "states"}``.

    Why the seeded states suffice: ``A`` and ``G`` are linear in the links' ``H``; a change of the ``H`` that leaves
    them equal at the states (to rounding) lies in the null space of that linear map at those states, and with
    ``S`` random states (S (n(n+1)/2 + n) equations against 10 per link) that null space is the one of every state
    (tests/test_identify_compare.py checks the ranks agree with 64 states), so ``A`` agrees everywhere, and with it
    its derivatives: the velocity terms, which follow from ``A`` (E20), agree too."""
    for kinds in UNSEEN_CANDIDATES:
        group = [i for i, d in enumerate(diffs) if d.kind in kinds and d.undo is not None]
        if sum(not (diffs[i].effect or {}).get("at_rounding") for i in group) < 2:
            continue
        rest = [d for i, d in enumerate(diffs) if i not in group]
        if any(d.undo is None and d.kind not in NOT_IN_A_G and d.kind != "root_pose" for d in rest):
            return None
        r = _residual(terms, rest, [d.urdf for d in rest if d.kind == "armature"], signs=signs)
        if r["A"] <= EFFECT_ROUNDING and r["G"] <= EFFECT_ROUNDING:
            return {"indices": group, "kinds": sorted({diffs[i].kind for i in group}), "states": int(len(terms.Q)),
                    **r}
    return None


def _residual(terms: Terms, rest: list[Difference], armature_joints: list, *, signs: bool) -> dict:
    """A and G of the first description against the second with ``rest`` undone (relative, as :meth:`Terms.compare`),
    less a constant diagonal of ``A`` on the coordinates of ``armature_joints`` (the first description's joints
    whose armature differs, that difference undone in ``rest``): the inertias of a group may carry part of an
    armature (a URDF cannot hold one, and ``identify --write-urdf`` moves what it can of one into the links, E49),
    which the armature's difference, listed and dynamic, accounts for; that part is ``carried`` ({coordinate:
    kg m^2})."""
    side = Side(terms.ctx.mjcf)
    for d in sorted(rest, key=lambda d: _UNDO_ORDER.get(d.kind, 3)):
        if d.undo is not None:
            side = d.undo(side)
    r = terms.compare(side, signs=signs)
    Am, Gm, _im = r["terms"]
    iu = np.array(r["first_coordinates"], dtype=int)
    if not iu.size:
        return {"A": r["A"], "G": r["G"], "carried": {}}
    dA = terms.A[:, iu][:, :, iu] - Am
    dG = terms.G[:, iu] - Gm
    carried = {}
    joints = {j.name: j.coordinates for j, _b in terms.ctx.urdf.joints}
    for name in armature_joints:
        for c in joints.get(name, ()):
            k = [terms.names[i] for i in iu].index(c) if c in [terms.names[i] for i in iu] else None
            if k is not None:
                carried[c] = float(np.mean(dA[:, k, k]))
                dA[:, k, k] -= carried[c]
    return {"A": float(np.max(np.abs(dA))) / r["scale_A"] if r["scale_A"] > 0 else r["A"],
            "G": float(np.max(np.abs(dG))) / r["scale_G"] if r["scale_G"] > 0 else r["G"], "carried": carried}


def _summary(base, rows, diffs, label) -> dict:
    out = {"A": {"max_rel_difference": base["A"], "largest": base["worst_A"]},
           "G": {"max_rel_difference": base["G"], "largest": base["worst_G"]}, "coordinates": label}
    for term in ("A", "G"):
        best = max(rows, key=lambda r: r[f"explains_{term}"], default=None)
        if best is not None and best[f"explains_{term}"] > 0.0:
            d = diffs[best["index"]]
            out[term]["explained_by"] = {"kind": d.kind, "urdf": d.urdf, "mjcf": d.mjcf,
                                         "explains": best[f"explains_{term}"], "after_undoing": best[f"{term}_after"]}
        else:
            out[term]["explained_by"] = None
    return out


def evaluate_effects(ctx: PairContext, diffs: list[Difference], *, states: int = 8, seed: int = 0) -> dict:
    """``A`` and ``G`` of both descriptions of the pair ``ctx`` at seeded states, the attribution to ``diffs`` (each
    difference's ``effect`` is set), and what is left with every difference undone (module doc). JSON-ready."""
    terms = Terms(ctx, states=states, seed=seed)
    base, rows = _attribute(terms, diffs, signs=True)
    effects = {i: {"A_after": None, "G_after": None, "explains_A": 0.0, "explains_G": 0.0, "changes_A": None,
                   "changes_G": None} for i in range(len(diffs))}
    for r in rows:
        effects[r["index"]] = {k: v for k, v in r.items() if k != "index"}
    out = {"states": states, "seed": seed, "gravity": terms.gravity.tolist(),
           "mapped": _summary(base, rows, diffs, "mapped: q_mjcf = sign q_urdf + offset"),
           "after_undoing_all": _undo_all(terms, diffs, signs=True)}
    if any(m.sign < 0 for m in ctx.mapping.matches):
        base_n, rows_n = _attribute(terms, diffs, signs=False)
        out["as_named"] = _summary(base_n, rows_n, diffs, "as named: q_mjcf = q_urdf + offset (every sign 1)")
        for r in rows_n:
            e = effects[r["index"]]
            e["as_named_explains_A"], e["as_named_explains_G"] = r["explains_A"], r["explains_G"]
            e["as_named_changes_A"], e["as_named_changes_G"] = r["changes_A"], r["changes_G"]
    for i, d in enumerate(diffs):
        e = effects[i]
        e["undoable"] = d.undo is not None
        e["at_rounding"] = _at_rounding(d, e)
        d.effect = e
    group = unseen_group(terms, diffs)
    out["dynamics_equal"] = None if group is None else {k: v for k, v in group.items() if k != "indices"} | {
        "count": len(group["indices"])}
    for i in (group or {}).get("indices", ()):
        diffs[i].effect["dynamics_equal"] = True
    return out


#: An effect on ``A`` or ``G`` at or below this (relative to the term's largest entry) is rounding: MuJoCo's XML
#: writer keeps 6 significant digits, and a URDF against MuJoCo's import of itself agrees to it
#: (tests/test_pairs_corpus.py: below 1e-5 for every robot imported as written).
EFFECT_ROUNDING = 1e-5

#: The kinds that are no term of ``A`` or ``G`` (limits, forces, speeds, frames, collision geometry; damping,
#: stiffness and friction act on the motion, not on A and G): their effect on A and G is nil.
NOT_IN_A_G = ("limits", "effort", "velocity", "frame_missing", "collision", "damping", "stiffness", "friction")


def _at_rounding(d: Difference, e: dict) -> bool | None:
    """Whether what ``d`` does to ``A`` and ``G`` is at rounding (:data:`EFFECT_ROUNDING`): the change undoing it
    alone makes, mapped and (with a negated axis) as named; None when it cannot be undone (its effect is in
    ``after_undoing_all``)."""
    if d.kind in NOT_IN_A_G or (d.kind == "root_pose" and d.undo is None):
        return True               # a floating root's pose at home is a state: both are evaluated from the same
    changes = [e.get(k) for k in ("changes_A", "changes_G", "as_named_changes_A", "as_named_changes_G") if k in e]
    if d.undo is None or any(c is None for c in changes[:2]):
        return None
    return bool(all(c <= EFFECT_ROUNDING for c in changes if c is not None))


def effect_size(d: Difference, effects: dict | None = None) -> float:
    """What undoing ``d`` alone changes in ``A`` or ``G`` (the larger, relative to the term's largest entry; mapped,
    and as named with a negated axis), 0 when that is at rounding (:data:`EFFECT_ROUNDING`), nil, or not known (a
    type, a missing joint or link, a coupling: they cannot be undone alone): the order of :func:`order_differences`.
    ``effects`` is not needed (kept for callers that pass it)."""
    e = d.effect or {}
    if e.get("dynamics_equal"):
        return 0.0                # with the others of its group it changes neither A nor G (unseen_group)
    values = [e.get(k) for k in ("changes_A", "changes_G", "as_named_changes_A", "as_named_changes_G")]
    best = max([float(v) for v in values if v is not None] + [0.0])
    return 0.0 if best <= EFFECT_ROUNDING else best


#: The order of every printed list of differences, in words (stdout, summary.md, the HTML).
ORDER_WORDS = ("largest effect on A and G first (what undoing each alone changes in A or G, relative to the "
               "term's largest entry; 0 at rounding or when it cannot be undone alone), then by how many times its "
               "rounding level the difference is")


def order_differences(diffs: list[Difference], effects: dict | None = None) -> list[Difference]:
    """:data:`ORDER_WORDS`: by :func:`effect_size`, then by :attr:`Difference.ratio` (damping, limits and the like
    change no term), then by kind and names (a stable order)."""
    return sorted(diffs, key=lambda d: (-effect_size(d), -d.ratio, d.kind, str(d.urdf), str(d.mjcf)))

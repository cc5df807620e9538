"""One pair of descriptions compared: read, map, compare part by part, say what each difference does.

:func:`compare_descriptions_of` is the description half of ``urdf2links compare A --against B`` and of
every pair of ``urdf2links report --pairs``: both files read as parts
(:func:`urdf2links.parsers.parts.robot_parts`), their joints matched
(:func:`~urdf2links.compare.pairs.mapping.map_joints`) into the pair's context, computed once
(:func:`~urdf2links.compare.pairs.context.pair_context`), compared
(:func:`~urdf2links.compare.pairs.differences.compare_descriptions`), the differences' effects on ``A``
and ``G`` attributed (:func:`~urdf2links.compare.pairs.effects.evaluate_effects`) and ordered, largest
first. :meth:`PairComparison.summary` is the JSON the report writes (``joint_mapping``,
``description_differences``, ``description_effects``), and :meth:`PairComparison.check` the verdict
against tolerances.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from urdf2links.compilation import clock  # durations without numba's compilation
from urdf2links.console import shown_path
from urdf2links.parsers.parts import RobotParts, robot_parts

from .constraints import constraint_differences
from .collisions import collision_differences
from .context import PairContext, pair_context
from .couplings import coupling_differences
from .differences import KINDS, ROUNDING, Difference, compare_descriptions
from .effects import evaluate_effects, order_differences
from .explanations import explain
from .mapping import JointMapping

__all__ = ["PairComparison", "compare_descriptions_of", "TERM_KEYS", "check_tolerances", "exceedances", "DYNAMIC_KINDS",
           "DYNAMICS_EQUAL_WORDS"]

#: The kinds that change the dynamics (A, G, the joint forces); the others (limits, effort, velocity, frames,
#: collision geometry) do not, and ``root_pose`` is counted apart.
DYNAMIC_KINDS = ("mass", "com", "inertia", "origin", "axis", "armature", "damping", "stiffness", "friction", "type",
                 "joint_missing", "link_missing", "constraint", "coupling")

#: What a difference of the group "values differ, dynamics equal" is (effects.unseen_group): not counted as a
#: dynamic difference.
DYNAMICS_EQUAL_WORDS = ("values differ, dynamics equal: with the others of the group they change neither A nor G "
                        "beyond rounding at the seeded states (these parameters are not seen by the equations of "
                        "motion of this tree: only combinations of them are)")

#: Tolerances a pair may give besides the kinds: the relative differences of ``A`` and ``G`` (mapped).
TERM_KEYS = ("A", "G")


@dataclass(eq=False)
class PairComparison:
    """The pair's :class:`~urdf2links.compare.pairs.context.PairContext` (both descriptions' parts, home poses,
    joint mapping, matched bodies, the roots' alignment), the ordered differences, their effects, notes."""

    context: PairContext
    urdf_path: Path
    mjcf_path: Path
    differences: list[Difference]
    below_rounding: dict
    effects: dict
    notes: list[str] = field(default_factory=list)
    seconds: float = 0.0

    @property
    def urdf(self) -> RobotParts:
        """The first description's parts."""
        return self.context.urdf

    @property
    def mjcf(self) -> RobotParts:
        """The second description's parts."""
        return self.context.mjcf

    @property
    def mapping(self) -> JointMapping:
        return self.context.mapping

    def first_of(self, kind: str) -> Difference | None:
        """The largest difference of ``kind`` (None when there is none above rounding)."""
        return next((d for d in self.differences if d.kind == kind), None)

    def summary(self) -> dict:
        """The JSON of the description half (module doc)."""
        counts = {k: sum(d.kind == k for d in self.differences) for k in KINDS}
        equal = [d for d in self.differences if (d.effect or {}).get("dynamics_equal")]
        dyn = [d for d in self.differences if d.kind in DYNAMIC_KINDS and d not in equal]
        eff = self.effects["mapped"]
        group = self.effects.get("dynamics_equal") or {}
        head = {"dynamics": {"count": len(dyn), "kinds": sorted({d.kind for d in dyn}),
                             "effect": {"A": eff["A"]["max_rel_difference"], "G": eff["G"]["max_rel_difference"],
                                        "after_undoing_all": dict(self.effects["after_undoing_all"])}},
                "non_dynamic": {"count": sum(d.kind not in DYNAMIC_KINDS and d.kind != "root_pose"
                                             for d in self.differences),
                                "kinds": sorted({d.kind for d in self.differences
                                                 if d.kind not in DYNAMIC_KINDS and d.kind != "root_pose"})},
                "dynamics_equal": {"count": len(equal), "kinds": sorted({d.kind for d in equal}),
                                   "states": group.get("states"), "A": group.get("A"), "G": group.get("G"),
                                   "carried_armature": {c: v for c, v in (group.get("carried") or {}).items()
                                                        if abs(v) > 1e-9},
                                   "what": DYNAMICS_EQUAL_WORDS},
                "root_pose": {"count": counts.get("root_pose", 0),
                              "floating": bool(self.mapping.root and all(self.mapping.root.floating))}}
        return {
            "description_counts": head,
            "descriptions": {"urdf": {"file": shown_path(self.urdf_path), "format": self.urdf.format,
                                      "name": self.urdf.name, "bodies": len(self.urdf.bodies),
                                      "joints": len(self.urdf.joints)},
                             "mjcf": {"file": shown_path(self.mjcf_path), "format": self.mjcf.format,
                                      "name": self.mjcf.name, "bodies": len(self.mjcf.bodies),
                                      "joints": len(self.mjcf.joints)},
                             "note": "'urdf' is the first description, 'mjcf' the one given with --against "
                                     "(either may be a URDF, xacro or MJCF file)"},
            "joint_mapping": self.mapping.to_json(),
            "description_differences": [d.to_json() for d in self.differences],
            "description_difference_counts": {"listed": counts, "below_rounding": dict(self.below_rounding),
                                              "rounding": dict(ROUNDING)},
            "description_effects": self.effects,
            "description_notes": list(self.notes),
        }

    def check(self, tolerances: dict | None = None) -> list[str]:
        """What exceeds ``tolerances`` (``{kind or "A"/"G": number}``, in each kind's unit; a kind not given is
        held to its rounding level): one line per failure, empty when the pair passes."""
        return check_tolerances(self.summary(), tolerances)


def check_tolerances(summary: dict, tolerances: dict | None = None) -> list[str]:
    """:meth:`PairComparison.check` on a written summary (``summary.json`` of a pair)."""
    return [e["text"] for e in exceedances(summary, tolerances)]


def _value(v) -> float:
    return math.inf if v in ("inf", "nan") else float(v)


def exceedances(summary: dict, tolerances: dict | None = None) -> list[dict]:
    """What of a pair's ``summary`` exceeds ``tolerances`` (:meth:`PairComparison.check`), one dict each:
    ``kind`` (a difference kind, or ``A``/``G``), ``value``, ``limit``, ``text`` (the line), and for a
    difference ``difference`` (its JSON: names, both values, unit)."""
    tol = dict(tolerances or {})
    bad = [k for k in tol if k not in KINDS and k not in TERM_KEYS]
    if bad:
        raise ValueError(f"tolerances: unknown key(s) {bad}; the kinds are {list(KINDS)}, and A, G for the terms")
    out = []
    floating = bool(summary.get("description_counts", {}).get("root_pose", {}).get("floating"))
    for d in summary["description_differences"]:
        if d["kind"] == "root_pose" and floating and "root_pose" not in tol:
            continue                  # a floating root's pose at home is a state, not a description difference
        limit = float(tol.get(d["kind"], ROUNDING.get(d["kind"], 0.0)))
        value = _value(d["difference"])
        if not value <= limit:
            names = " / ".join(str(n) for n in (d["urdf"], d["mjcf"]) if n)
            out.append({"kind": d["kind"], "value": value, "limit": limit, "difference": d,
                        "text": f"{d['kind']} {names}: {value:.4g} {d['unit']} > {limit:g}"})
    eff = summary["description_effects"]["mapped"]
    for term in TERM_KEYS:
        if term in tol:
            value = _value(eff[term]["max_rel_difference"])
            if not value <= float(tol[term]):
                out.append({"kind": term, "value": value, "limit": float(tol[term]),
                            "text": f"{term}: max relative difference {value:.4g} > {float(tol[term]):g}"})
    return out


def _notes(U: RobotParts, M: RobotParts) -> list[str]:
    notes = []
    if not np.allclose(U.gravity, M.gravity):
        notes.append(f"gravity differs: {U.gravity.tolist()} ({U.format}) against {M.gravity.tolist()} ({M.format}); "
                     "A and G are compared with the first description's, the motion runs each file's own")
    for label, p in (("urdf", U), ("mjcf", M)):
        notes += [f"{label}: {n}" for n in p.notes if "MuJoCo said" in n]
    return notes


def compare_descriptions_of(urdf, mjcf, *, explicit_map: dict | None = None, load: dict | None = None,
                            states: int = 8, seed: int = 0) -> PairComparison:
    """Compare the robot files ``urdf`` and ``mjcf`` part by part (module doc). ``explicit_map``: ``{urdf
    joint: mjcf joint}`` (``--map``); ``load``: the first file's loading options (``floating_base``,
    ``package_dirs``, ``strict``, ``xacro_args``; the second takes ``package_dirs`` and ``xacro_args`` too when
    it is a URDF)."""
    start = clock()
    load = dict(load or {})
    U = robot_parts(urdf, **load)
    M = robot_parts(mjcf, **{k: v for k, v in load.items() if k != "floating_base"})
    ctx = pair_context(U, M, explicit_map=explicit_map)       # computed once: everything below reads it
    diffs, below = compare_descriptions(ctx)
    collisions, below["collision"] = collision_differences(ctx, load=load)
    diffs += collisions
    diffs += constraint_differences(urdf, mjcf)      # issue 36: loops closed on one side only
    diffs += coupling_differences(urdf, mjcf, ctx.mapping, load=load)
    explain(diffs, U, M)
    effects = evaluate_effects(ctx, diffs, states=states, seed=seed)
    ordered = order_differences(diffs, effects)
    return PairComparison(ctx, Path(urdf), Path(mjcf), ordered, below, effects, _notes(U, M), clock() - start)

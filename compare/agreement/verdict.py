"""The verdict of a comparison: what the engines' agreement is, and what it checked.

"The engines agree to 1e-13" is only as good as the run behind it. :func:`comparison_verdict` joins
the trajectory's agreement with what qualifies it, each stated in the verdict itself (not only in the
notes):

* **scope** (:func:`cut_scope`): a model whose equality constraints, tendons or mimic couplings were
  dropped on both sides runs as the open tree of a closed (or coupled) mechanism: "open tree of a
  closed mechanism (N constraints, M tendons dropped)";
* **weak evidence** (E67, :mod:`urdf2links.scenes.coverage`): fewer than half of the coordinates moved;
* **MuJoCo's blow-up** and the stable setting that replaced it
  (:func:`urdf2links.compare.mujoco_side.stable_run.stable_run`), or a blow-up that nothing replaced.

``summary()["verdict"]`` of a comparison is :func:`comparison_verdict`'s dictionary; its ``text`` is
also ``summary()["trajectory"]["verdict"]``, the line reports show.
"""

from __future__ import annotations

from ..mujoco_side.mujoco_run import instability_note

__all__ = ["cut_scope", "comparison_verdict", "FULL_SCOPE"]

#: ``verdict.scope`` of a model that nothing was cut from.
FULL_SCOPE = "the whole model"


def cut_scope(model, load_options: dict | None = None, plan=None) -> dict:
    """What of ``model``'s mechanism both engines leave out: ``equalities`` and ``tendons`` of an MJCF
    file (MuJoCo's run disables them; the tree has none), ``mimic`` couplings of a URDF loaded with
    ``mimic="independent"``; ``text`` is :data:`FULL_SCOPE` when nothing was cut, else
    "open tree of a closed mechanism (N constraints, M tendons dropped)". With ``plan``, what its
    constraints model is not cut (issue 36: ``[constraints] from_file``, ``mimic``): the file's equalities it
    solves, its fixed tendons, and every fixed tendon that carries no force (nothing to drop)."""
    closed = model.info.get("closed") or {}
    eq, tendons = int(closed.get("equalities", 0)), int(closed.get("tendons", 0))
    coupled = (load_options or {}).get("mimic", "independent") == "independent"
    mimic = sum(1 for j in model.info.get("joints", []) if j.get("mimic")) if coupled else 0
    scene = getattr(plan, "scene", None)
    if scene is not None and getattr(scene, "file_constraints", False):
        cons = plan.constraints
        eq -= 0 if cons is None else sum(1 for c in cons.cset.constraints if c.source.startswith("MJCF"))
        named = {a.name for a in getattr(scene, "actuators", ())}   # the others act on neither engine (notes)
        inert = [t for t in model.info.get("tendons", []) if t["fixed"] and not (
            t["stiffness"] or t["damping"] or set(t["actuators"]) & named or t["limited"] or t["frictionloss"])]
        tendons -= (0 if cons is None else len(cons.tendons)) + len(inert)
    if scene is not None and getattr(scene, "mimic_constraints", False):
        mimic = 0
    out = {"equalities": eq, "tendons": tendons, "mimic": mimic, "cut": bool(eq or tendons or mimic)}
    if eq or tendons:
        out["text"] = (f"open tree of a closed mechanism ({eq} constraint{'s' * (eq != 1)}, {tendons} "
                       f"tendon{'s' * (tendons != 1)} dropped)" + (f", {mimic} mimic couplings dropped" if mimic else ""))
    elif mimic:
        out["text"] = (f"open tree of a coupled mechanism ({mimic} mimic coupling{'s' * (mimic != 1)} dropped: the "
                       "mimic joints move as independent coordinates)")
    else:
        out["text"] = FULL_SCOPE
    return out


def _mujoco_part(run_integrator: str, run_timestep: float, blow_ups: dict, fallback: dict | None) -> str | None:
    """The verdict's words on MuJoCo's stability: the fallback that replaced a blow-up, or the blow-up."""
    if fallback and fallback.get("chosen"):
        a, c = fallback["asked"], fallback["chosen"]
        conv = fallback.get("convergence") or {}
        return (f"MuJoCo {a['integrator']} blew up at dt {a['timestep']:g} s, so MuJoCo ran {c['integrator']} at dt "
                f"{c['timestep']:g} s instead (stable; "
                + ("converged" if fallback.get("converged") else "NOT converged")
                + (f": {conv['max_abs_difference']:.2g} from its run at half the step)" if conv else ")"))
    if blow_ups:
        return instability_note(blow_ups, run_integrator, run_timestep) + ": the difference is MuJoCo's blow-up"
    return None


def comparison_verdict(agreement: str, *, scope: dict, coverage, mujoco_integrator: str, mujoco_timestep: float,
                       blow_ups: dict, fallback: dict | None) -> dict:
    """The verdict (module doc): ``agreement`` (the trajectories' sentence), ``scope`` (:func:`cut_scope`),
    ``weak_evidence`` and ``coverage`` (:class:`~urdf2links.scenes.coverage.Coverage`'s line), ``mujoco``
    (the fallback or blow-up sentence, or None) and ``text``, all of them in one paragraph."""
    parts = [agreement.rstrip(".")]
    if scope["cut"]:
        parts.append(f"as the {scope['text']}, not the whole mechanism")
    mj = _mujoco_part(mujoco_integrator, mujoco_timestep, blow_ups, fallback)
    if mj:
        parts.append(mj)
    if coverage.weak:
        parts.append(f"WEAK EVIDENCE: {coverage.text().split(':')[0]}")
    return {"text": "; ".join(parts) + ".", "agreement": agreement, "scope": scope["text"], "cut": scope,
            "weak_evidence": bool(coverage.weak), "coverage": coverage.text(), "moved_fraction": coverage.moved_fraction,
            "mujoco": mj}

"""The verdict of a comparison: what the engines' agreement is, and what it checked.

"The engines agree to 1e-13" is only as good as the run behind it. :func:`comparison_verdict` joins
the trajectory's agreement with what qualifies it, each stated in the verdict itself (not only in the
notes):

* **plausibility first** (:mod:`urdf2links.compare.agreement.plausibility`): a run that fails the gate on
  either engine (a body through its ground, a joint far past a limit, a speed no robot reaches, energy
  gained in a passive scene) gets "implausible run: <reasons>", never "agree" or "DIVERGE";
* **scope** (:func:`cut_scope`, :func:`switched_off`, :func:`run_scope`): a model whose equality
  constraints, tendons or mimic couplings were dropped on both sides runs as the open tree of a closed (or
  coupled) mechanism: "open tree of a closed mechanism (N constraints, M tendons dropped)"; every effect of
  the file switched off on both engines (contact, joint limits, friction loss, the file's springs and
  dampers, its actuators) is named: "the model without its joint limits (6 joints: ...), ...";
* **weak evidence** (E67, :mod:`urdf2links.scenes.coverage`): fewer than half of the coordinates moved;
* **MuJoCo's blow-up** and the stable setting that replaced it
  (:func:`urdf2links.compare.mujoco_side.stable_run.stable_run`), or a blow-up that nothing replaced.

``summary()["verdict"]`` of a comparison is :func:`comparison_verdict`'s dictionary; its ``text`` is
also ``summary()["trajectory"]["verdict"]``, the line reports show.
"""

from __future__ import annotations

from ..mujoco_side.mujoco_stepping import instability_note

__all__ = ["cut_scope", "switched_off", "run_scope", "comparison_verdict", "FULL_SCOPE", "loop_scope", "with_loops"]

#: ``verdict.scope`` of a model that nothing was cut from and nothing switched off in.
FULL_SCOPE = "the whole model"
#: Names listed per switched-off effect in the scope (the JSON's ``switched_off`` lists them all).
SHOWN_NAMES = 4
#: Limits at or beyond this magnitude are "no limit" (as :data:`urdf2links.scenes.excitation.NO_LIMIT`).
_NO_LIMIT = 1e6


def cut_scope(model, load_options: dict | None = None, plan=None) -> dict:
    """What of ``model``'s mechanism both engines leave out: ``equalities`` and ``tendons`` of an MJCF
    file (MuJoCo's run disables them; the tree has none), ``mimic`` couplings of a URDF loaded with
    ``mimic="independent"``; ``text`` is :data:`FULL_SCOPE` when nothing was cut, else
    "open tree of a closed mechanism (N constraints, M tendons dropped)". With ``plan``, what its
    constraints model is not cut (issue 36; issue 45: an MJCF file's equalities and fixed tendons act by default):
    the file's equalities it solves, its fixed tendons, every fixed tendon that carries no force (nothing to drop)
    and the file's inactive equalities (off in MuJoCo too: :func:`switched_off` lists them). A scene that opens
    the loops (``--open-loops``, ``[constraints] from_file = false``) says so: "loops open: ..." (``opened``)."""
    closed = model.info.get("closed") or {}
    eq, tendons = int(closed.get("equalities", 0)), int(closed.get("tendons", 0))
    coupled = (load_options or {}).get("mimic", "independent") == "independent"
    joints = {j["name"]: j for j in model.info.get("joints", [])}     # a <mimic> of a fixed joint couples nothing
    mimic = sum(1 for j in joints.values() if j.get("mimic") and j.get("coordinates")
                and (joints.get(j["mimic"]) or {}).get("coordinates")) if coupled else 0
    scene = getattr(plan, "scene", None)
    eq -= sum(1 for e in model.info.get("equalities", []) if e["supported"] and not e["active"])
    named = {a.name for a in getattr(scene, "actuators", ())}   # the others act on neither engine (notes)
    inert = [t for t in model.info.get("tendons", []) if t["fixed"] and not (
        t["stiffness"] or t["damping"] or set(t["actuators"]) & named or t["limited"] or t["frictionloss"])]
    tendons -= len(inert)
    opened = scene is not None and not getattr(scene, "file_constraints", True)
    mimic_opened = scene is not None and not getattr(scene, "mimic_constraints", True)
    if scene is not None and not opened:
        cons = plan.constraints
        eq -= 0 if cons is None else sum(1 for c in cons.cset.constraints if c.source.startswith("MJCF"))
        tendons -= 0 if cons is None else len({td.name.removesuffix("__limit") for td in cons.tendons})
    if scene is not None and getattr(scene, "mimic_constraints", False) and plan.constraints is not None:
        mimic -= sum(1 for c in plan.constraints.cset.constraints if c.source == "URDF <mimic>")
    opened = (opened and bool(eq or tendons)) or (mimic_opened and bool(mimic))
    laws = [] if scene is None or plan.constraints is None else [  # issue 45: the tendon-limit law (E87)
        f"tendon limit of {td.name.removesuffix('__limit')}: the project's law on both engines"
        for td in plan.constraints.tendons if td.name.endswith("__limit")]
    out = {"equalities": eq, "tendons": tendons, "mimic": mimic, "cut": bool(eq or tendons or mimic),
           "opened": opened, "laws": laws}
    loops = loop_scope(model, plan, load_options)      # issue 45: which loops were closed, on which side
    if loops is not None:
        out["loops"] = loops
    if eq or tendons:
        out["text"] = (("loops open: the " if opened else "") + f"open tree of a closed mechanism ({eq} "
                       f"constraint{'s' * (eq != 1)}, {tendons} tendon{'s' * (tendons != 1)} dropped"
                       + (" on both engines: --open-loops or [constraints] from_file = false" if opened else "") + ")"
                       + (f", {mimic} mimic couplings dropped" if mimic else ""))
    elif mimic:
        out["text"] = (("loops open: the " if opened else "") + f"open tree of a coupled mechanism ({mimic} mimic "
                       f"coupling{'s' * (mimic != 1)} dropped: the mimic joints move as independent coordinates)")
    else:
        out["text"] = FULL_SCOPE
    return out


def _left_open(model, plan, load_options) -> list[str]:
    """The file's loops and couplings that neither engine closes, each with why: an MJCF equality the plan does
    not solve (not read: ``[constraints] from_file`` off; inactive in the file; not modelled), URDF mimic joints
    run as independent coordinates."""
    cons = getattr(plan, "constraints", None)
    solved = set() if cons is None else {c.name for c in cons.cset.constraints}
    scene = getattr(plan, "scene", None)
    from_file = bool(getattr(scene, "file_constraints", False))
    out = []
    for r in model.info.get("equalities", []) or []:
        if r.get("name") in solved:
            continue
        why = ("not modelled: " + r["why"] if not r.get("supported", True) else
               "inactive in the file" if not r.get("active", True) else
               "the file's equalities not read ([constraints] from_file = false)" if not from_file else "not solved")
        out.append(f"{r.get('name')} ({r.get('kind')}: {why})")
    if (load_options or {}).get("mimic", "independent") == "independent" and not getattr(scene, "mimic_constraints", False):
        out += [f"{j['name']} (mimic: an independent coordinate)" for j in model.info.get("joints", []) if j.get("mimic")]
    return out


def loop_scope(model, plan, load_options: dict | None = None) -> dict | None:
    """Which loops and couplings the run closes, on which side, and which it leaves open (issue 45):
    ``closed`` (the plan's constraints, ``name (kind)``), ``tendons`` (its fixed tendons), ``open`` (the file's
    equalities and mimic couplings neither engine closes, each with why) and ``text``; None for a model with no
    loop, coupling or tendon at all."""
    from ..mujoco_side.mujoco_constraints import COMPARE_SOLREF, SOLIMP

    cons = getattr(plan, "constraints", None)
    closed = [] if cons is None else [f"{c.name} ({c.kind})" for c in cons.cset.constraints]
    tendons = [] if cons is None else [td.name for td in cons.tendons]
    left = _left_open(model, plan, load_options)
    if not closed and not tendons and not left:
        return None
    parts = []
    if closed:
        parts.append(f"loops closed on both engines: {', '.join(closed)}; urdf2links: exact constraints with "
                     "multipliers (E72), projected onto Phi = 0, Phi' = 0 after every step (E74); MuJoCo: soft equality "
                     f"constraints (solref {COMPARE_SOLREF[0]:g} s, damping ratio {COMPARE_SOLREF[1]:g}, solimp "
                     f"{SOLIMP[0]:g})")
    if tendons:
        parts.append(f"fixed tendons on both engines: {', '.join(tendons)} (E76)")
    parts.append("left open on both engines: " + (", ".join(left) if left else "none"))
    return {"closed": closed, "tendons": tendons, "open": left, "text": "; ".join(parts)}


def with_loops(verdict: dict, loops: dict) -> dict:
    """``verdict`` (:func:`comparison_verdict`) with the loops' agreement of the report (issue 45,
    :func:`urdf2links.compare.agreement.constraint_agreement.loop_figures`: ``agree``, ``text``) stated in it:
    after the agreement when the loops agree; in its place when they do not (the trajectories' sentence kept in
    brackets, its "agree" said as "within"), so that a disagreeing loop never reads "agree"."""
    out = dict(verdict)
    out["loops"] = {k: loops[k] for k in ("agree", "reasons", "text")}
    head = verdict["agreement"].rstrip(".")
    text = verdict["text"]
    if not verdict.get("plausible", True) or not text.startswith(head):
        out["text"] = text.rstrip(".") + f"; {loops['text']}."
        return out
    rest = text[len(head):]
    if loops["agree"]:
        out["text"] = f"{head}; {loops['text']}{rest}"
    else:
        said = head.replace("the engines agree to", "the trajectories are within").replace(" agree ", " are within ")
        out["text"] = f"{loops['text']} ({said}){rest}"
    return out


def _effect(effect: str, words: str, names: list[str], unit: str) -> dict | None:
    if not names:
        return None
    shown = ", ".join(names[:SHOWN_NAMES]) + (", ..." if len(names) > SHOWN_NAMES else "")
    return {"effect": effect, "count": len(names), "names": list(names),
            "text": f"{words} ({len(names)} {unit}{'s' * (len(names) != 1)}: {shown})"}


def switched_off(model, plan, file_model=None) -> list[dict]:
    """Every effect of the robot's file that both engines leave out of this run (issue 43), each
    ``{effect, count, names, text}``: ``contact`` (an MJCF file's colliding geoms, its floor among them, in a
    scene without ``[[contact]]``), ``limits`` (joints with limits: neither engine enforces them),
    ``frictionloss`` (Coulomb friction: not modelled), ``springs`` (the file's joint stiffness or damping the
    scene does not apply, on joints without a ``[[spring]]`` of the scene), ``actuators`` (an MJCF file's
    actuators the scene does not name). ``file_model``: the MJCF file compiled by MuJoCo (its geoms), when
    there is one."""
    joints = model.info.get("joints", [])
    scene = plan.scene
    out = []
    if file_model is not None and not plan.contact_set:
        import mujoco

        m = file_model
        colliding = [g for g in range(m.ngeom) if m.geom_contype[g] or m.geom_conaffinity[g]]
        name = {g: mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_GEOM, g) or f"geom {g}" for g in colliding}
        planes = [name[g] for g in colliding if int(m.geom_type[g]) == int(mujoco.mjtGeom.mjGEOM_PLANE)]
        floor = f" and the file's floor {', '.join(repr(p) for p in planes)}" if planes else ""
        others = [name[g] for g in colliding if name[g] not in planes]
        out.append(_effect("contact", "contact" + floor, planes + others, "colliding geom"))
    out.append(_effect("limits", "joint limits", [j["name"] for j in joints if j.get("lower") is not None
                                                  and j.get("upper") is not None and j["lower"] < j["upper"]
                                                  and max(abs(j["lower"]), abs(j["upper"])) < _NO_LIMIT], "joint"))
    out.append(_effect("frictionloss", "friction loss (Coulomb friction)", [j["name"] for j in joints
                                                                            if j.get("friction")], "joint"))
    given = {s.coordinate for s in plan.spring_set.springs}     # the scene's own spring replaces the file's
    own = [j for j in joints if not set(j.get("coordinates") or ()) & given]
    springs = [] if getattr(scene, "file_springs", False) else [j["name"] for j in own if j.get("stiffness")]
    if not getattr(scene, "urdf_damping", False):
        springs += [j["name"] for j in own if j.get("damping") and j["name"] not in springs]
    out.append(_effect("springs", "the file's joint springs and dampers", springs, "joint"))
    out.append(_effect("inactive", "the file's inactive equalities (active=\"false\": off in MuJoCo too)",
                       [e["name"] for e in model.info.get("equalities", []) if e["supported"] and not e["active"]],
                       "equality"))
    named = {a.name for a in plan.actuator_set.actuators}
    cons = getattr(plan, "constraints", None)       # issue 45: a fixed tendon's actuators act on both engines
    named |= {a.name for td in (cons.tendons if cons is not None else ()) for a in td.actuators}
    acts = [a.get("name") or f"#{k}" + (f" on {a['joint']}" if a.get("joint") else "")   # an unnamed one by its
            for k, a in enumerate(model.info.get("actuators", []))                          # index and joint
            if not a.get("name") or a["name"] not in named]
    out.append(_effect("actuators", "the file's actuators", acts, "actuator"))
    return [x for x in out if x]


def run_scope(cut: dict, off: list[dict]) -> str:
    """The scope in words: :data:`FULL_SCOPE`, or the cut mechanism (:func:`cut_scope`) and the effects
    :func:`switched_off` names: "the model without its joint limits (6 joints: ...), ... (switched off on
    both engines)"."""
    laws = "".join(f"; {w}" for w in cut.get("laws", ()))
    if not cut["cut"] and not off:
        return FULL_SCOPE + laws
    head = cut["text"] if cut["cut"] else "the model"
    return head + (f" without its {', '.join(x['text'] for x in off)} (switched off on both engines)" if off
                   else "") + laws


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
                       blow_ups: dict, fallback: dict | None, off: list[dict] = (), plausibility=None) -> dict:
    """The verdict (module doc): ``agreement`` (the trajectories' sentence), ``scope`` (:func:`cut_scope`),
    ``off`` (:func:`switched_off`), ``weak_evidence`` and ``coverage``
    (:class:`~urdf2links.scenes.coverage.Coverage`'s line), ``mujoco`` (the fallback or blow-up sentence, or
    None), ``plausible`` and ``text``, all of them in one paragraph. With a ``plausibility``
    (:class:`~urdf2links.compare.agreement.plausibility.Plausibility`) that found something, the paragraph
    opens with "implausible run: <reasons>" in place of the agreement."""
    implausible = plausibility is not None and not plausibility.plausible
    parts = [plausibility.text() if implausible else agreement.rstrip(".")]
    if scope["cut"]:
        parts.append(f"{scope['text']}, not the whole mechanism" if scope.get("opened") else
                     f"as the {scope['text']}, not the whole mechanism")
    if scope.get("loops"):      # issue 45: the loops closed, on which side, and those left open
        parts.append(scope["loops"]["text"])
    if off:
        parts.append(f"without its {', '.join(x['text'] for x in off)} (switched off on both engines)")
    mj = _mujoco_part(mujoco_integrator, mujoco_timestep, blow_ups, fallback)
    if mj:
        parts.append(mj)
    if coverage.weak:
        parts.append(f"WEAK EVIDENCE: {coverage.text().split(':')[0]}")
    where = run_scope(scope, list(off)) + (f"; {scope['loops']['text']}" if scope.get("loops") else "")
    return {"text": "; ".join(parts) + ".", "agreement": agreement, "scope": where, "cut": scope,
            "switched_off": list(off), "plausible": not implausible,
            "weak_evidence": bool(coverage.weak), "coverage": coverage.text(), "moved_fraction": coverage.moved_fraction,
            "mujoco": mj}

"""An MJCF file's equality constraints and fixed tendons, read from MuJoCo's compiled model (issue 36).

``equality_rows(b)`` and ``tendon_rows(b)`` turn the compiled ``mjModel`` of a
:class:`~urdf2links.parsers.mjcf._Builder` into plain dicts for ``model.info["equalities"]`` and
``model.info["tendons"]``; :mod:`urdf2links.scenes.file_constraints` makes them constraints (E68)-(E70) and
tendons (E76) when a scene asks (``[constraints] from_file = true``). MuJoCo's own numbers are kept:

- ``connect`` (body semantic): ``anchor1`` in body 1's frame, ``anchor2`` in body 2's (the compiler puts it
  where ``anchor1`` is at ``qpos0``);
- ``weld``: the point ``relpos`` of body 1 on ``anchor`` of body 2, and the orientation ``R_1 R_rel = R_2``
  (``relquat``); ``torquescale`` scales MuJoCo's rotation rows only (0: the orientation is free);
- ``joint``: ``qpos_1 - qpos0_1 = sum_k c_k (qpos_2 - qpos0_2)^k`` (``polycoef``, ``qpos0``);
- ``tendon`` (of fixed tendons): the same law on the tendons' lengths, ``tendon_length0`` their lengths at
  ``qpos0``;
- a fixed tendon: its joints and coefficients, stiffness, damping, spring length (a range), its limits (the
  project's limit law, E87, on both engines) with their ``solref``, its friction loss (not modelled: noted), and
  the actuators whose transmission it is.

Site-semantic equalities, ``tendon`` equalities of spatial tendons, ``flex`` equalities and spatial tendons
are listed with why they are not read.
"""

from __future__ import annotations

import numpy as np

from .mjcf_state import quat_to_matrix

__all__ = ["equality_rows", "tendon_rows", "inspect_rows", "compiled_equalities"]


def _eq_type(b, i) -> str:
    return b.mj.mjtEq(int(b.m.eq_type[i])).name.removeprefix("mjEQ_").lower()


def equality_rows(b) -> tuple[list[dict], list[str]]:
    """``(rows, notes)``: one dict per equality MuJoCo compiled (``kind``, ``name``, ``active``, ``solref``,
    ``solimp``, and the kind's objects and numbers); ``supported`` False with ``why`` for the others."""
    m = b.m
    rows, notes = [], []
    for i in range(m.neq):
        kind = _eq_type(b, i)
        d = np.asarray(m.eq_data[i], float)
        row = {"name": b.name("mjOBJ_EQUALITY", i, f"equality{i}"), "kind": kind, "index": i,
               "active": bool(m.eq_active0[i]), "solref": [float(x) for x in m.eq_solref[i]],
               "solimp": [float(x) for x in m.eq_solimp[i]], "supported": True, "why": ""}
        o1, o2 = int(m.eq_obj1id[i]), int(m.eq_obj2id[i])
        site = int(m.eq_objtype[i]) == int(b.mj.mjtObj.mjOBJ_SITE)
        if kind in ("connect", "weld") and site:
            row.update(supported=False, why="site semantic (site1/site2) is not read: give body1/body2 and anchor")
        elif kind in ("connect", "weld"):
            row.update(body1=b.name("mjOBJ_BODY", o1, f"body{o1}"),
                       body2="world" if o2 <= 0 else b.name("mjOBJ_BODY", o2, f"body{o2}"))
            if kind == "connect":
                row.update(anchor1=d[0:3].tolist(), anchor2=d[3:6].tolist())
            else:
                row.update(anchor2=d[0:3].tolist(), anchor1=d[3:6].tolist(),
                           rel=quat_to_matrix(d[6:10] / np.linalg.norm(d[6:10])).tolist(), torquescale=float(d[10]))
        elif kind == "joint":
            row.update(joint1=b.name("mjOBJ_JOINT", o1, f"joint{o1}"),
                       joint2=None if o2 < 0 else b.name("mjOBJ_JOINT", o2, f"joint{o2}"), polycoef=d[:5].tolist(),
                       qpos0_1=float(m.qpos0[m.jnt_qposadr[o1]]),
                       qpos0_2=None if o2 < 0 else float(m.qpos0[m.jnt_qposadr[o2]]))
            kinds = [int(m.jnt_type[j]) for j in (o1, o2) if j >= 0]
            if any(k not in (2, 3) for k in kinds):       # mjJNT_SLIDE = 2, mjJNT_HINGE = 3
                row.update(supported=False, why="a joint equality of a ball or free joint (MuJoCo couples qpos "
                                                "entries of its quaternion; not a coordinate here)")
        elif kind == "tendon":
            fixed = [int(m.tendon_num[t]) > 0 and all(int(m.wrap_type[m.tendon_adr[t] + w]) == int(b.mj.mjtWrap.mjWRAP_JOINT)
                                                       for w in range(int(m.tendon_num[t]))) for t in (o1, o2) if t >= 0]
            row.update(tendon1=b.name("mjOBJ_TENDON", o1, f"tendon{o1}"),
                       tendon2=None if o2 < 0 else b.name("mjOBJ_TENDON", o2, f"tendon{o2}"), polycoef=d[:5].tolist(),
                       length0_1=float(m.tendon_length0[o1]), length0_2=None if o2 < 0 else float(m.tendon_length0[o2]))
            if not all(fixed):
                row.update(supported=False, why="a tendon equality on a spatial tendon (fixed tendons only: their "
                                                "lengths are linear in the coordinates)")
        else:
            row.update(supported=False, why=f"a {kind} equality is not modelled (connect, weld, joint and tendon "
                                            "equalities of fixed tendons are)")
        if not row["supported"]:
            notes.append(f"equality {row['name']!r} ({kind}): {row['why']}")
        rows.append(row)
    return rows, notes


def tendon_rows(b) -> tuple[list[dict], list[str]]:
    """``(rows, notes)``: one dict per tendon (``name``, ``fixed``, ``joints`` [(joint, coef)], ``stiffness``,
    ``damping``, ``lengthspring`` (2,), ``limited``, ``range``, ``frictionloss``, ``actuators`` (names))."""
    m, mj = b.m, b.mj
    rows, notes = [], []
    acts = {}
    for k in range(m.nu):
        if int(m.actuator_trntype[k]) == int(mj.mjtTrn.mjTRN_TENDON):
            acts.setdefault(int(m.actuator_trnid[k, 0]), []).append(b.name("mjOBJ_ACTUATOR", k, f"actuator{k}"))
    for t in range(m.ntendon):
        adr, num = int(m.tendon_adr[t]), int(m.tendon_num[t])
        types = [int(m.wrap_type[adr + w]) for w in range(num)]
        fixed = all(ty == int(mj.mjtWrap.mjWRAP_JOINT) for ty in types)
        name = b.name("mjOBJ_TENDON", t, f"tendon{t}")
        spring = np.ravel(m.tendon_lengthspring[t]) if hasattr(m, "tendon_lengthspring") else np.zeros(2)
        row = {"name": name, "fixed": fixed, "stiffness": float(np.ravel(m.tendon_stiffness)[t]),
               "damping": float(np.ravel(m.tendon_damping)[t]), "lengthspring": [float(spring[0]), float(spring[-1])],
               "limited": bool(m.tendon_limited[t]), "range": [float(x) for x in m.tendon_range[t]],
               "frictionloss": float(m.tendon_frictionloss[t]), "actuators": acts.get(t, []),
               "solref_lim": [float(x) for x in m.tendon_solref_lim[t]],
               "joints": [(b.name("mjOBJ_JOINT", int(m.wrap_objid[adr + w]), f"joint{int(m.wrap_objid[adr + w])}"),
                           float(m.wrap_prm[adr + w])) for w in range(num)] if fixed else []}
        if not fixed:
            notes.append(f"tendon {name!r} is spatial (it wraps sites or geoms): not modelled; MuJoCo's run zeroes its "
                         "stiffness and damping")
        elif row["frictionloss"]:
            notes.append(f"tendon {name!r}: its friction loss is not modelled (MuJoCo's run disables it)")
        rows.append(row)
    return rows, notes


def inspect_rows(info: dict) -> tuple[list[tuple], list[tuple]]:
    """``urdf2links inspect``'s tables of a model's equalities and tendons (header rows first; empty without)."""
    eq = [("equality", "kind", "between", "numbers", "active", "read")]
    for r in info.get("equalities", []):
        if r["kind"] in ("connect", "weld") and "body1" in r:
            between = f"{r['body1']} / {r['body2']}"
            nums = f"anchor1 {np.round(r['anchor1'], 6).tolist()}, anchor2 {np.round(r['anchor2'], 6).tolist()}"
        elif r["kind"] in ("joint", "tendon") and "polycoef" in r:
            k = r["kind"]
            between = f"{r[k + '1']} / {r[k + '2'] or '-'}"
            nums = f"polycoef {np.round(r['polycoef'], 6).tolist()}"
        else:
            between, nums = "-", "-"
        eq.append((r["name"], r["kind"], between, nums, "yes" if r["active"] else "no",
                   "yes" if r["supported"] else f"no: {r['why']}"))
    td = [("tendon", "kind", "length", "stiffness", "damping", "spring length", "actuators", "not modelled")]
    for r in info.get("tendons", []):
        length = " + ".join(f"{c:g} {j}" for j, c in r["joints"]) if r["fixed"] else "(wraps sites/geoms)"
        nm = [w for w, on in (("friction loss", r["frictionloss"]),
                              ("spatial", not r["fixed"])) if on]
        td.append((r["name"], "fixed" if r["fixed"] else "spatial", length, f"{r['stiffness']:g}", f"{r['damping']:g}",
                   " .. ".join(f"{x:g}" for x in dict.fromkeys(r["lengthspring"])), ", ".join(r["actuators"]) or "-",
                   ", ".join(nm) or "-"))
    return (eq if len(eq) > 1 else []), (td if len(td) > 1 else [])


class _Compiled:
    """What :func:`equality_rows` needs of a builder: the compiled model, MuJoCo, names."""

    def __init__(self, m):
        import mujoco

        self.m, self.mj = m, mujoco

    def name(self, obj: str, i: int, fallback: str) -> str:
        return self.mj.mj_id2name(self.m, getattr(self.mj.mjtObj, obj), i) or fallback


def compiled_equalities(m) -> list[dict]:
    """:func:`equality_rows` of a model ``m`` (``mujoco.MjModel``) compiled by MuJoCo alone, without a tree
    (:func:`urdf2links.parsers.mjcf.file_equalities`: a pair's files)."""
    return equality_rows(_Compiled(m))[0]

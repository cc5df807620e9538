"""What a robot description holds that the dynamics does not use: the import notes' inventory.

Nothing is dropped silently: :func:`inventory_notes` walks the ``<robot>`` element and names, in
grouped notes, every element the importer does not read -- transmissions, gazebo tags,
materials, ``<safety_controller>``, ``<calibration>``, unknown elements, the second of an
element urdfdom reads once (``<origin>``, ``<inertial>``, ``<limit>``, ...) -- and
:func:`joint_value_notes` what it reads but does not apply by itself (``<dynamics damping>``
only when a scene asks, ``<dynamics friction>`` never, ``<limit>`` not enforced).

Each note names the element, the links or joints that carry it, and what was done.
"""

from __future__ import annotations

from lxml import etree

__all__ = ["inventory_notes", "joint_value_notes"]

#: Children each element may have: read by the importer, or known and not used (value: why).
_USED = {
    "robot": ("link", "joint"),
    "link": ("inertial", "visual", "collision"),
    "inertial": ("origin", "mass", "inertia"),
    "visual": ("origin", "geometry", "material"),
    "collision": ("origin", "geometry"),
    "joint": ("origin", "parent", "child", "axis", "limit", "mimic", "dynamics"),
}
_NOT_USED = {
    "robot": {"material": "visual only", "transmission": "actuators are not modelled",
              "gazebo": "simulator-specific", "mujoco": "MuJoCo's compiler settings"},
    "joint": {"safety_controller": "controller settings", "calibration": "sensor calibration"},
    "collision": {"verbose": "collision checking only"},
}
#: Elements read once per parent (urdfdom reads the first; so does urdf2links).
_ONCE = {"origin", "inertial", "mass", "inertia", "geometry", "material", "parent", "child", "axis", "limit",
         "mimic", "dynamics", "safety_controller", "calibration"}


def _name(el) -> str:
    return etree.QName(el).localname


def _owner(el) -> str:
    """``link 'x'`` / ``joint 'j'`` of the element (its nearest named link or joint), else ``robot``."""
    while el is not None:
        if isinstance(el.tag, str) and _name(el) in ("link", "joint") and el.get("name"):
            return f"{_name(el)} '{el.get('name')}'"
        el = el.getparent()
    return "robot"


def _walk(el, path: str, groups: dict) -> None:
    """Record unused, unknown and repeated children of ``el`` (path: ``<link> <visual>`` ...)."""
    tag = _name(el)
    used, known = _USED.get(tag), _NOT_USED.get(tag, {})
    seen: dict[str, int] = {}
    for child in el:
        if not isinstance(child.tag, str):
            continue
        c = _name(child)
        seen[c] = seen.get(c, 0) + 1
        where = f"{path} <{c}>".strip()
        if seen[c] == 2 and c in _ONCE and tag != "robot":
            groups.setdefault((f"a second {where}", "ignored: only the first is read, as urdfdom does"),
                              []).append(_owner(child))
        if used is None:
            continue
        if c in used:
            if (seen[c] == 1 or c not in _ONCE) and tag in ("robot", "link", "joint", "inertial", "visual", "collision"):
                _walk(child, f"<{c}>" if tag == "robot" else where, groups)
        elif c in known:
            groups.setdefault((where, f"not used ({known[c]})"), []).append(
                child.get("name") or _owner(child) if tag == "robot" else _owner(child))
        else:
            groups.setdefault((where, "unknown element, skipped (urdfdom skips it too)"), []).append(_owner(child))


def _format(groups: dict) -> list[str]:
    out = []
    for (where, action), owners in groups.items():
        owners = [o for o in owners if o]
        if where.startswith("<") and where.count("<") == 1:   # robot-level elements: a count and names
            named = [o for o in owners if o != "robot"]
            out.append(f"{where}: {len(owners)} element(s)" + (f" ({', '.join(dict.fromkeys(named))})" if named
                                                                  else "") + f": {action}")
        else:
            out.append(f"{where} in {_owners(list(dict.fromkeys(owners)))}: {action}")
    return out


def _owners(owners: list[str]) -> str:
    """``joint 'a'`` / ``joints 'a', 'b'`` (mixed kinds listed one by one)."""
    kinds = {o.split(" ", 1)[0] for o in owners}
    if len(owners) > 1 and len(kinds) == 1 and " " in owners[0]:
        return f"{kinds.pop()}s " + ", ".join(o.split(" ", 1)[1] for o in owners)
    return ", ".join(owners)


def inventory_notes(root) -> list[str]:
    """Grouped notes on every element of ``root`` (the ``<robot>``) that the importer does not read."""
    groups: dict[tuple[str, str], list[str]] = {}
    _walk(root, "", groups)
    return _format(groups)


def _listed(joints) -> str:
    return ", ".join(f"'{j.name}'" for j in joints)


def joint_value_notes(joints) -> list[str]:
    """Notes on what ``<dynamics>`` and ``<limit>`` of ``joints`` (JointDescription) hold and how it is used."""
    notes = []
    damped = [j for j in joints if j.damping]
    rubbing = [j for j in joints if j.friction]
    bounded = [j for j in joints if j.limit_lower is not None or j.limit_upper is not None]
    rated = [j for j in joints if j.limit_effort is not None or j.limit_velocity is not None]
    if damped:
        notes.append(f"<dynamics damping> on joints {_listed(damped)}: read; applied as dampers only by a scene "
                     "that asks for it ([dampers] from_urdf = true; default scenes do)")
    if rubbing:
        notes.append(f"<dynamics friction> on joints {_listed(rubbing)}: Coulomb friction is not modelled "
                     "(read, shown by inspect, never applied)")
    if bounded:
        notes.append(f"<limit lower upper> on joints {_listed(bounded)}: not enforced; simulate and compare note "
                     "when a trajectory leaves them")
    if rated:
        notes.append(f"<limit effort velocity> on joints {_listed(rated)}: not used (actuators are not modelled)")
    return notes

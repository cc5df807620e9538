"""``urdf2links inspect`` (a robot's tree of links, joints, inertia audit and import notes; a scene's plan) and
``urdf2links list`` (the shipped robots and scenes): the commands that look at a robot or a scene without running it."""

from __future__ import annotations

import warnings

from .options import INPUT, add_default_scene_options, add_load_options

__all__ = ["format_tree", "add_inspect", "run_inspect", "run_list"]


def add_inspect(p) -> None:
    """The ``inspect`` command's options."""
    p.add_argument("file", help=INPUT + "; a scene prints its plan")
    p.add_argument("--scene", action="store_true", help="print the robot's default scene (TOML) and its plan")
    p.add_argument("--t-end", type=float, help="default scene's run length in s (default 1)")
    add_load_options(p)
    add_default_scene_options(p, write_scene=False)


def format_tree(model) -> str:
    """The tree as a table: link, parent, the six parameters (coordinates marked ``[name]``),
    mass, COM, eigenvalues of H; then the audit findings and the importer's notes."""
    import numpy as np

    from ..dynamics.transforms import PARAMETERS

    tree = model.tree
    rows = [("link", "parent", *PARAMETERS, "mass", "COM", "eig(H)")]
    for p, name in enumerate(tree.link_names):
        parent = tree.link_names[tree.parent[p]] if tree.parent[p] >= 0 else "{A}"
        cells = []
        for k in range(6):
            i = tree.coord[p, k]
            v = tree.params[p, k]
            if i >= 0:
                off = f"{v:+.4g}+" if v != 0 else ""
                cells.append(f"{off}[{tree.coordinate_names[i]}]")
            else:
                cells.append("0" if v == 0 else f"{v:.4g}")
        m = tree.H[p, 3, 3]
        com = "-" if m <= 0 else "(" + ", ".join(f"{c:.3g}" for c in tree.com[p]) + ")"
        eig = "massless" if not np.any(tree.H[p]) else ", ".join(f"{e:.3g}" for e in np.linalg.eigvalsh(tree.H[p]))
        rows.append((name, parent, *cells, f"{m:.4g}", com, eig))
    lines = _table(rows)
    out = [f"robot {model.name!r} from {model.source}: {tree.n_links} links, {model.n} coordinates", ""] + lines
    out += _joint_lines(model.info.get("joints", []))
    out += _constraint_lines(model.info)
    out += ["", f"inertia audit: {len(model.audit)} finding(s)"]
    out += [f"  - {r}" for r in model.audit]
    notes = model.info.get("notes", [])
    if notes:
        out += ["", "import notes:"] + [f"  - {n}" for n in notes]
    return "\n".join(out)


def _constraint_lines(info) -> list[str]:
    """An MJCF model's equalities and tendons (issue 36): read, and acting in every scene unless it opens the
    loops (issue 45: ``--open-loops``, ``[constraints] from_file = false``; docs/constraints.md)."""
    from ..parsers.mjcf_constraints import inspect_rows

    eq, td = inspect_rows(info)
    out = []
    if eq:
        out += ["", "equalities (read; constraints of every scene unless --open-loops or from_file = false, E68-E70):"] + _table(eq)
    if td:
        out += ["", "tendons (fixed ones act in every scene unless --open-loops or from_file = false, E76; limits: E87):"] + _table(td)
    return out


def _table(rows) -> list[str]:
    """Rows of cells as aligned text lines, a rule under the first (the header)."""
    widths = [max(len(r[c]) for r in rows) for c in range(len(rows[0]))]
    lines = ["  ".join(cell.ljust(w) for cell, w in zip(r, widths)).rstrip() for r in rows]
    lines.insert(1, "  ".join("-" * w for w in widths))
    return lines


def _num(v) -> str:
    return "-" if v is None else f"{v:.4g}"


def _mjcf_joint_lines(joints) -> list[str]:
    """An MJCF model's joints: type, coordinates, limits, armature (in A), damping, stiffness at springref."""
    rows = [("joint", "type", "coordinates", "lower", "upper", "armature", "damping", "stiffness", "springref",
             "frictionloss")]
    for j in joints:
        rows.append((j["name"], j["type"], ", ".join(j["coordinates"]), _num(j["lower"]), _num(j["upper"]),
                     _num(j["armature"]), _num(j["damping"]), _num(j["stiffness"]), _num(j["springref"]),
                     _num(j["friction"])))
    lines = _table(rows)
    return ["", "joints (MuJoCo's compiled values; qpos of hinges and slides is the coordinate; armature is part of A; "
            "damping, stiffness and gravcomp act in scenes that ask ([dampers], [springs], [gravcomp] from_file, as "
            "the default scene does); limits not enforced; friction not modelled):"] + lines


def _joint_lines(joints) -> list[str]:
    """The URDF joints with what ``<limit>`` and ``<dynamics>`` say (limits are not enforced; damping acts
    only in scenes with ``[dampers] from_urdf = true``; friction is not modelled); an MJCF model's
    joints with armature, damping and stiffness (:func:`_mjcf_joint_lines`)."""
    if joints and "armature" in joints[0]:
        return _mjcf_joint_lines(joints)
    moving = [j for j in joints if j["type"] != "fixed"]
    if not moving:
        return []
    rows = [("joint", "type", "coordinates", "lower", "upper", "effort", "velocity", "damping", "friction")]
    for j in moving:
        rows.append((j["name"], j["type"], ", ".join(j["coordinates"]) or "(coupled)", _num(j["lower"]),
                     _num(j["upper"]), _num(j["effort"]), _num(j["velocity"]), _num(j["damping"]),
                     _num(j["friction"])))
    lines = _table(rows)
    return ["", "joints (limits not enforced, noted when a run leaves them; damping acts in scenes with [dampers] "
            "from_urdf = true; friction not modelled):"] + lines


def run_inspect(args) -> int:
    """``urdf2links inspect``: a robot's tree of links as a table (:func:`format_tree`), or a scene's plan (a robot's
    default scene with ``--scene``, as TOML that parses)."""
    from ..scenes.plan import compile_plan
    from ..scenes.scene_toml import ground_of, hold_of, load_options_of, scene_or_robot, scene_with_plan

    if args.scene or str(args.file).endswith(".toml"):
        scene = scene_or_robot(args.file, q0=args.q0, seed=args.seed, t_end=args.t_end, load=load_options_of(args),
                               hold=hold_of(args), open_loops=bool(getattr(args, "open_loops", False)))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            model = scene.model()
        scene = ground_of(args, scene, model)     # issues 37, 43: --ground, the file's floor
        print(scene_with_plan(scene, compile_plan(scene, model).describe()))     # a default scene: TOML that parses
        return 0
    from ..parsers.robot_file import load_robot

    opts = load_options_of(args)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the findings are printed in the table below
        model = load_robot(args.file, **opts)
    print(format_tree(model))
    return 0


def run_list(args) -> int:
    """``urdf2links list``: the shipped robots and scenes, one line each, runnable by name from anywhere."""
    from ..locations import shipped, shipped_robots_dir

    items = shipped()
    width = max(len(s.name) for s in items)
    kind_width = max(len(s.kind) for s in items)
    print(f"shipped robots and scenes ({shipped_robots_dir()}); run them by name from any folder, e.g. "
          "`urdf2links simulate ship_crane`, `urdf2links inspect ur5_like`:")
    for s in items:
        print(f"  {s.name:{width}s}  {s.kind:{kind_width}s}  {s.summary}")
    return 0

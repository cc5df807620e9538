"""Command line: ``urdf2links inspect FILE.urdf`` (later issues add simulate, compare, report)."""

from __future__ import annotations

import argparse
import sys
import warnings

import numpy as np

from .errors import URDFError
from .transforms import PARAMETERS

__all__ = ["main", "format_tree"]


def format_tree(model) -> str:
    """The tree as a table: link, parent, the six parameters (coordinates marked ``[name]``),
    mass, COM, eigenvalues of H; then the audit findings and the importer's notes."""
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
    widths = [max(len(r[c]) for r in rows) for c in range(len(rows[0]))]
    lines = ["  ".join(cell.ljust(w) for cell, w in zip(r, widths)).rstrip() for r in rows]
    lines.insert(1, "  ".join("-" * w for w in widths))
    out = [f"robot {model.name!r} from {model.source}: {tree.n_links} links, {model.n} coordinates", ""] + lines
    out += ["", f"inertia audit: {len(model.audit)} finding(s)"]
    out += [f"  - {r}" for r in model.audit]
    notes = model.info.get("notes", [])
    if notes:
        out += ["", "import notes:"] + [f"  - {n}" for n in notes]
    return "\n".join(out)


def _inspect(args) -> int:
    from .importer import load_urdf

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the findings are printed in the table below
        model = load_urdf(args.file, floating_base=args.floating_base, inertia=args.inertia,
                          mimic=args.mimic, package_dirs=args.package_dir)
    print(format_tree(model))
    return 0


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="urdf2links", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("inspect", help="print a URDF's tree of links and its inertia audit")
    p.add_argument("file", help="a .urdf file")
    p.add_argument("--floating-base", action="store_true", help="six coordinates for the root link")
    p.add_argument("--inertia", choices=("audit", "strict", "repair"), default="audit")
    p.add_argument("--mimic", choices=("independent", "coupled"), default="independent")
    p.add_argument("--package-dir", action="append", default=[], help="folder searched for package:// meshes")
    p.set_defaults(func=_inspect)
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except URDFError as err:
        print(f"urdf2links {args.command}: error: {err}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())

"""The table of real MJCF models with equalities or fixed tendons in docs/constraints.md, from the test's figures.

``tests/test_constraints_models.py`` compares dm_control's and gymnasium's models that have ``<equality>`` or
``<tendon>`` with them enabled on both engines and records what it measured (``record_figure``)::

    python -m pytest tests/test_constraints_models.py -n 0 --figures reports/constraints_models
    python -m urdf2links.compare.reports.models_table

The second command writes that run's ``reports/constraints_models/constraints_models.json`` as one row per
model (file, equalities, tendons, what is modelled, the measured agreement) between the markers of
``docs/constraints.md``. Nothing is typed by hand; a case whose test failed is marked so.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

__all__ = ["render", "write_doc", "BEGIN", "END"]

BEGIN = "<!-- BEGIN constraint_models (python -m urdf2links.compare.reports.models_table) -->"
END = "<!-- END constraint_models -->"


def render(data: dict) -> str:
    """The markdown table (and its provenance line) of the figures ``data`` (the JSON the test wrote)."""
    lines = ["| file | equalities | tendons | max \\|lambda\\| | max \\|q_MuJoCo - q\\| over 0.1 s | "
             "verdict scope |", "|---|---|---|---|---|---|"]
    for row in data["rows"]:
        f = {x["name"]: x["text"] for x in row["figures"]}
        failed = " **FAILED**" if row["failed"] else ""
        lines.append(f"| {row['case']}{failed} | {f.get('equalities', '-')} | {f.get('tendons', '-')} | "
                     f"{f.get('max |lambda|', '-')} | {f.get('max |dq|', '-')} rad | {f.get('verdict scope', '-')} |")
    lines += ["", f"Generated from `{data['command']}` (machine: {data['machine']}, python {data['python']}, "
              f"numpy {data['numpy']})."]
    return "\n".join(lines)


def write_doc(data: dict, doc: Path) -> None:
    """``doc`` with the table between :data:`BEGIN` and :data:`END` (both must be there)."""
    text = doc.read_text()
    if BEGIN not in text or END not in text:
        raise ValueError(f"{doc}: the markers {BEGIN!r} and {END!r} are not both there; add them where the table goes")
    head, rest = text.split(BEGIN, 1)
    _, tail = rest.split(END, 1)
    doc.write_text(head + BEGIN + "\n" + render(data) + "\n" + END + tail)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m urdf2links.compare.reports.models_table", description=__doc__.split("\n")[0])
    p.add_argument("--figures", type=Path, default=Path("reports/constraints_models/constraints_models.json"),
                   help="the JSON written by the test's --figures run (default: %(default)s)")
    p.add_argument("--doc", type=Path, default=Path("docs/constraints.md"), help="the page to write (default: %(default)s)")
    a = p.parse_args(argv)
    if not a.figures.is_file():
        p.error(f"--figures {a.figures}: no such file; run python -m pytest tests/test_constraints_models.py -n 0 "
                "--figures reports/constraints_models first")
    write_doc(json.loads(a.figures.read_text()), a.doc)
    print(f"wrote the table of {a.figures} into {a.doc}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

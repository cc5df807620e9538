"""Constraint differences between two descriptions of one robot (issue 36): kind ``constraint``.

A URDF cannot close a loop; an MJCF file closes one with ``<equality><connect>`` or ``<weld>``. A loop closed
on one side only (or closed between other bodies, or at another point) is a difference of kind
``constraint``: the two descriptions are not the same mechanism, whatever their parts say. Each ``connect``
or ``weld`` (body semantic, read by :mod:`urdf2links.parsers.mjcf_constraints`) is matched with the other
side's of the same kind between the same bodies (by name); unmatched ones, and matched ones whose anchors
differ by more than rounding, are reported (``difference``: the rows the loop removes, or the anchors'
distance in m). Joint equalities against URDF ``<mimic>`` are couplings, not compared here.
"""

from __future__ import annotations

import numpy as np

from urdf2links.parsers.mjcf import is_mjcf_path
from urdf2links.parsers.mjcf import file_equalities

from .kinds import Difference

__all__ = ["constraint_differences", "ANCHOR_ROUNDING"]

ANCHOR_ROUNDING = 1e-5      # m: MuJoCo's XML writer prints 6 significant digits


def _loops(path) -> list[dict]:
    if not is_mjcf_path(path):
        return []
    return [r for r in file_equalities(path) if r["kind"] in ("connect", "weld") and r["supported"] and r["active"]]


def _key(r):
    return r["kind"], frozenset((r["body1"], r["body2"]))


def constraint_differences(first, second) -> list[Difference]:
    """The ``constraint`` differences between the robot files ``first`` and ``second`` (module doc)."""
    a, b = _loops(first), _loops(second)
    out = []
    byb = {_key(r): r for r in b}
    for r in a:
        o = byb.pop(_key(r), None)
        rows = 3 if r["kind"] == "connect" else 6
        where = f"{r['kind']} {r['name']!r} between {r['body1']} and {r['body2']}"
        if o is None:
            out.append(Difference("constraint", r["name"], None, where, None, float(rows), "rows",
                                  f"{where} closes a loop the second description does not have",
                                  (r["body1"], r["body2"])))
            continue
        same = o["body1"] == r["body1"]
        d = max(np.abs(np.subtract(r["anchor1"], o["anchor1" if same else "anchor2"])).max(),
                np.abs(np.subtract(r["anchor2"], o["anchor2" if same else "anchor1"])).max())
        if d > ANCHOR_ROUNDING:
            out.append(Difference("constraint", r["name"], o["name"], [r["anchor1"], r["anchor2"]],
                                  [o["anchor1"], o["anchor2"]], float(d), "m",
                                  f"{where}: the anchors differ by {d:.3g} m", (r["body1"], r["body2"])))
    for o in byb.values():
        where = f"{o['kind']} {o['name']!r} between {o['body1']} and {o['body2']}"
        out.append(Difference("constraint", None, o["name"], None, where, float(3 if o["kind"] == "connect" else 6),
                              "rows", f"{where} closes a loop the first description does not have",
                              (o["body1"], o["body2"])))
    return out

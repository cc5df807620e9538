"""Joint limits along a trajectory: not enforced, but never passed over in silence.

The importer reads ``<limit lower upper>`` (``model.info["joints"]``); neither engine of a comparison
enforces them (route 1 writes no limits, route 2 disables MuJoCo's). :func:`limit_excursions` finds,
for every coordinate that is a limited joint's position (revolute and prismatic joints with
``lower < upper``), the first sample outside ``[lower, upper]`` by more than
:data:`LIMIT_TOLERANCE` of the range, the largest excess and when it happens. ``urdf2links simulate`` prints them; ``urdf2links compare`` puts them in the report's notes.

Public API: :func:`limit_excursions`, :class:`LimitExcursion`.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

__all__ = ["LimitExcursion", "limit_excursions", "LIMIT_TOLERANCE"]

#: A coordinate counts as outside its limits when it passes one by more than this share of the range
#: ``upper - lower`` (1e-9 rad on a 1 rad range): a start on a limit and the integrator's rounding
#: (r2d2's gripper once "left" its limit by 1.2e-35 rad) are not excursions.
LIMIT_TOLERANCE = 1e-9


@dataclass(frozen=True)
class LimitExcursion:
    """Coordinate ``coordinate`` (of joint ``joint``) left ``[lower, upper]`` first at ``t_first`` (s),
    by ``worst`` at most (rad or m, ``units``) at ``t_worst``; ``side`` is where the worst excess is
    (``"lower"`` or ``"upper"``); ``fraction``: the share of samples outside."""

    joint: str
    coordinate: str
    lower: float
    upper: float
    t_first: float
    t_worst: float
    worst: float
    side: str
    fraction: float
    units: str

    tolerance: float = 0.0

    def text(self) -> str:
        bound = self.lower if self.side == "lower" else self.upper
        return (f"joint {self.joint!r} left its limits [{self.lower:.4g}, {self.upper:.4g}] {self.units} at "
                f"t = {self.t_first:.4g} s; worst {self.worst:.3g} {self.units} past the {self.side} limit "
                f"{bound:.4g} at t = {self.t_worst:.4g} s ({100 * self.fraction:.0f} % of the samples outside by more "
                f"than {self.tolerance:.2g} {self.units}, {LIMIT_TOLERANCE:g} of the range: less is rounding; "
                "limits are not enforced)")

    def as_dict(self) -> dict:
        return asdict(self)


def limit_excursions(model, t, q) -> list[LimitExcursion]:
    """The excursions of trajectory ``q`` (m, n) at times ``t`` (m,) of ``model`` (module doc)."""
    t, q = np.asarray(t, float), np.asarray(q, float)
    names = list(model.coordinate_names)
    out = []
    for j in model.info.get("joints", []):
        lo, hi = j.get("lower"), j.get("upper")
        if j["type"] not in ("revolute", "prismatic") or lo is None or hi is None or not lo < hi:
            continue
        if len(j["coordinates"]) != 1 or j["coordinates"][0] not in names:
            continue  # a coupled mimic follower: not a coordinate of the model
        x = q[:, names.index(j["coordinates"][0])]
        below, above = lo - x, x - hi
        excess = np.maximum(below, above)
        tol = LIMIT_TOLERANCE * (hi - lo)
        outside = excess > tol
        if not outside.any():
            continue
        k = int(np.argmax(excess))
        out.append(LimitExcursion(joint=j["name"], coordinate=j["coordinates"][0], lower=float(lo), upper=float(hi),
                                  t_first=float(t[np.argmax(outside)]), t_worst=float(t[k]), worst=float(excess[k]),
                                  side="lower" if below[k] > above[k] else "upper",
                                  fraction=float(outside.mean()), units="m" if j["type"] == "prismatic" else "rad",
                                  tolerance=float(tol)))
    return out

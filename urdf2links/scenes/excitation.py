"""Initial states that exercise every coordinate: the default scenes' ``q0 = "excite"`` (E65).

A robot at rest under gravity tests little: a floating robot falls as one rigid body and no joint
moves, an arm hangs near a stable pose. :func:`excited_state` draws, for every coordinate ``k``, a
starting value within its range ``[lo_k, hi_k]`` (:func:`coordinate_ranges`: the joint's limits, else
a window around the file's start) and a rate that carries it a good part of that range within the run
(E65)::

    q0_k  ~ U(lo_k, hi_k)                    (around the home keyframe: U of the quarter range there)
    d_k   ~ U(TRAVEL) (hi_k - lo_k)          (the distance to travel: a quarter to a half of the range)
    q'0_k = s_k d_k / t_end                  (s_k = +1 toward the farther limit, else -1)

so that, were the coordinate free of forces, it would stay within its limits and move ``d_k`` in the
run. A damped coordinate (damping ``c_k``) also gets the constant torque ``tau_k = c_k q'0_k``
(:func:`damper_torques`), the damper's force at that rate: without it a strongly damped joint stops
within microseconds and moves nothing. A floating root (six coordinates) gets the same rule on its window, i.e. a random base twist;
its position starts where the file puts it. Every draw comes from one seeded generator, so the seed
recorded in the scene's description reproduces the state. :func:`coordinate_ranges` also gives the
range the terms' states are drawn from (``urdf2links.compare.agreement``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["coordinate_ranges", "excited_state", "damper_torques", "ExcitedState", "CoordinateRanges", "TRAVEL",
           "NO_LIMIT", "FREE_WINDOW", "HOME_KEY", "DAMPER_TORQUE_TEXT"]

#: How a default scene's description names the torques of :func:`damper_torques`.
DAMPER_TORQUE_TEXT = ("a constant torque c q'0 on each damped joint, the damper's own at the initial rate, so that "
                      "a joint whose damping would stop it at once keeps moving (E65)")

#: Limits at or beyond this magnitude (rad or m) are "no limit" (URDF files write 1e16 for none).
NO_LIMIT = 1e6
#: Half-width (rad or m) of the window around the start of a coordinate without limits.
FREE_WINDOW = 1.0
#: The fraction of its range a coordinate travels in the run (uniform between these).
TRAVEL = (0.25, 0.5)
#: The name of the keyframe an MJCF file's robot starts around (``<key name="home">``).
HOME_KEY = "home"


@dataclass(frozen=True)
class CoordinateRanges:
    """Per coordinate (n,): ``lower``, ``upper`` (rad or m), ``limited`` (the joint's own limits,
    else the window around ``start``), ``start`` (MuJoCo's qpos0 or the home keyframe, else 0) and
    ``root`` (a floating root's x, y, z: its start is kept)."""

    names: tuple[str, ...]
    lower: np.ndarray
    upper: np.ndarray
    limited: np.ndarray
    start: np.ndarray
    root: np.ndarray
    home: bool = False

    @property
    def width(self) -> np.ndarray:
        return self.upper - self.lower


@dataclass(frozen=True)
class ExcitedState:
    """``q0`` and ``qd0`` (dicts by coordinate name, as a Scene holds them) and how they were drawn
    (``text``: a phrase for the scene's description)."""

    q0: dict
    qd0: dict
    text: str


def coordinate_ranges(model) -> CoordinateRanges:
    """The range of every coordinate of ``model``: its joint's limits when both are finite, below
    :data:`NO_LIMIT` and ``lower < upper``; else ``start +- FREE_WINDOW`` around MuJoCo's qpos0 or the
    file's ``home`` keyframe (``model.info['home']``), or around 0 for a URDF."""
    names = tuple(model.coordinate_names)
    n = len(names)
    limits = {j["coordinates"][0]: (j["lower"], j["upper"]) for j in model.info.get("joints", [])
              if len(j["coordinates"]) == 1 and j.get("lower") is not None and j.get("upper") is not None
              and j["lower"] < j["upper"] and max(abs(j["lower"]), abs(j["upper"])) < NO_LIMIT}
    home = model.info.get("home")
    start = model.info.get("q0") if home is None else home
    start = np.zeros(n) if start is None else np.asarray(start, float)
    root = np.array([(c.get("joint") is None or c.get("type") == "free") and c["slot"] in "xyz"
                     for c in model.info.get("coordinates", [{"slot": ""}] * n)] or [False] * n, bool)
    lo, hi, lim = np.empty(n), np.empty(n), np.zeros(n, bool)
    for i, name in enumerate(names):
        if name in limits:
            (lo[i], hi[i]), lim[i] = limits[name], True
        else:
            lo[i], hi[i] = start[i] - FREE_WINDOW, start[i] + FREE_WINDOW
    return CoordinateRanges(names=names, lower=lo, upper=hi, limited=lim, start=start, root=root,
                            home=home is not None)


def excited_state(model, *, seed: int, t_end: float) -> ExcitedState:
    """A seeded initial state that moves every coordinate a good part of its range within ``t_end``
    seconds (E65, module doc); the same ``seed`` gives the same state."""
    if not t_end > 0:
        raise ValueError(f"excited_state: t_end must be positive, got {t_end!r}")
    r = coordinate_ranges(model)
    rng = np.random.default_rng(seed)
    width = r.width
    if r.home:      # around the home keyframe (held within the limits): a quarter of the range on each side
        home = np.clip(r.start, r.lower, r.upper)
        lo, hi = np.maximum(r.lower, home - width / 4), np.minimum(r.upper, home + width / 4)
    else:
        lo, hi = r.lower, r.upper
    q = rng.uniform(lo, hi)
    q = np.where(r.root, r.start, q)
    travel = rng.uniform(*TRAVEL, size=len(q)) * width
    up, down = r.upper - q, q - r.lower
    sign = np.where(up > down, 1.0, np.where(up < down, -1.0, rng.choice((-1.0, 1.0), size=len(q))))
    qd = sign * travel / float(t_end)
    where = "around the file's home keyframe" if r.home else "within the joint limits"
    text = (f"q0 random {where} and q' random, each coordinate set to travel {TRAVEL[0]:g}..{TRAVEL[1]:g} of its "
            f"range in {t_end:g} s (seed {seed})")
    return ExcitedState(q0=dict(zip(r.names, q.tolist())), qd0=dict(zip(r.names, qd.tolist())), text=text)


def damper_torques(springs, qd0: dict) -> tuple:
    """``[[torque]]`` entries ``(coordinate, Constant(c q'0))`` for every damper of ``springs`` (c > 0) on a
    coordinate with an initial rate in ``qd0`` (E65): the force the damper takes at that rate, supplied,
    so that a joint whose damping would stop it within microseconds (the Allegro hand's fingers: 3..10
    N m s/rad on links of grams) drifts at its initial rate instead; on a lightly damped joint it is a
    small constant torque."""
    from .functions import Constant

    return tuple((s.coordinate, Constant(float(s.damping * qd0[s.coordinate])))
                 for s in springs if s.damping > 0 and qd0.get(s.coordinate))

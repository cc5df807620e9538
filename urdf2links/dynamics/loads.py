"""Applied forces and moments on links, the inputs of the generalized forces Q, docs/equations.md (E23)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["Wrench"]

FRAMES = ("link", "world")


@dataclass(frozen=True)
class Wrench:
    """A force ``force`` (3,) applied at ``point`` (3,) (in the link's own frame, the point rho_N of
    (E23)) and a moment ``moment`` (3,) acting on link ``link``. ``frame`` says in which axes
    ``force`` and ``moment`` are given: ``"link"`` (F~, M~ of (E23)) or ``"world"`` {0}."""

    link: str
    force: np.ndarray = field(default_factory=lambda: np.zeros(3))
    moment: np.ndarray = field(default_factory=lambda: np.zeros(3))
    point: np.ndarray = field(default_factory=lambda: np.zeros(3))
    frame: str = "link"

    def __post_init__(self):
        for name in ("force", "moment", "point"):
            v = np.asarray(getattr(self, name), dtype=float)
            if v.shape != (3,) or not np.all(np.isfinite(v)):
                raise ValueError(f"Wrench on link {self.link!r}: {name} must be 3 finite numbers, got {getattr(self, name)!r}")
            v = v.copy()
            v.setflags(write=False)         # frozen: the packed row below stays what the arrays say
            object.__setattr__(self, name, v)
        if self.frame not in FRAMES:
            raise ValueError(f"Wrench on link {self.link!r}: frame must be one of {FRAMES}, got {self.frame!r}")
        row = np.r_[self.force, self.moment, self.point, float(self.frame == "link")]
        row.setflags(write=False)
        object.__setattr__(self, "row", row)

    row: np.ndarray = field(init=False, repr=False, compare=False)
    """``(force (3), moment (3), point (3), local)`` (10,): the wrench as the kernels take it (after
    the link's index, :func:`urdf2links.dynamics.rows.load_rows`)."""

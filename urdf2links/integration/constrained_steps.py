"""The methods of constrained runs, and the steppers of their oracle (:mod:`urdf2links.integration.constrained_oracle`):
a scene's ``method`` and ``dt`` honoured, or refused by name. Issue 45: constrained scenes run in the compiled loops
(RK4, RK45, DOP853, Radau5, auto: :data:`CONSTRAINED_METHODS`); the steppers below serve the oracle only.

The constrained path takes one step at a time and projects the state onto ``Phi = 0``, ``Phi' = 0`` after every
step (E74), so its stepper must accept a state changed between two steps. Accepted (:data:`CONSTRAINED_METHODS`):

- ``DOP853`` and ``RK45``: scipy's explicit pairs with the scene's ``rtol`` and ``atol``, step for step (the
  projected state and its derivative become the next step's first stage, FSAL);
- ``auto``: DOP853 as above. ``auto`` is DOP853 until its stiffness test hands over to Radau5; the constrained
  path carries no stiffness test and no Radau5, so the run is DOP853 throughout, and its statistics say so;
- ``RK4``: the classic fixed-step method with the scene's ``dt`` on the constrained right-hand side (E72), on
  the same step times as the open path's RK4 (a last step shorter than ``dt`` ends at ``t_end``), each step
  projected; samples between steps from the cubic Hermite polynomial of the step's ends.

Refused with a :class:`~urdf2links.errors.SceneError` naming the method, the scene and what is accepted:
``Radau5``, ``Radau``, ``BDF``, ``LSODA`` (implicit or multistep: their Newton matrices or their history would
not follow the projected state) and ``midpoint`` (the implicit midpoint rule's Newton iterations are not carried
on the constraint solve).
"""

from __future__ import annotations

import numpy as np

from ..errors import SceneError

__all__ = ["CONSTRAINED_METHODS", "ORACLE_METHODS", "RK4Stepper", "constrained_stepper", "check_constrained_method"]

#: The methods the constrained path runs (module doc); any other is refused by name.
CONSTRAINED_METHODS = ("auto", "DOP853", "RK45", "RK4", "Radau5")
#: The oracle's (:mod:`urdf2links.integration.constrained_oracle`): scipy's pairs step by step, and RK4.
ORACLE_METHODS = ("auto", "DOP853", "RK45", "RK4")


def check_constrained_method(run, where: str, *, oracle: bool = False) -> str:
    """The method a constrained run takes for ``run``; a SceneError naming the method, the scene ``where`` and the
    accepted methods otherwise. Compiled (issue 45): :data:`CONSTRAINED_METHODS` as named (``auto`` with its
    stretches); the oracle (``oracle``): :data:`ORACLE_METHODS`, ``auto`` -> ``DOP853``."""
    if run.method not in (ORACLE_METHODS if oracle else CONSTRAINED_METHODS):
        raise SceneError(f"{where}: method {run.method!r} does not run a scene with constraints or fixed tendons: "
                         "accepted are DOP853 and RK45 (with the scene's rtol and atol), Radau5, auto (DOP853 and "
                         "Radau5 in stretches) and RK4 (with dt), in the compiled loops, which project the state onto "
                         "the constraints after every step; scipy's Radau, BDF, LSODA and the implicit midpoint rule "
                         "take no projection (docs/constraints.md)")
    if run.method == "RK4" and run.dt is None:
        raise SceneError(f"{where}: method 'RK4' takes a fixed step on the constrained path too: give dt (seconds)")
    return "DOP853" if (run.method == "auto" and oracle) else run.method


def constrained_stepper(rhs, y0, run, where: str):
    """The stepper of ``run``'s method from ``(0, y0)`` to ``run.t_end`` (scipy's OdeSolver interface: ``status``,
    ``step()``, ``t``, ``y``, ``f``, ``dense_output()``) and its label; ``rhs(t, y)`` the constrained y'."""
    method = check_constrained_method(run, where, oracle=True)
    if method == "RK4":
        return RK4Stepper(rhs, y0, run.t_end, run.dt), f"RK4 dt {run.dt:g}"
    from scipy.integrate import DOP853, RK45      # here: scipy.integrate takes 0.6 s to import

    cls = DOP853 if method == "DOP853" else RK45
    return cls(rhs, 0.0, y0, run.t_end, rtol=run.rtol, atol=run.atol), f"{method} rtol {run.rtol:g}"


def step_times(t_end: float, dt: float) -> np.ndarray:
    """``0, dt, 2 dt, ...``, the last one ``t_end`` (a final step shorter than ``dt``; a remainder below 1e-9 dt
    absorbed in the step before): the step times of the open path's RK4 (:mod:`urdf2links.integration.integrators`)."""
    n = max(1, int(np.ceil(t_end / dt - 1e-9)))
    g = dt * np.arange(n + 1, dtype=float)
    g[-1] = t_end
    return g


class _Hermite:
    """The cubic Hermite polynomial of one step from ``(t0, y0, f0)`` to ``(t1, y1, f1)``; ``f1`` is evaluated on
    the first call (a step whose interval holds no sample costs no evaluation)."""

    def __init__(self, rhs, t0, y0, f0, t1, y1):
        self.rhs, self.t0, self.y0, self.f0, self.t1, self.y1 = rhs, t0, y0, f0, t1, y1
        self.f1 = None

    def __call__(self, t):
        if self.f1 is None:
            self.f1 = self.rhs(self.t1, self.y1)
        h = self.t1 - self.t0
        s = (t - self.t0) / h
        h00, h10, h01, h11 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s, -2 * s**3 + 3 * s**2, s**3 - s**2
        return h00 * self.y0 + h10 * h * self.f0 + h01 * self.y1 + h11 * h * self.f1


class RK4Stepper:
    """Classic RK4 on :func:`step_times`, one step per :meth:`step`, with scipy's OdeSolver attributes: ``t``,
    ``y`` (the caller may replace it by the projected state) and ``f`` (its derivative, the next step's first
    stage), ``status`` ``"running"`` until ``t_end``, ``"finished"`` then, ``"failed"`` on a non-finite state."""

    def __init__(self, fun, y0, t_end: float, dt: float):
        self.fun, self.grid, self.k = fun, step_times(t_end, dt), 0
        self.t, self.y = 0.0, np.array(y0, float)
        self.f = fun(0.0, self.y)
        self.status = "running"
        self._dense = None

    def step(self):
        """One step; returns None, or a message when the state is no longer finite (``status`` ``"failed"``)."""
        t, h, y, k1 = self.t, self.grid[self.k + 1] - self.grid[self.k], self.y, self.f
        k2 = self.fun(t + h / 2, y + h / 2 * k1)
        k3 = self.fun(t + h / 2, y + h / 2 * k2)
        k4 = self.fun(t + h, y + h * k3)
        y1 = y + h / 6 * (k1 + 2 * (k2 + k3) + k4)
        if not np.all(np.isfinite(y1)):
            self.status = "failed"
            return f"the state is not finite after the step of dt {h:g} s"
        self.k += 1
        t1 = float(self.grid[self.k])
        self._dense = _Hermite(self.fun, t, y, k1, t1, y1)
        self.t, self.y = t1, y1
        self.f = None           # the caller sets f at the projected state (FSAL), as for scipy's pairs
        if self.k == self.grid.size - 1:
            self.status = "finished"
        return None

    def dense_output(self):
        """The last step's interpolant (module doc)."""
        return self._dense

"""The physical ranges every number read from a robot description or a scene must fall in.

A finite number can still be absurd: a mass of ``1e308`` kg passes ``math.isfinite`` and then
overflows the first product it enters (``m c c^T``, ``A``), and numpy reports that as a bare
``LinAlgError`` or a NaN far from the file. Each quantity is therefore read with a range
(:data:`RANGES`), wide enough for any real robot or ship and narrow enough that no product the
dynamics forms can overflow a float64 (docs/importing.md, "Physical ranges"):

====================  ============  ===============================================================
quantity              bound         why
====================  ============  ===============================================================
``length``            1e4 m         origins, centres of mass, geometry sizes, points (corpus max 8 m)
``mass``              1e9 kg        ``<mass>`` (corpus max 6 000 kg; a loaded supertanker ~5e8 kg)
``inertia``           1e15 kg m^2   ``<inertia>`` entries (corpus max 5 460; 1e9 kg spread over 1 km ~ 1e14)
``scale``             1e4           mesh ``scale`` factors (corpus max 1)
``multiplier``        1e6           ``<mimic multiplier>`` (corpus max 1.06)
``damping``           1e12          ``<dynamics damping|friction>``, springs' stiffness and damping (corpus max 2e4)
``state``             1e6           initial q (m, rad) and qd (m/s, rad/s) of a scene
``value``             1e9           a scene's functions of time: forces (N), moments, torques, base motion
``frequency``         1e4 Hz        a ``sines`` term's frequency
``acceleration``      1e4 m/s^2     gravity (1 000 g)
``time``              1e6 s         ``t_end``, table times (11.6 days of simulated time)
====================  ============  ===============================================================

With every input inside its range, the largest products the terms form are far below 1e308:
``H`` entries are at most ``m L^2 + I ~ 1e17``, ``A`` sums them over the links times squared
lever arms (``(n L)^2``), ``e`` multiplies by two rates, and the base factors by ``(2 pi f)^2 a``:
every term stays below ~1e60 for trees of up to a million links. Joint ``<limit>`` values, efforts
and velocities are only required to be finite (the corpus writes ``1e16`` for "no limit").

Public API: :data:`RANGES`, :func:`out_of_range`.
"""

from __future__ import annotations

import math

__all__ = ["RANGES", "out_of_range", "MIN_T_END", "MIN_ATOL", "MAX_SAMPLES", "MAX_STEPS", "MAX_TABLE_SAMPLES", "RTOL_FLOOR",
           "METHODS", "Q0_CHOICES"]

#: The integration methods a scene or ``integrate()`` may name (:mod:`urdf2links.integration.integrators`);
#: ``auto`` (DOP853, Radau5 while the scene is stiff) is the default of scenes.
#: The initial states a robot's default scene can start from (urdf2links.scenes.excitation; ``--q0``).
Q0_CHOICES = ("excite", "random", "rest", "zero")
METHODS = ("auto", "RK45", "DOP853", "Radau5", "Radau", "BDF", "LSODA", "RK4", "midpoint")

#: quantity -> (largest absolute value, unit) (module doc).
RANGES: dict[str, tuple[float, str]] = {
    "length": (1e4, "m"),
    "mass": (1e9, "kg"),
    "inertia": (1e15, "kg m^2"),
    "scale": (1e4, ""),
    "multiplier": (1e6, ""),
    "damping": (1e12, "SI units"),
    "state": (1e6, "m or rad (per s)"),
    "value": (1e9, "SI units"),
    "frequency": (1e4, "Hz"),
    "acceleration": (1e4, "m/s^2"),
    "time": (1e6, "s"),
}

#: Shortest run (s): a nanosecond is below any step a robot simulation takes, and far above the
#: subnormal numbers where ``t_end / (samples - 1)`` loses its digits (the slow fuzz profile drew
#: ``t_end = 1e-320``: its sample times came out unsorted).
MIN_T_END = 1e-9
#: Smallest ``atol``: far below the resolution of any quantity a robot has (float64 resolves 1e-22 at
#: 1e-6) and far above the subnormals whose squares vanish in the error norm (the slow fuzz profile drew
#: ``atol = 1e-320``: the step-size controller divided by zero).
MIN_ATOL = 1e-30
#: Most samples a run may ask for (``[run] samples``): 1e6 samples of 40 coordinates are ~650 MB.
MAX_SAMPLES = 1_000_000
#: Most points of a ``{times, values}`` table.
MAX_TABLE_SAMPLES = 100_000
#: Most accepted integration steps of one run (:func:`urdf2links.integration.simulate.simulate` raises an
#: :class:`~urdf2links.errors.IntegrationError` beyond): 200 000 steps of the 1000 s hard case are 2 %.
MAX_STEPS = 10_000_000
#: The smallest ``rtol`` float64 can honour: scipy's solvers raise a smaller one to ``100 eps`` (with
#: a warning); a scene asking for less is refused.
RTOL_FLOOR = 100 * 2.220446049250313e-16


def out_of_range(value: float, quantity: str) -> str | None:
    """None when ``|value|`` is within the range of ``quantity``; otherwise the problem, in words
    (``"1e+308 is outside the physical range |mass| <= 1e+09 kg"``)."""
    bound, unit = RANGES[quantity]
    if math.isfinite(value) and abs(value) <= bound:
        return None
    return f"{value:g} is outside the physical range |{quantity}| <= {bound:g}{(' ' + unit) if unit else ''}"

#: How a robot's inconsistent inertias are treated, and how mimic joints are read (the loaders' options;
#: here, in the base layer, so that the command line can offer them without loading the importer).
INERTIA_POLICIES = ("audit", "strict", "repair")
MIMIC_POLICIES = ("independent", "coupled")

"""Identification: the dynamics' parameters from motion and forces, in the trace method's own terms.

Lagrange's equations in trace form are linear in each link's H (the pseudo-inertia, E10), so
``tau = Y(q, q', q'') pi`` (E89); a link is physically consistent exactly when its H is positive
definite (E12). Modules, bottom to top:

- :mod:`.parameters`: :class:`ParameterSet`, the layout of ``pi`` (each link's 10 H entries; per joint
  damping, Coulomb friction, armature, offset; fixed tendons), to and from a Model;
- :mod:`.regression`: :func:`regressor`, ``Y`` (S, n, p) from the compiled kinematics pass (E89);
- :mod:`.energy`: :func:`energy_regressor` and :func:`energy_rows`, ``E + V`` linear in ``pi`` and the
  power balance over intervals, for data without accelerations (E90);
- :mod:`.base`: :func:`base_parameters`, the identifiable combinations by a pivoted QR, named in link
  terms, and what the data cannot identify (E91);
- :mod:`.fit`: :func:`identify`, the least-squares fit with standard deviations (blocked normal
  equations), and the :class:`Identification` result;
- :mod:`.consistency`: :func:`consistent_fit`, every H positive definite, regularised toward the
  description (E92).

The API is written down in docs/identify.md.
"""

from .parameters import LINK_ENTRIES, ParameterSet, link_matrix, link_vector
from .regression import regressor, regressor_block
from .base import BaseParameters, base_parameters
from .fit import (Identification, NormalEquations, fit_rows, identify, normal_equations, project_constraints,
                  solve_normal_equations)
from .energy import EnergyRows, energy_regressor, energy_rows
from .consistency import Consistency, consistent_fit, min_eigenvalues

__all__ = ["ParameterSet", "LINK_ENTRIES", "link_vector", "link_matrix", "regressor", "regressor_block",
           "BaseParameters", "base_parameters", "Identification", "NormalEquations", "identify", "normal_equations", "fit_rows",
           "solve_normal_equations", "project_constraints",
           "EnergyRows", "energy_regressor", "energy_rows", "Consistency", "consistent_fit", "min_eigenvalues"]

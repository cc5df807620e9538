"""The regressor ``Q = Y(q, q', q'') pi`` as the command needs it: an adapter, until the library's
:mod:`urdf2links.identification` is merged (docs/identify.md, "The command").

``pi`` (module doc of the library): per tree link its ``H``'s 10 entries in :data:`H_ENTRIES` order, then per
coordinate viscous damping, Coulomb friction, armature and a torque offset. The link columns come from the
project's own inverse dynamics (E54), which is linear in each ``H``: column ``(t, k)`` is
``Model.inverse_dynamics`` of the tree with ``H_t = E_k`` (the symmetric unit matrix of entry ``k``) and every
other ``H`` zero, gravity on, armature off. The joint columns are ``q'_j``, ``tanh(q'_j / COULOMB_EPS)`` (the
regularised Coulomb law), ``q''_j`` and 1, on row ``j``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from urdf2links.dynamics.model import Model
from urdf2links.dynamics.tree import LinkTree

__all__ = ["H_ENTRIES", "JOINT_TERMS", "COULOMB_EPS", "Parameters", "regressor", "parameters_of", "coulomb"]

#: H's entries in pi's order: the planar moments, their products, the first moments, the mass.
H_ENTRIES = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2), (0, 3), (1, 3), (2, 3), (3, 3))
_H_LABELS = ("Hxx", "Hyy", "Hzz", "Hxy", "Hxz", "Hyz", "mx", "my", "mz", "m")
#: The joint terms in pi's order, per coordinate.
JOINT_TERMS = ("damping", "coulomb", "armature", "offset")
#: The regularisation speed (rad/s or m/s) of the Coulomb law ``f tanh(q' / eps)``.
COULOMB_EPS = 1e-3


def coulomb(qd) -> np.ndarray:
    """The regularised Coulomb law's shape ``tanh(q' / COULOMB_EPS)``, same shape as ``qd``."""
    return np.tanh(np.asarray(qd, float) / COULOMB_EPS)


@dataclass(frozen=True)
class Parameters:
    """pi's labels (P,) (``panda_link3.m``, ``panda_joint2.damping``), its ``link`` / ``coordinate`` names and
    the index of the first joint term ``joint_start``."""

    labels: tuple[str, ...]
    links: tuple[str, ...]
    coordinates: tuple[str, ...]

    @property
    def joint_start(self) -> int:
        return 10 * len(self.links)

    def __len__(self) -> int:
        return len(self.labels)


def _labels(model) -> Parameters:
    links, names = tuple(model.tree.link_names), tuple(model.coordinate_names)
    labels = [f"{ln}.{h}" for ln in links for h in _H_LABELS] + [f"{c}.{j}" for c in names for j in JOINT_TERMS]
    return Parameters(tuple(labels), links, names)


def parameters_of(model, joints: dict) -> tuple[Parameters, np.ndarray]:
    """pi (P,) of ``model`` (its tree's H, its armature) and ``joints`` (coordinate -> {"damping", "coulomb",
    "offset"}; absent: 0)."""
    p = _labels(model)
    H = model.tree.H
    pi = [H[t][i, j] for t in range(len(p.links)) for i, j in H_ENTRIES]
    for k, c in enumerate(p.coordinates):
        j = joints.get(c, {})
        pi += [j.get("damping", 0.0), j.get("coulomb", 0.0), float(model.tree.armature[k]), j.get("offset", 0.0)]
    return p, np.array(pi, float)


def _unit(i, j) -> np.ndarray:
    E = np.zeros((4, 4))
    E[i, j] = E[j, i] = 1.0
    return E


def regressor(model, q, qd, qdd) -> np.ndarray:
    """``Y`` (S, n, P) at the samples ``q``, ``q'``, ``q''`` (S, n) (module doc)."""
    tree = model.tree
    S, n = np.shape(q)
    L = tree.n_links
    Y = np.zeros((S, n, 10 * L + 4 * n))
    for t in range(L):
        for k, (i, j) in enumerate(H_ENTRIES):
            H = np.zeros((L, 4, 4))
            H[t] = _unit(i, j)
            unit = LinkTree(tree.link_names, tree.parent, tree.params, tree.coord, H, tree.coordinate_names)
            Y[:, :, 10 * t + k] = Model(unit, gravity=model.gravity_vector).inverse_dynamics(q, qd, qdd)
    rows = np.arange(n)
    for c, x in enumerate((qd, coulomb(qd), qdd, np.ones_like(qd))):
        Y[:, rows, 10 * L + 4 * rows + c] = x
    return Y

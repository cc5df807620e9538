"""The model users hold: a tree of links and its dynamics, the public API of the project.

``Model`` evaluates the terms of the equations of motion (docs/equations.md (E24)) with the compiled
recursive form (:mod:`urdf2links.kernels`). ``method="literal"`` (the trace formulas term by term) and
``method="numpy"`` (the recursive form in numpy) run the oracles of :mod:`urdf2links.oracles`
instead, for checking. Every dynamics call takes optional keyword arguments ``t`` (time) and
``base`` (None for a fixed base, a :class:`~urdf2links.transforms.BaseState`, or a callable
``t -> BaseState``, the prescribed motion of {A}); a fixed base computes no base terms at all.

Coupled coordinates (mimic joints loaded with ``mimic="coupled"``) are a constant linear map
``q_tree = C q + d`` from the model's ``n`` coordinates to the tree's; then
``A = C^T A_tree C``, ``e = C^T e_tree``, ``G = C^T G_tree``, ``Q = C^T Q_tree`` (C constant, so no
extra velocity terms: E42).
"""

from __future__ import annotations

from typing import Iterable, Sequence

import numpy as np
import scipy.linalg

from .errors import DynamicsError
from .kernels import CompiledTree, forward_dynamics as _fd_kernel
from .loads import Wrench
from .transforms import BaseState, base_state_at, resolve_base
from .tree import LinkTree

__all__ = ["Model", "METHODS", "DEFAULT_GRAVITY"]

METHODS = ("recursive", "numpy", "literal")
_NO_BASE = np.zeros(18)
_NO_BASE.setflags(write=False)
_NO_G = np.zeros(3)
_NO_G.setflags(write=False)
DEFAULT_GRAVITY = (0.0, 0.0, -9.81)


class Model:
    """A robot as a tree of links, with the trace-method dynamics.

    Parameters
    ----------
    tree : LinkTree
    gravity : (3,) gravitational acceleration in {0} used by :meth:`gravity` and
        :meth:`potential_energy`; default ``(0, 0, -9.81)`` (Z up, g = 9.81).
    coupling : optional ``(C (n_tree, n), d (n_tree,), names (n,))`` for coupled coordinates.
    name, source : the robot's name and where it came from.
    audit : findings of the importer's inertia audit (a list of records).
    """

    def __init__(self, tree: LinkTree, *, gravity=DEFAULT_GRAVITY, coupling=None, name: str = "",
                 source: str | None = None, audit: Sequence = (), info: dict | None = None):
        self.tree = tree
        g = np.asarray(gravity, float)
        if g.shape != (3,) or not np.all(np.isfinite(g)):
            raise ValueError(f"gravity must be 3 finite numbers, got {gravity!r}")
        g.setflags(write=False)
        self.gravity_vector = g
        self.name = name
        self.source = source
        self.audit = list(audit)
        self.info = dict(info or {})
        self.compiled = CompiledTree(tree)
        """The tree flattened for the kernels, with its scratch (:class:`~urdf2links.kernels.CompiledTree`)."""
        self._zeros = np.zeros(tree.n)      # tau = 0 for the kernel (never written)
        self._numpy_plan = None
        if coupling is None:
            self._C = None
            self._d = None
            self._names = tree.coordinate_names
        else:
            C, d, names = coupling
            C = np.asarray(C, float)
            d = np.asarray(d, float)
            if C.shape != (tree.n, len(names)) or d.shape != (tree.n,):
                raise ValueError(f"coupling shapes {C.shape}, {d.shape} do not fit a tree of {tree.n} coordinates")
            self._C, self._d, self._names = C, d, tuple(names)

    # -- identity --------------------------------------------------------------------------------
    @property
    def n(self) -> int:
        """Number of generalized coordinates."""
        return len(self._names)

    @property
    def coordinate_names(self) -> tuple[str, ...]:
        return self._names

    @property
    def link_names(self) -> tuple[str, ...]:
        return self.tree.link_names

    @property
    def coupling(self) -> tuple[np.ndarray, np.ndarray] | None:
        """``(C (n_tree, n), d (n_tree,))`` of coupled coordinates, ``q_tree = C q + d``; None without."""
        return None if self._C is None else (self._C, self._d)

    def __repr__(self) -> str:
        return f"<Model {self.name!r}: {self.tree.n_links} links, {self.n} coordinates>"

    # -- coordinates -----------------------------------------------------------------------------
    def vector(self, x, what: str) -> np.ndarray:
        """``x`` as a float array of shape (n,); a ValueError naming ``what`` and the coordinates
        otherwise."""
        a = np.asarray(x, dtype=float)
        if a.shape != (self.n,):
            raise ValueError(f"{what} must have shape ({self.n},) for coordinates {self._names}; got shape {a.shape}")
        return a

    def tree_state(self, q, qd=None):
        """The tree's coordinates (and rates) of a model state: ``(C q + d, C qd)``, or ``(q, qd)``."""
        q = self.vector(q, "q")
        qd = None if qd is None else self.vector(qd, "qd")
        if self._C is None:
            return q, qd
        return self._C @ q + self._d, (None if qd is None else self._C @ qd)

    def reduce(self, x):
        """A tree vector (n_tree,) or matrix (n_tree, n_tree) in the model's coordinates:
        ``C^T x`` or ``C^T x C``."""
        if self._C is None:
            return x
        return self._C.T @ x if x.ndim == 1 else self._C.T @ x @ self._C

    # -- plumbing --------------------------------------------------------------------------------
    @staticmethod
    def _check_method(method):
        if method not in METHODS:
            raise ValueError(f"method must be one of {METHODS}, got {method!r}")

    def wrenches(self, loads: Iterable[Wrench]) -> list:
        """``(tree link index, force, moment, point, frame)`` of :class:`~urdf2links.loads.Wrench` loads."""
        out = []
        for w in loads:
            if not isinstance(w, Wrench):
                raise TypeError(f"loads must be Wrench objects, got {type(w).__name__}")
            out.append((self.tree.link_index(w.link), w.force, w.moment, w.point, w.frame))
        return out

    @staticmethod
    def base18(base, t) -> np.ndarray:
        """(18,) pose, rate and acceleration of {A} for the kernels (zeros for a fixed base)."""
        state = base_state_at(base, t)
        if state is None:
            return _NO_BASE
        return np.concatenate([np.asarray(state.pose, float), np.asarray(state.rate, float),
                               np.asarray(state.accel, float)])

    def _compiled_terms(self, q, qd, t, base, gravity: bool, want_A: bool):
        qt, qdt = self.tree_state(q, qd)
        if qdt is None:
            qdt = np.zeros(self.tree.n)
        return self.compiled.terms(qt, qdt, self.base18(base, t), self.gravity_vector if gravity else _NO_G,
                                   want_A=want_A)

    def _oracle(self, method, q, qd, t, base, wrenches=()) -> dict:
        """A, e, G, Q, E, V (tree coordinates) of an oracle form (:mod:`urdf2links.oracles`)."""
        qt, qdt = self.tree_state(q, np.zeros(self.n) if qd is None else qd)
        kw = dict(base_T=resolve_base(base, t), gravity_vector=self.gravity_vector, wrenches=wrenches)
        if method == "literal":
            from .oracles.literal import literal_terms

            return literal_terms(self.tree, qt, qdt, **kw)
        from .oracles.recursive import RecursivePlan, numpy_terms

        if self._numpy_plan is None:
            self._numpy_plan = RecursivePlan(self.tree)
        return numpy_terms(self._numpy_plan, qt, qdt, **kw)

    # -- the public API --------------------------------------------------------------------------
    def mass_matrix(self, q, *, t: float = 0.0, base=None, method: str = "recursive") -> np.ndarray:
        """A (n, n), (E19): ``a_il = sum_p tr(T_i H T_l^T)``."""
        self._check_method(method)
        if method != "recursive":
            return self.reduce(self._oracle(method, q, None, t, base)["A"])
        return self.reduce(self._compiled_terms(q, None, t, base, False, True)[0])

    def bias(self, q, qd, *, t: float = 0.0, base=None, method: str = "recursive") -> np.ndarray:
        """e (n,), (E20): velocity terms and base-motion terms (E15); no gravity."""
        self._check_method(method)
        if method != "recursive":
            return self.reduce(self._oracle(method, q, qd, t, base)["e"])
        return self.reduce(-self._compiled_terms(q, qd, t, base, False, False)[1])

    def gravity(self, q, *, t: float = 0.0, base=None, method: str = "recursive") -> np.ndarray:
        """G (n,), (E22): ``g_i = m g e3^T T_i r_C`` summed over links, for ``self.gravity_vector``."""
        self._check_method(method)
        if method != "recursive":
            return self.reduce(self._oracle(method, q, None, t, base)["G"])
        state = base_state_at(base, t)      # at rest relative to a base at rest: b = -G
        still = None if state is None else BaseState.fixed(state.pose)
        return self.reduce(-self._compiled_terms(q, None, t, still, True, False)[1])

    def generalized_forces(self, q, loads: Iterable[Wrench], *, t: float = 0.0, base=None,
                           method: str = "recursive") -> np.ndarray:
        """Q (n,), (E23): generalized forces of applied forces and moments on links."""
        self._check_method(method)
        wr = self.wrenches(loads)
        if method != "recursive":
            return self.reduce(self._oracle(method, q, None, t, base, wr)["Q"])
        qt, _ = self.tree_state(q)
        if not wr:
            return np.zeros(self.n)
        return self.reduce(self.compiled.forces(qt, self.base18(base, t), wr))

    def kinetic_energy(self, q, qd, *, t: float = 0.0, base=None, method: str = "recursive") -> float:
        """E, (E17): ``0.5 sum_p tr(T' H T'^T)``, base motion included."""
        self._check_method(method)
        if method != "recursive":
            return float(self._oracle(method, q, qd, t, base)["E"])
        qt, qdt = self.tree_state(q, qd)
        return float(self.compiled.energies(qt, qdt, self.base18(base, t), _NO_G)[0])

    def potential_energy(self, q, *, t: float = 0.0, base=None, method: str = "recursive") -> float:
        """V of gravity, (E21): ``sum_p m_p g z_C`` (for ``self.gravity_vector``)."""
        self._check_method(method)
        if method != "recursive":
            return float(self._oracle(method, q, None, t, base)["V"])
        qt, _ = self.tree_state(q)
        return float(self.compiled.energies(qt, np.zeros(self.tree.n), self.base18(base, t), self.gravity_vector)[1])

    def link_poses(self, q, *, t: float = 0.0, base=None) -> np.ndarray:
        """(L, 4, 4): the {0}-pose ``T^(p)`` of every link (E4)."""
        qt, _ = self.tree_state(q)
        return self.compiled.poses(qt, self.base18(base, t))

    def forward_dynamics(self, q, qd, tau=None, *, loads: Iterable[Wrench] = (), t: float = 0.0,
                         base=None, gravity: bool = True) -> np.ndarray:
        """q'' (n,) from (E24), ``A q'' = Q - G - e``, by Cholesky (E46).

        ``tau`` (n,) are generalized forces added to Q (joint torques and forces); ``loads`` applied
        wrenches; ``gravity=False`` leaves G out. Raises :class:`~urdf2links.errors.DynamicsError`
        naming the configuration and the coordinates when A is not positive definite.
        """
        if not loads and self._C is None:    # the hot path: one compiled call
            q = np.asarray(q, dtype=float)
            qd = np.asarray(qd, dtype=float)
            fast = self.compiled
            shape = (fast.n,)
            if q.shape != shape or qd.shape != shape:
                self.vector(q, "q"), self.vector(qd, "qd")
            out = np.empty(shape)
            pivot = _fd_kernel(fast.I, fast.F, fast.W, q, qd,
                               self._zeros if tau is None else self.vector(tau, "tau"),
                               _NO_BASE if base is None else self.base18(base, t),
                               self.gravity_vector if gravity else _NO_G, out)
            if pivot < 0:
                return out
        A, b = self._compiled_terms(q, qd, t, base, gravity, True)
        qt, _ = self.tree_state(q)
        wr = self.wrenches(loads)
        if wr:
            b = b + self.compiled.forces(qt, self.base18(base, t), wr)
        rhs = self.reduce(b)
        if tau is not None:
            rhs = rhs + self.vector(tau, "tau")
        return self.solve_mass_matrix(self.reduce(A), rhs, q=q)

    def solve_mass_matrix(self, A: np.ndarray, rhs: np.ndarray, *, q=None) -> np.ndarray:
        """``A^{-1} rhs`` by Cholesky; a matrix that is not positive definite raises DynamicsError."""
        try:
            c, low = scipy.linalg.cho_factor(A, lower=True, check_finite=True)
        except (np.linalg.LinAlgError, ValueError) as err:
            raise self.not_positive_definite(A, q) from err
        pivots = np.diag(c) ** 2
        scale = max(float(np.max(np.abs(np.diag(A)))), np.finfo(float).tiny)
        if np.min(pivots) <= 10.0 * np.finfo(float).eps * scale * len(pivots):
            # A semi-definite matrix can pass the factorization on rounding: a pivot at the level of
            # the rounding error of A's entries (n eps max|A_ii|) means a zero eigenvalue.
            raise self.not_positive_definite(A, q)
        return scipy.linalg.cho_solve((c, low), rhs, check_finite=False)

    def not_positive_definite(self, A, q) -> DynamicsError:
        """The :class:`~urdf2links.errors.DynamicsError` for a mass matrix ``A`` (n, n) at ``q`` that is
        not positive definite: its smallest eigenvalue, the coordinates and links it moves, the fix."""
        if not np.all(np.isfinite(A)):
            bad = sorted({self._names[i] for i, j in zip(*np.nonzero(~np.isfinite(A)))})
            return DynamicsError(f"mass matrix A has non-finite entries at q={_fmt(q)} in coordinates {bad}",
                                 q=q, coordinates=tuple(bad))
        w, V = np.linalg.eigh(A)
        vec = V[:, 0]
        big = np.nonzero(np.abs(vec) > 0.1 * np.abs(vec).max())[0]
        names = tuple(self._names[i] for i in big)
        parts = ", ".join(f"{self._names[i]} ({vec[i]:+.2f})" for i in big)
        links = sorted({self.tree.link_names[self.tree.coord_link[self.tree.coordinate_index(nm)]]
                        for nm in names if nm in self.tree.coordinate_names})
        return DynamicsError(
            f"mass matrix A of model {self.name!r} is not positive definite at q={_fmt(q)}: smallest "
            f"eigenvalue {w[0]:.3e} (largest {w[-1]:.3e}); its eigenvector moves coordinates {parts}, "
            f"of links {links}. A moving link (or subtree) without mass or without inertia about its "
            f"joint axis does this; load with inertia='repair' or give the link an inertia.",
            q=q, coordinates=names,
        )


def _fmt(q) -> str:
    if q is None:
        return "?"
    return np.array2string(np.asarray(q, float), precision=4, separator=", ", max_line_width=10_000)

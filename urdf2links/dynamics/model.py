"""The model users hold: a tree of links and its dynamics, the public API of the project.

``Model`` evaluates the terms of the equations of motion (docs/equations.md (E24)) with the compiled
recursive form (:mod:`urdf2links.dynamics.kernels`, called through :mod:`urdf2links.dynamics.model_kernels`).
``method="literal"`` (the trace formulas term by term) and ``method="numpy"`` (the recursive form in
numpy) run the oracles of :mod:`urdf2links.dynamics.oracles` instead, for checking. Every dynamics call takes
optional keyword arguments ``t`` (time) and ``base`` (None for a fixed base, a
:class:`~urdf2links.dynamics.transforms.BaseState`, or a callable ``t -> BaseState``, the prescribed motion of
{A}); a fixed base computes no base terms at all.

**Batches.** The compiled calls accept one state, ``q`` (n,), or a batch, ``Q`` (B, n) (and ``QD``,
``TAU`` of the same shape), and return ``(B, ...)``: one compiled call, parallel over the rows (numba
threads: ``NUMBA_NUM_THREADS``, or ``numba.set_num_threads``), equal to the per-state calls to the
last bit. A batch's base is one BaseState for every row, a BaseState of ``(B, 6)`` arrays (one per
row), or a callable evaluated at ``t``: a number (every row at that time) or an array ``(B,)`` (each
row at its own time) (:mod:`urdf2links.dynamics.rows`). A failure names the first offending row.

Coupled coordinates (mimic joints loaded with ``mimic="coupled"``) are a constant linear map
``q_tree = C q + d`` from the model's ``n`` coordinates to the tree's; then
``A = C^T A_tree C``, ``e = C^T e_tree``, ``G = C^T G_tree``, ``Q = C^T Q_tree`` (C constant, so no
extra velocity terms: E42).
"""

from __future__ import annotations

import copy
from collections import namedtuple
from typing import Iterable, Sequence

import numpy as np

from ..errors import DynamicsError
from . import model_kernels as MK
from .loads import Wrench
from .rows import NO_LOADS, base_rows, kernel_array, load_rows, state_rows
from .transforms import resolve_base
from .tree import LinkTree
from .tree_arrays import flat_tree, tf_with_gravity

__all__ = ["Model", "METHODS", "DEFAULT_GRAVITY", "FlatTree"]

METHODS = ("recursive", "numpy", "literal")
DEFAULT_GRAVITY = (0.0, 0.0, -9.81)
_NO_C, _NO_D = np.zeros((0, 0)), np.zeros(0)
_EMPTY, _EMPTY2 = np.empty(0), np.empty((0, 0))        # an absent qd or tau, the unused output of a hot terms call
_empty = np.empty       # one lookup on the hot path
_FROZEN = MK.FROZEN     # the frozen hot entries (model_kernels.frozen), one lookup on the hot path

FlatTree = namedtuple("FlatTree", ["TI", "TF"])
"""The tree flattened for the kernels (:func:`urdf2links.dynamics.tree_arrays.flat_tree`)."""


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
        self.name = name
        self.source = source
        self.audit = list(audit)
        self.info = dict(info or {})
        self.compiled = FlatTree(*flat_tree(tree))
        """The tree flattened for the kernels (:class:`FlatTree`)."""
        self._TI = self.compiled.TI     # the hot entries' tree, one lookup each (and _TFg, _TF0: _set_gravity)
        self._set_gravity(gravity)
        self._nq = tree.n               # the length of q'' on the hot path (no coupling there)
        self._numpy_plan = None
        if coupling is None:
            self._C = None
            self._d = None
            self._names = tree.coordinate_names
            self._Ck, self._dk = _NO_C, _NO_D
        else:
            C, d, names = coupling
            C = np.asarray(C, float)
            d = np.asarray(d, float)
            if C.shape != (tree.n, len(names)) or d.shape != (tree.n,):
                raise ValueError(f"coupling shapes {C.shape}, {d.shape} do not fit a tree of {tree.n} coordinates")
            self._C, self._d, self._names = C, d, tuple(names)
            # writable C-contiguous copies: a read-only array is another numba type (another compilation)
            self._Ck, self._dk = np.array(C, float, order="C"), np.array(d, float, order="C")

    def _set_gravity(self, gravity) -> None:
        """``gravity_vector`` (3,), read-only, and the hot path's copies: ``_g`` (writable: the compiled
        kernels take writable arrays) and the hot entries' ``TF`` with this gravity and with none
        (:func:`~urdf2links.dynamics.tree_arrays.tf_with_gravity`). The caller's array is copied, not frozen."""
        g = np.array(gravity, float)
        if g.shape != (3,) or not np.all(np.isfinite(g)):
            raise ValueError(f"gravity must be 3 finite numbers, got {gravity!r}")
        self._g, self._g0 = g.copy(), np.zeros(3)
        self._TFg, self._TF0 = tf_with_gravity(self.compiled.TF, self._g), tf_with_gravity(self.compiled.TF, self._g0)
        g.setflags(write=False)
        self.gravity_vector = g

    def with_gravity(self, gravity) -> Model:
        """This model under the gravity ``gravity`` (3,): a shallow copy sharing the tree (the model itself
        when its gravity is the same), whose every call, compiled or oracle, uses it. Raises ValueError
        naming the value when it is not 3 finite numbers."""
        g = np.asarray(gravity, float)
        if g.shape == (3,) and np.array_equal(self.gravity_vector, g):
            return self
        out = copy.copy(self)
        out._set_gravity(gravity)
        return out

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

    # -- MuJoCo's state (models read from MJCF) -----------------------------------------------------
    def _mujoco_map(self):
        qmap = self.info.get("mujoco")
        if qmap is None:
            raise ValueError(f"model {self.name!r} was not loaded from an MJCF file: it has no MuJoCo state to map "
                             "to (load_mjcf gives one)")
        return qmap

    def to_mujoco(self, q, qd=None):
        """``(qpos, qvel)`` in the compiled MJCF file's order of the state ``(q, qd)`` (``qvel`` None
        without ``qd``): hinges and slides as they are, ball and free joints' ZYX angles as quaternions
        and their rates as angular velocities (:mod:`urdf2links.parsers.mjcf_state`). Models read from
        MJCF only."""
        return self._mujoco_map().to_mujoco(q, qd)

    def from_mujoco(self, qpos, qvel=None, *, reference=None):
        """``(q, qd)`` of MuJoCo's ``(qpos, qvel)``: the inverse of :meth:`to_mujoco`; ``reference`` (n,)
        picks, for ball and free joints, the branch of the ZYX angles nearest it."""
        return self._mujoco_map().from_mujoco(qpos, qvel, reference=reference)

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
        """``(tree link index, force, moment, point, frame)`` of :class:`~urdf2links.dynamics.loads.Wrench` loads."""
        out = []
        for w in loads:
            if not isinstance(w, Wrench):
                raise TypeError(f"loads must be Wrench objects, got {type(w).__name__}")
            out.append((self.tree.link_index(w.link), w.force, w.moment, w.point, w.frame))
        return out

    def _rows(self, named):
        return state_rows(self.n, self._names, named)

    def _common(self, base, t, B, batched, *, still=False):
        """The arguments every compiled row takes after the state: base rows, has_base."""
        return base_rows(base, t, B, batched=batched, still=still)

    def _terms(self, what, method, q, qd, t, base, *, gravity, still=False, loads=()):
        """A (MASS), e or G (BIAS) or Q (FORCES), for one state or a batch (compiled)."""
        named = [("q", q)] if qd is None else [("q", q), ("qd", qd)]
        rows = self._rows(named)
        Q, QD = rows.arrays[0], rows.arrays[-1]
        B, n = Q.shape
        BASE, has_base = self._common(base, t, B, rows.batched, still=still)
        g = self._g if gravity else self._g0
        LD = load_rows(self.tree, loads) if loads else NO_LOADS
        A = np.empty((B, n, n) if what == MK.MASS else (1, 0, 0))
        V = np.empty((1, 0) if what == MK.MASS else (B, n))
        args = (BASE, has_base, g[0], g[1], g[2], LD, self._Ck, self._dk, self._C is not None, what)
        if rows.batched:
            MK.terms_batch(self.compiled.TI, self.compiled.TF, Q, QD, qd is not None, *args, A, V, MK.chunks(B))
        else:
            MK.terms_one(self.compiled.TI, self.compiled.TF, Q[0], QD[0], qd is not None, BASE[0], *args[1:],
                         A[0], V[0])
        out = A if what == MK.MASS else V
        return out if rows.batched else out[0]

    def _energies(self, q, qd, t, base):
        rows = self._rows([("q", q)] if qd is None else [("q", q), ("qd", qd)])
        Q, QD = rows.arrays[0], rows.arrays[-1]
        B = Q.shape[0]
        BASE, has_base = self._common(base, t, B, rows.batched)
        g = self._g
        args = (qd is not None, BASE, has_base, g[0], g[1], g[2], self._Ck, self._dk, self._C is not None)
        if rows.batched:
            E, V = np.empty(B), np.empty(B)
            MK.energy_batch(self.compiled.TI, self.compiled.TF, Q, QD, *args, E, V, MK.chunks(B))
            return E, V
        E, V = MK.energy_one(self.compiled.TI, self.compiled.TF, Q[0], QD[0], args[0], BASE[0], *args[2:])
        return float(E), float(V)

    @staticmethod
    def _single(method, q, what):
        if method != "recursive" and np.ndim(q) != 1:
            raise ValueError(f"method={method!r} evaluates one state (q of shape (n,)); {what} of a batch runs "
                             f"compiled (method='recursive'), or loop over the rows")

    def _oracle(self, method, q, qd, t, base, wrenches=()) -> dict:
        """A, e, G, Q, E, V (tree coordinates) of an oracle form (:mod:`urdf2links.dynamics.oracles`)."""
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
    # Each call first tries its hot path (a fixed base, no coupling, float64 vectors: one frozen compiled
    # call, model_kernels.frozen); anything else (batches, a base, coupled coordinates, other types, an
    # oracle method) goes through the general path, which checks and converts.
    def _plain(self, base, method):
        return base is None and self._C is None and method == "recursive"

    def mass_matrix(self, q, *, t=0.0, base=None, method: str = "recursive") -> np.ndarray:
        """A (n, n), or (B, n, n) for q (B, n), (E19): ``a_il = sum_p tr(T_i H T_l^T)``."""
        if self._plain(base, method):
            A = np.empty((self._nq, self._nq))
            if self._call("terms_plain", self._TF0, q, _EMPTY, MK.MASS, A, _EMPTY) == 0:
                return A
        self._check_method(method)
        if method != "recursive":
            self._single(method, q, "mass_matrix")
            return self.reduce(self._oracle(method, q, None, t, base)["A"])
        return self._terms(MK.MASS, method, q, None, t, base, gravity=False)

    def bias(self, q, qd, *, t=0.0, base=None, method: str = "recursive") -> np.ndarray:
        """e (n,) or (B, n), (E20): velocity terms and base-motion terms (E15); no gravity."""
        if self._plain(base, method):
            v = np.empty(self._nq)
            if self._call("terms_plain", self._TF0, q, qd, MK.BIAS, _EMPTY2, v) == 0:
                return v
        self._check_method(method)
        if method != "recursive":
            self._single(method, q, "bias")
            return self.reduce(self._oracle(method, q, qd, t, base)["e"])
        return self._terms(MK.BIAS, method, q, qd, t, base, gravity=False)

    def gravity(self, q, *, t=0.0, base=None, method: str = "recursive") -> np.ndarray:
        """G (n,) or (B, n), (E22): ``g_i = m g e3^T T_i r_C`` summed over links, for ``self.gravity_vector``."""
        if self._plain(base, method):
            v = np.empty(self._nq)
            if self._call("terms_plain", self._TFg, q, _EMPTY, MK.BIAS, _EMPTY2, v) == 0:
                return v
        self._check_method(method)
        if method != "recursive":
            self._single(method, q, "gravity")
            return self.reduce(self._oracle(method, q, None, t, base)["G"])
        # at rest relative to a base at rest in its pose: -b = G
        return self._terms(MK.BIAS, method, q, None, t, base, gravity=True, still=True)

    def generalized_forces(self, q, loads: Iterable[Wrench], *, t=0.0, base=None,
                           method: str = "recursive") -> np.ndarray:
        """Q (n,) or (B, n), (E23): generalized forces of applied forces and moments on links."""
        loads = loads if isinstance(loads, list) else list(loads)
        if self._plain(base, method) and loads:
            v = np.empty(self._nq)
            LD = load_rows(self.tree, loads)
            if self._call("forces_plain", self._TF0, q, LD, v) == 0:
                return v
        self._check_method(method)
        if method != "recursive":
            self._single(method, q, "generalized_forces")
            return self.reduce(self._oracle(method, q, None, t, base, self.wrenches(loads))["Q"])
        if not loads:
            load_rows(self.tree, loads)
            return np.zeros(np.shape(self._rows([("q", q)]).arrays[0]) if np.ndim(q) == 2 else self.n)
        return self._terms(MK.FORCES, method, q, None, t, base, gravity=False, loads=loads)

    def kinetic_energy(self, q, qd, *, t=0.0, base=None, method: str = "recursive"):
        """E (a float, or (B,)), (E17): ``0.5 sum_p tr(T' H T'^T)``, base motion included."""
        if self._plain(base, method):
            out = np.empty(2)
            if self._call("energy_plain", self._TFg, q, qd, out) == 0:
                return float(out[0])
        self._check_method(method)
        if method != "recursive":
            self._single(method, q, "kinetic_energy")
            return float(self._oracle(method, q, qd, t, base)["E"])
        return self._energies(q, qd, t, base)[0]

    def potential_energy(self, q, *, t=0.0, base=None, method: str = "recursive"):
        """V of gravity (a float, or (B,)), (E21): ``sum_p m_p g z_C`` (for ``self.gravity_vector``)."""
        if self._plain(base, method):
            out = np.empty(2)
            if self._call("energy_plain", self._TFg, q, _EMPTY, out) == 0:
                return float(out[1])
        self._check_method(method)
        if method != "recursive":
            self._single(method, q, "potential_energy")
            return float(self._oracle(method, q, None, t, base)["V"])
        return self._energies(q, None, t, base)[1]

    def link_poses(self, q, *, t: float = 0.0, base=None) -> np.ndarray:
        """(L, 4, 4): the {0}-pose ``T^(p)`` of every link (E4)."""
        q = kernel_array(self.vector(q, "q"))
        BASE, has_base = self._common(base, t, 1, False)
        L = self.tree.n_links
        R, o = np.empty((L, 3, 3)), np.empty((L, 3))
        MK.poses_one(self.compiled.TI, self.compiled.TF, q, BASE[0], has_base, self._Ck, self._dk,
                     self._C is not None, R, o)
        T = np.zeros((L, 4, 4))
        T[:, :3, :3], T[:, :3, 3], T[:, 3, 3] = R, o, 1.0
        return T

    def forward_dynamics(self, q, qd, tau=None, *, loads: Iterable[Wrench] = (), t=0.0,
                         base=None, gravity: bool = True, method: str = "recursive", lanes: bool = True) -> np.ndarray:
        """q'' (n,), or (B, n) for a batch, from (E24), ``A q'' = Q - G - e``, by the tree-sparse
        factorization (E47) (dense Cholesky (E46) for coupled coordinates).

        A batch with a fixed base, no loads, no coupled coordinates and no armature is computed in SIMD
        lanes, blocks of states at once (:mod:`urdf2links.dynamics.lane_batch`: the scalar rows' results to
        rounding); ``lanes=False`` computes it row by row (:func:`~urdf2links.dynamics.model_kernels.fd_batch`,
        the comparison of benchmarks/batch_cost.py and tests/test_lanes.py).

        ``tau`` (n,) or (B, n) are generalized forces added to Q (joint torques and forces); ``loads``
        applied wrenches (the same for every row); ``gravity=False`` leaves G out; ``method`` as for
        every other call (``"literal"`` or ``"numpy"``: the oracle's terms, solved by Cholesky). Raises
        :class:`~urdf2links.errors.DynamicsError` naming the configuration (and the row of a batch) and
        the coordinates when A is not positive definite.
        """
        if base is None and not loads and method == "recursive" and self._C is None:    # the hot path
            out = _empty(self._nq)
            try:        # _call's work inlined: each Python step here is a few percent of the call
                pivot = (_FROZEN.get("fd_plain") or MK.frozen("fd_plain"))(
                    self._TI, self._TFg if gravity else self._TF0, q, qd, _EMPTY if tau is None else tau, out)
            except TypeError:       # not float64 vectors (or a batch): converted on the general path
                pivot = -2
            if pivot == -1:
                return out
        if method != "recursive":
            return self._forward_oracle(method, q, qd, tau, list(loads), t, base, gravity)
        return self._forward_dynamics(q, qd, tau, list(loads), t, base, gravity, lanes)

    def inverse_dynamics(self, q, qd, qdd, *, t=0.0, base=None, loads: Iterable[Wrench] = (), gravity: bool = True,
                         method: str = "recursive") -> np.ndarray:
        """tau (n,), or (B, n) for a batch: the generalized forces that give the state ``(q, q')`` the
        accelerations ``q''``, ``tau = A q'' + e + G - Q`` (E54), the inverse of :meth:`forward_dynamics`
        (``forward_dynamics(q, qd, tau, loads=...)`` returns ``qdd``).

        Sign convention: ``loads`` (applied wrenches, the same for every row) act on the robot, so
        their generalized forces ``Q`` (E23) are subtracted: ``tau`` is what the joints must add to
        them. ``e`` includes the base terms of a moving ``base`` and the armature (E49);
        ``gravity=False`` leaves ``G`` out. One compiled O(n) pass (E54) with ``method="recursive"``
        (batches: one compiled call, parallel over rows, equal to the per-state calls to the bit);
        ``"literal"`` and ``"numpy"`` evaluate ``A q'' + e + G - Q`` from the oracles' terms."""
        if base is None and not loads and self._C is None and method == "recursive":    # the hot path
            out = np.empty(self._nq)
            if self._call("id_plain", self._TFg if gravity else self._TF0, q, qd, qdd, out) == 0:
                return out
        loads = list(loads)
        if method != "recursive":
            self._check_method(method)
            self._single(method, q, "inverse_dynamics")
            terms = self._oracle(method, q, qd, t, base, self.wrenches(loads))
            tau = self.reduce(terms["A"]) @ self.vector(qdd, "qdd") + self.reduce(terms["e"]) - self.reduce(terms["Q"])
            return tau + self.reduce(terms["G"]) if gravity else tau
        from . import inverse_kernels as IK

        rows = self._rows([("q", q), ("qd", qd), ("qdd", qdd)])
        Q, QD, QDD = rows.arrays
        B = Q.shape[0]
        BASE, has_base = self._common(base, t, B, rows.batched)
        g = self._g if gravity else self._g0
        LD = load_rows(self.tree, loads) if loads else NO_LOADS
        OUT = np.empty_like(Q)
        args = (has_base, g[0], g[1], g[2], LD, self._Ck, self._dk, self._C is not None)
        if rows.batched:
            IK.id_batch(self.compiled.TI, self.compiled.TF, Q, QD, QDD, BASE, *args, OUT, MK.chunks(B))
            return OUT
        IK.id_one(self.compiled.TI, self.compiled.TF, Q[0], QD[0], QDD[0], BASE[0], *args, OUT[0])
        return OUT[0]

    def _call(self, name, TF, *args):
        """The frozen hot entry ``name`` on this model's tree, ``TF`` one of its two hot ones (``_TFg``
        or ``_TF0``); -2 when the arguments are not float64 vectors of the right sizes (the caller then
        takes the general path)."""
        fn = _FROZEN.get(name) or MK.frozen(name)
        try:
            return fn(self._TI, TF, *args)
        except TypeError:       # not float64 vectors (or a batch): converted on the general path
            return -2

    def _forward_oracle(self, method, q, qd, tau, loads, t, base, gravity):
        """q'' from an oracle's A, e, G, Q (one state)."""
        self._check_method(method)
        self._single(method, q, "forward_dynamics")
        terms = self._oracle(method, q, qd, t, base, self.wrenches(loads))
        rhs = self.reduce(terms["Q"]) - self.reduce(terms["e"])
        if gravity:
            rhs = rhs - self.reduce(terms["G"])
        if tau is not None:
            rhs = rhs + self.vector(tau, "tau")
        return self.solve_mass_matrix(self.reduce(terms["A"]), rhs, q=q)

    def _forward_dynamics(self, q, qd, tau, loads, t, base, gravity, lanes=True):
        rows = self._rows([("q", q), ("qd", qd), ("tau", tau)])
        Q, QD, TAU = rows.arrays
        B = Q.shape[0]
        BASE, has_base = self._common(base, t, B, rows.batched)
        g = self._g if gravity else self._g0
        LD = load_rows(self.tree, loads) if loads else NO_LOADS
        OUT = np.empty_like(Q)
        args = (tau is not None, BASE, has_base, g[0], g[1], g[2], LD, self._Ck, self._dk, self._C is not None)
        TI, TF = self.compiled.TI, self.compiled.TF
        if rows.batched:
            status = np.empty(B, np.int64)
            if lanes and _lanes_for(TI, has_base, bool(loads), self._C is not None):
                from . import lane_batch as LB       # here: a single state neither imports nor compiles it

                lw = LB.lane_width().width
                LB.fd_lanes(TI, TF, Q, QD, Q if tau is None else TAU, tau is not None, g[0], g[1], g[2], OUT, status,
                            LB.chunks(B, lw), (False,) * lw)
            else:
                MK.fd_batch(TI, TF, Q, QD, Q if tau is None else TAU, *args, OUT, status, MK.chunks(B))
            bad = np.flatnonzero(status >= 0)
            if bad.size:
                b = int(bad[0])
                raise self.not_positive_definite(self._mass_row(Q[b], BASE[b if len(BASE) > 1 else 0], has_base),
                                                 Q[b], row=b)
            return OUT
        if MK.fd_one(TI, TF, Q[0], QD[0], Q[0] if tau is None else TAU[0], args[0], BASE[0], *args[2:], OUT[0]) >= 0:
            raise self.not_positive_definite(self._mass_row(Q[0], BASE[0], has_base), Q[0])
        return OUT[0]

    def _mass_row(self, q, base18, has_base):
        A = np.empty((self.n, self.n))
        MK.terms_one(self.compiled.TI, self.compiled.TF, q, q, False, base18, has_base, 0.0, 0.0, 0.0, NO_LOADS,
                     self._Ck, self._dk, self._C is not None, MK.MASS, A, np.empty(0))
        return A

    def solve_mass_matrix(self, A: np.ndarray, rhs: np.ndarray, *, q=None) -> np.ndarray:
        """``A^{-1} rhs`` by Cholesky; a matrix that is not positive definite raises DynamicsError."""
        try:
            import scipy.linalg     # here: the oracles alone need it (a slow import)

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

    def not_positive_definite(self, A, q, *, row: int | None = None) -> DynamicsError:
        """The :class:`~urdf2links.errors.DynamicsError` for a mass matrix ``A`` (n, n) at ``q`` that is
        not positive definite: its smallest eigenvalue, the coordinates and links it moves, the fix;
        ``row``: the row of a batch where it happened."""
        where = "" if row is None else f"row {row} of the batch: "
        if not np.all(np.isfinite(A)):
            bad = sorted({self._names[i] for i, j in zip(*np.nonzero(~np.isfinite(A)))})
            return DynamicsError(f"{where}mass matrix A has non-finite entries at q={_fmt(q)} in coordinates {bad}",
                                 q=q, coordinates=tuple(bad), row=row)
        w, V = np.linalg.eigh(A)
        vec = V[:, 0]
        big = np.nonzero(np.abs(vec) > 0.1 * np.abs(vec).max())[0]
        names = tuple(self._names[i] for i in big)
        parts = ", ".join(f"{self._names[i]} ({vec[i]:+.2f})" for i in big)
        links = sorted({self.tree.link_names[self.tree.coord_link[self.tree.coordinate_index(nm)]]
                        for nm in names if nm in self.tree.coordinate_names})
        return DynamicsError(
            f"{where}mass matrix A of model {self.name!r} is not positive definite at q={_fmt(q)}: smallest "
            f"eigenvalue {w[0]:.3e} (largest {w[-1]:.3e}); its eigenvector moves coordinates {parts}, "
            f"of links {links}. {_unphysical(self.tree)}A moving link (or subtree) without mass or without inertia "
            "about its joint axis does this; load with inertia='repair' (the command line's --inertia repair) or "
            "give the link a physical inertia.",
            q=q, coordinates=names, row=row,
        )


def _lanes_for(TI, has_base, loads, coupled) -> bool:
    """A batch :func:`urdf2links.dynamics.lane_batch.fd_lanes` computes: a fixed base, no loads, no coupled
    coordinates, no armature (decided without importing the lanes)."""
    from .tree_arrays import N_ARM

    return not has_base and not loads and not coupled and TI[N_ARM] == 0


def _unphysical(tree) -> str:
    """The links whose pseudo-inertia H has a negative eigenvalue (a negative mass or principal moment), with
    their mass, as a sentence (issue 43: the message names the link and the value); empty when none has."""
    bad = []
    for p, name in enumerate(tree.link_names):
        H = np.asarray(tree.H[p], float)
        scale = max(float(np.max(np.abs(H))), np.finfo(float).tiny)
        if float(np.linalg.eigvalsh(H)[0]) < -1e-12 * scale:
            bad.append(f"{name!r} (mass {H[3, 3]:.6g} kg" + (")" if H[3, 3] < 0 else ", a negative principal moment)"))
    return f"Unphysical inertia on link{'s' * (len(bad) > 1)} {', '.join(bad[:6])}: its H is not positive definite. " \
        if bad else ""


def _fmt(q) -> str:
    if q is None:
        return "?"
    return np.array2string(np.asarray(q, float), precision=4, separator=", ", max_line_width=10_000)

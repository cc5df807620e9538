"""The parameters of identification: each link's H, each joint's damping, friction, armature and offset.

``pi`` (p,) is the vector the regressor multiplies, ``Q = Y(q, q', q'') pi`` (docs/equations.md (E89)).
Its layout (:class:`ParameterSet`, built once from a :class:`~urdf2links.dynamics.model.Model`):

- per link that moves (a link hanging from the base without a coordinate above it cannot change any
  generalized force and is left out, listed in ``ParameterSet.fixed_links``; so is, by default, a massless
  frame without a coordinate of its own, ``ParameterSet.frames_left_out``), the 10 entries of its
  pseudo-inertia H (E10) in the link's frame, in the order of :data:`LINK_ENTRIES`::

      Hxx Hyy Hzz Hxy Hxz Hyz   the planar second moments  int x^2 dm, ..., int x y dm, ...
      mx my mz                  the first moments m c (H's last column)
      m                         the mass (H[3, 3])

  named ``<entry>_<link>`` (``m_panda_link3``, ``mx_panda_link3``);
- per armature unit (E49): a coordinate of its own (``armature_<coordinate>``) or the three angles of a
  ball or free link, which share one (named by the first angle coordinate); armature is the tree's, so
  a coupled follower's armature acts through ``C`` (E42);
- per coordinate of the model: ``damping_<c>`` (viscous, ``-b q'``), ``friction_<c>`` (Coulomb,
  regularised like the scenes' contact friction (E79): ``f q' / sqrt(q'^2 + v_s^2)``), ``offset_<c>``
  (a constant torque); these act on the model's coordinates (E42);
- per fixed tendon (E76, ``tendons=`` the ``(name, c (n,))`` of the file's fixed tendons): its damping,
  friction and armature on the length ``l = c . q`` (``tendon_damping_<name>`` ...).

Sign convention: ``Y pi`` is the generalized force the joints apply, ``tau = A q'' + e + G + b q' +
f reg(q') + offset`` (+ the tendons' ``c (b_t l' + f_t reg(l') + a_t l'')``), so every dissipative
parameter of a physical joint is >= 0.

:meth:`ParameterSet.to_model` writes values back into a Model (the links' H, the armature);
:meth:`ParameterSet.joint_values` gives the rest by name. :meth:`ParameterSet.H` gives the (L, 4, 4) of a
vector, for the consistency check (E12: a link is physically consistent exactly when its H is positive
definite).
"""

from __future__ import annotations

import copy
import dataclasses
from dataclasses import dataclass

import numpy as np

from ..dynamics.tree import LinkTree

__all__ = ["ParameterSet", "LINK_ENTRIES", "JOINT_KINDS", "TENDON_KINDS", "DEFAULT_SLIP_SPEED", "link_vector",
           "link_matrix"]

LINK_ENTRIES = ("Hxx", "Hyy", "Hzz", "Hxy", "Hxz", "Hyz", "mx", "my", "mz", "m")
JOINT_KINDS = ("damping", "friction", "offset")
TENDON_KINDS = ("damping", "friction", "armature")
#: the regularisation speed v_s of Coulomb friction, the scenes' contact default (scenes/contact.py, E79)
DEFAULT_SLIP_SPEED = 0.01
_IJ = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))


def link_vector(H) -> np.ndarray:
    """The 10 entries (:data:`LINK_ENTRIES`) of a pseudo-inertia ``H`` (4, 4), or (..., 10) of (..., 4, 4)."""
    H = np.asarray(H, float)
    return np.stack([H[..., i, j] for i, j in _IJ] + [H[..., k, 3] for k in range(3)] + [H[..., 3, 3]], axis=-1)


def link_matrix(v) -> np.ndarray:
    """H (..., 4, 4) of the 10 entries ``v`` (..., 10): the inverse of :func:`link_vector`."""
    v = np.asarray(v, float)
    H = np.zeros(v.shape[:-1] + (4, 4))
    for k, (i, j) in enumerate(_IJ):
        H[..., i, j] = H[..., j, i] = v[..., k]
    for k in range(3):
        H[..., k, 3] = H[..., 3, k] = v[..., 6 + k]
    H[..., 3, 3] = v[..., 9]
    return H


@dataclass(frozen=True, eq=False)
class ParameterSet:
    """The parameter vector's layout for one model (module doc).

    Fields: ``model``; ``names`` (p,); ``values`` (p,) the description's values (damping, friction and
    offsets from ``damping``/``friction`` given to :meth:`from_model`, else 0); ``kind`` (p,) one of
    ``"link"``, ``"armature"``, ``"damping"``, ``"friction"``, ``"offset"``, ``"tendon_damping"``,
    ``"tendon_friction"``, ``"tendon_armature"``; ``owner`` (p,) the link, coordinate or tendon name;
    ``link_col`` (L,) the first column of each tree link's 10 (-1: left out); ``arm_units`` (k, 4) int
    ``(kind, tree coordinate, link, column)`` (kind 0: own, 1: ball, as
    :data:`~urdf2links.dynamics.tree_arrays.ARM_ONE`/``ARM_BALL``); ``joint_cols`` (n, 3) the columns of
    damping, friction, offset per model coordinate (-1: left out); ``tendon_coef`` (t, n),
    ``tendon_cols`` (t, 3), ``tendon_names``; ``slip_speed`` v_s (E79); ``fixed_links`` the links left out (fixed to the base); ``frames_left_out`` the
    massless frames left out (:meth:`from_model`).
    """

    model: object
    names: tuple
    values: np.ndarray
    kind: tuple
    owner: tuple
    link_col: np.ndarray
    arm_units: np.ndarray
    joint_cols: np.ndarray
    tendon_coef: np.ndarray
    tendon_cols: np.ndarray
    tendon_names: tuple
    slip_speed: float
    fixed_links: tuple
    frames_left_out: tuple = ()

    @property
    def p(self) -> int:
        return len(self.names)

    @property
    def n(self) -> int:
        return self.model.n

    def index(self, name: str) -> int:
        try:
            return self.names.index(name)
        except ValueError:
            raise KeyError(f"no parameter named {name!r}; parameters are {list(self.names)[:12]}... "
                           f"({self.p} in all; link entries are {LINK_ENTRIES})") from None

    @classmethod
    def from_model(cls, model, *, joints=("damping", "friction", "armature", "offset"), damping=None, friction=None,
                   offset=None, tendons=(), slip_speed: float = DEFAULT_SLIP_SPEED, frames: bool = False) -> "ParameterSet":
        """The parameters of ``model``: every moving link's 10 H entries, and the joint parameters named in
        ``joints`` (any of damping, friction, armature, offset); ``damping``, ``friction``, ``offset``:
        description values by coordinate name (absent: 0); ``tendons``: ``(name, c (n,), damping,
        friction, armature)`` or objects with ``name``, ``coef`` (and optionally ``damping``) of the
        file's fixed tendons (E76); ``frames``: also the massless links without a coordinate of their own (the
        importer's joint frames, ``<joint>.frame``: they ride rigidly on their parent and hold no mass; left
        out by default, listed in ``frames_left_out``). Raises ValueError naming an unknown coordinate or kind."""
        bad = set(joints) - {"damping", "friction", "armature", "offset"}
        if bad:
            raise ValueError(f"joints= names unknown kinds {sorted(bad)}: use any of damping, friction, armature, offset")
        if not slip_speed > 0:
            raise ValueError(f"slip_speed must be > 0 (the friction's regularisation speed, E79), got {slip_speed!r}")
        tree: LinkTree = model.tree
        names, values, kind, owner = [], [], [], []
        moving = _moving_links(tree)
        own = np.zeros(tree.n_links, bool)
        own[np.asarray(tree.coord_link)] = True
        frame = ~own & ~np.any(np.asarray(tree.H) != 0.0, axis=(1, 2))     # massless, no coordinate: a pure frame
        link_col = np.full(tree.n_links, -1, np.int64)
        for p, ln in enumerate(tree.link_names):
            if not moving[p] or (frame[p] and not frames):
                continue
            link_col[p] = len(names)
            names += [f"{e}_{ln}" for e in LINK_ENTRIES]
            values += list(link_vector(tree.H[p]))
            kind += ["link"] * 10
            owner += [ln] * 10
        units = []
        if "armature" in joints:
            for kd, i, p in _armature_units(tree):
                units.append((kd, i, p, len(names)))
                names.append(f"armature_{tree.coordinate_names[i]}")
                values.append(float(tree.armature[i]))
                kind.append("armature")
                owner.append(tree.coordinate_names[i])
        given = {"damping": dict(damping or {}), "friction": dict(friction or {}), "offset": dict(offset or {})}
        for k, d in given.items():
            unknown = set(d) - set(model.coordinate_names)
            if unknown:
                raise ValueError(f"{k}= names coordinates {sorted(unknown)} the model {model.name!r} does not have; "
                                 f"its coordinates are {list(model.coordinate_names)}")
        joint_cols = np.full((model.n, 3), -1, np.int64)
        for j, cn in enumerate(model.coordinate_names):
            for k, kd in enumerate(JOINT_KINDS):
                if kd in joints:
                    joint_cols[j, k] = len(names)
                    names.append(f"{kd}_{cn}")
                    values.append(float(given[kd].get(cn, 0.0)))
                    kind.append(kd)
                    owner.append(cn)
        coef, tcols, tnames = [], [], []
        for t in tendons:
            tn, c, vals = _tendon(t, model.n)
            coef.append(c)
            tnames.append(tn)
            tcols.append([len(names) + k for k in range(3)])
            for k, kd in enumerate(TENDON_KINDS):
                names.append(f"tendon_{kd}_{tn}")
                values.append(vals[k])
                kind.append(f"tendon_{kd}")
                owner.append(tn)
        if len(set(names)) != len(names):
            dup = sorted({x for x in names if names.count(x) > 1})
            raise ValueError(f"model {model.name!r}: parameter names {dup[:5]} occur twice (a link or coordinate "
                             "name repeats a generated one); rename the link or joint")
        return cls(model=model, names=tuple(names), values=np.array(values, float), kind=tuple(kind),
                   owner=tuple(owner), link_col=link_col, arm_units=np.array(units, np.int64).reshape(-1, 4),
                   joint_cols=joint_cols, tendon_coef=np.array(coef, float).reshape(-1, model.n),
                   tendon_cols=np.array(tcols, np.int64).reshape(-1, 3), tendon_names=tuple(tnames),
                   slip_speed=float(slip_speed),
                   fixed_links=tuple(ln for p, ln in enumerate(tree.link_names) if not moving[p]),
                   frames_left_out=tuple(ln for p, ln in enumerate(tree.link_names)
                                         if moving[p] and frame[p] and not frames))

    # -- values <-> model -----------------------------------------------------------------------------
    def vector(self, values) -> np.ndarray:
        v = np.asarray(values, float)
        if v.shape != (self.p,):
            raise ValueError(f"a parameter vector has {self.p} entries (names: ParameterSet.names); got shape {v.shape}")
        return v

    def H(self, values=None) -> np.ndarray:
        """(L, 4, 4): every tree link's H with the entries of ``values`` (p,) (default: the description's);
        links left out keep the model's."""
        v = self.values if values is None else self.vector(values)
        H = np.array(self.model.tree.H, float)
        for p, c in enumerate(self.link_col):
            if c >= 0:
                H[p] = link_matrix(v[c:c + 10])
        return H

    def armature(self, values=None) -> np.ndarray:
        """(n_tree,): the tree's armature with the units of ``values`` (a ball unit on its three angles)."""
        v = self.values if values is None else self.vector(values)
        arm = np.array(self.model.tree.armature, float)
        tree = self.model.tree
        for kd, i, p, c in self.arm_units:
            if kd == 1:
                arm[tree.coord[p, 3:6]] = v[c]
            else:
                arm[i] = v[c]
        return arm

    def to_model(self, values):
        """A copy of the model with the links' H and the armature of ``values`` (p,): same frames,
        coordinates, coupling, gravity; ``info["identified"]`` says so. Raises ValueError from the tree
        when an armature is negative (the tree holds armature >= 0)."""
        from ..dynamics.model import Model

        v = self.vector(values)
        arm = self.armature(v)
        notes = []
        tiny = (arm < 0) & (arm >= -1e-12 * max(1.0, float(np.abs(arm).max())))    # a fitted zero's rounding
        if np.any(tiny):
            notes.append(f"armature of {[self.model.tree.coordinate_names[i] for i in np.flatnonzero(tiny)]} "
                         f"was negative at rounding level (>= -1e-12): written as 0")
            arm = np.where(tiny, 0.0, arm)
        if np.any(arm < 0):
            bad = [f"{self.names[c]} = {v[c]:.6g}" for _, _, _, c in self.arm_units if v[c] < 0]
            raise ValueError(f"model {self.model.name!r}: a negative armature cannot be written into a model ({', '.join(bad)}); "
                             "the consistent fit (identify(..., consistent=True)) keeps it >= 0")
        tree = dataclasses.replace(self.model.tree, H=self.H(v), armature=arm)
        m = self.model
        info = copy.deepcopy(m.info)
        info["identified"] = True
        if notes:
            info["identification_notes"] = notes
        coupling = None if m.coupling is None else (*m.coupling, m.coordinate_names)
        return Model(tree, gravity=m.gravity_vector, coupling=coupling, name=m.name, source=m.source, audit=m.audit,
                     info=info)

    def joint_values(self, values) -> dict:
        """``{kind: {coordinate or tendon: value}}`` of the joint and tendon parameters of ``values``."""
        v = self.vector(values)
        out: dict = {}
        for k, (kd, ow) in enumerate(zip(self.kind, self.owner)):
            if kd != "link":
                out.setdefault(kd, {})[ow] = float(v[k])
        return out

    def link_parameters(self, link: str) -> slice:
        """The columns of ``link``'s 10 entries. KeyError naming the links when it has none."""
        p = self.model.tree.link_index(link)
        c = int(self.link_col[p])
        if c < 0:
            raise KeyError(f"link {link!r} has no parameters: it is fixed to the base (no coordinate above it)")
        return slice(c, c + 10)


def _moving_links(tree) -> np.ndarray:
    """(L,) bool: a coordinate's link is the link or one of its ancestors."""
    has = np.zeros(tree.n_links, bool)
    has[np.asarray(tree.coord_link)] = True
    return (np.asarray(tree.ancestor) & has[None, :]).any(axis=1)


def _armature_units(tree):
    """``(kind, coordinate, link)`` of every armature unit (E49): a ball or free link's three angles one
    (kind 1, its first angle), every other coordinate one (kind 0)."""
    units, done = [], set()
    for p in range(tree.n_links):
        tri = tree.coord[p, 3:6]
        if np.all(tri >= 0):
            done.update(int(i) for i in tri)
            units.append((1, int(tri[0]), p))
    for i in range(tree.n):
        if i not in done:
            units.append((0, i, int(tree.coord_link[i])))
    return sorted(units, key=lambda u: u[1])


def _tendon(t, n):
    if isinstance(t, tuple):
        name, c, *rest = t
        vals = [float(x) for x in rest] + [0.0] * (3 - len(rest))
    else:
        name, c = t.name, t.coef
        vals = [float(getattr(t, "damping", 0.0)), 0.0, 0.0]
    c = np.asarray(c, float)
    if c.shape != (n,):
        raise ValueError(f"tendon {name!r}: its coefficients must have shape ({n},) (one per model coordinate), "
                         f"got {c.shape}")
    return str(name), c, vals

"""The tree of links of the trace method: the project's form of a robot, frozen and array-backed.

Per link ``p`` (links in topological order, parents first, docs/equations.md (E5)):

- ``parent[p]``: index of the preceding link ``s`` or ``-1`` when ``p`` hangs from the base {A};
- ``params[p]`` (6,): the constants ``x, y, z, phi_x, phi_y, phi_z`` of ``T~ = T1..T6`` (E3);
  where a slot is a generalized coordinate, the slot's value is ``params[p, k] + q[coord[p, k]]``
  (so ``params`` holds the coordinate's offset, usually 0);
- ``coord[p]`` (6,): index into ``q`` of the coordinate in each slot, or ``-1`` for a constant;
- ``H[p]`` (4, 4): the pseudo-inertia matrix (E10) in the link's frame; all zeros for a
  massless link (a pure frame);
- ``armature`` (n,): the rotor inertia reflected to each coordinate (MJCF ``armature``, E49): it adds
  ``0.5 a_k q_k'^2`` to the kinetic energy, except on a link whose three angle slots are all
  coordinates (a ball or a free body), whose three angles share one armature ``a`` acting on the
  link's angular velocity relative to its parent: ``0.5 a |omega|^2`` (MuJoCo's armature on the
  three dofs of a ball joint).

Coordinates are numbered link by link in tree order and, inside a link, in slot order
``x, y, z, phi_x, phi_y, phi_z``, which is the order of (E5).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Mapping, Sequence

import numpy as np

from .transforms import PARAMETERS

__all__ = ["LinkSpec", "LinkTree", "build_tree", "pseudo_inertia_from"]


def pseudo_inertia_from(mass: float, com=(0.0, 0.0, 0.0), inertia=None) -> np.ndarray:
    """H (4, 4) of (E10) from a mass, a COM (3,) and the inertia tensor (3, 3) about the COM
    in the link's axes (URDF convention: ``I = [[ixx, ixy, ixz], ...]``, ``ixy = -integral(x y dm)``)."""
    from .inertia import pseudo_inertia

    I = np.zeros((3, 3)) if inertia is None else np.asarray(inertia, float)
    return pseudo_inertia(float(mass), np.asarray(com, float), I)


@dataclass(frozen=True)
class LinkSpec:
    """One link as written in code: name, parent name (None: the base {A}), the six constants
    ``params`` (6,) of (E3), ``coordinates`` mapping a slot name (``"x"`` ... ``"phi_z"``) to the
    name of the generalized coordinate in that slot, ``H`` (4, 4) (None: massless), and
    ``armature`` mapping a coordinate slot to its armature (E49; absent slots: 0)."""

    name: str
    parent: str | None = None
    params: Sequence[float] = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    coordinates: Mapping[str, str] = field(default_factory=dict)
    H: np.ndarray | None = None
    armature: Mapping[str, float] = field(default_factory=dict)


def _readonly(a: np.ndarray) -> np.ndarray:
    a = np.ascontiguousarray(a)
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False)
class LinkTree:
    """Frozen array-backed tree of ``L`` links and ``n`` generalized coordinates (see module doc).

    ``armature`` (n,) (E49), zeros when not given. Derived arrays: ``coord_link`` (n,) the link of
    each coordinate, ``coord_slot`` (n,) its slot 0..5, ``ancestor`` (L, L) bool, ``ancestor[p, a]`` when ``a`` is ``p`` or precedes it
    (``a`` in ``N_p`` of (E5)), ``children`` tuple of tuples.
    """

    link_names: tuple[str, ...]
    parent: np.ndarray
    params: np.ndarray
    coord: np.ndarray
    H: np.ndarray
    coordinate_names: tuple[str, ...]
    armature: np.ndarray | None = None
    coord_link: np.ndarray = field(init=False)
    coord_slot: np.ndarray = field(init=False)
    ancestor: np.ndarray = field(init=False)
    children: tuple[tuple[int, ...], ...] = field(init=False)

    def __post_init__(self):
        L = len(self.link_names)
        parent = np.asarray(self.parent, dtype=np.int64)
        params = np.asarray(self.params, dtype=float)
        coord = np.asarray(self.coord, dtype=np.int64)
        H = np.asarray(self.H, dtype=float)
        if parent.shape != (L,) or params.shape != (L, 6) or coord.shape != (L, 6) or H.shape != (L, 4, 4):
            raise ValueError(
                f"LinkTree arrays do not match {L} links: parent {parent.shape}, params {params.shape}, "
                f"coord {coord.shape}, H {H.shape}"
            )
        for p in range(L):
            if not -1 <= parent[p] < p:
                raise ValueError(
                    f"link {self.link_names[p]!r}: parent index {parent[p]} must precede it (links in tree order)"
                )
        n = len(self.coordinate_names)
        used = coord[coord >= 0]
        if sorted(used.tolist()) != list(range(n)):
            raise ValueError(f"coord must use each of the {n} coordinate indices exactly once; got {sorted(used.tolist())}")
        coord_link = np.empty(n, dtype=np.int64)
        coord_slot = np.empty(n, dtype=np.int64)
        for p, k in zip(*np.nonzero(coord >= 0)):
            coord_link[coord[p, k]] = p
            coord_slot[coord[p, k]] = k
        ancestor = np.zeros((L, L), dtype=bool)
        for p in range(L):
            ancestor[p, p] = True
            if parent[p] >= 0:
                ancestor[p] |= ancestor[parent[p]]
        children = tuple(tuple(int(c) for c in np.nonzero(parent == p)[0]) for p in range(L))
        armature = np.zeros(n) if self.armature is None else np.array(self.armature, dtype=float)
        if armature.shape != (n,) or not np.all(np.isfinite(armature)) or np.any(armature < 0):
            raise ValueError(f"armature must be {n} finite numbers >= 0 (one per coordinate), got {self.armature!r}")
        for p in range(L):
            tri = coord[p, 3:6]
            if np.all(tri >= 0) and len(set(armature[tri].tolist())) > 1:
                raise ValueError(f"link {self.link_names[p]!r}: its three angle coordinates share one armature (it acts "
                                 f"on the link's angular velocity, E49); got {armature[tri].tolist()}")
        for name, value in (
            ("parent", parent), ("params", params), ("coord", coord), ("H", H), ("armature", armature),
            ("coord_link", coord_link), ("coord_slot", coord_slot), ("ancestor", ancestor),
        ):
            object.__setattr__(self, name, _readonly(value))
        object.__setattr__(self, "children", children)

    @property
    def n(self) -> int:
        return len(self.coordinate_names)

    @property
    def n_links(self) -> int:
        return len(self.link_names)

    @property
    def has_armature(self) -> bool:
        return bool(np.any(self.armature != 0.0))

    @property
    def mass(self) -> np.ndarray:
        """(L,) link masses, ``H[:, 3, 3]``."""
        return self.H[:, 3, 3].copy()

    @property
    def com(self) -> np.ndarray:
        """(L, 3) COM of each link in its own frame, ``H e4 / m`` (E21); zeros for a massless link."""
        m = self.H[:, 3, 3]
        safe = np.where(m > 0, m, 1.0)
        return np.where((m > 0)[:, None], self.H[:, :3, 3] / safe[:, None], 0.0)

    def link_index(self, name: str) -> int:
        try:
            return self.link_names.index(name)
        except ValueError:
            raise KeyError(f"no link named {name!r}; links are {list(self.link_names)}") from None

    def coordinate_index(self, name: str) -> int:
        try:
            return self.coordinate_names.index(name)
        except ValueError:
            raise KeyError(f"no coordinate named {name!r}; coordinates are {list(self.coordinate_names)}") from None

    def coordinate_ancestor(self) -> np.ndarray:
        """(n, n) bool: ``[i, l]`` when the link of coordinate ``l`` is the link of ``i`` or precedes it."""
        return self.ancestor[np.ix_(self.coord_link, self.coord_link)]


def build_tree(links: Sequence[LinkSpec]) -> LinkTree:
    """A :class:`LinkTree` from link specs in tree order (each parent named before its children)."""
    names: list[str] = []
    parent, params, coord, H, coordinate_names, armature = [], [], [], [], [], []
    for spec in links:
        if spec.name in names:
            raise ValueError(f"duplicate link name {spec.name!r}")
        if spec.parent is None:
            parent.append(-1)
        elif spec.parent in names:
            parent.append(names.index(spec.parent))
        else:
            raise ValueError(
                f"link {spec.name!r}: parent {spec.parent!r} is not defined before it; known links {names}"
            )
        names.append(spec.name)
        p = np.asarray(spec.params, dtype=float)
        if p.shape != (6,) or not np.all(np.isfinite(p)):
            raise ValueError(f"link {spec.name!r}: params must be 6 finite numbers, got {spec.params!r}")
        params.append(p)
        c = np.full(6, -1, dtype=np.int64)
        for slot, cname in spec.coordinates.items():
            if slot not in PARAMETERS:
                raise ValueError(f"link {spec.name!r}: unknown slot {slot!r}; slots are {PARAMETERS}")
        for slot in spec.armature:
            if slot not in spec.coordinates:
                raise ValueError(f"link {spec.name!r}: armature on slot {slot!r}, which is not a coordinate of it")
        for k, slot in enumerate(PARAMETERS):
            if slot in spec.coordinates:
                cname = spec.coordinates[slot]
                if cname in coordinate_names:
                    raise ValueError(f"link {spec.name!r}: coordinate name {cname!r} used twice")
                c[k] = len(coordinate_names)
                coordinate_names.append(cname)
                armature.append(float(spec.armature.get(slot, 0.0)))
        coord.append(c)
        h = np.zeros((4, 4)) if spec.H is None else np.asarray(spec.H, dtype=float)
        if h.shape != (4, 4) or not np.all(np.isfinite(h)) or not np.allclose(h, h.T, rtol=0, atol=1e-12 * max(1.0, np.abs(h).max())):
            raise ValueError(f"link {spec.name!r}: H must be a finite symmetric (4, 4) matrix")
        H.append(h)
    if not names:
        raise ValueError("a tree needs at least one link")
    return LinkTree(
        link_names=tuple(names),
        parent=np.array(parent),
        params=np.array(params),
        coord=np.array(coord),
        H=np.array(H),
        coordinate_names=tuple(coordinate_names),
        armature=np.array(armature, dtype=float),
    )

"""URDF -> tree of links: the importer, with the inertia audit.

Data flow: :func:`urdf2links.parsers.urdf.parse_urdf` (validated description) -> this module (frames,
coordinates, H, audit) -> :class:`urdf2links.dynamics.tree.LinkTree` -> :class:`urdf2links.dynamics.model.Model`.

Frames (docs/equations.md (E9), (E11)). Every URDF link ``C`` lives in some tree link ``t`` with a constant transform ``X``
(``r_t = X r_C``). A joint with origin ``O`` (4, 4) and unit axis ``u`` becomes:

- revolute/continuous: one tree link whose ``T~`` has translation and rotation of ``M Ra`` (``M = X_parent O``,
  ``Ra e_z = u``, :func:`~urdf2links.dynamics.rotations.axis_alignment`) and the coordinate in slot ``phi_z``;
  the URDF child then sits at ``X = Ra^T`` in it. Exact: ``M Ra Rz(q) Ra^T = M Rot(u, q)``, so the
  coordinate equals the URDF joint position (same zero, same sign, offset 0);
- prismatic: the same with slot ``z``, after a massless constant frame ``<joint>.frame`` carrying
  ``M Ra`` (translations of ``T~`` are along the parent's axes) unless ``M Ra`` has no rotation;
- fixed: no tree link; the child's H is added to the parent's (``H += X H_C X^T``, exact) and its
  children re-attached through ``X``;
- floating (six coordinates ``<joint>.x ... <joint>.phi_z``), spherical (three, the ZYX angles
  ``<joint>.phi_x``, ``<joint>.phi_y``, ``<joint>.phi_z``: ``R = Rx Ry Rz`` (E3) relative to the joint
  frame; re-charted near ``phi_y = +-pi/2`` like a floating link, (E45), :mod:`urdf2links.integration.charts`) and planar
  (``<joint>.x``, ``<joint>.y``, ``<joint>.phi_z`` in the plane normal to the axis): after a constant
  frame when needed.

``model.info`` holds ``notes`` (the reader's and the importer's: what was tolerated, folded, not
used), ``joints`` (one dict per URDF joint: type, coordinates, limits, damping, friction) for
``inspect``, scenes (URDF dampers) and limit checks, ``coordinates``, ``frame_of``, ``repaired_H``.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np

from ..dynamics.inertia import audit_pseudo_inertia, inertial_from_pseudo, nearest_consistent, pseudo_inertia
from ..dynamics.model import Model
from ..dynamics.rotations import axis_alignment, homogeneous, matrix_to_xyz_angles, rpy_to_matrix
from ..dynamics.transforms import PARAMETERS
from ..dynamics.tree import LinkSpec, build_tree
from ..errors import InertiaError, MeshError, URDFError, URDFStructureError, URDFValueError
from .description import RobotDescription
from .geometry_inertia import combined_geometry_inertia
from .urdf import parse_urdf

__all__ = ["load_urdf", "load_urdf_string", "urdf_link_poses", "AuditRecord", "INERTIA_POLICIES", "MIMIC_POLICIES"]

from ..ranges import INERTIA_POLICIES, MIMIC_POLICIES  # noqa: E402  (the options, shared with the command line)
_I4 = np.eye(4)


@dataclass(frozen=True)
class AuditRecord:
    """One finding of the inertia audit on a URDF link.

    ``kind``: ``nan``, ``non_positive_mass``, ``negative_principal_moment``, ``triangle_inequality``,
    ``not_positive_definite`` (the link's own H), ``massless_moving_subtree`` or ``zero_axis_inertia``
    (a joint that moves nothing with inertia: ``A`` would be singular). ``action``: ``"reported"``
    or ``"repaired"``; ``fix`` says what was changed, ``values`` holds the numbers.
    """

    link: str
    kind: str
    message: str
    action: str = "reported"
    fix: str = ""
    values: dict = field(default_factory=dict)

    def __str__(self) -> str:
        return self.message + (f" -> repaired: {self.fix}" if self.action == "repaired" else "")


def load_urdf(source, *, floating_base: bool = False, inertia: str = "audit", mimic: str = "independent",
              package_dirs=(), density: float = 1000.0, strict: bool = False, xacro_args=None) -> Model:
    """Load a URDF file (or URDF text, or a xacro file) as a :class:`~urdf2links.dynamics.model.Model`.

    Parameters
    ----------
    source : path to a ``.urdf`` file, a ``.xacro`` file (expanded with the optional ``xacro``
        package: ``pip install "urdf2links[xacro]"``), or the URDF text itself.
    floating_base : give the root link six coordinates ``<root>.x ... <root>.phi_z`` (E3).
    inertia : ``"audit"`` (report findings in ``model.audit`` and warn once), ``"strict"`` (raise
        :class:`~urdf2links.errors.InertiaError` on any finding) or ``"repair"`` (fix every finding:
        from the link's geometry when it has some, otherwise the smallest change that makes H
        positive definite; each fix recorded in ``model.audit``).
    mimic : ``"independent"`` (mimic joints keep their own coordinate, as MuJoCo and Pinocchio load
        them) or ``"coupled"`` (``q_follower = multiplier * q_leader + offset``; one coordinate fewer).
    package_dirs : folders searched for ``package://`` meshes, after the URDF's folder and its ancestors.
    density : kg/m^3, for inertia computed from geometry when a link has no usable mass.
    strict : refuse what the default reading tolerates like urdfdom, each with a note in
        ``model.info["notes"]`` (:mod:`urdf2links.parsers.urdf`; docs/importing.md).
    xacro_args : ``{name: value}`` for a ``.xacro`` source (xacro's ``name:=value`` arguments).
    """
    if inertia not in INERTIA_POLICIES:
        raise ValueError(f"inertia must be one of {INERTIA_POLICIES}, got {inertia!r}")
    if mimic not in MIMIC_POLICIES:
        raise ValueError(f"mimic must be one of {MIMIC_POLICIES}, got {mimic!r}")
    if not (np.isfinite(density) and density > 0):
        raise ValueError(f"density must be a positive number of kg/m^3, got {density!r}")
    desc = parse_urdf(source, package_dirs=package_dirs, strict=strict, xacro_args=xacro_args)
    return _Importer(desc, floating_base=floating_base, policy=inertia, mimic=mimic, density=density).model()


def load_urdf_string(text: str, **options) -> Model:
    """:func:`load_urdf` for URDF text (relative mesh paths resolve against ``package_dirs`` only)."""
    if not isinstance(text, str) or not text.lstrip().startswith("<"):
        raise URDFValueError("load_urdf_string needs URDF text starting with '<'; for a file use load_urdf(path)")
    return load_urdf(text, **options)


class _Importer:
    def __init__(self, desc: RobotDescription, *, floating_base, policy, mimic, density):
        self.desc = desc
        self.floating_base = floating_base
        self.policy = policy
        self.mimic = mimic
        self.density = density
        self.records: list[AuditRecord] = []
        self.notes: list[str] = list(desc.notes)
        self.H_link = {name: self._inertial_H(link) for name, link in desc.links.items()}
        # The scale of repair spheres, fixed before any repair (so that repairs do not shrink it).
        masses = [float(h[3, 3]) for h in self.H_link.values() if h[3, 3] > 0]
        self.small_mass = 1e-3 * (min(masses) if masses else 1.0)

    # -- inertia ------------------------------------------------------------------------------------
    @staticmethod
    def _inertial_H(link) -> np.ndarray:
        if link.inertial is None:
            return np.zeros((4, 4))
        i = link.inertial
        return pseudo_inertia(i.mass, i.origin.xyz, i.inertia, rotation=rpy_to_matrix(i.origin.rpy))

    def _audit_links(self):
        for name, link in self.desc.links.items():
            if link.inertial is None:
                continue
            H = self.H_link[name]
            if H[3, 3] == 0.0 and not np.any(H):
                continue  # an explicit zero inertial is a massless frame
            for f in audit_pseudo_inertia(H, link=name):
                if f.kind == "not_positive_definite" and any(
                        r.link == name and r.kind in ("triangle_inequality", "negative_principal_moment", "non_positive_mass")
                        for r in self.records):
                    continue  # same defect, already reported in its own terms
                self.records.append(AuditRecord(name, f.kind, f"{self.desc.source}: {f.message}", values=f.values))

    def _geometry_H(self, name, *, mass):
        link = self.desc.links[name]
        geoms = link.collisions or link.visuals
        if not geoms:
            return None, "no geometry"
        try:
            gi = combined_geometry_inertia(geoms, mass=mass, density=self.density)
        except MeshError as err:
            return None, f"geometry unusable ({err})"
        except URDFError as err:
            return None, f"geometry unusable ({err})"
        which = "collision" if link.collisions else "visual"
        return gi.H, f"inertia from {which} geometry ({gi.method}; {gi.note})"

    def _repair_from_geometry(self, rec: AuditRecord, name: str) -> tuple[AuditRecord | None, str]:
        """First choice of every repair: the link's own geometry (keeping its mass when it has one),
        if that gives a consistent inertia. Returns the repaired record (or None) and what was tried."""
        mass = float(self.H_link[name][3, 3])
        Hg, how = self._geometry_H(name, mass=mass if mass > 0 else None)
        if Hg is not None and not audit_pseudo_inertia(Hg, link=name):
            self.H_link[name] = Hg
            return _replace(rec, how), how
        return None, how

    def _repair_link(self, rec: AuditRecord) -> AuditRecord:
        name = rec.link
        done, how = self._repair_from_geometry(rec, name)
        if done is not None:
            return done
        H = self.H_link[name]
        mass = float(H[3, 3])
        try:
            fixed = nearest_consistent(H, link=name)
        except InertiaError:
            fixed = None
        if fixed is not None and not audit_pseudo_inertia(fixed, link=name):
            self.H_link[name] = fixed
            m, c, I = inertial_from_pseudo(fixed)
            return _replace(rec, f"principal moments raised to the nearest consistent values, mass {m:.6g} and COM kept "
                                 f"(new diagonal {np.diag(I).round(12).tolist()}); {how}")
        # No size to keep (a point mass, or rounding noise as its tensor), or no mass: a small sphere
        # with the link's own mass and COM when it has a mass.
        sphere = self._small_body(H)
        self.H_link[name] = sphere
        return _replace(rec, f"replaced by a sphere of radius 0.01 m (mass {sphere[3, 3]:.3g} kg"
                             f"{', the link mass, COM kept' if mass > 0 else ''}) ; {how}")

    def _small_body(self, old: np.ndarray) -> np.ndarray:
        """A sphere of radius 0.01 m at the COM of ``old`` (origin if massless), with the mass of
        ``old`` when it has one, else :attr:`small_mass`."""
        m = float(old[3, 3]) if old[3, 3] > 0 else self.small_mass
        com = old[:3, 3] / old[3, 3] if old[3, 3] > 0 else np.zeros(3)
        return pseudo_inertia(m, com, np.eye(3) * 0.4 * m * 0.01**2)

    # -- frames and coordinates ---------------------------------------------------------------------
    def _build(self):
        desc = self.desc
        specs: list[LinkSpec] = []
        H_tree: list[np.ndarray] = []
        self.frame_of = {}          # URDF link -> (tree link index, X (4, 4))
        self.coord_info = []        # one dict per tree coordinate
        root = desc.root
        if self.floating_base:
            specs.append(LinkSpec(root, None, coordinates={s: f"{root}.{s}" for s in PARAMETERS}))
            self.coord_info += [dict(name=f"{root}.{s}", joint=None, type="floating", slot=s, sign=1.0, offset=0.0)
                                for s in PARAMETERS]
        else:
            specs.append(LinkSpec(root, None))
        H_tree.append(np.zeros((4, 4)))
        self.frame_of[root] = (0, _I4)

        def add(spec):
            specs.append(spec)
            H_tree.append(np.zeros((4, 4)))
            return len(specs) - 1

        for j in desc.joints:
            t_parent, X_parent = self.frame_of[j.parent]
            O = homogeneous(rpy_to_matrix(j.origin.rpy), np.asarray(j.origin.xyz, float))
            M = X_parent @ O
            parent_name = specs[t_parent].name
            if j.type == "fixed":
                self.frame_of[j.child] = (t_parent, M)
                self.notes.append(f"fixed joint {j.name!r}: link {j.child!r} folded into {parent_name!r}")
                continue
            if j.type in ("floating", "spherical"):
                u = np.array([0.0, 0.0, 1.0])
            else:
                u = np.asarray(j.axis, float)
                norm = float(np.linalg.norm(u))
                if abs(norm - 1.0) > 1e-9:
                    self.notes.append(f"joint {j.name!r}: axis {u.tolist()} normalized (length {norm:.6g})")
            Ra = homogeneous(axis_alignment(u), np.zeros(3))
            F = M @ Ra
            slots = {"revolute": ("phi_z",), "continuous": ("phi_z",), "prismatic": ("z",),
                     "planar": ("x", "y", "phi_z"), "floating": PARAMETERS,
                     "spherical": ("phi_x", "phi_y", "phi_z")}[j.type]
            names = (j.name,) if len(slots) == 1 else tuple(f"{j.name}.{s}" for s in slots)
            rotation_only = slots == ("phi_z",)
            if rotation_only or np.array_equal(F[:3, :3], np.eye(3)):
                params = _params(F)
                if not rotation_only:
                    params[3:] = 0.0
            else:
                frame = add(LinkSpec(f"{j.name}.frame", parent_name, params=_params(F)))
                why = ("its coordinates fill the angle slots, so the joint frame's constant rotation needs a link of "
                       "its own" if j.type == "spherical" else "so that its translation is along a link axis")
                self.notes.append(f"joint {j.name!r} ({j.type}): massless frame {j.name + '.frame'!r} added {why}")
                parent_name = specs[frame].name
                params = np.zeros(6)
            t = add(LinkSpec(j.child, parent_name, params=params, coordinates=dict(zip(slots, names))))
            self.frame_of[j.child] = (t, Ra.T)
            for s, nm in zip(slots, names):
                self.coord_info.append(dict(name=nm, joint=j.name, type=j.type, slot=s, sign=1.0,
                                            offset=0.0, axis=(u / np.linalg.norm(u)).tolist()))
        for name, (t, X) in self.frame_of.items():
            H_tree[t] = H_tree[t] + X @ self.H_link[name] @ X.T
        specs = [LinkSpec(s.name, s.parent, s.params, s.coordinates, 0.5 * (H + H.T))
                 for s, H in zip(specs, H_tree)]
        try:
            return build_tree(specs)
        except ValueError as err:   # a tree the description's checks let through: say which file
            raise URDFValueError(f"{self.desc.source}: the tree of links cannot be built: {err}; check the "
                                 "file's <inertial> and <origin> values") from err

    def _coupling(self, tree):
        if self.mimic == "independent":
            return None
        joints = {j.name: j for j in self.desc.joints}
        followers = {}
        for j in self.desc.joints:
            if j.mimic is None:
                continue
            if j.mimic.joint not in joints or j.mimic.joint == j.name:
                raise URDFStructureError(f"{self.desc.source}: joint {j.name!r} <mimic joint=\"{j.mimic.joint}\">: "
                                         + ("it mimics itself" if j.mimic.joint == j.name else
                                            f"there is no joint named {j.mimic.joint!r}")
                                         + "; mimic='coupled' needs the joint to follow: correct <mimic>, or load "
                                           "with mimic='independent' (then <mimic> has no effect)")
            leader = joints[j.mimic.joint]
            odd = [jj for jj in (j, leader) if jj.type not in ("revolute", "continuous", "prismatic")]
            if odd:
                # Real files keep <mimic> on joints they have made fixed (Talos' reduced grippers).
                self.notes.append(f"mimic of joint {j.name!r} on {leader.name!r} ignored: joint {odd[0].name!r} is "
                                  f"{odd[0].type}, only one-coordinate joints can be coupled")
                continue
            followers[j.name] = (leader.name, j.mimic.multiplier, j.mimic.offset)
        if not followers:
            return None

        def resolve(name, seen=()):
            if name not in followers:
                return name, 1.0, 0.0
            if name in seen:
                raise URDFValueError(f"{self.desc.source}: mimic joints form a cycle through {name!r}")
            leader, k, off = followers[name]
            root, k2, off2 = resolve(leader, seen + (name,))
            return root, k * k2, k * off2 + off

        names = [nm for nm in tree.coordinate_names if nm not in followers]
        C = np.zeros((tree.n, len(names)))
        d = np.zeros(tree.n)
        for i, nm in enumerate(tree.coordinate_names):
            leader, k, off = resolve(nm)
            C[i, names.index(leader)] = k
            d[i] = off
            if nm in followers:
                self.notes.append(f"mimic joint {nm!r} coupled: q = {k:g} * {leader} + {off:g}")
        return C, d, tuple(names)

    def _joint_findings(self, tree) -> list[AuditRecord]:
        """Moving joints that move no mass or no inertia: ``A_ii`` ~ 0 at two configurations.

        "~ 0" is ``A_ii <= 1e-10 max_k A_kk``: below that, the coordinate's acceleration carries a
        condition number above 1e10 (ten digits lost), which no real link should cause.
        """
        from ..dynamics.oracles.recursive import RecursivePlan, numpy_mass_matrix

        # the numpy oracle's A: a few milliseconds for a humanoid, and loading a robot compiles nothing (the
        # compiled form cost a first `simulate` a second of compilation for this check alone, issue 32)
        probe = RecursivePlan(tree)
        rng = np.random.default_rng(0)
        diag = np.maximum(np.abs(np.diag(numpy_mass_matrix(probe, np.zeros(tree.n)))),
                          np.abs(np.diag(numpy_mass_matrix(probe, rng.uniform(-1, 1, tree.n)))))
        scale = float(diag.max()) if diag.size else 0.0
        out = []
        mass_c = _subtree_mass(tree)
        for i, nm in enumerate(tree.coordinate_names):
            if diag[i] > 1e-10 * scale and scale > 0:
                continue
            link = tree.link_names[tree.coord_link[i]]
            if mass_c[tree.coord_link[i]] <= 0.0:
                kind, what = "massless_moving_subtree", "moves no mass (no link after it has mass)"
            else:
                kind, what = "zero_axis_inertia", (f"moves (almost) no inertia about its axis: A_ii = {diag[i]:.3g}, "
                                                  f"{diag[i] / scale:.2g} of the largest")
            out.append(AuditRecord(link, kind, f"{self.desc.source}: coordinate {nm!r} of link {link!r} {what}; "
                                   f"A is singular", values={"coordinate": nm, "A_ii": float(diag[i])}))
        return out

    def model(self) -> Model:
        self._audit_links()
        if self.policy == "repair":
            self.records = [self._repair_link(r) for r in self.records]
        tree = self._build()
        for _ in range(3):
            joint_records = self._joint_findings(tree)
            if self.policy != "repair" or not joint_records:
                break
            for r in joint_records:
                self.records.append(self._repair_joint(r))
            tree = self._build()
        if self.policy != "repair":
            self.records += joint_records
        else:
            left = self._joint_findings(tree)
            if left:  # never silently: what three rounds of repair did not fix stays a finding
                self.records += [AuditRecord(r.link, r.kind, r.message + " (not repaired after 3 rounds)", "reported",
                                             values=r.values) for r in left]
                warnings.warn(f"{self.desc.source}: {len(left)} finding(s) remain after repair: "
                              + "; ".join(r.message for r in left), UserWarning, stacklevel=3)
        if self.records and self.policy == "strict":
            raise InertiaError(f"{self.desc.source}: {len(self.records)} inertia finding(s) (inertia='strict'):\n  "
                               + "\n  ".join(r.message for r in self.records)
                               + "\nFix the <inertial> elements, or load with inertia='repair'.")
        if self.records and self.policy == "audit":
            warnings.warn(f"{self.desc.source}: {len(self.records)} inertia finding(s) in robot {self.desc.name!r} "
                          f"(links {sorted({r.link for r in self.records})}); see model.audit, or load with "
                          f"inertia='repair'", UserWarning, stacklevel=3)
        coupling = self._coupling(tree)
        repaired = sorted({r.link for r in self.records if r.action == "repaired"})
        info = {"coordinates": self.coord_info, "notes": self.notes, "joints": self._joint_table(),
                # issue 42: every mesh whose file was not found (description file, link, element, paths looked for)
                "missing_files": [g.missing for link in self.desc.links.values()
                                  for g in (*link.collisions, *link.visuals) if g.missing],
                # URDF-link inertias after repair (link frame H (4, 4)), to write a repaired URDF for other tools
                "repaired_H": {k: self.H_link[k].tolist() for k in repaired if k in self.H_link},
                "frame_of": {
            k: (tree.link_names[t], X.tolist()) for k, (t, X) in self.frame_of.items()},
                # each URDF link's mass and centre of mass (link frame), for gravcomp (MuJoCo's body gravcomp)
                "body_mass_com": {k: (float(H[3, 3]), (H[:3, 3] / H[3, 3] if H[3, 3] > 0 else np.zeros(3)).tolist())
                                  for k, H in self.H_link.items()},
                # issue 37: every <collision> sphere (link, centre in the link frame, radius), for [[contact]]
                "collision_spheres": [(name, np.asarray(g.origin.xyz, float).tolist(), float(g.radius))
                                      for name, link in self.desc.links.items() for g in link.collisions
                                      if g.kind == "sphere" and g.radius]}
        return Model(tree, coupling=coupling, name=self.desc.name, source=self.desc.source,
                     audit=self.records, info=info)

    def _joint_table(self) -> list[dict]:
        """One dict per URDF joint: name, type, coordinates, limits, damping, friction, mimic."""
        coords: dict[str, list[str]] = {}
        for c in self.coord_info:
            if c["joint"] is not None:
                coords.setdefault(c["joint"], []).append(c["name"])
        return [{"name": j.name, "type": j.type, "coordinates": coords.get(j.name, []),
                 "lower": j.limit_lower, "upper": j.limit_upper, "effort": j.limit_effort,
                 "velocity": j.limit_velocity, "damping": j.damping, "friction": j.friction,
                 "mimic": None if j.mimic is None else j.mimic.joint,
                 "mimic_multiplier": None if j.mimic is None else j.mimic.multiplier,     # issue 36: mimic as
                 "mimic_offset": None if j.mimic is None else j.mimic.offset} for j in self.desc.joints]  # a constraint

    def _repair_joint(self, rec: AuditRecord) -> AuditRecord:
        # Joint findings are on tree links that carry coordinates; those are named after the URDF child.
        name = rec.link
        done, how = self._repair_from_geometry(rec, name)
        if done is not None:
            return done
        sphere = self._small_body(np.zeros((4, 4)))
        self.H_link[name] = self.H_link[name] + sphere
        return _replace(rec, f"a sphere of radius 0.01 m and mass {sphere[3, 3]:.3g} kg added at the origin of "
                             f"link {name!r}; {how}")


def urdf_link_poses(model: Model, q, **kw) -> dict[str, np.ndarray]:
    """{0}-pose (4, 4) of every URDF link of an imported model at ``q`` (keyword arguments as
    :meth:`Model.link_poses`): the pose of its tree link times its constant placement ``X``."""
    T = model.link_poses(q, **kw)
    index = {name: i for i, name in enumerate(model.link_names)}
    return {name: T[index[t]] @ np.asarray(X) for name, (t, X) in model.info["frame_of"].items()}


def _replace(rec: AuditRecord, fix: str) -> AuditRecord:
    return AuditRecord(rec.link, rec.kind, rec.message, "repaired", fix, rec.values)


def _params(F) -> np.ndarray:
    """The six parameters (E3) of a constant transform F (4, 4): its origin and ZYX angles (E7)."""
    return np.r_[F[:3, 3], matrix_to_xyz_angles(F[:3, :3])]


def _subtree_mass(tree) -> np.ndarray:
    m = tree.H[:, 3, 3].copy()
    for p in range(tree.n_links - 1, 0, -1):
        if tree.parent[p] >= 0:
            m[tree.parent[p]] += m[p]
    return m

"""Route 1's model as MuJoCo compiled it: the project's coordinates, links and base in MuJoCo's arrays.

:class:`MjcfModel` is what :func:`urdf2links.compare.mujoco_side.mjcf.mjcf_from_model` returns: the MJCF text,
MuJoCo's ``MjModel`` and the maps between them and the project's tree (``qpos_index`` / ``dof_index`` of each
coordinate, the base's dofs, the body of each link: :mod:`urdf2links.compare.mujoco_side.mjcf_bodies`), with
the project's states written into an ``MjData`` and every link's pose read back (a folded link's too).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import mujoco
import numpy as np

from urdf2links.dynamics.transforms import BaseState, link_transform

__all__ = ["MjcfModel", "body_pose"]


@dataclass(frozen=True, eq=False)
class MjcfModel:
    """The project's tree compiled by MuJoCo from MJCF text.

    ``xml``: the MJCF text; ``model``: the ``mujoco.MjModel``.
    ``qpos_index`` / ``dof_index`` (n,): coordinate ``i`` of the project (``coordinate_names[i]``)
    is MuJoCo's ``qpos[qpos_index[i]]`` / ``qvel[dof_index[i]]`` (same value, same sign: MuJoCo's
    qpos IS the project's q).
    ``base_dofs`` / ``base_qpos`` (6,) or empty: the dofs / qpos of ``base_A`` (x, y, z, phi_x,
    phi_y, phi_z of {A}) when built with ``moving_base=True``.
    ``body_of_link`` (L,): MuJoCo body id of each tree link, ``-1`` for a folded massless link.
    ``host_body`` (L,): the body that carries a link's joints (its own body, or for a folded link
    the body it is folded into). ``folded_links``, ``tiny_mass_links``: link names.
    ``source``: the project :class:`~urdf2links.dynamics.model.Model`; ``gravity`` (3,) or None;
    ``springs``: the springs/dampers built in; ``notes``: what was done and why.
    """

    xml: str
    model: mujoco.MjModel
    qpos_index: np.ndarray
    dof_index: np.ndarray
    base_dofs: np.ndarray
    base_qpos: np.ndarray
    body_of_link: np.ndarray
    host_body: np.ndarray
    coordinate_names: tuple[str, ...]
    source: object
    gravity: np.ndarray | None
    springs: tuple = ()
    folded_links: tuple[str, ...] = ()
    tiny_mass_links: tuple[str, ...] = ()
    base_body: int = -1
    notes: list[str] = field(default_factory=list)
    actuators: tuple = ()
    """The scene's actuators written as MuJoCo ``<general>`` actuators, in this order (E55)."""
    gravcomp_in_bodies: bool = False
    """The scene's gravcomp written as the bodies' own ``gravcomp`` (MuJoCo's ``qfrc_passive``), not as loads."""

    @property
    def n(self) -> int:
        return len(self.coordinate_names)

    @property
    def moving_base(self) -> bool:
        return self.base_body >= 0

    # -- states ------------------------------------------------------------------------------------
    def set_state(self, d: mujoco.MjData, q, qd=None, *, base: BaseState | None = None) -> None:
        """Write the project's ``q``, ``qd`` (n,) (and the base pose/rate) into ``d.qpos``/``d.qvel``."""
        q = np.asarray(q, float)
        if q.shape != (self.n,):
            raise ValueError(f"q must have shape ({self.n},) for coordinates {self.coordinate_names}")
        d.qpos[self.qpos_index] = q
        if qd is not None:
            qd = np.asarray(qd, float)
            if qd.shape != (self.n,):
                raise ValueError(f"qd must have shape ({self.n},)")
            d.qvel[self.dof_index] = qd
        if base is not None:
            if not self.moving_base:
                raise ValueError("a base state was given but the MJCF model was built with moving_base=False")
            d.qpos[self.base_qpos] = np.asarray(base.pose, float)
            d.qvel[self.base_dofs] = np.asarray(base.rate, float)

    def data(self, q, qd=None, *, base: BaseState | None = None, t: float = 0.0) -> mujoco.MjData:
        """A fresh ``MjData`` at the given state after ``mj_forward`` (no control callback:
        ``qacc`` is MuJoCo's free acceleration, the base NOT prescribed)."""
        d = mujoco.MjData(self.model)
        d.time = float(t)
        self.set_state(d, q, qd, base=base)
        mujoco.mj_forward(self.model, d)
        return d

    def terms(self, q, qd, *, base: BaseState | None = None) -> tuple[np.ndarray, np.ndarray]:
        """``(M, bias)`` of the robot's coordinates in the project's order: ``mj_fullM`` (n, n)
        and ``qfrc_bias`` (n,) (= ``e + G`` of the project for the gravity built in; with a moving
        base, the robot rows at the base's pose and RATE, i.e. without the base's acceleration)."""
        d = self.data(q, qd, base=base)
        M = np.zeros((self.model.nv, self.model.nv))
        mujoco.mj_fullM(self.model, d, M)
        i = self.dof_index
        return M[np.ix_(i, i)].copy(), np.array(d.qfrc_bias[i])

    def link_poses(self, d: mujoco.MjData) -> np.ndarray:
        """(L, 4, 4) {0}-pose of every tree link from MuJoCo's ``xpos``/``xmat`` (after
        kinematics); a folded link's pose is its parent's pose times its own ``T~`` at MuJoCo's
        qpos (its joints live in its child's body)."""
        tree = self.source.tree
        out = np.empty((tree.n_links, 4, 4))
        for p in range(tree.n_links):
            b = int(self.body_of_link[p])
            if b >= 0:
                out[p] = body_pose(d, b)
            else:
                out[p] = self._parent_pose(d, out, p) @ self.link_transform(d, p)
        return out

    def link_pose(self, d: mujoco.MjData, p: int) -> np.ndarray:
        """(4, 4) {0}-pose of tree link ``p`` (see :meth:`link_poses`)."""
        b = int(self.body_of_link[p])
        if b >= 0:
            return body_pose(d, b)
        par = int(self.source.tree.parent[p])
        parent_pose = self._frame_of_parent(d, par)
        return parent_pose @ self.link_transform(d, p)

    def _frame_of_parent(self, d, par: int) -> np.ndarray:
        if par >= 0:
            return self.link_pose(d, par)
        return body_pose(d, self.base_body) if self.moving_base else np.eye(4)

    def _parent_pose(self, d, done, p) -> np.ndarray:
        par = int(self.source.tree.parent[p])
        if par >= 0:
            return done[par]
        return body_pose(d, self.base_body) if self.moving_base else np.eye(4)

    def link_transform(self, d: mujoco.MjData, p: int) -> np.ndarray:
        """``T~`` (4, 4) of tree link ``p`` at MuJoCo's current qpos."""
        tree = self.source.tree
        v = np.array(tree.params[p], float)
        for k in range(6):
            c = int(tree.coord[p, k])
            if c >= 0:
                v[k] += d.qpos[self.qpos_index[c]]
        return link_transform(v)


def body_pose(d: mujoco.MjData, b: int) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3] = np.asarray(d.xmat[b]).reshape(3, 3)
    T[:3, 3] = d.xpos[b]
    return T

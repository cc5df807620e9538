"""compare: cross-checks of urdf2links against MuJoCo (this package may import mujoco)."""

from .mujoco_urdf import (
    FREE_DOF_LABELS,
    MujocoRefused,
    MujocoURDF,
    Terms,
    mujoco_data_at,
    mujoco_from_urdf,
    mujoco_terms,
)

__all__ = [
    "FREE_DOF_LABELS",
    "MujocoRefused",
    "MujocoURDF",
    "Terms",
    "mujoco_data_at",
    "mujoco_from_urdf",
    "mujoco_terms",
]

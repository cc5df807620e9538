"""compare: cross-checks of urdf2links against MuJoCo (this package may import mujoco)."""

from .mjcf import MjcfModel, mjcf_from_model, mjcf_from_scene
from .mujoco_run import MujocoRun, mujoco_accelerations, run_mujoco
from .mujoco_urdf import (
    FREE_DOF_LABELS,
    MujocoRefused,
    MujocoURDF,
    Terms,
    mujoco_data_at,
    mujoco_from_urdf,
    mujoco_terms,
)
from .report import CheckResult, check_baseline, load_baselines, write_baselines, write_index, write_report
from .terms import TermsComparison, compare_terms_urdf, massless_moving_links, repaired_urdf_text
from .trajectory import DIVERGENCE_THRESHOLD, SceneComparison, compare_scene, growth_fit, scene_key

__all__ = [
    "MjcfModel",
    "MujocoRun",
    "mjcf_from_model",
    "mjcf_from_scene",
    "mujoco_accelerations",
    "run_mujoco",
    "FREE_DOF_LABELS",
    "MujocoRefused",
    "MujocoURDF",
    "Terms",
    "mujoco_data_at",
    "mujoco_from_urdf",
    "mujoco_terms",
    "TermsComparison",
    "compare_terms_urdf",
    "massless_moving_links",
    "repaired_urdf_text",
    "SceneComparison",
    "compare_scene",
    "growth_fit",
    "scene_key",
    "DIVERGENCE_THRESHOLD",
    "CheckResult",
    "check_baseline",
    "load_baselines",
    "write_baselines",
    "write_index",
    "write_report",
]

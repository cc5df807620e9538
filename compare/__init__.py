"""urdf2links.compare: the MuJoCo side, the same model in MuJoCo, metrics, reports, trade-off studies.

Installed as ``urdf2links.compare`` from the repository's top-level ``compare/`` folder; it imports
MuJoCo (``import urdf2links`` does not).
"""

from urdf2links import numba_cache as _numba_cache

_numba_cache.install()     # before any compiled function is defined (idempotent)

from .agreement.terms import TermsComparison, compare_terms_urdf, massless_moving_links, repaired_urdf_text
from .agreement.trajectory import DIVERGENCE_THRESHOLD, SceneComparison, compare_scene, growth_fit, scene_key
from .mujoco_side.mjcf import mjcf_from_model, mjcf_from_scene
from .mujoco_side.mjcf_model import MjcfModel
from .mujoco_side.mujoco_run import MujocoRun, mujoco_accelerations, run_mujoco
from .mujoco_side.mujoco_urdf import (
    FREE_DOF_LABELS,
    MujocoRefused,
    MujocoURDF,
    Terms,
    mujoco_data_at,
    mujoco_from_urdf,
    mujoco_terms,
)
from .reports.baselines import CheckResult, check_baseline, load_baselines, write_baselines
from .reports.report import write_index, write_report

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

"""Numbers and JSON for the reports: non-finite values as strings, dotted lookups, short formats."""

from __future__ import annotations

import html
import math
from pathlib import Path

import numpy as np

__all__ = ["json_ready", "get", "fmt", "fmt_t", "fmt_md", "machine_info"]


def json_ready(x):
    """``x`` with numpy scalars/arrays made plain and non-finite floats written as strings."""
    if isinstance(x, dict):
        return {str(k): json_ready(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [json_ready(v) for v in x]
    if isinstance(x, np.ndarray):
        return json_ready(x.tolist())
    if isinstance(x, (np.bool_, bool)):
        return bool(x)
    if isinstance(x, (np.integer, int)):
        return int(x)
    if isinstance(x, (np.floating, float)):
        v = float(x)
        return v if math.isfinite(v) else ("nan" if math.isnan(v) else ("inf" if v > 0 else "-inf"))
    if isinstance(x, Path):
        return str(x)
    return x


def get(summary: dict, dotted: str):
    """``summary["a"]["b"]`` for ``"a.b"``; None when missing."""
    cur = summary
    for part in dotted.split("."):
        if not isinstance(cur, dict) or part not in cur:
            return None
        cur = cur[part]
    return cur


def fmt(x, digits: int = 2, unit: str = "") -> str:
    if x is None:
        return "&ndash;"
    if isinstance(x, str):
        return html.escape(x)
    if isinstance(x, bool):
        return "yes" if x else "no"
    if isinstance(x, (int, np.integer)):
        return f"{int(x)}{unit}"
    v = float(x)
    if not math.isfinite(v):
        return str(v)
    if v == 0:
        return "0" + unit
    a = abs(v)
    s = f"{v:.{digits}e}" if (a < 1e-2 or a >= 1e5) else f"{v:.{digits + 1}g}"
    return s + unit


def fmt_t(x) -> str:
    return "none" if x is None else f"{float(x):.4g} s"


def fmt_md(x, digits=2, unit="") -> str:
    return fmt(x, digits, unit).replace("&ndash;", "-")


def machine_info() -> dict:
    """The machine and the versions a timing was taken with (JSON-ready): platform, processor,
    CPU count, Python, numpy, scipy, numba, MuJoCo, matplotlib, urdf2links and the git commit of
    the source tree (None outside a checkout)."""
    import os
    import platform
    import subprocess
    import sys
    from importlib.metadata import PackageNotFoundError, version

    def ver(name):
        try:
            return version(name)
        except PackageNotFoundError:
            return None

    try:
        commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                                timeout=5, cwd=Path(__file__).resolve().parent).stdout.strip() or None
    except (OSError, subprocess.SubprocessError):
        commit = None
    return {"platform": platform.platform(), "processor": platform.processor() or platform.machine(),
            "cpu_count": os.cpu_count(), "python": sys.version.split()[0], "numpy": np.__version__,
            "scipy": ver("scipy"), "numba": ver("numba"), "mujoco": ver("mujoco"), "matplotlib": ver("matplotlib"),
            "urdf2links": ver("urdf2links"), "git_commit": commit}

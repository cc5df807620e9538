"""Where robots are: the project's shipped ``robots/`` and the optional example-robot-data corpus."""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, distribution
from pathlib import Path

__all__ = ["shipped_robots_dir", "example_robot_data_dir"]


def shipped_robots_dir() -> Path:
    """The shipped robots and scenes: the package data ``urdf2links.robots`` (the repository's
    ``robots/`` folder in a checkout or an editable install)."""
    import urdf2links.robots

    return Path(urdf2links.robots.__file__).resolve().parent


def example_robot_data_dir() -> Path | None:
    """``<site-packages>/cmeel.prefix/share/example-robot-data/robots`` when the
    ``example-robot-data`` package is installed (it ships data only, no importable module), else None."""
    try:
        root = Path(distribution("example-robot-data").locate_file("cmeel.prefix/share/example-robot-data/robots"))
    except PackageNotFoundError:
        return None
    return root if root.is_dir() else None

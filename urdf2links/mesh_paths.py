"""Where the files a robot description names are: ``package://`` and relative mesh paths, ``$(find pkg)``.

Public API: :func:`resolve_mesh_path`, :func:`require_mesh`, :func:`find_package_dir`.
"""

from __future__ import annotations

import os
from pathlib import Path
from urllib.parse import unquote

from .description import Geometry
from .errors import MeshError

__all__ = ["resolve_mesh_path", "require_mesh", "find_package_dir"]


def _package_bases(directory, package_dirs) -> list[Path]:
    bases = []
    if directory is not None:
        directory = Path(directory)
        bases += [directory, *directory.parents]
    bases += [Path(p) for p in package_dirs]
    bases += [Path(p) for p in os.environ.get("ROS_PACKAGE_PATH", "").split(os.pathsep) if p]
    return bases


def resolve_mesh_path(filename: str, *, directory=None, package_dirs=()) -> Path | None:
    """Find the file a ``<mesh filename>`` names; ``None`` when it cannot be found.

    - ``package://pkg/rest`` (also ``model://``): for each base folder -- the URDF's
      ``directory`` and its ancestors, then each of ``package_dirs``, then ``ROS_PACKAGE_PATH``
      -- try ``base/pkg/rest`` (and ``base/rest`` when ``base`` is itself named ``pkg``);
      then, as a fallback, ``base/rest`` for each base.
    - ``file:///abs/path`` is that path; ``file://rel`` is relative to ``directory``.
    - Otherwise an absolute path, or a path relative to ``directory`` (then ``package_dirs``).
    """
    candidates: list[Path] = []
    for scheme in ("package://", "model://"):
        if filename.startswith(scheme):
            pkg, _, rest = unquote(filename[len(scheme):]).partition("/")
            bases = _package_bases(directory, package_dirs)
            for base in bases:
                candidates.append(base / pkg / rest)
                if base.name == pkg:
                    candidates.append(base / rest)
            candidates += [base / rest for base in bases]
            break
    else:
        name = unquote(filename[len("file://"):]) if filename.startswith("file://") else filename
        path = Path(name).expanduser()
        if path.is_absolute():
            candidates.append(path)
        else:
            bases = ([Path(directory)] if directory is not None else []) + [Path(p) for p in package_dirs]
            candidates += [b / path for b in bases]
    for c in candidates:
        if c.is_file():
            return c.resolve()
    return None


def require_mesh(geometry: Geometry, *, link: str, source: str) -> Path:
    """The resolved path of a mesh geometry, or a :class:`MeshError` naming file, link and mesh."""
    if geometry.kind != "mesh":
        raise MeshError(f"{source}: link '{link}': the geometry is a {geometry.kind}, not a mesh")
    if geometry.path is not None and Path(geometry.path).is_file():
        return Path(geometry.path)
    fix = "correct the filename"
    if geometry.filename and geometry.filename.startswith(("package://", "model://")):
        pkg = geometry.filename.split("://", 1)[1].split("/", 1)[0]
        fix = (f"pass package_dirs=[<folder that contains '{pkg}'>] to parse_urdf, "
               "or correct the filename")
    raise MeshError(f"{source}: link '{link}': mesh '{geometry.filename}' was not found; {fix}")


def find_package_dir(pkg: str, *, directory=None, package_dirs=()) -> Path | None:
    """The folder of package ``pkg`` (for ``$(find pkg)``): for each base folder of
    :func:`resolve_mesh_path`, ``base/pkg``, or ``base`` itself when it is named ``pkg``."""
    for base in _package_bases(directory, package_dirs):
        if base.name == pkg and base.is_dir():
            return base.resolve()
        if (base / pkg).is_dir():
            return (base / pkg).resolve()
    return None

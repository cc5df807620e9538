"""Where the files a robot description names are: ``package://`` and relative mesh paths, ``$(find pkg)``.

Only regular files are ever read: a mesh path naming a device (``/dev/zero``), a directory or a FIFO
is refused with a :class:`~urdf2links.errors.MeshError`, and so is a ``package://pkg/rest`` whose
``rest`` climbs out of the package (``package://pkg/../../etc/passwd``): the allowed roots of a
package path are the package folders found for it. A file is handed to the mesh reader only when
its suffix is a mesh format (:data:`MESH_SUFFIXES`), so ``/etc/passwd`` named as a mesh is refused
without being opened.

A mesh that does not resolve is named with the description file, the link, the element (visual or collision)
and the paths looked for (:func:`missing_mesh`): a note when the file is read leniently, an error with
``strict`` (:mod:`urdf2links.parsers.urdf`), and the error of whatever needs the mesh (an inertia from geometry,
a drawing, the collision kind of ``compare --against``).

Public API: :func:`resolve_mesh_path`, :func:`require_mesh`, :func:`find_package_dir`,
:func:`check_mesh_file`, :func:`missing_mesh`, :data:`MESH_SUFFIXES`.
"""

from __future__ import annotations

import os
import stat
from dataclasses import dataclass
from pathlib import Path
from urllib.parse import unquote

from ..errors import MeshError
from .description import Geometry

__all__ = ["resolve_mesh_path", "require_mesh", "find_package_dir", "check_mesh_file", "MESH_SUFFIXES",
           "leaves_package", "unresolved_mesh_problem", "mesh_candidates", "missing_mesh", "MissingMesh"]

#: Suffixes of the mesh formats trimesh reads (and the corpus uses: stl, dae, obj); others are refused.
MESH_SUFFIXES = (".stl", ".dae", ".obj", ".ply", ".off", ".glb", ".gltf", ".3mf", ".stp", ".step", ".xaml",
                 ".zae", ".3dxml")


def leaves_package(rest: str) -> bool:
    """True when the path ``rest`` inside a package is absolute or climbs above the package (``..``)."""
    return rest.startswith(("/", "\\")) or os.path.normpath(rest or ".").split(os.sep)[0] == ".."


def _plain_path(filename: str) -> Path:
    """A ``file://`` or plain mesh path as a Path (``~`` expanded when it names a known home)."""
    name = unquote(filename[len("file://"):]) if filename.startswith("file://") else filename
    try:
        return Path(name).expanduser()
    except RuntimeError:          # '~someone' with no such user: the name as written
        return Path(name)


def _regular(path: Path) -> bool:
    """``path`` exists and is a regular file (symlinks followed); never opens it."""
    try:
        return stat.S_ISREG(path.stat().st_mode)
    except (OSError, ValueError):
        return False


def _kind_of(path: Path) -> str | None:
    """What ``path`` is when it exists but is not a regular file ('a directory', 'a character
    device', ...); None when it is a regular file or does not exist."""
    try:
        mode = path.stat().st_mode
    except (OSError, ValueError):
        return None
    for test, name in ((stat.S_ISDIR, "a directory"), (stat.S_ISCHR, "a character device"),
                       (stat.S_ISBLK, "a block device"), (stat.S_ISFIFO, "a FIFO"), (stat.S_ISSOCK, "a socket")):
        if test(mode):
            return name
    return None


def check_mesh_file(path, *, name: str) -> Path:
    """``path`` if it is a regular file with a mesh suffix; a :class:`MeshError` naming the mesh
    ``name`` (as the description writes it) otherwise. Nothing is opened."""
    path = Path(path)
    kind = _kind_of(path)
    if kind is not None:
        raise MeshError(f"mesh {name!r}: {str(path)!r} is {kind}, not a regular file; it is not read")
    if not _regular(path):
        raise MeshError(f"mesh {name!r}: file {str(path)!r} does not exist")
    if path.suffix.lower() not in MESH_SUFFIXES:
        raise MeshError(f"mesh {name!r}: {str(path)!r} is not a mesh file (suffix {path.suffix or 'none'!r}; "
                        f"read are {', '.join(MESH_SUFFIXES)}); it is not read")
    return path


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
    for c in mesh_candidates(filename, directory=directory, package_dirs=package_dirs):
        if _regular(c):
            return c.resolve()
    return None


def mesh_candidates(filename: str, *, directory=None, package_dirs=()) -> list[Path]:
    """The paths :func:`resolve_mesh_path` tries for ``filename``, in its order (none for a package path that
    leaves its package)."""
    candidates: list[Path] = []
    for scheme in ("package://", "model://"):
        if filename.startswith(scheme):
            pkg, _, rest = unquote(filename[len(scheme):]).partition("/")
            if not pkg or leaves_package(rest) or leaves_package(pkg):
                return []         # outside every package folder: refused by require_mesh, never read
            bases = _package_bases(directory, package_dirs)
            for base in bases:
                candidates.append(base / pkg / rest)
                if base.name == pkg:
                    candidates.append(base / rest)
            candidates += [base / rest for base in bases]
            break
    else:
        path = _plain_path(filename)
        if path.is_absolute():
            candidates.append(path)
        else:
            bases = ([Path(directory)] if directory is not None else []) + [Path(p) for p in package_dirs]
            candidates += [b / path for b in bases]
    return list(dict.fromkeys(candidates))


@dataclass(frozen=True)
class MissingMesh:
    """A mesh that did not resolve: its ``filename`` as written in the description file ``source``, ``why``,
    ``looked`` (the paths looked for, in words) and ``fix``."""

    filename: str
    source: str
    why: str
    looked: str
    fix: str

    @property
    def problem(self) -> str:
        """The defect with the file it is named in (a parser's note or strict error adds the link and element)."""
        return f"mesh {self.filename!r} named in {self.source}: {self.why}{self.looked}"

    def text(self, where: str) -> str:
        """The error of what needs the file; ``where`` names the description file, the link and the element."""
        return f"{where}: mesh {self.filename!r}: {self.why}{self.looked}; {self.fix}"


def missing_mesh(filename: str, *, source: str, directory=None, package_dirs=()) -> MissingMesh:
    """Why ``filename`` (named in the description file ``source``) did not resolve (:func:`unresolved_mesh_problem`)
    and the paths looked for: the first three, and how many more."""
    tried = mesh_candidates(filename, directory=directory, package_dirs=package_dirs)
    looked = ", ".join(repr(str(p)) for p in tried[:3]) + (f" and {len(tried) - 3} other place(s)" if len(tried) > 3 else "")
    why, _, fix = unresolved_mesh_problem(filename).partition("; ")
    return MissingMesh(filename, source, why, f" (looked for {looked})" if tried else "", fix or "correct the filename")


def unresolved_mesh_problem(filename: str) -> str:
    """Why a mesh ``filename`` did not resolve to a readable file, in words (for a MeshError)."""
    name = filename or ""
    if name.startswith(("package://", "model://")):
        pkg, _, rest = unquote(name.split("://", 1)[1]).partition("/")
        if not pkg or leaves_package(rest) or leaves_package(pkg):
            return ("it leaves its package folder ('..' or an absolute path after the package name); it is not read: "
                    "name a file inside the package")
        return (f"it was not found; pass package_dirs=[<folder that contains '{pkg}'>] to parse_urdf, "
                "or correct the filename")
    plain = _plain_path(name)
    kind = _kind_of(plain) if plain.is_absolute() else None
    if kind is not None:
        return f"it is {kind}, not a regular file; it is not read"
    return "it was not found; correct the filename"


def require_mesh(geometry: Geometry, *, link: str, source: str) -> Path:
    """The resolved path of a mesh geometry, or a :class:`MeshError` naming file, link and mesh."""
    if geometry.kind != "mesh":
        raise MeshError(f"{source}: link '{link}': the geometry is a {geometry.kind}, not a mesh")
    if geometry.path is not None:
        return check_mesh_file(geometry.path, name=geometry.filename or str(geometry.path))
    if geometry.missing:
        raise MeshError(geometry.missing)
    raise MeshError(f"{source}: link '{link}': mesh '{geometry.filename}': "
                    f"{unresolved_mesh_problem(geometry.filename or '')}")


def find_package_dir(pkg: str, *, directory=None, package_dirs=()) -> Path | None:
    """The folder of package ``pkg`` (for ``$(find pkg)``): for each base folder of
    :func:`resolve_mesh_path`, ``base/pkg``, or ``base`` itself when it is named ``pkg``."""
    for base in _package_bases(directory, package_dirs):
        if base.name == pkg and base.is_dir():
            return base.resolve()
        if (base / pkg).is_dir():
            return (base / pkg).resolve()
    return None

"""What a robot file depends on, and which files changed: ``urdf2links check --changed-since GIT_REF``.

:func:`robot_files` is a robot file and every file it reads: a URDF's meshes (``package://``, relative and
``file://`` paths resolved as the importer resolves them, :func:`urdf2links.parsers.mesh_paths.resolve_mesh_path`),
a xacro file's includes (the ``xacro`` package records them while it expands) and the meshes of its
expansion, an MJCF file's ``<include>`` files and its assets (``mesh``, ``hfield``, ``texture``, ``skin``
under the compiler's ``meshdir``/``texturedir``/``assetdir``). A file that cannot be read counts only itself:
the check then says why it cannot be loaded. :func:`changed_files` asks git which files differ from a
commit (committed since, staged, in the work tree, or new and untracked).
"""

from __future__ import annotations

import subprocess
from pathlib import Path

from lxml import etree

from urdf2links.parsers.mesh_paths import resolve_mesh_path

__all__ = ["robot_files", "changed_files"]

_ASSET_DIRS = {"mesh": "meshdir", "hfield": "meshdir", "skin": "meshdir", "texture": "texturedir"}


def _urdf_meshes(root, folder: Path, package_dirs) -> set[Path]:
    out = set()
    for m in root.iter("mesh"):
        name = m.get("filename")
        found = resolve_mesh_path(name, directory=folder, package_dirs=package_dirs) if name else None
        if found is not None:
            out.add(found)
    return out


def _xacro_files(path: Path, load: dict) -> set[Path]:
    """The xacro file's includes (recorded by the ``xacro`` package while it expands) and its meshes."""
    import xacro

    from urdf2links.parsers.xacro_input import expand_xacro

    xacro.all_includes.clear()
    text = expand_xacro(path, xacro_args=load.get("xacro_args"), package_dirs=load.get("package_dirs", ()))
    files = {Path(f).resolve() for f in xacro.all_includes}
    root = etree.fromstring(text.encode("utf-8"))
    return files | _urdf_meshes(root, path.parent, load.get("package_dirs", ()))


def _mjcf_files(path: Path, seen: set[Path], dirs: dict | None = None) -> set[Path]:
    """The MJCF file, its includes (recursively, relative to the main file's folder as MuJoCo reads them) and
    the asset files they name."""
    root = etree.parse(str(path)).getroot()
    main = dirs is None
    dirs = dict(dirs or {"base": path.parent})
    for comp in root.iter("compiler"):
        for key in ("meshdir", "texturedir", "assetdir"):
            if comp.get(key):
                dirs[key] = dirs["base"] / comp.get(key)
    out = {path}
    for inc in root.iter("include"):
        f = (dirs["base"] / inc.get("file", "")).resolve()
        if f.is_file() and f not in seen:
            seen.add(f)
            out |= _mjcf_files(f, seen, dirs)
    for tag, key in _ASSET_DIRS.items():
        for el in root.iter(tag):
            if el.get("file"):
                folder = dirs.get(key) or dirs.get("assetdir") or dirs["base"]
                out.add((folder / el.get("file")).resolve())
    return out if main else out | {path}


def robot_files(path, load: dict | None = None) -> set[Path]:
    """The robot file ``path`` and every file it reads (module doc), as absolute paths; ``load``: its loading
    options (``package_dirs``, ``xacro_args``)."""
    path = Path(path).resolve()
    load = load or {}
    try:
        if path.name.endswith(".xacro"):
            return {path} | _xacro_files(path, load)
        if path.name.endswith(".xml"):
            return _mjcf_files(path, {path})
        root = etree.parse(str(path)).getroot()
        return {path} | _urdf_meshes(root, path.parent, load.get("package_dirs", ()))
    except Exception:  # noqa: BLE001 -- an unreadable file counts itself; loading it says what is wrong
        return {path}


def changed_files(ref: str, folder) -> set[Path]:
    """The files of the git repository holding ``folder`` that differ from commit ``ref`` (committed since, staged,
    changed in the work tree, or untracked), as absolute paths. ValueError names a ``ref`` git does not know, or
    a folder outside a repository."""
    def git(*args) -> str:
        r = subprocess.run(["git", *args], cwd=folder, capture_output=True, text=True)
        if r.returncode != 0:
            raise ValueError(f"--changed-since {ref}: git {' '.join(args)} failed in {folder}: {r.stderr.strip()}")
        return r.stdout

    top = Path(git("rev-parse", "--show-toplevel").strip())
    git("rev-parse", "--verify", "--quiet", f"{ref}^{{commit}}")
    names = git("diff", "--name-only", "-z", ref, "--").split("\0")
    names += git("ls-files", "--others", "--exclude-standard", "--full-name", "-z").split("\0")
    return {(top / n).resolve() for n in names if n}

"""Where numba caches urdf2links' compiled code: a per-user folder, never the installed package.

numba's ``cache=True`` writes its index and object files next to the source by default, into
``site-packages/urdf2links/**/__pycache__``. pip's uninstall does not know those files, so it leaves
the folders behind, and Python then takes the leftover ``urdf2links/`` for a namespace package that
hides the next (editable) install; a read-only install cannot be cached at all. So the project's
compiled functions cache into

- ``$NUMBA_CACHE_DIR`` when the user set it (numba's own setting wins), else
- ``$URDF2LINKS_CACHE_DIR``, else the user's cache folder: ``$XDG_CACHE_HOME/urdf2links/numba``
  (default ``~/.cache``; ``%LOCALAPPDATA%`` on Windows, ``~/Library/Caches`` on macOS), else (not
  writable) a folder of the user's in the temporary directory.

Only functions of the ``urdf2links`` package are placed there (a cache locator put first in numba's
list answers for them alone); other numba code in the same process caches where it always did.

**Freshness.** numba keys a file's cache on that file's own timestamp, but the integration loops
inline the kernels of other files: after an edit of ``dynamics/kernels.py`` the cached loops would
still call the old kernels. The locator's source stamp is therefore the stamp of every compiled
source file of the package together (path, size, modification time of each file that uses numba):
an edit of any of them invalidates every cached function, which is then compiled again once.

**numba's private hook.** numba has no public way to add a cache locator: :func:`install` puts one
first in ``numba.core.caching.CacheImpl._locator_classes``, a subclass of its
``UserProvidedCacheLocator``. numba is pinned to the tested minor release (pyproject.toml), and
``tests/test_numba_hooks.py`` checks that the locator is installed and that urdf2links' compiled
functions cache into this folder (a numba without the list falls back to its documented
``config.CACHE_DIR``, for every function of the process).
"""

from __future__ import annotations

import hashlib
import os
import re
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

__all__ = ["cache_dir", "install", "source_stamp", "CacheFolder", "cache_folders", "clear_cache", "ORIGIN"]

#: The file in each cached source folder's subfolder that names the source folder it caches.
ORIGIN = "origin.txt"

_PACKAGE = "urdf2links"
_STAMP: list = []
_INSTALLED: list = []
#: A source file that defines compiled functions (its edits invalidate the cache).
_COMPILED = re.compile(r"@njit|\bnjit\(|\bcfunc\(|@jit\b|numba\.jit\(|@vectorize|@guvectorize")


def cache_dir() -> Path:
    """The folder numba caches urdf2links' compiled functions in (module doc); not created here."""
    given = os.environ.get("NUMBA_CACHE_DIR") or os.environ.get("URDF2LINKS_CACHE_DIR")
    if given:
        return Path(given).expanduser()
    if sys.platform == "win32":
        base = Path(os.environ.get("LOCALAPPDATA") or Path.home() / "AppData" / "Local")
    elif sys.platform == "darwin":
        base = Path.home() / "Library" / "Caches"
    else:
        base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return base / _PACKAGE / "numba"


def _writable(folder: Path) -> bool:
    try:
        folder.mkdir(parents=True, exist_ok=True)
        tempfile.TemporaryFile(dir=folder).close()
        return True
    except OSError:
        return False


def _roots() -> list[Path]:
    """The folders of the package's sources: urdf2links/ and compare/ (urdf2links.compare, which an
    editable install maps to the repository's top-level compare/)."""
    import importlib.util

    roots = [Path(__file__).resolve().parent]
    spec = importlib.util.find_spec(f"{_PACKAGE}.compare")
    if spec is not None and spec.submodule_search_locations:
        roots += [Path(p).resolve() for p in spec.submodule_search_locations]
    return list(dict.fromkeys(roots))


def source_stamp() -> str:
    """A digest of (path, size, modification time) of every source file of the package that defines
    compiled functions: the freshness of every cached function (module doc). Computed once per process."""
    if not _STAMP:
        h = hashlib.sha1()
        for root in _roots():
            for f in sorted(root.rglob("*.py")):
                try:
                    if not _COMPILED.search(f.read_text(encoding="utf-8", errors="ignore")):
                        continue
                    st = f.stat()
                except OSError:
                    continue
                h.update(f"{f}\0{st.st_size}\0{st.st_mtime_ns}\n".encode())
        _STAMP.append(h.hexdigest())
    return _STAMP[0]


def install() -> Path | None:
    """Put the package's cache locator first in numba's list (once); returns the cache folder, or
    None when the user's ``NUMBA_CACHE_DIR`` decides (numba's own locator then serves every function).
    Folders of installs whose sources are gone are removed (:func:`clear_cache`). A folder that cannot
    be written: the compiled code is kept for this process only (a private temporary folder, removed
    at exit), said once on stderr."""
    from . import compilation

    compilation.watch()         # numba's compilation events: kept out of reported times, shown while they run
    if os.environ.get("NUMBA_CACHE_DIR") or _INSTALLED:
        return _INSTALLED[0] if _INSTALLED else None
    folder = cache_dir()
    if _writable(folder):
        clear_cache(folder, which="gone")
    else:
        import atexit
        import shutil

        wanted = folder
        folder = Path(tempfile.mkdtemp(prefix=f"{_PACKAGE}-numba-"))
        atexit.register(shutil.rmtree, folder, True)
        print(f"urdf2links: note: the cache folder {wanted} cannot be written; the compiled code is kept for this "
              "process only (set URDF2LINKS_CACHE_DIR to a writable folder to keep it)", file=sys.stderr)
    _INSTALLED.append(folder)
    from numba.core import caching

    impl = getattr(caching, "CacheImpl", None)
    base = getattr(caching, "UserProvidedCacheLocator", None)
    if impl is None or base is None or not hasattr(impl, "_locator_classes"):
        from numba import config    # numba without the locator list: its documented setting, for the process

        config.CACHE_DIR = str(folder)
        return folder
    if not any(getattr(c, "_urdf2links", False) for c in impl._locator_classes):
        impl._locator_classes.insert(0, _locator_class(base, folder))
    return folder


def _locator_class(base, folder: Path):
    """numba's user-provided locator, answering only for urdf2links' functions, in ``folder``, with
    the package-wide :func:`source_stamp`."""

    class PackageCacheLocator(base):
        _urdf2links = True

        def __init__(self, py_func, py_file):
            self._py_file = py_file
            self._lineno = py_func.__code__.co_firstlineno
            self._cache_path = os.path.join(str(folder), self.get_suitable_cache_subpath(py_file))

        def get_source_stamp(self):
            return source_stamp()

        def ensure_cache_path(self):
            super().ensure_cache_path()
            origin = Path(self._cache_path) / ORIGIN
            if not origin.exists():       # which source folder this subfolder caches (cache --list)
                origin.write_text(str(Path(self._py_file).resolve().parent) + "\n", encoding="utf-8")

        @classmethod
        def from_function(cls, py_func, py_file):
            module = getattr(py_func, "__module__", "") or ""
            if module != _PACKAGE and not module.startswith(_PACKAGE + "."):
                return None
            if not os.path.exists(py_file):
                return None
            return cls(py_func, py_file)

    return PackageCacheLocator


# -- the cache folder's contents: urdf2links cache --list | --clear -------------------------------------
@dataclass(frozen=True)
class CacheFolder:
    """One subfolder of the cache: ``path``, ``source`` (the source folder it caches, None when not
    recorded), ``status``: ``"current"`` (this install's sources), ``"other"`` (another install, still
    there) ``"gone"`` (sources removed) or ``"unknown"`` (no origin recorded: an older version's folder, or one being created); ``size`` in bytes, ``files``."""

    path: Path
    source: Path | None
    status: str
    size: int
    files: int


def _current_sources() -> set:
    return {str(f.parent) for root in _roots() for f in root.rglob("*.py")}


def cache_folders(folder: Path | None = None) -> list[CacheFolder]:
    """Every subfolder of the cache ``folder`` (default :func:`cache_dir`), with its status."""
    folder = Path(folder) if folder is not None else cache_dir()
    if not folder.is_dir():
        return []
    current, out = _current_sources(), []
    for sub in sorted(p for p in folder.iterdir() if p.is_dir()):
        origin = sub / ORIGIN
        try:
            source = Path(origin.read_text(encoding="utf-8").strip()) if origin.exists() else None
        except OSError:
            source = None
        # no origin file: an older version's folder, or one that another process is creating right now
        # (two processes starting at once, pytest-xdist's workers): never removed as "gone"
        status = ("unknown" if source is None else "current" if str(source) in current else
                  "other" if source.is_dir() else "gone")
        files = [f for f in sub.rglob("*") if f.is_file()]
        out.append(CacheFolder(sub, source, status, sum(_size(f) for f in files), len(files)))
    return out


def clear_cache(folder: Path | None = None, *, which: str = "stale") -> list[CacheFolder]:
    """Remove the cache's subfolders ``which`` says: ``"gone"`` (their sources no longer exist),
    ``"stale"`` (gone, unknown -- no origin file, an older version's -- and other installs'), ``"all"``.
    Returns the removed ones."""
    import shutil

    if which not in ("gone", "stale", "all"):
        raise ValueError(f"clear_cache: which must be 'gone', 'stale' or 'all', got {which!r}")
    keep = {"gone": ("current", "other", "unknown"), "stale": ("current",), "all": ()}[which]
    removed = []
    for f in cache_folders(folder):
        if f.status not in keep:
            shutil.rmtree(f.path, ignore_errors=True)
            removed.append(f)
    return removed


def _size(f: Path) -> int:
    """``f``'s size, 0 when it is gone: another process (a second command, a pytest-xdist worker) may remove a
    stale folder's files between the listing and this ``stat``."""
    try:
        return f.stat().st_size
    except OSError:
        return 0


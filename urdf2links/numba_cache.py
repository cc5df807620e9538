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
"""

from __future__ import annotations

import hashlib
import os
import re
import sys
import tempfile
from pathlib import Path

__all__ = ["cache_dir", "install", "source_stamp"]

_PACKAGE = "urdf2links"
_STAMP: list = []
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
    None when the user's ``NUMBA_CACHE_DIR`` decides (numba's own locator then serves every function)."""
    if os.environ.get("NUMBA_CACHE_DIR"):
        return None
    folder = cache_dir()
    if not _writable(folder):
        folder = Path(tempfile.gettempdir()) / f"{_PACKAGE}-numba-{os.getuid() if hasattr(os, 'getuid') else 'user'}"
        folder.mkdir(parents=True, exist_ok=True)
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

        @classmethod
        def from_function(cls, py_func, py_file):
            module = getattr(py_func, "__module__", "") or ""
            if module != _PACKAGE and not module.startswith(_PACKAGE + "."):
                return None
            if not os.path.exists(py_file):
                return None
            return cls(py_func, py_file)

    return PackageCacheLocator

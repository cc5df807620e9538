"""A robot file of any kind -> Model: ``.urdf`` and ``.xacro`` by the URDF importer, ``.xml`` (MJCF) by
MuJoCo's compiler (:mod:`urdf2links.parsers.mjcf`). The one place that dispatches on the suffix, for
scenes and every command."""

from __future__ import annotations

from ..dynamics.model import Model
from ..errors import MJCFError
from . import importer, mjcf
from .mjcf import is_mjcf_path

__all__ = ["load_robot", "is_mjcf_path", "URDF_ONLY"]

#: Loading options that only a URDF (or xacro) file takes, with the value that means "not asked for".
URDF_ONLY = {"floating_base": False, "mimic": "independent", "package_dirs": (), "xacro_args": None,
             "density": 1000.0}


def load_robot(path, **options) -> Model:
    """``path`` loaded by the reader its suffix names, with ``options`` (those of
    :func:`~urdf2links.parsers.importer.load_urdf`; an MJCF file takes ``inertia`` and ``strict``, and
    refuses the URDF-only ones when they ask for something)."""
    if not is_mjcf_path(path):
        return importer.load_urdf(path, **options)     # through the module: one place to count or wrap loads
    asked = [k for k, v in options.items() if k in URDF_ONLY and v not in (URDF_ONLY[k], None, (), [], {})]
    if asked:
        raise MJCFError(f"{path}: {', '.join(asked)} apply to URDF files; an MJCF file says itself how its bodies move "
                        "(a free joint for a floating base) and has no mimic joints, package:// paths or xacro "
                        "arguments")
    unknown = [k for k in options if k not in URDF_ONLY and k not in ("inertia", "strict")]
    if unknown:
        raise TypeError(f"load_robot: unknown option(s) {unknown}")
    return mjcf.load_mjcf(path, **{k: v for k, v in options.items() if k in ("inertia", "strict")})

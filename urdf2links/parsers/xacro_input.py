"""xacro input: expand a ``.xacro`` robot description into URDF text with the ``xacro`` package.

``xacro`` is an optional dependency (``pip install "urdf2links[xacro]"``); without it
:func:`expand_xacro` raises a :class:`~urdf2links.errors.URDFError` that says what to install.
``$(find pkg)`` and ``<xacro:include filename="package://pkg/...">`` are resolved the way
``package://pkg/...`` mesh paths are
(:func:`urdf2links.parsers.mesh_paths.find_package_dir`: the file's folder and its ancestors,
``package_dirs``, ``ROS_PACKAGE_PATH``), then by ROS's ``ament_index`` when it is installed, so a
description that lives outside a ROS workspace still expands. ``xacro_args`` are the
``name:=value`` arguments of the ``xacro`` command (``<xacro:arg name=... default=...>``).

Public API: :func:`expand_xacro`, :func:`is_xacro_path`, :func:`parse_xacro_arg`.
"""

from __future__ import annotations

from contextlib import contextmanager
from pathlib import Path

from ..errors import URDFError
from .mesh_paths import find_package_dir, resolve_mesh_path

__all__ = ["expand_xacro", "is_xacro_path", "parse_xacro_arg", "XACRO_INSTALL"]

XACRO_INSTALL = 'pip install "urdf2links[xacro]"'


def is_xacro_path(source) -> bool:
    """True for a path whose name ends in ``.xacro`` (``robot.urdf.xacro``, ``robot.xacro``)."""
    return not (isinstance(source, str) and source.lstrip().startswith("<")) and str(source).endswith(".xacro")


def parse_xacro_arg(text: str) -> tuple[str, str]:
    """``"name:=value"`` (the xacro command's form) -> ``(name, value)``; ValueError otherwise."""
    name, sep, value = text.partition(":=")
    if not sep or not name.strip():
        raise ValueError(f"xacro argument {text!r}: write name:=value (e.g. prefix:=left_)")
    return name.strip(), value


@contextmanager
def _package_finder(xacro_module, subst, directory: Path, package_dirs):
    """Let ``$(find pkg)`` and ``<xacro:include filename="package://pkg/...">`` search the same folders as
    ``package://pkg`` meshes (then ament, if present). ``subst`` is ``xacro.substitution_args``, whose
    ``_find`` calls ``_eval_find(pkg)``; includes go through ``xacro.abs_filename_spec``."""
    original_find, original_abs = subst._eval_find, xacro_module.abs_filename_spec

    def find(pkg):
        found = find_package_dir(pkg, directory=directory, package_dirs=package_dirs)
        if found is not None:
            return str(found)
        try:
            return original_find(pkg)
        except Exception as err:  # ament not installed, or it does not know pkg
            raise URDFError(f"$(find {pkg}): no folder named '{pkg}' next to or above {directory}, in "
                            f"package_dirs or ROS_PACKAGE_PATH ({type(err).__name__}: {err}); pass "
                            f"package_dirs=[<folder that contains '{pkg}'>] (CLI: --package-dir)") from None

    def absolute(spec):
        if spec.startswith(("package://", "model://")):
            found = resolve_mesh_path(spec, directory=directory, package_dirs=package_dirs)
            if found is None:
                raise URDFError(f"<xacro:include filename=\"{spec}\">: not found next to or above {directory}, in "
                                "package_dirs or ROS_PACKAGE_PATH; pass package_dirs (CLI: --package-dir) or "
                                "correct the filename")
            return str(found)
        return original_abs(spec)

    subst._eval_find, xacro_module.abs_filename_spec = find, absolute
    try:
        yield
    finally:
        subst._eval_find, xacro_module.abs_filename_spec = original_find, original_abs


def expand_xacro(path, *, xacro_args=None, package_dirs=()) -> str:
    """The URDF text of the xacro file ``path`` expanded with ``xacro_args`` (dict name -> value)."""
    try:
        import xacro
        from xacro import substitution_args
    except ImportError:
        raise URDFError(f"{path}: is a xacro file; expanding it needs the xacro package: "
                        f"{XACRO_INSTALL} (or run `xacro {Path(path).name} > robot.urdf` and load the URDF)") from None
    path = Path(path)
    if not path.is_file():
        raise URDFError(f"{path}: the xacro file does not exist")
    args = {str(k): str(v) for k, v in (xacro_args or {}).items()}
    try:
        with _package_finder(xacro, substitution_args, path.resolve().parent, tuple(Path(p) for p in package_dirs)):
            doc = xacro.process_file(str(path), mappings=args)
    except URDFError:
        raise
    except Exception as err:  # xacro's own errors: XacroException, XML errors, NameError in ${...}
        what = str(err) or type(err).__name__
        raise URDFError(f"{path}: xacro could not expand the file ({type(err).__name__}: {what}); "
                        f"arguments given: {args or 'none'}") from None
    return doc.toprettyxml(indent="  ")

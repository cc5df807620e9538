"""Where robots are: the project's shipped ``robots/``, the optional example-robot-data corpus, and
the files a command is given (a path, or the name of a shipped robot or scene from any folder)."""

from __future__ import annotations

import re
import tomllib
from dataclasses import dataclass
from importlib.metadata import PackageNotFoundError, distribution
from pathlib import Path

__all__ = ["shipped_robots_dir", "example_robot_data_dir", "Shipped", "shipped", "find_input", "InputNotFound",
           "DESCRIPTION_SUFFIXES"]

#: Suffixes of the files a command reads: scenes, and robot descriptions.
DESCRIPTION_SUFFIXES = (".toml", ".urdf", ".xacro", ".xml")


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


@dataclass(frozen=True)
class Shipped:
    """A shipped robot (``.urdf``) or scene (``.toml``): its ``name`` (the file's stem, what a command
    takes from any folder), ``kind``, ``path`` and a one-line ``summary``."""

    name: str
    kind: str
    path: Path
    summary: str


def _robot_summaries(folder: Path) -> dict[str, str]:
    """``{file name: first sentence}`` of the robots' sections in ``robots/README.md``."""
    readme = folder / "README.md"
    if not readme.is_file():
        return {}
    out = {}
    text = readme.read_text()
    for m in re.finditer(r"^##+ `([\w./-]+\.urdf)`\s*\n+(.+?)(?:\n\n|\Z)", text, re.M | re.S):
        out[Path(m.group(1)).name] = _first_sentence(m.group(2))
    for m in re.finditer(r"^- `([\w./-]+\.urdf)`[^:]*:\s*(.+?)(?=\n- |\n\n|\Z)", text, re.M | re.S):
        out.setdefault(Path(m.group(1)).name, _first_sentence(m.group(2)))
        for other in re.findall(r"`([\w-]+\.urdf)`", m.group(0).split(":")[0]):
            out.setdefault(other, out[Path(m.group(1)).name])
    return out


def _first_sentence(text: str) -> str:
    text = " ".join(text.split())
    return re.split(r"(?<=[.:;])\s", text, maxsplit=1)[0].rstrip(":.;")


def shipped() -> list[Shipped]:
    """Every shipped robot and scene (``robots/`` and ``robots/hard/``), robots first, by name."""
    folder = shipped_robots_dir()
    summaries = _robot_summaries(folder)
    out = []
    for sub in (folder, folder / "hard"):
        for p in sorted(sub.glob("*.urdf")):
            out.append(Shipped(p.stem, "robot" if sub == folder else "robot (hard case)", p,
                               summaries.get(p.name, "")))
    for sub in (folder, folder / "hard"):
        for p in sorted(sub.glob("*.toml")):
            try:
                summary = str(tomllib.loads(p.read_text()).get("description", ""))
            except (OSError, tomllib.TOMLDecodeError):
                summary = ""
            out.append(Shipped(p.stem, "scene" if sub == folder else "scene (hard case)", p, summary))
    return out


class InputNotFound(FileNotFoundError):
    """A command's file is neither a path nor a shipped robot or scene; the message says where the
    shipped ones are and how to list them."""


def find_input(arg, *, kinds=("robot", "scene")) -> tuple[Path, str | None]:
    """``(path, note)`` of a command's file argument: an existing path as it is (note None); else the
    shipped robot or scene of that name (``ship_crane``, ``ur5_like.urdf``, or a path in the shipped
    layout like ``robots/ship_crane.toml`` given outside a checkout), with a note saying which file
    stands in; else :class:`InputNotFound` naming what was looked for and where the shipped ones are."""
    text = str(arg)
    path = Path(text).expanduser()
    if path.exists():
        return path, None
    stem = path.stem if path.suffix in DESCRIPTION_SUFFIXES else path.name
    wanted = [s for s in shipped() if s.name == stem and s.kind.split()[0] in kinds
              and (path.suffix not in DESCRIPTION_SUFFIXES or s.path.suffix == path.suffix)]
    layout = path.parent.as_posix() in (".", "robots", "robots/hard", "hard")
    if len(wanted) == 1 and layout:
        hit = wanted[0]
        note = None if path.parent.as_posix() == "." else (f"{text} is not a file here; using the shipped {hit.kind} "
                                                            f"{hit.name!r} ({hit.path})")
        return hit.path, note
    if len(wanted) > 1:
        raise InputNotFound(f"{text!r} names several shipped files ({', '.join(str(s.path) for s in wanted)}): "
                            "give the suffix (.urdf or .toml)")
    raise InputNotFound(f"no such file: {text!r} (looked in {Path.cwd()}); the shipped robots and scenes run by name "
                        f"from any folder (for example `urdf2links simulate ship_crane`, `urdf2links inspect "
                        f"ur5_like`); `urdf2links list` lists them (they are in {shipped_robots_dir()})")

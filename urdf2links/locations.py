"""Where robots are: the project's shipped ``robots/``, the optional example-robot-data corpus, and
the files a command is given (a path, or the name of a shipped robot or scene from any folder)."""

from __future__ import annotations

import re
import tomllib
from dataclasses import dataclass
from importlib.metadata import PackageNotFoundError, distribution
from pathlib import Path

__all__ = ["shipped_robots_dir", "example_robot_data_dir", "Shipped", "shipped", "find_input", "InputNotFound",
           "DESCRIPTION_SUFFIXES", "DEFAULT_OUT", "checkout_root", "report_scenes", "default_baselines",
           "REPORT_FOLDERS", "report_scene_files", "read_toml"]

#: Suffixes of the files a command reads: scenes, and robot descriptions.
DESCRIPTION_SUFFIXES = (".toml", ".urdf", ".xacro", ".xml")


def read_toml(path, *, error: type[Exception], what: str) -> dict:
    """The TOML file ``path`` (a scene file, a pairs file) as a dict; ``error`` (the reader's own error class)
    names ``what`` and the file when it does not exist or is not valid TOML."""
    path = Path(path)
    try:
        return tomllib.loads(path.read_text())
    except FileNotFoundError:
        raise error(f"{what} {path} does not exist") from None
    except tomllib.TOMLDecodeError as err:
        raise error(f"{path}: not valid TOML: {err}") from None


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
    for m in re.finditer(r"^##+ `([\w./-]+\.(?:urdf|xml))`\s*\n+(.+?)(?:\n\n|\Z)", text, re.M | re.S):
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
    """Every shipped robot and scene (``robots/``, ``robots/hard/`` and ``robots/loops/``), robots first, by name; then the pairs
    files of ``urdf2links report --pairs`` (``robots/pairs/``, kind ``pairs``)."""
    folder = shipped_robots_dir()
    summaries = _robot_summaries(folder)
    out = []
    kind = {folder: "", folder / "hard": " (hard case)", folder / "loops": " (closed loop)"}   # loops: issue 36
    for sub in kind:
        for p in sorted([*sub.glob("*.urdf"), *sub.glob("*.xml")]):
            out.append(Shipped(p.stem, "robot" + kind[sub] + (" (MJCF)" if p.suffix == ".xml" else ""), p,
                               summaries.get(p.name, "")))
    for sub in kind:
        for p in sorted(sub.glob("*.toml")):
            try:
                summary = str(tomllib.loads(p.read_text()).get("description", ""))
            except (OSError, tomllib.TOMLDecodeError):
                summary = ""
            out.append(Shipped(p.stem, "scene" + kind[sub], p, summary))
    for p in sorted((folder / "pairs").glob("*.toml")):      # pairs files of `report --pairs NAME`
        try:
            summary = str(tomllib.loads(p.read_text()).get("description", ""))
        except (OSError, tomllib.TOMLDecodeError):
            summary = ""
        out.append(Shipped(p.stem, "pairs", p, summary))
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
        note = None if path.parent.as_posix() == "." else (f"{text} is not a file here; using the shipped "
                                                            f"{hit.kind.split()[0]} {hit.name!r} ({hit.path})")
        return hit.path, note
    if len(wanted) > 1:
        raise InputNotFound(f"{text!r} names several shipped files ({', '.join(str(s.path) for s in wanted)}): "
                            "give the suffix (.urdf or .toml)")
    raise InputNotFound(f"no such file: {text!r} (looked in {Path.cwd()}); the shipped robots and scenes run by name "
                        f"from any folder (for example `urdf2links simulate ship_crane`, `urdf2links inspect "
                        f"ur5_like`); `urdf2links list` lists them (they are in {shipped_robots_dir()})")


#: Where commands write their reports unless told (``--out``): a scratch folder under the current one,
#: so that a checkout's committed ``reports/`` change only when asked (``--out reports``).
DEFAULT_OUT = Path("out") / "reports"


def checkout_root(start=None) -> Path | None:
    """The urdf2links checkout the current folder (or ``start``) is in: that folder or an ancestor holding
    a ``pyproject.toml`` of the project ``urdf2links`` and a ``robots/`` folder; None elsewhere."""
    here = Path(start or Path.cwd()).resolve()
    for folder in (here, *here.parents):
        py = folder / "pyproject.toml"
        if py.is_file() and (folder / "robots").is_dir():
            try:
                if tomllib.loads(py.read_text()).get("project", {}).get("name") == "urdf2links":
                    return folder
            except (OSError, tomllib.TOMLDecodeError):
                return None
    return None


#: The folders of ``robots/`` whose scenes ``urdf2links report`` runs: the shipped scenes and the closed loops
#: (issue 42); ``robots/hard/`` is run by its own tests and docs/hard-cases.md.
REPORT_FOLDERS = ("", "loops")


def report_scene_files(folder: Path) -> list[Path]:
    """The scene files ``urdf2links report`` runs in the robots folder ``folder`` (:data:`REPORT_FOLDERS`)."""
    return [p for sub in REPORT_FOLDERS for p in sorted((folder / sub).glob("*.toml"))]


def report_scenes() -> tuple[list[Path], str]:
    """``(scene files, where)`` that ``urdf2links report`` runs by default: a checkout's own
    ``robots/*.toml`` and ``robots/loops/*.toml`` when run inside one (an edit there counts without
    reinstalling), else the installed package's; ``where`` says which, for the run's first line."""
    root = checkout_root()
    if root is not None:
        return report_scene_files(root / "robots"), f"robots/*.toml and robots/loops/*.toml of the checkout {root}"
    folder = shipped_robots_dir()
    return report_scene_files(folder), f"the shipped scenes installed with urdf2links ({folder}, loops/ included)"


def default_baselines(out: Path, *, sub: str = "") -> tuple[Path | None, list[Path]]:
    """``(baselines file or None, the places looked at)`` for a report written to ``out``:
    ``<out>/baselines.json``, then a checkout's committed ``reports/<sub>/baselines.json``."""
    looked = [Path(out) / "baselines.json"]
    root = checkout_root()
    if root is not None:
        looked.append(root / "reports" / sub / "baselines.json" if sub else root / "reports" / "baselines.json")
    for p in dict.fromkeys(looked):
        if p.is_file():
            return p, looked
    return None, looked

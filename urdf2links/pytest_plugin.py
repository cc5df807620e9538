"""The pytest plugin of ``urdf2links check`` (the ``pytest11`` entry point ``urdf2links``).

Active when the repository pytest runs in is configured for ``urdf2links check`` (``urdf2links.toml``, or a
``[tool.urdf2links]`` table in ``pyproject.toml``, in pytest's root folder or above it up to the repository's
root) and pytest was started without file arguments, or whenever ``pytest --urdf2links`` asks. Then every robot,
pair and scene of the configuration is one test item beside the repository's own tests, named after its
file: ``robots/arm.urdf::robot``, ``robots/arm.xml::pair[robots/arm.urdf]``, ``scenes/swing.toml::scene``,
``robots/arm.urdf::default_scene``. A failure says the file, the link or joint, the value and the tolerance
(:mod:`urdf2links.compare.check.cases`). Elsewhere -- urdf2links' own repository included -- it adds nothing
and imports nothing beyond this module (no MuJoCo).
"""

from __future__ import annotations

import tomllib
from pathlib import Path

import pytest

_ROOT = pytest.StashKey[Path]()
_NAMES = ("urdf2links.toml", "pyproject.toml")


def pytest_addoption(parser):
    group = parser.getgroup("urdf2links", "urdf2links check: robots, pairs and scenes as tests")
    group.addoption("--urdf2links", action="store_true", default=False,
                    help="run the robots, pairs and scenes of urdf2links.toml / [tool.urdf2links] as tests (the "
                         "default when pytest runs without file arguments in a repository configured for them)")


def _configured(folder: Path) -> bool:
    """Whether ``folder`` or a folder above it, up to the repository's root, configures ``urdf2links check``."""
    for here in (folder, *folder.parents):
        if (here / _NAMES[0]).is_file():
            return True
        py = here / _NAMES[1]
        if py.is_file():
            try:
                if "urdf2links" in tomllib.loads(py.read_text()).get("tool", {}):
                    return True
            except (OSError, tomllib.TOMLDecodeError):
                pass
        if (here / ".git").exists():
            return False
    return False


def pytest_configure(config):
    asked = config.getoption("--urdf2links")
    plain = config.args_source != pytest.Config.ArgsSource.ARGS   # no file arguments: the whole suite
    root = Path(config.rootpath)
    if asked or (plain and _configured(root)):
        config.stash[_ROOT] = root


class CheckFailed(Exception):
    """A case that did not pass; carries its result."""

    def __init__(self, result):
        super().__init__(result.message())
        self.result = result


class CheckItem(pytest.Item):
    """One robot, pair or scene of the configuration (or the configuration itself, when it cannot be read)."""

    def __init__(self, *, case=None, ctx=None, problem: str | None = None, **kw):
        super().__init__(**kw)
        self.case, self.ctx, self.problem = case, ctx, problem

    def runtest(self):
        if self.problem is not None:
            raise CheckFailed(_Unusable(self.problem))
        from urdf2links.compare.check.cases import run_case

        result = run_case(self.case, self.ctx)
        if result.status != "pass":
            raise CheckFailed(result)

    def repr_failure(self, excinfo, style=None):
        if isinstance(excinfo.value, CheckFailed):
            return excinfo.value.result.message()
        return super().repr_failure(excinfo, style=style)

    def reportinfo(self):
        what = f"{self.case.kind} {self.case.name}" if self.case is not None else "configuration"
        return self.path, None, f"urdf2links check: {what}"


class _Unusable:
    def __init__(self, text: str):
        self.text = text

    def message(self) -> str:
        return self.text


class CheckFile(pytest.File):
    """The file a robot, pair or scene is named after; its items are given, not read from it."""

    def __init__(self, *, specs=(), **kw):
        super().__init__(**kw)
        self.specs = list(specs)

    def collect(self):
        return [CheckItem.from_parent(self, name=name, **spec) for name, spec in self.specs]


def _item_name(case) -> str:
    if case.kind == "pair":
        return f"pair[{case.entry.urdf.id}]"
    if case.kind == "scene":
        return "scene" if case.entry.path is not None else "default_scene"
    return "robot"


def _collect(session, root: Path) -> list:
    from urdf2links.compare.check.cases import RunContext, cases_of
    from urdf2links.compare.check.config import ConfigError, read_config
    from urdf2links.compare.reports.baselines import load_baselines

    try:
        config = read_config(root)
        baselines = load_baselines(config.baselines) if config.baselines.is_file() else None
    except (ConfigError, OSError, ValueError) as exc:
        path = root / _NAMES[0] if (root / _NAMES[0]).is_file() else root / _NAMES[1]
        f = CheckFile.from_parent(session, path=path, specs=[("configuration", {"problem": str(exc)})])
        return f.collect()
    ctx = RunContext(baselines, str(config.baselines.name), config.factor)
    files: dict[Path, list] = {}
    for case in cases_of(config):
        files.setdefault(config.root / case.file, []).append((_item_name(case), {"case": case, "ctx": ctx}))
    items = []
    for path, specs in files.items():
        items += CheckFile.from_parent(session, path=path, specs=specs).collect()
    return items


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(session, config, items):
    """The configuration's checks joined to the collected tests (before -k and -m select among them)."""
    root = config.stash.get(_ROOT, None)
    if root is not None:
        items.extend(_collect(session, root))

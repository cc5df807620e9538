"""The subpackages are layers, and every import goes downward (docs/layout.md, "Layers").

Each module of ``urdf2links/`` and ``compare/`` belongs to one layer of :data:`LAYERS`; a module may
import modules of its own layer and of the layers below it, never above. Every import statement
counts, also those inside functions (a lazy import that goes the wrong way is still a dependency
the wrong way). The test walks the source with :mod:`ast`, so it needs no import of the package.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

#: Bottom to top: (layer name, module prefixes). A module's layer is its longest matching prefix;
#: ``urdf2links`` itself (the public API, re-exported) matches only the package's ``__init__``.
LAYERS = [
    ("base", ("urdf2links.errors", "urdf2links.ranges", "urdf2links.console", "urdf2links.locations",
              "urdf2links.numba_cache", "urdf2links.compilation", "urdf2links.robots")),
    ("dynamics", ("urdf2links.dynamics",)),
    ("parsers", ("urdf2links.parsers",)),
    ("robot logs", ("urdf2links.robot_logs",)),
    ("scenes", ("urdf2links.scenes",)),
    ("integration", ("urdf2links.integration",)),
    ("identification", ("urdf2links.identification",)),
    ("view", ("urdf2links.view",)),
    ("api", ("urdf2links",)),
    ("compare: shared output", ("urdf2links.compare.formatting", "urdf2links.compare.figures")),
    ("compare: MuJoCo side", ("urdf2links.compare.mujoco_side",)),
    ("compare: agreement", ("urdf2links.compare.agreement",)),
    ("compare: tradeoff", ("urdf2links.compare.tradeoff",)),
    ("compare: reports", ("urdf2links.compare.reports",)),
    ("compare: pairs", ("urdf2links.compare.pairs",)),
    ("compare: corpus", ("urdf2links.compare.corpus",)),
    ("compare: check", ("urdf2links.compare.check",)),
    ("compare: identify", ("urdf2links.compare.identify",)),
    ("compare: commands", ("urdf2links.compare", "urdf2links.compare.commands")),
    ("command line", ("urdf2links.cli", "urdf2links.commands", "urdf2links.__main__", "urdf2links.pytest_plugin")),
]
EXACT = {"urdf2links", "urdf2links.compare"}    # prefixes that match only themselves


def layer_of(module: str) -> int | None:
    """Index in :data:`LAYERS` of ``module`` (a dotted name under urdf2links), or None outside."""
    best, best_len = None, -1
    for i, (_name, prefixes) in enumerate(LAYERS):
        for p in prefixes:
            hit = module == p or (p not in EXACT and module.startswith(p + "."))
            if hit and len(p) > best_len:
                best, best_len = i, len(p)
    return best


def module_name(path: Path) -> str:
    rel = path.relative_to(ROOT).with_suffix("")
    parts = list(rel.parts)
    if parts[0] == "compare":
        parts = ["urdf2links", "compare"] + parts[1:]
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def imports_of(source: str, module: str, *, is_package: bool) -> list[tuple[int, str]]:
    """``(line, imported module)`` of every import in ``source`` that names a urdf2links module;
    ``from pkg import name`` counts as ``pkg.name`` when that is a module, else as ``pkg``."""
    package = module if is_package else module.rsplit(".", 1)[0]
    out = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            out += [(node.lineno, a.name) for a in node.names if a.name.split(".")[0] == "urdf2links"]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if target.split(".")[0] != "urdf2links":
                continue
            for a in node.names:
                sub = f"{target}.{a.name}"
                out.append((node.lineno, sub if sub in ALL_MODULES else target))
    return out


def _sources() -> dict[str, Path]:
    found = {}
    for top in ("urdf2links", "compare"):
        for p in sorted((ROOT / top).rglob("*.py")):
            found[module_name(p)] = p
    return found


SOURCES = _sources()
ALL_MODULES = set(SOURCES) | {"urdf2links.robots"}


def wrong_way(module: str, source: str, *, is_package: bool) -> list[str]:
    """The imports of ``module`` that go up the layers, as messages."""
    own = layer_of(module)
    bad = []
    for line, target in imports_of(source, module, is_package=is_package):
        theirs = layer_of(target)
        if theirs is not None and theirs > own:
            bad.append(f"{module} (layer {LAYERS[own][0]!r}) line {line} imports {target} "
                       f"(layer {LAYERS[theirs][0]!r}, above it)")
    return bad


def test_every_module_has_a_layer():
    assert [m for m in SOURCES if layer_of(m) is None] == []


@pytest.mark.parametrize("module", sorted(SOURCES))
def test_imports_go_downward(module):
    path = SOURCES[module]
    assert wrong_way(module, path.read_text(), is_package=path.name == "__init__.py") == []


@pytest.mark.parametrize("module, planted", [
    ("urdf2links.dynamics.model", "from ..scenes.plan import compile_plan"),          # dynamics -> scenes
    ("urdf2links.dynamics.kernels", "def f():\n    from urdf2links.view import animation\n"),   # lazy, absolute
    ("urdf2links.parsers.importer", "from ..integration import simulate"),           # parsers -> integration
    ("urdf2links.scenes.scene", "from ..integration.integrators import METHODS"),    # the import issue 21 removed
    ("urdf2links.integration.simulate", "import urdf2links.compare.agreement.trajectory"),
    ("urdf2links.compare.mujoco_side.mjcf", "from ..reports.report import write_report"),
    ("urdf2links.compare.tradeoff.study", "from ..corpus import rows"),
    ("urdf2links.compare.corpus.rows", "from ..check.config import read_config"),       # corpus -> check
    ("urdf2links.scenes.scene_toml", "from ..commands.options import INPUT"),           # scenes -> command line
    ("urdf2links.robot_logs.checks", "from ..scenes.functions import SumOfSines"),       # robot logs -> scenes
    ("urdf2links.compare.commands", "def f():\n    from urdf2links.commands import run\n"),   # compare -> command line
])
def test_a_planted_wrong_way_import_is_caught(module, planted):
    """The check fails on an import that goes up: each planted line added to a real module."""
    path = SOURCES[module]
    source = path.read_text() + "\n" + planted + "\n"
    found = wrong_way(module, source, is_package=False)
    assert len(found) == 1, found


def test_only_the_command_line_imports_compare():
    """Nothing under urdf2links/ but the command line (and the pytest plugin of ``urdf2links check``, lazily,
    when it is active) reaches the MuJoCo side."""
    offenders = []
    for module, path in SOURCES.items():
        if module.startswith(("urdf2links.compare", "urdf2links.commands")) or module in (
                "urdf2links.cli", "urdf2links.__main__", "urdf2links.pytest_plugin"):
            continue
        for line, target in imports_of(path.read_text(), module, is_package=path.name == "__init__.py"):
            if target.startswith("urdf2links.compare"):
                offenders.append(f"{module}:{line} imports {target}")
    assert offenders == []

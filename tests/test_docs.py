"""The documents travel with the code: README.md and docs/*.md link only files that exist, and the
source paths they name in backticks exist (a moved module breaks this test, not the reader)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PAGES = [ROOT / "README.md", ROOT / "robots" / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
LINK = re.compile(r"\]\(([^)#\s]+)(?:#[^)]*)?\)")
PATH = re.compile(r"`((?:urdf2links|compare|benchmarks|tests|robots|docs|reports)/[\w/.-]+\.(?:py|md|toml|urdf|json))`")


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_links_and_paths_resolve(page):
    text = page.read_text()
    missing = []
    for target in LINK.findall(text):
        if re.match(r"[a-z]+:", target):          # http(s), mailto: not ours to check
            continue
        if not (page.parent / target).exists():
            missing.append(f"link {target}")
    for path in PATH.findall(text):
        if "<" in path or "*" in path:
            continue
        if not (ROOT / path).exists():
            missing.append(f"path {path}")
    assert not missing, f"{page.relative_to(ROOT)} names what does not exist: {missing}"


def test_docs_do_not_point_outside_the_repository():
    """A clone has no ../shared: the project's documents must not send readers there."""
    for page in PAGES:
        assert "../shared" not in page.read_text() and "DESIGN.md" not in page.read_text(), page


# -- code names ------------------------------------------------------------------------------------
CODE = re.compile(r"`([A-Za-z_][\w]*(?:\.[A-Za-z_][\w]*)+)(?:\(\))?`")
FILE_SUFFIXES = {"html", "json", "md", "png", "csv", "npz", "toml", "urdf", "xml", "py", "txt", "js", "css", "dae",
                 "stl", "obj", "xacro", "whl", "cfg", "yaml", "log", "svg", "so", "nbi", "nbc", "gz", "zip", "TXT"}


def _modules() -> dict[str, list[str]]:
    """basename -> dotted names of every module of urdf2links (compare included)."""
    out: dict[str, list[str]] = {}
    for top, prefix in (("urdf2links", "urdf2links"), ("compare", "urdf2links.compare")):
        for p in (ROOT / top).rglob("*.py"):
            rel = p.relative_to(ROOT / top).with_suffix("").parts
            parts = [prefix, *rel[:-1]] + ([] if rel[-1] == "__init__" else [rel[-1]])
            out.setdefault(parts[-1], []).append(".".join(parts))
    return out


def _resolves(name: str, modules: dict[str, list[str]]) -> bool | None:
    """True/False when ``name`` is a code name of the project (found or not); None when it is not
    one of ours (another library's, a file name)."""
    import importlib

    import urdf2links

    parts = name.split(".")
    if parts[-1] in FILE_SUFFIXES:
        return None
    if parts[0] == "urdf2links":
        candidates = [(".".join(parts[:k]), parts[k:]) for k in range(len(parts), 0, -1)]
    elif parts[0] in modules:
        candidates = [(m, parts[1:]) for m in modules[parts[0]]]
    elif parts[0] in urdf2links.__all__ or parts[0] in ("Plan", "Scene", "Trajectory", "SceneComparison"):
        candidates = [("urdf2links", parts)] + [(m, parts) for m in ("urdf2links.scenes", "urdf2links.integration",
                                                                     "urdf2links.compare")]
    else:
        return None
    for module, rest in candidates:
        try:
            obj = importlib.import_module(module)
        except ImportError:
            continue
        if _has_path(obj, rest):
            return True
    return False


def _has_path(obj, rest) -> bool:
    """``obj.rest[0].rest[1]...`` exists; a class's instance attribute (``self.name = ...`` in its
    source, or a dataclass field) counts."""
    import dataclasses
    import inspect

    for k, attr in enumerate(rest):
        if hasattr(obj, attr):
            obj = getattr(obj, attr)
            continue
        if inspect.isclass(obj) and k == len(rest) - 1:
            fields = {f.name for f in dataclasses.fields(obj)} if dataclasses.is_dataclass(obj) else set()
            return attr in fields or re.search(rf"self\.{attr}\b\s*(?::[^=]*)?=", inspect.getsource(obj)) is not None
        return False
    return True


def _json_keys() -> set[str]:
    """Dotted key paths of the committed JSON reports (``terms.route1``, ``trajectory.max_abs_error``):
    the documents cite them too, and they are not code."""
    import json

    keys: set[str] = set()

    def walk(x, prefix):
        if isinstance(x, dict):
            for k, v in x.items():
                path = f"{prefix}.{k}" if prefix else str(k)
                keys.add(path)
                walk(v, path)
        elif isinstance(x, list) and x:
            walk(x[0], prefix)

    for f in (ROOT / "reports").rglob("*.json"):
        data = json.loads(f.read_text())
        walk(data, "")
        for row in data.get("rows", []) if isinstance(data, dict) else []:
            walk(row, "")
    return keys


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_code_names_exist(page):
    """Every ``module.name`` a document cites in backticks (``tree_arrays.flat_tree``,
    ``urdf2links.integration.simulate.simulate``, ``Model.forward_dynamics``) exists."""
    modules, keys = _modules(), _json_keys()
    missing = sorted({n for n in CODE.findall(page.read_text()) if n not in keys and _resolves(n, modules) is False})
    assert not missing, f"{page.relative_to(ROOT)} cites code that does not exist: {missing}"


def test_equation_labels_exist():
    """Every (En) the code and the documents cite is a label of docs/equations.md, and a range
    "(E1)-(En)" names the last one."""
    eqs = (ROOT / "docs" / "equations.md").read_text()
    labels = {int(x) for x in re.findall(r"\(E(\d+)\)", eqs)}
    last = max(labels)
    texts = [p for p in PAGES] + [p for top in ("urdf2links", "compare") for p in (ROOT / top).rglob("*.py")]
    bad = []
    for p in texts:
        text = p.read_text()
        bad += [f"{p.relative_to(ROOT)}: (E{k})" for k in map(int, re.findall(r"\(E(\d+)\)", text)) if k not in labels]
    for p in PAGES:      # "labelled (E1)-(En)" in a document: all of them
        bad += [f"{p.relative_to(ROOT)}: (E1)-(E{k}), the last is (E{last})"
                for k in map(int, re.findall(r"\(E1\)\s*[-–]\s*\(E(\d+)\)", p.read_text())) if k != last]
    assert not bad, bad

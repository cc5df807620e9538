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

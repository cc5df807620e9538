"""The CI workflow of ``urdf2links check --write-workflow``: one GitHub Actions file a repository copies.

It installs urdf2links from its source at a pinned commit (or a path in the repository), on a pinned Python,
keeps numba's cache folder (``URDF2LINKS_CACHE_DIR``, :mod:`urdf2links.numba_cache`) between runs so that the
compiled kernels are compiled once, runs the check (on a pull request only what the change touches,
``--changed-since`` the base branch), uploads the JUnit and Markdown reports, adds the summary to the run's page
and, in a job of its own that alone may write, posts it on a pull request from the same repository (a fork's
token is read-only). docs/ci.md shows the text and why.

Where urdf2links comes from (:class:`Source`), in this order:

- ``--from GIT_URL@COMMIT`` (a full commit hash: a branch or a tag can move) or ``--from PATH`` (a checkout in
  the repository, e.g. a git submodule; or an absolute path, for a self-hosted runner that has it);
- else this installation's own source: pip's record of a VCS install (``direct_url.json``, PEP 610: the URL
  and the commit installed), or the git checkout this urdf2links runs from (its ``origin`` remote and its
  ``HEAD``), when that remote is a URL a runner can reach;
- else a placeholder, marked ``SET-ME``, that the install step refuses with a message until it is set.

The package's name is never looked up on an index: no index serves urdf2links, and a package registered
there under that name by someone else would be installed and run with the repository's token.
"""

from __future__ import annotations

import json
import re
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

__all__ = ["WORKFLOW_PATH", "PLACEHOLDER", "Source", "source_from", "derived_source", "workflow_text",
           "write_workflow"]

#: Where ``--write-workflow`` puts it, relative to the repository's root.
WORKFLOW_PATH = ".github/workflows/urdf2links-check.yml"
#: The install source written when none is given or derivable: the install step refuses it.
PLACEHOLDER = "SET-ME: urdf2links @ git+https://github.com/OWNER/urdf2links@FULL_COMMIT_HASH"
_COMMIT = re.compile(r"[0-9a-f]{40}([0-9a-f]{24})?")       # SHA-1, or SHA-256 object names

_TEMPLATE = """\
# urdf2links check: the robots, pairs and scenes of urdf2links.toml (or [tool.urdf2links]) on every change.
# Written by `urdf2links check --write-workflow` (docs/ci.md).
name: urdf2links check
on:
  push:
    branches: [main]
  pull_request:
permissions: {}                     # each job asks for what it needs
env:
  # urdf2links from its repository at a pinned commit (pip's `name @ git+URL@COMMIT`), or a path in this
  # repository: never by name from a package index.__NOTE__
  URDF2LINKS_SOURCE: "__SOURCE__"
  PYTHON_VERSION: "__PYTHON__"      # the Python the configuration was accepted with
jobs:
  check:
    runs-on: ubuntu-latest
    permissions:
      contents: read
    env:
      URDF2LINKS_CACHE_DIR: ${{ github.workspace }}/.urdf2links-cache
    defaults:
      run:
        shell: bash
    steps:
      - uses: actions/checkout@v4
        with:
          fetch-depth: 0            # --changed-since needs the base branch's history
      - uses: actions/setup-python@v5
        with:
          python-version: ${{ env.PYTHON_VERSION }}
      - name: Install urdf2links
        run: |
          case "$URDF2LINKS_SOURCE" in
            SET-ME*)
              echo "::error::set URDF2LINKS_SOURCE in this workflow to urdf2links' repository at a commit (docs/ci.md)"
              exit 1 ;;
          esac
          python -m pip install "$URDF2LINKS_SOURCE"
      - name: Cache numba's compiled kernels
        uses: actions/cache@v4
        with:
          path: ${{ env.URDF2LINKS_CACHE_DIR }}
          key: urdf2links-numba-${{ runner.os }}-py${{ env.PYTHON_VERSION }}-${{ hashFiles('**/urdf2links.toml', '**/pyproject.toml') }}
          restore-keys: urdf2links-numba-${{ runner.os }}-py${{ env.PYTHON_VERSION }}-
      - name: Run the check
        env:
          BASE_REF: ${{ github.base_ref }}      # set on pull requests only
        run: |
          since=()
          if [ -n "$BASE_REF" ]; then
            since=(--changed-since "origin/$BASE_REF")
          fi
          urdf2links check "${since[@]}" --jobs 2 --junit urdf2links-check.xml --markdown urdf2links-check.md
      - name: Add the summary to the run's page
        if: always()
        run: if [ -f urdf2links-check.md ]; then cat urdf2links-check.md >> "$GITHUB_STEP_SUMMARY"; fi
      - name: Upload the reports
        if: always()
        uses: actions/upload-artifact@v4
        with:
          name: urdf2links-check
          path: |
            urdf2links-check.xml
            urdf2links-check.md
  comment:
    # only where the token can write: a pull request from a branch of this repository (a fork's token is read-only)
    needs: check
    if: always() && github.event_name == 'pull_request' && github.event.pull_request.head.repo.full_name == github.repository
    runs-on: ubuntu-latest
    permissions:
      pull-requests: write
    steps:
      - uses: actions/download-artifact@v4
        continue-on-error: true     # no reports when the check could not start: nothing to post
        with:
          name: urdf2links-check
      - name: Post the summary on the pull request
        env:
          GH_TOKEN: ${{ github.token }}
          GH_REPO: ${{ github.repository }}
          PR: ${{ github.event.pull_request.number }}
        run: |
          test -f urdf2links-check.md || exit 0
          gh pr comment "$PR" --body-file urdf2links-check.md --edit-last \\
            || gh pr comment "$PR" --body-file urdf2links-check.md
"""


@dataclass(frozen=True)
class Source:
    """Where the workflow installs urdf2links from: ``requirement`` (what ``pip install`` is given), ``how`` (where
    it was found, for the command's message), ``placeholder`` (nothing was found: the user must set it)."""

    requirement: str
    how: str
    placeholder: bool = False


def _git_url(url: str) -> str | None:
    """A remote URL pip can clone on a runner (``https://``, ``ssh://``, ``git://``, ``http://``), scp-like
    ``user@host:path`` as https; None for a local path or a ``file://`` URL."""
    url = url.strip().removeprefix("git+")
    scp = re.fullmatch(r"[\w.-]+@([\w.-]+):(?!//)(.+)", url)
    if scp:
        return f"https://{scp.group(1)}/{scp.group(2)}"
    return url if re.match(r"(https?|ssh|git)://", url) else None


def source_from(text: str, *, root) -> Source:
    """``--from``: ``GIT_URL@COMMIT`` (``git+`` optional; the commit a full hash) or a path holding urdf2links'
    ``pyproject.toml`` (relative to the current folder; written relative to the repository ``root`` when inside
    it). ValueError says what is wrong."""
    path = Path(text).expanduser()
    if not re.match(r"(git\+)?[a-z]+://|[\w.-]+@[\w.-]+:", text):
        project = path / "pyproject.toml"
        if not project.is_file() or not re.search(r'(?m)^name\s*=\s*"urdf2links"', project.read_text()):
            raise ValueError(f"--from {text}: not a git URL@COMMIT, and not a folder whose pyproject.toml is "
                             "urdf2links' (give the repository's URL at a full commit hash, or a checkout's folder)")
        full, root = path.resolve(), Path(root).resolve()
        shown = f"./{full.relative_to(root).as_posix()}" if full.is_relative_to(root) else str(full)
        return Source(shown, "--from (a path)")
    url, _, commit = text.rpartition("@")
    if not url or not _COMMIT.fullmatch(commit):
        raise ValueError(f"--from {text}: pin a full commit hash after '@' (40 hex digits; a branch or a tag can "
                         "move): e.g. https://github.com/OWNER/urdf2links@$(git rev-parse HEAD)")
    if url.removeprefix("git+").startswith("file://"):     # file:///x as file://localhost/x: pip's parser wants a host
        local = re.sub(r"^file:///", "file://localhost/", url.removeprefix("git+"))
        return Source(f"urdf2links @ git+{local}@{commit}", "--from (a local repository)")
    remote = _git_url(url)
    if remote is None:
        raise ValueError(f"--from {text}: {url!r} is not a git URL (https://, ssh://, git:// or user@host:path)")
    return Source(f"urdf2links @ git+{remote}@{commit}", "--from")


def _git(folder: Path, *args: str) -> str | None:
    try:
        out = subprocess.run(["git", "-C", str(folder), *args], capture_output=True, text=True, timeout=30)
    except (OSError, subprocess.TimeoutExpired):
        return None
    return out.stdout.strip() if out.returncode == 0 else None


def derived_source() -> Source:
    """The source of the urdf2links running now (module doc), or the placeholder."""
    import importlib.metadata

    try:
        direct = json.loads(importlib.metadata.distribution("urdf2links").read_text("direct_url.json") or "{}")
    except (importlib.metadata.PackageNotFoundError, ValueError):
        direct = {}
    vcs = direct.get("vcs_info", {})
    if vcs.get("vcs") == "git" and vcs.get("commit_id") and _git_url(direct.get("url", "")):
        return Source(f"urdf2links @ git+{_git_url(direct['url'])}@{vcs['commit_id']}", "pip's record of this install")
    here = Path(__file__).resolve().parents[2]          # the checkout of an editable install (compare/ is in it)
    top = _git(here, "rev-parse", "--show-toplevel")
    if top and (Path(top) / "pyproject.toml").is_file():
        remote, head = _git(here, "remote", "get-url", "origin"), _git(here, "rev-parse", "HEAD")
        url = _git_url(remote or "")
        if url and head:
            dirty = _git(here, "status", "--porcelain")
            said = " (its work tree has changes that commit does not hold)" if dirty else ""
            return Source(f"urdf2links @ git+{url}@{head}", f"this checkout's origin at HEAD{said}")
    return Source(PLACEHOLDER, "nowhere: set it in the file, or give --from", placeholder=True)


def workflow_text(source: Source, *, python: str | None = None) -> str:
    """The workflow installing ``source`` on Python ``python`` (default: the one running, major.minor)."""
    python = python or f"{sys.version_info.major}.{sys.version_info.minor}"
    note = ("\n  # SET-ME: replace the value below (docs/ci.md); the install step refuses it until then"
            if source.placeholder else "")
    return (_TEMPLATE.replace("__NOTE__", note).replace("__SOURCE__", source.requirement)
            .replace("__PYTHON__", python))


def write_workflow(folder, path: str | None = None, *, source: str | None = None) -> tuple[Path, Source]:
    """Write the workflow (:func:`workflow_text`) to ``folder/.github/workflows/urdf2links-check.yml`` (or
    ``path``), installing from ``source`` (``--from``, :func:`source_from`) or :func:`derived_source`; refuses
    to replace a different file there (ValueError). Returns the file and the source written."""
    src = source_from(source, root=folder) if source else derived_source()
    text = workflow_text(src)
    target = Path(path) if path else Path(folder) / WORKFLOW_PATH
    if target.is_file() and target.read_text() != text:
        raise ValueError(f"--write-workflow: {target} exists and differs; remove it first (or give another FILE)")
    target.parent.mkdir(parents=True, exist_ok=True)
    target.write_text(text)
    return target, src

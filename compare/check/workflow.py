"""The CI workflow of ``urdf2links check --write-workflow``: one GitHub Actions file a repository copies.

It installs urdf2links, keeps numba's cache folder (``URDF2LINKS_CACHE_DIR``, :mod:`urdf2links.numba_cache`)
between runs so that the compiled kernels are compiled once, runs the check (on a pull request only what the
change touches, ``--changed-since`` the base branch), uploads the JUnit and Markdown reports, adds the summary to
the run's page and posts it on the pull request. docs/ci.md shows the same text (a test keeps them equal).
"""

from __future__ import annotations

from pathlib import Path

__all__ = ["WORKFLOW", "WORKFLOW_PATH", "write_workflow"]

#: Where ``--write-workflow`` puts it, relative to the repository's root.
WORKFLOW_PATH = ".github/workflows/urdf2links-check.yml"

WORKFLOW = """\
# urdf2links check: the robots, pairs and scenes of urdf2links.toml (or [tool.urdf2links]) on every change.
# Written by `urdf2links check --write-workflow` (docs/ci.md).
name: urdf2links check
on:
  push:
    branches: [main]
  pull_request:
permissions:
  contents: read
  pull-requests: write
jobs:
  check:
    runs-on: ubuntu-latest
    env:
      URDF2LINKS_CACHE_DIR: ${{ github.workspace }}/.urdf2links-cache
    steps:
      - uses: actions/checkout@v4
        with:
          fetch-depth: 0            # --changed-since needs the base branch's history
      - uses: actions/setup-python@v5
        with:
          python-version: "3.12"
      - name: Install urdf2links
        run: python -m pip install urdf2links
      - name: Cache numba's compiled kernels
        uses: actions/cache@v4
        with:
          path: ${{ env.URDF2LINKS_CACHE_DIR }}
          key: urdf2links-numba-${{ runner.os }}-${{ hashFiles('**/urdf2links.toml', '**/pyproject.toml') }}
          restore-keys: urdf2links-numba-${{ runner.os }}-
      - name: Run the check
        run: |
          since=""
          if [ "${{ github.event_name }}" = "pull_request" ]; then
            since="--changed-since origin/${{ github.base_ref }}"
          fi
          urdf2links check $since --jobs 2 --junit urdf2links-check.xml --markdown urdf2links-check.md
      - name: Add the summary to the run's page
        if: always()
        run: test -f urdf2links-check.md && cat urdf2links-check.md >> "$GITHUB_STEP_SUMMARY" || true
      - name: Upload the reports
        if: always()
        uses: actions/upload-artifact@v4
        with:
          name: urdf2links-check
          path: |
            urdf2links-check.xml
            urdf2links-check.md
      - name: Post the summary on the pull request
        if: always() && github.event_name == 'pull_request'
        env:
          GH_TOKEN: ${{ github.token }}
        run: |
          test -f urdf2links-check.md || exit 0
          gh pr comment ${{ github.event.pull_request.number }} --body-file urdf2links-check.md --edit-last \\
            || gh pr comment ${{ github.event.pull_request.number }} --body-file urdf2links-check.md
"""


def write_workflow(folder, path: str | None = None) -> Path:
    """Write :data:`WORKFLOW` to ``folder/.github/workflows/urdf2links-check.yml`` (or ``path``); refuses to
    replace a different file there (ValueError)."""
    target = Path(path) if path else Path(folder) / WORKFLOW_PATH
    if target.is_file() and target.read_text() != WORKFLOW:
        raise ValueError(f"--write-workflow: {target} exists and differs; remove it first (or give another FILE)")
    target.parent.mkdir(parents=True, exist_ok=True)
    target.write_text(WORKFLOW)
    return target

"""Every command line of the README's Commands table runs from an empty folder (issue 22).

A user installs with ``pip install .`` and works in a folder of their own: the shipped robots and
scenes must run by name there, and what the table says a command writes must be there afterwards.
Each line runs as written, with one addition so that the suite stays short: a short ``--t-end``
where the command takes one and the line sets none (the length of a run changes no code path the
line demonstrates). The outputs the table names in backticks (``out/...``) are checked to exist.
Each line runs in this process (tests/cli_runner.py: what a subprocess would show, without paying
Python's start and numba's cache loading again per line); the installed command itself starts in
tests/test_packaging.py's fresh environments.
"""

from __future__ import annotations

import os
import re
import shlex
from pathlib import Path

import pytest

from cli_runner import run_cli

ROOT = Path(__file__).resolve().parents[1]


def _table_rows() -> list[tuple[str, str]]:
    """``(command, what it does)`` of each row of the README's Commands table."""
    text = (ROOT / "README.md").read_text()
    section = text.split("## Commands", 1)[1].split("\n## ", 1)[0]
    rows = []
    for line in section.splitlines():
        m = re.match(r"\|\s*`(urdf2links [^`]+)`\s*\|(.*)\|\s*$", line)
        if m:
            rows.append((m.group(1), m.group(2)))
    return rows


ROWS = _table_rows()
#: the short run added where a line sets no length (s); the corpus runs ~70 robots, so shorter still
SHORT = {"report --corpus": "0.005"}


def _argv(command: str) -> list[str]:
    argv = shlex.split(command)
    if "--t-end" not in argv and argv[1] in ("simulate", "compare", "report", "sweep", "tradeoff"):
        key = "report --corpus" if "--corpus" in argv else argv[1]
        argv += ["--t-end", SHORT.get(key, "0.05")]
    if "--corpus" in argv:
        argv += ["--no-thumbnails"]
    return argv


def test_the_table_has_the_commands():
    commands = {shlex.split(c)[1] for c, _ in ROWS}
    assert {"list", "inspect", "simulate", "compare", "report", "sweep", "tradeoff"} <= commands, commands


@pytest.mark.parametrize("command, what", ROWS, ids=[c for c, _ in ROWS])
def test_a_readme_command_runs_from_an_empty_folder(command, what, tmp_path):
    argv = _argv(command)
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    out = run_cli(*argv[1:], cwd=tmp_path, env=env)
    assert out.returncode == 0, f"{' '.join(argv)}\n{out.stderr[-3000:]}"
    assert "Traceback" not in out.stderr
    for path in re.findall(r"`(out/[^`\s]+)`", what):
        assert (tmp_path / path).exists(), f"{command}: the README says it writes {path}; {sorted(os.listdir(tmp_path))}"

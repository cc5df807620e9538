"""The command line run in the test process: ``urdf2links.cli.main`` with the folder, the environment and the
output streams a subprocess would have, and the same result (returncode, stdout, stderr).

Why not a subprocess: every ``python -m urdf2links.cli`` pays Python's start, the imports (MuJoCo,
matplotlib) and the loading of every numba function it calls from the disk cache again, 2-15 s on a
2-core machine, for what this process has loaded already; the suite ran ~100 such commands (issue 31).
That the installed ``urdf2links`` command starts (the console script, a wheel in a fresh venv, a
read-only install) is tested in subprocesses in tests/test_packaging.py; here the command's behaviour is.

What a subprocess would show is kept: stdout and stderr as text (``print`` to either, the progress
lines, Python's warnings written as a process shows them, once per place), the exit status (argparse's
``SystemExit`` included), the working folder and environment variables set only for the call.
"""

from __future__ import annotations

import contextlib
import io
import os
import subprocess
import sys
import warnings
from pathlib import Path


def _show(message, category, filename, lineno, file=None, line=None):
    sys.stderr.write(warnings.formatwarning(message, category, filename, lineno, line))


@contextlib.contextmanager
def _environment(env: dict | None):
    if env is None:
        yield
        return
    saved = dict(os.environ)
    os.environ.clear()
    os.environ.update(env)
    try:
        yield
    finally:
        os.environ.clear()
        os.environ.update(saved)


def run_cli(*args, cwd=None, env=None) -> subprocess.CompletedProcess:
    """``urdf2links ARGS`` in this process, run in ``cwd`` (default: the current folder) with ``env`` (default:
    this process's environment) as the whole environment: a ``CompletedProcess`` with text stdout and stderr."""
    from urdf2links import cli

    argv = [str(a) for a in args]
    out, err = io.StringIO(), io.StringIO()
    here = Path.cwd()
    with _environment(env), warnings.catch_warnings(), contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        warnings.resetwarnings()
        warnings.simplefilter("default")            # a process's own filters: each warning once per place
        warnings.showwarning = _show
        os.chdir(cwd if cwd is not None else here)
        try:
            code = cli.main(argv)
        except SystemExit as exc:                   # argparse: --help (0) and usage errors (2)
            code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
        finally:
            os.chdir(here)
    return subprocess.CompletedProcess(["urdf2links", *argv], int(code or 0), out.getvalue(), err.getvalue())

"""The command line, run as a user runs it (in this process: tests/cli_runner.py)."""

from __future__ import annotations

from pathlib import Path

from cli_runner import run_cli

ROBOTS = Path(__file__).resolve().parent.parent / "robots"


def run(*args):
    return run_cli(*args)          # in this process, as a subprocess would show it (tests/cli_runner.py)


def test_inspect_prints_tree_and_audit():
    out = run("inspect", str(ROBOTS / "double_pendulum.urdf"))
    assert out.returncode == 0, out.stderr
    assert "2 coordinates" in out.stdout
    assert "[shoulder]" in out.stdout and "[elbow]" in out.stdout
    assert "inertia audit: 0 finding(s)" in out.stdout


def test_inspect_bad_file_is_a_clean_error(tmp_path):
    bad = tmp_path / "bad.urdf"
    bad.write_text("<robot name='x'><link name='a'></robot>")
    out = run("inspect", str(bad))
    assert out.returncode == 2
    assert "bad.urdf" in out.stderr and "Traceback" not in out.stderr

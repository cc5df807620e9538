"""The command line, run as a user runs it."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROBOTS = Path(__file__).resolve().parent.parent / "robots"


def run(*args):
    return subprocess.run([sys.executable, "-m", "urdf2links.cli", *args], capture_output=True, text=True)


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

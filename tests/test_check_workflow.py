"""The workflow of ``urdf2links check --write-workflow`` (issue 42): linted by a real linter, and run.

The written file is validated against GitHub's workflow schema (check-jsonschema's vendored
``vendor.github-workflows``, a test dependency), which catches a planted mistake; it installs urdf2links from a
pinned source (never by name from an index), pins Python, and posts on a pull request only from a job that may
write, only for a pull request of the same repository. Then its steps run as written, with bash, in a temporary
git repository: the install step (urdf2links from this repository at its ``HEAD`` as a ``git+file://`` URL, into
a virtual environment that sees the running one's packages: ``--no-deps`` through ``PIP_NO_DEPS``, 13 s here), the
check step as a push and as a pull request, and the summary step.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

import pytest
import yaml

from urdf2links.cli import main
from urdf2links.compare.check.workflow import PLACEHOLDER, Source, derived_source, source_from, workflow_text
from urdf2links.locations import shipped_robots_dir

PROJECT = Path(__file__).resolve().parents[1]
WORKFLOW = ".github/workflows/urdf2links-check.yml"
SHA = "0123456789abcdef0123456789abcdef01234567"


def _lint(path: Path) -> subprocess.CompletedProcess:
    """check-jsonschema with GitHub's workflow schema (vendored in the package: no network)."""
    return subprocess.run([sys.executable, "-m", "check_jsonschema", "--builtin-schema", "vendor.github-workflows",
                           str(path)], capture_output=True, text=True)


def _git(repo: Path, *args: str) -> str:
    return subprocess.run(["git", "-c", "user.email=ci@urdf2links", "-c", "user.name=ci", *args], cwd=repo,
                          check=True, capture_output=True, text=True).stdout.strip()


def test_the_written_workflow_passes_the_linter_and_a_planted_mistake_does_not(tmp_path, capsys):
    assert main(["check", str(tmp_path), "--write-workflow", "--from", f"https://github.com/o/urdf2links@{SHA}"]) == 0
    path = tmp_path / WORKFLOW
    run = _lint(path)
    assert run.returncode == 0, run.stdout + run.stderr
    text = path.read_text()
    for wrong in (text.replace("runs-on:", "run-on:", 1),                       # a misspelt key
                  text.replace("pull-requests: write", "pull-requests: writ"),  # a permission that does not exist
                  text.replace("  comment:\n", "  comment:\n    timeout-minutes: soon\n")):
        bad = tmp_path / "bad.yml"
        bad.write_text(wrong)
        assert _lint(bad).returncode != 0, wrong
    flow = yaml.safe_load(text)
    assert flow["env"]["URDF2LINKS_SOURCE"] == f"urdf2links @ git+https://github.com/o/urdf2links@{SHA}"
    assert flow["env"]["PYTHON_VERSION"] == f"{sys.version_info.major}.{sys.version_info.minor}"
    assert "pip install urdf2links" not in text               # the name from an index: never
    assert flow["permissions"] == {} and flow["jobs"]["check"]["permissions"] == {"contents": "read"}
    comment = flow["jobs"]["comment"]
    assert comment["permissions"] == {"pull-requests": "write"} and comment["needs"] == "check"
    assert "github.event.pull_request.head.repo.full_name == github.repository" in comment["if"]
    assert "${{" not in "".join(s.get("run", "") for j in flow["jobs"].values() for s in j["steps"])  # env, not pasted


def test_docs_ci_shows_the_workflow_written_without_a_known_source():
    doc = (PROJECT / "docs" / "ci.md").read_text()
    block = re.search(r"```yaml\n(.*?)```", doc, re.S).group(1)
    assert block == workflow_text(Source(PLACEHOLDER, "nowhere", placeholder=True), python="3.12"), \
        "docs/ci.md shows another workflow than `urdf2links check --write-workflow` writes"


def test_from_takes_a_pinned_git_url_or_a_path_and_refuses_the_rest(tmp_path, capsys):
    assert source_from(f"git@github.com:o/urdf2links.git@{SHA}", root=tmp_path).requirement == \
        f"urdf2links @ git+https://github.com/o/urdf2links.git@{SHA}"
    assert source_from(f"file:///srv/urdf2links@{SHA}", root=tmp_path).requirement == \
        f"urdf2links @ git+file://localhost/srv/urdf2links@{SHA}"
    vendored = tmp_path / "third_party" / "urdf2links"
    vendored.mkdir(parents=True)
    shutil.copy(PROJECT / "pyproject.toml", vendored / "pyproject.toml")
    assert source_from(str(vendored), root=tmp_path).requirement == "./third_party/urdf2links"
    for wrong, words in ((f"https://github.com/o/urdf2links@main", "pin a full commit hash"),
                         (f"https://github.com/o/urdf2links@{SHA[:12]}", "pin a full commit hash"),
                         (str(tmp_path), "not a git URL@COMMIT, and not a folder")):
        with pytest.raises(ValueError, match=words):
            source_from(wrong, root=tmp_path)
        capsys.readouterr()
        assert main(["check", str(tmp_path), "--write-workflow", "--from", wrong]) == 2
        assert words in capsys.readouterr().err
    assert main(["check", str(tmp_path), "--from", str(vendored)]) == 2        # --from alone: said, exit 2
    assert "--from goes with --write-workflow" in capsys.readouterr().err
    src = derived_source()     # this checkout has no reachable remote here (CI: a local clone): the placeholder
    assert src.placeholder or re.fullmatch(r"urdf2links @ git\+\S+@[0-9a-f]{40}", src.requirement), src


def _steps(flow: dict) -> dict:
    return {s.get("name", s.get("uses")): s for s in flow["jobs"]["check"]["steps"]}


def _environment(tmp_path: Path) -> dict:
    """A virtual environment that sees the running one's packages (a .pth file listing its sys.path), first on
    PATH, so that the steps' ``python`` and ``urdf2links`` are its own."""
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True, capture_output=True)
    purelib = subprocess.run([venv / "bin" / "python", "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"
                              ], check=True, capture_output=True, text=True).stdout.strip()
    running = [p for p in sys.path if p and Path(p).is_dir() and "site-packages" in p]
    assert sysconfig.get_paths()["purelib"] in running
    Path(purelib, "zz_running_environment.pth").write_text("\n".join(running) + "\n")
    env = {k: v for k, v in os.environ.items() if not k.startswith(("PIP_", "PYTHON", "GITHUB_"))}
    env.update(PATH=f"{venv / 'bin'}{os.pathsep}{env['PATH']}", PIP_NO_DEPS="1", PIP_DISABLE_PIP_VERSION_CHECK="1")
    return env


def _bash(script: str, cwd: Path, env: dict, **more) -> subprocess.CompletedProcess:
    """A step's ``run`` as GitHub runs it with ``shell: bash`` (``bash -e -o pipefail``)."""
    return subprocess.run(["bash", "--noprofile", "--norc", "-eo", "pipefail", "-c", script], cwd=cwd,
                          env={**env, **more}, capture_output=True, text=True, timeout=600)


def test_the_workflows_install_and_check_steps_run_in_a_temporary_repository(tmp_path):
    head = _git(PROJECT, "rev-parse", "HEAD")      # the test runs from urdf2links' git repository (a clone in CI)
    repo = tmp_path / "robots_repo"
    (repo / "robots").mkdir(parents=True)
    for name in ("pendulum.urdf", "double_pendulum.urdf"):        # robots alone: loaded, nothing compiled
        shutil.copy(shipped_robots_dir() / name, repo / "robots" / name)
    (repo / "urdf2links.toml").write_text('[[robots]]\nfiles = ["robots/*.urdf"]\n')
    _git(repo, "init", "-q", "-b", "main")
    assert main(["check", str(repo), "--write-workflow", "--from", f"git+file://{PROJECT}@{head}"]) == 0
    assert main(["check", str(repo), "--write-baselines", "--quiet"]) == 0     # the robots' fingerprints accepted
    _git(repo, "add", "-A")
    _git(repo, "commit", "-qm", "a robot and the workflow")
    flow = yaml.safe_load((repo / WORKFLOW).read_text())
    steps = _steps(flow)
    env = _environment(tmp_path)
    env.update(flow["env"], URDF2LINKS_CACHE_DIR=str(tmp_path / "cache"))
    refused = _bash(steps["Install urdf2links"]["run"], repo, env, URDF2LINKS_SOURCE=PLACEHOLDER)
    assert refused.returncode == 1 and "::error::set URDF2LINKS_SOURCE" in refused.stdout
    install = _bash(steps["Install urdf2links"]["run"], repo, env)
    assert install.returncode == 0, install.stdout + install.stderr
    where = _bash("command -v urdf2links; python -c 'import urdf2links; print(urdf2links.__file__)'", repo, env)
    assert where.stdout.split() == [str(tmp_path / "venv" / "bin" / "urdf2links"),
                                    str(next((tmp_path / "venv" / "lib").glob("python*/site-packages"))
                                        / "urdf2links" / "__init__.py")], where.stdout    # the installed copy runs
    push = _bash(steps["Run the check"]["run"], repo, env, BASE_REF="")
    assert push.returncode == 0, push.stdout + push.stderr
    assert "all 2 checks hold" in push.stdout and (repo / "urdf2links-check.xml").is_file()
    summary = tmp_path / "step_summary.md"
    shown = _bash(steps["Add the summary to the run's page"]["run"], repo, env, GITHUB_STEP_SUMMARY=str(summary))
    assert shown.returncode == 0 and summary.read_text() == (repo / "urdf2links-check.md").read_text()
    _git(repo, "update-ref", "refs/remotes/origin/main", "HEAD")         # the base branch, as fetched on a runner
    pr = _bash(steps["Run the check"]["run"], repo, env, BASE_REF="main")
    assert pr.returncode == 0, pr.stdout + pr.stderr
    assert "0 of 2 checks" in pr.stderr and "changed since origin/main" in pr.stderr

"""``urdf2links check``, its pytest plugin and its workflow (issue 34), in a temporary git repository holding an
example-robot-data robot (the double pendulum without meshes: two joints, fast) and MuJoCo's saved import of it
(:func:`~urdf2links.compare.pairs.mujoco_import.save_mujoco_import`) as its MJCF.

The story: ``check --init`` accepts the current state (each difference of the pair by name, each file's
fingerprint) and ``check`` passes (exit 0); a mass planted in the MJCF makes ``check`` exit 1 with two failing JUnit
cases (the MJCF's fingerprint and the pair), which, like the Markdown, name the link and both masses; ``pytest`` in
that repository fails the same two items beside the repository's own test; ``--changed-since HEAD~1`` checks only
what depends on the changed MJCF; a limit added to a joint the URDF gives ``lower = upper = 0`` fails, and is no
longer explained by MuJoCo's import (issue 42). The checks run in this process (``main``); only the pytest plugin
runs in a subprocess (``sys.executable``: this environment). The Panda's edits one by one: tests/test_check_edits.py.
"""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from lxml import etree

from urdf2links.cli import main
from urdf2links.compare.check.command import run_check
from urdf2links.compare.check.config import ConfigError, read_config
from urdf2links.compare.check.depends import robot_files
from urdf2links.compare.check.workflow import WORKFLOW
from urdf2links.compare.pairs.mujoco_import import save_mujoco_import
from urdf2links.pytest_plugin import _configured

from corpus import MISSING, ROOT as ERD, needs_corpus

PROJECT = Path(__file__).resolve().parents[1]
PENDULUM = "double_pendulum_description/urdf/double_pendulum_simple.urdf"
URDF, MJCF = "robots/double_pendulum.urdf", "robots/double_pendulum.xml"


def _git(repo: Path, *args: str) -> None:
    subprocess.run(["git", "-c", "user.email=check@urdf2links", "-c", "user.name=check", *args], cwd=repo, check=True,
                   capture_output=True)


@pytest.fixture(scope="module")
def repo(tmp_path_factory):
    """The repository, after ``check --init`` (exit asserted by the first test) and its commit."""
    if ERD is None:
        pytest.fail(MISSING)
    repo = tmp_path_factory.mktemp("check_repo")
    (repo / "robots").mkdir()
    shutil.copy(ERD / PENDULUM, repo / URDF)
    save_mujoco_import(repo / URDF, repo / MJCF, keep_geometry=False)
    (repo / "tests").mkdir()
    (repo / "tests" / "test_own.py").write_text("def test_the_repositorys_own_test():\n    assert 1 + 1 == 2\n")
    _git(repo, "init", "-q")
    _git(repo, "add", "-A")
    _git(repo, "commit", "-qm", "a robot and its MJCF")
    return repo


@pytest.fixture(scope="module")
def initialised(repo):
    code = main(["check", str(repo), "--init", "--quiet"])
    _git(repo, "add", "-A")
    _git(repo, "commit", "-qm", "urdf2links check --init")
    return code


@pytest.fixture(scope="module")
def planted(repo, initialised):
    """The MJCF with link2's mass changed from 0.3 to 0.35 kg, committed."""
    mjcf = repo / MJCF
    text = mjcf.read_text()
    assert text.count('mass="0.3"') == 1
    mjcf.write_text(text.replace('mass="0.3"', 'mass="0.35"'))
    _git(repo, "commit", "-qam", "a heavier link2 in the MJCF")
    return repo


@needs_corpus
def test_init_then_check_passes(repo, initialised, capsys):
    assert initialised == 0
    config = read_config(repo)
    assert [r.id for r in config.robots] == [URDF, MJCF]
    assert [(p.urdf.id, p.mjcf.id) for p in config.pairs] == [(URDF, MJCF)]      # guessed by the robot's name
    # MuJoCo's import leaves the URDF's lower = upper = 0 joints unlimited and fuses the massless tip frame:
    # accepted at init by name, nothing else, and no kind as a whole
    pair = config.pairs[0]
    assert pair.tolerances == {}
    assert [(r.kind, r.part, r.urdf, r.mjcf) for r in pair.accepted] == [
        ("limits", "joint joint1", [0.0, 0.0], "unlimited"), ("limits", "joint joint2", [0.0, 0.0], "unlimited"),
        ("frame_missing", "frame link3", "link3", "none")]
    assert all(0 < r.tolerance <= 1e-5 for r in pair.accepted)       # the kinds' rounding (compare/check/accepted.py)
    assert [(s.id, s.q0) for s in config.scenes] == [(URDF, "excite"), (MJCF, "excite")] and config.baselines.is_file()
    fingerprints = json.loads(config.baselines.read_text())["fingerprints"]
    assert sorted(fingerprints) == [URDF, MJCF]
    assert fingerprints[MJCF]["bodies"]["link2"]["mass"] == 0.3 and fingerprints[URDF]["joints"]["joint2"]["range"] == [
        0.0, 0.0] and fingerprints[MJCF]["joints"]["joint2"]["range"] == "unlimited"
    capsys.readouterr()
    assert main(["check", str(repo)]) == 0
    assert "all 5 checks hold" in capsys.readouterr().out


@needs_corpus
def test_a_planted_mass_fails_the_fingerprint_and_the_pair_naming_the_link_and_both_masses(planted, tmp_path, capsys):
    junit, md = tmp_path / "check.xml", tmp_path / "check.md"
    assert main(["check", str(planted), "--junit", str(junit), "--markdown", str(md), "--quiet"]) == 1
    cases = etree.parse(str(junit)).getroot().findall(".//testcase")
    assert len(cases) == 5                                   # 2 robots, 1 pair, 2 scenes
    failing = {c.get("classname"): c for c in cases if c.find("failure") is not None or c.find("error") is not None}
    assert sorted(failing) == ["urdf2links.pair", "urdf2links.robot"]
    assert failing["urdf2links.robot"].get("name") == MJCF
    pair = failing["urdf2links.pair"].find("failure").get("message")
    robot = failing["urdf2links.robot"].find("failure").get("message")
    summary = md.read_text()
    for text in (pair, summary):
        assert re.search(r"mass of link link2\b.*0\.3 in robots/double_pendulum\.urdf, 0\.35 in "
                         r"robots/double_pendulum\.xml", text), text
        assert "not accepted" in text and 'kind = "mass"' in text        # and the row that would accept it
    # the MJCF against its own accepted state: the body, the quantity, both values, the command that accepts it
    m = re.search(r"robots/double_pendulum\.xml: body link2: mass was (\S+), now (\S+) kg .*--write-baselines", robot)
    assert m and (float(m[1]), float(m[2])) == (0.3, 0.35), robot
    assert "2 failed" in capsys.readouterr().out


@needs_corpus
def test_pytest_in_the_repository_shows_the_same_failures(planted):
    run = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-rf"], cwd=planted,
                         capture_output=True, text=True, timeout=300)
    out = run.stdout
    assert run.returncode == 1, out + run.stderr
    assert "2 failed, 4 passed" in out, out               # the repository's own test and 3 checks pass
    assert f"FAILED {MJCF}::pair[{URDF}]" in out and f"FAILED {MJCF}::robot" in out, out
    assert re.search(r"mass of link link2\b.*0\.3 in .*0\.35 in", out), out


@needs_corpus
def test_changed_since_checks_only_what_depends_on_the_changed_file(planted):
    run = run_check(planted, changed_since="HEAD~1", jobs=2)      # two processes: the same cases, same verdicts
    ran = [(r.case.kind, r.case.file) for r in run.results]
    assert ran == [("robot", MJCF), ("pair", MJCF), ("scene", MJCF)], ran
    assert [r.status for r in run.results] == ["fail", "fail", "pass"]       # its fingerprint, the pair
    assert ("robot", URDF) in [(c.kind, c.file) for c in run.skipped]


@needs_corpus
def test_a_limit_added_after_init_fails_and_is_no_longer_explained_by_the_import(initialised, repo, tmp_path, capsys):
    """Issue 42: the URDF's joint2 has ``lower = upper = 0`` and MuJoCo's import leaves it unlimited (accepted at
    init by name). ``limited="true" range="-0.3 0.3"`` added to the MJCF's joint2 fails the pair, naming the joint
    and both ranges, and the MJCF's fingerprint; "MuJoCo's import leaves such a joint unlimited" is not said any
    more (explanations are computed from both files). The MJCF is taken as init committed it."""
    copy = shutil.copytree(repo, tmp_path / "copy")
    init = subprocess.run(["git", "log", "--format=%H", "-1", "--grep", "urdf2links check --init"], cwd=copy,
                          capture_output=True, text=True, check=True).stdout.strip()
    text = subprocess.run(["git", "show", f"{init}:{MJCF}"], cwd=copy, capture_output=True, text=True,
                          check=True).stdout
    edited = re.sub(r'(<joint name="joint2"[^>]*?) limited="false"', r'\1 limited="true" range="-0.3 0.3"', text)
    assert edited.count('range="-0.3 0.3"') == 1                 # MuJoCo's writer said limited="false"
    (copy / MJCF).write_text(edited)
    capsys.readouterr()
    assert main(["check", str(copy)]) == 1
    out = capsys.readouterr().out
    pair = re.search(r"robots/double_pendulum\.xml: limits of joint joint2: \[0, 0\] in robots/double_pendulum\.urdf, "
                     r"\[-0\.3, 0\.3\] in robots/double_pendulum\.xml .*accepted \[0, 0\] and unlimited", out)
    assert pair, out
    assert re.search(r"robots/double_pendulum\.xml: joint joint2: range was unlimited, now \[-0\.3, 0\.3\]", out), out
    assert "leaves such a joint unlimited" not in out, out


@needs_corpus
def test_a_scene_that_grew_past_its_baseline_fails(initialised, repo, tmp_path):
    """A baseline of the trajectory difference lowered below what the run measures: the scene fails, naming the
    figure, the value and what was allowed."""
    copy = shutil.copytree(repo, tmp_path / "copy")
    path = copy / "urdf2links-baselines.json"
    path.write_text(re.sub(r'"trajectory.max_abs_error": [^,\n]+', '"trajectory.max_abs_error": 1e-20',
                           path.read_text()))
    config = copy / "urdf2links.toml"
    config.write_text(config.read_text().replace("factor = 10.0", "factor = 1.0"))
    run = run_check(copy, changed_since=None)
    scenes = [r for r in run.results if r.case.kind == "scene"]
    assert [r.status for r in scenes] == ["fail", "fail"] and run.status == 1
    assert "trajectory.max_abs_error" in scenes[0].message() and "allowed" in scenes[0].message()


@needs_corpus
def test_a_scene_with_weak_evidence_fails_and_says_so(initialised, repo, tmp_path, capsys):
    """The MJCF's default scene at rest (``q0 = "rest"``: the pendulum balanced upright, where nothing moves in
    0.5 s) fails, saying weak evidence, even while --write-baselines accepts its figures; the excited default
    scene of the same file (init's, ``test_init_then_check_passes``) passes."""
    copy = shutil.copytree(repo, tmp_path / "copy")
    config = copy / "urdf2links.toml"
    text = config.read_text()
    assert text.count('q0 = "excite"') == 2
    config.write_text(text.replace('q0 = "excite"', 'q0 = "rest"'))
    capsys.readouterr()
    assert main(["check", str(copy), "--write-baselines"]) == 1
    out = capsys.readouterr().out
    for robot in (URDF, MJCF):
        assert re.search(rf"^FAIL  scene {re.escape(robot)} \(default scene\).*\n        {re.escape(robot)}: weak "
                         r"evidence: .*q0 = \"excite\"", out, re.M), out


def test_a_robot_that_cannot_be_loaded_or_has_inertia_findings(tmp_path, capsys):
    """A load error is an error (exit 2, a JUnit <error>); an inertia finding fails unless allowed."""
    bad_inertia = ('<robot name="r"><link name="base"/><link name="arm"><inertial><mass value="1"/>'
                   '<inertia ixx="1" iyy="1" izz="5" ixy="0" ixz="0" iyz="0"/></inertial></link>'
                   '<joint name="j" type="revolute"><parent link="base"/><child link="arm"/><axis xyz="0 0 1"/>'
                   '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>')
    (tmp_path / "arm.urdf").write_text(bad_inertia)
    (tmp_path / "urdf2links.toml").write_text('[[robots]]\nfiles = ["*.urdf"]\n')
    assert main(["check", str(tmp_path), "--quiet"]) == 1
    assert "link arm: inertia triangle_inequality" in capsys.readouterr().out
    (tmp_path / "urdf2links.toml").write_text('[[robots]]\nfiles = ["*.urdf"]\nallow_inertia_findings = ["arm"]\n')
    assert main(["check", str(tmp_path), "--quiet"]) == 1          # no fingerprint accepted yet: it says how
    assert "no accepted fingerprint" in capsys.readouterr().out
    assert main(["check", str(tmp_path), "--quiet", "--write-baselines"]) == 0
    assert main(["check", str(tmp_path), "--quiet"]) == 0
    (tmp_path / "broken.urdf").write_text("<robot name='b'><link name='x'>")
    junit = tmp_path / "j.xml"
    assert main(["check", str(tmp_path), "--quiet", "--junit", str(junit)]) == 2
    errors = etree.parse(str(junit)).getroot().findall(".//testcase/error")
    assert len(errors) == 1 and "broken.urdf" in errors[0].get("message")


@pytest.mark.parametrize("text, words", [
    ('[[robots]]\nfiles = ["*.urdf"]\ncolour = "red"\n', ["[robots 1]", "colour"]),
    ('[[robots]]\nfiles = ["nothing/*.urdf"]\n', ["[robots 1]", "nothing/*.urdf", "matches no"]),
    ('tolerances = { weight = 1 }\n[[robots]]\nfiles = ["*.urdf"]\n', ["unknown key 'weight'", "A and G"]),
    ('tolerances = { limits = inf }\n[[robots]]\nfiles = ["*.urdf"]\n', ["tolerances.limits", "a whole kind",
                                                                          "accepted"]),
    ('[[pairs]]\nurdf = "a.urdf"\nmjcf = "a.urdf"\naccepted = [{ kind = "limits", part = "joint j", urdf = 0, '
     'mjcf = "none", difference = inf, unit = "rad", tolerance = inf }]\n', ["[pairs 1]", "accepted[0]",
                                                                           "limits of joint j", "tolerance = inf"]),
    ('[[pairs]]\nurdf = "a.urdf"\nmjcf = "missing.xml"\n', ["[pairs 1]", "missing.xml", "does not exist"]),
])
def test_a_configuration_that_cannot_be_used_exits_2_naming_file_and_key(tmp_path, capsys, text, words):
    (tmp_path / "a.urdf").write_text((Path(__file__).parents[1] / "robots" / "double_pendulum.urdf").read_text())
    (tmp_path / "urdf2links.toml").write_text(text)
    with pytest.raises(ConfigError):
        read_config(tmp_path)
    assert main(["check", str(tmp_path)]) == 2
    message = capsys.readouterr().err
    for w in [str(tmp_path / "urdf2links.toml"), *words]:
        assert w in message, (w, message)


def test_the_configuration_docs_ci_shows_is_read_as_it_says(tmp_path):
    """docs/ci.md's configuration, with its files made: the accepted rows by name, A and G only, excited scenes."""
    doc = (PROJECT / "docs" / "ci.md").read_text()
    text = re.search(r"```toml\n(.*?)```", doc, re.S).group(1)
    (tmp_path / "robots").mkdir()
    (tmp_path / "scenes").mkdir()
    (tmp_path / "robots/arm.urdf").write_text((PROJECT / "robots" / "double_pendulum.urdf").read_text())
    (tmp_path / "scenes/swing.toml").write_text("# only found by its glob here, not read\n")
    save_mujoco_import(tmp_path / "robots/arm.urdf", tmp_path / "robots/arm.xml", keep_geometry=False)
    (tmp_path / "urdf2links.toml").write_text(text)
    config = read_config(tmp_path)
    pair = config.pairs[0]
    assert pair.tolerances == {"A": 1e-3, "G": 1e-3} and config.tolerances == {"A": 1e-3}
    assert [(r.kind, r.part, r.mjcf, r.unit, r.tolerance) for r in pair.accepted] == [
        ("armature", "joint joint1", 0.1, "kg m^2", 1e-6), ("damping", "joint joint1", 1.0, "N m s/rad", 1e-5)]
    assert [s.q0 for s in config.scenes if s.robot is not None] == ["excite"]


def test_the_configuration_in_pyproject(tmp_path):
    (tmp_path / "a.urdf").write_text((PROJECT / "robots" / "double_pendulum.urdf").read_text())
    (tmp_path / "pyproject.toml").write_text('[project]\nname = "x"\n\n[[tool.urdf2links.robots]]\nfiles = "*.urdf"\n')
    (tmp_path / "sub").mkdir()
    config = read_config(tmp_path / "sub")                  # found from a folder below it
    assert config.source == tmp_path / "pyproject.toml" and [r.id for r in config.robots] == ["a.urdf"]


@needs_corpus
def test_dependencies_count_meshes_and_includes(tmp_path):
    """A URDF's package:// meshes, a xacro file's includes, an MJCF file's includes and meshes."""
    urdf = ERD / "double_pendulum_description/urdf/double_pendulum.urdf"
    meshes = {p.name for p in robot_files(urdf)} - {urdf.name}
    assert meshes == {"base_link.stl", "link1.stl", "link2.stl"}
    (tmp_path / "arm.xacro").write_text('<robot name="a" xmlns:xacro="http://www.ros.org/wiki/xacro">'
                                        '<xacro:include filename="part.xacro"/><xacro:part/></robot>')
    (tmp_path / "part.xacro").write_text('<robot xmlns:xacro="http://www.ros.org/wiki/xacro"><xacro:macro '
                                         'name="part"><link name="l"><visual><geometry><mesh filename="m.stl"/>'
                                         '</geometry></visual></link></xacro:macro></robot>')
    (tmp_path / "m.stl").write_bytes((ERD / "double_pendulum_description/meshes/link1.stl").read_bytes())
    assert {p.name for p in robot_files(tmp_path / "arm.xacro")} == {"arm.xacro", "part.xacro", "m.stl"}
    (tmp_path / "body.xml").write_text('<mujoco><worldbody><body><geom type="mesh" mesh="m"/></body></worldbody>'
                                       '</mujoco>')
    (tmp_path / "arm.xml").write_text('<mujoco><compiler meshdir="assets"/><asset><mesh name="m" file="m.stl"/>'
                                      '</asset><include file="body.xml"/></mujoco>')
    files = robot_files(tmp_path / "arm.xml")
    assert files == {tmp_path / "arm.xml", tmp_path / "body.xml", tmp_path / "assets" / "m.stl"}


def test_write_workflow_writes_the_file_docs_ci_shows(tmp_path, capsys):
    assert main(["check", str(tmp_path), "--write-workflow"]) == 0
    written = (tmp_path / ".github/workflows/urdf2links-check.yml").read_text()
    assert written == WORKFLOW
    doc = (PROJECT / "docs" / "ci.md").read_text()
    block = re.search(r"```yaml\n(.*?)```", doc, re.S).group(1)
    assert block == WORKFLOW, "docs/ci.md shows another workflow than `urdf2links check --write-workflow` writes"
    for step in ("pip install urdf2links", "actions/cache", "URDF2LINKS_CACHE_DIR", "urdf2links check",
                 "--junit", "upload-artifact", "GITHUB_STEP_SUMMARY", "gh pr comment"):
        assert step in written, step


def test_the_plugin_is_inactive_in_this_repository():
    """urdf2links' own repository has no check configuration: its own test run gets no check items, and the
    plugin module loads no MuJoCo."""
    assert not _configured(PROJECT)
    run = subprocess.run([sys.executable, "-c", "import sys, urdf2links.pytest_plugin; "
                          "print('mujoco' in sys.modules, 'urdf2links.compare' in sys.modules)"],
                         capture_output=True, text=True, check=True)
    assert run.stdout.split() == ["False", "False"]

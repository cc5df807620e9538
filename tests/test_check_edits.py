"""``urdf2links check`` catches every meaningful edit of an MJCF kept beside its URDF (issue 42), on a real robot.

The repository: example-robot-data's Panda URDF (its ``panda_joint7`` made continuous, as a wrist often is) and
MuJoCo's own import of it (:func:`~urdf2links.compare.pairs.mujoco_import.save_mujoco_import`), edited as a
public MJCF is before ``check --init`` accepts it: ``panda_joint1`` damped at 1 N m s/rad (the URDF says 0.003)
and armature 0.1 kg m^2 on joints 1 to 4 (a URDF has none). ``check --init`` runs once (a module fixture); each
edit below is then made alone, in the MJCF of a copy, and ``check`` must exit 1 naming the part -- in the pair's
problems (a difference not accepted, or an accepted one that moved) and in the MJCF's fingerprint (the
parameter, its old and new value, the command that accepts it). A comment added exits 0. ``pytest`` in the
repository (the plugin, tests/test_check.py has its story) fails the same items.

Every edit changes one element's attributes, made with lxml on the file as init committed it; both engines run
the edited file alike in a scene, so only the pair and the fingerprint can see them (the scenes, 0.5 s each,
are run too, as ``check`` runs them: they pass or fail as they do, and are not asserted here).
"""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from lxml import etree

from urdf2links.cli import main
from urdf2links.compare.check.config import read_config
from urdf2links.compare.pairs.mujoco_import import save_mujoco_import

from corpus import MISSING, NAMED, ROOT as ERD, needs_corpus

URDF, MJCF = "robots/panda.urdf", "robots/panda.xml"


def _joint(root, name: str):
    return root.find(f".//joint[@name='{name}']")


def _body(root, name: str):
    return root.find(f".//body[@name='{name}']")


def _joint_set(name: str, **attrs):
    """An edit: the joint's attributes set (``frictionloss="0.5"``)."""
    return lambda root: [_joint(root, name).set(k, v) for k, v in attrs.items()]


def _body_moved(name: str, by):
    def edit(root):
        b = _body(root, name)
        b.set("pos", " ".join(f"{float(x) + d:.9g}" for x, d in zip((b.get("pos") or "0 0 0").split(), by)))
    return edit


def _inertial_scaled(name: str, attr: str, factor: float):
    def edit(root):
        e = _body(root, name).find("inertial")
        e.set(attr, " ".join(f"{float(x) * factor:.9g}" for x in e.get(attr).split()))
    return edit


#: The edits of issue 42: id -> (the edit of the MJCF's XML, the part the failure must name).
EDITS = {
    "range narrowed": (_joint_set("panda_joint2", range="-1.5 1.5"), "panda_joint2"),
    "damping set": (_joint_set("panda_joint5", damping="1"), "panda_joint5"),
    "damping halved": (_joint_set("panda_joint1", damping="0.5"), "panda_joint1"),
    "armature set": (_joint_set("panda_joint6", armature="0.1"), "panda_joint6"),
    "armature halved": (_joint_set("panda_joint1", armature="0.05"), "panda_joint1"),
    "frictionloss": (_joint_set("panda_joint3", frictionloss="0.5"), "panda_joint3"),
    "body moved 1 cm": (_body_moved("panda_link3", (0.01, 0.0, 0.0)), "panda_link3"),
    "axis negated": (_joint_set("panda_joint4", axis="0 0 -1"), "panda_joint4"),
    "inertia x 1.5": (_inertial_scaled("panda_link5", "diaginertia", 1.5), "panda_link5"),
    "mass x 1.1": (_inertial_scaled("panda_link2", "mass", 1.1), "panda_link2"),
    # MuJoCo's import writes the continuous joint limited="false": the limit is both attributes
    "limit added to a continuous joint": (_joint_set("panda_joint7", limited="true", range="-1 1"), "panda_joint7"),
}


def _git(repo: Path, *args: str) -> None:
    subprocess.run(["git", "-c", "user.email=check@urdf2links", "-c", "user.name=check", *args], cwd=repo, check=True,
                   capture_output=True)


def _prepared_mjcf(path: Path) -> None:
    """MuJoCo's import as a public MJCF would have it (module doc): joint 1 damped, joints 1 to 4 with armature."""
    tree = etree.parse(str(path))
    _joint(tree, "panda_joint1").set("damping", "1")
    for k in range(1, 5):
        _joint(tree, f"panda_joint{k}").set("armature", "0.1")
    path.write_text(etree.tostring(tree.getroot(), encoding="unicode") + "\n")


@pytest.fixture(scope="module")
def panda(tmp_path_factory):
    """The repository after ``check --init`` (asserted: exit 0), committed."""
    if ERD is None:
        pytest.fail(MISSING)
    repo = tmp_path_factory.mktemp("panda_repo")
    (repo / "robots").mkdir()
    text = (ERD / NAMED["panda"]).read_text()
    continuous = re.sub(r'<joint name="panda_joint7" type="revolute">', '<joint name="panda_joint7" type="continuous">',
                        text)
    assert continuous.count('type="continuous"') == 1
    (repo / URDF).write_text(continuous)
    # its meshes where its package:// paths resolve from the URDF's folder (check fails a robot whose mesh is
    # missing, naming it: issue 42)
    shutil.copytree(ERD / "panda_description" / "meshes",
                    repo / "robots" / "example-robot-data" / "robots" / "panda_description" / "meshes")
    save_mujoco_import(repo / URDF, repo / MJCF, keep_geometry=False)
    _prepared_mjcf(repo / MJCF)
    (repo / "tests").mkdir()
    (repo / "tests" / "test_own.py").write_text("def test_the_repositorys_own_test():\n    assert True\n")
    _git(repo, "init", "-q")
    assert main(["check", str(repo), "--init", "--quiet"]) == 0
    # The URDF's default scene lets the fingers slide off their rails (no limits modelled, no actuator holds
    # them): the plausibility gate calls it implausible, and --init leaves it out, saying why, instead of
    # accepting it (issue 43). The MJCF's (damped joints) stays.
    config = (repo / "urdf2links.toml").read_text()
    assert f"# left out at init: the default scene of {URDF} is no evidence to accept: implausible run" in config
    assert "panda_finger_joint" in config and f'robot = "{MJCF}"' in config
    _git(repo, "add", "-A")
    _git(repo, "commit", "-qm", "the Panda, its MJCF, urdf2links check --init")
    return repo


def _edited(panda: Path, tmp_path: Path, edit) -> Path:
    copy = shutil.copytree(panda, tmp_path / "repo")
    tree = etree.parse(str(copy / MJCF))
    edit(tree.getroot())
    (copy / MJCF).write_text(etree.tostring(tree.getroot(), encoding="unicode") + "\n")
    return copy


@needs_corpus
def test_init_accepts_the_differences_by_name(panda):
    """The MJCF's own damping and armature are accepted joint by joint, each with a tolerance far below a halving;
    nothing is accepted for a whole kind; the continuous joint has no limits on either side."""
    pair = read_config(panda).pairs[0]
    rows = {(r.kind, r.part): r for r in pair.accepted}
    assert ("damping", "joint panda_joint1") in rows and ("damping", "joint panda_joint2") not in rows
    assert {p for k, p in rows if k == "armature"} == {f"joint panda_joint{k}" for k in range(1, 5)}
    assert rows[("damping", "joint panda_joint1")].mjcf == 1.0 and rows[("armature", "joint panda_joint1")].urdf == 0.0
    # 1e-5 of the accepted value at most (compare/check/accepted.py): a halving is 5e4 times that
    assert all(r.tolerance <= 1e-5 * max(1.0, abs(r.difference)) for r in pair.accepted), pair.accepted
    assert not any(k == "limits" for k, _ in rows), rows
    assert pair.tolerances == {}


@needs_corpus
@pytest.mark.parametrize("name", list(EDITS))
def test_each_edit_of_the_mjcf_fails_naming_the_part(panda, tmp_path, capsys, name):
    edit, part = EDITS[name]
    repo = _edited(panda, tmp_path, edit)
    capsys.readouterr()
    code = main(["check", str(repo)])
    out = capsys.readouterr().out
    assert code == 1, out
    pair = re.search(r"^FAIL  pair .*?\n((?:        .*\n)+)", out, re.M)
    robot = re.search(rf"^FAIL  robot {re.escape(MJCF)} .*?\n((?:        .*\n)+)", out, re.M)
    assert pair and part in pair[1], out                      # the pair names the part ...
    assert re.search(rf"{re.escape(MJCF)}: \w+ of (joint|link) {part}\b", pair[1]), pair[1]
    assert robot and re.search(rf"{re.escape(MJCF)}: (joint|body) {part}: \w+ was .*, now .*--write-baselines",
                               robot[1]), out               # ... and so does the MJCF's own fingerprint
    assert re.search(rf"^ok    robot {re.escape(URDF)} ", out, re.M), out


@needs_corpus
def test_a_comment_added_passes(panda, tmp_path, capsys):
    repo = shutil.copytree(panda, tmp_path / "repo")
    text = (repo / MJCF).read_text()
    (repo / MJCF).write_text(text.replace("<worldbody>", "<worldbody>\n    <!-- reviewed: the arm as shipped -->", 1))
    assert (repo / MJCF).read_text() != text
    assert main(["check", str(repo)]) == 0, capsys.readouterr().out


@needs_corpus
def test_pytest_in_the_repository_fails_the_same_items(panda, tmp_path):
    """The plugin (tests/test_check.py): the halved damping fails the MJCF's robot item and the pair item, naming
    the joint; the repository's own test and the URDF pass (the one scene, the MJCF's default scene, is deselected:
    -k; --init left the URDF's out)."""
    repo = _edited(panda, tmp_path, EDITS["damping halved"][0])
    run = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-rf", "-k", "not scene"],
                         cwd=repo, capture_output=True, text=True, timeout=600)
    out = run.stdout
    assert run.returncode == 1, out + run.stderr
    assert re.search(r"\b2 failed, 2 passed, 1 deselected\b", out), out
    assert f"FAILED {MJCF}::robot" in out and f"FAILED {MJCF}::pair[{URDF}]" in out, out
    assert re.search(r"damping of joint panda_joint1: 0\.003 in .*, 0\.5 in", out), out

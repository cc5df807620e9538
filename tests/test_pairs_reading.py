"""Pairs that read (issue 43): a coupling is one difference naming both files' joints, effort through a tendon
actuator, each difference named as its part is called and said to be at rounding or not, one stated order
everywhere the list is printed, a pair's own summary.md and headline.

The second files are MuJoCo's import of the shipped ur5_like arm (``wrist_3_joint`` mimicking ``wrist_2_joint``:
multiplier 2, offset 0.1), edited through MjSpec the way hand-written MJCFs differ: joints renamed, the coupling's
roles swapped, a tendon actuator holding two joints.
"""

from __future__ import annotations

import contextlib
import html
import io
import json
import re
import warnings

import mujoco
import numpy as np
import pytest

from urdf2links.cli import main
from urdf2links.compare.pairs.effects import EFFECT_ROUNDING, ORDER_WORDS
from urdf2links.compare.pairs.mujoco_import import save_mujoco_import
from urdf2links.compare.pairs.pair import compare_descriptions_of
from urdf2links.locations import shipped_robots_dir


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    return tmp_path_factory.mktemp("reading")


def _compare(urdf, mjcf):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return compare_descriptions_of(urdf, mjcf)


def _edited(pair, folder, name, edit):
    spec = mujoco.MjSpec.from_file(str(pair[1]))
    edit(spec)
    spec.compile()
    out = folder / f"{name}.xml"
    out.write_text(spec.to_xml())
    return out


def _renamed_and_swapped(spec, polycoef):
    """Joints wrist_2/wrist_3 named j5/j6 (the file's own names) and the equality written j5 = f(j6)."""
    spec.joint("wrist_2_joint").name = "j5"
    spec.joint("wrist_3_joint").name = "j6"
    eq = next(iter(spec.equalities))
    eq.name1, eq.name2 = "j5", "j6"
    eq.data = np.r_[polycoef, np.zeros(eq.data.size - 2)]


# -- 2. a coupling is one difference that names both files' joints ---------------------------------------------
def test_a_coupling_with_its_roles_swapped_is_the_same_coupling(mimic_arm, folder):
    """q3 = 2 q2 + 0.1 written as q2 = 0.5 q3 - 0.05 under other names: no coupling difference (the old reading
    listed it twice, 'first description only' and 'second description only')."""
    same = _edited(mimic_arm, folder, "swapped", lambda s: _renamed_and_swapped(s, [-0.05, 0.5]))
    c = _compare(mimic_arm[0], same)
    assert {(m.urdf, m.mjcf) for m in c.mapping.matches} >= {("wrist_2_joint", "j5"), ("wrist_3_joint", "j6")}
    assert [d.label() for d in c.differences if d.kind == "coupling"] == []


def test_a_different_coupling_with_its_roles_swapped_is_one_difference_naming_both(mimic_arm, folder):
    """q2 = 0.6 q3 - 0.05, i.e. q3 = 1.667 q2 + 0.0833: one difference of 2 - 1/0.6 = 0.333, at wrist_3 / j6."""
    other = _edited(mimic_arm, folder, "swapped_other", lambda s: _renamed_and_swapped(s, [-0.05, 0.6]))
    cs = [d for d in _compare(mimic_arm[0], other).differences if d.kind == "coupling"]
    assert len(cs) == 1, [d.what for d in cs]
    d = cs[0]
    assert (d.urdf, d.mjcf, d.part) == ("wrist_3_joint", "j6", "joint")
    assert d.difference == pytest.approx(2 - 1 / 0.6, rel=1e-9)
    assert d.mjcf_value == pytest.approx([1 / 0.6, 0.05 / 0.6], rel=1e-9)       # in the first file's form
    for name in ("wrist_2_joint", "wrist_3_joint", "j5", "j6"):                   # both files' joints named
        assert name in d.what, (name, d.what)


# -- 3. effort through a tendon actuator ---------------------------------------------------------------------
def _tendon_actuator(spec, force):
    """A fixed tendon of wrist_2 and wrist_3 (coefficient 0.5 each), its actuator limited to +-``force`` (gear 1),
    and the joints' own actuatorfrcrange removed (as in Menagerie's gripper: the force is limited on the tendon)."""
    t = spec.add_tendon(name="wrists")
    for j in ("wrist_2_joint", "wrist_3_joint"):
        t.wrap_joint(j, 0.5)
        spec.joint(j).actfrclimited = 0
    a = spec.add_actuator(name="wrists_act", target="wrists", trntype=mujoco.mjtTrn.mjTRN_TENDON)
    a.gear = [1, 0, 0, 0, 0, 0]
    a.forcelimited, a.forcerange = 1, [-force, force]


def test_effort_through_a_tendon_actuator(folder):
    """The URDF's 28 N m at each wrist against a tendon actuator's forcerange x gear x coefficient: +-56 N gives
    28 N m (no difference; the old reading said '28 against None' at both), +-40 N gives 20 N m (8/28 each)."""
    urdf = shipped_robots_dir() / "ur5_like.urdf"
    arm = (urdf, save_mujoco_import(urdf, folder / "arm.xml", keep_geometry=False, keep_frames=True).path)
    same = _compare(urdf, _edited(arm, folder, "tendon56", lambda s: _tendon_actuator(s, 56.0)))
    assert [d.label() for d in same.differences if d.kind == "effort"] == []
    weaker = _compare(urdf, _edited(arm, folder, "tendon40", lambda s: _tendon_actuator(s, 40.0)))
    eff = {d.urdf: d for d in weaker.differences if d.kind == "effort"}
    assert set(eff) == {"wrist_2_joint", "wrist_3_joint"}
    for d in eff.values():
        assert d.mjcf_value == pytest.approx(20.0) and d.difference == pytest.approx(8 / 28)
        assert "wrists_act" in d.what and "tendon wrists" in d.what and d.effect["at_rounding"] is True


# -- 4. each difference named as its part is called, its effect at rounding or not -------------------------------
@pytest.fixture(scope="module")
def edited_arm(folder):
    """MuJoCo's import of ur5_like with the forearm 1.5 times heavier, the elbow damped (2 N m s/rad), wrist_1's
    frame moved 0.2 mm, and the upper arm 3e-5 heavier (3 times mass's rounding level: listed, its effect on A and
    G at rounding)."""
    urdf = shipped_robots_dir() / "ur5_like.urdf"
    arm = (urdf, save_mujoco_import(urdf, folder / "arm4.xml", keep_geometry=False, keep_frames=True).path)

    def edit(spec):
        spec.body("forearm_link").mass *= 1.5
        spec.body("upper_arm_link").mass *= 1 + 3e-5
        spec.joint("elbow_joint").damping = [2.0, 0.0, 0.0]
        spec.body("wrist_1_link").pos = spec.body("wrist_1_link").pos + [0.0, 2e-4, 0.0]
    return urdf, _edited(arm, folder, "edited4", edit)


def test_each_difference_names_its_part_and_says_whether_it_is_at_rounding(edited_arm):
    c = _compare(*edited_arm)
    by = {(d.kind, d.urdf): d for d in c.differences}
    heavy, light = by[("mass", "forearm_link")], by[("mass", "upper_arm_link")]   # links by their links (not
    assert heavy.mjcf == "forearm_link" and heavy.part == "link"                  # elbow_joint, shoulder_lift_joint)
    assert not any(d.kind == "mass" and d.urdf.endswith("_joint") for d in c.differences)
    assert by[("origin", "wrist_1_joint")].part == "joint" and by[("damping", "elbow_joint")].part == "joint"
    assert heavy.to_json()["part"] == "link"
    # the forearm's mass changes A and G by about 10 % of their largest entries: not rounding
    assert heavy.effect["at_rounding"] is False and min(heavy.effect["changes_A"], heavy.effect["changes_G"]) > 0.01
    # 3e-5 of the upper arm's mass: listed (above mass's 1e-5), but what it does to A and G is under EFFECT_ROUNDING
    assert light.difference == pytest.approx(3e-5, abs=1e-6)     # the import writes 6 digits: 3.87 kg -> 3.87012
    assert light.effect["at_rounding"] is True and max(light.effect["changes_A"], light.effect["changes_G"]) <= EFFECT_ROUNDING
    assert by[("damping", "elbow_joint")].effect["at_rounding"] is True       # no term of A or G
    origin = by[("origin", "wrist_1_joint")]                                   # 0.2 mm: A changes by ~1e-4
    assert origin.effect["at_rounding"] is False and origin.effect["changes_A"] > EFFECT_ROUNDING


# -- 5, 6. one order, stated wherever the list is printed; the pair's own summary.md and headline ---------------
@pytest.fixture(scope="module")
def against_run(edited_arm, tmp_path_factory):
    out = tmp_path_factory.mktemp("against")
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        code = main(["compare", str(edited_arm[0]), "--against", str(edited_arm[1]), "--t-end", "0.05", "--out",
                     str(out), "--animation-fps", "0", "--quiet"])
    assert code == 0
    return buf.getvalue(), (out / "summary.md").read_text(), (out / "report.html").read_text(), \
        json.loads((out / "summary.json").read_text())


def _effect_of(words: str) -> float:
    """The number a list's ``effect on A, G`` cell orders by: the larger of A's and G's; 0 at rounding or none."""
    values = [float(x) for x in re.findall(r"\b[AG] ([-+0-9.e]+)", words)]
    return max(values, default=0.0)


def test_the_order_is_stated_and_kept_wherever_the_list_is_printed(against_run):
    stdout, md, page, s = against_run
    listed = [(d["kind"], d["urdf"]) for d in s["description_differences"]]
    assert len(listed) == 5
    # stdout: the order in words, then the list in that order, each with its effect on A and G
    assert ORDER_WORDS in stdout
    rows = re.findall(r"^    (\w+)\s+(?:link|joint|frame) (\S+) / \S+: .*effect on A, G: (.*?)(?: \(explained\))?$",
                      stdout, flags=re.M)
    assert [(k, n) for k, n, _ in rows] == listed
    effects = [_effect_of(w) for _, _, w in rows]
    assert effects == sorted(effects, reverse=True) and effects[0] > 0.01
    assert "at rounding" in stdout and "none: not a term of A or G" in stdout
    # summary.md: the same words, the same order
    assert ORDER_WORDS in md
    md_rows = re.findall(r"^\| (\d+) \| (\w+) \| (\w+) \| (\S+) \| \S+ \| [^|]+ \| ([^|]+) \|", md, flags=re.M)
    assert [(k, n) for _, k, _, n, _ in md_rows] == listed
    assert [_effect_of(w) for *_, w in md_rows] == effects
    # the HTML: the same words (escaped as the page writes them), the same order
    assert html.escape(ORDER_WORDS) in page
    table = page[page.index("<h3>Differences</h3>"):]
    html_rows = re.findall(r"<tr><td>\d+</td><td>(\w+) <span class='small'>\(\w+\)</span></td><td><code>([^<]+)</code>"
                           r"</td><td><code>[^<]+</code></td><td>[^<]*</td><td>[^<]*</td><td class='num'>[^<]*</td>"
                           r"<td>([^<]*)</td>", table)
    assert [(k, n) for k, n, _ in html_rows] == listed
    assert [_effect_of(w) for *_, w in html_rows] == effects


def test_the_pairs_summary_md_lists_the_differences_and_its_page_opens_with_the_pair(against_run):
    _stdout, md, page, s = against_run
    assert md.startswith("# ") and "two descriptions of one robot" in md.splitlines()[0]
    for d in s["description_differences"]:            # every difference a row of summary.md
        assert f"| {d['kind']} | {d['part']} | {d['urdf']} |" in md, d["kind"]
    assert md.index("Differences above rounding: 5") < md.index("## ur5_like / default: urdf2links against MuJoCo")
    body = page[page.index("<body>"):]
    h1 = re.search(r"<h1>(.*?)</h1>", body).group(1)
    assert "two descriptions of one robot" in h1
    first_box = re.search(r"<div class='box[^']*'>(.*?)</div>", body).group(1)
    assert "5 difference(s) above rounding" in first_box and "Trajectories" not in first_box
    assert body.index(first_box) < body.index("<b>Trajectories:</b>")
    assert "The first description against MuJoCo" in body[:body.index("<b>Trajectories:</b>")]

"""Planted recovery (issue 46): ``identify URDF --against TWIN --write-urdf FIXED`` finds the changes planted in an
MJCF twin of a 7-joint arm.

The arm: example-robot-data's Panda URDF (tests/corpus.py ``NAMED["panda"]``) with its two finger joints welded
(fixed), so that the arm's seven joints are the coordinates. The twin: the project's own tree of that URDF written
as MJCF by :func:`urdf2links.compare.mujoco_side.mjcf.mjcf_from_model` (route 1: the same frames, H and
coordinates, at full precision), with the URDF's joint damping kept and these changes planted:

- ``panda_link3`` and ``panda_link5``: mass x 1.2, centre of mass moved by (10, -5, 8) mm, the principal-axis
  diagonal of the inertia x 1.1 and ``ixy`` + 1e-4 kg m^2;
- ``panda_joint2``: damping 0.5, armature 0.1; ``panda_joint4``: damping 0.3, armature 0.05, frictionloss 0.8.

The data are noise free: MuJoCo's own ``qacc`` and the torque it was given at each recorded state
(``mj_inverse`` agrees to ~1e-14 N m), so every identifiable combination must come back to rounding; 1e-6
relative is the issue's bound. The frictionloss (MuJoCo: a soft constraint; the fit: the regularised Coulomb
law with v_s = 1e-5 rad/s, the samples with some |q'| < 0.05 rad/s left out) must come back to 2%.

Planted wrong once (by hand, not committed): with the friction band at 0 (the samples in MuJoCo's soft
frictionloss zone kept) the worst planted combination came back 0.74 relative off and the frictionloss 0.739
(7.7%): the first two tests fail; leaving the unwritten armatures out of A in the last test gave A 2.9e-2 apart.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from lxml import etree

from cli_runner import run_cli
from corpus import panda_arm

pytestmark = pytest.mark.usefixtures("corpus_installed")

PLANTED_LINKS = ("panda_link3", "panda_link5")
PLANTED_JOINTS = {"panda_joint2": {"damping": 0.5, "armature": 0.1},
                  "panda_joint4": {"damping": 0.3, "armature": 0.05, "frictionloss": 0.8}}


def _arm_urdf(out):
    return panda_arm(out)


def _twin(urdf, out):
    from urdf2links.compare.mujoco_side.mjcf import mjcf_from_model
    from urdf2links.parsers.parts import parts_model, robot_parts

    parts = robot_parts(urdf)
    model = parts_model(parts).model
    root = etree.fromstring(mjcf_from_model(model, gravity=model.gravity_vector).xml.encode())
    option = root.find("option")
    option.remove(option.find("flag"))          # route 1 switches damping, frictionloss ... off: the twin has them
    for b in root.iter("body"):
        if b.get("name") in PLANTED_LINKS:
            i = b.find("inertial")
            i.set("mass", repr(float(i.get("mass")) * 1.2))
            pos = np.array(i.get("pos").split(), float) + [0.010, -0.005, 0.008]
            i.set("pos", " ".join(repr(float(x)) for x in pos))
            full = np.array(i.get("fullinertia").split(), float)
            full[:3] *= 1.1
            full[3] += 1e-4
            i.set("fullinertia", " ".join(repr(float(x)) for x in full))
    damping = {j.name: j.damping for j, _b in parts.joints}
    for j in root.find("worldbody").iter("joint"):
        name = j.get("name")
        j.set("damping", repr(float(damping[name])))
        for k, v in PLANTED_JOINTS.get(name, {}).items():
            j.set(k, repr(v))
    out.write_text(etree.tostring(root, encoding="unicode"))
    return out


@pytest.fixture(scope="module")
def planted(tmp_path_factory):
    """The arm, its twin, and ``identify ARM --against TWIN --write-urdf FIXED`` run once (its report's JSON)."""
    d = tmp_path_factory.mktemp("identify")
    urdf, twin = _arm_urdf(d / "panda_arm.urdf"), None
    twin = _twin(urdf, d / "panda_twin.xml")
    fixed, out = d / "fixed.urdf", d / "report"
    r = run_cli("identify", str(urdf), "--against", str(twin), "--write-urdf", str(fixed), "--out", str(out))
    assert r.returncode == 0, r.stderr
    fixed_xml, out_xml = d / "fixed.xml", d / "report_mjcf"
    rx = run_cli("identify", str(urdf), "--against", str(twin), "--write-mjcf", str(fixed_xml), "--out", str(out_xml))
    assert rx.returncode == 0, rx.stderr
    return {"urdf": urdf, "twin": twin, "fixed": fixed, "out": out, "stdout": r.stdout,
            "summary": json.loads((out / "identify.json").read_text()), "fixed_xml": fixed_xml,
            "summary_xml": json.loads((out_xml / "identify.json").read_text())}


def _truth(twin) -> dict:
    """The twin's parameters by the library's names (the twin's tree has the arm's links and joints)."""
    from urdf2links.identification import ParameterSet
    from urdf2links.parsers.parts import parts_model, robot_parts

    parts = robot_parts(twin)
    joints = {j.name: j for j, _b in parts.joints}
    model = parts_model(parts).model
    p = ParameterSet.from_model(model, damping={c: joints[c].damping for c in model.coordinate_names},
                                friction={c: joints[c].friction for c in model.coordinate_names})
    return dict(zip(p.names, p.values))


def test_recovers_every_planted_combination(planted):
    """Every base combination the planted changes move comes back to 1e-6 relative (noise-free data: module doc)."""
    s, truth = planted["summary"], _truth(planted["twin"])
    moved = 0
    worst = 0.0
    for b in s["base_parameters"]:
        true = sum(c * truth[name] for name, c in b["terms"])
        if abs(true - b["described"]) <= 1e-9 * max(1.0, abs(true)):
            continue                           # not a planted combination
        if any(name.startswith("friction_") for name, _c in b["terms"]):
            continue                           # the frictionloss: its own bound (next test)
        moved += 1
        worst = max(worst, abs(b["identified"] - true) / abs(true))
    assert moved >= 20, f"only {moved} combinations changed: the planted changes did not reach the fit"
    assert worst <= 1e-6, f"worst relative error of a planted combination {worst:.2e}"


def test_recovers_frictionloss_within_two_percent(planted):
    """MuJoCo's frictionloss 0.8 N m on panda_joint4 (a soft constraint) comes back as the Coulomb friction to 2%."""
    row = next(r for r in planted["summary"]["parameters"] if r["parameter"] == "friction_panda_joint4")
    assert row["identifiable"] and row["changed"]
    assert abs(row["identified"] - 0.8) / 0.8 <= 0.02, row


def test_every_change_listed_and_written(planted):
    """The corrected URDF holds the damping and friction found; every change is on stdout and in the report.
    A URDF has no armature: an armature the data cannot tell from the links' inertias goes into them where the
    inertias stay consistent (panda_joint1's, which the fit moved); panda_joint4's (identified by itself) and
    panda_joint2's (absorbing it would need a negative inertia on panda_link1) are listed as not written, with
    their planted values."""
    from urdf2links.parsers.parts import robot_parts

    s = planted["summary"]
    joints = {j.name: j for j, _b in robot_parts(planted["fixed"]).joints}
    assert abs(joints["panda_joint2"].damping - 0.5) <= 1e-6 * 0.5
    assert abs(joints["panda_joint4"].damping - 0.3) <= 1e-6 * 0.3
    assert abs(joints["panda_joint4"].friction - 0.8) <= 0.02 * 0.8
    arm = {c["element"][6:]: c for c in s["changes"] if c["what"] == "armature"}
    assert set(arm) == {"panda_joint2", "panda_joint4"} and not any(c["written"] for c in arm.values())
    assert abs(arm["panda_joint4"]["after"] - 0.05) <= 1e-6 * 0.05      # identified by itself
    for c in s["changes"]:
        assert f"{c['element']} {c['what']}:" in planted["stdout"]
    assert (planted["out"] / "report.html").exists() and (planted["out"] / "identify.md").exists()


def test_compare_fixed_against_twin_shows_no_dynamic_difference(planted):
    """``compare FIXED --against TWIN``'s part-by-part comparison: G agrees to 1e-9; A agrees to 1e-9 once the
    armatures the report lists as not written (a URDF cannot hold them) are added back at their identified values
    (A of both files' trees at 8 seeded states, the twin's armature included); the planted joints' damping and
    friction agree (to 1e-6 and 2%). The masses, centres of mass and inertias of single links may differ from the
    twin's: only their identifiable combinations are fixed by the motion, and A and G, what they do, agree."""
    from urdf2links.compare.pairs.pair import compare_descriptions_of
    from urdf2links.parsers.parts import parts_model, robot_parts

    pc = compare_descriptions_of(planted["fixed"], planted["twin"])
    s = pc.summary()
    assert s["description_effects"]["mapped"]["G"]["max_rel_difference"] <= 1e-9
    fixed, twin = parts_model(robot_parts(planted["fixed"])).model, parts_model(robot_parts(planted["twin"])).model
    assert fixed.coordinate_names == twin.coordinate_names
    arm = np.zeros(fixed.n)
    for c in planted["summary"]["changes"]:
        if c["what"] == "armature" and not c["written"]:
            arm[fixed.coordinate_names.index(c["element"][6:])] = c["after"]
    rng = np.random.default_rng(0)
    for q in rng.uniform(-2.0, 2.0, size=(8, fixed.n)):
        A_t = twin.mass_matrix(q)
        assert np.max(np.abs(fixed.mass_matrix(q) + np.diag(arm) - A_t)) <= 1e-9 * np.max(np.abs(A_t))
    for d in pc.differences:
        if d.kind == "damping" and d.urdf in PLANTED_JOINTS:
            assert abs(d.urdf_value - d.mjcf_value) <= 1e-6 * abs(d.mjcf_value)
        if d.kind == "friction":
            assert abs(d.urdf_value - d.mjcf_value) <= 0.02 * abs(d.mjcf_value)


def _planted_part(d) -> bool:
    return bool({d.urdf, d.mjcf} & (set(PLANTED_LINKS) | set(PLANTED_JOINTS)))


def _dynamic(pc) -> list:
    from urdf2links.compare.pairs.pair import DYNAMIC_KINDS

    return [d for d in pc.differences if d.kind in DYNAMIC_KINDS and not (d.effect or {}).get("dynamics_equal")]


def _joint_terms_recovered(d) -> bool:
    """A planted damping back to 1e-6 relative, the frictionloss to 2% (the recovery bounds of the issue)."""
    bound = {"damping": 1e-6, "friction": 0.02}.get(d.kind)
    return bound is not None and abs(d.urdf_value - d.mjcf_value) <= bound * abs(d.mjcf_value)


def test_compare_fixed_urdf_lists_no_dynamic_difference_in_the_planted_parts(planted):
    """``compare FIXED.urdf --against TWIN``: the single links' masses, centres of mass and inertias that differ
    form one group "values differ, dynamics equal" (with every other difference undone, A and G agree to rounding:
    only their identifiable combinations are fixed by the motion), not counted as dynamic; what stays dynamic in
    the planted parts is the armature a URDF cannot hold (explained so, and listed by identify as not written, with
    ``--write-mjcf`` named as what writes it) and the damping and friction as recovered (their bounds).
    Planted wrong once: with the armature-shaped part the inertias carry (panda_joint2's 1.8e-4 kg m^2) not taken
    out of the group's residual, the group's A residual was 5.3e-5 > 1e-5 and the 21 inertial differences stayed
    dynamic: this test failed."""
    from urdf2links.compare.pairs.pair import compare_descriptions_of

    pc = compare_descriptions_of(planted["fixed"], planted["twin"])
    s = pc.summary()
    eq = s["description_counts"]["dynamics_equal"]
    assert eq["count"] >= 3 * len(PLANTED_LINKS) and set(eq["kinds"]) <= {"mass", "com", "inertia"}, eq
    assert eq["A"] <= 1e-9 and eq["G"] <= 1e-9, eq           # measured 1.0e-11, 7.0e-12
    not_written = {c["element"][6:]: c for c in planted["summary"]["changes"] if c["what"] == "armature"
                   and not c["written"]}
    for d in _dynamic(pc):
        assert d.kind not in ("mass", "com", "inertia"), d.label()
        if not _planted_part(d):
            continue
        if d.kind == "armature":
            assert d.explanation and d.explanation.startswith("a URDF has no armature"), d.label()
            assert d.urdf in not_written and "--write-mjcf" in not_written[d.urdf]["note"], d.label()
        else:
            assert _joint_terms_recovered(d), (d.label(), d.urdf_value, d.mjcf_value)
    assert s["description_counts"]["dynamics"]["count"] == len(_dynamic(pc))


def test_compare_fixed_mjcf_lists_no_dynamic_difference_in_the_planted_parts(planted):
    """``identify ARM --against TWIN --write-mjcf FIXED.xml`` (a URDF description: its identified tree as MJCF,
    armature included): ``compare FIXED.xml --against TWIN`` lists no armature difference, and no dynamic
    difference in the planted parts but the damping and friction as recovered; A and G agree to 1e-9."""
    from urdf2links.compare.pairs.pair import compare_descriptions_of

    assert all(c["written"] for c in planted["summary_xml"]["changes"] if c["what"] == "armature")
    pc = compare_descriptions_of(planted["fixed_xml"], planted["twin"])
    eff = pc.summary()["description_effects"]["mapped"]
    assert eff["A"]["max_rel_difference"] <= 1e-9 and eff["G"]["max_rel_difference"] <= 1e-9
    for d in _dynamic(pc):
        assert d.kind not in ("mass", "com", "inertia", "armature"), d.label()
        if _planted_part(d):
            assert _joint_terms_recovered(d), (d.label(), d.urdf_value, d.mjcf_value)


def test_a_real_mass_change_stays_dynamic(planted, tmp_path):
    """FIXED.urdf with panda_link5's mass x 1.01 (a real change, nothing compensates it): the inertial differences no
    longer change nothing together, so no group "dynamics equal" is formed and panda_link5's mass is listed as a
    dynamic difference (its effect on G above rounding)."""
    from urdf2links.compare.pairs.effects import EFFECT_ROUNDING
    from urdf2links.compare.pairs.pair import compare_descriptions_of

    root = etree.fromstring(planted["fixed"].read_bytes())
    mass = next(l for l in root.findall("link") if l.get("name") == "panda_link5").find("inertial/mass")
    mass.set("value", repr(float(mass.get("value")) * 1.01))
    heavier = tmp_path / "heavier.urdf"
    heavier.write_text(etree.tostring(root, encoding="unicode"))
    pc = compare_descriptions_of(heavier, planted["twin"])
    assert pc.summary()["description_counts"]["dynamics_equal"]["count"] == 0
    d = next(d for d in _dynamic(pc) if d.kind == "mass" and d.urdf == "panda_link5")
    assert d.effect["changes_G"] > EFFECT_ROUNDING


def test_seeded_states_see_every_combination(planted):
    """Why 8 seeded states suffice (effects.unseen_group): the linear map from the links' H to A and G has the same
    rank at the 8 states ``compare`` evaluates as at 64 states, so a change of H unseen at those 8 is unseen at
    every state (and so are the velocity terms, which follow from A). Measured: rank 45 of the 70 link parameters at
    8 states and at 64. Planted wrong once: with 2 states the rank is 42 (1 state: 29), and the test fails."""
    from urdf2links.compare.pairs.effects import seeded_states
    from urdf2links.identification import ParameterSet, regressor
    from urdf2links.parsers.parts import parts_model, robot_parts

    parts = robot_parts(planted["fixed"])
    model = parts_model(parts).model
    params = ParameterSet.from_model(model, joints=())
    names = model.coordinate_names

    def rank(Q):
        n = len(names)
        Z = np.zeros_like(Q)
        rows = [regressor(params, Q, Z, Z)]                      # G
        for k in range(n):                                        # the columns of A: Y(q, 0, e_k) - G
            E = Z.copy()
            E[:, k] = 1.0
            rows.append(regressor(params, Q, Z, E) - rows[0])
        Y = np.concatenate([r.reshape(-1, r.shape[-1]) for r in rows])
        return int(np.linalg.matrix_rank(Y / np.maximum(np.abs(Y).max(axis=0), 1e-300), tol=1e-9))

    eight = seeded_states(parts, names, set(names), states=8, seed=0)
    many = seeded_states(parts, names, set(names), states=64, seed=1)
    assert rank(eight) == rank(many) > 0


def test_held_out_run_on_the_project_simulation(planted):
    """The held-out validation's urdf2links runs are the project's simulation of a scene (validation.held_out_scene,
    urdf2links.simulate at rtol 1e-10): the identified model stays within 2e-3 rad of OTHER's recording (measured
    7.3e-4: what is left is MuJoCo's 1 ms Euler steps of the recording against a continuous run, O(dt)), ten times
    closer than the description (2.0e-2); on MuJoCo, stepped as OTHER was, the identified model is OTHER to 1e-9.
    Planted wrong once: without the identified damping as the scene's dampers the identified run was 4.2e-3 off
    (fails the 2e-3 bound)."""
    runs = {(v["model"], v["engine"]): v for v in planted["summary"]["validation"]}
    after = max(runs["identified", "urdf2links"]["max_error"])
    before = max(runs["description", "urdf2links"]["max_error"])
    assert "project's simulation" in runs["identified", "urdf2links"]["note"]
    assert after <= 2e-3 and after <= before / 10, (before, after)
    assert max(runs["identified", "MuJoCo"]["max_error"]) <= 1e-9

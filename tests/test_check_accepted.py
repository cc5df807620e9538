"""The rules of ``urdf2links check``'s accepted differences and fingerprints (issue 42), on planted cases: every
rule must catch its wrong case and let the unchanged one pass. Differences are written as the pair summary's JSON
(:meth:`~urdf2links.compare.pairs.pair.PairComparison.summary`); the end-to-end story on real files is in
tests/test_check.py and tests/test_check_edits.py."""

from __future__ import annotations

import copy
import math
import tomllib

import pytest

from urdf2links.compare.check.accepted import accepted_row, judge, read_rows, rows_toml
from urdf2links.compare.check.config import ConfigError
from urdf2links.compare.check.fingerprint import changes


def _d(kind, urdf_value, mjcf_value, difference, unit, *, names=("j1", "j1"), links=("l1", "l1")) -> dict:
    return {"kind": kind, "urdf": names[0], "mjcf": names[1], "urdf_value": urdf_value, "mjcf_value": mjcf_value,
            "difference": difference, "unit": unit, "what": kind, "links": list(links)}


def _origin(u, m, difference, unit, *, turn: float = 0.0) -> dict:
    """An origin difference: the frames' positions ``u``, ``m`` (m), the second turned by ``turn`` rad about z."""
    frames = {}
    for side, p, a in (("urdf", u, 0.0), ("mjcf", m, turn)):
        c, s = math.cos(a), math.sin(a)
        frames[side] = [[c, -s, 0.0, p[0]], [s, c, 0.0, p[1]], [0.0, 0.0, 1.0, p[2]], [0.0, 0.0, 0.0, 1.0]]
    return {**_d("origin", u, m, difference, unit, names=("j2", "j2"), links=("l2", "l2")), "frames": frames}


def _summary(*diffs) -> dict:
    return {"descriptions": {"urdf": {"format": "urdf"}, "mjcf": {"format": "mjcf"}},
            "description_counts": {"root_pose": {"floating": False}}, "description_differences": list(diffs)}


DAMPING = _d("damping", 0.0, 1.0, 1.0, "N m s/rad")
ORIGIN = _origin([0.1, 0.0, 0.0], [0.0, 0.0, 0.0], 0.1, "m", turn=0.01)        # moved 0.1 m, turned 0.01 rad
LIMITS = _d("limits", [-1.0, 1.0], ["nan", "nan"], "inf", "rad")


def _rows(*diffs):
    return tuple(accepted_row(d) for d in diffs)


def test_a_pair_as_accepted_passes_and_the_rows_name_their_parts():
    rows = _rows(DAMPING, ORIGIN, LIMITS)
    assert [r.part for r in rows] == ["joint j1", "link l2", "joint j1"]
    assert rows[2].mjcf == "unlimited" and rows[2].difference == math.inf and math.isfinite(rows[2].tolerance)
    assert judge(_summary(DAMPING, ORIGIN, LIMITS), rows) == []


def test_a_new_difference_fails_whatever_its_kind_and_comes_with_the_row_that_accepts_it():
    new = _d("friction", 0.0, 0.5, 0.5, "N m", names=("j3", "j3"))
    found = judge(_summary(DAMPING, new), _rows(DAMPING))
    assert [(p.what, p.replacement.part) for p in found] == [("new", "joint j3")]
    assert found[0].replacement == accepted_row(new)


@pytest.mark.parametrize("changed, which", [
    (_d("damping", 0.0, 0.5, 0.5, "N m s/rad"), "the difference"),              # halved
    # moved 1 cm across: the distance grows by only 5e-4 m, the MJCF's frame by 1 cm
    (_origin([0.1, 0.0, 0.0], [0.0, 0.01, 0.0], math.hypot(0.1, 0.01), "m", turn=0.01),
     "the mjcf frame's position"),
    # the same distance the other way round: only the frames say it moved
    (_origin([0.1, 0.0, 0.0], [0.2, 0.0, 0.0], 0.1, "m", turn=0.01), "the mjcf frame's position"),
    # turned 0.02 rad more, still less than it moved: the difference (in m) and the positions stay
    (_origin([0.1, 0.0, 0.0], [0.0, 0.0, 0.0], 0.1, "m", turn=0.03), "the mjcf frame's rotation"),
    (_origin([0.1, 0.0, 0.0], [0.0, 0.0, 0.0], 0.5, "rad", turn=0.5), "its unit changed from m to rad"),
    # one-sided: the difference stays inf, the URDF's range moved
    (_d("limits", [-2.0, 2.0], ["nan", "nan"], "inf", "rad"), "the urdf value"),
    # one-sided made two-sided: a limit added on the other side
    (_d("limits", [-1.0, 1.0], [-0.3, 0.3], 0.7, "rad"), "the difference"),
])
def test_an_accepted_difference_that_moved_fails_saying_what_moved(changed, which):
    rows = _rows(DAMPING, ORIGIN, LIMITS)
    base = {"damping": DAMPING, "origin": ORIGIN, "limits": LIMITS}
    base[changed["kind"]] = changed
    found = judge(_summary(*base.values()), rows)
    assert [(p.what, p.row.kind) for p in found] == [("moved", changed["kind"])], found
    assert found[0].detail == which and found[0].moved > found[0].allowed


def test_a_difference_within_its_rows_tolerance_passes_and_a_gone_one_fails():
    rows = _rows(DAMPING, ORIGIN)
    rounding = _d("damping", 0.0, 1.0 + 1e-6, 1.0 + 1e-6, "N m s/rad")         # the 6th digit of a file saved again
    assert judge(_summary(rounding, ORIGIN), rows) == []
    found = judge(_summary(DAMPING), rows)
    assert [(p.what, p.row.part) for p in found] == [("gone", "link l2")]


def test_the_rows_tolerances_catch_a_centimetre_and_a_halving():
    far = _origin([9.0, 0.0, 0.0], [8.0, 0.0, 0.0], 1.0, "m")
    for d in (DAMPING, far, _d("armature", 0.0, 0.1, 0.1, "kg m^2")):
        row = accepted_row(d)
        assert 0 < row.tolerance <= 1e-5 * max(1.0, 9.0), row      # 1e-5 of its size (compare/check/accepted.py)
    assert accepted_row(far).tolerance < 0.01 / 100


def test_rows_written_as_toml_read_back_the_same():
    rows = _rows(DAMPING, ORIGIN, LIMITS, _d("inertia", [[1, 0, 0], [0, 2, 0], [0, 0, 3]], [[1, 0, 0], [0, 2, 0],
                                                                                          [0, 0, 3.3]], 0.08,
                                         "relative"))
    text = "\n".join(rows_toml(rows))
    back = read_rows("x", tomllib.loads(text)["accepted"], lambda w, m: (_ for _ in ()).throw(ConfigError(m)))
    assert back == rows
    assert rows[3].urdf == [1.0, 2.0, 3.0, 0.0, 0.0, 0.0]
    assert rows[1].mjcf == [0.0, 0.0, 0.0, 0.0, 0.0, 0.01]              # an origin's frame: position, rpy


@pytest.mark.parametrize("row, words", [
    ({"kind": "limits", "part": "joint j", "urdf": 0, "mjcf": "none", "difference": math.inf, "unit": "rad",
      "tolerance": math.inf}, ["tolerance = inf", "limits of joint j"]),
    ({"kind": "weight", "part": "joint j", "urdf": 0, "mjcf": 0, "difference": 0, "unit": "", "tolerance": 0},
     ["unknown kind 'weight'"]),
    ({"kind": "mass", "part": "link l", "urdf": 1, "mjcf": 2}, ["missing ['difference', 'unit', 'tolerance']"]),
])
def test_a_bad_row_is_refused_naming_it(row, words):
    def fail(where, msg):
        raise ConfigError(f"{where}: {msg}")

    with pytest.raises(ConfigError) as err:
        read_rows("urdf2links.toml [pairs 1]", [row], fail)
    for w in ["urdf2links.toml [pairs 1]", "accepted[0]", *words]:
        assert w in str(err.value), (w, str(err.value))


FP = {"format": "mjcf", "gravity": [0.0, 0.0, -9.81],
      "bodies": {"b1": {"parent": None, "xyz": [0.0, 0.0, 0.3], "rpy": [1.5707963268, 0.0, 0.0], "mass": 2.0,
                        "com": [0.0, 0.01, 0.0], "inertia": [0.01, 0.02, 0.03, 0.0, 0.0, 0.0]}},
      "joints": {"j1": {"body": "b1", "type": "hinge", "axis": [0.0, 0.0, 1.0], "range": "unlimited",
                        "damping": 0.0, "armature": 0.1}},
      "actuators": {"m1": {"target": "joint j1", "gear": [1.0, 0, 0, 0, 0, 0], "ctrlrange": [-1.0, 1.0],
                           "gaintype": "fixed", "gain": [1.0, 0.0, 0.0]}}}


def _changed(path, value):
    fp = copy.deepcopy(FP)
    *head, last = path
    d = fp
    for k in head:
        d = d[k]
    if value is None:
        del d[last]
    else:
        d[last] = value
    return fp


@pytest.mark.parametrize("path, value, part, quantity", [
    (("bodies", "b1", "xyz"), [0.01, 0.0, 0.3], "body b1", "xyz"),
    (("bodies", "b1", "rpy"), [1.5717963268, 0.0, 0.0], "body b1", "rpy"),               # turned 1e-3 rad
    (("bodies", "b1", "mass"), 2.2, "body b1", "mass"),
    (("joints", "j1", "range"), [-1.0, 1.0], "joint j1", "range"),
    (("joints", "j1", "damping"), 1e-3, "joint j1", "damping"),
    (("joints", "j1", "armature"), 0.05, "joint j1", "armature"),
    (("actuators", "m1", "gaintype"), "affine", "actuator m1", "gaintype"),
    (("actuators", "m1", "gain"), [50.0, 0.0, 0.0], "actuator m1", "gain"),
    (("joints", "j2"), {"body": "b1", "type": "hinge"}, "joint j2", ""),                  # added
    (("actuators", "m1"), None, "actuator m1", ""),                                       # removed
    (("gravity",), [0.0, 0.0, -9.8], "the file", "gravity"),
])
def test_a_fingerprint_names_each_change(path, value, part, quantity):
    found = changes(FP, _changed(path, value))
    assert [(c.part, c.quantity) for c in found] == [(part, quantity)], found
    text = found[0].text("robots/arm.xml")
    assert text.startswith(f"robots/arm.xml: {part}") and "--write-baselines" in text


def test_a_fingerprint_sees_through_the_last_digits():
    noisy = _changed(("bodies", "b1", "inertia"), [0.01 * (1 + 1e-12), 0.02, 0.03, 1e-17, 0.0, 0.0])
    noisy["bodies"]["b1"]["xyz"] = [1e-17, 0.0, 0.3 * (1 + 1e-12)]
    assert changes(FP, noisy) == []


ARM = """<robot name="arm"><link name="base"/>
<link name="hub"/>
<link name="tip"><inertial><origin xyz="0 0 0.1"/><mass value="1"/>
<inertia ixx="0.01" iyy="0.01" izz="0.001" ixy="0" ixz="0" iyz="0"/></inertial></link>
<joint name="j1" type="revolute"><parent link="base"/><child link="hub"/><axis xyz="0 0 1"/>
<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
<joint name="j2" type="revolute"><parent link="hub"/><child link="tip"/><axis xyz="0 1 0"/>
<limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>"""


def test_an_explanation_is_said_only_while_both_files_fit_it(tmp_path):
    """The massless moving ``hub``: MuJoCo's balanced import bounds its mass (boundmass 1e-6), and the mass
    difference is explained so; the MJCF's hub given 0.5 kg by hand is a difference no bound makes: unexplained."""
    from urdf2links.compare.pairs.mujoco_import import save_mujoco_import
    from urdf2links.compare.pairs.pair import compare_descriptions_of

    (tmp_path / "arm.urdf").write_text(ARM)
    xml = save_mujoco_import(tmp_path / "arm.urdf", tmp_path / "arm.xml", keep_geometry=False, balance=True).path

    def hub_mass():
        c = compare_descriptions_of(tmp_path / "arm.urdf", xml)
        return next(d for d in c.differences if d.kind == "mass" and "hub" in d.links)

    bounded = hub_mass()
    assert bounded.mjcf_value == pytest.approx(1e-6) and "boundmass" in bounded.explanation
    text = xml.read_text()
    assert text.count('<body name="hub">') == 1                    # no inertial: MuJoCo's compiler bounds it
    xml.write_text(text.replace('<body name="hub">', '<body name="hub"><inertial pos="0 0 0" mass="0.5" '
                                                     'diaginertia="0.001 0.001 0.001"/>'))
    edited = hub_mass()
    assert edited.mjcf_value == 0.5 and edited.explanation is None

"""Terms level of the MuJoCo comparison, route 2: A and e + G against MuJoCo's own URDF import.

Every shipped robot and every URDF of example-robot-data: relative agreement below 1e-9 on the
original file when MuJoCo accepts it, on the project's repaired text when MuJoCo refuses it
(``urdf2links.compare.agreement.terms``). The assert messages and the ``route`` user property name the route used.
"""

from __future__ import annotations

import difflib
import re
import warnings
from pathlib import Path

import numpy as np
import pytest
from lxml import etree

import mujoco  # a declared dependency: a broken MuJoCo fails the suite

import corpus  # noqa: E402
from urdf2links.compare import MujocoRefused, mujoco_from_urdf, mujoco_terms  # noqa: E402
from urdf2links.compare.agreement.terms import (
    ROUTE_ORIGINAL, ROUTE_REPAIRED, compare_terms_urdf, massless_moving_links, repaired_urdf_text,
)
from urdf2links import InertiaError, Model, URDFError, load_urdf  # noqa: E402

TOL = 1e-9
ROBOTS_DIR = Path(__file__).resolve().parent.parent / "robots"
ROBOTS = sorted(p.name for p in ROBOTS_DIR.glob("*.urdf"))
FLOATING_ONLY = {"free_body.urdf": "one free body: no joint, nothing to compare with a fixed base"}

# Files where MuJoCo refuses even the project's repaired text. icub's repairs once fell below
# mjMINVAL (a point mass losing its mass, repair spheres shrinking, rounding noise kept as a size);
# the importer now re-audits every repair, keeps a point mass's mass and sizes spheres once.
REPAIR_REFUSED_BY_MUJOCO: dict[str, str] = {}  # none since the importer re-audits its repairs
# MuJoCo refuses massless MOVING links that the project accepts (their subtree has mass): the
# ball joints of human.urdf are three revolute joints through massless "virtual" links. Compared
# with a 1e-6 kg sphere on those links on both sides (compare_terms_urdf(massless_moving=...)).
MASSLESS_MOVING = {"human_description/robots/human.urdf": 1e-6}


def _load(source, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        return load_urdf(source, **kw)


def _states(model) -> int:
    return 4 if model.n > 40 else 8


def _check(path, model, request, **kw):
    res = compare_terms_urdf(path, model, states=_states(model), tolerance=TOL, **kw)
    request.node.user_properties.append(("route", res.route))
    request.node.user_properties.append(("max_rel_error", res.max_rel_error))
    msg = f"{path.name}: {res.summary()}\n" + "\n".join(res.notes)
    assert res.passed, msg
    return res


# --------------------------------------------------------------------------- shipped robots


@pytest.mark.parametrize("name", [r for r in ROBOTS if r not in FLOATING_ONLY])
def test_shipped_robot_terms_match_mujoco(name, request):
    path = ROBOTS_DIR / name
    model = _load(path, inertia="repair")
    massless = massless_moving_links(path.read_text())
    res = _check(path, model, request, massless_moving=1e-6)
    if massless or model.info["repaired_H"]:
        # MuJoCo refuses massless moving links (deck_crane's sway_gimbal: a 2-dof pendulum
        # through a massless link): compared with a small sphere on them on both sides
        assert res.route == ROUTE_REPAIRED and res.refusal, res.summary()
    else:
        assert res.route == ROUTE_ORIGINAL and res.refusal is None, res.summary()
    assert res.n == model.n > 0


def test_gravity_is_the_models_on_both_sides(request):
    path = ROBOTS_DIR / "prismatic_revolute.urdf"
    m = load_urdf(path)
    tilted = Model(m.tree, gravity=(0.0, 3.0, -5.0), name=m.name, source=m.source,
                   audit=m.audit, info=m.info)
    res = _check(path, tilted, request)
    assert any("gravity set to (0.0, 3.0, -5.0)" in n for n in res.notes)
    # and the comparison does see gravity: MuJoCo's default gravity would disagree
    mj = mujoco_from_urdf(path)
    q = {"slide": 0.3, "swing": 0.7}
    t = mujoco_terms(mj, q, {"slide": 0.0, "swing": 0.0}, order=tilted.coordinate_names)
    G = tilted.gravity([q[n] for n in tilted.coordinate_names])
    assert np.abs(G - t.bias).max() > 1e-2 * np.abs(t.bias).max()


# --------------------------------------------------------------------------- corpus

CORPUS = corpus.corpus_files()


@pytest.mark.parametrize("rel", CORPUS)
def test_corpus_terms_match_mujoco(rel, request):
    path = corpus.path(rel)
    if rel in corpus.KNOWN_BAD:
        with pytest.raises(URDFError):
            _load(path, inertia="repair")
        return
    model = _load(path, inertia="repair")
    if rel in REPAIR_REFUSED_BY_MUJOCO:
        with pytest.raises(MujocoRefused, match="also refuses the project's repaired text"):
            compare_terms_urdf(path, model, states=1)
        return          # the known refusal, asserted above (a pass that checks it, not an xfail that checks nothing)
    res = _check(path, model, request, massless_moving=MASSLESS_MOVING.get(rel))
    if res.route == ROUTE_REPAIRED:
        assert res.refusal, res.summary()
    else:
        assert res.refusal is None


def test_massless_moving_links_need_the_option():
    rel = "human_description/robots/human.urdf"
    path = corpus.path(rel)
    model = _load(path, inertia="repair")
    assert not model.info["repaired_H"]  # the project accepts the file as it is
    with pytest.raises(MujocoRefused, match="massless_moving=") as info:
        compare_terms_urdf(path, model, states=1)
    assert "left_upperleg_virtual" in info.value.reason
    assert "left_upperleg_virtual" in massless_moving_links(path.read_text())


def test_mujoco_fusestatic_drops_the_inertia_of_massless_links():
    """Why compare_terms_urdf leaves fusestatic off: bolt's feet have mass 0 but an inertia
    tensor. MuJoCo keeps it on an unfused body, but its fusion drops it; the project keeps it.
    Fused, MuJoCo agrees instead with the file whose feet have no inertia at all."""
    rel = "bolt_description/robots/bolt.urdf"
    path = corpus.path(rel)
    model = _load(path, inertia="audit")
    assert {(r.link, r.kind) for r in model.audit} == {("FL_FOOT", "non_positive_mass"),
                                                       ("FR_FOOT", "non_positive_mass")}
    assert compare_terms_urdf(path, model).max_rel_error < TOL  # fusestatic=False
    fused = compare_terms_urdf(path, model, fusestatic=True)
    assert fused.max_rel_error_A > 1e-5  # 1.5e-4: the feet's iyy = 8.4e-7 against A ~ 5e-3

    root = etree.fromstring(path.read_bytes())
    for link in root.iterchildren("link"):
        if link.get("name") in ("FL_FOOT", "FR_FOOT"):
            inertia = link.find("inertial/inertia")
            for k in list(inertia.attrib):
                inertia.set(k, "0")
    no_feet = _load(etree.tostring(root, encoding="unicode"), inertia="audit")
    assert compare_terms_urdf(path, no_feet, fusestatic=True).max_rel_error < TOL


# --------------------------------------------------------------------------- repaired text

REPAIR_ME = """<?xml version="1.0" encoding="utf-8"?>
<!-- a chain with three links the importer repairs -->
<robot name="repair_me">
  <link name="base"/>
  <joint name="j1" type="revolute">
    <parent link="base"/><child link="thin"/>
    <origin xyz="0 0 1" rpy="0.1 0.2 0.3"/><axis xyz="0 1 0"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/>
  </joint>
  <link name="thin">
    <!-- violates the triangle inequality, no geometry: nearest consistent -->
    <inertial>
      <origin xyz="0.1 0 -0.3" rpy="0.3 0 0.5"/>
      <mass value="1.5"/>
      <inertia ixx="0.01" ixy="0.001" ixz="0" iyy="0.01" iyz="0" izz="0.05"/>
    </inertial>
  </link>
  <joint name="j2" type="continuous">
    <parent link="thin"/><child link="boxy"/>
    <origin xyz="0 0.2 -0.6"/><axis xyz="1 0 0"/>
  </joint>
  <link name="boxy">
    <inertial>
      <origin xyz="0 0 -0.2"/>
      <mass value="0.8"/>
      <inertia ixx="-0.01" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.02"/>
    </inertial>
    <collision><origin xyz="0 0 -0.2"/><geometry><box size="0.1 0.2 0.4"/></geometry></collision>
  </link>
  <joint name="j3" type="prismatic">
    <parent link="boxy"/><child link="tip"/>
    <origin xyz="0 0 -0.4"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/>
  </joint>
  <link name="tip"/>
</robot>
"""


def _outside_inertials(text: str, links) -> bytes:
    """The document without the repaired links' <inertial> (and the whitespace inside those
    links: a created <inertial> indents a link that was written <link name="..."/>)."""
    root = etree.fromstring(text.encode("utf-8"))
    for link in root.iterchildren("link"):
        if link.get("name") in links:
            for el in link.findall("inertial"):
                link.remove(el)
            if link.text is not None and not link.text.strip():
                link.text = None
            for el in link:
                if el.tail is not None and not el.tail.strip():
                    el.tail = None
    return etree.tostring(root)


def _assert_round_trip(path, model):
    text = repaired_urdf_text(path, model)
    repaired = set(model.info["repaired_H"])
    original = path.read_text()
    assert _outside_inertials(text, repaired) == _outside_inertials(original, repaired)
    again = _load(text, inertia="strict")  # raises InertiaError on any finding
    assert again.audit == []
    assert again.coordinate_names == model.coordinate_names
    rng = np.random.default_rng(3)
    for _ in range(3):
        q = rng.uniform(-1, 1, model.n)
        qd = rng.standard_normal(model.n)
        A = model.mass_matrix(q)
        np.testing.assert_allclose(again.mass_matrix(q), A, rtol=0, atol=1e-12 * np.abs(A).max())
        b = model.bias(q, qd) + model.gravity(q)
        np.testing.assert_allclose(again.bias(q, qd) + again.gravity(q), b, rtol=0,
                                   atol=1e-12 * max(np.abs(b).max(), 1.0))
    return text


@pytest.mark.parametrize("nl", ["\n", "\r\n"], ids=["LF", "CRLF"])
def test_repaired_text_round_trips(tmp_path, request, nl):
    path = tmp_path / "repair_me.urdf"
    path.write_bytes(REPAIR_ME.replace("\n", nl).encode())
    model = load_urdf(path, inertia="repair")
    kinds = {(r.link, r.kind) for r in model.audit}
    assert {"thin", "boxy", "tip"} <= {link for link, _ in kinds}
    assert all(r.action == "repaired" for r in model.audit)
    assert set(model.info["repaired_H"]) == {"thin", "boxy", "tip"}
    text = _assert_round_trip(path, model)

    # every other byte kept: only lines of the three repaired inertials differ
    before, after = REPAIR_ME.split("\n"), text.split(nl)
    changed = [ln[0] + ln[1:].strip() for ln in difflib.unified_diff(before, after, lineterm="", n=0)
               if ln[:1] in "+-" and not ln.startswith(("+++", "---"))]
    assert changed and all(re.search(r"<(/?inertial|origin|mass|inertia)\b", ln) or
                           ln in ('-<link name="tip"/>', '+<link name="tip">', "+</link>")
                           for ln in changed), "\n".join(changed)
    assert "\r\n" not in text.replace(nl, "") and text.count(nl) >= REPAIR_ME.count("\n")
    assert text.startswith('<?xml version="1.0" encoding="utf-8"?>' + nl + '<!-- a chain with three')
    assert "<!-- violates the triangle inequality, no geometry: nearest consistent -->" in text
    assert '<link name="base"/>' in text
    assert '<collision><origin xyz="0 0 -0.2"/><geometry><box size="0.1 0.2 0.4"/>' in text
    tip = etree.fromstring(text.encode()).find("link[@name='tip']/inertial")
    assert tip is not None and tip.find("origin").get("rpy") == "0 0 0"
    # the repaired values, in the URDF sign convention (ixy = -integral(x y dm))
    thin = etree.fromstring(text.encode()).find("link[@name='thin']/inertial/inertia")
    assert float(thin.get("ixy")) != 0.0

    # the audit model leaves the file as it is; MuJoCo refuses it, and accepts the repaired text
    with pytest.raises(MujocoRefused):
        compare_terms_urdf(path, _load(path, inertia="audit"))
    res = _check(path, model, request)
    assert res.route == ROUTE_REPAIRED and res.refusal
    assert any("REPAIRED" in n for n in res.notes)


def test_no_repair_means_the_file_unchanged():
    path = ROBOTS_DIR / "double_pendulum.urdf"
    assert repaired_urdf_text(path, load_urdf(path, inertia="repair")) == path.read_text()


READABLE = [rel for rel in corpus.corpus_files() if rel not in corpus.KNOWN_BAD]


# The repaired model is not clean by the importer's own audit, so its text fails inertia="strict":
ROUND_TRIP_FAILS: dict[str, tuple[str, str]] = {}  # none since the importer re-audits its repairs


@pytest.mark.parametrize("rel", READABLE)
def test_corpus_repaired_text_round_trips(rel):
    path = corpus.path(rel)
    model = _load(path, inertia="repair")
    if not model.info["repaired_H"]:        # nothing repaired: the file's text comes back byte for byte
        assert repaired_urdf_text(path, model) == path.read_bytes().decode("utf-8"), rel
        return
    if rel in ROUND_TRIP_FAILS:
        match, _why = ROUND_TRIP_FAILS[rel]
        with pytest.raises(InertiaError, match=match):
            _assert_round_trip(path, model)
        return          # the known failure, asserted above with its message (a pass that checks it, not an xfail)
    _assert_round_trip(path, model)


# --------------------------------------------------------------------------- misuse


def test_repaired_model_is_replaced_by_the_file_when_mujoco_accepts_it(request):
    """so101.urdf loads in MuJoCo as written, and the importer repairs one of its inertias: the comparison
    uses the file as written (route "original") against the model loaded as written (inertia='audit'),
    and says so. (panda, used here before, has nothing to repair: the test could not fail.)"""
    path = corpus.path("so_arm_description/urdf/so101.urdf")
    model = _load(path, inertia="repair")
    assert model.info["repaired_H"], "the premise: a repaired model"
    res = _check(path, model, request)
    assert res.route == ROUTE_ORIGINAL and res.refusal is None, res.summary()
    assert any("inertia='audit'" in n for n in res.notes), res.notes


def test_refused_file_needs_a_repaired_model():
    path = corpus.path("anymal_b_simple_description/robots/anymal.urdf")
    with pytest.raises(MujocoRefused, match="inertia='repair'"):
        compare_terms_urdf(path, _load(path, inertia="audit"))


def test_floating_base_and_coupled_mimic_are_refused():
    path = ROBOTS_DIR / "double_pendulum.urdf"
    with pytest.raises(ValueError, match="fixed base only"):
        compare_terms_urdf(path, load_urdf(path, floating_base=True))
    mimic = """<robot name="m"><link name="a"/>
      <link name="b"><inertial><mass value="1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>
      <link name="c"><inertial><origin xyz="0.3 0 0"/><mass value="1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>
      <joint name="j1" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/>
        <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
      <joint name="j2" type="revolute"><parent link="b"/><child link="c"/><axis xyz="0 1 0"/>
        <limit lower="-1" upper="1" effort="1" velocity="1"/><mimic joint="j1" multiplier="2"/></joint></robot>"""
    import tempfile
    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / "mimic.urdf"
        p.write_text(mimic)
        with pytest.raises(ValueError, match="mimic='independent'"):
            compare_terms_urdf(p, load_urdf(p, mimic="coupled"))
        res = compare_terms_urdf(p, load_urdf(p, mimic="independent"), tolerance=TOL)
        assert res.passed and res.n == 2, res.summary()
        assert any("equality constraint" in n for n in res.notes)

"""Fuzzing MJCF text (issue 24): nothing crashes, nothing hangs, nothing comes out non-finite.

Mutants of the test MJCF files (tests/mjcf_models.py) and of gymnasium's models, changed the way
tests/fuzz_inputs.py changes URDF (a number replaced by nan, inf, 1e308, a negative, garbage; an
attribute or element deleted or duplicated; a joint type garbled; names duplicated; the text
truncated or garbled), end in a :class:`~urdf2links.dynamics.model.Model` whose terms and map to
MuJoCo's state are finite at finite states (forward dynamics finite, or a DynamicsError), or in an
:class:`~urdf2links.errors.MJCFError`. Anything else, or an example past its time limit, fails.

Budget: the hypothesis profile's ``max_examples`` (tests/conftest.py): "ci" 200 derandomized, "slow"
5000. The outcomes are counted and their shares asserted (as tests/test_fuzz.py does): at least
``SHARE`` of the mutants load and at least ``SHARE`` are refused, so that a mutator that breaks every
input, or one that changes nothing, fails the test instead of passing on nothing.
"""

from __future__ import annotations

import collections
import importlib.resources
import tempfile
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from lxml import etree

from fuzz_inputs import BAD_NUMBERS, OVERFLOWING
from mjcf_models import INCLUDED, MODELS
from test_fuzz import SHARE, Hang, time_limit  # noqa: F401 - Hang is what time_limit raises
from urdf2links import load_mjcf
from urdf2links.errors import DynamicsError, MJCFError

LIMIT_S = 30.0
BASE = settings.default.max_examples
COUNTS: collections.Counter = collections.Counter()
GYM = sorted(p.name for p in importlib.resources.files("gymnasium").joinpath("envs", "mujoco", "assets").iterdir()
             if p.name.endswith(".xml"))
JOINT_TYPES = ("hinge", "slide", "ball", "free", "HINGE", "", "revolute", "fixed")
NUMERIC = ("pos", "quat", "euler", "axis", "size", "mass", "density", "fromto", "range", "ref", "armature", "damping",
           "stiffness", "springref", "gravity", "diaginertia", "fullinertia", "gravcomp", "timestep", "frictionloss")


@pytest.fixture(scope="module")
def folder():
    with tempfile.TemporaryDirectory() as d:
        for name, text in INCLUDED.items():
            (Path(d) / name).write_text(text)
        yield Path(d)


def _base_text(draw) -> str:
    if draw(st.booleans()):
        return MODELS[draw(st.sampled_from(sorted(MODELS)))]
    name = draw(st.sampled_from(GYM))
    return importlib.resources.files("gymnasium").joinpath("envs", "mujoco", "assets", name).read_text()


def _mutate(draw, root) -> None:
    els = [el for el in root.iter() if isinstance(el.tag, str)]
    op = draw(st.sampled_from(["number", "number", "number", "delete_attr", "delete_el", "duplicate_el", "type",
                               "dup_name", "add_joint"]))
    if op in ("number", "delete_attr"):
        owners = [(el, a) for el in els for a in el.attrib]
        numeric = [(el, a) for el, a in owners if a in NUMERIC]
        if not owners:
            return
        el, attr = draw(st.sampled_from(numeric if numeric and draw(st.booleans()) else owners))
        if op == "delete_attr":
            del el.attrib[attr]
        else:
            el.set(attr, draw(st.sampled_from(OVERFLOWING + BAD_NUMBERS + ("1e-300", "1e30", "0 0 0 0", "1 0 0 0"))))
    elif op in ("delete_el", "duplicate_el"):
        el = draw(st.sampled_from(els[1:] or els))
        parent = el.getparent()
        if parent is None:
            return
        if op == "delete_el":
            parent.remove(el)
        else:
            parent.insert(parent.index(el), etree.fromstring(etree.tostring(el)))
    elif op == "type":
        joints = [el for el in els if el.tag == "joint"]
        if joints:
            draw(st.sampled_from(joints)).set("type", draw(st.sampled_from(JOINT_TYPES)))
    elif op == "dup_name":
        named = [el for el in els if el.get("name") is not None]
        if len(named) >= 2:
            draw(st.sampled_from(named)).set("name", draw(st.sampled_from(named)).get("name"))
    else:
        bodies = [el for el in els if el.tag == "body"]
        if bodies:
            j = etree.SubElement(draw(st.sampled_from(bodies)), "joint")
            j.set("type", draw(st.sampled_from(JOINT_TYPES[:4])))
            j.set("pos", draw(st.sampled_from(["0 0 0", "0.1 -0.2 0.3", "nan 0 0", "1e308 0 0"])))


@st.composite
def mutated_mjcf(draw) -> str:
    root = etree.fromstring(_base_text(draw).encode())
    for _ in range(draw(st.integers(1, 3))):
        _mutate(draw, root)
    text = etree.tostring(root, encoding="unicode")
    op = draw(st.sampled_from(["none", "none", "none", "truncate", "garbage"]))
    if op == "truncate":
        return text[:draw(st.integers(0, max(0, len(text) - 1)))]
    if op == "garbage":
        i = draw(st.integers(0, len(text)))
        return text[:i] + draw(st.sampled_from(["<", "&", "\x00", "]]>", "<!--", "<body>", "\ufeff"])) + text[i:]
    return text


def _check_finite(model, text):
    rng = np.random.default_rng(0)
    for q, qd in ((model.info["q0"] + rng.uniform(-3, 3, model.n), rng.normal(size=model.n)),
                  (np.full(model.n, 1e3), 10 * rng.normal(size=model.n))):
        with np.errstate(all="raise"):
            terms = {"A": model.mass_matrix(q), "e": model.bias(q, qd), "G": model.gravity(q)}
        for name, v in terms.items():
            assert np.all(np.isfinite(v)), f"{name} not finite:\n{text}"
        qpos, qvel = model.to_mujoco(q, qd)
        assert np.all(np.isfinite(qpos)) and np.all(np.isfinite(qvel)), text
        try:
            qdd = model.forward_dynamics(q, qd)
        except DynamicsError:
            COUNTS["DynamicsError"] += 1
            continue
        assert np.all(np.isfinite(qdd)), text


def test_mutated_mjcf_ends_in_a_model_or_an_mjcf_error(folder):
    COUNTS.clear()
    _mjcf_mutants(folder=folder)
    total = COUNTS["loaded"] + COUNTS["MJCFError"]
    # the derandomized ci profile: 200 mutants, 52 loaded (26 %), 148 refused (74 %); 10 % either way
    # (test_fuzz.SHARE) is clear of both, and of a mutator that breaks or keeps every input
    print(f"\nMJCF mutants: {total} outcomes: " + ", ".join(f"{k} {v}" for k, v in sorted(COUNTS.items())))
    assert total >= BASE // 2, f"only {total} of {BASE} MJCF mutants ran: {dict(COUNTS)}"
    assert COUNTS["loaded"] >= SHARE * total, f"too few MJCF mutants loaded: {dict(COUNTS)}"
    assert COUNTS["MJCFError"] >= SHARE * total, f"too few MJCF mutants refused: {dict(COUNTS)}"


@settings(max_examples=BASE, suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(text=mutated_mjcf())
def _mjcf_mutants(text, folder):
    path = folder / "mutant.xml"
    path.write_text(text, encoding="utf-8", errors="surrogatepass")
    with time_limit(LIMIT_S, "loading an MJCF mutant"), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            model = load_mjcf(path)
        except MJCFError as err:
            COUNTS["MJCFError"] += 1
            assert str(path) in str(err), err
            return
        _check_finite(model, text)
    COUNTS["loaded"] += 1

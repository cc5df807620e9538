"""Tests of urdf2links.scenes.functions: prescribed functions of time and their TOML specs."""

from __future__ import annotations

import math
import tomllib

import numpy as np
import pytest

from urdf2links.scenes.functions import (
    Constant, SceneValueError, Sines, Table, TimeFunction, VectorFunction, parse_function, vector_function,
)

WHERE = "scene.toml: [base] heave"


def _table(kind="cubic", n=9, seed=0):
    rng = np.random.default_rng(seed)
    times = np.cumsum(rng.uniform(0.2, 1.0, n))
    values = rng.normal(size=n)
    return Table(times.tolist(), values.tolist(), kind=kind)


# ---- Constant ------------------------------------------------------------------------------


def test_constant_value_and_zero_derivatives():
    c = Constant(2.5)
    assert c(3.0) == 2.5 and isinstance(c(3.0), float)
    assert c.derivative(1.0) == 0.0 and c.second_derivative(1.0) == 0.0
    t = np.linspace(0, 1, 7).reshape(7, 1)
    assert c(t).shape == (7, 1) and np.all(c(t) == 2.5)
    assert np.all(c.second_derivative(t) == 0.0)
    assert "2.5" in c.describe()


def test_constant_rejects_non_finite():
    for bad in (float("nan"), float("inf"), True, "1.0"):
        with pytest.raises(ValueError, match="value"):
            Constant(bad)


# ---- Sines ---------------------------------------------------------------------------------


def test_sines_exact_derivatives_against_analytic():
    rng = np.random.default_rng(1)
    terms = [tuple(rng.uniform([0.1, 0.05, -3], [2.0, 2.0, 3])) for _ in range(3)]
    offset, rate = 0.7, -0.3
    s = Sines(offset=offset, terms=terms, rate=rate)
    t = rng.uniform(-5, 20, 50)
    val = offset + rate * t + sum(a * np.sin(2 * np.pi * f * t + p) for a, f, p in terms)
    d1 = rate + sum(a * 2 * np.pi * f * np.cos(2 * np.pi * f * t + p) for a, f, p in terms)
    d2 = sum(-a * (2 * np.pi * f) ** 2 * np.sin(2 * np.pi * f * t + p) for a, f, p in terms)
    np.testing.assert_allclose(s(t), val, rtol=0, atol=1e-12)
    np.testing.assert_allclose(s.derivative(t), d1, rtol=0, atol=1e-11)
    np.testing.assert_allclose(s.second_derivative(t), d2, rtol=0, atol=1e-10)
    for ti, vi, d1i, d2i in zip(t[:5], val, d1, d2):  # scalar path agrees
        assert s(float(ti)) == pytest.approx(vi, abs=1e-12)
        assert s.derivative(float(ti)) == pytest.approx(d1i, abs=1e-11)
        assert s.second_derivative(float(ti)) == pytest.approx(d2i, abs=1e-10)


def test_sines_phase_optional_and_describe():
    s = Sines(terms=[(0.5, 0.25)], rate=0.1)
    assert s.terms == ((0.5, 0.25, 0.0),)
    assert s(1.0) == pytest.approx(0.1 + 0.5 * math.sin(2 * math.pi * 0.25))
    text = s.describe()
    assert "0.1*t" in text and "sin(2*pi*0.25*t" in text
    assert Sines().describe() == "0"
    assert Sines()(np.zeros(4)).shape == (4,)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"terms": [(1.0,)]}, r"terms\[0\]"),
        ({"terms": [(1.0, -2.0)]}, "frequency_hz must be >= 0"),
        ({"terms": [(1.0, float("nan"))]}, "frequency_hz"),
        ({"offset": float("inf")}, "offset"),
        ({"rate": "fast"}, "rate"),
        ({"terms": "abc"}, "terms"),
    ],
)
def test_sines_validation(kwargs, match):
    with pytest.raises(ValueError, match=match):
        Sines(**kwargs)


# ---- Table ---------------------------------------------------------------------------------


@pytest.mark.parametrize("kind", ["cubic", "quintic"])
def test_table_reproduces_samples(kind):
    tab = _table(kind)
    np.testing.assert_allclose(tab(np.array(tab.times)), tab.values, atol=1e-12)
    assert tab(tab.times[3]) == pytest.approx(tab.values[3], abs=1e-12)


@pytest.mark.parametrize("kind", ["cubic", "quintic"])
def test_table_derivatives_match_central_differences(kind):
    tab = _table(kind, seed=2)
    rng = np.random.default_rng(3)
    t = rng.uniform(tab.times[0] + 0.01, tab.times[-1] - 0.01, 40)
    h = 1e-5
    fd1 = (tab(t + h) - tab(t - h)) / (2 * h)
    fd2 = (tab.derivative(t + h) - tab.derivative(t - h)) / (2 * h)
    fd2b = (tab(t + h) - 2 * tab(t) + tab(t - h)) / h**2
    np.testing.assert_allclose(tab.derivative(t), fd1, atol=1e-6)
    np.testing.assert_allclose(tab.second_derivative(t), fd2, atol=1e-5)
    np.testing.assert_allclose(tab.second_derivative(t), fd2b, atol=1e-3)


@pytest.mark.parametrize("kind", ["cubic", "quintic"])
def test_table_second_derivative_continuous_at_knots(kind):
    tab = _table(kind, seed=4)
    knots = np.array(tab.times[1:-1])
    eps = 1e-9
    for fn in (tab, tab.derivative, tab.second_derivative):
        np.testing.assert_allclose(fn(knots - eps), fn(knots + eps), atol=1e-6)


def test_table_holds_end_values_outside():
    tab = _table()
    t = np.array([tab.times[0] - 5.0, tab.times[0] - 1e-3, tab.times[-1] + 1e-3, tab.times[-1] + 9.0])
    np.testing.assert_allclose(tab(t), [tab.values[0]] * 2 + [tab.values[-1]] * 2, atol=1e-15)
    assert np.all(tab.derivative(t) == 0.0) and np.all(tab.second_derivative(t) == 0.0)
    assert "held at the end values with zero derivatives outside" in tab.describe() and "9 samples" in tab.describe()


def test_table_two_samples_is_linear():
    tab = Table([0.0, 2.0], [1.0, 3.0])
    assert tab(0.5) == pytest.approx(1.5)
    assert tab.derivative(1.0) == pytest.approx(1.0)
    assert tab.second_derivative(1.0) == pytest.approx(0.0)


@pytest.mark.parametrize(
    "args, kwargs, match",
    [
        (([0, 1, 1, 2], [0, 1, 2, 3]), {}, r"strictly increasing.*times\[1\]=1.0 then times\[2\]=1.0"),
        (([0, 2, 1], [0, 1, 2]), {}, "strictly increasing"),
        (([0, 1, 2], [0, 1]), {}, "same length.*3 times and 2 values"),
        (([0.0], [1.0]), {}, "at least 2 samples"),
        (([0, 1, 2, 3], [0, 1, 2, 3]), {"kind": "quintic"}, "quintic table needs at least 6"),
        (([0, float("nan")], [0, 1]), {}, r"times\[1\] must be a finite number"),
        (([0, 1], [0, float("inf")]), {}, r"values\[1\]"),
        (([0, 1], [0, 1]), {"kind": "linear"}, "kind must be one of.*cubic.*quintic.*'linear'"),
        ((3.0, [0, 1]), {}, "times must be a list"),
    ],
)
def test_table_validation(args, kwargs, match):
    with pytest.raises(ValueError, match=match):
        Table(*args, **kwargs)


def test_functions_are_frozen_and_comparable():
    s = Sines(offset=1.0, terms=[[1, 2, 3]])
    with pytest.raises(AttributeError):
        s.offset = 2.0
    assert s == Sines(offset=1.0, terms=((1.0, 2.0, 3.0),))
    assert Table([0, 1], [0, 1]) == Table([0.0, 1.0], [0.0, 1.0])
    assert isinstance(s, TimeFunction)
    with pytest.raises(TypeError):
        TimeFunction()


# ---- vectorized shapes ---------------------------------------------------------------------


@pytest.mark.parametrize("fn", [Constant(1.0), Sines(terms=[(1, 1, 0)], rate=1), Table([0, 1, 2], [0, 1, 0])])
@pytest.mark.parametrize("shape", [(), (5,), (2, 3)])
def test_vectorized_shapes(fn, shape):
    t = np.random.default_rng(5).uniform(0, 2, shape)
    for method in (fn, fn.derivative, fn.second_derivative):
        out = method(t)
        if shape == ():
            assert isinstance(out, float)
        else:
            assert isinstance(out, np.ndarray) and out.shape == shape
            assert out.flat[0] == pytest.approx(method(float(t.flat[0])))


def test_vector_function_shapes_and_values():
    v = vector_function([0.5, {"sines": [[1.0, 0.5, 0.0]]}, {"times": [0, 1, 2], "values": [0, 1, 0]}],
                        where="scene.toml: [base] position")
    assert isinstance(v, VectorFunction) and len(v) == 3
    assert v(0.25).shape == (3,) and v.derivative(0.25).shape == (3,) and v.second_derivative(0.25).shape == (3,)
    t = np.linspace(0, 2, 11)
    for method in (v, v.derivative, v.second_derivative):
        assert method(t).shape == (3, 11)
    np.testing.assert_allclose(v(t)[1], np.sin(np.pi * t), atol=1e-12)
    np.testing.assert_allclose(v.derivative(t)[0], 0.0)
    assert v(1.0)[2] == pytest.approx(1.0)
    assert v.describe().count(";") == 2


# ---- parse_function / TOML ------------------------------------------------------------------


def test_parse_from_toml_document():
    doc = tomllib.loads("""
        [base]
        heave = { sines = [[0.5, 0.1, 0.0], [0.1, 0.3]], offset = 1.0, rate = 0.02 }
        surge = { rate = 0.5 }
        sway = 0.25
        yaw = { constant = -1 }
        pitch = { times = [0, 1, 2, 3, 4, 5], values = [0, 0.1, 0.05, 0, -0.1, 0], kind = "quintic" }
        roll = { times = [0, 1, 2], values = [0, 0.1, 0] }
        position = [0, { sines = [[1, 1]] }, 2.0]
    """)["base"]
    heave = parse_function(doc["heave"], where=WHERE)
    assert heave == Sines(offset=1.0, terms=[(0.5, 0.1, 0.0), (0.1, 0.3, 0.0)], rate=0.02)
    assert parse_function(doc["surge"], where=WHERE) == Sines(rate=0.5)
    assert parse_function(doc["sway"], where=WHERE) == Constant(0.25)
    assert parse_function(doc["yaw"], where=WHERE) == Constant(-1.0)
    pitch = parse_function(doc["pitch"], where=WHERE)
    assert isinstance(pitch, Table) and pitch.kind == "quintic"
    roll = parse_function(doc["roll"], where=WHERE)
    assert isinstance(roll, Table) and roll.kind == "cubic"
    assert vector_function(doc["position"], where=WHERE)(0.0).tolist() == [0.0, 0.0, 2.0]


@pytest.mark.parametrize(
    "spec, fragments",
    [
        ({"sine": [[1, 1]]}, ["unknown key 'sine'", "did you mean 'sines'", "'constant'", "'times'"]),
        ({"time": [0, 1], "values": [0, 1]}, ["unknown key 'time'", "did you mean 'times'"]),
        ({"frequency": 1}, ["unknown key 'frequency'", "valid keys are"]),
        ({"constant": 1, "rate": 2}, ["more than one function form", "'constant', 'rate'"]),
        ({}, ["no function form", "sines = "]),
        ({"kind": "cubic"}, ["missing 'times'"]),
        ({"times": [0, 1]}, ["missing 'values'"]),
        ("1.0", ["expected a number", "got '1.0'"]),
        (True, ["expected a number", "got True"]),
        ([1, 2], ["expected a number"]),
        (float("nan"), ["value must be a finite number"]),
        ({"constant": "x"}, ["value must be a finite number, got 'x'"]),
        ({"sines": [[1, -1]]}, ["sines[0] frequency_hz must be >= 0"]),
        ({"sines": [[1]]}, ["sines[0] must be [amplitude, frequency_hz]"]),
        ({"sines": [[1, 1]], "offset": "a"}, ["offset must be a finite number"]),
        ({"times": [0, 0], "values": [0, 1]}, ["strictly increasing"]),
        ({"times": [0, 1], "values": [0, 1], "kind": "spline"}, ["kind must be one of", "'spline'"]),
    ],
)
def test_parse_errors_name_place_key_and_choices(spec, fragments):
    with pytest.raises(SceneValueError) as info:
        parse_function(spec, where=WHERE)
    msg = str(info.value)
    assert msg.startswith(WHERE + ": ")
    for fragment in fragments:
        assert fragment in msg, (fragment, msg)
    assert isinstance(info.value, ValueError)


def test_vector_function_errors():
    with pytest.raises(SceneValueError, match=r"\[base\] position: expected a list of 3 functions"):
        vector_function([1, 2], where="[base] position")
    with pytest.raises(SceneValueError, match=r"expected a list of 6"):
        vector_function({"constant": 1}, where="[base] motion", length=6)
    with pytest.raises(SceneValueError, match=r"^\[base\] position\[1\]: unknown key 'sine'"):
        vector_function([0, {"sine": [[1, 1]]}, 0], where="[base] position")
    with pytest.raises(ValueError, match=r"components\[0\] must be a TimeFunction"):
        VectorFunction((1.0,))

"""Batched forward dynamics in SIMD lanes (``urdf2links.dynamics.lane_batch``, issue 48) against the scalar rows
(``Model.forward_dynamics(..., lanes=False)``, ``model_kernels.fd_batch``).

The lanes do the scalar rows' operations in the same order, without fastmath, and call the same libm ``cos`` and
``sin``: the results are expected to be equal to the last bit (measured: 0 difference on the twelve robots).
The check allows 1e-14 relative to the largest ``|q''|`` of the row (the issue's tolerance: rounding of a
reordered sum would stay far below it on these robots, whose ``q''`` the scalar rows give to ~1e-13 of MuJoCo's).
Planted wrong cases, each seen to fail once: ``_rates`` in ``lane_kernels`` with ``+ v2 * s1`` for ``- v2 * s1``
in the first linear acceleration row (all twelve robots failed); the padded tail block loading row ``B - 2``
instead of ``B - 1`` (five of the six tail cases failed, all but B = 1); the lanes' pivot status not written
back (status -1 for every row: the singular-row test failed, no DynamicsError).
"""

from __future__ import annotations

import warnings

import numba
import numpy as np
import pytest

import corpus
from test_batch_dynamics import _slider
from urdf2links import DynamicsError, load_urdf
from urdf2links.dynamics.model import _lanes_for

TOL = 1e-14         # relative to the largest |q''| of the row (module doc)

ROBOTS = corpus.TWELVE       # the twelve example-robot-data robots of the equality tests
_LOADED: dict = {}


def _robot(name):
    if name not in _LOADED:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")     # inertia findings: not what these tests check
            _LOADED[name] = load_urdf(corpus.path(ROBOTS[name]), inertia="repair")
    return _LOADED[name]


def _states(model, B, seed):
    rng = np.random.default_rng(seed)
    return rng.uniform(-1.5, 1.5, (B, model.n)), rng.normal(size=(B, model.n)), rng.normal(size=(B, model.n))


def _max_relative(lanes, rows):
    """The largest difference of a row, relative to the row's largest |q''|, over the rows."""
    scale = np.maximum(np.abs(rows).max(axis=1), np.finfo(float).tiny)
    return float((np.abs(lanes - rows).max(axis=1) / scale).max())


@corpus.needs_corpus
@pytest.mark.parametrize("name", list(ROBOTS))
def test_lanes_equal_the_scalar_rows(name):
    """37 states (a block of 32 and a padded tail on an AVX-512 machine) with and without torques and gravity."""
    model = _robot(name)
    assert _lanes_for(model.compiled.TI, False, False, model.coupling is not None), "not a batch the lanes compute"
    Q, QD, TAU = _states(model, 37, 3)
    for kw in ({}, {"tau": TAU}, {"gravity": False}):
        tau = kw.get("tau")
        grav = kw.get("gravity", True)
        lanes = model.forward_dynamics(Q, QD, tau, gravity=grav)
        rows = model.forward_dynamics(Q, QD, tau, gravity=grav, lanes=False)
        assert lanes.shape == rows.shape == (37, model.n)
        err = _max_relative(lanes, rows)
        assert err <= TOL, (name, kw.keys(), err)


@corpus.needs_corpus
@pytest.mark.parametrize("B", [1, 3, 31, 32, 33, 70])
def test_tail_blocks(B):
    """Batches shorter than a block, a block exactly and blocks with a padded tail: every row as the scalar rows."""
    model = _robot("ur5")
    Q, QD, TAU = _states(model, B, 4)
    lanes = model.forward_dynamics(Q, QD, TAU)
    assert _max_relative(lanes, model.forward_dynamics(Q, QD, TAU, lanes=False)) <= TOL


@corpus.needs_corpus
def test_threads_one_and_two_give_the_same_rows():
    model = _robot("talos")
    Q, QD, _ = _states(model, 101, 5)
    before = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        one = model.forward_dynamics(Q, QD)
        numba.set_num_threads(min(2, numba.config.NUMBA_NUM_THREADS))
        two = model.forward_dynamics(Q, QD)
    finally:
        numba.set_num_threads(before)
    assert np.array_equal(one, two)


def test_a_singular_lane_names_its_row():
    """The slider's mass matrix is singular with the mass on the axis: rows 34 (in the padded tail) and 3 (the first
    block) of 40; the error names row 3, as the scalar rows do, and the coordinate of the first failing pivot."""
    model = _slider()
    rng = np.random.default_rng(6)
    Q = np.column_stack([rng.uniform(-1, 1, 40), rng.uniform(0.2, 1.0, 40)])
    Q[[3, 34], 1] = -0.3
    QD = np.ones_like(Q)
    for lanes in (True, False):
        with pytest.raises(DynamicsError, match=r"^row 3 of the batch: mass matrix A of model 'slider'") as err:
            model.forward_dynamics(Q, QD, lanes=lanes)
        assert err.value.row == 3 and err.value.coordinates == ("turn",)
    ok = np.delete(Q, [3, 34], axis=0)
    assert _max_relative(model.forward_dynamics(ok, ok), model.forward_dynamics(ok, ok, lanes=False)) <= TOL


def test_lane_width_says_why():
    from urdf2links.dynamics.lane_batch import REGISTERS_PER_BLOCK, lane_width

    w = lane_width()
    assert w.vector_doubles in (2, 4, 8) and w.width == w.vector_doubles * REGISTERS_PER_BLOCK
    assert w.isa in w.reason and str(w.width) in w.reason

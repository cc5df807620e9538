"""One compiled run, passed down: a comparison loads its robot once and compiles its scene once.

``compare_scene`` used to load the scene's robot three times and compile the scene's plan four
times (the warm-up, ``simulate`` and MuJoCo's inputs each compiled their own). The counters below
wrap the two places where that work happens, ``Scene.model`` / ``load_urdf`` (an import of the
robot file) and ``Plan.__init__`` (a compilation of the scene for a model), so that a stage that
loads or compiles again makes the count grow.
"""

from __future__ import annotations

import numpy as np
import pytest

from urdf2links.compare.agreement.trajectory import compare_scene
from urdf2links.compare.corpus.rows import CorpusSettings, evaluate_robot, find_robots
from urdf2links.integration.batch import simulate_batch, sweep_states
from urdf2links.integration.simulate import simulate, warm_up
from urdf2links.locations import example_robot_data_dir, shipped_robots_dir
from urdf2links.parsers import importer
from urdf2links.scenes import plan as plan_module
from urdf2links.scenes.plan import as_plan
from urdf2links.scenes.scene_read import load_scene


@pytest.fixture
def counts(monkeypatch):
    """``{"load": robot imports, "plan": scene compilations}`` from here on."""
    n = {"load": 0, "plan": 0}
    load, init = importer.load_urdf, plan_module.Plan.__init__

    def counted_load(*args, **kwargs):
        n["load"] += 1
        return load(*args, **kwargs)

    def counted_init(self, *args, **kwargs):
        n["plan"] += 1
        init(self, *args, **kwargs)

    monkeypatch.setattr(importer, "load_urdf", counted_load)
    monkeypatch.setattr(plan_module.Plan, "__init__", counted_init)
    return n


@pytest.mark.parametrize("scene", ["ur5_falling.toml", "ship_crane.toml"])
def test_compare_scene_loads_once_and_compiles_once(counts, scene):
    """Route 2's first attempt takes the scene's own import; each attempt after a refusal (ship_crane:
    MuJoCo refuses its massless links, the repaired text follows) imports the file in another form."""
    sc = load_scene(shipped_robots_dir() / scene)
    c = compare_scene(sc, t_end=0.05)
    assert counts["plan"] == 1
    r2 = c.terms["route2"]
    assert counts["load"] == 1 + len(r2.get("refusals", [])), r2.get("label")


def test_a_plan_passed_down_is_not_compiled_again(counts):
    plan = as_plan(shipped_robots_dir() / "ur5_falling.toml")
    assert counts == {"load": 1, "plan": 1}
    warm_up(plan)
    simulate(plan, t_end=0.01, samples=3, progress=False)
    q0, qd0 = sweep_states(plan.scene, plan.model, 3, seed=0)
    simulate_batch(plan, q0, qd0, t_end=0.01, samples=3)
    assert counts == {"load": 1, "plan": 1}
    assert as_plan(plan) is plan
    with pytest.raises(ValueError, match="brings its own model"):
        as_plan(plan, model=plan.model.__class__(plan.model.tree))


def test_a_corpus_row_loads_once_and_compiles_once(counts):
    robot = next(r for r in find_robots([example_robot_data_dir() / "ur_description/urdf/ur5_robot.urdf"]))
    res = evaluate_robot(robot, CorpusSettings(t_end=0.05, pages=False, thumbnails=False))
    assert res.row["status"] == "compared", res.row
    assert counts == {"load": 1, "plan": 1}
    assert np.isfinite(res.row["terms"]["route1"])

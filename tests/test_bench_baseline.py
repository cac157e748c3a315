"""The benchmark's textbook RRT* baseline (bench/textbook_rrtstar.py) finds real paths."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np

from quadnav.planning import PlannerSettings, make_problem
from quadnav.world import load_world

BASELINE = Path(__file__).resolve().parents[1] / "bench" / "textbook_rrtstar.py"


def _load_baseline():
    spec = importlib.util.spec_from_file_location("textbook_rrtstar", BASELINE)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up by name
    spec.loader.exec_module(module)
    return module


def test_textbook_rrtstar_finds_a_path_through_the_forest_that_avoids_every_block():
    plan_textbook = _load_baseline().plan_textbook
    world = load_world("forest")
    problem = make_problem(world, world.start, world.goal, world.margin)
    settings = PlannerSettings(seed=3, stop_at_first=True, time_limit=3.0)

    result = plan_textbook(problem, settings)

    assert result.solved and result.planner == "textbook"
    assert np.array_equal(result.path[0], world.start)
    assert np.array_equal(result.path[-1], world.goal)
    assert world.segments_free(np.stack([result.path[:-1], result.path[1:]], axis=1)).all()
    assert 0 < result.stats.time_to_first <= result.stats.seconds
    assert np.array_equal(plan_textbook(problem, settings).path, result.path)

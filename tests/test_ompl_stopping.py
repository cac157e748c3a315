"""OMPL's planners stop by quadnav's rule: a planner that counts its iterations stops the
given number of them after its first solution, as RRT* stops after its samples, instead of
spending the whole time budget, or by the stall rule; PRM*, which counts none, stops at the
time limit."""

from __future__ import annotations

import pytest

pytest.importorskip("ompl", reason="the optional OMPL wheel is not installed (pip install ompl)")

from quadnav.planning import PlannerSettings, StallRule, make_problem
from quadnav.planning.ompl_planners import plan_ompl
from quadnav.world import load_world

#: A time limit no search here comes near: a search that reaches it did not stop by its rule.
GENEROUS = 120.0
#: Iterations allowed after the first solution.
IMPROVE = 300


@pytest.fixture(scope="module")
def forest():
    world = load_world("forest")
    return make_problem(world, None, None, world.margin)


@pytest.mark.parametrize("name", ["RRTstar", "InformedRRTstar", "BITstar"])
def test_a_planner_that_counts_iterations_stops_after_its_improvement(forest, name):
    """Before, `fly --planner ompl:BITstar` spent the whole --time (10 s) every time."""
    settings = PlannerSettings(time_limit=GENEROUS, improve_iterations=IMPROVE, seed=3)
    result = plan_ompl(forest, settings, name)
    assert result.solved
    assert result.stats.stopped_by == "improvement"
    assert result.stats.seconds < GENEROUS
    capped = plan_ompl(forest, settings.replace(max_iterations=IMPROVE // 3,
                                                improve_iterations=None), name)
    assert capped.stats.stopped_by == "iterations"
    assert capped.stats.iterations == IMPROVE // 3


def test_prm_star_counts_no_iterations_and_stops_at_the_time_limit(forest):
    result = plan_ompl(forest, PlannerSettings(time_limit=0.3, improve_iterations=IMPROVE,
                                               seed=3), "PRMstar")
    assert result.stats.stopped_by == "time"


@pytest.mark.parametrize("name", ["RRTstar", "BITstar"])
def test_a_planner_that_counts_iterations_stops_by_the_stall_rule(forest, name):
    # a rule that any search meets at its first comparison: at most 50 % shorter over
    # the IMPROVE iterations after the first solution
    rule = StallRule(fraction=0.5, samples=IMPROVE)
    fixed = PlannerSettings(time_limit=GENEROUS, improve_iterations=10 * IMPROVE, seed=3)
    stalled = plan_ompl(forest, fixed.replace(stall=rule), name)
    full = plan_ompl(forest, fixed, name)
    assert stalled.solved and stalled.stats.stopped_by == "stall"
    assert full.stats.stopped_by == "improvement"
    assert stalled.stats.iterations < full.stats.iterations

"""OMPL's planners behind quadnav's interface: exact, collision-free paths and honest stats."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

pytest.importorskip("ompl", reason="the optional OMPL wheel is not installed (pip install ompl)")

from quadnav.errors import PlanningWarning, QuadnavError
from quadnav.planning import PlannerSettings, make_problem, path_length, plan
from quadnav.planning.contract import OMPL_PLANNERS
from quadnav.planning.ompl_planners import plan_ompl, simplify_ompl
from quadnav.world import World, load_world

OPTIMIZING = ("RRTstar", "InformedRRTstar", "BITstar", "PRMstar")
#: A seed with which every planner finds the window world's first path within ~0.05 s.
WINDOW_SEED = 11
#: Search budget, s: ample on a busy machine for the ~0.05 s the searches need.
BUDGET = 0.5


def builtin_problem(spec: str):
    world = load_world(spec)
    return make_problem(world, None, None, world.margin)


PROBLEMS = {spec: builtin_problem(spec) for spec in ("forest", "window")}


def segments(path: np.ndarray) -> np.ndarray:
    return np.stack([path[:-1], path[1:]], axis=1)


def assert_free_path(problem, path: np.ndarray) -> None:
    """Exactly from start to goal; every segment off the legs is free in the inflated world."""
    assert np.array_equal(path[0], problem.start)
    assert np.array_equal(path[-1], problem.goal)
    first = int(not np.array_equal(problem.start, problem.search_start))
    last = len(path) - int(not np.array_equal(problem.goal, problem.search_goal))
    assert problem.free_world.segments_free(segments(path[first:last])).all()


def assert_consistent_stats(result) -> None:
    stats = result.stats
    history = stats.cost_history
    assert stats.nodes == len(result.tree_nodes)
    assert 0 <= stats.time_to_first <= stats.seconds
    assert history[0, 0] == stats.time_to_first
    assert np.all(np.diff(history[:, 0]) >= 0) and np.all(np.diff(history[:, 1]) < 0)
    assert history[-1, 1] == pytest.approx(result.length, rel=1e-9)


def assert_forest(result, problem) -> None:
    """Each vertex has one parent (or -1 for a root); the parents never form a cycle; every
    edge drawn was checked by the exact motion validator, so it is free."""
    parents = result.tree_parents
    assert np.all((parents >= -1) & (parents < len(parents)))
    assert problem.free_world.segments_free(result.tree_edges()).all()
    vertex = np.arange(len(parents))
    for _ in range(len(parents)):  # every root is reached within as many steps, or a cycle
        vertex = np.where(vertex >= 0, parents[np.maximum(vertex, 0)], -1)
        if np.all(vertex < 0):
            break
    assert np.all(vertex < 0), "a cycle in the tree"


@pytest.mark.parametrize("spec", PROBLEMS)
@pytest.mark.parametrize("name", OMPL_PLANNERS)
def test_every_planner_finds_a_free_exact_path(name, spec):
    problem = PROBLEMS[spec]
    reports = []
    result = plan_ompl(problem, PlannerSettings(time_limit=BUDGET, seed=WINDOW_SEED), name,
                       lambda fraction, best: reports.append((fraction, best)))
    assert result.solved, result.message
    assert result.planner == f"ompl:{name}" and result.seed == WINDOW_SEED
    assert_free_path(problem, result.path)
    assert_consistent_stats(result)
    assert_forest(result, problem)
    if name != "BITstar":  # OMPL's BIT* graph is not read (see the module docstring)
        assert len(result.tree_nodes) > 0
    if name in OPTIMIZING:  # the search uses the whole budget, reporting now and then
        assert result.stats.seconds >= BUDGET
        fractions, best = np.array(reports).T
        assert np.all((fractions >= 0) & (fractions <= 1)) and np.all(np.diff(fractions) >= 0)
        assert np.all(np.diff(best[np.isfinite(best)]) <= 0)


@pytest.mark.parametrize("name", OMPL_PLANNERS)
def test_the_same_seed_gives_the_same_first_path(name):
    problem = PROBLEMS["window"]
    settings = PlannerSettings(time_limit=30, seed=WINDOW_SEED, stop_at_first=True)
    first, second = (plan_ompl(problem, settings, name) for _ in range(2))
    assert first.solved and second.solved
    assert len(first.stats.cost_history) == 1
    if name != "PRMstar":  # PRM* searches with two threads: not repeatable
        assert np.array_equal(first.path, second.path)
        assert np.array_equal(first.tree_nodes, second.tree_nodes)


@pytest.mark.parametrize("name", ["RRTstar", "BITstar"])
def test_max_iterations_ends_a_search_repeatably(name):
    problem = PROBLEMS["forest"]
    settings = PlannerSettings(time_limit=30, max_iterations=1500, seed=3)
    first, second = (plan_ompl(problem, settings, name) for _ in range(2))
    assert first.stats.iterations == second.stats.iterations == 1500
    assert np.array_equal(first.path, second.path)
    assert np.array_equal(first.stats.cost_history[:, 1], second.stats.cost_history[:, 1])


def caged_goal_problem():
    """The goal is shut in a box of 2 cm plates: no path exists, but the plates are too thin
    for the voxel check to prove it, so the planners search the whole budget."""
    outer = np.array([7.0, 7.0, 1.0, 9.0, 9.0, 3.0])
    plates = []
    for axis in range(3):
        for side, face in ((0, outer[axis]), (1, outer[axis + 3])):
            plate = outer.copy()
            plate[axis], plate[axis + 3] = (face, face + 0.02) if side == 0 else (face - 0.02, face)
            plates.append(plate)
    world = World(boundary=[0, 0, 0, 10, 10, 4], blocks=plates, name="cage")
    return make_problem(world, (1, 1, 2), (8, 8, 2), 0.0)


@pytest.mark.parametrize("name", OMPL_PLANNERS)
def test_no_path_within_the_budget_is_reported_cleanly(name):
    result = plan_ompl(caged_goal_problem(), PlannerSettings(time_limit=0.15), name)
    assert not result.solved
    assert result.path.shape == (0, 3) and result.length == float("inf")
    assert result.stats.time_to_first is None and result.stats.cost_history.shape == (0, 2)
    assert result.message.startswith("no path found in ")
    assert result.message.endswith("the time budget ran out; raise --time")


def test_the_registry_runs_ompl_planners():
    problem = PROBLEMS["forest"]
    result = plan(problem, PlannerSettings(time_limit=0.2), planner="ompl:RRTstar")
    assert result.planner == "ompl:RRTstar" and result.solved
    assert_free_path(problem, result.path)


def test_an_unknown_planner_is_a_user_error():
    with pytest.raises(QuadnavError, match="unknown OMPL planner 'RRT'"):
        plan_ompl(PROBLEMS["forest"], PlannerSettings(), "RRT")


def test_simplify_shortens_a_path_and_keeps_its_ends():
    problem = PROBLEMS["window"]
    rough = plan_ompl(problem, PlannerSettings(seed=1, stop_at_first=True), "RRTConnect")
    simplified = simplify_ompl(problem, rough.path, time_limit=0.2)
    assert_free_path(problem, simplified)
    assert path_length(simplified) < rough.length


def test_simplify_keeps_the_legs_out_of_the_margin():
    world = load_world("forest")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PlanningWarning)
        problem = make_problem(world, (0.05, 0.05, 1.0), None, world.margin)
    assert not np.array_equal(problem.start, problem.search_start)
    rough = plan_ompl(problem, PlannerSettings(seed=2, stop_at_first=True), "RRTConnect")
    simplified = simplify_ompl(problem, rough.path, time_limit=0.2)
    assert np.array_equal(simplified[1], problem.search_start)
    assert_free_path(problem, simplified)
    assert path_length(simplified) <= rough.length


def test_simplify_rejects_a_path_for_another_query():
    problem = PROBLEMS["forest"]
    with pytest.raises(QuadnavError, match="does not begin with the problem's start leg"):
        simplify_ompl(problem, [problem.start, problem.start + 1.0])

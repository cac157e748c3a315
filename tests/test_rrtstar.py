"""RRT*: paths are exact, collision-free and reproducible; the problem checks catch bad input."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given
from hypothesis import settings as hypothesis_settings
from hypothesis import strategies as st

from quadnav.errors import PlanningWarning, QuadnavError
from quadnav.planning import PlannerSettings, make_problem, plan
from quadnav.world import World, load_world

BOUNDARY = np.array([0.0, 0.0, 0.0, 10.0, 10.0, 5.0])


def edges(path: np.ndarray) -> np.ndarray:
    return np.stack([path[:-1], path[1:]], axis=1)


def assert_valid_path(problem, result) -> None:
    """Starts and ends exactly at start and goal; every search edge is free (exact)."""
    assert result.solved, result.message
    assert np.array_equal(result.path[0], problem.start)
    assert np.array_equal(result.path[-1], problem.goal)
    first = 0 if np.array_equal(problem.start, problem.search_start) else 1
    last = len(result.path) - (0 if np.array_equal(problem.goal, problem.search_goal) else 1)
    search = result.path[first:last]
    assert np.array_equal(search[0], problem.search_start)
    assert np.array_equal(search[-1], problem.search_goal)
    assert problem.free_world.segments_free(edges(search)).all()


def assert_valid_tree(problem, result) -> None:
    """Every tree edge is free, and every vertex leads back to the root without cycles."""
    parents = result.tree_parents
    assert parents[0] == -1 and np.all(parents[1:] >= 0) and np.all(parents < len(parents))
    assert problem.free_world.segments_free(result.tree_edges()).all()
    vertex = np.arange(len(parents))
    for _ in range(len(parents)):  # every vertex reaches the root within len(parents) hops
        vertex = np.where(vertex >= 0, parents[np.maximum(vertex, 0)], -1)
        if np.all(vertex < 0):
            break
    assert np.all(vertex < 0), "a cycle in the tree"


@st.composite
def random_query(draw):
    """A world of up to 12 random boxes with a free start and goal far apart."""
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    count = draw(st.integers(0, 12))
    lower = rng.uniform(BOUNDARY[:3], BOUNDARY[3:] - 0.5, size=(count, 3))
    size = rng.uniform(0.3, [4.0, 4.0, 3.0], size=(count, 3))
    blocks = np.hstack([lower, np.minimum(lower + size, BOUNDARY[3:])])
    world = World(boundary=BOUNDARY, blocks=blocks)
    free = world.inflate(0.2).sample_free(200, seed=rng)
    far = np.linalg.norm(free - free[0], axis=1)
    return world, free[0], free[int(np.argmax(far))], draw(st.integers(0, 1000))


@hypothesis_settings(max_examples=40, deadline=None,
                     suppress_health_check=[HealthCheck.too_slow])
@given(random_query())
def test_every_path_is_free_and_exact_in_random_worlds(query):
    world, start, goal, seed = query
    try:
        problem = make_problem(world, start, goal, 0.2)
    except QuadnavError as error:  # provably disconnected: nothing to plan
        assert "disconnected" in str(error)
        return
    result = plan(problem, PlannerSettings(seed=seed, max_iterations=3000, time_limit=60))
    if result.solved:
        assert_valid_path(problem, result)
    assert_valid_tree(problem, result)


def test_a_goal_in_sight_of_the_start_is_joined_at_once():
    world = load_world("empty")
    problem = make_problem(world, None, [1.05, 1.0, 1.0], world.margin)  # 5 cm away
    result = plan(problem, PlannerSettings(seed=1, time_limit=10))
    assert result.solved and result.stats.stopped_by == "direct"
    assert result.stats.iterations == 0 and result.stats.seconds < 10
    assert np.array_equal(result.path, [world.start, [1.05, 1.0, 1.0]])
    assert result.message == "the goal is in sight of the start: joined directly"


@pytest.mark.parametrize("spec", ["forest", "window", "maze"])
def test_builtin_worlds_are_solved(spec):
    world = load_world(spec)
    problem = make_problem(world, None, None, world.margin)
    result = plan(problem, PlannerSettings(seed=1, max_iterations=20000, time_limit=60))
    assert_valid_path(problem, result)
    assert_valid_tree(problem, result)
    stats = result.stats
    assert 0 < stats.time_to_first <= stats.seconds
    assert stats.nodes == len(result.tree_nodes) and stats.iterations >= stats.nodes - 1
    history = stats.cost_history
    assert np.all(np.diff(history[:, 0]) >= 0) and np.all(np.diff(history[:, 1]) < 0)
    assert history[-1, 1] == pytest.approx(result.length)
    assert result.length >= np.linalg.norm(problem.goal - problem.start)


def test_same_seed_same_path_other_seed_other_path():
    world = load_world("forest")
    problem = make_problem(world, None, None, 0.2)
    budget = PlannerSettings(seed=7, max_iterations=4000, time_limit=60)
    first, again = plan(problem, budget), plan(problem, budget)
    other = plan(problem, budget.replace(seed=8))
    assert np.array_equal(first.path, again.path)
    assert np.array_equal(first.tree_nodes, again.tree_nodes)
    assert not np.array_equal(first.path, other.path)


def test_longer_search_finds_shorter_paths_and_informed_sampling_helps():
    world = load_world("forest")
    problem = make_problem(world, None, None, 0.2)
    short = plan(problem, PlannerSettings(seed=3, max_iterations=500, time_limit=60))
    long = plan(problem, PlannerSettings(seed=3, max_iterations=20000, time_limit=60))
    assert long.length <= short.length
    straight = np.linalg.norm(problem.goal - problem.start)
    assert long.length < 1.1 * straight


def test_stop_at_first_returns_the_first_solution():
    world = load_world("forest")
    problem = make_problem(world, None, None, 0.2)
    result = plan(problem, PlannerSettings(seed=2, stop_at_first=True, time_limit=10))
    assert result.solved and len(result.stats.cost_history) == 1
    assert result.stats.seconds < 10


def test_no_path_within_the_budget_is_a_clear_result():
    world = load_world("maze")
    problem = make_problem(world, None, None, 0.2)
    result = plan(problem, PlannerSettings(seed=0, max_iterations=3, time_limit=60))
    assert not result.solved and result.path.shape == (0, 3)
    assert "the search stopped at its cap of 3 samples" in result.message
    assert result.stats.stopped_by == "iterations"
    assert result.length == float("inf") and result.stats.time_to_first is None


def test_map1_from_the_course_is_solved(shared_maps):
    world = load_world(shared_maps / "rbe595" / "map1.txt")
    problem = make_problem(world, [0.5, -4.5, 0.5], [8, 18, 3], 0.2)
    result = plan(problem, PlannerSettings(seed=0, max_iterations=20000, time_limit=60))
    assert_valid_path(problem, result)
    assert result.length < 30  # the shortest route over the walls is about 24 m


def test_start_on_the_boundary_leaves_the_margin_by_a_short_leg(shared_maps):
    world = load_world(shared_maps / "rbe595" / "map1.txt")
    with pytest.warns(PlanningWarning, match=r"start \(0, -5, 0\) is inside the 0.2 m safety margin; only the straight"):
        problem = make_problem(world, [0.0, -5.0, 0.0], [8, 18, 3], 0.2)
    assert problem.free_world.is_free(problem.search_start)
    # Straight out of the floor's and the wall's margins, 1 cm past them (sqrt(3) * 0.21).
    assert np.linalg.norm(problem.search_start - problem.start) == pytest.approx(0.3637, abs=1e-4)
    result = plan(problem, PlannerSettings(seed=0, max_iterations=20000, time_limit=60))
    assert_valid_path(problem, result)
    assert np.array_equal(result.path[1], problem.search_start)


def test_goal_near_a_block_leaves_the_margin_without_touching_the_block():
    world = World(boundary=BOUNDARY, blocks=np.array([[4.0, 0.0, 0.0, 6.0, 10.0, 3.0]]))
    with pytest.warns(PlanningWarning, match="goal"):
        problem = make_problem(world, [1.0, 5.0, 1.0], [6.1, 5.0, 1.0], 0.2)
    assert problem.search_goal == pytest.approx([6.21, 5.0, 1.0], abs=1e-9)  # 1 cm past
    assert world.replace(boundary=BOUNDARY + np.repeat([-1.0, 1.0], 3)).segment_free(
        problem.goal, problem.search_goal)
    assert_valid_path(problem, plan(problem, PlannerSettings(seed=0, max_iterations=20000, time_limit=60)))


def test_free_start_and_goal_give_no_warning():
    world = load_world("forest")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        problem = make_problem(world, None, None, 0.2)
    assert np.array_equal(problem.search_start, problem.start)


@pytest.mark.parametrize(("point", "expected"), [
    ([5.0, 5.0, 1.0], "inside block 0"),
    ([5.0, 5.0, 9.0], "outside the boundary"),
])
def test_start_in_a_block_or_outside_is_an_error_naming_it(point, expected):
    world = World(boundary=BOUNDARY, blocks=np.array([[4.0, 4.0, 0.0, 6.0, 6.0, 3.0]]))
    with pytest.raises(QuadnavError, match=expected):
        make_problem(world, point, [9.0, 9.0, 1.0], 0.2)


def test_provably_disconnected_start_and_goal_are_reported(shared_maps):
    world = load_world(shared_maps / "meam620" / "test_impossible.json")
    with pytest.raises(QuadnavError, match=r"disconnected with a 0\.1 m margin: no path exists"):
        make_problem(world, None, None, world.margin)


def test_a_gap_narrower_than_the_margin_disconnects():
    # A wall across the map with a 0.3 m hole: open at margin 0.1, closed at margin 0.2.
    wall = [[4.0, 0.0, 0.0, 4.5, 4.85, 5.0], [4.0, 5.15, 0.0, 4.5, 10.0, 5.0]]
    world = World(boundary=BOUNDARY, blocks=np.array(wall))
    ends = ([1.0, 5.0, 2.0], [9.0, 5.0, 2.0])
    with pytest.raises(QuadnavError, match="disconnected"):
        make_problem(world, *ends, 0.2)
    problem = make_problem(world, *ends, 0.1)
    assert_valid_path(problem, plan(problem, PlannerSettings(seed=0, max_iterations=50000, time_limit=60)))


def test_map_without_start_needs_one():
    world = World(boundary=BOUNDARY)
    with pytest.raises(QuadnavError, match="the map has no start"):
        make_problem(world, None, [1.0, 1.0, 1.0], 0.2)


@pytest.mark.parametrize("chunk_seconds", [0.0, 1e9])
def test_the_tree_does_not_depend_on_how_long_chunks_take(monkeypatch, chunk_seconds):
    from quadnav.planning import rrtstar

    world = load_world("window:size=4x6x3,walls=1")  # a seed where the tree used to differ
    problem = make_problem(world, world.start, world.goal, world.margin)
    settings = PlannerSettings(time_limit=60.0, improve_iterations=10_000, seed=1)
    usual = plan(problem, settings)
    assert len(usual.tree_nodes) > 4096  # the arrays grew at least once
    # chunks that never double (every chunk "slow"), or that always do
    monkeypatch.setattr(rrtstar, "CHUNK_SECONDS", chunk_seconds)
    other = plan(problem, settings)
    assert np.array_equal(other.tree_nodes, usual.tree_nodes)
    assert np.array_equal(other.path, usual.path)

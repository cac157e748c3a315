"""The quadrotor kinodynamic planner: model, sign convention, exact motion, tree safety,
replay, goals on real maps, determinism, goal bias, errors and figures."""

from __future__ import annotations

import functools
import math
import re
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import pytest
from figurecheck import assert_labels_apart, assert_legends_outside, assert_outlined

from quadnav.errors import PlanningWarning, QuadnavError
from quadnav.kinodynamic import KinoResult, KinoSettings
from quadnav.kinodynamic.closing import CLOSING_ACCELERATION
from quadnav.kinodynamic.pointmass import SampledQuadrotor, exact_positions
from quadnav.kinodynamic.quadrotor import (
    CHORD_TOLERANCE,
    REPLAY_TOLERANCE,
    _lowest_heights,
    plan_quadrotor,
    replay,
)
from quadnav.planning import make_problem
from quadnav.viz.figures import save_figure
from quadnav.viz.kino3d import (
    MAX_TREE_SEGMENTS,
    TREE_PIECES,
    quadrotor_controls_figure,
    quadrotor_figure,
)
from quadnav.viz.style import TREE_COLOR
from quadnav.world import World, load_world

MODEL = SampledQuadrotor()
MARGIN = 0.2
# Iteration-bounded budgets, so every result below is the same on every machine.
SETTINGS = KinoSettings(max_iterations=4000, time_limit=60.0)
MAP1_START, MAP1_GOAL = (0.5, -4.5, 0.5), (8.0, 18.0, 3.0)


def issue_acceleration(phi, theta, psi, thrust, mass, g):
    """The issue's formula, literally (a z-down frame)."""
    c, s, f = math.cos, math.sin, thrust / mass
    return np.array([(-c(phi) * s(theta) * c(psi) - s(phi) * s(psi)) * f,
                     (-c(phi) * s(theta) * s(psi) + s(phi) * c(psi)) * f,
                     g - c(phi) * c(theta) * f])


@pytest.fixture(scope="module")
def forest() -> World:
    return load_world("forest")


@pytest.fixture(scope="module")
def forest_plan(forest: World) -> KinoResult:
    return plan_quadrotor(forest, forest.start, forest.goal, SETTINGS, MODEL, MARGIN)


@functools.cache
def _map1_plan(path: Path) -> tuple[World, KinoResult]:
    world = load_world(path)
    return world, plan_quadrotor(world, MAP1_START, MAP1_GOAL, SETTINGS, MODEL, MARGIN)


@pytest.fixture
def map1_plan(shared_maps: Path) -> tuple[World, KinoResult]:
    """The course map1 and a plan across it (planned once per test process)."""
    return _map1_plan(shared_maps / "rbe595" / "map1.txt")


# ------------------------------------------------------------------------------ model
def test_hover_thrust_at_zero_tilt_gives_zero_acceleration():
    for model in (MODEL, SampledQuadrotor(mass=1.3, yaw=0.7)):
        assert np.allclose(model.acceleration([0.0, 0.0, model.hover_thrust]), 0.0, atol=1e-12)
        rest = np.array([1.0, 2.0, 3.0, 0.0, 0.0, 0.0])
        assert np.allclose(model.propagate(rest, [0.0, 0.0, model.hover_thrust], 2.0), rest)


def test_sign_convention_z_up_and_the_issue_formula():
    g, weight = MODEL.gravity, MODEL.hover_thrust
    ax, ay, az = MODEL.acceleration([0.0, 0.2, weight])  # positive pitch: towards +x
    assert ax > 0 and ay == pytest.approx(0.0) and az < 0
    ax, ay, _ = MODEL.acceleration([0.2, 0.0, weight])  # positive roll: towards -y
    assert ay < 0 and ax == pytest.approx(0.0)
    assert MODEL.acceleration([0.0, 0.0, 1.2 * weight])[2] == pytest.approx(0.2 * g)
    rng = np.random.default_rng(3)
    for phi, theta, psi, thrust in rng.uniform([-1, -1, -3, 0], [1, 1, 3, 2], size=(50, 4)):
        model = SampledQuadrotor(mass=0.1, yaw=psi)
        ours = model.acceleration([phi, theta, thrust])
        # Same numbers: every component flips sign.
        assert np.allclose(ours, -issue_acceleration(phi, theta, psi, thrust, 0.1, g))
        # Change of frame z-down -> z-up (half turn about x): (x,y,z) -> (x,-y,-z) and
        # (phi, theta, psi) -> (phi, -theta, -psi).
        assert np.allclose(ours, np.array([1, -1, -1])
                           * issue_acceleration(phi, -theta, -psi, thrust, 0.1, g))


def test_default_limits_and_max_acceleration_bound():
    assert MODEL.min_thrust == pytest.approx(0.5 * 0.08 * 9.81)
    assert MODEL.max_thrust == pytest.approx(1.5 * 0.08 * 9.81)
    controls = MODEL.sample_controls(np.random.default_rng(0), 20000)
    assert np.all((controls >= MODEL.control_lower) & (controls <= MODEL.control_upper))
    norms = np.linalg.norm(MODEL.acceleration(controls), axis=1)
    corners = MODEL.acceleration([[0.35, 0.35, MODEL.max_thrust], [0.35, 0.35, MODEL.min_thrust]])
    assert norms.max() <= MODEL.max_acceleration + 1e-12
    assert np.linalg.norm(corners, axis=1).max() == pytest.approx(MODEL.max_acceleration)


@pytest.mark.parametrize("kwargs", [{"mass": 0.0}, {"max_roll": 2.0}, {"max_pitch": -0.1},
                                    {"min_thrust": 2.0, "max_thrust": 1.0},
                                    {"speed_limit": 0.0}, {"gravity": math.inf}])
def test_bad_model_is_a_user_error(kwargs):
    with pytest.raises(QuadnavError):
        SampledQuadrotor(**kwargs)


def test_exact_propagation_matches_fine_rk4():
    rng = np.random.default_rng(1)
    start = np.concatenate([rng.uniform(-5, 5, 3), rng.uniform(-2, 2, 3)])
    controls = MODEL.sample_controls(rng, 12)
    durations = rng.uniform(0.05, 0.9, 12)
    times, flown = replay(MODEL, start, controls, durations, dt=1e-4)
    exact = [start]
    for control, duration in zip(controls, durations, strict=True):
        exact.append(MODEL.propagate(exact[-1], control, duration))
    knots = np.searchsorted(times, np.concatenate([[0.0], np.cumsum(durations)]))
    assert np.max(np.abs(flown[knots] - np.array(exact))) < 1e-9
    # Between the knots too: positions along the exact parabola of the first control.
    inside = times[: knots[1] + 1]
    assert np.max(np.abs(exact_positions(start, MODEL.acceleration(controls[0]), inside)
                         - flown[: knots[1] + 1, :3])) < 1e-9


def test_chord_pieces_keep_the_parabola_within_the_tolerance():
    duration = 0.5
    pieces = MODEL.chord_pieces(duration, CHORD_TOLERANCE)
    rng = np.random.default_rng(2)
    controls = np.vstack([MODEL.sample_controls(rng, 200),
                          [[0.35, 0.35, MODEL.max_thrust], [-0.35, 0.35, MODEL.min_thrust]]])
    state = np.array([0.0, 0.0, 0.0, 1.0, -1.0, 0.5])
    accelerations = MODEL.acceleration(controls)
    dense = exact_positions(state, accelerations, np.linspace(0, duration, 20 * pieces + 1))
    knots = dense[:, ::20]
    # Each dense point against the chord of its piece at the same parameter.
    fraction = (np.arange(20 * pieces + 1) % 20 / 20)[None, :, None]
    first = np.repeat(knots[:, :-1], 20, axis=1)
    last = np.repeat(knots[:, 1:], 20, axis=1)
    chord = first + fraction[:, :-1] * (last - first)
    assert np.max(np.linalg.norm(dense[:, :-1] - chord, axis=2)) <= CHORD_TOLERANCE


# ---------------------------------------------------------------------------- planner
def _check_plan(world: World, result: KinoResult, start, goal, settings=SETTINGS) -> None:
    assert result.solved, result.message
    assert result.planner == "quadrotor"
    assert np.array_equal(result.states[0], [*start, 0, 0, 0])
    # The tree reaches the goal region; the closing stop from there ends at rest exactly
    # at the goal, in two pieces of equal duration.
    assert result.closing_controls == 2 and result.goal_leg_controls == 0
    assert np.linalg.norm(result.states[-3, :3] - goal) <= settings.goal_radius
    assert np.array_equal(result.states[-1], [*goal, 0, 0, 0])
    assert np.allclose(result.durations[:-2], settings.duration)
    assert result.durations[-2] == result.durations[-1]
    assert np.linalg.norm(MODEL.acceleration(result.controls[-2:]), axis=1).max() \
        <= CLOSING_ACCELERATION + 1e-9
    following = MODEL.propagate(result.states[:-1], result.controls, result.durations)
    assert np.allclose(following, result.states[1:], rtol=0, atol=1e-12)
    assert np.all((result.controls >= MODEL.control_lower)
                  & (result.controls <= MODEL.control_upper))


def test_goal_reached_in_the_forest(forest, forest_plan):
    _check_plan(forest, forest_plan, forest.start, forest.goal)
    print(forest_plan.message)


def test_goal_reached_through_the_windows():
    world = load_world("window")
    result = plan_quadrotor(world, world.start, world.goal, SETTINGS, MODEL, MARGIN)
    _check_plan(world, result, world.start, world.goal)
    print(result.message)


def test_goal_reached_on_course_map1(map1_plan):
    world, result = map1_plan
    _check_plan(world, result, MAP1_START, MAP1_GOAL)
    print(result.message)


def _dense_tree(world: World, result: KinoResult, per_edge: int = 100):
    """Every tree motion re-sampled at ``per_edge + 1`` times: positions (E, n, 3) and
    velocities (E, n, 3)."""
    children = np.flatnonzero(result.tree_parents >= 0)
    parents = result.tree_states[result.tree_parents[children]]
    accelerations = MODEL.acceleration(result.tree_controls[children])
    times = result.tree_durations[children, None] * np.linspace(0, 1, per_edge + 1)
    positions = exact_positions(parents, accelerations, times)
    velocities = parents[:, None, 3:] + accelerations[:, None] * times[..., None]
    return positions, velocities


@pytest.mark.parametrize("which", ["forest", "map1"])
def test_every_tree_edge_is_free_slow_and_above_the_floor(which, forest, forest_plan, request):
    world, result = ((forest, forest_plan) if which == "forest"
                     else request.getfixturevalue("map1_plan"))
    children = np.flatnonzero(result.tree_parents >= 0)
    assert len(children) > 50
    # The tree is consistent: each state is its parent's state under its control.
    assert np.allclose(MODEL.propagate(result.tree_states[result.tree_parents[children]],
                                       result.tree_controls[children],
                                       result.tree_durations[children]),
                       result.tree_states[children], rtol=0, atol=1e-12)
    positions, velocities = _dense_tree(world, result)
    margin_world = world.inflate(MARGIN)
    assert margin_world.points_free(positions.reshape(-1, 3)).all()
    floor = world.lower[2] + MARGIN
    assert positions[..., 2].min() > floor
    assert result.tree_states[:, 2].min() > floor
    assert np.linalg.norm(velocities, axis=2).max() <= MODEL.speed_limit + 1e-12


def test_the_closing_stop_is_checked_like_every_motion():
    """A goal 0.4 m behind a wall, with a 1.5 m goal region: the tree reaches the region on
    the near side of the wall first, but no closing stop through the wall is taken; the
    plan closes from the far side, and its stop keeps the margin along its exact motion."""
    world = World(boundary=[0, 0, 0, 10, 10, 4], blocks=[[5, 0, 0, 5.2, 7, 4]])
    goal = np.array([5.6, 5.0, 2.0])
    settings = SETTINGS.replace(goal_radius=1.5)
    result = plan_quadrotor(world, (1.0, 5.0, 2.0), goal, settings, MODEL, MARGIN)
    _check_plan(world, result, (1.0, 5.0, 2.0), goal, settings)
    near_side = result.tree_states[(result.tree_states[:, 0] < 5)
                                   & (np.linalg.norm(result.tree_states[:, :3] - goal, axis=1)
                                      <= settings.goal_radius)]
    refused = int(re.search(r"(\d+) states in the goal region with no free closing stop",
                            result.message)[1])
    assert len(near_side) > 0 and refused >= len(near_side)
    assert result.states[-3, 0] > 5.2 + MARGIN
    stop = exact_positions(result.states[-3:-1], MODEL.acceleration(result.controls[-2:]),
                           np.linspace(0, 1, 200) * result.durations[-2:, None])
    assert world.inflate(MARGIN).points_free(stop.reshape(-1, 3)).all()
    assert stop[..., 2].min() > MARGIN


def test_floor_prunes_motions_that_would_dip_below_it():
    # Start and goal hug the floor of an empty room: the tree presses against the floor
    # but no motion of it ever dips below it.
    world = load_world("empty")
    start, goal = (1.0, 1.0, MARGIN + 0.1), (9.0, 9.0, MARGIN + 0.3)
    result = plan_quadrotor(world, start, goal, SETTINGS.replace(biased=False), MODEL, MARGIN)
    positions, _ = _dense_tree(world, result)
    floor = world.lower[2] + MARGIN
    assert floor < positions[..., 2].min() < floor + 0.1
    assert int(re.search(r"(\d+) below the floor", result.message)[1]) > 0


def test_lowest_heights_are_exact_on_the_parabola():
    rng = np.random.default_rng(4)
    for _ in range(20):
        state = np.concatenate([[0, 0, 1.0], rng.uniform(-2, 2, 3)])
        accelerations = MODEL.acceleration(MODEL.sample_controls(rng, 50))
        dense = exact_positions(state, accelerations, np.linspace(0, 0.5, 5001))[..., 2]
        lowest = _lowest_heights(state, accelerations, 0.5)
        assert np.all(lowest <= dense.min(axis=1) + 1e-12)
        assert np.allclose(lowest, dense.min(axis=1), rtol=0, atol=1e-6)


def test_replay_reproduces_the_planned_states(forest_plan, map1_plan):
    worst = 0.0
    for result in (forest_plan, map1_plan[1]):
        times, flown = replay(MODEL, result.states[0], result.controls, result.durations)
        knots = np.concatenate([[0.0], np.cumsum(result.durations)])
        rows = np.searchsorted(times, knots)
        assert np.array_equal(times[rows], knots)
        assert np.all(np.diff(times) > 0) and np.diff(times).max() <= 1e-3 * (1 + 1e-9)
        worst = max(worst, float(np.abs(flown[rows] - result.states).max()))
    print(f"replay: largest state error {worst:.2e} (tolerance {REPLAY_TOLERANCE:.0e})")
    assert worst < REPLAY_TOLERANCE


def test_same_seed_same_result(forest):
    settings = SETTINGS.replace(seed=5, max_iterations=300)
    first, second = (plan_quadrotor(forest, forest.start, forest.goal, settings)
                     for _ in range(2))
    for name in ("states", "controls", "durations", "tree_states", "tree_parents",
                 "tree_controls", "tree_durations"):
        assert np.array_equal(getattr(first, name), getattr(second, name)), name
    assert first.iterations == second.iterations
    other = plan_quadrotor(forest, forest.start, forest.goal, settings.replace(seed=6))
    assert not np.array_equal(first.tree_states[:20], other.tree_states[:20])


def test_biased_sampling_reaches_the_goal_in_fewer_iterations(forest):
    budget = SETTINGS.replace(max_iterations=2000)
    counts = {}
    for biased in (True, False):
        counts[biased] = [plan_quadrotor(forest, forest.start, forest.goal,
                                         budget.replace(seed=seed, biased=biased)).iterations
                          for seed in range(8)]
    print(f"iterations to the goal, seeds 0-7 (budget {budget.max_iterations}): "
          f"biased {counts[True]} median {np.median(counts[True])}; "
          f"unbiased {counts[False]} median {np.median(counts[False])}")
    assert np.median(counts[True]) < np.median(counts[False])


def test_start_inside_the_goal_region_is_solved_at_once_by_the_closing_stop(forest):
    goal = np.add(forest.start, [0.1, 0, 0])
    result = plan_quadrotor(forest, forest.start, goal, SETTINGS)
    assert result.solved and result.iterations == 0 and len(result.tree_states) == 3
    assert result.states.shape == (3, 6) and result.controls.shape == (2, 3)
    assert np.array_equal(result.states[-1], [*goal, 0, 0, 0])
    # From rest to rest straight along x: accelerating, then braking as hard.
    accelerations = MODEL.acceleration(result.controls)
    assert np.allclose(accelerations[:, 1:], 0, atol=1e-12)
    assert accelerations[0, 0] == pytest.approx(-accelerations[1, 0])
    assert 0 < accelerations[0, 0] <= CLOSING_ACCELERATION
    assert result.time_to_goal is not None


def test_budget_exhausted_is_an_unsolved_result(forest):
    calls = []
    result = plan_quadrotor(forest, forest.start, forest.goal,
                            SETTINGS.replace(max_iterations=600, biased=False),
                            progress=lambda *a:
                            calls.append(a))
    assert not result.solved and result.iterations == 600
    assert result.states.shape == (0, 6) and result.time_to_goal is None
    assert "not reached" in result.message
    fractions = [fraction for fraction, _ in calls]
    assert fractions == sorted(fractions) and fractions[-1] == 1.0 and len(calls) == 4
    closest = [distance for _, distance in calls]
    assert closest == sorted(closest, reverse=True)


@pytest.mark.parametrize(("start", "goal", "words"), [
    ((-1.0, 1.0, 1.0), None, r"start \(-1, 1, 1\): outside the boundary"),
    ((1.0, 1.0, 1.0), (1.0, 1.0, 1.0), r"start and goal are the same point \(1, 1, 1\)"),
    (None, (19.0, 19.0, 30.0), r"goal \(19, 19, 30\): outside the boundary"),
])
def test_bad_start_or_goal_is_a_user_error(forest, start, goal, words):
    with pytest.raises(QuadnavError, match=words):
        plan_quadrotor(forest, forest.start if start is None else start,
                       forest.goal if goal is None else goal, SETTINGS)


def test_a_start_in_the_margin_leaves_it_by_its_leg_as_for_every_planner(shared_maps):
    world = load_world(shared_maps / "meam620" / "test_window.json")  # starts 0.1 m from walls
    with pytest.warns(PlanningWarning, match=r"start \(0.1, -4.9, 0.2\) is inside the 0.32 m"):
        problem = make_problem(world, world.start, world.goal, world.margin + CHORD_TOLERANCE)
    with pytest.warns(PlanningWarning, match="inside the 0.32 m safety margin"):
        result = plan_quadrotor(world, world.start, world.goal, SETTINGS, MODEL, world.margin)
    assert result.solved, result.message
    # The leg first: straight out at rest to rest, then the tree keeps the whole margin.
    leg_end = problem.search_start
    assert np.array_equal(result.states[0], [*world.start, 0, 0, 0])
    assert np.allclose(result.states[2], [*leg_end, 0, 0, 0], atol=1e-12)
    following = MODEL.propagate(result.states[:-1], result.controls, result.durations)
    assert np.allclose(following, result.states[1:], rtol=0, atol=1e-12)
    leg = exact_positions(result.states[:2], MODEL.acceleration(result.controls[:2]),
                          np.linspace(0, 1, 50) * result.durations[:2, None])
    offsets = leg.reshape(-1, 3) - world.start
    direction = (leg_end - world.start) / np.linalg.norm(leg_end - world.start)
    assert np.allclose(offsets - np.outer(offsets @ direction, direction), 0, atol=1e-12)
    positions = exact_positions(result.states[2:-1], MODEL.acceleration(result.controls[2:]),
                                np.linspace(0, 1, 50) * result.durations[2:, None])
    assert world.inflate(world.margin).points_free(positions.reshape(-1, 3)).all()


def test_start_in_a_block_is_a_user_error(forest):
    centre = (forest.blocks[0, :3] + forest.blocks[0, 3:]) / 2
    with pytest.raises(QuadnavError, match=r"^start .* inside block 0"):
        plan_quadrotor(forest, centre, forest.goal, SETTINGS)


def test_disconnected_start_and_goal_is_a_user_error():
    wall = World(boundary=[0, 0, 0, 10, 10, 4], blocks=[[0, 4, 0, 10, 5, 4]])
    with pytest.raises(QuadnavError, match="disconnected"):
        plan_quadrotor(wall, (2, 2, 2), (8, 8, 2), SETTINGS)


# ---------------------------------------------------------------------------- figures
def test_figures_draw_the_tree_the_flight_and_the_controls(forest, forest_plan, tmp_path):
    fig = quadrotor_figure(forest, forest_plan, MODEL, goal=forest.goal)
    ax = fig.axes[0]
    tree = [drawn for drawn in ax.get_lines() if drawn.get_color() == TREE_COLOR]
    assert len(tree) == 1  # one line through every edge's chords, the pen lifted between
    x = tree[0].get_data_3d()[0]
    edges = min(len(forest_plan.tree_states) - 1, MAX_TREE_SEGMENTS // TREE_PIECES)
    assert np.isnan(x).sum() == edges - 1 and len(x) == edges * (TREE_PIECES + 2) - 1
    flight = ax.get_lines()[-1]
    assert np.allclose(np.array(flight.get_data_3d()).T[[0, -1]],
                       forest_plan.states[[0, -1], :3])
    assert_outlined(flight)
    assert_legends_outside(fig)
    assert_labels_apart(fig)
    save_figure(fig, tmp_path / "tree.png")
    fig = quadrotor_controls_figure(forest_plan, MODEL)
    assert_labels_apart(fig)
    assert len(fig.axes) == 4
    steps = fig.axes[0].get_lines()[0].get_data()
    assert steps[0][-1] == pytest.approx(forest_plan.duration)
    save_figure(fig, tmp_path / "controls.png")
    unsolved = plan_quadrotor(forest, forest.start, forest.goal,
                              SETTINGS.replace(max_iterations=3))
    for fig in (quadrotor_figure(forest, unsolved, MODEL), quadrotor_controls_figure(unsolved)):
        plt.close(fig)
    assert (tmp_path / "tree.png").stat().st_size > 0
    assert (tmp_path / "controls.png").stat().st_size > 0

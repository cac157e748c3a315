"""Differential drive: exact unicycle motion, planar worlds, and the kinodynamic RRT whose
tree edges are collision-free along their integrated motion."""

from __future__ import annotations

import re

import numpy as np
import pytest
from figurecheck import assert_labels_apart, assert_legends_outside, assert_outlined

from quadnav.errors import MapError, PlanningWarning, QuadnavError
from quadnav.kinodynamic import KinoSettings
from quadnav.kinodynamic.diffdrive import (
    CHORD_TOLERANCE,
    LEG_SPEED,
    DiffDrive,
    arc_samples,
    control_profile,
    plan_diffdrive,
    propagate,
    segments_needed,
    track,
    wheel_tracks,
    wrap_angle,
)
from quadnav.kinodynamic.world2d import World2D, load_world2d, parse_map2d, slice_world
from quadnav.viz.figures import save_figure
from quadnav.viz.kino2d import (
    biased_vs_unbiased_figure,
    diffdrive_controls_figure,
    diffdrive_figure,
)
from quadnav.world import World, load_world

# Two walls make an S-shaped course from the lower left to the upper right.
WALLS = World2D(boundary=[0, 0, 10, 10], rects=[[3, 0, 4, 6], [6, 4, 7, 10]], name="walls")
START = (1.0, 1.0, 0.0)
GOAL = (9.0, 9.0)
MARGIN = 0.1
MODEL = DiffDrive()
SETTINGS = KinoSettings(max_iterations=20000, time_limit=60.0, seed=3)


def angle_gap(a, b) -> np.ndarray:
    return np.abs(wrap_angle(np.asarray(a) - np.asarray(b)))


def rk4_unicycle(states: np.ndarray, controls: np.ndarray, t: float, steps: int) -> np.ndarray:
    """The unicycle ODE integrated with classic RK4 (reference only)."""
    def f(s):
        return np.column_stack([controls[:, 0] * np.cos(s[:, 2]),
                                controls[:, 0] * np.sin(s[:, 2]), controls[:, 1]])
    s, h = states.copy(), t / steps
    for _ in range(steps):
        k1 = f(s)
        k2 = f(s + 0.5 * h * k1)
        k3 = f(s + 0.5 * h * k2)
        k4 = f(s + h * k3)
        s = s + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return s


@pytest.fixture(scope="module")
def walls_plan():
    return plan_diffdrive(WALLS, START, GOAL, SETTINGS, MODEL, margin=MARGIN)


# ------------------------------------------------------------------------ integration
def test_propagate_matches_a_fine_rk4():
    rng = np.random.default_rng(0)
    states = rng.uniform([-5, -5, -np.pi], [5, 5, np.pi], size=(40, 3))
    controls = rng.uniform([-0.5, -2.0], [1.5, 2.0], size=(40, 2))
    controls[:4, 1] = [0.0, 1e-12, -1e-9, 1e-6]  # straight and nearly straight
    controls[4, 0] = 0.0  # turning on the spot
    exact = propagate(states, controls, 1.3)
    reference = rk4_unicycle(states, controls, 1.3, steps=4000)
    np.testing.assert_allclose(exact[:, :2], reference[:, :2], atol=1e-9, rtol=0)
    assert angle_gap(exact[:, 2], reference[:, 2]).max() < 1e-9
    assert np.all((-np.pi <= exact[:, 2]) & (exact[:, 2] < np.pi))


def test_straight_line_and_full_circle():
    straight = propagate([1.0, 2.0, 0.3], [0.8, 0.0], 2.0)
    np.testing.assert_allclose(straight, [1 + 1.6 * np.cos(0.3), 2 + 1.6 * np.sin(0.3), 0.3],
                               atol=1e-15)
    start = np.array([2.0, -1.0, 2.5])
    for v, omega in ((1.0, 0.7), (-0.3, -1.9), (0.5, 1e-3)):
        back = propagate(start, [v, omega], 2 * np.pi / abs(omega))
        np.testing.assert_allclose(back[:2], start[:2], atol=1e-9)
        assert angle_gap(back[2], start[2]) < 1e-9
        half = propagate(start, [v, omega], np.pi / abs(omega))  # opposite side of the circle
        assert np.hypot(*(half[:2] - start[:2])) == pytest.approx(2 * abs(v / omega))


@pytest.mark.parametrize(("control", "reach"), [
    ((1.0, 1.5), 0.0), ((0.05, -1.5), 0.0), ((1.0, 1e-7), 0.0), ((0.0, 1.2), 0.15),
    ((0.4, 0.9), 0.15), ((-0.2, 0.0), 0.15)])
def test_track_chords_stay_within_the_tolerance(control, reach):
    """Every point of the true motion (centre, and points ``reach`` m to either side) is
    within the tolerance of the chord drawn between the samples around it."""
    tolerance, duration = 1e-3, 3.0
    state = np.array([0.5, 0.5, 0.4])
    samples = track(state, control, duration, tolerance, reach)
    np.testing.assert_array_equal(samples[-1], propagate(state, control, duration))
    steps = len(samples) - 1
    fine = arc_samples(samples[:-1], np.tile(control, (steps, 1)), duration / steps, 50)
    for side in (-reach, 0.0, reach):
        offset = side * np.stack([-np.sin(fine[..., 2]), np.cos(fine[..., 2])], axis=-1)
        curve = fine[..., :2] + offset
        a, b = curve[:, :1], curve[:, -1:]  # chord ends per step
        ab = b - a
        along = np.clip(np.sum((curve - a) * ab, -1) / np.maximum(np.sum(ab * ab, -1), 1e-300),
                        0, 1)
        deviation = np.linalg.norm(curve - (a + along[..., None] * ab), axis=-1)
        assert deviation.max() <= tolerance + 1e-12


def test_segments_needed_is_one_for_straight_motion_and_grows_with_curvature():
    counts = segments_needed([[1.0, 0.0], [0.0, 0.0], [1.0, 0.5], [1.0, 1.5]], 2.0, 1e-3)
    assert counts[0] == counts[1] == 1
    assert 1 < counts[2] < counts[3]


def test_wheels_follow_the_wheel_speeds():
    """Wheels sit b/2 to either side; each wheel's track is as long as |its speed| x t."""
    model = DiffDrive(wheel_base=0.4)
    state = np.array([1.0, 1.0, 0.5])
    left, right = model.wheel_positions(state)
    np.testing.assert_allclose(left - right, 0.4 * np.array([-np.sin(0.5), np.cos(0.5)]))
    np.testing.assert_allclose(0.5 * (left + right), state[:2])
    for control in ((0.8, 1.2), (0.0, -1.0), (0.3, 0.0), (-0.2, 1.5)):
        samples = track(state, control, 2.0, 1e-6, reach=0.2)
        tracks = model.wheel_positions(samples)
        speeds = model.wheel_speeds(control)
        for wheel, speed in zip(tracks, speeds, strict=True):
            length = np.linalg.norm(np.diff(wheel, axis=0), axis=1).sum()
            assert length == pytest.approx(abs(speed) * 2.0, abs=1e-4)
    left_speed, right_speed = model.wheel_speeds((0.5, 1.0))
    assert (left_speed, right_speed) == pytest.approx((0.3, 0.7))  # turning left


def test_model_limits_are_checked():
    for bad in ({"wheel_base": 0.0}, {"v_min": 1.0, "v_max": 1.0}, {"omega_max": -1.0},
                {"radius": -0.1}, {"v_max": float("nan")}):
        with pytest.raises(QuadnavError):
            DiffDrive(**bad)
    controls = MODEL.sample_controls(np.random.default_rng(0), 1000)
    assert np.all((MODEL.v_min <= controls[:, 0]) & (controls[:, 0] <= MODEL.v_max))
    assert np.all(np.abs(controls[:, 1]) <= MODEL.omega_max)


# ----------------------------------------------------------------------------- planning
def test_plan_reaches_the_goal_region(walls_plan):
    result = walls_plan
    assert result.solved, result.message
    assert result.planner == "diffdrive"
    np.testing.assert_array_equal(result.states[0], START)
    assert np.hypot(*(result.states[-1, :2] - GOAL)) <= SETTINGS.goal_radius
    assert result.controls.shape == (len(result.states) - 1, 2)
    np.testing.assert_array_equal(result.durations, SETTINGS.duration)
    assert result.time_to_goal == result.seconds and result.iterations <= SETTINGS.max_iterations


def test_every_tree_edge_is_collision_free_along_its_motion(walls_plan):
    """Each edge re-tracked finely is free of the rectangles grown by radius + margin
    (not by the chord tolerance the search adds)."""
    result = walls_plan
    world = WALLS.inflate(MODEL.radius + MARGIN)
    parents = result.tree_parents
    assert parents[0] == -1 and np.all(
        (parents[1:] >= 0) & (parents[1:] < np.arange(1, len(parents))))
    steps = int(segments_needed(result.tree_controls[1:], SETTINGS.duration, 1e-4).max())
    arcs = arc_samples(result.tree_states[parents[1:]], result.tree_controls[1:],
                       result.tree_durations[1:], steps)
    np.testing.assert_array_equal(arcs[:, -1], result.tree_states[1:])
    xy = arcs[..., :2]
    chords = np.stack([xy[:, :-1], xy[:, 1:]], axis=2).reshape(-1, 2, 2)
    assert world.segments_free(chords).all()
    assert len(result.tree_states) > 100


def test_controls_reproduce_the_path(walls_plan):
    result = walls_plan
    state = np.array(START)
    for i, (control, duration) in enumerate(zip(result.controls, result.durations, strict=True)):
        state = propagate(state, control, duration)
        np.testing.assert_allclose(state[:2], result.states[i + 1, :2], atol=1e-9, rtol=0)
        assert angle_gap(state[2], result.states[i + 1, 2]) < 1e-9
    centre, left, right, t = wheel_tracks(result, MODEL)
    np.testing.assert_allclose(centre[-1], result.states[-1, :2], atol=1e-12)
    assert t[-1] == pytest.approx(result.duration) and np.all(np.diff(t) > 0)
    np.testing.assert_allclose(np.linalg.norm(left - right, axis=1), MODEL.wheel_base)
    times, v, omega, left_speed, right_speed = control_profile(result, MODEL)
    assert times.shape == v.shape == (2 * len(result.controls),)
    np.testing.assert_allclose(times[1::2] - times[::2], result.durations)
    np.testing.assert_array_equal(v[::2], result.controls[:, 0])
    np.testing.assert_allclose(right_speed - left_speed, omega * MODEL.wheel_base)


def test_same_seed_same_plan(walls_plan):
    again = plan_diffdrive(WALLS, START, GOAL, SETTINGS, MODEL, margin=MARGIN)
    np.testing.assert_array_equal(again.tree_states, walls_plan.tree_states)
    np.testing.assert_array_equal(again.controls, walls_plan.controls)
    other = plan_diffdrive(WALLS, START, GOAL, SETTINGS.replace(seed=4), MODEL, margin=MARGIN)
    assert not np.array_equal(other.tree_states[:50], walls_plan.tree_states[:50])


def test_biased_sampling_needs_fewer_iterations():
    counts = {}
    for biased in (True, False):
        runs = [plan_diffdrive(WALLS, START, GOAL, SETTINGS.replace(seed=seed, biased=biased),
                               MODEL) for seed in range(10)]
        assert all(r.solved for r in runs)
        counts[biased] = [r.iterations for r in runs]
    print(f"\niterations to the goal over seeds 0-9: biased {counts[True]} "
          f"(median {np.median(counts[True]):g}), unbiased {counts[False]} "
          f"(median {np.median(counts[False]):g})")
    assert np.median(counts[True]) < np.median(counts[False])


def test_budget_ends_the_search_without_a_plan():
    calls = []
    result = plan_diffdrive(WALLS, START, GOAL, SETTINGS.replace(max_iterations=30), MODEL,
                            progress=lambda fraction, closest: calls.append((fraction, closest)))
    assert not result.solved and result.iterations == 30
    assert result.states.shape == (0, 3) and result.time_to_goal is None
    assert "not reached in 30 iterations" in result.message
    assert calls[-1][0] == 1.0 and calls[-1][1] > SETTINGS.goal_radius


@pytest.mark.parametrize(("start", "goal", "expected"), [
    ((3.5, 3.0, 0.0), GOAL, "walls: start (3.5, 3) is within 0.21 m (robot radius 0.2 m + tolerance 0.01 m) of rect 0 [3, 4] x [0, 6]"),
    ((2.85, 3.0, 0.0), GOAL, "start (2.85, 3) is within 0.21 m (robot radius"),
    ((1.0, 1.0, 0.0), (1.0, 1.0), "start and goal are the same point (1, 1)"),
    ((11.0, 3.0, 0.0), GOAL, "start (11, 3) is outside the boundary [0, 10] x [0, 10]"),
    (START, (9.0, 9.9), "tolerance 0.01 m) of the boundary"),
    (START, (6.5, 12.0), "goal (6.5, 12) is outside the boundary"),
    ((1.0, 1.0), GOAL, "start: expected 3 finite numbers x y theta"),
])
def test_bad_start_or_goal_is_named(start, goal, expected):
    with pytest.raises(QuadnavError, match=re.escape(expected)):
        plan_diffdrive(WALLS, start, goal, SETTINGS, MODEL, margin=MARGIN)


# ------------------------------------------------------------------------------ worlds
def test_world2d_queries_are_exact_and_open():
    assert WALLS.is_free([2.0, 2.0]) and not WALLS.is_free([3.5, 2.0])
    assert not WALLS.is_free([3.0, 2.0])  # on a rectangle's edge
    assert not WALLS.is_free([0.0, 2.0])  # on the boundary
    segments = [[[2, 7], [5, 7]], [[2, 6], [5, 6]], [[2, 6.0001], [5, 6.0001]], [[2, 1], [2, 9]]]
    np.testing.assert_array_equal(WALLS.segments_free(segments), [True, False, True, True])
    grown = WALLS.inflate(0.5)
    np.testing.assert_array_equal(grown.boundary, [0.5, 0.5, 9.5, 9.5])
    np.testing.assert_array_equal(grown.rects[0], [2.5, -0.5, 4.5, 6.5])
    assert not grown.is_free([2.6, 2.0]) and grown.is_free([2.4, 2.0])
    with pytest.raises(QuadnavError, match="leaves no free space"):
        WALLS.inflate(5.0)


def test_slice_of_a_builtin_world():
    world = load_world("forest")
    plane = load_world2d("forest", 1.0)
    held = (world.blocks[:, 2] <= 1.0) & (world.blocks[:, 5] >= 1.0)
    assert 0 < len(plane) == held.sum() < len(world)  # the branches are higher up
    np.testing.assert_array_equal(plane.rects, world.blocks[held][:, [0, 1, 3, 4]])
    points = np.random.default_rng(1).uniform(world.lower[:2], world.upper[:2], size=(2000, 2))
    lifted = np.column_stack([points, np.ones(len(points))])
    np.testing.assert_array_equal(plane.points_free(points), world.points_free(lifted))
    result = plan_diffdrive(plane, (*world.start[:2], 0.0), world.goal[:2], SETTINGS, MODEL)
    assert result.solved, result.message


def test_slice_of_a_course_map(shared_maps):
    plane = load_world2d(shared_maps / "rbe595" / "map1.txt", 3.0)
    np.testing.assert_array_equal(plane.boundary, [0, -5, 10, 20])
    np.testing.assert_array_equal(plane.rects, [[0, 2, 3, 2.5], [7, 2, 10, 2.5],
                                                [3, 0, 7, 0.5], [0, 15, 10, 16]])
    result = plan_diffdrive(plane, (5.0, -3.0, np.pi / 2), (5.0, 10.0), SETTINGS, MODEL)
    assert result.solved, result.message
    assert result.states[-1, 1] > 9  # through the gap in the wall at y = 2


def test_slice_height_must_be_inside_the_boundary():
    world = World(boundary=[0, 0, 0, 5, 5, 3], blocks=[[1, 1, 0, 2, 2, 1], [3, 3, 1, 4, 4, 2]])
    assert len(slice_world(world, 1.0)) == 2  # touching faces count
    assert len(slice_world(world, 0.5)) == 1
    assert len(load_world2d(world)) == 1  # half way up: z = 1.5
    for height in (0.0, 3.0, -1.0, float("nan")):
        with pytest.raises(QuadnavError, match="outside the boundary's z-range"):
            slice_world(world, height)


def test_map2d_file(tmp_path):
    path = tmp_path / "course.map2d"
    path.write_text("# a small course\n\nrect 2 0 3 3.5  # wall\n"
                    "boundary 0 0 6 5\r\nrect\t4 1.5 5 5\n")
    plane = load_world2d(path, height=123.0)  # the height of a 2D map is not used
    np.testing.assert_array_equal(plane.boundary, [0, 0, 6, 5])
    np.testing.assert_array_equal(plane.rects, [[2, 0, 3, 3.5], [4, 1.5, 5, 5]])
    assert plane.name == str(path)
    result = plan_diffdrive(plane, (1.0, 1.0, np.pi / 2), (5.3, 0.7), SETTINGS, MODEL)
    assert result.solved, result.message
    with pytest.raises(MapError, match="cannot read"):
        load_world2d(tmp_path / "missing.map2d")


@pytest.mark.parametrize(("content", "expected"), [
    ("", "m.map2d: empty map"),
    ("# nothing\n\n", "m.map2d: empty map"),
    ("boundary 0 0 5 5\nblock 0 0 0 1 1 1\n", "m.map2d:2: unknown keyword 'block'"),
    ("boundary 0 0 5\n", "m.map2d:1: boundary: expected 4 numbers (xmin ymin xmax ymax), got 3"),
    ("boundary 0 0 5 5\n\nrect 1 1 2 2 3\n", "m.map2d:3: rect: expected 4 numbers"),
    ("boundary 0 0 5 5\nrect 1 one 2 2\n", "m.map2d:2: rect: expected a number, got 'one'"),
    ("boundary 0 0 5 inf\n", "m.map2d:1: boundary: expected a finite number"),
    ("boundary 0 0 5 0\n", "m.map2d:1: boundary: zero thickness along y (ymin = ymax = 0): "
     "expected a box with a volume"),
    ("boundary 0 0 5 5\nboundary 0 0 6 6\n", "m.map2d:2: a second boundary line (the first is line 1)"),
    ("rect 1 1 2 2\n", "m.map2d: no 'boundary"),
])
def test_malformed_map2d_lines(content, expected):
    with pytest.raises(MapError) as info:
        parse_map2d(content, "m.map2d")
    assert str(info.value).startswith(expected)
    assert "\n" not in str(info.value)


# ----------------------------------------------------------------------------- figures
def test_figures_are_written(tmp_path, walls_plan):
    unbiased = plan_diffdrive(WALLS, START, GOAL, SETTINGS.replace(biased=False), MODEL,
                              margin=MARGIN)
    figures = {
        "plan.png": diffdrive_figure(WALLS, walls_plan, MODEL, GOAL, SETTINGS.goal_radius),
        "controls.png": diffdrive_controls_figure(walls_plan, MODEL),
        "compare.png": biased_vs_unbiased_figure(WALLS, walls_plan, unbiased, MODEL, GOAL,
                                                 SETTINGS.goal_radius),
    }
    for name, fig in figures.items():
        assert_legends_outside(fig)
        assert_labels_apart(fig)
        if name != "controls.png":
            centres = [line for ax in fig.axes for line in ax.get_lines()
                       if line.get_label().startswith("centre")]
            assert len(centres) == (2 if name == "compare.png" else 1)
            for centre in centres:
                assert_outlined(centre)
        save_figure(fig, tmp_path / name)
        assert (tmp_path / name).stat().st_size > 10_000


def test_a_start_in_the_margin_leaves_it_by_turning_on_the_spot_and_driving_straight():
    x = 3 - MODEL.radius - CHORD_TOLERANCE - 0.5 * MARGIN  # inside the margin of rect 0
    with pytest.warns(PlanningWarning, match=rf"start \({x:.4g}, 3\) is inside the 0.1 m"):
        result = plan_diffdrive(WALLS, (x, 3.0, 0.0), GOAL, SETTINGS, MODEL, margin=MARGIN)
    assert result.solved
    # Turn to face away from the wall (pi), then drive straight out of the margin.
    assert np.allclose(np.abs(result.controls[:2]), [[0.0, MODEL.omega_max], [LEG_SPEED, 0.0]])
    assert result.durations[0] == pytest.approx(np.pi / MODEL.omega_max)
    leg_end = result.states[2]
    assert leg_end[1] == 3.0 and 3 - leg_end[0] > MODEL.radius + CHORD_TOLERANCE + MARGIN
    following = propagate(result.states[:-1], result.controls, result.durations)
    assert np.allclose(following[:, :2], result.states[1:, :2], atol=1e-9)
    assert np.allclose(angle_gap(following[:, 2], result.states[1:, 2]), 0, atol=1e-9)
    # After the leg the robot keeps radius + margin from every rectangle.
    kept = WALLS.inflate(MODEL.radius + MARGIN)
    assert kept.points_free(result.states[2:, :2]).all()


def test_a_goal_in_the_margin_is_reached_along_its_leg_within_the_goal_radius():
    """The goal region is centred on the end of the goal's leg, 0.58 m from the goal; the
    plan drives from the state reached there straight to that point and along the leg, so
    it ends on the goal asked for, not up to 1.08 m from it."""
    margin, settings = 0.6, KinoSettings(seed=3)
    goal = np.array([10 - MODEL.radius - CHORD_TOLERANCE - 0.05, 9.0])  # 0.05 m in
    with pytest.warns(PlanningWarning, match=r"goal \(9.74, 9\) is inside the 0.6 m"):
        result = plan_diffdrive(WALLS, START, goal, settings, MODEL, margin=margin)
    assert result.solved
    assert np.array_equal(result.states[-1, :2], goal)
    assert result.closing_controls >= 1 and result.goal_leg_controls >= 1
    tail = result.closing_controls + result.goal_leg_controls
    reached, leg_end = result.states[-1 - tail], result.states[-1 - result.goal_leg_controls]
    assert np.linalg.norm(leg_end[:2] - goal) > settings.goal_radius  # the region's centre
    assert np.linalg.norm(reached[:2] - leg_end[:2]) <= settings.goal_radius
    following = propagate(result.states[:-1], result.controls, result.durations)
    assert np.allclose(following[:, :2], result.states[1:, :2], atol=1e-9)
    # Up to the leg the robot keeps radius + margin from every rectangle and the boundary.
    kept = WALLS.inflate(MODEL.radius + margin)
    drive = np.linspace(reached[:2], leg_end[:2], 200)
    assert kept.points_free(np.vstack([result.states[:-result.goal_leg_controls, :2],
                                       drive])).all()


def test_chord_tolerance_is_part_of_the_clearance():
    """A start just outside the radius, but inside the chord tolerance, is refused."""
    x = 3 - MODEL.radius - 0.5 * CHORD_TOLERANCE
    with pytest.raises(QuadnavError, match="tolerance"):
        plan_diffdrive(WALLS, (x, 3.0, 0.0), GOAL, SETTINGS, MODEL, margin=MARGIN)

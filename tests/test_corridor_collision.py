"""Safe corridors around real and hand-made paths, dense collision checks of trajectories,
and refinement that adds waypoints until a trajectory stays free.

Real paths come from the RRT* planner (seeded) with shortcuts and smoothing, on the
built-in worlds and the public course maps; corner-cutting trajectories are clamped cubic
splines written here, so nothing depends on the other trajectory generators.
"""

from __future__ import annotations

import itertools
import re
from functools import cache

import numpy as np
import pytest
from scipy.interpolate import CubicSpline

from quadnav.errors import QuadnavError
from quadnav.planning import PlannerSettings, PlanningProblem, make_problem, plan
from quadnav.planning.refine import refine
from quadnav.trajectory import Trajectory, ppoly_from_ascending
from quadnav.trajectory.clearance.collision import (
    Collision,
    collisions,
    first_collision,
    insert_points,
    refine_until_free,
)
from quadnav.trajectory.clearance.corridor import CLEARANCE, safe_corridors
from quadnav.world import World, load_world, read_map

SPEED = 1.0  # m/s, for the test's cubic splines


@cache
def planned(spec: str, margin: float = 0.2, start=None, goal=None
            ) -> tuple[PlanningProblem, np.ndarray]:
    """A problem and the free part (from search start to search goal) of its refined
    RRT* path; ``spec`` is a built-in world spec or a map file path."""
    world = read_map(spec) if spec.endswith((".txt", ".json")) else load_world(spec)
    problem = make_problem(world, start, goal, margin)
    result = refine(problem, plan(problem, PlannerSettings(
        seed=0, max_iterations=20000, time_limit=60)))
    assert result.solved
    path = result.path
    return problem, problem.search_part(path)


def cubic(waypoints: np.ndarray, times: np.ndarray) -> Trajectory:
    """A clamped cubic spline through ``waypoints`` (N, 3) with segment ``times`` (N - 1,)."""
    breaks = np.concatenate([[0.0], np.cumsum(times)])
    return Trajectory(CubicSpline(breaks, waypoints, bc_type="clamped"), waypoints, "cubic")


def distance_times(waypoints: np.ndarray) -> np.ndarray:
    return np.linalg.norm(np.diff(waypoints, axis=0), axis=1) / SPEED


def polyline(waypoints, breaks) -> Trajectory:
    """Straight lines at constant speed between waypoints (N, 3) passed at ``breaks``."""
    points = np.asarray(waypoints, dtype=float)
    durations = np.diff(breaks)[:, None]
    coefficients = np.stack([points[:-1], np.diff(points, axis=0) / durations], axis=1)
    return Trajectory(ppoly_from_ascending(coefficients, breaks), points, "linear")


def assert_corridors(free_world: World, path: np.ndarray, points: np.ndarray,
                     boxes: np.ndarray) -> None:
    """``points`` is ``path`` with points on its segments added, and every box contains
    its segment, misses every inflated block strictly and lies inside the boundary."""
    assert boxes.shape == (len(points) - 1, 6)
    # The original waypoints, in order, with the added points on the original segments.
    kept = [int(np.flatnonzero(np.all(points == p, axis=1))[0]) for p in path]
    assert kept[0] == 0 and kept[-1] == len(points) - 1 and np.all(np.diff(kept) > 0)
    for i, (first, last) in enumerate(itertools.pairwise(kept)):
        chord = path[i + 1] - path[i]
        along = (points[first:last + 1] - path[i]) @ chord / (chord @ chord)
        assert np.all(np.diff(along) > 0)
        np.testing.assert_allclose(path[i] + along[:, None] * chord, points[first:last + 1],
                                   atol=1e-9)
    lower, upper = boxes[:, :3], boxes[:, 3:]
    assert np.all(lower <= np.minimum(points[:-1], points[1:]))
    assert np.all(upper >= np.maximum(points[:-1], points[1:]))
    blocks = free_world.blocks
    overlap = np.all((lower[:, None] <= blocks[None, :, 3:])
                     & (blocks[None, :, :3] <= upper[:, None]), axis=2)
    assert not overlap.any()
    assert np.all(lower > free_world.lower) and np.all(upper < free_world.upper)
    # So the segments, and the boxes' corners and centres, are free.
    assert free_world.segments_free(np.stack([points[:-1], points[1:]], axis=1)).all()
    corners = np.stack([lower, upper, 0.5 * (lower + upper)], axis=1).reshape(-1, 3)
    assert free_world.points_free(corners).all()


# ------------------------------------------------------------------------------ corridors
@pytest.mark.parametrize("spec", ["forest", "window", "maze",
                                  "forest:size=100x100x20,density=0.08"])
def test_corridors_around_real_plans_on_builtin_worlds(spec):
    problem, path = planned(spec)
    points, boxes = safe_corridors(problem.free_world, path)
    assert_corridors(problem.free_world, path, points, boxes)
    # Growth made room: every box is thicker than the bounding box of its segment.
    thickness = boxes[:, 3:] - boxes[:, :3]
    assert np.all(thickness.min(axis=1) > 0.1)
    # Deterministic, and a second pass over its own output splits nothing.
    again_points, again_boxes = safe_corridors(problem.free_world, points)
    np.testing.assert_array_equal(again_points, points)
    np.testing.assert_array_equal(safe_corridors(problem.free_world, path)[1], boxes)
    assert again_boxes.shape == boxes.shape


@pytest.mark.filterwarnings("ignore:start .* is inside the 0.3 m safety margin")
@pytest.mark.parametrize(("name", "start", "goal", "margin"), [
    ("rbe595/map1.txt", (0.5, -4.5, 0.5), (8.0, 18.0, 3.0), 0.2),
    ("meam620/test_window.json", None, None, 0.3),  # start inside the margin
    ("rbe595/map4.txt", (5.0, 16.0, 3.0), (24.0, 16.0, 3.0), 0.2),
])
def test_corridors_around_real_plans_on_public_maps(shared_maps, name, start, goal, margin):
    problem, path = planned(str(shared_maps / name), margin, start, goal)
    points, boxes = safe_corridors(problem.free_world, path)
    assert_corridors(problem.free_world, path, points, boxes)


def test_diagonal_segment_past_a_corner_is_split_where_both_pieces_clear_it():
    # A wall x in [4, 6], y <= 4; the segment y = x + 2 passes its corner (4, 4).
    world = World(boundary=[0, 0, 0, 10, 10, 10], blocks=[[4, 0, 0, 6, 4, 10]])
    path = np.array([[1.0, 3, 5], [7, 9, 5]])
    points, boxes = safe_corridors(world, path, max_growth=0.0)
    # x < 4 holds before s = 1/2, y > 4 after s = 1/6: split at s = 1/3.
    np.testing.assert_allclose(points, [[1, 3, 5], [3, 5, 5], [7, 9, 5]])
    np.testing.assert_allclose(boxes, [[1, 3, 5, 3, 5, 5], [3, 5, 5, 7, 9, 5]])
    assert_corridors(world, path, points, boxes)
    with pytest.raises(QuadnavError, match=r"no safe corridor for waypoint segment 0 from "
                                           r"\(1, 3, 5\) to \(7, 9, 5\): after 0 levels"):
        safe_corridors(world, path, max_splits=0)


def test_segment_grazing_several_corners_in_3d():
    # Blocks on both sides of a 3D diagonal, each passed 1 mm off one of its vertices.
    path = np.array([[0.5, 0.5, 0.5], [9.5, 9.5, 9.5]])
    near = np.array([3.0, 3.0, 3.0]) + 0.001 / np.sqrt(2) * np.array([1, -1, 0])
    blocks = [[near[0], 0, 0, 10, near[1], near[2]],  # below-right of the line at t = 3
              [0, 6.001, 0, 5.999, 10, 10]]  # above-left at t = 6
    world = World(boundary=[0, 0, 0, 10, 10, 10], blocks=blocks)
    assert world.segment_free(*path)
    points, boxes = safe_corridors(world, path)
    assert_corridors(world, path, points, boxes)
    # One split per block, each where the line passes the block's vertex (halving would
    # need about 13 levels for a 1 mm clearance on a 15.6 m segment).
    np.testing.assert_allclose(points[1:-1], [[3, 3, 3], [6, 6, 6]], atol=1e-9)


def test_growth_stops_at_blocks_and_the_boundary():
    world = World(boundary=[0, 0, 0, 10, 10, 10], blocks=[
        [3.5, 0, 0, 4, 10, 10],  # wall ahead in +x, 0.5 m away
        [0, 2.3, 0, 3.2, 10, 10],  # block ahead in +y, 0.3 m away
        [0, 0, 0, 10, 10, 1.5],  # floor, 0.5 m below
        [6, 0, 0, 7, 0.5, 10],  # behind the wall: never reached
    ])
    path = np.array([[0.4, 2, 2], [3, 2, 2]])
    points, boxes = safe_corridors(world, path, max_growth=1.0)
    np.testing.assert_array_equal(points, path)
    expected = [CLEARANCE, 1, 1.5 + CLEARANCE, 3.5 - CLEARANCE, 2.3 - CLEARANCE, 3]
    np.testing.assert_allclose(boxes[0], expected, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(safe_corridors(world, path, max_growth=0.0)[1],
                                  [[0.4, 2, 2, 3, 2, 2]])


def test_corridors_of_random_free_segments_among_random_blocks():
    rng = np.random.default_rng(0)
    lows = rng.uniform(0, 9, size=(60, 3))
    world = World(boundary=[0, 0, 0, 10, 10, 10],
                  blocks=np.hstack([lows, lows + rng.uniform(0.2, 1.5, size=(60, 3))]))
    ends = world.sample_free(200, seed=1).reshape(100, 2, 3)
    free = ends[world.segments_free(ends)]
    assert len(free) > 20
    for segment in free:
        assert_corridors(world, segment, *safe_corridors(world, segment, max_growth=0.7))


@pytest.mark.parametrize(("waypoints", "options", "message"), [
    ([[1, 1, 1]], {}, r"waypoints must be an \(N, 3\) array with N >= 2, got shape \(1, 3\)"),
    ([[1, 1, 1], [2, np.nan, 1]], {}, r"waypoint 1 is \[2.0, nan, 1.0\]; expected finite"),
    ([[1, 1, 1], [9, 9, 1]], {}, r"waypoint segment 0 from \(1, 1, 1\) to \(9, 9, 1\) is not "
                                 r"in free space"),
    ([[1, 1, 1], [2, 1, 1]], {"max_growth": -1.0}, r"corridor growth must be .* got -1.0"),
    ([[1, 1, 1], [2, 1, 1]], {"max_splits": -1}, r"corridor splits must be >= 0, got -1"),
])
def test_bad_corridor_input_is_a_one_line_error(waypoints, options, message):
    world = World(boundary=[0, 0, 0, 10, 10, 10], blocks=[[4, 4, 0, 6, 6, 10]])
    with pytest.raises(QuadnavError, match=message):
        safe_corridors(world, waypoints, **options)


# ------------------------------------------------------------------------------ collisions
#: The region x < 4.5, y > 1.5 is blocked; the L-shaped path (1,1) -> (5,1) -> (5,5) is free.
CORNER = World(boundary=[0, 0, 0, 10, 10, 2], blocks=[[0, 1.5, 0, 4.5, 10, 2]])


def test_first_collision_of_a_corner_cutting_trajectory():
    # Straight from (1, 1, 1) to (5, 5, 1) at (1, 1) m/s: it enters the block at t = 0.5 s.
    cutting = polyline([[1, 1, 1], [3, 3, 1], [5, 5, 1]], [0.0, 2.0, 4.0])
    hit = first_collision(cutting, CORNER)
    assert isinstance(hit, Collision)
    assert hit.t == pytest.approx(0.5, abs=1e-9)
    np.testing.assert_allclose(hit.point, [1.5, 1.5, 1], atol=1e-9)
    assert hit.segment == 0
    np.testing.assert_array_equal(collisions(cutting, CORNER), [0, 1])
    around = polyline([[1, 1, 1], [5, 1, 1], [5, 5, 1]], [0.0, 4.0, 8.0])
    assert first_collision(around, CORNER) is None
    assert collisions(around, CORNER).size == 0


@pytest.mark.parametrize(("speed", "time_tolerance"), [(1.0, 2e-3), (0.0, 2e-2)])
def test_dense_check_finds_a_dip_between_coarse_samples(speed, time_tolerance):
    # y = -(t - 1.06)^2 peaks at 0, and dips 1 mm into the block y > -0.001 for 63 ms,
    # while x moves at ``speed``. Standing still in x, the samples near the peak are
    # close together however long apart in time: the chords' stray from the curve,
    # not their length, asks for more samples.
    world = World(boundary=[-1, -5, -1, 10, 5, 5], blocks=[[0, -0.001, 0, 10, 1, 2]])
    apex = 1.06
    coefficients = [[[0.5, -apex**2, 1], [speed, 2 * apex, 0], [0, -1, 0]]]
    trajectory = Trajectory(ppoly_from_ascending(coefficients, [0.0, 2.0]),
                            [[0.5, -apex**2, 1], [0.5 + 2 * speed, -(2 - apex) ** 2, 1]],
                            "quadratic")
    hit = first_collision(trajectory, world, spacing=0.02)
    assert hit is not None and hit.segment == 0
    assert hit.t == pytest.approx(apex - np.sqrt(0.001), abs=time_tolerance)
    assert hit.point[1] == pytest.approx(-0.001, abs=1e-3)
    np.testing.assert_allclose(hit.point, trajectory.position(hit.t))
    # Checked only every ~0.125 s, the chords pass below the dip.
    assert first_collision(trajectory, world, spacing=1.0) is None


def test_insert_points_keeps_order_and_places_points_on_segments():
    points = np.array([[0.0, 0, 0], [1, 0, 0], [1, 2, 0], [1, 2, 4]])
    np.testing.assert_array_equal(
        insert_points(points, np.array([0, 2]), [0.25, 0.5]),
        [[0, 0, 0], [0.25, 0, 0], [1, 0, 0], [1, 2, 0], [1, 2, 2], [1, 2, 4]])


# ------------------------------------------------------------------------------ refinement
def test_refinement_makes_a_corner_cutting_cubic_free_through_a_real_plan():
    problem, path = planned("window")
    times = distance_times(path)
    before = cubic(path, times)
    assert first_collision(before, problem.free_world) is not None
    after = refine_until_free(problem.free_world, path, times, cubic)
    assert first_collision(after, problem.free_world) is None
    rounds, inserted = after.info["refine_rounds"], after.info["inserted_waypoints"]
    assert rounds >= 1 and inserted >= rounds
    assert len(after.waypoints) == len(path) + inserted
    # Every original waypoint is passed, at its original time.
    rows = [int(np.flatnonzero(np.all(after.waypoints == p, axis=1))[0]) for p in path]
    np.testing.assert_allclose(after.breaks[rows], before.breaks, rtol=1e-12)
    np.testing.assert_allclose(after.position(after.breaks[rows]), path, atol=1e-9)
    # A free trajectory comes back as built, with zero rounds.
    free = refine_until_free(problem.free_world, after.waypoints, after.segment_times, cubic)
    assert free.info == {"refine_rounds": 0, "inserted_waypoints": 0}
    np.testing.assert_array_equal(free.poly.c, after.poly.c)


def test_refinement_gives_up_with_the_collision_in_the_message():
    problem, path = planned("window")
    times = distance_times(path)
    hit = first_collision(cubic(path, times), problem.free_world)
    expected = (f"trajectory still leaves free space at ({hit.point[0]:.4g}, "
                f"{hit.point[1]:.4g}, {hit.point[2]:.4g}) at t = {hit.t:.3f} s after 0 "
                "refinements; lower the speed or add waypoints")
    with pytest.raises(QuadnavError, match=f"^{re.escape(expected)}$"):
        refine_until_free(problem.free_world, path, times, cubic, max_rounds=0)


@pytest.mark.parametrize(("times", "options", "message"), [
    ([1.0], {}, r"expected 2 segment times for 3 waypoints, got shape \(1,\)"),
    ([1.0, 0.0], {}, r"segment times must be positive finite seconds, got \[1.0, 0.0\]"),
    ([1.0, 1.0], {"max_rounds": -1}, r"max rounds must be >= 0, got -1"),
    ([1.0, 1.0], {"spacing": 0.0}, r"check spacing must be a positive distance in m, got 0.0"),
])
def test_bad_refinement_input_is_a_one_line_error(times, options, message):
    waypoints = [[1, 1, 1], [5, 1, 1], [5, 5, 1]]
    with pytest.raises(QuadnavError, match=message):
        refine_until_free(CORNER, waypoints, times, cubic, **options)

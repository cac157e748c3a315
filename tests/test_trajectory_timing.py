"""The fastest timing flies at the asked speed: on every course map and built-in world, at
1, 2 and 3 m/s with a 3 m/s^2 limit, the trajectory's duration is close to the
rest-to-rest bound along its own curve, it never backs up, stays within the limits and
keeps the margin; and the time-optimal speed profile is right where it can be worked out
by hand."""

from __future__ import annotations

import functools
import math
import warnings
from pathlib import Path

import numpy as np
import pytest
from publicmaps import MAPS, course_query

from quadnav.errors import PlanningWarning, QuadnavError
from quadnav.mission import MissionSettings
from quadnav.planning import make_problem, plan
from quadnav.planning.refine import refine
from quadnav.trajectory.clearance.space import SafeSpace, trajectory_margins
from quadnav.trajectory.generate import METHODS, TrajectorySettings, make_trajectory
from quadnav.trajectory.timing.speed_profile import fastest_speeds, travel_times
from quadnav.world import load_world
from quadnav.world.builtin import world_names

SPEEDS = (1.0, 2.0, 3.0)
ACCELERATION = 3.0
#: Samples along a trajectory for its length, peaks and progress.
SAMPLES = 20_000
#: How far inside the margin the collision refinement may leave a curve, m: it checks
#: chords at most 1 mm from it (quadnav.trajectory.clearance.collision).
CHECK_TOLERANCE = 0.002
#: Most any one map and speed may take over the bound (see the README: the legs out of
#: the margin stop twice, and many sharp turns at 3 m/s slow down).
MOST_ABOVE_BOUND = 2.2


def rest_to_rest_bound(length: float, v: float, a: float) -> float:
    """The fastest rest-to-rest move over ``length`` m within v m/s and a m/s^2, turns
    ignored: ``L / v + v / a``, or ``2 sqrt(L / a)`` when it never reaches v."""
    return length / v + v / a if length >= v * v / a else 2.0 * math.sqrt(length / a)


def curve_length(trajectory) -> float:
    t = np.linspace(0.0, trajectory.duration, SAMPLES)
    return float(np.trapezoid(np.linalg.norm(trajectory.velocity(t), axis=1), t))


def least_progress(trajectory) -> float:
    """The slowest the trajectory moves along its waypoint polyline, m/s: at each sample,
    the velocity along the segment holding the nearest point of the polyline (searched
    among the segments near the one being flown), or 0 where that point is a vertex (the
    trajectory rounding a corner). Negative where it backs up along the path."""
    t = np.linspace(0.0, trajectory.duration, SAMPLES)
    position, velocity = trajectory.position(t), trajectory.velocity(t)
    starts, chords = trajectory.waypoints[:-1], np.diff(trajectory.waypoints, axis=0)
    lengths = np.linalg.norm(chords, axis=1)
    flown = np.clip(np.searchsorted(trajectory.breaks, t, side="right") - 1, 0,
                    len(chords) - 1)
    nearest, rate = np.full(len(t), np.inf), np.zeros(len(t))
    for shift in range(-2, 3):
        k = np.clip(flown + shift, 0, len(chords) - 1)
        along = np.einsum("ij,ij->i", position - starts[k], chords[k]) / lengths[k] ** 2
        foot = starts[k] + np.clip(along, 0.0, 1.0)[:, None] * chords[k]
        distance = np.linalg.norm(position - foot, axis=1)
        inside = (along > 0.0) & (along < 1.0)
        speed = np.where(inside, np.einsum("ij,ij->i", velocity, chords[k]) / lengths[k], 0.0)
        closer = distance < nearest
        nearest[closer], rate[closer] = distance[closer], speed[closer]
    return float(rate.min())


def _planned(world, start, goal, margin):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PlanningWarning)  # starts inside the margin
        problem = make_problem(world, start, goal, margin)
    settings = MissionSettings()
    return refine(problem, plan(problem, settings.planning, settings.planner)).path


@functools.cache
def _every_path(folder: Path) -> list[tuple]:
    """(name, world, margin, refined path) for every course map and built-in world."""
    cases = []
    for name in MAPS:
        world, start, goal, margin = course_query(folder, name)
        cases.append((name, world, margin, _planned(world, start, goal, margin)))
    for name in world_names():
        world = load_world(name)
        cases.append((name, world, world.margin,
                      _planned(world, world.start, world.goal, world.margin)))
    return cases


@functools.cache
def _map1(folder: Path) -> tuple:
    """(world, margin, refined path) of rbe595/map1.txt with the course's start and goal."""
    world, start, goal, margin = course_query(folder, "rbe595/map1.txt")
    return world, margin, _planned(world, start, goal, margin)


@pytest.fixture
def every_path(shared_maps):
    return _every_path(shared_maps)


#: The tests that share the planned paths run on one worker, which plans them once.
SHARED_PATHS = pytest.mark.xdist_group("trajectory-timing-paths")


@SHARED_PATHS
def test_every_map_flies_near_the_rest_to_rest_bound_never_backing_up(every_path):
    ratios = {}
    for name, world, margin, path in every_path:
        for v in SPEEDS:
            settings = TrajectorySettings(v_max=v, a_max=ACCELERATION)
            trajectory = make_trajectory(path, settings, SafeSpace(world, margin))
            length = curve_length(trajectory)
            ratios[name, v] = trajectory.duration / rest_to_rest_bound(length, v, ACCELERATION)
            t = np.linspace(0.0, trajectory.duration, SAMPLES)
            assert np.linalg.norm(trajectory.velocity(t), axis=1).max() <= v * 1.005
            assert np.linalg.norm(trajectory.acceleration(t), axis=1).max() <= 1.005 * (
                ACCELERATION)
            assert least_progress(trajectory) >= -1e-9, (name, v)
            kept, _ = trajectory_margins(trajectory, world)
            # Measured exactly; made by a check of chords within 1 mm of the curve.
            assert kept >= margin - CHECK_TOLERANCE, (name, v, kept)
    for (name, v), ratio in sorted(ratios.items(), key=lambda item: item[1]):
        print(f"{name} at {v:g} m/s: {ratio:.3f} x the rest-to-rest bound")
    values = np.array(list(ratios.values()))
    print(f"median {np.median(values):.3f}, max {values.max():.3f}")
    assert np.median(values) <= 1.2
    assert values.max() <= MOST_ABOVE_BOUND


@SHARED_PATHS
@pytest.mark.parametrize("method", [m for m in METHODS if m != "minsnap"])
def test_no_method_backs_up_on_any_map(every_path, method):
    for name, world, margin, path in every_path:
        settings = TrajectorySettings(method=method, v_max=3.0, a_max=ACCELERATION)
        trajectory = make_trajectory(path, settings, SafeSpace(world, margin))
        assert least_progress(trajectory) >= -1e-9, (name, method)
        kept, _ = trajectory_margins(trajectory, world)
        assert kept >= margin - CHECK_TOLERANCE, (name, method, kept)


@SHARED_PATHS
@pytest.mark.parametrize("method", METHODS.names())
def test_every_method_cruises_on_map1(shared_maps, method):
    world, margin, path = _map1(shared_maps)
    trajectory = make_trajectory(path, TrajectorySettings(method=method, v_max=2.0),
                                 SafeSpace(world, margin))
    length = curve_length(trajectory)
    ratio = trajectory.duration / rest_to_rest_bound(length, 2.0, 3.0)
    print(f"{method}: {trajectory.duration:.2f} s for {length:.2f} m, {ratio:.3f} x the bound")
    assert least_progress(trajectory) >= -1e-9
    assert ratio <= (1.3 if method != "quintic-average" else 2.5)


def test_the_speed_profile_of_a_straight_line_is_the_trapezoid():
    s = np.linspace(0.0, 10.0, 2001)
    speeds = fastest_speeds(s, np.zeros_like(s), 2.0, 1.0)
    assert speeds.max() == pytest.approx(2.0)
    np.testing.assert_allclose(speeds, np.minimum.reduce(
        [np.full_like(s, 2.0), np.sqrt(2.0 * s), np.sqrt(2.0 * (10.0 - s))]), atol=1e-12)
    assert travel_times(s, speeds)[-1] == pytest.approx(10.0 / 2.0 + 2.0 / 1.0, rel=1e-3)


def test_the_speed_profile_takes_a_turn_at_the_speed_its_curvature_allows():
    # A circle of radius 0.5 m at 3 m/s^2 is taken at sqrt(a r) = 1.22 m/s.
    s = np.linspace(0.0, 20.0, 4001)
    curvature = np.where((s > 8.0) & (s < 12.0), 2.0, 0.0)
    speeds = fastest_speeds(s, curvature, 3.0, 3.0)
    turning = (s > 8.0) & (s < 12.0)
    assert speeds[turning].max() == pytest.approx(math.sqrt(1.5), rel=1e-9)
    assert speeds.max() == pytest.approx(3.0)


def test_a_bad_profile_input_is_refused():
    with pytest.raises(QuadnavError, match="strictly increasing"):
        fastest_speeds([0.0, 0.0, 1.0], [0.0, 0.0, 0.0], 1.0, 1.0)
    with pytest.raises(QuadnavError, match="limits must be > 0"):
        fastest_speeds([0.0, 1.0], [0.0, 0.0], 0.0, 1.0)
    with pytest.raises(QuadnavError, match="unknown timing"):
        TrajectorySettings(timing="quick")


@SHARED_PATHS
def test_corridors_on_map1_at_the_default_limits(shared_maps):
    # Once "Clarabel: InsufficientProgress" on the README's own map1 path.
    world, margin, path = _map1(shared_maps)
    trajectory = make_trajectory(path, TrajectorySettings(corridor=True),
                                 SafeSpace(world, margin))
    kept, _ = trajectory_margins(trajectory, world)
    assert kept >= margin - CHECK_TOLERANCE
    assert least_progress(trajectory) >= -1e-9


def test_the_speed_profile_starts_and_stops_within_a_jerk():
    # From rest at jerk j the acceleration is a = j t and the distance d = j t^3 / 6, so
    # a <= (6 d j^2)^(1/3): at 1 mm from either end with j = 15 m/s^3, 1.13 m/s^2.
    s = np.linspace(0.0, 10.0, 10_001)
    free = fastest_speeds(s, np.zeros_like(s), 2.0, 3.0)
    ramped = fastest_speeds(s, np.zeros_like(s), 2.0, 3.0, start_jerk=15.0)
    assert np.all(ramped <= free + 1e-12) and ramped.max() == pytest.approx(2.0)
    speeding_up = np.diff(ramped[:20] ** 2) / (2 * np.diff(s[:20]))  # sddot over each step
    assert np.all(speeding_up <= np.cbrt(6.0 * s[1:20] * 15.0**2) + 1e-9)
    assert travel_times(s, ramped)[-1] > travel_times(s, free)[-1]

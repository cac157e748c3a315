"""make_trajectory: every method through real plans, collision-free, through every waypoint."""

from __future__ import annotations

import numpy as np
import pytest

from quadnav.errors import PlanningWarning, QuadnavError
from quadnav.planning import PlannerSettings, make_problem, plan
from quadnav.planning.refine import refine
from quadnav.trajectory.clearance.collision import first_collision
from quadnav.trajectory.clearance.space import SafeSpace, trajectory_margins
from quadnav.trajectory.generate import METHODS, TrajectorySettings, make_trajectory
from quadnav.trajectory.model import YawMode
from quadnav.trajectory.polynomials.minsnap import minimum_snap
from quadnav.trajectory.timing.segment_times import optimize_times, trapezoidal_times
from quadnav.world import load_world


def planned(spec: str, start=None, goal=None, margin: float = 0.2):
    world = load_world(spec)
    problem = make_problem(world, start, goal, margin)
    result = plan(problem, PlannerSettings(seed=0, max_iterations=20000, time_limit=60))
    return world, refine(problem, result).path


def contains_in_order(trajectory, points: np.ndarray) -> bool:
    """Every point is one of the trajectory's waypoints, in order."""
    rows = [np.flatnonzero(np.all(trajectory.waypoints == p, axis=1)) for p in points]
    return all(r.size for r in rows) and np.all(np.diff([r[0] for r in rows]) > 0)


@pytest.mark.parametrize("method", METHODS.names())
@pytest.mark.parametrize("spec", ["forest", "window", "maze"])
def test_every_method_is_free_and_passes_every_waypoint(spec, method):
    world, path = planned(spec)
    space = SafeSpace(world, 0.2)
    trajectory = make_trajectory(path, TrajectorySettings(method=method), space)
    assert first_collision(trajectory, space.inflated) is None
    assert trajectory_margins(trajectory, world) >= (0.199, None)
    assert contains_in_order(trajectory, path)
    assert np.allclose(trajectory.position(trajectory.breaks), trajectory.waypoints, atol=1e-8)
    assert np.allclose(trajectory.velocity([0.0, trajectory.duration]), 0.0, atol=1e-9)


def test_corridor_qp_stays_free_and_within_the_limits():
    world, path = planned("forest")
    space = SafeSpace(world, 0.2)
    settings = TrajectorySettings(corridor=True, v_max=1.0, a_max=1.5)
    trajectory = make_trajectory(path, settings, space)
    assert first_collision(trajectory, space.inflated) is None
    assert contains_in_order(trajectory, path)
    t = np.linspace(0, trajectory.duration, 4000)
    assert np.linalg.norm(trajectory.velocity(t), axis=1).max() <= 1.0 + 0.05


def test_optimised_times_trade_snap_for_time():
    _, path = planned("forest")
    weight = 1e-3
    start = trapezoidal_times(path, 1.0, 1.5)
    optimised = optimize_times(start, lambda t: minimum_snap(path, t).info["cost"], weight)

    def objective(times):
        return minimum_snap(path, times).info["cost"] + weight * times.sum()

    assert objective(optimised) < objective(start)
    settings = TrajectorySettings(timing="snap-time", time_weight=weight)
    trajectory = make_trajectory(path, settings)
    t = np.linspace(0, trajectory.duration, 20000)
    assert np.linalg.norm(trajectory.velocity(t), axis=1).max() <= settings.v_max


def test_travel_yaw_faces_the_velocity():
    _, path = planned("forest")
    trajectory = make_trajectory(path, TrajectorySettings(yaw=YawMode.TRAVEL))
    t = np.linspace(0.0, trajectory.duration, 500)
    v = trajectory.velocity(t)
    moving = np.hypot(v[:, 0], v[:, 1]) >= 0.05
    assert 0.5 < moving.mean() < 1
    assert np.allclose(trajectory.yaw(t)[moving], np.arctan2(v[moving, 1], v[moving, 0]))
    chord = trajectory.waypoints[1] - trajectory.waypoints[0]
    assert trajectory.yaw(0.0) == pytest.approx(np.arctan2(chord[1], chord[0]))


def test_only_the_leg_from_a_start_on_the_boundary_is_inside_the_margin(shared_maps):
    with pytest.warns(PlanningWarning, match=r"start \(0, -5, 0\) is inside the 0.2 m safety"):
        world, path = planned(str(shared_maps / "rbe595" / "map1.txt"), [0.0, -5.0, 0.0],
                              [8.0, 18.0, 3.0])
    space = SafeSpace(world, 0.2)
    assert space.split(path) == (1, len(path) - 1)
    trajectory = make_trajectory(path, TrajectorySettings(), space)
    assert np.array_equal(trajectory.position(0.0), [0.0, -5.0, 0.0])
    begin, end = trajectory.main_window
    legs = trajectory.leg_segments[0]  # the leg's segment, with waypoints added on it
    assert legs >= 1 and 0 < begin == trajectory.breaks[legs] and end == trajectory.duration
    # The leg is flown straight, from rest to rest, exactly along the path's first segment.
    t = np.linspace(0.0, begin, 200)
    along = trajectory.position(t) - path[0]
    direction = (path[1] - path[0]) / np.linalg.norm(path[1] - path[0])
    assert np.allclose(along - np.outer(along @ direction, direction), 0.0, atol=1e-12)
    progress = along @ direction  # forward only, never past the leg's end
    assert np.all(np.diff(progress) >= -1e-12)
    assert progress.max() <= np.linalg.norm(path[1] - path[0]) + 1e-12
    assert np.allclose(trajectory.velocity([0.0, begin]), 0.0, atol=1e-12)
    kept, on_leg = trajectory_margins(trajectory, world)
    assert kept >= 0.199 and on_leg == pytest.approx(0.0, abs=1e-12)


def test_bad_settings_and_paths_are_user_errors():
    world, path = planned("forest")
    with pytest.raises(QuadnavError, match="unknown trajectory method 'spline'"):
        TrajectorySettings(method="spline")
    with pytest.raises(QuadnavError, match="need method minsnap"):
        TrajectorySettings(method="cubic", corridor=True)
    with pytest.raises(QuadnavError, match=r"v_max: expected from 0\.005 to 100 m/s, got 0"):
        TrajectorySettings(v_max=0)
    with pytest.raises(QuadnavError, match=r"a_max: expected from 0\.005 to 1,000 m/s"):
        TrajectorySettings(a_max=1e-6)
    with pytest.raises(QuadnavError, match="at least 2 distinct waypoints"):
        make_trajectory([path[0], path[0]])
    through_trunk = np.array([world.start, world.blocks[0, :3] + 0.01, world.goal])
    with pytest.raises(QuadnavError, match=r"path segment 0 from .* touches a block"):
        make_trajectory(through_trunk, TrajectorySettings(), SafeSpace(world, 0.2))


@pytest.mark.parametrize("method", METHODS.names())
def test_the_result_keeps_within_the_speed_and_acceleration_limits(method):
    _, path = planned("maze")
    settings = TrajectorySettings(method=method, v_max=0.8, a_max=1.0)
    trajectory = make_trajectory(path, settings)
    t = np.linspace(0, trajectory.duration, 20000)
    assert np.linalg.norm(trajectory.velocity(t), axis=1).max() <= 0.8
    assert np.linalg.norm(trajectory.acceleration(t), axis=1).max() <= 1.0


def test_trajectory_times_follow_the_trapezoid():
    _, path = planned("window")
    trajectory = minimum_snap(path, trapezoidal_times(path, 1.0, 1.5))
    assert trajectory.duration == pytest.approx(trapezoidal_times(path, 1.0, 1.5).sum())

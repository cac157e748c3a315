"""Cubic spline, quintic segments, the minimum-jerk quintic, and segment time allocation."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.polynomial import Polynomial

from quadnav.errors import QuadnavError
from quadnav.planning import PlannerSettings, make_problem, plan
from quadnav.planning.refine import refine
from quadnav.trajectory.polynomials.cubic import cubic_spline
from quadnav.trajectory.polynomials.minsnap import minimum_derivative
from quadnav.trajectory.polynomials.quintic import quintic_c2, quintic_segments
from quadnav.trajectory.timing.segment_times import (
    DEFAULT_A_MAX,
    DEFAULT_V_MAX,
    optimize_times,
    segment_lengths,
    trapezoidal_times,
)
from quadnav.world import load_world


@pytest.fixture(scope="module")
def maze_path() -> np.ndarray:
    """A real planner path through the built-in maze: many waypoints, sharp turns."""
    problem = make_problem(load_world("maze"), None, None, 0.2)
    result = plan(problem, PlannerSettings(seed=0, max_iterations=20000, time_limit=60))
    path = refine(problem, result).path
    assert len(path) >= 10
    return path


def one_sided(trajectory, order: int) -> tuple[np.ndarray, np.ndarray]:
    """The ``order``-th derivative (N - 2, 3) at each interior waypoint, from the segment
    arriving (left limit) and from the segment leaving (right limit), from the coefficients."""
    poly = trajectory.poly.derivative(order) if order else trajectory.poly
    powers = trajectory.segment_times[:, None] ** np.arange(poly.c.shape[0])[::-1]
    ends = np.einsum("ksa,sk->sa", poly.c, powers)
    return ends[:-1], poly.c[-1, 1:]


def assert_continuous(trajectory, order: int, rtol: float = 1e-9) -> None:
    left, right = one_sided(trajectory, order)
    scale = max(1.0, np.abs(left).max())
    np.testing.assert_allclose(left, right, rtol=0, atol=rtol * scale)


# ------------------------------------------------------------------ cubic
def test_cubic_passes_waypoints_at_rest_and_is_c2(maze_path):
    times = trapezoidal_times(maze_path)
    trajectory = cubic_spline(maze_path, times)
    assert trajectory.method == "cubic"
    np.testing.assert_allclose(trajectory.segment_times, times, rtol=1e-12)
    np.testing.assert_allclose(trajectory.position(trajectory.breaks), maze_path, atol=1e-12)
    np.testing.assert_allclose(trajectory.velocity([0.0, trajectory.duration]), 0.0, atol=1e-12)
    for order in range(3):
        assert_continuous(trajectory, order)
    left, right = one_sided(trajectory, 3)
    assert np.abs(left - right).max() > 1e-3  # a cubic spline's jerk jumps


# ---------------------------------------------------------- quintic segments
def test_quintic_interior_velocity_follows_the_documented_rule():
    corner = quintic_segments([[0, 0, 0], [1, 0, 0], [1, 1, 0]], [1.0, 1.0], cruise_speed=0.5)
    np.testing.assert_allclose(corner.velocity(1.0), [0.25, 0.25, 0.0], atol=1e-12)
    # Straight on: the cruise speed 5 m/s is capped by the harmonic mean of the segments'
    # mean speeds 1 and 2 m/s, 4/3 m/s.
    straight = quintic_segments([[0, 0, 0], [1, 0, 0], [3, 0, 0]], [1.0, 1.0], cruise_speed=5)
    np.testing.assert_allclose(straight.velocity(1.0), [4 / 3, 0.0, 0.0], atol=1e-12)
    back = quintic_segments([[0, 0, 0], [0, 0, 2], [0, 0, 0]], [2.0, 2.0], cruise_speed=1)
    np.testing.assert_allclose(back.velocity(2.0), 0.0, atol=1e-12)
    assert straight.info == {"cruise_speed": 5.0}


def test_quintic_segments_end_conditions_and_c1(maze_path):
    times = trapezoidal_times(maze_path)
    trajectory = quintic_segments(maze_path, times, DEFAULT_V_MAX)
    assert trajectory.method == "quintic"
    b = trajectory.breaks
    np.testing.assert_allclose(trajectory.position(b), maze_path, atol=1e-12)
    np.testing.assert_allclose(trajectory.velocity(b[[0, -1]]), 0.0, atol=1e-12)
    np.testing.assert_allclose(trajectory.acceleration(b), 0.0, atol=1e-10)
    chords = np.diff(maze_path, axis=0)
    lengths = np.linalg.norm(chords, axis=1)
    units = chords / lengths[:, None]
    velocity = trajectory.velocity(b[1:-1])
    bisector = units[:-1] + units[1:]
    cross = np.cross(velocity, bisector)
    assert np.abs(cross).max() < 1e-12 and np.all(np.einsum("ia,ia->i", velocity, bisector) >= 0)
    cap = np.minimum(DEFAULT_V_MAX, 2 / (times[:-1] / lengths[:-1] + times[1:] / lengths[1:]))
    np.testing.assert_allclose(np.linalg.norm(velocity, axis=1),
                               cap * np.linalg.norm(bisector, axis=1) / 2, rtol=1e-12)
    for order in range(3):  # acceleration: zero on both sides
        assert_continuous(trajectory, order)
    np.testing.assert_allclose(one_sided(trajectory, 2), 0.0, atol=1e-10)


# ------------------------------------------------------------- minimum jerk
def test_quintic_c2_passes_waypoints_at_rest_and_is_c4(maze_path):
    times = trapezoidal_times(maze_path)
    trajectory = quintic_c2(maze_path, times)
    assert trajectory.method == "quintic-c2"
    np.testing.assert_allclose(trajectory.position(trajectory.breaks), maze_path, atol=1e-12)
    ends = [0.0, trajectory.duration]
    np.testing.assert_allclose(trajectory.velocity(ends), 0.0, atol=1e-12)
    np.testing.assert_allclose(trajectory.acceleration(ends), 0.0, atol=1e-11)
    for order in range(5):  # position ... snap
        assert_continuous(trajectory, order, rtol=1e-8)


def test_quintic_c2_is_the_minimum_jerk_spline(maze_path):
    times = trapezoidal_times(maze_path, scale=0.7)
    ours = quintic_c2(maze_path, times)
    reference = minimum_derivative(maze_path, times, derivative=3)
    t = np.linspace(0.0, ours.duration, 3001)
    for order in range(4):
        np.testing.assert_allclose(ours.derivative(t, order), reference.derivative(t, order),
                                   atol=1e-8)


def test_one_segment_quintics_are_the_rest_to_rest_quintic():
    points = [[0.0, 0.0, 1.0], [2.0, -1.0, 2.0]]
    c1, c2 = quintic_segments(points, [2.0], 1.0), quintic_c2(points, [2.0])
    np.testing.assert_allclose(c1.poly.c, c2.poly.c, atol=1e-12)
    # s(tau) = 10 tau^3 - 15 tau^4 + 6 tau^5: peak speed 1.875 L / T at the middle.
    speed = np.linalg.norm(c2.velocity(1.0))
    assert speed == pytest.approx(1.875 * np.sqrt(6.0) / 2.0, rel=1e-12)


# ------------------------------------------------------------------ timing
def test_trapezoidal_times_by_hand():
    # v = 1 m/s, a = 1.5 m/s^2: the cruise speed is reached on segments of 2/3 m or more.
    points = [[0, 0, 0], [3, 0, 0], [3, 0.375, 0], [3, 0.375, 1 / 1.5]]
    times = trapezoidal_times(points, v_max=1.0, a_max=1.5)
    np.testing.assert_allclose(times, [3 + 1 / 1.5, 2 * np.sqrt(0.375 / 1.5), 2 / 1.5],
                               rtol=1e-12)
    np.testing.assert_allclose(trapezoidal_times(points, 1.0, 1.5, scale=2.0), 2 * times)
    assert (DEFAULT_V_MAX, DEFAULT_A_MAX) == (2.0, 3.0)  # fly, traj and the library alike
    np.testing.assert_allclose(segment_lengths(points), [3, 0.375, 1 / 1.5])


def snap_cost(lengths: np.ndarray):
    """The snap cost of rest-to-rest minimum-snap segments of ``lengths`` m, summed:
    ``K L^2 / T^7`` each (K = 100800), with ``s(tau) = 35 tau^4 - 84 tau^5 + 70 tau^6 -
    20 tau^7`` the rest-to-rest minimum-snap profile."""
    s = Polynomial([0, 0, 0, 0, 35, -84, 70, -20])
    k = (s.deriv(4) ** 2).integ()(1.0)
    return k, lambda times: float(np.sum(k * lengths**2 / times**7))


def test_optimize_times_reaches_the_analytic_optimum():
    lengths = np.array([1.0, 2.0, 0.5, 4.0])
    k, cost = snap_cost(lengths)
    weight = 10.0
    optimum = (7 * k * lengths**2 / weight) ** (1 / 8)  # d/dT (k L^2 T^-7 + w T) = 0
    points = np.zeros((len(lengths) + 1, 3))
    points[1:, 0] = np.cumsum(lengths)
    start = trapezoidal_times(points)
    times = optimize_times(start, cost, weight)
    np.testing.assert_allclose(times, optimum, rtol=1e-4)
    np.testing.assert_array_equal(optimize_times(start, cost, weight), times)  # deterministic


def test_optimize_times_keeps_the_minimum_time():
    lengths = np.array([1.0, 1.0])
    k, cost = snap_cost(lengths)
    weight = 1e18
    assert (7 * k / weight) ** (1 / 8) < 0.05
    times = optimize_times([1.0, 0.01], cost, weight, min_time=0.05)
    np.testing.assert_allclose(times, 0.05, rtol=1e-9)


# -------------------------------------------------------------- bad inputs
GOOD = np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0]])
BAD_CALLS = [
    (lambda: cubic_spline(GOOD[:1], []), "N >= 2"),
    (lambda: cubic_spline(GOOD[:, :2], [1, 1]), "shape"),
    (lambda: cubic_spline([[0, 0, 0], [np.nan, 0, 0]], [1]), "waypoint 1"),
    (lambda: cubic_spline(GOOD, [1.0]), "times must have shape"),
    (lambda: cubic_spline(GOOD, [1.0, 0.0]), "segment time 1"),
    (lambda: cubic_spline(GOOD, [1.0, np.inf]), "segment time 1"),
    (lambda: cubic_spline(GOOD[[0, 1, 1, 2]], [1, 1, 1]), "waypoints 1 and 2 are the same"),
    (lambda: quintic_segments(GOOD, [1, 1], 0.0), "cruise speed"),
    (lambda: quintic_segments(GOOD, [1, -1], 1.0), "segment time 1"),
    (lambda: quintic_c2(GOOD[[0, 0, 1]], [1, 1]), "waypoints 0 and 1 are the same"),
    (lambda: trapezoidal_times(GOOD, v_max=0.0), "v_max"),
    (lambda: trapezoidal_times(GOOD, a_max=-1.0), "a_max"),
    (lambda: trapezoidal_times(GOOD, scale=np.nan), "time scale"),
    (lambda: trapezoidal_times(GOOD[[0, 1, 1]]), "same point"),
    (lambda: optimize_times([1.0, -1.0], sum, 1.0), "starting times"),
    (lambda: optimize_times([], sum, 1.0), "starting times"),
    (lambda: optimize_times([1.0], sum, 0.0), "time weight"),
    (lambda: optimize_times([1.0], sum, 1.0, min_time=0.0), "minimum segment time"),
    (lambda: optimize_times([1.0], lambda t: np.nan, 1.0), "cost of the starting times"),
]


@pytest.mark.parametrize(("call", "message"), BAD_CALLS)
def test_bad_input_is_a_one_line_quadnav_error(call, message):
    with pytest.raises(QuadnavError, match=message) as error:
        call()
    assert "\n" not in str(error.value)

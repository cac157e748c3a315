"""Minimum-snap and minimum-jerk trajectories: closed form, exact cost, and the Clarabel QP
with corridors and limits, on seeded random walks and a real plan through the forest."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import simpson

from quadnav.errors import QuadnavError
from quadnav.planning import PlannerSettings, make_problem, plan
from quadnav.planning.refine import refine
from quadnav.trajectory import Trajectory, ppoly_from_ascending
from quadnav.trajectory.polynomials.minsnap import minimum_derivative, minimum_snap, snap_cost
from quadnav.trajectory.polynomials.minsnap_qp import minimum_snap_qp
from quadnav.world import load_world


def walk(count: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """A seeded random 3D walk of ``count`` waypoints and its times at 1 m/s."""
    waypoints = np.cumsum(np.random.default_rng(seed).normal(scale=2.0, size=(count, 3)), axis=0)
    return waypoints, np.linalg.norm(np.diff(waypoints, axis=0), axis=1)


@pytest.fixture(scope="module")
def forest_path() -> tuple[np.ndarray, np.ndarray]:
    """A refined RRT* path through the built-in forest and its times at 1 m/s."""
    world = load_world("forest")
    problem = make_problem(world, None, None, 0.2)
    result = plan(problem, PlannerSettings(seed=0, max_iterations=20000, time_limit=60))
    path = refine(problem, result).path
    return path, np.linalg.norm(np.diff(path, axis=0), axis=1)


@pytest.fixture(params=["walk", "forest"])
def case(request) -> tuple[np.ndarray, np.ndarray]:
    """Waypoints and segment times: a 12-point random walk, or the forest plan."""
    return walk(12, seed=7) if request.param == "walk" else request.getfixturevalue("forest_path")


def jumps(trajectory: Trajectory, order: int) -> np.ndarray:
    """(interior waypoints, 3) right minus left limit of the ``order``-th derivative,
    each side evaluated on its own segment's polynomial, divided by the largest value of
    that derivative at the segment starts."""
    ascending = trajectory.poly.derivative(order).c[::-1]  # (degree + 1, segments, 3)
    times = trajectory.segment_times[:-1]
    left = np.einsum("kia,ik->ia", ascending[:, :-1], times[:, None] ** np.arange(len(ascending)))
    right = ascending[0, 1:]
    return (right - left) / max(np.abs(ascending[0]).max(), 1.0)


def sample_times(trajectory: Trajectory, per_segment: int, start: int = 1) -> np.ndarray:
    """Times ``t_i + T_i * k / per_segment`` for ``k = start..per_segment``, every segment."""
    tau = np.arange(start, per_segment + 1) / per_segment
    return (trajectory.breaks[:-1, None] + trajectory.segment_times[:, None] * tau).ravel()


def box_excess(trajectory: Trajectory, boxes: np.ndarray, per_segment: int) -> float:
    """Largest distance, m, by which any sample of segment ``i`` leaves ``boxes[i]``."""
    positions = trajectory.position(sample_times(trajectory, per_segment, start=0))
    positions = positions.reshape(len(boxes), per_segment + 1, 3)
    return float(max(np.max(boxes[:, None, :3] - positions),
                     np.max(positions - boxes[:, None, 3:])))


def grown_boxes(waypoints: np.ndarray, margin: float) -> np.ndarray:
    """(segments, 6) bounding box of each segment grown by ``margin`` m."""
    return np.hstack([np.minimum(waypoints[:-1], waypoints[1:]) - margin,
                      np.maximum(waypoints[:-1], waypoints[1:]) + margin])


# ------------------------------------------------------------------ closed form
def test_minimum_snap_passes_the_waypoints_rests_at_both_ends_and_is_c6(case):
    waypoints, times = case
    trajectory = minimum_snap(waypoints, times)

    assert trajectory.method == "minsnap"
    assert np.allclose(trajectory.segment_times, times, rtol=1e-12)
    assert np.abs(trajectory.position(trajectory.breaks) - waypoints).max() < 1e-9
    for order in (1, 2, 3):
        assert np.abs(trajectory.derivative([0.0, trajectory.duration], order)).max() < 1e-9
    for order in range(7):  # continuity 1..4 imposed, 5 and 6 from optimality
        assert np.abs(jumps(trajectory, order)).max() < 1e-8, order
    assert np.abs(jumps(trajectory, 7)).max() > 1e-3  # a 7th-order spline, not a polynomial


def test_minimum_jerk_is_c4_passes_the_waypoints_and_beats_minimum_snap_on_jerk(case):
    waypoints, times = case
    trajectory = minimum_derivative(waypoints, times, derivative=3)

    assert trajectory.method == "minjerk"
    assert trajectory.poly.c.shape[0] == 6  # quintic segments
    assert np.abs(trajectory.position(trajectory.breaks) - waypoints).max() < 1e-9
    for order in (1, 2):
        assert np.abs(trajectory.derivative([0.0, trajectory.duration], order)).max() < 1e-9
    for order in range(5):  # continuity 1..3 imposed, 4 from optimality
        assert np.abs(jumps(trajectory, order)).max() < 1e-8, order
    # The minimum-snap trajectory is feasible for the minimum-jerk problem, so it can only
    # have more jerk.
    assert trajectory.info["cost"] < snap_cost(minimum_snap(waypoints, times), derivative=3)
    assert trajectory.info["cost"] == pytest.approx(snap_cost(trajectory, 3), rel=1e-9)


def test_optimal_cost_is_the_exact_integral_and_agrees_with_quadrature(case):
    waypoints, times = case
    trajectory = minimum_snap(waypoints, times)
    t = np.concatenate([np.linspace(a, b, 2001) for a, b in
                        zip(trajectory.breaks[:-1], trajectory.breaks[1:], strict=True)])
    squared = np.sum(trajectory.snap(t) ** 2, axis=1).reshape(len(times), 2001)
    quadrature = sum(simpson(row, x=t[i * 2001:(i + 1) * 2001]) for i, row in enumerate(squared))

    assert trajectory.info["cost"] > 0
    assert trajectory.info["cost"] == pytest.approx(snap_cost(trajectory), rel=1e-9)
    assert trajectory.info["cost"] == pytest.approx(quadrature, rel=1e-8)


def test_snap_cost_of_known_polynomials():
    # x = t^5 for 2 s (snap 120 t, integral 14400 * 2^3 / 3), then y = 3 t for 1 s.
    coefficients = np.zeros((2, 6, 3))
    coefficients[0, 5, 0] = 1.0
    coefficients[1, 0, 0] = 32.0
    coefficients[1, 1, 1] = 3.0
    trajectory = Trajectory(ppoly_from_ascending(coefficients, [0.0, 2.0, 3.0]),
                            [[0, 0, 0], [32, 0, 0], [32, 3, 0]], "test")

    assert snap_cost(trajectory) == pytest.approx(38400.0, rel=1e-12)
    assert snap_cost(trajectory, derivative=1) == pytest.approx(25 * 2**9 / 9 + 9.0, rel=1e-12)
    assert snap_cost(trajectory, derivative=6) == 0.0


def test_a_single_segment_is_the_unique_rest_to_rest_polynomial():
    trajectory = minimum_snap([[0, 0, 0], [1, 2, 3]], [2.0])
    # Rest to rest in T: x(t) = d * s(t/T), s(u) = 35u^4 - 84u^5 + 70u^6 - 20u^7.
    u = np.linspace(0, 1, 11)
    expected = np.outer(35 * u**4 - 84 * u**5 + 70 * u**6 - 20 * u**7, [1, 2, 3])
    assert np.allclose(trajectory.position(2.0 * u), expected, atol=1e-12)


# ------------------------------------------------------------------ QP
def test_qp_without_inequalities_is_the_closed_form(case):
    waypoints, times = case
    closed = minimum_snap(waypoints, times)
    far = np.concatenate([waypoints.min(axis=0) - 100, waypoints.max(axis=0) + 100])
    for qp in (minimum_snap_qp(waypoints, times), minimum_snap_qp(waypoints, times, boundary=far)):
        assert abs(qp.info["cost"] - closed.info["cost"]) < 1e-6 * closed.info["cost"]
        assert np.abs(qp.position(sample_times(closed, 50)) - closed.position(
            sample_times(closed, 50))).max() < 1e-5
        assert qp.method == "minsnap"
        assert qp.info["solver"] == "clarabel" and qp.info["status"] == "Solved"
        assert isinstance(qp.info["iterations"], int) and qp.info["solve_time"] >= 0


def test_qp_keeps_each_segment_in_its_corridor_where_the_closed_form_leaves_it():
    waypoints, times = walk(10, seed=3)
    corridors = grown_boxes(waypoints, 0.3)
    closed = minimum_snap(waypoints, times)
    assert box_excess(closed, corridors, 200) > 1.0

    qp = minimum_snap_qp(waypoints, times, corridors=corridors, samples_per_segment=20)

    assert box_excess(qp, corridors, 20) < 1e-6  # at the constrained samples
    assert box_excess(qp, corridors, 200) < 0.01  # between them, mm-scale excursions
    assert qp.info["cost"] > closed.info["cost"]
    assert qp.info["cost"] == pytest.approx(snap_cost(qp), rel=1e-9)
    assert np.abs(qp.position(qp.breaks) - waypoints).max() < 1e-9
    assert np.abs(qp.derivative([0.0, qp.duration], 1)).max() < 1e-9
    for order in range(5):
        assert np.abs(jumps(qp, order)).max() < 1e-7, order


def test_qp_keeps_every_segment_inside_a_boundary_box():
    waypoints, times = walk(10, seed=5)
    boundary = np.concatenate([waypoints.min(axis=0) - 0.2, waypoints.max(axis=0) + 0.2])
    boxes = np.tile(boundary, (len(times), 1))
    closed = minimum_snap(waypoints, times)
    assert box_excess(closed, boxes, 200) > 1.0

    qp = minimum_snap_qp(waypoints, times, boundary=boundary, samples_per_segment=30)

    assert box_excess(qp, boxes, 30) < 1e-6
    assert box_excess(qp, boxes, 200) < 0.01
    assert qp.info["cost"] > closed.info["cost"]


def test_qp_respects_velocity_and_acceleration_limits_at_the_samples():
    waypoints, times = walk(12, seed=7)
    closed = minimum_snap(waypoints, times)
    t = sample_times(closed, 20)
    # 90 % of the closed form's largest per-axis speed and acceleration, as norm limits.
    v_max = 0.9 * np.sqrt(3) * np.abs(closed.velocity(t)).max()
    a_max = 0.9 * np.sqrt(3) * np.abs(closed.acceleration(t)).max()

    qp = minimum_snap_qp(waypoints, times, v_max=v_max, a_max=a_max)

    assert np.abs(qp.velocity(t)).max() <= v_max / np.sqrt(3) * (1 + 1e-6)
    assert np.abs(qp.acceleration(t)).max() <= a_max / np.sqrt(3) * (1 + 1e-6)
    assert np.linalg.norm(qp.velocity(t), axis=1).max() <= v_max * (1 + 1e-6)
    assert qp.info["inequalities"] == 2 * 2 * 20 * len(times)


def test_limits_too_tight_for_the_times_raise_a_clear_error():
    waypoints, times = walk(6, seed=1)
    with pytest.raises(QuadnavError, match=r"not solved on the [xyz] axis .*allow more time"):
        minimum_snap_qp(waypoints, times, v_max=0.2)


@pytest.mark.parametrize(("waypoints", "times", "message"), [
    ([[0, 0, 0]], [], r"N >= 2"),
    ([[0, 0], [1, 1]], [1.0], r"shape \(N, 3\)"),
    ([[0, 0, 0], [1, 1, 1]], [0.0], r"segment time 0 is 0.0 s"),
    ([[0, 0, 0], [1, 1, 1], [2, 2, 2]], [1.0, -1.0], r"segment time 1 is -1.0 s"),
    ([[0, 0, 0], [1, 1, 1], [2, 2, 2]], [1.0], r"times must have shape \(2,\)"),
    ([[0, 0, 0], [1, np.nan, 1]], [1.0], r"waypoint 1 is \[1.0, nan, 1.0\]"),
    ([[0, 0, 0], [1, 1, 1]], [np.inf], r"segment time 0 is inf s"),
    ([[0, 0, 0], ["a", 1, 1]], [1.0], r"must be numbers"),
])
def test_bad_waypoints_or_times_raise(waypoints, times, message):
    for solve in (minimum_snap, minimum_snap_qp):
        with pytest.raises(QuadnavError, match=message):
            solve(waypoints, times)


@pytest.mark.parametrize(("options", "message"), [
    ({"corridors": [[0, 0, 0, 2, 2, 2]] * 2}, r"corridors must have shape \(1, 6\)"),
    ({"corridors": [[0, 0, 0, 0.5, 2, 2]]}, r"waypoint 1 \[1.0, 1.0, 1.0\] is outside the box"),
    ({"corridors": [[0, 0, 0, -1, 2, 2]]}, r"every min below its max"),
    ({"boundary": [0.5, 0, 0, 2, 2, 2]}, r"waypoint 0 .* outside the box of segment 0"),
    ({"boundary": [0, 0, 0, 2, 2]}, r"boundary must have shape \(6,\)"),
    ({"v_max": -1.0}, r"v_max is -1.0; expected a finite number > 0"),
    ({"a_max": float("nan")}, r"a_max is nan"),
    ({"samples_per_segment": 0}, r"samples_per_segment is 0"),
    ({"samples_per_segment": 2.5}, r"samples_per_segment is 2.5"),
])
def test_bad_qp_options_raise(options, message):
    with pytest.raises(QuadnavError, match=message):
        minimum_snap_qp([[0, 0, 0], [1, 1, 1]], [1.0], **options)


def test_unsupported_derivative_raises():
    with pytest.raises(QuadnavError, match="derivative must be one of"):
        minimum_derivative([[0, 0, 0], [1, 1, 1]], [1.0], derivative=2)

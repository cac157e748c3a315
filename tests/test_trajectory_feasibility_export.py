"""Feasibility reports on trajectories of known peaks, and the CSV and MP.csv exports."""

from __future__ import annotations

import io
import json
import math

import numpy as np
import pytest

from quadnav.errors import QuadnavError
from quadnav.trajectory.feasibility import GRAVITY, Limits, feasibility, quantities
from quadnav.trajectory.model import YawMode
from quadnav.trajectory.polynomials.cubic import cubic_spline
from quadnav.trajectory.polynomials.quintic import quintic_c2
from quadnav.trajectory.references.contract import samples_at
from quadnav.trajectory.references.export import CSV_HEADER, mp_csv, trajectory_csv
from quadnav.trajectory.timing.segment_times import trapezoidal_times
from quadnav.world import World, load_world

#: A rest-to-rest quintic of L = 2 m in T = 2.5 s along x: s(tau) = 10 tau^3 - 15 tau^4 +
#: 6 tau^5 gives the peak speed 1.875 L/T at the middle, the peak acceleration
#: (10 / sqrt(3)) L/T^2 at tau = 1/2 -+ sqrt(3)/6, and the peak jerk 60 L/T^3 at both ends.
LENGTH, DURATION = 2.0, 2.5
V_PEAK = 1.875 * LENGTH / DURATION
A_PEAK = 10 / math.sqrt(3) * LENGTH / DURATION**2
A_PEAK_TIME = (0.5 - math.sqrt(3) / 6) * DURATION
J_PEAK = 60 * LENGTH / DURATION**3


def straight(direction=(1.0, 0.0, 0.0)):
    return quintic_c2([[0.0, 0.0, 0.0], np.multiply(LENGTH, direction)], [DURATION])


def test_known_peaks_of_a_straight_quintic():
    report = feasibility(straight(), None, Limits(), dt=0.01)
    assert report.ok and report.violations == ()
    assert report.max_speed.value == pytest.approx(V_PEAK, rel=1e-12)
    assert report.max_speed.t == pytest.approx(DURATION / 2)
    assert report.max_acceleration.value == pytest.approx(A_PEAK, rel=1e-3)
    assert min(abs(report.max_acceleration.t - A_PEAK_TIME),
               abs(report.max_acceleration.t - (DURATION - A_PEAK_TIME))) < 0.01
    assert report.max_jerk.value == pytest.approx(J_PEAK, rel=1e-12)
    assert report.max_jerk.t in (0.0, DURATION)
    assert report.max_thrust_to_weight.value == pytest.approx(
        math.hypot(A_PEAK, GRAVITY) / GRAVITY, rel=1e-4)
    assert report.max_tilt.value == pytest.approx(math.atan2(A_PEAK, GRAVITY), rel=1e-3)
    assert report.min_clearance is None
    assert report.duration == DURATION


def test_climbing_needs_thrust_but_no_tilt():
    report = feasibility(straight((0.0, 0.0, 1.0)), None, Limits())
    assert report.max_thrust_to_weight.value == pytest.approx(1 + A_PEAK / GRAVITY, rel=1e-4)
    assert report.max_tilt.value == pytest.approx(0.0, abs=1e-12)


def test_exceeded_limits_are_named_with_value_limit_and_time():
    limits = Limits(v_max=1.2, jerk_max=5.0, tilt_max=math.radians(10))
    report = feasibility(straight(), None, limits)
    assert not report.ok
    assert report.violations[0] == "speed 1.5 m/s exceeds the limit 1.2 m/s at t = 1.25 s"
    assert report.violations[1] in ("jerk 7.68 m/s^3 exceeds the limit 5 m/s^3 at t = 0.00 s",
                                    "jerk 7.68 m/s^3 exceeds the limit 5 m/s^3 at t = 2.50 s")
    assert report.violations[2].startswith("tilt 10.7 deg exceeds the limit 10 deg at t = ")
    assert len(report.violations) == 3
    summary = report.summary()
    assert summary.startswith("NOT feasible: 3 violations")
    assert "max tilt 10.7 deg" in summary and "(limit 10 deg)" in summary
    assert "max acceleration 1.85 m/s^2" in summary and "(limit 4 m/s^2)" in summary


def test_the_roll_pitch_acceleration_is_the_thrust_directions_turn_differentiated():
    # The closed form against finite differences of b x b', b the thrust direction
    # (acceleration + gravity + drag), on a curve through a waypoint, away from it (where
    # a C2 quintic's jerk may jump).
    trajectory = quintic_c2([[0.0, 0.0, 1.0], [2.0, 1.0, 1.5], [3.0, -1.0, 1.0]], [1.5, 1.5])
    limits = Limits(drag=(0.5, 0.5, 0.7))
    drag = np.array(limits.drag)

    def direction(t):
        thrust = (trajectory.acceleration(t) + [0.0, 0.0, GRAVITY]
                  + drag * trajectory.velocity(t))
        return thrust / np.linalg.norm(thrust, axis=1)[:, None]

    def turn(t, h=1e-4):
        return np.cross(direction(t), (direction(t + h) - direction(t - h)) / (2 * h))

    t = np.concatenate([np.linspace(0.2, 1.3, 12), np.linspace(1.7, 2.8, 12)])
    h = 1e-3
    measured = np.linalg.norm((turn(t + h) - turn(t - h)) / (2 * h), axis=1)
    series = quantities(*(trajectory.derivative(t, order) for order in (1, 2, 3, 4)), limits)
    assert np.allclose(series["max_angular_acceleration"], measured, rtol=1e-5, atol=1e-6)
    assert np.allclose(series["max_body_rate"], np.linalg.norm(turn(t), axis=1), rtol=1e-6)
    assert measured.max() > 1.0  # the curve does turn the body


def test_a_roll_pitch_acceleration_beyond_the_limit_is_named():
    limits = Limits(angular_acceleration_max=0.5)
    report = feasibility(quintic_c2([[0.0, 0.0, 1.0], [2.0, 0.0, 1.0], [2.0, 2.0, 1.0]],
                                    [2.0, 2.0]), None, limits)
    assert not report.ok
    peak = report.max_angular_acceleration
    assert report.violations == (
        f"roll/pitch acceleration {peak.value:.3g} rad/s^2 exceeds the limit 0.5 rad/s^2 at "
        f"t = {peak.t:.2f} s",)
    assert report.as_dict()["max_angular_acceleration"] == peak.as_dict()
    assert "max roll/pitch acceleration" in report.summary()


def test_clearance_in_a_world_and_a_collision():
    boundary = [-1.0, -1.0, -1.0, 3.0, 1.0, 1.0]
    beside = World(boundary, blocks=[[0.9, 0.3, -1.0, 1.1, 1.0, 1.0]], name="beside")
    report = feasibility(straight(), beside, Limits())
    assert report.ok
    assert report.min_clearance.value == pytest.approx(0.3, abs=1e-12)
    x = straight().position(report.min_clearance.t)[0]
    assert 0.9 <= x <= 1.1
    across = World(boundary, blocks=[[0.9, -0.1, -0.1, 1.1, 0.1, 0.1]], name="across")
    report = feasibility(straight(), across, Limits())
    assert report.min_clearance.value == pytest.approx(-0.1, abs=1e-12)
    assert not report.ok
    assert report.violations == (
        f"clearance -0.1 m is not above 0 m at t = {report.min_clearance.t:.2f} s: the "
        "trajectory touches or enters an obstacle of across",)


def test_report_on_a_window_world_path_is_json_ready_and_bounds_dense_samples():
    world = load_world("window")
    path = np.array([world.start, [5.0, 9.5, 3.0], world.goal])
    trajectory = cubic_spline(path, trapezoidal_times(path))
    report = feasibility(trajectory, world.inflate(0.2), Limits(), dt=0.05)
    data = json.loads(json.dumps(report.as_dict()))
    assert data["ok"] == report.ok and data["world"] == world.name
    assert data["limits"]["tilt_max"] == pytest.approx(math.radians(35))
    assert set(data) >= {"max_speed", "max_acceleration", "max_jerk", "max_thrust_to_weight",
                         "max_tilt", "min_clearance", "violations", "dt", "duration"}
    dense = np.linspace(0.0, trajectory.duration, 20001)
    speed = np.linalg.norm(trajectory.velocity(dense), axis=1)
    assert report.max_speed.value <= speed.max() <= report.max_speed.value * 1.001
    acceleration = np.linalg.norm(trajectory.acceleration(dense), axis=1)
    # a cubic's acceleration peaks at a waypoint, which is always sampled
    assert report.max_acceleration.value == pytest.approx(acceleration.max(), rel=1e-6)


# ------------------------------------------------------------------ export
@pytest.mark.parametrize("dt", [0.01, 0.03])
def test_csv_parses_back_to_the_samples(dt):
    path = np.array([[0.0, 0.0, 1.0], [1.0, 2.0, 1.5], [3.0, 2.0, 1.0]])
    trajectory = quintic_c2(path, trapezoidal_times(path)).replace(yaw_mode=YawMode.TRAVEL)
    samples = trajectory.sample(dt)
    text = trajectory_csv(trajectory, dt)
    assert text.splitlines()[0] == CSV_HEADER == "t,x,y,z,vx,vy,vz,ax,ay,az,yaw"
    table = np.loadtxt(io.StringIO(text), delimiter=",", skiprows=1)
    assert table.shape == (len(samples.t), 11)
    expected = np.column_stack([samples.t, samples.position, samples.velocity,
                                samples.acceleration, samples.yaw])
    np.testing.assert_allclose(table, expected, rtol=1e-8, atol=1e-12)
    assert table[-1, 0] == pytest.approx(trajectory.duration, rel=1e-9)

    # MP.csv has no times: its columns are exactly k dt apart, the last at or after the end.
    mp = np.loadtxt(io.StringIO(mp_csv(trajectory, dt)), delimiter=",")
    grid = np.arange(mp.shape[1]) * dt
    assert grid[-2] < trajectory.duration <= grid[-1]
    at_grid = samples_at(trajectory, grid)
    np.testing.assert_allclose(mp, np.vstack([at_grid.position.T, at_grid.velocity.T,
                                              at_grid.acceleration.T]), rtol=1e-8, atol=1e-12)
    np.testing.assert_allclose(mp[:3, -1], path[-1], rtol=1e-9)
    np.testing.assert_allclose(mp[3:, -1], 0.0, atol=1e-12)


# -------------------------------------------------------------- bad inputs
@pytest.mark.parametrize(("call", "message"), [
    (lambda: feasibility(straight(), None, Limits(), dt=0.0), "dt"),
    (lambda: trajectory_csv(straight(), -0.1), "dt"),
    (lambda: mp_csv(straight(), math.nan), "dt"),
    (lambda: Limits(v_max=-1.0), "v_max"),
    (lambda: Limits(jerk_max=0.0), "jerk_max"),
    (lambda: Limits(tilt_max=4.0), "tilt_max"),
    (lambda: Limits(thrust_to_weight_max=math.inf), "thrust_to_weight_max"),
])
def test_bad_input_is_a_one_line_quadnav_error(call, message):
    with pytest.raises(QuadnavError, match=message) as error:
        call()
    assert "\n" not in str(error.value)

"""The tracking library the gain tuner calls: the step response measures on a known
response, the world a reference is flown in, and track_reference on any Reference."""

from __future__ import annotations

import json

import numpy as np
import pytest

from quadnav.control.gains import PID, Gains
from quadnav.sim.settings import SimSettings
from quadnav.sim.step_response import step_response
from quadnav.tracking import track_reference, track_world
from quadnav.trajectory.generate import make_trajectory
from quadnav.trajectory.references.builtin import build_reference
from quadnav.vehicle.params import load_params


def test_step_response_measures_a_known_second_order_response():
    # x(t) = 1 - exp(-z w t) (cos(wd t) + z w / wd sin(wd t)) after a step at 1 s, along -y.
    zeta, omega = 0.5, 4.0
    damped = omega * np.sqrt(1 - zeta**2)
    t = np.arange(0.0, 9.0, 1e-4)
    s = np.clip(t - 1.0, 0.0, None)
    y = 1 - np.exp(-zeta * omega * s) * (np.cos(damped * s)
                                         + zeta * omega / damped * np.sin(damped * s))
    start, target = np.array([2.0, 1.0, 1.0]), np.array([2.0, -1.0, 1.0])
    position = start + np.outer(y, target - start)
    response = step_response(t, position, start, target, at=1.0)
    assert response.overshoot == pytest.approx(np.exp(-np.pi * zeta / np.sqrt(1 - zeta**2)),
                                               abs=1e-6)  # 16.3 %
    # The last time outside the 2 % band, from the envelope's extremes: within a peak spacing.
    assert 1.5 < response.settling_time < 2.2
    assert response.rise_time == pytest.approx(0.41, abs=0.02)
    assert response.steady_state_error < 1e-6
    # Still outside the band at the end: not settled.
    assert step_response(t[:20000], position[:20000], start, target, 1.0).settling_time is None
    with pytest.raises(ValueError, match="no sample at or after the step"):
        step_response(t[:100], position[:100], start, target, 1.0)


def test_the_world_is_the_bounding_box_widened_with_a_floor_when_high_enough():
    world = track_world(build_reference("circle:radius=2,height=1"))
    assert np.allclose(world.boundary, [-3, -1, 0, 3, 5, 2], atol=1e-3)
    assert np.allclose(world.start, [0, 0, 1]) and np.allclose(world.goal, [0, 0, 1], atol=1e-9)
    low = track_world(build_reference("step:axis=z,size=-0.9,height=1"))
    assert np.allclose(low.boundary, [-1, -1, -0.9, 1, 1, 2])  # below 0.3 m: no floor at 0
    assert np.allclose(low.goal, [0, 0, 0.1])


def test_any_reference_flies_and_its_metrics_and_parameters_are_json():
    path = np.array([[0.0, 0.0, 1.0], [1.5, 0.5, 1.2]])
    tracking = track_reference(make_trajectory(path), settings=SimSettings(settle_time=0.5))
    metrics = tracking.metrics()
    assert metrics["reference"] == "minsnap trajectory" and metrics["success"]
    assert metrics["rms_tracking_error_m"] < 0.05 and "overshoot_percent" not in metrics
    parameters = json.loads(json.dumps(tracking.parameters()))
    assert parameters["simulation"]["settle_time"] == 0.5
    assert parameters["vehicle"]["name"] == "tello"


def test_a_step_is_recorded_at_the_control_rate_and_bad_gains_fail():
    step = build_reference("step:size=0.5,at=0.5,duration=3")
    settings = SimSettings(control_rate=500.0, physics_rate=1000.0, settle_time=0.5)
    good = track_reference(step, settings=settings)
    assert good.settings.record_rate == 500.0 and np.allclose(np.diff(good.flight.t), 0.002)
    assert good.success and good.step_metrics()["settling_time_s"] < 2.0
    # A velocity loop with no gain never moves the vehicle to the step's target: a failure.
    bad = track_reference(step, load_params("tello"), Gains().replace(velocity=PID()), settings)
    metrics = bad.metrics()
    assert not bad.success and not metrics["success"]
    assert metrics["final_error_m"] > settings.goal_tolerance
    assert metrics["rise_time_s"] is None and metrics["settling_time_s"] is None

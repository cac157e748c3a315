"""The quadrotor plan's controls flown open loop through the full 6-DOF dynamics: hover,
sign conventions against the point mass, the inner loops' delays, the stated tolerance
on real plans, and what ``quadnav kino quadrotor`` reports."""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np
import pytest

from quadnav.cli.kino_command import replay_6dof_summary
from quadnav.errors import QuadnavError
from quadnav.kinodynamic import KinoResult, KinoSettings
from quadnav.kinodynamic.pointmass import SampledQuadrotor
from quadnav.kinodynamic.quadrotor import plan_quadrotor, replay
from quadnav.sim.replay6dof import (
    DRIFT_RATE,
    replay_6dof,
    replay_6dof_tolerance,
    replay_vehicle,
    response_delays,
)
from quadnav.vehicle.params import load_params
from quadnav.world import load_world

MODEL = SampledQuadrotor()
VEHICLE = replay_vehicle()
# The problems of test_kino_quadrotor.py, with its iteration-bounded budget.
SETTINGS = KinoSettings(max_iterations=4000, time_limit=60.0)
MAP1_START, MAP1_GOAL = (0.5, -4.5, 0.5), (8.0, 18.0, 3.0)


@functools.cache
def _plans(shared_maps: Path | None) -> tuple[tuple[str, KinoResult], ...]:
    """Plans across the forest (seeds 0-2), the windows and course map1 (when present)."""
    forest, window = load_world("forest"), load_world("window")
    problems = [(f"forest seed {seed}", forest, forest.start, forest.goal, seed)
                for seed in range(3)]
    problems.append(("window seed 0", window, window.start, window.goal, 0))
    if shared_maps is not None:
        problems.append(("map1 seed 0", load_world(shared_maps / "rbe595" / "map1.txt"),
                         MAP1_START, MAP1_GOAL, 0))
    plans = []
    for label, world, start, goal, seed in problems:
        result = plan_quadrotor(world, start, goal, SETTINGS.replace(seed=seed), MODEL)
        assert result.solved, (label, result.message)
        plans.append((label, result))
    return tuple(plans)


@pytest.fixture
def plans(optional_shared_maps: Path | None) -> tuple[tuple[str, KinoResult], ...]:
    """The real plans, planned once per test process."""
    return _plans(optional_shared_maps)


def _errors(result: KinoResult, leads=None) -> tuple[np.ndarray, np.ndarray]:
    """The planned states' times (K,) and the replay's distance from them (K,), m."""
    times, states = replay_6dof(MODEL, VEHICLE, result.states[0], result.controls,
                                result.durations, leads=leads)
    knots = np.concatenate([[0.0], np.cumsum(result.durations)])
    rows = np.searchsorted(times, knots)
    assert np.array_equal(times[rows], knots)
    assert np.diff(times).max() <= 1e-3 * (1 + 1e-9)
    return knots, np.linalg.norm(states[rows, :3] - result.states[:, :3], axis=1)


# ------------------------------------------------------------------ simple flights
@pytest.mark.parametrize("model", [MODEL, SampledQuadrotor(mass=0.1, yaw=0.7)])
def test_hover_control_stays_at_the_start(model):
    start = np.array([1.0, 2.0, 3.0, 0.0, 0.0, 0.0])
    times, states = replay_6dof(model, VEHICLE, start, [[0.0, 0.0, model.hover_thrust]] * 4,
                                [0.5] * 4)
    assert times[-1] == pytest.approx(2.0) and states.shape == (len(times), 17)
    assert np.linalg.norm(states[:, :3] - start[:3], axis=1).max() < 2e-3
    assert np.linalg.norm(states[:, 3:6], axis=1).max() < 2e-3


@pytest.mark.parametrize(("model", "step"), [
    (MODEL, [0.0, 0.2, 1.1]),  # positive pitch: towards +x, climbing
    (MODEL, [0.25, 0.0, 0.9]),  # positive roll: towards -y, sinking
    (SampledQuadrotor(mass=0.1, yaw=0.7), [-0.2, 0.3, 1.0]),  # another mass and heading
])
def test_a_step_flies_as_the_point_mass_within_the_tolerance(model, step):
    """From a hover, one tilted control for 1.5 s: the 6-DOF flight follows the point
    mass in direction and to within the stated tolerance."""
    hover = model.hover_thrust
    controls = [[0.0, 0.0, hover], [step[0], step[1], step[2] * hover]]
    durations = [0.5, 1.5]
    start = np.zeros(6)
    times, flown = replay_6dof(model, VEHICLE, start, controls, durations)
    exact_times, exact = replay(model, start, controls, durations)
    assert np.array_equal(times, exact_times)
    errors = np.linalg.norm(flown[:, :3] - exact[:, :3], axis=1)
    assert np.all(errors <= replay_6dof_tolerance(times))
    moved, planned = flown[-1, :3], exact[-1, :3]
    assert np.linalg.norm(planned) > 1.0
    assert moved @ planned / (np.linalg.norm(moved) * np.linalg.norm(planned)) > 0.999
    print(f"step {step}: {np.linalg.norm(planned):.2f} m flown, off by {errors[-1]:.3f} m "
          f"(tolerance {replay_6dof_tolerance(2.0):.3f} m)")


def test_response_delays_of_the_tello():
    attitude, thrust = response_delays(VEHICLE)
    assert 0.05 < attitude < 0.12
    # The collective thrust only waits for the rotors: their first-order lag.
    assert thrust == pytest.approx(VEHICLE.motor_time_constant, rel=0.1)
    # The course's vehicle, 100 times the inertia, turns far more slowly.
    assert response_delays(load_params("rbe595"))[0] > 1.5 * attitude


def test_no_controls_is_the_start_alone():
    times, states = replay_6dof(MODEL, VEHICLE, [1, 2, 3, 0, 0, 0], np.zeros((0, 3)), [])
    assert np.array_equal(times, [0.0]) and np.array_equal(states[0, :3], [1, 2, 3])


def test_bad_step_or_gravity_is_a_user_error():
    with pytest.raises(QuadnavError, match="step must be > 0"):
        replay_6dof(MODEL, VEHICLE, np.zeros(6), [[0, 0, 1]], [1.0], dt=0.0)
    with pytest.raises(QuadnavError, match="gravity"):
        replay_6dof(SampledQuadrotor(gravity=9.7), VEHICLE, np.zeros(6), [[0, 0, 1]], [1.0])


# ------------------------------------------------------------------ real plans
def test_real_plans_are_flown_within_the_tolerance(plans):
    for label, result in plans:
        knots, errors = _errors(result)
        ratio = errors[1:] / knots[1:] ** 1.5
        print(f"{label}: {result.duration:.1f} s; 6-DOF replay off by {errors[10]:.2f} m "
              f"after 5 s, {errors.max():.2f} m at most (tolerance at the end "
              f"{replay_6dof_tolerance(knots[-1]):.1f} m); largest error / t^1.5 "
              f"{ratio.max():.3f} (tolerance {DRIFT_RATE})")
        assert np.all(errors <= replay_6dof_tolerance(knots)), label


def test_issuing_controls_early_cuts_the_drift(plans):
    with_lead = [_errors(result)[1].max() for _, result in plans]
    on_time = [_errors(result, leads=(0.0, 0.0))[1].max() for _, result in plans]
    print(f"largest deviation, m: leads {np.round(with_lead, 2)}, "
          f"none {np.round(on_time, 2)}")
    assert sum(with_lead) < 0.7 * sum(on_time)


def test_the_command_reports_the_6dof_replay(plans):
    _, result = plans[0]
    entry, flown = replay_6dof_summary(MODEL, result)
    _, errors = _errors(result)
    assert entry["max_position_error"] == pytest.approx(errors.max())
    assert entry["tolerance"] == pytest.approx(replay_6dof_tolerance(result.duration))
    assert entry["within_tolerance"] and entry["vehicle"] == "tello without drag"
    assert (entry["attitude_lead"], entry["thrust_lead"]) == response_delays(VEHICLE)
    assert flown.shape[1] == 3 and np.array_equal(flown[0], result.states[0, :3])
    unsolved = plan_quadrotor(load_world("forest"), (1, 1, 1), (19, 19, 3),
                              SETTINGS.replace(max_iterations=1))
    entry, flown = replay_6dof_summary(MODEL, unsolved)
    assert entry["max_position_error"] is None and flown is None

"""Closed-loop simulation: contact with blocks, the boundary, divergence, records, seeds."""

from __future__ import annotations

import json
import math
import time

import numpy as np
import pytest

from quadnav.sim.collision import boxes_touch
from quadnav.sim.flight import Ending
from quadnav.sim.settings import SimSettings
from quadnav.sim.simulate import CHUNK_SECONDS, simulate
from quadnav.trajectory.generate import TrajectorySettings, make_trajectory
from quadnav.trajectory.model import hold_trajectory
from quadnav.vehicle import quaternion
from quadnav.vehicle.dynamics import hover_state
from quadnav.vehicle.params import load_params
from quadnav.world import World

TELLO = load_params("tello")
HALF = 0.5 * TELLO.body_size
BLOCK = np.array([2.0, -1.0, 0.0, 3.0, 1.0, 3.0])
WORLD = World(np.array([-1.0, -3.0, 0.0, 6.0, 3.0, 4.0]), BLOCK[None])


def _yawed(angle: float) -> np.ndarray:
    return quaternion.to_matrix(quaternion.from_yaw(angle))


@pytest.mark.parametrize(("angle", "reach"), [
    (0.0, HALF[0]), (math.pi / 4, (HALF[0] + HALF[1]) / math.sqrt(2)),
    (math.pi / 2, HALF[1]), (math.pi / 6, HALF[0] * math.cos(math.pi / 6)
                             + HALF[1] * math.sin(math.pi / 6))])
def test_the_body_box_touches_a_block_exactly_at_its_reach(angle, reach):
    rotation = _yawed(angle)
    touching = np.array([BLOCK[0] - reach, 0.0, 1.0])
    assert boxes_touch(touching, rotation, HALF, BLOCK)
    assert not boxes_touch(touching - [1e-9, 0, 0], rotation, HALF, BLOCK)


def test_a_tilted_body_reaches_further_down():
    pitch = math.radians(30)
    rotation = np.array([[math.cos(pitch), 0, math.sin(pitch)], [0, 1, 0],
                         [-math.sin(pitch), 0, math.cos(pitch)]])
    reach = HALF[0] * math.sin(pitch) + HALF[2] * math.cos(pitch)
    floor_block = np.array([-5.0, -5.0, -1.0, 5.0, 5.0, 0.0])
    assert boxes_touch(np.array([0.0, 0.0, reach]), rotation, HALF, floor_block)
    assert not boxes_touch(np.array([0.0, 0.0, reach + 1e-9]), rotation, HALF, floor_block)
    # an edge-on approach: only the 9 edge-edge axes separate these two
    edge = _yawed(math.pi / 4) @ rotation
    corner = np.array([-1.0, -1.0, -1.0, 0.0, 0.0, 0.0])
    assert not boxes_touch(np.array([0.06, 0.06, 0.06]), edge, HALF, corner)


def _straight(a, b, speed=1.0):
    return make_trajectory(np.array([a, b], dtype=float), TrajectorySettings(v_max=speed))


def test_flying_into_a_block_stops_at_the_contact():
    trajectory = _straight([0.0, 0.0, 1.0], [5.0, 0.0, 1.0])
    flight = simulate(trajectory, TELLO, world=WORLD, settings=SimSettings(record_rate=1000.0))
    assert flight.ending is Ending.COLLISION
    assert flight.contact_block == 0
    front = flight.position[-1, 0] + HALF[0]
    assert front == pytest.approx(BLOCK[0], abs=0.01)  # body level-ish at contact
    times = np.linspace(0, trajectory.duration, 20001)
    expected = times[np.argmax(trajectory.position(times)[:, 0] + HALF[0] >= BLOCK[0])]
    assert flight.contact_time == pytest.approx(expected, abs=0.1)


def test_leaving_the_boundary_and_turning_over_stop_the_flight():
    out = _straight([5.0, 0.0, 1.0], [8.0, 0.0, 1.0])
    flight = simulate(out, TELLO, world=WORLD)
    assert flight.ending is Ending.LEFT_BOUNDARY
    assert flight.position[-1, 0] > WORLD.boundary[3] + SimSettings().boundary_tolerance
    upside_down = hover_state(TELLO, [4.0, 0.0, 2.0])
    upside_down[6:10] = [0.0, 1.0, 0.0, 0.0]
    flight = simulate(hold_trajectory([4.0, 0.0, 2.0], 2.0), TELLO, world=WORLD,
                      initial_state=upside_down)
    assert flight.ending is Ending.DIVERGED
    assert flight.contact_time is not None and flight.contact_block is None


def test_a_takeoff_from_the_floor_is_no_collision():
    trajectory = _straight([4.0, 0.0, 0.0], [4.0, 2.0, 1.5])
    flight = simulate(trajectory, TELLO, world=WORLD)
    assert flight.ending is Ending.COMPLETED
    assert flight.position[:, 2].min() >= 0.0
    assert flight.final_error < 0.01


OPEN = World(np.array([-1.0, -3.0, 0.0, 6.0, 3.0, 4.0]))  # no blocks, the floor at z = 0


def test_hitting_the_floor_at_speed_is_a_crash_not_a_completed_flight():
    # a reference that dips 0.3 m below the floor and comes back up: the floor stops the
    # vehicle at 1.5 m/s, where the plan is 0.3 m under it (the flight went on, and ended
    # at the goal, before floor contact counted)
    dip = make_trajectory(np.array([[0.0, 0.0, 1.5], [2.0, 0.0, -0.3], [4.0, 0.0, 1.5]]),
                          TrajectorySettings(v_max=2.0))
    flight = simulate(dip, TELLO, world=OPEN)
    assert flight.ending is Ending.FLOOR
    assert flight.floor_speed > 2 * SimSettings().touchdown_speed
    assert flight.position[-1, 2] == 0.0 and flight.contact_block is None
    low = dip.position(np.linspace(0.0, dip.duration, 2001))[:, 2]
    assert flight.contact_time < dip.duration / 2 + 0.2 and low.min() < -0.25
    # the same dip with the floor allowed to be met anywhere at any speed flies on
    anyhow = simulate(dip, TELLO, world=OPEN, settings=SimSettings(touchdown_speed=np.inf,
                                                                    goal_tolerance=1.0))
    assert anyhow.ending is Ending.COMPLETED and anyhow.floor_speed == flight.floor_speed


def test_a_landing_where_the_plan_lands_is_no_crash():
    landing = _straight([4.0, 2.0, 1.5], [4.0, 0.0, 0.0])
    flight = simulate(landing, TELLO, world=OPEN)
    assert flight.ending is Ending.COMPLETED and flight.final_error < 0.01
    assert 0.0 < flight.floor_speed < 0.5 * SimSettings().touchdown_speed
    assert flight.position[-1, 2] == 0.0


def test_tracking_statistics_cover_every_control_step():
    trajectory = _straight([0.0, -2.0, 1.0], [5.0, -2.5, 2.0], speed=2.0)
    flight = simulate(trajectory, TELLO, world=WORLD, settings=SimSettings(record_rate=1000.0))
    errors = flight.tracking_error[:-1]  # the last row is the final state
    assert flight.rms_tracking_error == pytest.approx(np.sqrt(np.mean(errors ** 2)), rel=1e-12)
    assert flight.max_tracking_error == pytest.approx(errors.max(), rel=1e-12)
    assert np.allclose(np.diff(flight.t[:-1]), 1e-3)
    coarse = simulate(trajectory, TELLO, world=WORLD, settings=SimSettings(record_rate=50.0))
    assert np.allclose(np.diff(coarse.t[:-1]), 0.02)
    assert coarse.rms_tracking_error == flight.rms_tracking_error
    assert np.array_equal(coarse.states[-1], flight.states[-1])


def test_the_same_seed_flies_the_same_flight_and_another_does_not():
    trajectory = _straight([0.0, -2.0, 1.0], [5.0, -2.5, 2.0])
    noisy = SimSettings(gust_std=0.01, position_noise=0.002, velocity_noise=0.01,
                        attitude_noise=0.005, gyro_noise=0.01, seed=3)
    a = simulate(trajectory, TELLO, world=WORLD, settings=noisy)
    b = simulate(trajectory, TELLO, world=WORLD, settings=noisy)
    c = simulate(trajectory, TELLO, world=WORLD, settings=noisy.replace(seed=4))
    assert np.array_equal(a.states, b.states)
    assert not np.array_equal(a.states, c.states)
    assert a.ending is Ending.COMPLETED and c.ending is Ending.COMPLETED


def test_the_loop_is_timed_apart_from_its_loading():
    # a controller object this process has not flown, whose loop the flight looks up and
    # loads; the times are checked for their order only (which interval holds which), not
    # for a speed
    from quadnav.control.contract import Controller
    from quadnav.control.se3 import se3_controller

    se3 = se3_controller()
    fresh = Controller("fresh", se3.step, se3.gains, se3.memory_size)
    trajectory = _straight([0.0, -2.0, 1.0], [5.0, -2.5, 2.0], speed=2.0)
    stamps = []
    began = time.perf_counter()
    flight = simulate(trajectory, TELLO, world=WORLD, controller=fresh,
                      progress=lambda _: stamps.append(time.perf_counter()))
    ended = time.perf_counter()
    assert len(stamps) >= flight.duration / CHUNK_SECONDS  # a chunk a second
    # loading, then the loop: two disjoint intervals inside the call, the loading wholly
    # before the first chunk ended and the loop covering every chunk
    assert 0.0 < flight.load_time < stamps[0] - began
    assert stamps[-1] - stamps[0] <= flight.wall_time <= ended - began - flight.load_time


def test_the_real_time_factor_divides_the_flight_by_the_loop_alone(tmp_path):
    from clitools import run_here

    result = run_here("track", "hover", "--no-figures", "--quiet", "-o", tmp_path)
    metrics = json.loads((tmp_path / "metrics.json").read_text())
    assert metrics["real_time_factor"] == metrics["flight_time_s"] / metrics["sim_wall_time_s"]
    assert metrics["sim_load_time_s"] > 0.0
    assert (f"  wall time: loading the loop {metrics['sim_load_time_s']:.2f} s, simulation "
            f"{metrics['sim_wall_time_s']:.2f} s ({metrics['real_time_factor']:.0f}x real time)"
            in result.stdout.splitlines())


def test_slower_control_than_physics_still_tracks():
    trajectory = _straight([0.0, -2.0, 1.0], [5.0, -2.5, 2.0], speed=2.0)
    settings = SimSettings(physics_rate=2000.0, control_rate=250.0)
    flight = simulate(trajectory, TELLO, world=WORLD, settings=settings)
    assert flight.ending is Ending.COMPLETED
    assert flight.rms_tracking_error < 0.05


@pytest.mark.parametrize(("changes", "message"), [
    ({"physics_rate": 1500.0}, "whole multiple"),
    ({"record_rate": 2000.0}, "must not exceed the control rate"),
    ({"goal_tolerance": 0.0}, "goal tolerance"),
    ({"touchdown_speed": 0.0}, "touchdown speed must be > 0 m/s"),
    ({"gust_std": -1.0}, "gust_std: expected from 0 to 100 N"),
    ({"physics_rate": 1e9}, "physics rate: expected from 10 to 100,000 Hz"),
    ({"settle_time": 1e9}, "settle time: expected from 0 to 60 s"),
    ({"wind": [0.0, 1e300, 0.0]}, "wind: expected from -100 to 100 N"),
])
def test_bad_settings_are_user_errors(changes, message):
    from quadnav.errors import QuadnavError

    with pytest.raises(QuadnavError, match=message):
        SimSettings(**changes)


def test_a_heavier_plant_than_the_controller_knows_lags_more_but_still_flies():
    trajectory = _straight([0.0, 0.0, 1.0], [4.0, 0.0, 2.0], speed=2.0)
    nominal = simulate(trajectory, TELLO)
    heavier = TELLO.replace(mass=1.3 * TELLO.mass, drag=1.5 * TELLO.drag)
    unaware = simulate(trajectory, heavier, model=TELLO)
    aware = simulate(trajectory, heavier)

    assert nominal.ending is unaware.ending is aware.ending is Ending.COMPLETED
    assert np.linalg.norm(unaware.position[-1] - [4.0, 0.0, 2.0]) < 0.1
    # the controller that believes the nominal mass lags behind: its thrust feed-forward
    # is short of the weight until the integrators make up for it
    assert unaware.rms_tracking_error > 1.5 * nominal.rms_tracking_error
    assert unaware.rms_tracking_error > aware.rms_tracking_error
    assert np.array_equal(simulate(trajectory, TELLO, model=TELLO).states, nominal.states)

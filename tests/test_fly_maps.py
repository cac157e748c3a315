"""The main job end to end: every public course map with a path is flown to the goal with
no collision at 1, 2 and 3 m/s, keeping the margin off the legs, and every built-in world
over 20 seeds at a 2 m/s top speed."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from publicmaps import MAPS, course_query

from quadnav.errors import PlanningWarning
from quadnav.mission import Mission, MissionSettings, fly_mission
from quadnav.sim.settings import SimSettings
from quadnav.trajectory.generate import TrajectorySettings
from quadnav.world import load_world
from quadnav.world.builtin import world_names

SEEDS = range(20)


def _fly(world, start, goal, margin, seed: int = 0) -> Mission:
    settings = MissionSettings(planning=MissionSettings().planning.replace(seed=seed),
                               sim=SimSettings(seed=seed))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PlanningWarning)  # starts inside the margin
        return fly_mission(world, start, goal, margin, settings)


def _assert_clean_success(mission: Mission) -> None:
    metrics = mission.metrics()
    assert metrics["path_found"], metrics
    assert not metrics["collision"], metrics
    assert metrics["reached_goal"] and metrics["success"], metrics
    assert metrics["final_error_m"] <= SimSettings().goal_tolerance
    clearance = metrics["min_clearance_m"]
    assert clearance is None or clearance > 0.0


@pytest.mark.parametrize("name", MAPS)
def test_every_course_map_is_flown_at_one_two_and_three_metres_per_second(shared_maps, name):
    world, start, goal, margin = course_query(shared_maps, name)
    for speed in (1.0, 2.0, 3.0):
        settings = MissionSettings(trajectory=TrajectorySettings(v_max=speed, a_max=3.0))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", PlanningWarning)  # starts inside the margin
            mission = fly_mission(world, start, goal, margin, settings)
        _assert_clean_success(mission)
        metrics = mission.metrics()
        assert metrics["trajectory_margin_m"] >= 0.95 * margin, (speed, metrics)
        assert metrics["flight_margin_m"] >= 0.5 * margin, (speed, metrics)
        leg = metrics["trajectory_leg_margin_m"]
        assert leg is None or leg >= 0.0
        t = np.linspace(0.0, mission.trajectory.duration, 4000)
        top_speed = np.linalg.norm(mission.trajectory.velocity(t), axis=1).max()
        assert top_speed <= speed * (1 + 1e-3)
        print(f"{name} at {speed:g} m/s: top speed {top_speed:.2f} m/s, RMS tracking "
              f"{100 * mission.flight.rms_tracking_error:.2f} cm, margin kept "
              f"{metrics['trajectory_margin_m']:.3f} m (flown {metrics['flight_margin_m']:.3f}"
              f" m) of {margin:g} m")
        assert mission.flight.rms_tracking_error < 0.05


def test_map1_is_tracked_within_five_centimetres_rms_at_two_metres_per_second(shared_maps):
    mission = _fly(*course_query(shared_maps, "rbe595/map1.txt"))
    t = np.linspace(0.0, mission.trajectory.duration, 4000)
    top_speed = np.linalg.norm(mission.trajectory.velocity(t), axis=1).max()
    rms = mission.flight.rms_tracking_error
    print(f"rbe595/map1.txt at {top_speed:.2f} m/s top speed: RMS tracking error "
          f"{100 * rms:.2f} cm, max {100 * mission.flight.max_tracking_error:.2f} cm")
    _assert_clean_success(mission)
    assert top_speed == pytest.approx(2.0, rel=0.01)
    assert rms < 0.05


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("name", world_names())
def test_every_built_in_world_is_flown_to_the_goal_over_twenty_seeds(name, seed):
    spec = name if name == "empty" else f"{name}:seed={seed}"  # the empty world has no seed
    world = load_world(spec)
    _assert_clean_success(_fly(world, world.start, world.goal, world.margin, seed))


@pytest.mark.parametrize("name", MAPS)
def test_every_course_map_is_flown_by_the_se3_controller_at_two_metres_per_second(
        shared_maps, name):
    """The second controller, through the same contract and loop (fly --controller se3)."""
    world, start, goal, margin = course_query(shared_maps, name)
    settings = MissionSettings(controller="se3",
                               trajectory=TrajectorySettings(v_max=2.0, a_max=3.0))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PlanningWarning)  # starts inside the margin
        mission = fly_mission(world, start, goal, margin, settings)
    _assert_clean_success(mission)
    metrics = mission.metrics()
    assert metrics["flight_margin_m"] >= 0.5 * margin, metrics
    assert mission.flight.rms_tracking_error < 0.05
    assert mission.parameters()["controller"] == "se3"

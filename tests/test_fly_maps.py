"""The main job end to end: every public course map with a path is flown to the goal with
no collision at 1, 2 and 3 m/s, keeping the margin off the legs, and every built-in world
over 20 seeds at a 2 m/s top speed.

A course map's path is planned once (the same seed and budget at every speed and with
either controller) and flown at each speed and by each controller; the built-in worlds
are planned with 2,000 samples of improvement instead of 50,000, since the claim is that
the path found is flown, not how short it is."""

from __future__ import annotations

import warnings
from functools import cache
from pathlib import Path

import numpy as np
import pytest
from publicmaps import MAPS, course_query

from quadnav.errors import PlanningWarning
from quadnav.mission import Mission, MissionSettings, fly_mission, fly_plan, plan_mission
from quadnav.planning import make_problem
from quadnav.sim.settings import SimSettings
from quadnav.trajectory.generate import TrajectorySettings
from quadnav.world import load_world
from quadnav.world.builtin import world_names

SEEDS = range(20)


def _fly(world, start, goal, margin, seed: int = 0) -> Mission:
    planning = MissionSettings().planning.replace(seed=seed, improve_iterations=2000)
    settings = MissionSettings(planning=planning, sim=SimSettings(seed=seed))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PlanningWarning)  # starts inside the margin
        return fly_mission(world, start, goal, margin, settings)


@cache
def _course_plan(folder: Path, name: str) -> Mission:
    """The course map ``name``'s path, planned as ``fly`` plans it (seed 0)."""
    world, start, goal, margin = course_query(folder, name)
    settings = MissionSettings()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PlanningWarning)  # starts inside the margin
        problem = make_problem(world, start, goal, margin, settings.body)
    return plan_mission(problem, settings)


@cache
def _course_flight(folder: Path, name: str, speed: float, controller: str = "cascade"
                   ) -> Mission:
    """The course map ``name`` flown at ``speed`` m/s top speed by ``controller``."""
    settings = MissionSettings(controller=controller,
                               trajectory=TrajectorySettings(v_max=speed, a_max=3.0))
    return fly_plan(_course_plan(folder, name), settings)


#: The course maps, each one's tests on one worker, which plans its path once.
COURSE_MAPS = [pytest.param(name, marks=pytest.mark.xdist_group(f"fly-maps-{name}"))
               for name in MAPS]


def _assert_clean_success(mission: Mission) -> None:
    metrics = mission.metrics()
    assert metrics["path_found"], metrics
    assert not metrics["collision"], metrics
    assert metrics["reached_goal"] and metrics["success"], metrics
    assert metrics["final_error_m"] <= SimSettings().goal_tolerance
    clearance = metrics["min_clearance_m"]
    assert clearance is None or clearance > 0.0


@pytest.mark.parametrize("name", COURSE_MAPS)
def test_every_course_map_is_flown_at_one_two_and_three_metres_per_second(shared_maps, name):
    margin = _course_plan(shared_maps, name).problem.margin
    for speed in (1.0, 2.0, 3.0):
        mission = _course_flight(shared_maps, name, speed)
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


@pytest.mark.xdist_group("fly-maps-rbe595/map1.txt")
def test_map1_is_tracked_within_five_centimetres_rms_at_two_metres_per_second(shared_maps):
    assert TrajectorySettings(v_max=2.0, a_max=3.0) == MissionSettings().trajectory
    mission = _course_flight(shared_maps, "rbe595/map1.txt", 2.0)  # as fly flies it
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


@pytest.mark.parametrize("name", COURSE_MAPS)
def test_every_course_map_is_flown_by_the_se3_controller_at_two_metres_per_second(
        shared_maps, name):
    """The second controller, through the same contract and loop (fly --controller se3)."""
    margin = _course_plan(shared_maps, name).problem.margin
    mission = _course_flight(shared_maps, name, 2.0, "se3")
    _assert_clean_success(mission)
    metrics = mission.metrics()
    assert metrics["flight_margin_m"] >= 0.5 * margin, metrics
    assert mission.flight.rms_tracking_error < 0.05
    assert mission.parameters()["controller"] == "se3"

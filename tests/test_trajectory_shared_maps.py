"""Plan and make a minimum-snap trajectory on every public course map: collision-free."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from quadnav.errors import PlanningWarning
from quadnav.planning import PlannerSettings, make_problem, plan
from quadnav.planning.refine import refine
from quadnav.trajectory.collision import first_collision
from quadnav.trajectory.generate import TrajectorySettings, checking_world, make_trajectory
from quadnav.world import load_world, read_start_goal

MAPS = [
    "meam620/grid_forest.json", "meam620/map_2017_boundary9fields.txt",
    "meam620/map_2017_nocolor_blocks.txt", "meam620/single_cube.txt", "meam620/test_empty.json",
    "meam620/test_window.json", "rbe595/map1.txt", "rbe595/map4.txt", "rbe595/p2b_map1.txt",
    "rotorpy/double_pillar.json", "rotorpy/pillar.json",
]
#: Start and goal files that go with a map.
START_GOAL = {"rbe595/p2b_map1.txt": "rbe595/p2b_startandgoal_map1.txt"}


def far_apart_free_points(free_world):
    """A deterministic start and goal: the two most distant of 300 seeded free samples."""
    points = free_world.sample_free(300, seed=0)
    distances = np.linalg.norm(points[:, None] - points[None], axis=2)
    i, j = np.unravel_index(np.argmax(distances), distances.shape)
    return points[i], points[j]


@pytest.mark.parametrize("name", MAPS)
def test_minimum_snap_through_a_plan_is_free_on_every_course_map(shared_maps, name):
    world = load_world(shared_maps / name)
    margin = world.margin if world.margin is not None else 0.2
    start, goal = world.start, world.goal
    if name in START_GOAL:
        start, goal = read_start_goal(shared_maps / START_GOAL[name])
    if start is None:
        start, goal = far_apart_free_points(world.inflate(margin))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PlanningWarning)  # starts on the boundary
        problem = make_problem(world, start, goal, margin)
        result = plan(problem, PlannerSettings(seed=0, max_iterations=20000, time_limit=60))
        path = refine(problem, result).path
        free_world, _ = checking_world(world, margin, path)
    trajectory = make_trajectory(path, TrajectorySettings(), free_world)
    assert first_collision(trajectory, free_world) is None
    assert np.allclose(trajectory.position([0.0, trajectory.duration]), [start, goal],
                       atol=1e-9)
    t = np.linspace(0.0, trajectory.duration, 5000)
    assert np.linalg.norm(trajectory.velocity(t), axis=1).max() <= TrajectorySettings().v_max

"""Plan and make a minimum-snap trajectory on every public course map: collision-free."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from publicmaps import MAPS, course_query

from quadnav.errors import PlanningWarning
from quadnav.planning import PlannerSettings, make_problem, plan
from quadnav.planning.refine import refine
from quadnav.trajectory.collision import first_collision
from quadnav.trajectory.generate import TrajectorySettings, checking_world, make_trajectory


@pytest.mark.parametrize("name", MAPS)
def test_minimum_snap_through_a_plan_is_free_on_every_course_map(shared_maps, name):
    world, start, goal, margin = course_query(shared_maps, name)
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

"""Plan and make a minimum-snap trajectory on every public course map: it keeps the whole
margin off the legs, measured exactly, and never touches a block on them."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from publicmaps import MAPS, course_query

from quadnav.errors import PlanningWarning
from quadnav.planning import PlannerSettings, make_problem, plan
from quadnav.planning.refine import refine
from quadnav.trajectory.clearance.collision import first_collision
from quadnav.trajectory.clearance.space import SafeSpace, trajectory_margins
from quadnav.trajectory.generate import TrajectorySettings, make_trajectory


@pytest.mark.parametrize("name", MAPS)
def test_minimum_snap_through_a_plan_is_free_on_every_course_map(shared_maps, name):
    world, start, goal, margin = course_query(shared_maps, name)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PlanningWarning)  # starts on the boundary
        problem = make_problem(world, start, goal, margin)
        result = plan(problem, PlannerSettings(seed=0, max_iterations=20000, time_limit=60))
        path = refine(problem, result).path
    space = SafeSpace(world, margin)
    trajectory = make_trajectory(path, TrajectorySettings(), space)
    assert first_collision(trajectory, space.inflated) is None or trajectory.legs != (0, 0)
    kept, on_legs = trajectory_margins(trajectory, world)
    assert kept >= 0.99 * margin
    assert on_legs is None or on_legs >= 0.0
    assert np.allclose(trajectory.position([0.0, trajectory.duration]), [start, goal],
                       atol=1e-9)
    t = np.linspace(0.0, trajectory.duration, 5000)
    assert np.linalg.norm(trajectory.velocity(t), axis=1).max() <= TrajectorySettings().v_max

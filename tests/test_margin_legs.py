"""The safety margin is kept everywhere but on the legs out of it, checked exactly.

Maps of our own making in the shapes that broke real course runs: 1 m corridors between
long walls and the boundary with start and goal on the boundary, a start and goal on the
boundary each with a wall 0.2 m in front of it (a pocket no wider than the margin, with
room for the vehicle's 0.1 m body), and a lab-maze file whose thin walls give their
extents the wrong way round.
Each is flown at 1, 2 and 3 m/s over 5 seeds: the trajectory keeps at least 95 % of the
margin off the legs, measured exactly, and every flight reaches the goal with no contact
and its body inside the map.
"""

from __future__ import annotations

import dataclasses
import json
import warnings

import numpy as np
import pytest

from quadnav.errors import MapWarning, PlanningWarning, QuadnavError
from quadnav.mission import Mission, MissionSettings, fly_plan, plan_mission
from quadnav.planning import make_problem
from quadnav.planning.legs import find_leg
from quadnav.sim.settings import SimSettings
from quadnav.trajectory.generate import TrajectorySettings
from quadnav.world import World, load_world
from quadnav.world.margins import box_margins, point_margins, polyline_margin

MARGIN = 0.2
#: 1 m corridors: along y = 0..1 (the boundary), 2..3 and 4..5 (the boundary), joined at
#: alternate ends; start and goal on the boundary x = 0.
CORRIDORS = World(boundary=[0, 0, 0, 10, 5, 2], blocks=[[0, 1, 0, 8, 2, 2], [2, 3, 0, 10, 4, 2]],
                  start=[0, 0.5, 1], goal=[0, 4.5, 1], name="corridors")
#: Start and goal on the boundary, each 0.2 m behind a full-height wall: no wider than the
#: margin, so the only way out runs sideways along the boundary first.
POCKETS = World(boundary=[0, 0, 0, 8, 6, 3],
                blocks=[[0.2, 2, 0, 1.5, 4, 3], [6.5, 2, 0, 7.8, 4, 3]],
                start=[0, 3, 1.5], goal=[8, 3, 1.5], name="pockets")
#: A maze-like lab map as MEAM620's current files write it: thin walls whose extents give
#: min and max the wrong way round on an axis (read as the box between, with a warning).
SWAPPED_JSON = json.dumps({
    "bounds": {"extents": [0, 6, 0, 4, 0, 2]},
    "blocks": [{"extents": [3.02, 2.98, 0.0, 3.0, 0.0, 2.0]},
               {"extents": [1.52, 1.48, 4.0, 1.0, 0.0, 2.0]}],
    "start": [0.0, 2.0, 1.0], "goal": [6.0, 2.0, 1.0], "margin": 0.2})
SPEEDS = (1.0, 2.0, 3.0)
SEEDS = range(5)


def _plan(world: World, seed: int) -> Mission:
    settings = MissionSettings(
        planning=MissionSettings().planning.replace(seed=seed, improve_iterations=5000))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PlanningWarning)
        return plan_mission(make_problem(world, None, None, MARGIN, settings.body), settings)


def _fly(planned: Mission, speed: float, seed: int) -> Mission:
    """``planned``'s path flown at ``speed`` m/s top speed (the path does not depend on it)."""
    settings = dataclasses.replace(
        planned.settings, trajectory=TrajectorySettings(v_max=speed, a_max=1.5 * speed),
        sim=SimSettings(seed=seed))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PlanningWarning)
        return fly_plan(planned, settings)


@pytest.fixture(scope="module")
def swapped(tmp_path_factory) -> World:
    path = tmp_path_factory.mktemp("maps") / "lab_maze.json"
    path.write_text(SWAPPED_JSON)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        world = load_world(path)
    assert [str(w.message).split(": ")[1:3] for w in caught] == [
        ["blocks[0]", "min and max swapped (xmin 3.02 > xmax 2.98); read as the box between them"],
        ["blocks[1]", "min and max swapped (xmin 1.52 > xmax 1.48, ymin 4 > ymax 1); read as "
                      "the box between them"]]
    assert all(w.category is MapWarning for w in caught)
    assert np.allclose(world.blocks, [[2.98, 0, 0, 3.02, 3, 2], [1.48, 1, 0, 1.52, 4, 2]])
    return world.replace(name="swapped")


@pytest.mark.parametrize("world", ["corridors", "pockets", "swapped"])
def test_flights_keep_the_margin_off_the_legs_at_every_speed_and_seed(world, request):
    world = {"corridors": CORRIDORS, "pockets": POCKETS}.get(world) or request.getfixturevalue(
        world)
    worst = {}
    for seed in SEEDS:
        planned = _plan(world, seed)
        for speed in SPEEDS:
            mission = _fly(planned, speed, seed)
            m = mission.metrics()
            assert m["success"] and not m["collision"], (speed, seed, m)
            assert m["body_outside_m"] == 0.0
            assert m["trajectory_margin_m"] >= 0.95 * MARGIN, (speed, seed, m)
            assert m["trajectory_leg_margin_m"] >= 0.0  # the legs touch nothing
            assert m["flight_margin_m"] >= 0.75 * MARGIN, (speed, seed, m)
            # The legs are only where the path enters and leaves the margin.
            assert 0 < m["start_leg_m"] < 1.5 and 0 < m["goal_leg_m"] < 1.5
            worst[speed] = min(worst.get(speed, np.inf), m["trajectory_margin_m"])
    print(f"{world.name}: smallest margin kept off the legs by speed: {worst}")


def test_a_leg_out_of_a_pocket_runs_along_the_boundary_and_keeps_its_start_clearance():
    free = POCKETS.inflate(MARGIN)
    leg = find_leg(POCKETS, free, POCKETS.start, MARGIN, "start")
    assert len(leg) == 3 and np.array_equal(leg[0], POCKETS.start)
    assert free.is_free(leg[-1]) and point_margins(POCKETS, leg[-1:])[0] > MARGIN
    assert not free.points_free(leg[:-1]).any()  # only the last point keeps the margin
    # Never closer to the wall than the start (0.2 m), never outside the boundary.
    assert polyline_margin(POCKETS, leg, boundary=False) >= 0.2 * (1 - 1e-3)
    assert np.all(leg >= POCKETS.lower) and np.all(leg <= POCKETS.upper)
    # The shortest way: along the boundary to just past the wall's margin, then out.
    assert np.linalg.norm(np.diff(leg, axis=0), axis=1).sum() < 1.45
    assert np.allclose(leg[:, 2], 1.5)


def test_a_start_the_vehicle_cannot_leave_is_refused_with_the_reason():
    # A closed room 0.3 m wide: inside it nothing keeps a 0.2 m margin.
    room = World(boundary=[0, 0, 0, 4, 4, 3],
                 blocks=[[0.3, 0, 0, 0.4, 4, 3], [0, 0.3, 0, 0.3, 4, 3]], name="room")
    with pytest.raises(QuadnavError, match=r"start \(0.1, 0.1, 1\) is inside the 0.2 m safety "
                                           r"margin and there is no way out of it"):
        make_problem(room, [0.1, 0.1, 1.0], [3, 3, 1], MARGIN)


def test_box_margins_are_what_inflation_defines():
    world = World(boundary=[0, 0, 0, 10, 10, 4], blocks=[[4, 4, 0, 6, 6, 2]])
    rng = np.random.default_rng(0)
    points = rng.uniform([0, 0, 0], [10, 10, 4], size=(2000, 3))
    margins = point_margins(world, points)
    for m in (0.1, 0.5, 1.0):
        inflated = world.inflate(m)
        assert np.array_equal(inflated.points_free(points), margins > m)
    assert point_margins(world, [[0, 5, 1]])[0] == 0.0  # on the boundary
    assert point_margins(world, [[5, 5, 1]])[0] == -1.0  # 1 m deep in the block
    box = np.array([[3.0, 3.0, 1.0, 3.5, 7.0, 3.0]])  # 0.5 m left of the block
    assert box_margins(world, box)[0] == pytest.approx(0.5)


def test_polyline_margins_are_exact_between_the_vertices():
    world = World(boundary=[-10, -10, -10, 10, 10, 10], blocks=[[-1, -1, -1, 1, 1, 1]])
    # A segment passing the block's edge diagonally: its vertices are far, its middle near.
    segment = np.array([[-3.0, 0.5, 0.0], [0.5, -3.0, 0.0]])  # x + y = -2.5
    assert point_margins(world, segment).min() == pytest.approx(2.0)
    assert polyline_margin(world, segment) == pytest.approx(0.25, abs=1e-8)
    assert polyline_margin(world, segment, boundary=False) == pytest.approx(0.25, abs=1e-8)

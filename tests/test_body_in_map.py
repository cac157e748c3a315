"""The vehicle's body stays inside the map, or the flight is not a success.

A goal on the boundary is replaced by the nearest point where the body fits (said once, both
points in metrics.json); a start on it is left by the shortest move that brings the body
inside, and the legs run where the body fits, not along the wall; a flight whose body leaves
the map after its start, by any amount, fails. Checked on built-in worlds and maps of our own
making, the RBE595 Tello map when ../shared is there, and against the body measured here
from flight.csv at every record (scipy's rotations, not quadnav's).
"""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest
from clitools import assert_user_error, run_here
from scipy.spatial.transform import Rotation

from quadnav.errors import PlanningWarning
from quadnav.mission import MissionSettings, fly_mission
from quadnav.planning import PlannerSettings, make_problem
from quadnav.runs import read_run, run_outcome
from quadnav.trajectory.model import YawMode
from quadnav.vehicle.params import load_params
from quadnav.viz.html_viewer import viewer_data
from quadnav.world import World, load_world
from quadnav.world.margins import polyline_margin

#: The Tello's body box half extents, m.
HALF = 0.5 * load_params("tello").body_size
#: How far inside the boundary the body is kept where the planner moves it (docs/maps.md).
BODY_ROOM = 0.03
#: A room whose wall stands 0.2 m in front of the x = 0 face, 2 m high under a 3 m ceiling:
#: a start on that face at 0.5 m can only leave the margin by climbing over the wall.
WALL = World(boundary=[0, 0, 0, 4, 3, 3], blocks=[[0.2, 0, 0, 1, 3, 2]], name="wall")


def _flown(folder) -> tuple[dict, np.ndarray]:
    """metrics.json and flight.csv of a run folder."""
    metrics = json.loads((folder / "metrics.json").read_text())
    return metrics, np.loadtxt(folder / "flight.csv", delimiter=",", skiprows=1)


def _body_outside(flight: np.ndarray, boundary: np.ndarray) -> np.ndarray:
    """How far (N,), m, the Tello's body box sticks out of ``boundary`` (6,) at each record
    of a flight.csv table (negative: inside by that much)."""
    turned = Rotation.from_quat(flight[:, [8, 9, 10, 7]]).as_matrix()  # scalar last
    reach = np.abs(turned) @ HALF
    position = flight[:, 1:4]
    return np.maximum(boundary[:3] - (position - reach),
                      position + reach - boundary[3:]).max(axis=1)


def _after_leaving_the_start(outside: np.ndarray) -> np.ndarray:
    """The records from the first at which the body is wholly inside (at least one)."""
    assert (outside <= 0.0).any()
    return outside[int(np.argmax(outside <= 0.0)):]


def test_a_goal_on_the_boundary_is_flown_to_the_nearest_point_where_the_body_fits(tmp_path):
    result = run_here("fly", "empty:size=4x4x3", "--start", "1", "2", "1", "--goal", "4", "2",
                      "1", "--quiet", "--no-figures", "-o", tmp_path / "run")
    assert result.returncode == 0, result.stderr
    said = [line for line in result.stderr.splitlines() if "too close to the boundary" in line]
    assert said == [
        "quadnav: warning: goal (4, 2, 1) is too close to the boundary for the vehicle's "
        "0.1 x 0.1 x 0.05 m body; flying to (3.92, 2, 1) instead, the nearest point where it "
        "fits with 3 cm to spare"]
    metrics, flight = _flown(tmp_path / "run")
    assert metrics["goal_asked"] == [4.0, 2.0, 1.0]
    assert metrics["goal"] == pytest.approx([4.0 - HALF[0] - BODY_ROOM, 2.0, 1.0], abs=1e-12)
    assert metrics["success"] and metrics["body_outside_m"] == 0.0
    assert metrics["body_outside_time_s"] == 0.0 and metrics["body_outside_since_s"] is None
    # The tolerance is judged at the point flown to, and the body never touched the wall.
    assert np.linalg.norm(flight[-1, 1:4] - metrics["goal"]) == pytest.approx(
        metrics["final_error_m"], abs=1e-6)
    assert _body_outside(flight, np.array([0, 0, 0, 4, 4, 3])).max() < -0.005


def test_the_rbe595_tello_start_and_goal_on_the_floor_take_off_and_land_inside(
        tmp_path, shared_maps):
    folder = shared_maps / "rbe595"
    result = run_here("fly", folder / "p2b_map1.txt", "--start-goal",
                      folder / "p2b_startandgoal_map1.txt", "--quiet", "--no-figures",
                      "-o", tmp_path / "run")
    assert result.returncode == 0, result.stderr
    assert ("goal (-0.59, 6.81, 0) is too close to the boundary for the vehicle's 0.1 x 0.1 x "
            "0.05 m body; flying to (-0.59, 6.81, 0.055) instead" in result.stderr)
    metrics, flight = _flown(tmp_path / "run")
    assert metrics["goal_asked"] == [-0.59, 6.81, 0.0]
    assert metrics["goal"] == pytest.approx([-0.59, 6.81, HALF[2] + BODY_ROOM], abs=1e-12)
    assert metrics["start_leg_m"] == pytest.approx(0.21)  # straight up off the floor
    assert metrics["success"] and metrics["body_outside_m"] == 0.0
    outside = _body_outside(flight, load_world(folder / "p2b_map1.txt").boundary)
    assert outside[0] == pytest.approx(HALF[2])  # it stands half in the floor at the start
    assert _after_leaving_the_start(outside).max() <= 0.0  # then never leaves the map again
    assert outside[-100:].max() < -0.01  # and lands with room to spare


def test_a_start_on_the_boundary_behind_a_wall_climbs_out_where_the_body_fits(tmp_path):
    settings = MissionSettings(planning=PlannerSettings(improve_iterations=2000))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PlanningWarning)
        mission = fly_mission(WALL, [0.0, 1.5, 0.5], [3.0, 1.5, 1.0], 0.2, settings)
    leg = mission.problem.start_leg
    # The shortest move inside (3 cm to spare), then up along the wall, never closer to it
    # than the body's half-size and the room: no leg along the wall at 0.0001 m from it.
    assert np.allclose(leg[1], [HALF[0] + BODY_ROOM, 1.5, 0.5])
    assert leg[2, 2] > 2.0
    assert polyline_margin(World(WALL.boundary), leg[1:]) >= HALF[0] + BODY_ROOM - 1e-9
    assert mission.success and mission.flight.ending.value == "completed"
    record = np.column_stack([mission.flight.t, mission.flight.position,
                              np.zeros((len(mission.flight.t), 3)), mission.flight.attitude])
    outside = _body_outside(record, WALL.boundary)
    assert outside[0] == pytest.approx(HALF[0])
    assert _after_leaving_the_start(outside).max() <= 0.0


def test_a_start_whose_body_cannot_fit_beside_a_block_is_refused_in_one_line(tmp_path):
    pocket = World(boundary=[0, 0, 0, 4, 3, 3], blocks=[[0.1, 0, 0, 1, 3, 2]], name="pocket")
    path = tmp_path / "pocket.json"
    path.write_text(json.dumps({"bounds": {"extents": [0, 4, 0, 3, 0, 3]},
                                "blocks": [{"extents": [0.1, 1, 0, 3, 0, 2]}]}))
    result = run_here("fly", path, "--start", "0", "1.5", "0.5", "--goal", "3", "1.5", "1",
                      "-o", tmp_path / "run", "--quiet")
    assert_user_error(result, "start (0, 1.5, 0.5): the vehicle's 0.1 x 0.1 x 0.05 m body does "
                      "not fit there: moved inside the boundary, to (0.08, 1.5, 0.5), it "
                      "touches block 0 [0.1, 1] x [0, 3] x [0, 2]; move the start")
    assert not (tmp_path / "run").exists()
    # A point fits (plan and map check plan for one): its leg runs along the wall.
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PlanningWarning)
        assert make_problem(pocket, [0, 1.5, 0.5], [3, 1.5, 1], 0.2).start_leg[1, 0] < 1e-3


def test_a_flight_blown_out_of_the_map_is_not_a_success(tmp_path):
    # A steady 0.1 N wind towards the x = 4 wall pushes the body 4-5 cm through it; the
    # centre stays inside and ends 5 cm from the goal, so only the body says it failed.
    result = run_here("fly", "empty:size=4x4x3", "--start", "1", "2", "1", "--goal", "3.9", "2",
                      "1", "--wind", "0.1", "0", "0", "--quiet", "--no-figures",
                      "-o", tmp_path / "run")
    assert result.returncode == 1
    assert "quadnav: flight failed: the body left the map by 4." in result.stderr
    metrics, flight = _flown(tmp_path / "run")
    assert not metrics["success"]
    assert metrics["ending"] == "completed" and metrics["reached_goal"]
    assert metrics["final_error_m"] < 0.08 and metrics["goal"] == metrics["goal_asked"]
    assert 0.03 < metrics["body_outside_m"] < 0.06 and metrics["body_outside_time_s"] > 1.0
    outside = _body_outside(flight, np.array([0, 0, 0, 4, 4, 3]))
    assert outside.max() == pytest.approx(metrics["body_outside_m"], abs=2e-3)
    assert flight[:, 1].max() < 4.0  # the centre never left: the old check saw nothing
    # the report's, figures' and viewer's outcome says why too (they said the goal was missed)
    assert run_outcome(metrics) == (f"the body left the map by {100 * metrics['body_outside_m']:.1f}"
                                    f" cm at {metrics['body_outside_since_s']:.2f} s")
    subtitle = viewer_data(read_run(tmp_path / "run"))["subtitle"]
    assert subtitle.startswith(f"FAILED: {run_outcome(metrics)} \u00b7 "), subtitle


def test_the_body_is_measured_at_its_attitude_and_after_its_start_move_only():
    from quadnav.sim.excursion import body_excursion

    boundary = np.array([0.0, 0, 0, 4, 4, 3])
    level, rolled = [1.0, 0, 0, 0], Rotation.from_euler("x", 45, degrees=True).as_quat()
    rolled = np.roll(rolled, 1)  # scalar first
    t = np.array([0.0, 0.01, 0.02])
    # 5 cm above the floor: the level body (2.5 cm half height) fits, rolled 45 deg it
    # reaches (0.05 + 0.025) / sqrt(2) = 5.3 cm down, 3 mm through the floor.
    low = np.array([[2.0, 2.0, 0.05]] * 3)
    assert not body_excursion(t, low, np.array([level] * 3), HALF, boundary)
    tilted = body_excursion(t, low, np.array([level, rolled, level]), HALF, boundary)
    assert tilted.depth == pytest.approx(0.075 / np.sqrt(2) - 0.05, abs=1e-9)
    assert tilted.duration == pytest.approx(0.02) and tilted.since == 0.0
    # From the x = 0 wall: moving straight in is the start, not counted; moving along the
    # wall with the body still half out is counted once past the start move's 8 cm.
    t = np.linspace(0.0, 1.0, 11)
    inward = np.column_stack([np.linspace(0, 0.2, 11), np.full(11, 2.0), np.full(11, 1.0)])
    along = np.column_stack([np.zeros(11), np.linspace(2.0, 3.0, 11), np.full(11, 1.0)])
    attitudes = np.array([level] * 11)
    assert not body_excursion(t, inward, attitudes, HALF, boundary)
    sideways = body_excursion(t, along, attitudes, HALF, boundary)
    assert sideways.depth == pytest.approx(HALF[0]) and sideways.since == pytest.approx(0.1)
    assert sideways.duration == pytest.approx(0.9)


def test_a_mission_that_faces_its_travel_keeps_the_body_inside_at_any_heading():
    """Turned to face its travel, the Tello's 0.1 x 0.1 m body reaches 7.1 cm along x or y,
    not the 5 cm it reaches at yaw 0: the start and goal are kept that far inside."""
    level = MissionSettings()
    facing = MissionSettings(trajectory=level.trajectory.replace(yaw=YawMode.TRAVEL))
    assert level.body == pytest.approx([0.05, 0.05, 0.025])
    assert facing.body == pytest.approx([0.05 * np.sqrt(2), 0.05 * np.sqrt(2), 0.025])
    world = load_world("empty:size=4x4x3")
    with pytest.warns(PlanningWarning) as said:  # the goal moved, then its leg
        mission = fly_mission(world, [1.0, 2.0, 1.0], [4.0, 2.0, 1.0], 0.2, facing)
    assert "the vehicle's 0.141421 x 0.141421 x 0.05 m body" in str(said[0].message)
    assert mission.problem.goal[0] == pytest.approx(4.0 - 0.05 * np.sqrt(2) - BODY_ROOM)
    assert mission.success and not mission.flight.body_outside

"""``quadnav tello fly`` from starts and to goals inside the safety margin: the legs.

The room of :mod:`test_query_rules` (4 x 3 x 2 m, a wall piece 0.1 m in front of its x = 0
face), fenced 0.1 m in (the path keeps 0.2 m): a start on the x = 4 boundary, a start in
the pocket between the x = 0 boundary and the wall piece, a goal on the boundary. The
takeoff column, the climb to the leg and the planner's leg may come closer than the fence
but stay in the leg's room (as close to a block as the start, inside the boundary); the
rest keeps the fence. Checked on dry runs (the ``go`` moves, de-rounded), an ``rc`` dry
run, and one mission of the real djitellopy client against the emulator.
"""

from __future__ import annotations

import io
import math
from functools import cache

import numpy as np
import pytest
from tellotools import assert_on_the_floor, emulated_flight, needs_netns

from quadnav.hardware.bridge.flight import GOAL_TOLERANCE, BridgeSettings, RcModeError, Status, fly
from quadnav.hardware.bridge.flight_plan import TAKEOFF_HEIGHT, FlightPlan, plan_flight
from quadnav.hardware.bridge.geofence import GeofenceError
from quadnav.hardware.bridge.lost_link import LostLinkBound
from quadnav.hardware.bridge.moves import MoveError
from quadnav.hardware.bridge.rc import stick_velocity
from quadnav.planning import PlannerSettings
from quadnav.trajectory.generate import TrajectorySettings
from quadnav.world import World
from quadnav.world.margins import point_margins, polyline_margin

ROOM = World(boundary=[0, 0, 0, 4, 3, 2], blocks=[[0.1, 1, 0, 0.6, 2, 2]], name="room")
MARGIN = 0.1
GOAL = (3.5, 1.5, 1.0)
ON_THE_WALL = (4.0, 0.5, 1.2)
IN_THE_POCKET = (0.0, 1.5, 1.2)


@cache
def planned(start: tuple, goal: tuple = GOAL, yaw: float = 0.0) -> FlightPlan:
    """The room's flight from ``start`` to ``goal``, planned once per test process."""
    return plan_flight(ROOM, start, goal, MARGIN, yaw,
                       planning=PlannerSettings(seed=0, max_iterations=2000),
                       trajectory=TrajectorySettings(v_max=0.5, a_max=1.0))


def dry_run(plan: FlightPlan, mode: str, tmp_path) -> tuple[list[str], str]:
    """The commands a dry run prints, and its outcome's message."""
    out = io.StringIO()
    outcome = fly(plan, BridgeSettings(mode=mode), tmp_path, stream=out).outcome
    assert outcome.status is Status.DRY_RUN, outcome.message
    return out.getvalue().splitlines(), outcome.message


def flown_go_track(plan: FlightPlan, commands: list[str]) -> np.ndarray:
    """(N, 3) map points a drone flying ``commands`` passes, de-rounded: the floor under
    the start, the takeoff height, the end of each ``go`` move, the floor under the last."""
    steps = [[int(v) for v in c.split()[1:4]] for c in commands if c.startswith("go ")]
    ends = plan.frame.cm_to_map(np.cumsum([[0, 0, round(100 * TAKEOFF_HEIGHT)], *steps],
                                          axis=0))
    return np.vstack([plan.takeoff_ground, ends, [*ends[-1, :2], 0.0]])


def test_the_room_of_a_leg_is_as_close_to_the_blocks_as_its_start():
    plan = planned(IN_THE_POCKET)
    room = plan.start_room
    assert room.clearance == pytest.approx(0.0999, abs=1e-8)  # 0.1 m less the sliver
    assert room.face_room.tolist() == [-1e-9, MARGIN, MARGIN, MARGIN, MARGIN, MARGIN]
    assert room.contains(plan.problem.start_leg).all()
    assert room.column_ok([0.0, 1.5, 0.0], [0.0, 1.5, 1.89])  # along the wall, to the ceiling
    assert not room.point_ok([0.0002, 1.5, 1.2])  # closer to the wall piece than the start
    assert not room.point_ok([-1e-6, 1.5, 1.2])  # outside the boundary
    assert not room.column_ok([0.0, 1.5, 0.0], [0.0, 1.5, 1.95])  # into the ceiling's margin
    inside = ROOM.inflate(MARGIN).sample_free(500, seed=1)
    assert room.contains(inside).all()  # the fence lies in it
    free = planned((2.0, 1.5, 1.0)).start_room  # a start free of the margin: the fence
    assert np.array_equal(free.free_world.boundary, free.fence.free_world.boundary)
    assert np.array_equal(free.free_world.blocks, free.fence.free_world.blocks)


@pytest.mark.parametrize(("start", "goal", "first_moves"), [
    (ON_THE_WALL, GOAL, ["go 0 0 40 50", "go -21 0 0 50"]),  # climb along x = 4, leave it
    (IN_THE_POCKET, GOAL, ["go 0 0 40 50", "go 0 -60 0 50", "go 21 -11 0 50"]),  # around
    ((2.0, 2.5, 1.2), (4.0, 2.5, 1.0), None),  # a goal on the boundary
], ids=["start on the boundary", "start in a pocket", "goal on the boundary"])
def test_dry_runs_leave_and_enter_the_margin_by_the_planners_legs(start, goal, first_moves,
                                                                  tmp_path):
    plan = planned(start, goal)
    problem, route, pruned = plan.problem, plan.route, plan.pruned
    assert np.array_equal(route.points[:route.head + 1], problem.start_leg)
    assert np.array_equal(route.points[route.tail:], problem.goal_leg)
    assert np.array_equal(pruned.points[:pruned.head + 1], problem.start_leg)
    assert np.array_equal(pruned.points[pruned.tail:], problem.goal_leg)
    commands, message = dry_run(plan, "waypoints", tmp_path)
    assert commands[:2] == ["command", "takeoff"] and commands[-1] == "land"
    if first_moves is not None:
        assert commands[2:2 + len(first_moves)] == first_moves
    track = flown_go_track(plan, commands)
    assert np.linalg.norm(track[-2] - goal) < 0.01  # the moves end at the goal (whole cm)
    # De-rounded, no move touches a block or leaves the boundary, and none comes closer
    # to a block than the start or goal itself (less the planner's 0.1 % sliver).
    closed = ROOM.replace(boundary=ROOM.boundary + np.repeat([-1e-9, 1e-9], 3))
    assert closed.segments_free(np.stack([track[:-1], track[1:]], axis=1)).all()
    own = min(point_margins(ROOM, [start, goal], boundary=False))
    assert polyline_margin(ROOM, track, boundary=False) >= min(MARGIN, 0.999 * own) - 1e-9
    # Between the legs the moves keep the fence: from the end of the start leg to the
    # start of the goal leg (whole centimetres from them).
    fence = plan.fence
    targets = track[2:-1]
    first = int(np.argmin(np.linalg.norm(targets - problem.search_start, axis=1)))
    last = int(np.argmin(np.linalg.norm(targets - problem.search_goal, axis=1)))
    assert np.linalg.norm(targets[first] - problem.search_start) < 0.01
    between = targets[first:last + 1]
    assert fence.free_world.segments_free(np.stack([between[:-1], between[1:]], axis=1)).all()
    assert "nothing was sent" in message


def test_rc_dry_run_flies_the_leg_out_of_a_pocket_within_its_room(tmp_path):
    plan = planned(IN_THE_POCKET)
    commands, message = dry_run(plan, "rc", tmp_path)
    sticks = np.array([[int(v) for v in c.split()[1:]] for c in commands[2:-1]])
    velocities = np.array([stick_velocity(s, 0.0) for s in sticks])
    flown = plan.takeoff_point + np.cumsum(velocities, axis=0) / 20  # 20 Hz, exactly
    before = np.vstack([plan.takeoff_point, flown[:-1]])
    assert np.linalg.norm(flown[-1, :2] - plan.route.points[-1, :2]) <= GOAL_TOLERANCE
    # The drone climbs along the wall and leaves the pocket inside the pocket's room, and a
    # link lost after any stick leaves it in that room (never closer to the wall piece than
    # the start, never outside); out of the pocket, in the fence.
    assert int(np.flatnonzero(plan.fence.contains(flown))[0]) > 20
    assert point_margins(ROOM, flown, boundary=False).min() >= plan.start_room.clearance
    assert flown[:, 0].min() >= 0.0
    room, fence = LostLinkBound(plan.start_room), LostLinkBound(plan.fence)
    for position, velocity in zip(before, velocities, strict=True):
        assert room.is_safe(position, velocity)
        assert position[0] < 0.5 or fence.is_safe(position, velocity)
    assert "nothing was sent" in message


def test_a_stick_along_a_wall_survives_a_correction_towards_the_block():
    bound = LostLinkBound(planned(IN_THE_POCKET).start_room)
    position, velocity = [0.0, 1.4, 1.2], [0.002, -0.05, 0.0]  # towards the wall piece
    assert not bound.is_safe(position, velocity)  # 15 s of 2 mm/s: into the wall piece
    limited = bound.limit(position, velocity)
    assert bound.is_safe(position, limited)
    assert limited[1] == pytest.approx(-0.05) and 0.0 <= limited[0] < 1e-5


def test_a_heading_off_the_axes_cannot_follow_a_leg_along_a_wall(tmp_path):
    plan = planned(IN_THE_POCKET, yaw=math.radians(30))  # accepted: the same query rule
    with pytest.raises(MoveError, match=r"the room of the start leg \(whole centimetres in "
                                        r"the frame of the drone's heading, 30 degrees"):
        plan.go_moves(TAKEOFF_HEIGHT, 50)
    with pytest.raises(RcModeError, match=r"rc mode cannot fly this plan: its sticks .* get "
                                          r"no further than .*nothing was sent"):
        fly(plan, BridgeSettings(mode="rc"), tmp_path / "out")
    assert not (tmp_path / "out").exists()


def test_a_takeoff_beside_a_block_is_still_refused():
    beside = ROOM.replace(blocks=[[1, 1, 0, 2, 2, 1.2]])  # the start 0.05 m from it, above
    with pytest.raises(GeofenceError, match=r"the takeoff from \(0.95, 1.5, 0\) to \(0.95, "
                                            r"1.5, 0.8\) comes within 0.1 m of block 0"):
        plan_flight(beside, (0.95, 1.5, 1.5), GOAL, MARGIN, 0.0,
                    planning=PlannerSettings(seed=0, max_iterations=2000))


@needs_netns
def test_emulated_mission_from_a_pocket_lands_at_the_goal(client_ns, tmp_path):
    plan = planned(IN_THE_POCKET)
    flown, drone = emulated_flight(plan, client_ns, tmp_path)
    outcome = flown.outcome
    assert outcome.status is Status.LANDED, outcome.message
    assert_on_the_floor(drone, GOAL)
    _, positions = drone.track()
    # Out of the pocket along the wall, 0.1 m from the wall piece: never touching it.
    assert point_margins(ROOM, positions, boundary=False).min() > 0.09
    assert positions[:, 0].min() > -0.005
    heard = [text.split()[0] for _, text in drone.commands_received()]
    assert heard[:2] == ["command", "takeoff"] and set(heard[2:-1]) == {"go"}

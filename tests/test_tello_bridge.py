"""``quadnav tello fly``: frames, ``go`` moves, the geofence, rc sticks, dry runs, and whole
missions flown by the real djitellopy client against the Tello emulator (see
:mod:`tellotools`; faults are in ``test_tello_faults.py``).

The emulator runs ten times faster than real time; the ``rc`` feedback still gets a state
packet every emulated second, enough for the dead reckoning at the bounded stick speeds.
"""

from __future__ import annotations

import argparse
import io
import json
import math

import numpy as np
import pytest
from clitools import assert_user_error, run, run_here
from hypothesis import given
from hypothesis import strategies as st
from tellotools import (
    MAP,
    MARGIN,
    ROOM,
    START_GOAL,
    assert_kept_the_fence,
    assert_on_the_floor,
    emulated_flight,
    needs_netns,
    planned_room,
)

from quadnav.cli.tello_fly_command import exit_code, ipv4, percent, tello_speed
from quadnav.hardware import sdk
from quadnav.hardware.arc import Arc
from quadnav.hardware.bridge.curves import TOLERANCE_CM, Curve
from quadnav.hardware.bridge.dead_reckoning import (
    HALF_UNIT,
    MOVE_VARIANCE,
    DeadReckoning,
    Estimate,
    clip_step,
    step_bound,
    step_slack,
)
from quadnav.hardware.bridge.flight import (
    GOAL_TOLERANCE,
    LANDING_TOLERANCE,
    BridgeSettings,
    Status,
    fly,
    landed,
)
from quadnav.hardware.bridge.flight_plan import (
    TAKEOFF_HEIGHT,
    TRACKING_ALLOWANCE,
    SavedPlan,
    plan_flight,
)
from quadnav.hardware.bridge.frames import TakeoffFrame, body_to_map, map_to_body, to_cm, to_m
from quadnav.hardware.bridge.geofence import Geofence, GeofenceError
from quadnav.hardware.bridge.lost_link import LostLinkBound
from quadnav.hardware.bridge.moves import (
    DETOUR_CM,
    GO_MAX_CM,
    Move,
    MoveError,
    go_moves,
    go_speed,
    is_long_enough,
)
from quadnav.hardware.bridge.rc import (
    RC_FULL_SPEED,
    StickRounder,
    stick_values,
    stick_velocity,
    tracking_velocity,
)
from quadnav.planning import PlannerSettings
from quadnav.runs import read_run
from quadnav.trajectory.generate import TrajectorySettings
from quadnav.trajectory.references.sampled import read_reference_file
from quadnav.world import World, load_world
from quadnav.world.placement import format_point

ALWAYS = lambda start, end, segments: True  # noqa: E731  (a geofence that allows all)


def land_on(moves: list[Move]) -> np.ndarray:
    """Where a list of moves ends, from the origin, cm."""
    return np.sum([m.step for m in moves], axis=0) if moves else np.zeros(3, dtype=int)


# --- frames ----------------------------------------------------------------------------


def test_map_and_takeoff_frames():
    east, north = np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])
    # Facing +x: forward is +x, left is +y. Facing +y: forward is +y, right is +x.
    assert np.allclose(map_to_body(north, 0.0), [0, 1, 0])
    assert np.allclose(map_to_body(north, math.pi / 2), [1, 0, 0])
    assert np.allclose(map_to_body(east, math.pi / 2), [0, -1, 0])
    assert np.allclose(map_to_body([0.0, 0.0, 2.0], 1.0), [0, 0, 2])  # up stays up
    vectors = np.random.default_rng(0).normal(size=(50, 3))
    for yaw in (-2.0, 0.3, math.pi):
        assert np.allclose(body_to_map(map_to_body(vectors, yaw), yaw), vectors)
        assert np.allclose(np.linalg.norm(map_to_body(vectors, yaw), axis=1),
                           np.linalg.norm(vectors, axis=1))
    frame = TakeoffFrame.under([1.0, 2.0, 0.7], math.pi / 2)
    assert frame.origin == (1.0, 2.0, 0.0)  # on the floor under the start
    assert np.allclose(frame.to_body([1.0, 3.0, 0.8]), [1.0, 0.0, 0.8])
    assert frame.to_body_cm([1.004, 3.456, 0.8]).tolist() == [146, -0, 80]
    assert np.allclose(frame.cm_to_map([146, 0, 80]), [1.0, 3.46, 0.8])


def test_centimetre_rounding():
    assert to_cm([1.234, -0.456, 0.0049, -0.0051]).tolist() == [123, -46, 0, -1]
    assert to_cm(0.5).dtype == np.int64 and to_m([150, -20]).tolist() == [1.5, -0.2]


# --- go moves ----------------------------------------------------------------------------


def test_a_long_step_is_split_within_the_sdk_limits():
    moves = go_moves([[0, 0, 0], [1200, -700, 30]], 50, ALWAYS)
    assert len(moves) == 3 and land_on(moves).tolist() == [1200, -700, 30]
    assert all(np.abs(m.step).max() <= GO_MAX_CM for m in moves)
    assert [m.command for m in moves] == ["go 400 -233 10 50", "go 400 -234 10 50",
                                          "go 400 -233 10 50"]


def test_a_short_step_is_merged_into_the_next():
    moves = go_moves([[0, 0, 0], [15, 0, 0], [100, 20, 0], [400, 20, 0]], 80, ALWAYS)
    assert [m.command for m in moves] == ["go 100 20 0 80", "go 300 0 0 80"]
    # Merging skips [15, 0, 0] and also the corner [100, 20, 0] when the fence allows it.
    straight = go_moves([[0, 0, 0], [15, 0, 0], [30, 0, 0]], 80, ALWAYS)
    assert [m.command for m in straight] == ["go 30 0 0 80"]


def test_a_short_last_step_becomes_a_detour_inside_the_fence():
    moves = go_moves([[0, 0, 0], [300, 0, 0], [310, 5, 0]], 50, ALWAYS)
    assert [m.command for m in moves] == ["go 300 0 0 50", f"go 10 5 {DETOUR_CM} 50",
                                          f"go 0 0 -{DETOUR_CM} 50"]

    def below_ceiling(start, end, segments):  # nothing above z = 10 cm: the detour goes down
        return max(start[2], end[2]) <= 10

    moves = go_moves([[0, 0, 0], [300, 0, 0], [310, 5, 0]], 50, below_ceiling)
    assert moves[1].z == -DETOUR_CM and land_on(moves).tolist() == [310, 5, 0]

    def corridor(start, end, segments):  # only forward along x, up to x = 310 cm
        return (start[1] == end[1] == 0 and start[2] == end[2] == 0
                and start[0] <= end[0] <= 310)

    overshoot = go_moves([[0, 0, 0], [300, 0, 0], [310, 0, 0]], 50, ALWAYS)
    assert [m.command for m in overshoot][1:] == [f"go 10 0 {DETOUR_CM} 50",
                                                  f"go 0 0 -{DETOUR_CM} 50"]
    with pytest.raises(MoveError, match="within"):
        go_moves([[0, 0, 0], [300, 0, 0], [310, 0, 0]], 50, corridor)
    with pytest.raises(MoveError, match="leaves the geofence"):
        go_moves([[0, 0, 0], [0, 300, 0]], 50, corridor)


@pytest.mark.parametrize(("step", "speed"), [((10, 10, 10), 50), ((20, -20, 20), 50),
                                             ((501, 0, 0), 50), ((100, 0, 0), 9),
                                             ((100, 0, 0), 101)])
def test_moves_outside_the_sdk_limits_are_refused(step, speed):
    with pytest.raises(MoveError, match="outside the SDK's limits"):
        Move(*step, speed=speed)
    with pytest.raises(sdk.SdkError):  # and the emulator's firmware refuses them too
        sdk.parse_command(f"go {step[0]} {step[1]} {step[2]} {speed}")


def test_go_speed_is_clamped_to_the_sdk_range():
    assert [go_speed(v) for v in (0.01, 0.456, 0.5, 3.0)] == [10, 46, 50, 100]
    assert not is_long_enough([20, -20, 0]) and is_long_enough([0, 0, -21])


@given(st.lists(st.tuples(*[st.integers(-900, 900)] * 3), min_size=2, max_size=12),
       st.integers(10, 100))
def test_any_waypoints_become_moves_the_firmware_accepts(points, speed):
    points = np.array(points)
    moves = go_moves(points, speed, ALWAYS)
    assert (land_on(moves) == points[-1] - points[0]).all()
    for move in moves:
        assert sdk.parse_command(move.command).name == "go"


# --- the geofence ------------------------------------------------------------------------


@pytest.fixture
def room() -> Geofence:
    """A 4 x 4 x 2 m room with one 1 m box at (2..3, 2..3, 0..1), fenced 0.2 m in."""
    return Geofence(World([0, 0, 0, 4, 4, 2], [[2, 2, 0, 3, 3, 1]], name="room"), 0.2)


def test_the_fence_is_the_map_shrunk_by_the_margin(room):
    inside = room.contains([[1, 1, 1], [1.79, 2.5, 0.5], [1.81, 2.5, 0.5], [0.19, 1, 1],
                            [1, 1, 1.81], [2.5, 2.5, 1.21], [2.5, 2.5, 1.19]])
    assert inside.tolist() == [True, True, False, False, False, True, False]
    assert room.point_ok([1, 1, 1]) and not room.point_ok([1, 1, 0.1])
    # Exact: a straight move passing 1e-9 m outside the grown box's edge is allowed.
    assert room.segment_ok([1.8 - 1e-9, 1, 0.5], [1.8 - 1e-9, 3.5, 0.5])
    assert not room.segment_ok([1.8 + 1e-9, 1, 0.5], [1.8 + 1e-9, 3.5, 0.5])


def test_refusals_name_the_move_and_what_it_comes_near(room):
    with pytest.raises(GeofenceError, match=r"the route from \(1, 2.5, 0.5\) to \(3.5, 2.5, "
                                            r"0.5\) comes within 0.2 m of block 0 \[2, 3\]"):
        room.check_track([[1, 2.5, 0.5], [3.5, 2.5, 0.5]], "the route")
    with pytest.raises(GeofenceError, match=r"the climb .* of the boundary"):
        room.check_track([[1, 1, 1], [1, 1, 1.9]], "the climb")


def test_takeoff_and_landing_columns(room):
    assert room.column_ok([1, 1, 0], [1, 1, 0.8])  # through the floor's margin
    assert not room.column_ok([1, 1, 0], [1, 1.5, 0.8])  # not vertical
    assert not room.column_ok([1.9, 2.5, 0], [1.9, 2.5, 0.8])  # beside the box
    assert not room.column_ok([1, 1, 0], [1, 1, 1.9])  # into the ceiling's margin
    assert not room.column_ok([1, 1, -0.01], [1, 1, 0.8])  # under the floor
    with pytest.raises(GeofenceError, match="the takeoff"):
        room.check_column([1.9, 2.5, 0], [1.9, 2.5, 0.8], "the takeoff")


# --- rc sticks and dead reckoning -------------------------------------------------------


def test_rc_sticks_are_percent_of_full_speed_with_the_sdk_signs():
    # Facing +x: +y is left, so the right/left stick is negative.
    assert np.allclose(stick_values([0.5, 0.0, 0.0], 0.0), [0, 50, 0])
    assert np.allclose(stick_values([0.0, 0.5, 0.0], 0.0), [-50, 0, 0])
    assert np.allclose(stick_values([0.0, 0.0, -0.3], 0.0), [0, 0, -30])
    assert np.allclose(stick_values([0.0, 0.5, 0.0], math.pi / 2), [0, 50, 0])
    assert np.allclose(stick_values([RC_FULL_SPEED, 0, 0], 0.0), [0, 100, 0])
    rounder = StickRounder()
    sent = np.array([rounder([0.4, -12.7, 150.0]) for _ in range(10)])
    assert sent[:, 0].sum() == 4 and sent[:, 1].sum() == -127  # rounding errors carried
    assert (sent[:, 2] == 100).all() and (sent[:, 3] == 0).all()  # clamped; no yaw
    for yaw in (0.0, 1.0):
        assert np.allclose(stick_velocity(stick_values([0.3, -0.2, 0.1], yaw), yaw),
                           [0.3, -0.2, 0.1])
    # Sticks not allowed (the lost-link bound): as few axes as need be go towards zero.
    no_climb = StickRounder()
    assert no_climb([3.6, 2.2, 0.7], lambda s: s[2] == 0) == (4, 2, 0, 0)
    assert no_climb([3.6, 2.2, 0.7], lambda s: False) == (0, 0, 0, 0)
    # Near the edge of what is allowed, sticks are halved rather than centred.
    assert StickRounder()([30.0, 20.0, 0.0], lambda s: np.abs(s).max() <= 8) == (7, 5, 0, 0)


def test_tracking_velocity_corrects_towards_the_reference_and_is_capped():
    v = tracking_velocity([1.0, 0, 1], [0.2, 0, 0], [0.9, 0, 1], gain=1.0)
    assert np.allclose(v, [0.3, 0, 0])
    assert np.linalg.norm(tracking_velocity([5.0, 0, 1], [0.5, 0, 0], [0, 0, 1], 1.0)) == \
        pytest.approx(RC_FULL_SPEED)


def test_dead_reckoning_keeps_within_what_the_reports_allow():
    # A step asked for is kept when the reports allow it, else clipped to them.
    assert np.allclose(clip_step([0.46, 0.0, 0.0], [0.5, 0.0, 0.0], 0.05), [0.46, 0, 0])
    assert np.allclose(clip_step([0.30, 0.0, 0.0], [0.5, 0.0, 0.0], 0.05), [0.45, 0, 0])
    estimate = DeadReckoning(TakeoffFrame.under([1.0, 2.0, 0.0], math.pi / 2))
    state = {"mid": -2, "x": -200, "y": -200, "z": -200, "yaw": 0, "vgx": 0, "vgy": 0,
             "vgz": 0, "h": 80}
    estimate.update(state)
    assert np.allclose(estimate.position(), [1.0, 2.0, 0.8])
    estimate.update({**state, "mid": 1, "x": 50, "y": -20, "z": 90})  # over a mission pad
    assert np.allclose(estimate.position(), [1.2, 2.5, 0.9])  # forward is +y on the map
    estimate.update({"bat": 50})  # not a full packet: ignored
    assert len(estimate.track()) == 2


class ReplayClock:
    """A wall clock that stands still until moved on (replays packets at chosen times)."""

    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


HOVER = {"mid": -2, "x": -200, "y": -200, "z": -200, "yaw": 0, "vgx": 0, "vgy": 0,
         "vgz": 0, "h": 80}


def replay(estimate: DeadReckoning, clock: ReplayClock, speeds, dt: float = 1.0) -> None:
    """Packets every ``dt`` s reporting forward speeds ``speeds`` (whole dm/s)."""
    for vgx in speeds:
        clock.now += dt
        estimate.update({**HOVER, "vgx": vgx})


def test_the_uncertainty_grows_with_each_step_by_what_the_reports_allow():
    clock = ReplayClock()
    estimate = DeadReckoning(TakeoffFrame.under([0.0, 0.0, 0.0], 0.0), clock=clock)
    estimate.update({**HOVER, "vgx": 5})
    assert estimate.estimate().sigma == 0.0
    replay(estimate, clock, [5, 5, 5, 5], dt=0.5)  # four steps at a steady 0.5 m/s ...
    steady = 4 * 2 * (HALF_UNIT * 0.5) ** 2 / 3  # ... each within half a unit on x and y
    assert np.allclose(estimate.position(), [1.0, 0, 0.8])
    assert estimate.estimate().sigma == pytest.approx(math.sqrt(steady))
    clock.now += 0.5
    estimate.update(HOVER)  # stopped: the change may have come anywhere in the step
    slack = step_slack([0.5, 0, 0], [0, 0, 0], 0.5)
    assert slack[0] == pytest.approx((HALF_UNIT + 0.25) * 0.5)
    assert np.allclose(estimate.position(), [1.125, 0, 0.8])
    assert estimate.estimate().sigma == pytest.approx(
        math.sqrt(steady + np.sum(slack[:2] ** 2) / 3))


@pytest.mark.parametrize(("speeds", "dt", "moved"), [
    ([2, 4, 3, 0], 1.0, 1.0),  # reckoned 0.9 m, and the reports allow the move's 1 m: taken
    ([0, 0, 0], 1.0, 1.0),  # a second between packets: a whole move may hide between them
    ([0] * 20, 0.1, 20 * step_bound(0.1) + step_bound(0.05)),  # it never moved: as far as
])                                                               # the reports allow
def test_a_move_answered_ok_is_taken_in_within_what_the_reports_allow(speeds, dt, moved):
    clock = ReplayClock()
    estimate = DeadReckoning(TakeoffFrame.under([1.0, 2.0, 0.0], math.pi / 2), clock=clock)
    estimate.update(HOVER)
    estimate.begin_move([1.0, 0.0, 0.0])  # go 100 0 0 ...: forward, +y on the map
    replay(estimate, clock, speeds, dt)
    assert estimate.position()[1] - 2.0 == pytest.approx(0.1 * sum(speeds) * dt)
    clock.now += dt / 2
    estimate.end_move()  # the ok, half a step after the last packet
    assert moved <= 1.0 and np.allclose(estimate.position(), [1.0, 2.0 + moved, 0.8])
    # the move's end is known to its accuracy, or to the reports' if they say more
    velocities = [0.0, *(0.1 * v for v in speeds), 0.0]  # at the ok: stopped
    seconds = [dt] * len(speeds) + [dt / 2]
    steps = sum(np.sum(step_slack([a, 0, 0], [b, 0, 0], t)[:2] ** 2) / 3
                for a, b, t in zip(velocities, velocities[1:], seconds, strict=False))
    assert estimate.estimate().sigma == pytest.approx(math.sqrt(min(steps, MOVE_VARIANCE)))


@pytest.mark.parametrize(("off", "status", "code"), [(0.05, Status.LANDED, 0),
                                                    (0.15, Status.OFF_GOAL, 1)])
def test_the_verdict_is_the_dead_reckoned_landing_within_the_tolerance(off, status, code):
    plan = planned_room()
    place = Estimate(plan.landing_ground + np.array([0.0, off, 0.0]), 0.04)
    outcome = landed(plan, "1 go moves", place)
    assert outcome.status is status and exit_code(outcome) == code
    assert outcome.landing is place  # one place: what the message says, the metrics hold
    assert outcome.message.startswith(
        f"landed at {format_point(place.point)} +- 0.04 m, {off:.2f} m from the goal")
    assert (f"beyond its {LANDING_TOLERANCE:g} m tolerance" in outcome.message) == bool(code)


# --- the plan ----------------------------------------------------------------------------


def test_the_plan_takes_off_under_the_start_and_lands_under_the_goal(course):
    _, start, goal, plan = course
    assert np.allclose(plan.takeoff_ground, [start[0], start[1], 0.0])
    assert np.allclose(plan.takeoff_point, [start[0], start[1], TAKEOFF_HEIGHT])
    route, pruned = plan.route.points, plan.pruned.points
    assert np.allclose(route[0, :2], start[:2]) and np.allclose(route[-1, :2], goal[:2])
    assert np.allclose(plan.landing_ground, [goal[0], goal[1], 0.0])
    assert plan.problem.margin == pytest.approx(MARGIN + TRACKING_ALLOWANCE)
    assert plan.fence.contains(route).all() and plan.fence.contains(pruned).all()
    assert np.allclose(plan.trajectory.position(0.0), plan.takeoff_point)
    assert np.allclose(plan.trajectory.position(plan.trajectory.duration), route[-1])
    assert len(pruned) < len(route)
    assert {tuple(p) for p in pruned} <= {tuple(p) for p in route}


@pytest.mark.parametrize("height", [0.8, 0.63, 1.07, 0.15])  # 0.15: under the fence
def test_go_moves_start_at_the_reported_height_and_end_above_the_goal(course, height):
    *_, plan = course
    moves = plan.go_moves(height, 50)
    end = to_cm([0.0, 0.0, height]) + land_on(moves)
    assert end.tolist() == plan.frame.to_body_cm(plan.route.points[-1]).tolist()
    assert all(sdk.parse_command(m.command).name == "go" for m in moves)


def test_a_plan_that_would_leave_the_fence_is_refused():
    low = World([0, 0, 0, 6, 3, 0.9], name="low room")  # takeoff height 0.8 > 0.9 - 0.2
    with pytest.raises(GeofenceError, match="the takeoff"):
        plan_flight(low, [1, 1, 0], [5, 2, 0], MARGIN, 0.0)


# --- dry runs ----------------------------------------------------------------------------


def test_cli_dry_run_prints_every_command_and_sends_nothing(shared_maps, tmp_path):
    result = run("tello", "fly", shared_maps / MAP, "--start-goal", shared_maps / START_GOAL,
                 "--dry-run", "--yaw", "90", "--quiet", "-o", tmp_path)
    assert result.returncode == 0, result.stderr
    assert result.stderr == ""
    lines = result.stdout.splitlines()
    commands = lines[:lines.index("land") + 1]
    assert commands[:3] == ["command", "takeoff", "go 0 0 -48 50"]  # down to 31.5 cm
    for command in commands[2:-1]:
        assert sdk.parse_command(command).name == "go"
    assert "dry run" in lines[-2] and "nothing was sent" in lines[-2]
    records = [json.loads(line) for line in (tmp_path / "tello_log.jsonl").open()]
    assert records[0]["kind"] == "start" and records[0]["dry_run"]
    assert [r["text"] for r in records if r["kind"] == "command"] == commands
    assert (tmp_path / "tello_track.png").stat().st_size > 0


def test_a_saved_path_is_flown_as_given_through_the_same_checks(tmp_path):
    room = tmp_path / "room.txt"
    room.write_text(ROOM)
    saved = tmp_path / "mine.csv"  # a student's own path: a dog-leg through the room
    saved.write_text("x,y,z\n0.5,1,0.8\n2,1.3,1.0\n3.5,1,0.8\n")
    result = run("tello", "fly", room, "--path", saved, "--dry-run", "--quiet",
                 "-o", tmp_path / "out")
    assert result.returncode == 0, result.stderr
    flown = read_run(tmp_path / "out")
    assert flown.metrics["planner"] == "saved path" and flown.tree_nodes.shape == (0, 3)
    assert np.allclose(flown.path[2:-1], [[0.5, 1, 0.8], [2, 1.3, 1.0], [3.5, 1, 0.8]])
    moves = [line for line in result.stdout.splitlines() if line.startswith("go ")]
    assert len(moves) >= 2  # the corner at (2, 1.3, 1) is flown, not cut

    near_wall = tmp_path / "near.csv"  # 0.25 m from the ceiling: inside margin + allowance
    near_wall.write_text("x,y,z\n0.5,1,0.8\n2,1,1.25\n3.5,1,0.8\n")
    assert_user_error(run_here("tello", "fly", room, "--path", near_wall, "--dry-run",
                          "-o", tmp_path / "refused"),
                      f"{near_wall}: the segment (0.5, 1, 0.8) -> (2, 1, 1.25) comes closer "
                      "than 0.3 m", "the path keeps 0.25 m; fly it with --margin 0.15 or less")
    assert not (tmp_path / "refused").exists()
    assert_user_error(run_here("tello", "fly", room, "--path", saved, "--goal", "3", "1", "1",
                          "--dry-run", "-o", tmp_path / "refused"),
                      "leave out --start, --goal and --start-goal")
    saved.write_text("x,y\n1,2\n")
    assert_user_error(run_here("tello", "fly", room, "--path", saved, "--dry-run",
                          "-o", tmp_path / "refused"), f"{saved}:1:", "x,y,z")


def test_a_saved_trajectory_is_followed_as_timed_through_the_same_checks(tmp_path):
    room = tmp_path / "room.txt"
    room.write_text(ROOM)
    assert run_here("plan", room, "--start", "0.5", "1", "0.8", "--goal", "3.5", "1", "0.8",
               "--margin", "0.3", "--quiet", "-o", tmp_path / "p").returncode == 0
    assert run_here("traj", room, "--path", tmp_path / "p" / "path.csv", "--speed", "0.5",
               "-o", tmp_path / "t").returncode == 0
    saved = tmp_path / "t" / "trajectory.csv"
    reference = read_reference_file(saved)
    plan = plan_flight(load_world(room), None, None, MARGIN, 0.0,
                       saved=SavedPlan(reference.samples.position, str(saved), reference.motion))
    begin, end = plan.trajectory.main_window
    assert end - begin == pytest.approx(reference.duration)
    t = np.linspace(0.0, reference.duration, 50)
    assert np.allclose(plan.trajectory.position(begin + t), reference.position(t), atol=1e-9)
    result = run("tello", "fly", room, "--trajectory", saved, "--mode", "rc", "--dry-run",
                 "--quiet", "-o", tmp_path / "rc")
    assert result.returncode == 0, result.stderr
    assert "rc commands" in result.stdout

    floor = tmp_path / "floor.csv"  # a trajectory from the floor: inside the margin
    rows = (tmp_path / "t" / "trajectory.csv").read_text().splitlines()
    first = rows[1].split(",")
    first[3] = "0"
    floor.write_text("\n".join([rows[0], ",".join(first), *rows[2:]]) + "\n")
    assert_user_error(run_here("tello", "fly", room, "--trajectory", floor, "--dry-run",
                          "-o", tmp_path / "refused"),
                      f"{floor}: the trajectory starts at (0.5, 1, 0), inside the 0.3 m margin",
                      "fly its path with --path")
    assert_user_error(run_here("tello", "fly", room, "--trajectory", saved, "--path", saved,
                          "--dry-run", "-o", tmp_path / "refused"), "give one saved plan")
    assert not (tmp_path / "refused").exists()


def test_curves_follow_the_trajectory_within_the_tolerance_inside_the_fence():
    """On a curved trajectory (the forest's: it climbs and dips between waypoints), the
    curves mode flies arcs that stay within 5 cm of it and every centimetre in the fence,
    with a few dozen commands where rc needs thousands."""
    world = load_world("forest")
    plan = plan_flight(world, world.start, world.goal, MARGIN, 0.0,
                       planning=PlannerSettings(seed=0, max_iterations=3000, time_limit=10),
                       trajectory=TrajectorySettings(v_max=0.5, a_max=1.0))
    commands = plan.curve_moves(TAKEOFF_HEIGHT, plan.speed)
    arcs = [c for c in commands if isinstance(c, Curve)]
    assert arcs and len(commands) < 40
    for command in commands:
        sdk.parse_command(command.command)  # within the SDK's limits (radius included)
    # Replay the commands in the takeoff frame from the takeoff and check each arc against
    # the trajectory and the fence, independently of the fitting.
    here = np.array([0.0, 0.0, 100.0 * TAKEOFF_HEIGHT])
    track = 100.0 * plan.frame.to_body(plan.trajectory.position(
        np.linspace(0.0, plan.trajectory.duration, 20_000)))
    for command in commands:
        if isinstance(command, Curve):
            arc = Arc(here, here + command.via, here + command.end)
            points = arc.at(np.linspace(0.0, arc.length, 200))[0]
            assert plan.fence.contains(plan.frame.cm_to_map(points)).all()
            near = np.linalg.norm(points[:, None, :] - track[None, ::10], axis=2).min(axis=1)
            assert near.max() < TOLERANCE_CM + 2.0  # the trajectory sampled every ~1 cm
        here = here + command.step


def test_rc_dry_run_streams_sticks_at_20_hz_within_the_lost_link_bound(course, tmp_path):
    *_, plan = course
    out = io.StringIO()
    flown = fly(plan, BridgeSettings(mode="rc"), tmp_path, stream=out)
    outcome, track = flown.outcome, flown.track
    assert outcome.status is Status.DRY_RUN and len(track) == 0
    lines = out.getvalue().splitlines()
    sticks = np.array([[int(v) for v in line.split()[1:]] for line in lines[2:-1]])
    assert lines[:2] == ["command", "takeoff"] and lines[-1] == "land"
    assert np.abs(sticks).max() <= 100 and (sticks[:, 3] == 0).all()
    seconds = float(outcome.message.split(" rc commands over ")[1].split()[0])
    assert len(sticks) == pytest.approx(20 * seconds, abs=2)  # 20 a second (t to 0.1 s)
    # A dry run's drone flies the sticks exactly, from the takeoff point, 20 a second:
    # their sum is the trajectory's way (takeoff frame, yaw 0: right = -y) ...
    velocities = np.array([stick_velocity(s, 0.0) for s in sticks])
    flown = plan.takeoff_point + np.cumsum(velocities, axis=0) / 20
    assert np.linalg.norm(flown[-1, :2] - plan.route.points[-1, :2]) <= GOAL_TOLERANCE
    # ... and a link lost after any one of them leaves the drone inside the fence, which
    # slows the flight down: 0.5 m/s is too fast for 15 s near the course's walls.
    bound = LostLinkBound(plan.fence)
    starts = np.vstack([plan.takeoff_point, flown[:-1]])
    assert all(bound.is_safe(p, v) for p, v in zip(starts, velocities, strict=True))
    assert not bound.is_safe(plan.takeoff_point, [0.0, 0.5, 0.0])
    assert 2 * plan.trajectory.duration < len(sticks) / 20 < 4 * plan.trajectory.duration
    assert "slowed where a lost link could otherwise leave the geofence" in outcome.message


def test_cli_bad_flags_are_one_line_errors(tmp_path):
    assert_user_error(run_here("tello", "fly", "forest", "--dry-run", "--speed", "2", "-o", tmp_path),
                      "--speed", "expected from 0.01 to 1 m/s")
    for check, text, message in ((tello_speed, "0", "from 0.01 to 1 m/s"), (ipv4, "drone", "IPv4"),
                                 (ipv4, "192.168.10.256", "IPv4"), (percent, "120", "0..100"),
                                 (percent, "half", "whole percentage")):
        with pytest.raises(argparse.ArgumentTypeError, match=message):
            check(text)
    assert (tello_speed("1"), ipv4("198.18.67.1"), percent("20")) == (1.0, "198.18.67.1", 20)


def test_cli_refuses_a_plan_outside_the_fence(tmp_path):
    low = tmp_path / "low.txt"
    low.write_text("boundary 0 0 0 6 3 0.9\n")
    assert_user_error(run_here("tello", "fly", low, "--start", "1", "1", "0", "--goal", "5", "2",
                          "0", "--dry-run", "--quiet", "-o", tmp_path / "out"),
                      "geofence", "the takeoff", "nothing was sent")
    assert not (tmp_path / "out").exists()


# --- the real client against the emulator --------------------------------------------------


@needs_netns
def test_the_first_move_starts_from_the_height_after_the_takeoff(client_ns, tmp_path):
    # At 40 times real time a state packet (10 a wall-clock second) is 4 s of drone time
    # apart, twice a takeoff: the last one before the takeoff's ``ok`` was sent during the
    # climb or before it, and a height read from it sent the drone up to 0.8 m too high.
    plan = planned_room()
    flown, drone = emulated_flight(plan, client_ns, tmp_path, "waypoints", 40.0)
    assert flown.outcome.status is Status.LANDED, flown.outcome.message
    _, positions = drone.track()
    assert positions[:, 2].max() == pytest.approx(TAKEOFF_HEIGHT, abs=0.03)


@needs_netns
@pytest.mark.parametrize("mode", ["waypoints", "curves", "rc"])
def test_whole_mission_on_the_emulator(request, client_ns, tmp_path, mode):
    # rc on the course takes 84 s of drone time (its dry run above): the room's is shorter,
    # and flown at half the time scale, as the rc feedback runs at 20 Hz of drone time.
    if mode != "rc":
        *_, plan = request.getfixturevalue("course")
        scale = 10.0
    else:
        plan, scale = planned_room(), 5.0
    flown, drone = emulated_flight(plan, client_ns, tmp_path, mode, scale)
    outcome, track = flown.outcome, flown.track
    assert outcome.status is Status.LANDED, outcome.message
    _, positions = drone.track()
    assert_kept_the_fence(plan, positions)
    assert_on_the_floor(drone, plan.landing_ground)
    assert positions[:, 2].max() == pytest.approx(TAKEOFF_HEIGHT, abs=0.03)
    heard = drone.commands_received()
    names = [text.split()[0] for _, text in heard]
    assert names[:2] == ["command", "takeoff"] and names[-1] == "land"
    if mode == "waypoints":
        assert set(names[2:-1]) == {"go"}
    elif mode == "curves":
        assert set(names[2:-1]) == {"go", "curve"}
        assert len(names) - 3 <= 2 * len(plan.go_moves(TAKEOFF_HEIGHT, 50))
    else:
        # (The 20 Hz schedule is checked by the dry run: here a busy machine may delay it.)
        # The dead-reckoned estimate followed the emulated drone to within a few cm.
        assert np.linalg.norm(track[-1, 1:3] - positions[-1, :2]) < 0.05
    records = [json.loads(line) for line in (tmp_path / "tello_log.jsonl").open()]
    kinds = {r["kind"] for r in records}
    assert kinds == {"start", "command", "reply", "state", "event"}
    assert [r["text"] for r in records if r["kind"] == "command"] == [c for _, c in heard]
    assert np.all(np.diff([r["t"] for r in records]) >= 0)
    assert (tmp_path / "tello_track.png").stat().st_size > 0

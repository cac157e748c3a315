"""``quadnav tello fly``: frames, ``go`` moves, the geofence, rc sticks, dry runs, and whole
missions flown by the real djitellopy client against the Tello emulator.

The emulator runs ``time_scale`` times faster than real time (10 for ``go`` moves, 5 for
``rc``, whose feedback needs the state packets, which come ten times a wall-clock
second). djitellopy's sockets live in a network namespace private to this process
(:func:`djitellopy_namespace`), so parallel workers never share port 8889. What the drone
really did is read from the emulator: its track (world frame) and the commands it heard.
"""

from __future__ import annotations

import argparse
import io
import json
import math
import signal
import subprocess
import time
from functools import cache
from pathlib import Path

import numpy as np
import pytest
from clitools import QUADNAV, assert_user_error, run
from hypothesis import given
from hypothesis import strategies as st

from quadnav.cli.tello_fly_command import ipv4, percent, tello_speed
from quadnav.hardware import sdk
from quadnav.hardware.bridge import BridgeSettings, Status, fly
from quadnav.hardware.dead_reckoning import DeadReckoning, clip_step
from quadnav.hardware.flight_plan import TAKEOFF_HEIGHT, TRACKING_ALLOWANCE, plan_flight
from quadnav.hardware.frames import TakeoffFrame, body_to_map, map_to_body, to_cm, to_m
from quadnav.hardware.geofence import Geofence, GeofenceError
from quadnav.hardware.moves import (
    DETOUR_CM,
    GO_MAX_CM,
    Move,
    MoveError,
    go_moves,
    go_speed,
    is_long_enough,
)
from quadnav.hardware.netns import NetNamespace, unavailable_reason
from quadnav.hardware.rc import RC_FULL_SPEED, StickRounder, stick_values, tracking_velocity
from quadnav.planning import PlannerSettings
from quadnav.trajectory.generate import TrajectorySettings
from quadnav.world import World, load_world, read_start_goal

MAP = "rbe595/p2b_map1.txt"
START_GOAL = "rbe595/p2b_startandgoal_map1.txt"
MARGIN = 0.2
NO_NETNS = unavailable_reason()
needs_netns = pytest.mark.skipif(NO_NETNS is not None, reason=NO_NETNS or "")
ALWAYS = lambda start, end: True  # noqa: E731  (a geofence that allows every move)


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

    def below_ceiling(start, end):  # nothing above z = 10 cm: the detour goes down
        return max(start[2], end[2]) <= 10

    moves = go_moves([[0, 0, 0], [300, 0, 0], [310, 5, 0]], 50, below_ceiling)
    assert moves[1].z == -DETOUR_CM and land_on(moves).tolist() == [310, 5, 0]

    def corridor(start, end):  # only forward along x, up to x = 310 cm
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


def test_tracking_velocity_corrects_towards_the_reference_and_is_capped():
    v = tracking_velocity([1.0, 0, 1], [0.2, 0, 0], [0.9, 0, 1], gain=1.0)
    assert np.allclose(v, [0.3, 0, 0])
    assert np.linalg.norm(tracking_velocity([5.0, 0, 1], [0.5, 0, 0], [0, 0, 1], 1.0)) == \
        pytest.approx(RC_FULL_SPEED)


def test_dead_reckoning_keeps_within_what_the_reports_allow():
    # A step asked for is kept when the reports allow it, else clipped to them.
    assert np.allclose(clip_step([0.46, 0.0, 0.0], [0.5, 0.0, 0.0], 1.0), [0.46, 0, 0])
    assert np.allclose(clip_step([0.30, 0.0, 0.0], [0.5, 0.0, 0.0], 1.0), [0.45, 0, 0])
    estimate = DeadReckoning(TakeoffFrame.under([1.0, 2.0, 0.0], math.pi / 2))
    state = {"mid": -2, "x": -200, "y": -200, "z": -200, "yaw": 0, "vgx": 0, "vgy": 0,
             "vgz": 0, "h": 80}
    estimate.update(state)
    assert np.allclose(estimate.position(), [1.0, 2.0, 0.8])
    estimate.update({**state, "mid": 1, "x": 50, "y": -20, "z": 90})  # over a mission pad
    assert np.allclose(estimate.position(), [1.2, 2.5, 0.9])  # forward is +y on the map
    estimate.update({"bat": 50})  # not a full packet: ignored
    assert len(estimate.track()) == 2


# --- the plan ----------------------------------------------------------------------------


@cache
def planned_course(folder: Path):
    """The RBE595 course map, its start and goal, and their planned flight (yaw 0), planned
    once per test process."""
    world = load_world(folder / MAP)
    start, goal = read_start_goal(folder / START_GOAL)
    plan = plan_flight(world, start, goal, MARGIN, 0.0,
                       planning=PlannerSettings(seed=0, max_iterations=50_000, time_limit=10),
                       trajectory=TrajectorySettings(v_max=0.5, a_max=1.0))
    return world, start, goal, plan


@pytest.fixture
def course(shared_maps):
    """:func:`planned_course` on the public corpus (skips without it)."""
    return planned_course(shared_maps)


def test_the_plan_takes_off_under_the_start_and_lands_under_the_goal(course):
    _, start, goal, plan = course
    assert np.allclose(plan.takeoff_ground, [start[0], start[1], 0.0])
    assert np.allclose(plan.takeoff_point, [start[0], start[1], TAKEOFF_HEIGHT])
    assert np.allclose(plan.route[0, :2], start[:2]) and np.allclose(plan.route[-1, :2], goal[:2])
    assert np.allclose(plan.landing_ground, [goal[0], goal[1], 0.0])
    assert plan.problem.margin == pytest.approx(MARGIN + TRACKING_ALLOWANCE)
    assert plan.fence.contains(plan.route).all() and plan.fence.contains(plan.pruned).all()
    assert np.allclose(plan.trajectory.position(0.0), plan.takeoff_point)
    assert np.allclose(plan.trajectory.position(plan.trajectory.duration), plan.route[-1])
    assert len(plan.pruned) < len(plan.route)
    assert {tuple(p) for p in plan.pruned} <= {tuple(p) for p in plan.route}


@pytest.mark.parametrize("height", [0.8, 0.63, 1.07, 0.15])  # 0.15: under the fence
def test_go_moves_start_at_the_reported_height_and_end_above_the_goal(course, height):
    *_, plan = course
    moves = plan.go_moves(height, 50)
    end = to_cm([0.0, 0.0, height]) + land_on(moves)
    assert end.tolist() == plan.frame.to_body_cm(plan.route[-1]).tolist()
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


def test_rc_dry_run_streams_sticks_at_20_hz(course, tmp_path):
    *_, plan = course
    out = io.StringIO()
    outcome, track = fly(plan, BridgeSettings(mode="rc"), tmp_path, stream=out)
    assert outcome.status is Status.DRY_RUN and len(track) == 0
    lines = out.getvalue().splitlines()
    sticks = np.array([[int(v) for v in line.split()[1:]] for line in lines[2:-1]])
    assert lines[:2] == ["command", "takeoff"] and lines[-1] == "land"
    assert len(sticks) >= 20 * plan.trajectory.duration
    assert np.abs(sticks).max() <= 100 and (sticks[:, 3] == 0).all()
    # The sticks' sum is the trajectory's way, in the takeoff frame (yaw 0: right = -y).
    way = plan.route[-1] - plan.takeoff_point
    assert sticks[:, 1].sum() * RC_FULL_SPEED / 100 / 20 == pytest.approx(way[0], abs=0.02)
    assert -sticks[:, 0].sum() * RC_FULL_SPEED / 100 / 20 == pytest.approx(way[1], abs=0.02)


def test_cli_bad_flags_are_one_line_errors(tmp_path):
    assert_user_error(run("tello", "fly", "forest", "--dry-run", "--speed", "2", "-o", tmp_path),
                      "--speed", "at most 1 m/s")
    for check, text, message in ((tello_speed, "0", "> 0"), (ipv4, "drone", "IPv4"),
                                 (ipv4, "192.168.10.256", "IPv4"), (percent, "120", "0..100"),
                                 (percent, "half", "whole percentage")):
        with pytest.raises(argparse.ArgumentTypeError, match=message):
            check(text)
    assert (tello_speed("1"), ipv4("198.18.67.1"), percent("20")) == (1.0, "198.18.67.1", 20)


def test_cli_refuses_a_plan_outside_the_fence(tmp_path):
    low = tmp_path / "low.txt"
    low.write_text("boundary 0 0 0 6 3 0.9\n")
    assert_user_error(run("tello", "fly", low, "--start", "1", "1", "0", "--goal", "5", "2",
                          "0", "--dry-run", "--quiet", "-o", tmp_path / "out"),
                      "geofence", "the takeoff", "nothing was sent")
    assert not (tmp_path / "out").exists()


# --- the real client against the emulator --------------------------------------------------


def emulated_flight(course, client_ns, folder, mode="waypoints", scale=10.0, **emulator):
    """Fly the course on an emulator; returns the outcome, the dead-reckoned track and the
    emulator (stopped) once the drone has come to rest."""
    from quadnav.hardware.emulator import TelloEmulator

    _, start, _, plan = course
    with TelloEmulator(start=tuple(start), time_scale=scale, client_netns=client_ns,
                       **emulator) as drone:
        outcome, track = fly(plan, BridgeSettings(mode=mode, time_scale=scale), folder,
                             host=drone.host, truth=lambda: drone.track()[1])
        deadline = time.monotonic() + 5.0
        while drone.flying() and time.monotonic() < deadline:  # e.g. landing by itself
            time.sleep(0.02)
    return outcome, track, drone


def assert_kept_the_fence(plan, positions):
    """Every position (N, 3) is inside the fence, or in the column of the takeoff or of
    the landing (which a safe stop makes where the drone is), and no block was touched."""
    fence = plan.fence
    on_columns = np.zeros(len(positions), dtype=bool)
    for ground in (plan.takeoff_ground, positions[-1]):
        on_columns |= np.linalg.norm(positions[:, :2] - ground[:2], axis=1) < 0.05
    inside = fence.contains(positions)
    assert (inside | on_columns).all(), positions[~(inside | on_columns)][:5]
    walls = fence.world.replace(boundary=fence.world.boundary + np.repeat([-1.0, 1.0], 3))
    assert walls.clearances(positions).min() >= MARGIN  # no block touched, margin kept


def assert_landed(drone, where):
    _, positions = drone.track()
    assert not drone.flying()
    assert positions[-1, 2] == pytest.approx(0.0, abs=1e-6)
    assert np.linalg.norm(positions[-1, :2] - np.asarray(where)[:2]) < 0.05


@needs_netns
@pytest.mark.parametrize(("mode", "scale"), [("waypoints", 10.0), ("rc", 5.0)])
def test_whole_mission_on_the_emulator(course, client_ns, tmp_path, mode, scale):
    *_, goal, plan = course
    outcome, track, drone = emulated_flight(course, client_ns, tmp_path, mode, scale)
    assert outcome.status is Status.LANDED, outcome.message
    _, positions = drone.track()
    assert_kept_the_fence(plan, positions)
    assert_landed(drone, goal)
    assert positions[:, 2].max() == pytest.approx(TAKEOFF_HEIGHT, abs=0.03)
    heard = drone.commands_received()
    names = [text.split()[0] for _, text in heard]
    assert names[:2] == ["command", "takeoff"] and names[-1] == "land"
    if mode == "waypoints":
        assert set(names[2:-1]) == {"go"}
    else:
        times = [when for when, text in heard if text.startswith("rc")]
        assert len(times) / (times[-1] - times[0]) >= 19.5  # at least 20 Hz, drone time
        # The dead-reckoned estimate followed the emulated drone to within a few cm.
        assert np.linalg.norm(track[-1, 1:3] - positions[-1, :2]) < 0.05
    records = [json.loads(line) for line in (tmp_path / "tello_log.jsonl").open()]
    kinds = {r["kind"] for r in records}
    assert kinds == {"start", "command", "reply", "state", "event"}
    assert [r["text"] for r in records if r["kind"] == "command"] == [c for _, c in heard]
    assert np.all(np.diff([r["t"] for r in records]) >= 0)
    assert (tmp_path / "tello_track.png").stat().st_size > 0


@needs_netns
@pytest.mark.parametrize(("faults", "fragments", "airborne"), [
    ({"drop_replies": 0.2}, ["no reply to 'go", "safe stop: stopped, landed"], True),
    ({"reply_delay_s": 1.5}, ["no reply to '", "safe stop: stopped, landed"], True),
    ({"dead_after_s": 1.5}, ["no state packet for 1 s", "the link is down"], True),
    ({"battery": 15.0}, ["battery 15 % is below the 20 %", "takeoff refused"], False),
])
def test_each_fault_ends_in_a_safe_stop(course, client_ns, tmp_path, faults, fragments,
                                         airborne):
    from quadnav.hardware.emulator import Faults

    *_, plan = course
    outcome, _, drone = emulated_flight(course, client_ns, tmp_path, faults=Faults(**faults))
    assert outcome.status is (Status.STOPPED if airborne else Status.REFUSED)
    for fragment in fragments:
        assert fragment in outcome.message, outcome.message
    _, positions = drone.track()
    assert_kept_the_fence(plan, positions)
    assert not drone.flying() and positions[-1, 2] == pytest.approx(0.0, abs=1e-6)
    heard = [text for _, text in drone.commands_received()]
    if not airborne:
        assert heard == ["command"] and positions[:, 2].max() == 0.0
    elif "dead_after_s" not in faults:
        assert heard[-2:] == ["stop", "land"]  # heard and obeyed
    events = [json.loads(line) for line in (tmp_path / "tello_log.jsonl").open()]
    assert any(r["kind"] == "event" and outcome.message in r["text"] for r in events)


@needs_netns
def test_cli_ctrl_c_stops_and_lands(shared_maps, tmp_path):
    from quadnav.hardware.emulator import TelloEmulator

    start, _ = read_start_goal(shared_maps / START_GOAL)
    host = "198.18.69.1"
    with NetNamespace.create() as namespace, TelloEmulator(
            host=host, start=tuple(start), time_scale=10.0, client_netns=namespace) as drone:
        process = namespace.call(lambda: subprocess.Popen(
            [*QUADNAV, "tello", "fly", str(shared_maps / MAP), "--start-goal",
             str(shared_maps / START_GOAL), "--host", host, "--time-scale", "10", "--quiet",
             "-o", str(tmp_path)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True))
        try:
            deadline = time.monotonic() + 60
            while not any(c.startswith("go") for _, c in drone.commands_received()):
                assert time.monotonic() < deadline and process.poll() is None
                time.sleep(0.01)
        finally:
            process.send_signal(signal.SIGINT)
            _, err = process.communicate(timeout=30)
        deadline = time.monotonic() + 5.0
        while drone.flying() and time.monotonic() < deadline:
            time.sleep(0.02)
        heard = [c for _, c in drone.commands_received()]
        assert process.returncode == 130, err
        assert "interrupted (Ctrl-C); safe stop: stopped, landed" in err
        assert heard[-2:] == ["stop", "land"] and not drone.flying()
        assert (tmp_path / "tello_log.jsonl").exists()

"""What each fault leads to when the bridge flies a Tello: the drone is brought down inside
the geofence, and the message and the exit code say what happened.

Faults are injected into the emulator (:class:`~quadnav.hardware.emulator.server.Faults`) under the
real djitellopy client (see :mod:`tellotools`); stop signals go to a real ``quadnav tello
fly`` process, or (for the handler itself) to this one.
"""

from __future__ import annotations

import dataclasses
import json
import re
import signal
import subprocess
import time

import numpy as np
import pytest
from clitools import QUADNAV
from hypothesis import given
from hypothesis import strategies as st
from tellotools import (
    ROOM,
    ROOM_GOAL,
    ROOM_START,
    assert_kept_the_fence,
    assert_on_the_floor,
    emulated_flight,
    needs_netns,
    planned_room,
)

from quadnav.cli.tello_fly_command import exit_code
from quadnav.hardware.bridge.flight import (
    LANDING_TOLERANCE,
    BridgeSettings,
    RcModeError,
    Status,
    fly,
    rc_pace,
)
from quadnav.hardware.bridge.geofence import Geofence
from quadnav.hardware.bridge.lost_link import HOLD, LostLinkBound, run_length, safe_speed
from quadnav.hardware.bridge.rc import stick_velocity
from quadnav.hardware.emulator.netns import NetNamespace
from quadnav.hardware.emulator.server import Faults, TelloEmulator
from quadnav.signals import Stopped, StopSignalHandler, signal_name
from quadnav.world import World

#: One worker flies this module's shared flights (each once, not once per worker).
pytestmark = pytest.mark.xdist_group("tello-faults")

# --- the lost-link bound -------------------------------------------------------------------


@pytest.fixture(scope="module")
def walled() -> LostLinkBound:
    """:data:`~tellotools.ROOM` with a 0.5 m wall piece from y = 0 to 1, fenced 0.2 m in."""
    room = World([0, 0, 0, 6, 2, 1.5], [[3, 0, 0, 3.5, 1, 1.5]], name="room")
    bound = LostLinkBound(Geofence(room, 0.2))
    bound.limit([1.0, 1.0, 1.0], [1.0, 0.0, 0.0])  # builds the block grid (not timed)
    return bound


def test_the_run_of_a_lost_link_and_the_speed_it_allows():
    for distance in (0.0, 0.155, 1.0, 7.2):
        assert run_length(safe_speed(distance)) == pytest.approx(distance)
    assert run_length(0.01) > HOLD * 0.01  # 15 s at one stick percent, and then some
    assert safe_speed(0.15) < 0.01 < safe_speed(0.16)  # one percent needs 15.5 cm


def test_reach_is_the_exact_distance_to_the_fence(walled):
    assert walled.reach([1.0, 0.5, 0.8], [1, 0, 0]) == pytest.approx(1.8, abs=1e-5)  # wall
    assert walled.reach([1.0, 1.5, 0.8], [1, 0, 0]) == pytest.approx(4.8, abs=1e-5)  # beside
    assert walled.reach([1.0, 1.5, 0.8], [0, 0, -1]) == pytest.approx(0.6, abs=1e-5)
    assert walled.reach([1.0, 1.5, 1.4], [0, 0, 1]) == 0.0  # outside the fence


def test_near_the_floor_the_bound_keeps_the_horizontal_motion(walled):
    position, velocity = [1.0, 1.5, 0.3], [0.3, 0.0, -0.05]
    assert not walled.is_safe(position, velocity)  # 15 s of 5 cm/s down: into the floor
    limited = walled.limit(position, velocity)
    assert walled.is_safe(position, limited)
    assert limited[0] == pytest.approx(0.3, rel=0.02) and -0.01 < limited[2] <= 0


@given(st.tuples(st.floats(0.2, 5.8), st.floats(0.2, 1.8), st.floats(0.2, 1.3)),
       st.tuples(*[st.floats(-1.0, 1.0)] * 3))
def test_every_limited_velocity_is_safe_and_no_faster(walled, position, velocity):
    limited = walled.limit(position, velocity)
    assert np.linalg.norm(limited) <= np.linalg.norm(velocity) + 1e-12
    assert walled.is_safe(position, limited) or not walled.fence.point_ok(position)


def test_rc_mode_refuses_a_plan_no_safe_stick_can_follow(course, tmp_path):
    *_, plan = course  # a fence 0.6 m from the floor: the trajectory flies lower
    narrow = dataclasses.replace(plan, fence=Geofence(plan.fence.world, 0.6))
    with pytest.raises(RcModeError, match=r"rc mode cannot fly this plan: at \(.*no stick "
                                          r"speed is safe.*nothing was sent"):
        fly(narrow, BridgeSettings(mode="rc"), tmp_path / "out")
    assert not (tmp_path / "out").exists()
    slowed = rc_pace(plan, BridgeSettings(mode="rc"))  # the course itself: slowed, flown
    assert 2 * slowed.planned < slowed.duration < 4 * slowed.planned


# --- stop signals ------------------------------------------------------------------------


@pytest.mark.parametrize(("first", "raised"), [(signal.SIGINT, KeyboardInterrupt),
                                               (signal.SIGTERM, Stopped)])
def test_the_first_stop_signal_raises_and_later_ones_wait(first, raised):
    before = [signal.getsignal(signum) for signum in (signal.SIGINT, signal.SIGTERM)]
    with StopSignalHandler(hold_after_first=True) as signals:
        with pytest.raises(raised) as caught:
            signal.raise_signal(first)
            time.sleep(5)  # the handler raises long before
        assert getattr(caught.value, "signum", signal.SIGINT) == first
        for signum in (signal.SIGHUP, signal.SIGINT, signal.SIGTERM):
            signal.raise_signal(signum)
        time.sleep(0.01)
        assert signals.take() == [signal.SIGHUP, signal.SIGINT, signal.SIGTERM]
        assert signals.held == []
    assert [signal.getsignal(signum) for signum in (signal.SIGINT, signal.SIGTERM)] == before


@pytest.mark.parametrize(("status", "signum", "code"), [
    (Status.LANDED, None, 0), (Status.DRY_RUN, None, 0), (Status.OFF_GOAL, None, 1),
    (Status.STOPPED, None, 1),
    (Status.AUTO_LANDED, None, 1), (Status.REFUSED, None, 1), (Status.LINK_LOST, None, 3),
    (Status.INTERRUPTED, signal.SIGINT, 130), (Status.INTERRUPTED, signal.SIGTERM, 143),
    (Status.INTERRUPTED, signal.SIGHUP, 129)])
def test_exit_codes(status, signum, code):
    from quadnav.hardware.bridge.flight import Outcome

    assert exit_code(Outcome(status, "", signum)) == code


# --- faults injected into the emulator -----------------------------------------------------


def log_events(folder) -> list[str]:
    return [r["text"] for r in map(json.loads, (folder / "tello_log.jsonl").open())
            if r["kind"] == "event"]


@needs_netns
@pytest.mark.parametrize(("faults", "status", "fragments"), [
    ({"drop_replies": 0.2}, Status.STOPPED,
     ["no reply to 'go", "; safe stop: 'stop' ", ", landed at about ("]),
    # At half the usual time scale a 2.4 s late reply is in time for the takeoff (3 s) and
    # late for the first go (1.84 s), with 0.6 s to spare each way and 15 s of drone time
    # (3 s) before a drone left without commands lands by itself.
    ({"reply_delay_s": 2.4}, Status.STOPPED, ["no reply to 'go ", ", landed at about ("]),
    ({"dead_after_s": 1.5}, Status.LINK_LOST,
     ["no state packet for 1 s", "'stop' got no reply, and 'land' got no answer",
      "if the Tello heard none of it, it finishes the go move it flies (inside the "
      "geofence), hovers and lands by itself 15 s after the last command it heard; last "
      "seen at ("]),
    ({"battery": 15.0}, Status.REFUSED, ["battery 15 % is below the 20 %", "takeoff refused"]),
])
def test_each_fault_ends_on_the_floor_inside_the_fence(course, client_ns, tmp_path, faults,
                                                        status, fragments):
    *_, plan = course
    scale = 5.0 if "reply_delay_s" in faults else 10.0
    flown, drone = emulated_flight(plan, client_ns, tmp_path, scale=scale,
                                   faults=Faults(**faults))
    outcome = flown.outcome
    assert outcome.status is status and exit_code(outcome) == (3 if status is
                                                               Status.LINK_LOST else 1)
    for fragment in fragments:
        assert fragment in outcome.message, outcome.message
    _, positions = drone.track()
    assert_kept_the_fence(plan, positions)
    assert_on_the_floor(drone)
    heard = [text for _, text in drone.commands_received()]
    if status is Status.REFUSED:
        assert heard == ["command"] and positions[:, 2].max() == 0.0
    elif status is Status.STOPPED:
        assert heard[-2:] == ["stop", "land"]  # heard and obeyed
    assert any(outcome.message in event for event in log_events(tmp_path))


@needs_netns
@pytest.mark.parametrize(("mode", "battery", "noticed"), [
    ("waypoints", 22.0, r"the Tello answered 'go [-\d ]+' with 'error Auto land': it is "
                        r"landing by itself"),
    ("rc", 30.0, r"battery \d % in flight, below the 10 % at which a Tello lands by itself")])
def test_a_battery_running_out_in_flight_lands_the_drone(course, client_ns, tmp_path, mode,
                                                          battery, noticed):
    *_, plan = course
    flown, drone = emulated_flight(plan, client_ns, tmp_path, mode,
                                   faults=Faults(battery=battery, battery_drain=10))
    outcome = flown.outcome
    assert outcome.status is Status.AUTO_LANDED and exit_code(outcome) == 1
    assert re.fullmatch(noticed + r"; it is on the floor at about \(.*\) \+- [\d.]+ m \(state "
                        r"packets\), battery \d %", outcome.message), outcome.message
    _, positions = drone.track()
    assert_kept_the_fence(plan, positions)
    assert_on_the_floor(drone)
    assert positions[:, 2].max() > 0.25  # it was flying
    heard = [text for _, text in drone.commands_received()]
    assert heard[-1] == "land" and "stop" not in heard  # asked once; it was landing anyway


@needs_netns
def test_a_link_that_dies_in_rc_mode_leaves_the_drone_inside_the_fence(client_ns, tmp_path):
    plan = planned_room()  # straight along the room, towards its far wall
    flown, drone = emulated_flight(plan, client_ns, tmp_path, "rc",
                                   faults=Faults(dead_after_s=0.7))
    outcome = flown.outcome
    assert outcome.status is Status.LINK_LOST and exit_code(outcome) == 3
    assert re.fullmatch(
        r"no state packet for 1 s during the rc flight \(t = [\d.]+ s\); 'stop' "
        r"got no reply, and 'land' got no answer \(3 tries\); if the Tello heard none of "
        r"it, it flies on at the last sticks it heard \(each bounded so that 15 s of "
        r"them stay inside the geofence\) and lands by itself 15 s after the last command it "
        r"heard; last seen at \(.*\) \(state packets\)", outcome.message), outcome.message
    heard = drone.commands_received()
    last = [text for _, text in heard if text.startswith("rc")][-1]
    assert stick_velocity([int(v) for v in last.split()[1:]], 0.0)[0] > 0.1  # flying on
    times, positions = drone.track()
    lost_at = positions[np.searchsorted(times, heard[-1][0])]
    assert positions[-1, 0] > lost_at[0] + 1.0  # it flew on for metres ...
    assert_kept_the_fence(plan, positions)  # ... and still stayed inside the fence
    assert_on_the_floor(drone)


# --- stop signals to `quadnav tello fly` ------------------------------------------------


def wait_until(condition, process) -> None:
    """Wait (up to 60 s) until ``condition()`` while ``process`` runs."""
    deadline = time.monotonic() + 60
    while not condition():
        assert time.monotonic() < deadline and process.poll() is None, process.stderr.read()
        time.sleep(0.01)


@needs_netns
@pytest.mark.parametrize(("first", "second"), [(signal.SIGTERM, signal.SIGTERM),
                                               (signal.SIGHUP, signal.SIGINT)])
def test_stop_signals_mid_move_stop_and_land(tmp_path, first, second):
    room = tmp_path / "room.txt"
    room.write_text(ROOM)
    host = "198.18.69.1"
    with NetNamespace.create() as namespace, TelloEmulator(
            host=host, start=(*ROOM_START[:2], 0.0), time_scale=10.0,
            client_netns=namespace) as drone:
        process = namespace.call(lambda: subprocess.Popen(
            [*QUADNAV, "tello", "fly", str(room), "--start", *map(str, ROOM_START),
             "--goal", *map(str, ROOM_GOAL), "--iterations", "300", "--host", host,
             "--time-scale", "10", "--quiet", "-o", str(tmp_path / "flight")],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True))
        try:  # mid-move: the go takes 9 s (0.9 s wall-clock)
            wait_until(lambda: drone.track()[1][:, 0].max(initial=0) > ROOM_START[0] + 0.5,
                       process)
            process.send_signal(first)
            wait_until(lambda: "stop" in [c for _, c in drone.commands_received()], process)
            process.send_signal(second)  # during the safe stop: must not cut it short
        finally:
            if process.poll() is None and len(drone.commands_received()) < 3:
                process.kill()
            _, err = process.communicate(timeout=30)
        deadline = time.monotonic() + 5.0
        while drone.flying() and time.monotonic() < deadline:
            time.sleep(0.02)
    assert process.returncode == 128 + first, err
    assert (f"quadnav: tello: interrupted: stopped by {signal_name(first)}; safe stop: "
            "'stop' answered ok (hovering), landed at about (") in err
    assert f"; {signal_name(second)} came later and waited until the drone was down" in err
    assert [c for _, c in drone.commands_received()][-2:] == ["stop", "land"]
    assert_on_the_floor(drone)
    _, positions = drone.track()
    assert ROOM_START[0] + 0.5 < positions[-1, 0] < ROOM_GOAL[0] - 0.5  # stopped mid-move
    assert (tmp_path / "flight" / "tello_log.jsonl").exists()


# --- a real Tello's imperfections --------------------------------------------------------------

REAL = Faults.real_tello()


@needs_netns
@pytest.mark.parametrize("mode", ["waypoints", "rc"])
def test_whole_missions_through_a_real_tellos_imperfections_land_inside_the_fence(
        course, client_ns, tmp_path, mode):
    """Moves that end off, a varying takeoff height, noisy velocities and lost replies: the
    mission (the course's go moves; rc sticks along the room, the shorter flight) still ends
    on the floor and never leaves the fence; when it lands, it lands near the goal, and
    the verdict is the dead-reckoned landing place's (at the goal within the tolerance,
    else off it: noisy velocities may put the estimate off while the drone is there)."""
    plan = course[-1] if mode == "waypoints" else planned_room()
    flown, drone = emulated_flight(plan, client_ns, tmp_path, mode, faults=REAL, seed=2)
    outcome = flown.outcome
    assert outcome.status in (Status.LANDED, Status.OFF_GOAL, Status.STOPPED), outcome.message
    _, positions = drone.track()
    assert_kept_the_fence(plan, positions)
    assert_on_the_floor(drone)
    if outcome.status is not Status.STOPPED:
        assert np.linalg.norm(positions[-1, :2] - plan.landing_ground[:2]) < 0.25
        off = np.linalg.norm(outcome.landing.point[:2] - plan.landing_ground[:2])
        assert (outcome.status is Status.LANDED) == (off <= LANDING_TOLERANCE)


@needs_netns
def test_the_imperfections_are_drawn_from_the_seed(client_ns, tmp_path):
    """The same seed: the same takeoff height (the highest point of this flight at the
    start's 0.8 m, or above it) and the same moves; another seed: others."""
    plan = planned_room()
    ends = {}
    for run, seed in enumerate((5, 5, 6)):
        _, drone = emulated_flight(plan, client_ns, tmp_path / str(run),
                                   faults=dataclasses.replace(REAL, drop_replies=0.0),
                                   seed=seed)
        _, positions = drone.track()
        ends[run] = (positions[:, 2].max(), positions[-1, :2])
    # the flight itself runs on the wall clock: equal to a centimetre or two (a loaded
    # machine's late replies move it), not to the bit, and far from another seed's
    assert ends[0][0] == pytest.approx(ends[1][0], abs=0.03)
    assert np.allclose(ends[0][1], ends[1][1], atol=0.02)
    assert abs(ends[0][0] - ends[2][0]) > 0.05  # seed 5 takes off 15 cm lower than seed 6

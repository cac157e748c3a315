"""The Tello emulator driven by the real djitellopy client over real UDP sockets.

djitellopy keeps one command socket and one state socket per process; they are bound in
a network namespace private to this test process (:func:`djitellopy_namespace`), and
every emulator links to it, so parallel test workers never share port 8889. Timing
checks bound wall-clock time from below only (the emulator may fall behind on a busy
machine, never ahead); what happened is read from the emulator's own record.
"""

from __future__ import annotations

import math
import os
import re
import signal
import socket
import subprocess
import time

import numpy as np
import pytest
from clitools import QUADNAV, assert_user_error, run
from djitellopy import Tello, TelloException

from quadnav.errors import QuadnavError
from quadnav.hardware import sdk
from quadnav.hardware.emulator.drone import (
    ACCELERATION,
    TAKEOFF_HEIGHT,
    Arc,
    SpeedProfile,
)
from quadnav.hardware.emulator.netns import NetNamespace, peer_address, unavailable_reason
from quadnav.hardware.emulator.server import (
    ALREADY_FLYING,
    AUTO_LAND_AFTER,
    AUTO_LANDING,
    BUSY,
    LOW_BATTERY_REPLY,
    NOT_FLYING,
    STOPPED,
    Faults,
    TelloEmulator,
    check_host,
)

NO_NETNS = unavailable_reason()
needs_netns = pytest.mark.skipif(NO_NETNS is not None, reason=NO_NETNS or "")
#: The SDK 2.0 state packet, field by field.
STATE_PATTERN = re.compile(
    r"mid:-?\d+;x:-?\d+;y:-?\d+;z:-?\d+;mpry:-?\d+,-?\d+,-?\d+;pitch:-?\d+;roll:-?\d+;"
    r"yaw:-?\d+;vgx:-?\d+;vgy:-?\d+;vgz:-?\d+;templ:-?\d+;temph:-?\d+;tof:\d+;h:-?\d+;"
    r"bat:\d+;baro:-?\d+\.\d\d;time:\d+;agx:-?\d+\.\d\d;agy:-?\d+\.\d\d;agz:-?\d+\.\d\d;\r\n")


@pytest.fixture
def emulate(client_ns):
    """``emulate(**kwargs)``: a started emulator linked to djitellopy, and its client."""
    made: list[tuple[TelloEmulator, Tello]] = []

    def make(**kwargs) -> tuple[TelloEmulator, Tello]:
        emulator = TelloEmulator(client_netns=client_ns, **kwargs).start()
        made.append((emulator, Tello(host=emulator.host)))
        return made[-1]

    yield make
    for emulator, client in made:
        client.is_flying = False  # the emulator goes away: no landing on the way out
        client.end()
        emulator.stop()


def wait_for(condition, timeout: float = 5.0) -> bool:
    """Poll ``condition()`` every 10 ms until true (True) or ``timeout`` s (False)."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if condition():
            return True
        time.sleep(0.01)
    return condition()


def received_at(emulator: TelloEmulator, text: str) -> float:
    """Emulated time of the last datagram ``text`` the emulator heard."""
    return [t for t, heard in emulator.commands_received() if heard == text][-1]


# --- the protocol on its own ---------------------------------------------------------


@pytest.mark.parametrize(("text", "reply"), [
    ("forward 19", sdk.OUT_OF_RANGE), ("back 501", sdk.OUT_OF_RANGE),
    ("cw 0", sdk.OUT_OF_RANGE), ("ccw 361", sdk.OUT_OF_RANGE),
    ("go 20 -20 20 50", sdk.OUT_OF_RANGE), ("go 501 0 0 50", sdk.OUT_OF_RANGE),
    ("go 100 0 0 9", sdk.OUT_OF_RANGE), ("go 100 0 0 101", sdk.OUT_OF_RANGE),
    ("curve 50 50 0 100 0 0 61", sdk.OUT_OF_RANGE),
    ("curve 50 0 0 100 0 0 30", sdk.OUT_OF_RANGE),  # in a line: no circle
    ("curve 30 30 0 60 0 0 30", sdk.OUT_OF_RANGE),  # radius 0.3 m < 0.5 m
    ("speed 5", sdk.OUT_OF_RANGE), ("rc 0 0 101 0", sdk.OUT_OF_RANGE),
    ("flip x", sdk.OUT_OF_RANGE), ("setfps fast", sdk.OUT_OF_RANGE),
    ("forward ten", sdk.BAD_ARGUMENTS), ("go 100 0 0", sdk.BAD_ARGUMENTS),
    ("takeoff now", sdk.BAD_ARGUMENTS), ("go 100 0 0 50 m9", sdk.BAD_ARGUMENTS),
    ("jump 100 0 0 50 0", sdk.BAD_ARGUMENTS),
    ("book", sdk.UNKNOWN), ("EXT led 255 0 0", sdk.UNKNOWN), ("", sdk.UNKNOWN),
])
def test_bad_commands_get_the_firmware_reply(text, reply):
    with pytest.raises(sdk.SdkError) as caught:
        sdk.parse_command(text)
    assert caught.value.reply == reply


def test_good_commands_parse_with_their_arguments():
    assert sdk.parse_command(" go -100 20 0 100 ") == sdk.Command("go", (-100, 20, 0, 100))
    assert sdk.parse_command("curve 50 50 0 100 0 0 60").args == (50, 50, 0, 100, 0, 0, 60)
    assert sdk.parse_command("go 10 10 10 50 m1").mission_pad  # pads: no 20 cm rule
    assert sdk.parse_command("rc -100 100 0 -7").args == (-100, 100, 0, -7)
    assert sdk.parse_command("flip b").args == ("b",)
    assert sdk.parse_command("battery?").name == "battery?"


def test_no_refusal_reads_as_ok_to_djitellopy():
    """djitellopy takes any reply containing 'ok' for success."""
    refusals = [sdk.OUT_OF_RANGE, sdk.UNKNOWN, sdk.BAD_ARGUMENTS, sdk.NO_MARKER, BUSY,
                NOT_FLYING, ALREADY_FLYING, AUTO_LANDING, LOW_BATTERY_REPLY, STOPPED]
    assert all("ok" not in reply.lower() for reply in refusals)


def test_state_packet_is_the_sdk_format_and_djitellopy_parses_it():
    telemetry = sdk.Telemetry(pitch=-3, roll=2, yaw=-179, velocity=(5, -1, 0),
                              acceleration=(-50.6, 0.0, -998.5), height=80, tof=80,
                              baro=1.2345, battery=87, motor_time=12, temperature=(61, 64))
    packet = sdk.format_state(telemetry)
    assert STATE_PATTERN.fullmatch(packet)
    state = Tello.parse_state(packet)
    assert state["mid"] == -2 and state["x"] == -200 and state["mpry"] == "0,0,0"
    assert (state["pitch"], state["roll"], state["yaw"]) == (-3, 2, -179)
    assert (state["vgx"], state["vgy"], state["vgz"]) == (5, -1, 0)
    assert (state["h"], state["tof"], state["bat"], state["time"]) == (80, 80, 87, 12)
    assert state["baro"] == 1.23 and state["agz"] == -998.5
    with_pads = Tello.parse_state(sdk.format_state(
        sdk.Telemetry(**{**telemetry.__dict__, "mission_pads": True})))
    assert (with_pads["mid"], with_pads["z"]) == (-1, -100)


def test_speed_profile_reaches_its_length_within_its_limits():
    for length, speed in ((1.0, 0.5), (0.1, 1.0), (5.0, 1.0)):
        profile = SpeedProfile(length, speed, ACCELERATION)
        t = np.linspace(0.0, profile.duration, 4001)
        s, v, a = profile.at(t)
        assert s[0] == 0 and s[-1] == pytest.approx(length)
        assert v.max() <= speed + 1e-9 and np.abs(a).max() <= ACCELERATION + 1e-6
        assert np.allclose(np.gradient(s, t), v, atol=1e-3)
        assert profile.duration >= length / speed


def test_arc_passes_through_its_middle_point():
    arc = Arc([0.0, 0.0, 1.0], [1.0, 1.0, 1.0], [2.0, 0.0, 1.0])
    assert arc.radius == pytest.approx(1.0) and arc.length == pytest.approx(math.pi)
    points, tangents, _ = arc.at(np.array([0.0, math.pi / 2, math.pi]))
    assert np.allclose(points, [[0, 0, 1], [1, 1, 1], [2, 0, 1]])
    assert np.allclose(np.linalg.norm(tangents, axis=1), 1.0)


def test_bad_emulator_settings_are_user_errors():
    with pytest.raises(QuadnavError, match=r"127\.0\.0\.2"):
        check_host("127.0.0.2")
    with pytest.raises(QuadnavError, match="IPv4"):
        check_host("drone")
    with pytest.raises(QuadnavError, match="drop_replies"):
        Faults(drop_replies=1.5)
    with pytest.raises(QuadnavError, match=r"battery_drain 0\.5: expected 1 to 1000"):
        Faults(battery_drain=0.5)
    with pytest.raises(QuadnavError, match="time scale"):
        TelloEmulator(time_scale=0)
    assert peer_address("198.18.67.1") == "198.18.67.0"


# --- djitellopy against the emulator -----------------------------------------------


@needs_netns
def test_connect_queries_and_state_at_10_hz(emulate):
    emulator, tello = emulate(start=(1.0, 2.0, 0.5))
    assert "Aborting" in tello.send_command_with_return("battery?", timeout=1)
    assert tello.get_current_state() == {}  # no reply and no state before "command"
    tello.connect()
    state = tello.get_current_state()
    assert (state["bat"], state["h"], state["yaw"], state["mid"]) == (100, 0, 0, -2)
    assert state["agz"] == pytest.approx(-1000.0, abs=1.0)
    assert state["baro"] == pytest.approx(0.5)
    assert tello.query_battery() == 100 and tello.query_speed() == 100
    assert tello.query_sdk_version() == "20" and tello.query_serial_number().startswith("0TQ")
    assert tello.query_flight_time() == 0 and tello.query_height() == 0
    assert tello.query_attitude() == {"pitch": 0, "roll": 0, "yaw": 0}
    assert tello.query_distance_tof() == 10.0 and int(tello.query_wifi_signal_noise_ratio())
    assert 40 <= tello.query_temperature() <= 90
    seen = [tello.get_current_state()]  # each packet is a new dict: count them
    end = time.monotonic() + 1.0
    while time.monotonic() < end:
        if tello.get_current_state() is not seen[-1]:
            seen.append(tello.get_current_state())
        time.sleep(0.005)
    assert 8 <= len(seen) - 1 <= 12
    heard = [text for _, text in emulator.commands_received()]
    assert heard[:3] == ["battery?", "command", "battery?"]


@needs_netns
def test_flight_moves_take_their_time_in_the_sdk_frames(emulate):
    scale = 3.0
    emulator, tello = emulate(start=(1.0, 2.0, 0.0), yaw=math.pi / 2, time_scale=scale)
    tello.connect()
    tello.takeoff()
    assert tello.get_height() == pytest.approx(100 * TAKEOFF_HEIGHT, abs=5)
    assert np.allclose(emulator.track()[1][-1], [1.0, 2.0, TAKEOFF_HEIGHT], atol=0.05)

    began = time.monotonic()
    tello.go_xyz_speed(100, 0, 0, 50)  # x forward: the nose points along world +y
    elapsed = time.monotonic() - began
    assert elapsed >= 1.0 / 0.5 / scale  # 1 m at 0.5 m/s, time scale 3
    t, positions = emulator.track()
    assert np.allclose(positions[-1], [1.0, 3.0, TAKEOFF_HEIGHT], atol=0.05)  # over at reply
    flown = t[t >= received_at(emulator, "go 100 0 0 50")]
    assert flown[-1] - flown[0] >= 1.0 / 0.5
    assert np.all(np.diff(positions[len(t) - len(flown):, 1]) > -0.01)  # straight on, +y

    tello.go_xyz_speed(0, 50, -30, 100)  # y left of +y is world -x; z up
    assert np.allclose(emulator.track()[1][-1], [0.5, 3.0, TAKEOFF_HEIGHT - 0.3], atol=0.05)
    with pytest.raises(TelloException, match="out of range"):
        tello.go_xyz_speed(10, 10, 10, 50)  # all three within 20 cm
    assert tello.send_command_with_return("forward 501") == sdk.OUT_OF_RANGE

    tello.rotate_clockwise(90)
    assert tello.get_yaw() == pytest.approx(90, abs=3)  # SDK yaw: clockwise positive
    tello.move_forward(50)  # now facing world +x
    assert np.allclose(emulator.track()[1][-1], [1.0, 3.0, TAKEOFF_HEIGHT - 0.3], atol=0.05)

    before = emulator.track()[1][-1]
    for _ in range(10):
        tello.send_rc_control(0, 100, 0, -100)  # forward and turning counter-clockwise
        time.sleep(0.05)
    assert tello.get_speed_x() > 0  # vgx: along the heading, dm/s
    tello.send_rc_control(0, 0, 0, 0)
    assert wait_for(lambda: np.linalg.norm(emulator.track()[1][-1] - emulator.track()[1][-25])
                    < 0.02)  # stopped
    moved = emulator.track()[1][-1] - before
    assert moved[0] > 0.1 and moved[1] > 0.05 and abs(moved[2]) < 0.05  # curving left
    assert tello.get_yaw() < 80  # turned back counter-clockwise

    tello.land()
    assert tello.get_height() == 0 and not emulator.flying()
    assert emulator.track()[1][-1][2] == pytest.approx(0.0, abs=1e-6)
    assert tello.query_flight_time() > 0


@needs_netns
def test_curve_stop_busy_and_emergency(emulate):
    emulator, tello = emulate(time_scale=4.0)
    tello.connect()
    with pytest.raises(TelloException, match="Motor stop"):
        tello.move_up(50)  # not flying
    tello.takeoff()
    tello.curve_xyz_speed(50, 50, 0, 100, 0, 0, 60)  # half a circle of radius 0.5 m
    t, positions = emulator.track()
    arc = positions[t >= received_at(emulator, "curve 50 50 0 100 0 0 60")]
    centre = np.array([0.5, 0.0, TAKEOFF_HEIGHT])
    assert np.allclose(np.linalg.norm(arc - centre, axis=1), 0.5, atol=0.05)
    assert arc[:, 1].max() == pytest.approx(0.5, abs=0.05)  # through (0.5, 0.5): left
    assert np.allclose(arc[-1], [1.0, 0.0, TAKEOFF_HEIGHT], atol=0.05)

    # Full stick forward until it has moved 15 cm (by the emulated track, not the wall
    # clock: a busy machine must not let it gather more speed before the stop).
    tello.send_rc_control(0, 100, 0, 0)
    assert wait_for(lambda: emulator.track()[1][-1][0] - arc[-1][0] > 0.15)
    tello.send_control_command("stop")  # hover where it is, sticks released
    # Measured from where the drone was when it heard the stop, an emulated second on:
    # how late the machine delivered it does not count.
    heard = received_at(emulator, "stop")
    assert wait_for(lambda: emulator.track()[0][-1] > heard + 1.0)
    t, positions = emulator.track()
    assert np.linalg.norm(positions[-1] - positions[np.searchsorted(t, heard)]) < 0.3

    tello.send_command_without_return("forward 300")  # its reply comes when it is over
    assert wait_for(lambda: any(c == "forward 300" for _, c in emulator.commands_received()))
    assert tello.send_command_with_return("back 50") == BUSY
    tello.emergency()  # motors off mid-move: it falls, the move ends unfinished
    responses = tello.get_own_udp_object()["responses"]
    assert wait_for(lambda: responses) and responses.pop(0) == STOPPED.encode()
    assert wait_for(lambda: tello.get_height() == 0)
    assert emulator.track()[1][-1][0] < 2.5  # far short of 3 m forward
    assert tello.send_command_with_return("forward 50") == NOT_FLYING


@needs_netns
def test_auto_land_after_15_s_without_a_command(emulate):
    scale = 20.0
    emulator, tello = emulate(time_scale=scale)
    tello.connect()
    tello.takeoff()
    took_off = emulator.time
    time.sleep(0.5 * AUTO_LAND_AFTER / scale)
    assert tello.get_height() > 70  # still up half way
    assert wait_for(lambda: tello.get_height() == 0, timeout=5.0)
    assert not emulator.flying()
    heard = emulator.commands_received()
    assert heard[-1][1] == "takeoff" and emulator.time - took_off >= AUTO_LAND_AFTER
    assert tello.send_command_with_return("forward 50") == NOT_FLYING


@needs_netns
def test_dropped_replies(emulate):
    emulator, tello = emulate(faults=Faults(drop_replies=1.0))
    assert "Aborting" in tello.send_command_with_return("command", timeout=1)
    assert [text for _, text in emulator.commands_received()] == ["command"]
    assert wait_for(lambda: tello.get_current_state().get("bat") == 100)  # state flows


@needs_netns
def test_late_replies(emulate):
    _, tello = emulate(faults=Faults(reply_delay_s=0.6))
    began = time.monotonic()
    tello.connect()
    assert tello.query_battery() == 100
    assert time.monotonic() - began >= 1.2  # two replies, each 0.6 s late


@needs_netns
def test_dead_link(emulate):
    emulator, tello = emulate(faults=Faults(dead_after_s=0.5))
    tello.connect()
    time.sleep(0.6)
    assert "Aborting" in tello.send_command_with_return("battery?", timeout=1)
    tello.get_own_udp_object()["state"] = {}
    time.sleep(0.3)
    assert tello.get_current_state() == {}  # no state either
    assert "battery?" not in [text for _, text in emulator.commands_received()]


@needs_netns
def test_low_battery(emulate):
    emulator, tello = emulate(faults=Faults(battery=5))
    tello.connect()
    assert tello.get_battery() == 5 and tello.query_battery() == 5
    with pytest.raises(TelloException, match="Low battery"):
        tello.takeoff()
    assert not emulator.flying()


@needs_netns
def test_battery_running_low_in_flight_lands(emulate):
    # An aged battery (draining 20 times faster) runs from 12 % to below 10 % in flight.
    emulator, tello = emulate(time_scale=5.0, faults=Faults(battery=12, battery_drain=20))
    tello.connect()
    tello.takeoff()
    assert wait_for(lambda: tello.get_battery() < 10, timeout=5.0)
    assert tello.get_height() > 50  # it is landing by itself: refusals say so
    assert tello.send_command_with_return("forward 50") == AUTO_LANDING
    assert tello.send_command_with_return("stop") == AUTO_LANDING
    assert tello.send_command_with_return("land") == AUTO_LANDING
    assert wait_for(lambda: tello.get_height() == 0 and not emulator.flying(), timeout=5.0)
    assert tello.send_command_with_return("land") == NOT_FLYING
    assert [c for _, c in emulator.commands_received()][:2] == ["command", "takeoff"]


@needs_netns
def test_cli_emulate_serves_djitellopy_until_ctrl_c(client_ns, tmp_path):
    host, truth = "198.18.68.1", tmp_path / "truth.csv"
    began = time.time()
    process = client_ns.call(lambda: subprocess.Popen(
        [*QUADNAV, "tello", "emulate", "--host", host, "--start", "1", "2", "0", "--yaw", "90",
         "--truth", str(truth)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True))
    try:
        banner = process.stdout.readline()
        assert f"Emulated Tello at {host}" in banner, process.stderr.read()
        assert f"its true track written to {truth}" in banner
        tello = Tello(host=host)
        tello.connect()
        assert tello.query_battery() == 100 and tello.get_yaw() == 0
        tello.end()
        deadline = time.monotonic() + 30.0  # rows come as the emulator's clock ticks
        while (not truth.exists() or truth.read_text().count("\n") <= 10) and \
                time.monotonic() < deadline:
            time.sleep(0.05)
    finally:
        process.send_signal(signal.SIGINT)
        _, err = process.communicate(timeout=10)
    assert process.returncode == 130, err
    links = client_ns.call(lambda: subprocess.run(["ip", "-br", "link"], capture_output=True,
                                                  text=True)).stdout
    assert "qtc6124401" not in links  # the link went with the emulator
    # the true track: UNIX time and world position, the drone on the floor at its start
    lines = truth.read_text().splitlines()
    assert lines[0] == "unix_time_s,x,y,z" and len(lines) > 10
    rows = np.array([[float(v) for v in line.split(",")] for line in lines[1:]])
    assert began < rows[0, 0] and np.all(np.diff(rows[:, 0]) > 0) and rows[-1, 0] < time.time()
    assert np.allclose(rows[:, 1:], [1, 2, 0])


def test_cli_emulate_refuses_a_true_track_it_cannot_write(tmp_path):
    assert_user_error(run("tello", "emulate", "--truth", tmp_path / "no" / "truth.csv"),
                      f"{tmp_path / 'no' / 'truth.csv'}: cannot write the true track")


def test_cli_emulate_rejects_a_loopback_host():
    assert_user_error(run("tello", "emulate", "--host", "127.0.0.2"), "127.0.0.2", "127.0.0.0/8")


@needs_netns
def test_namespace_of_a_socket_is_the_one_it_was_made_in():
    with NetNamespace.create() as namespace:
        sock = namespace.call(lambda: socket.socket(socket.AF_INET, socket.SOCK_DGRAM))
        with sock, NetNamespace.of_socket(sock) as found, NetNamespace.current() as here:
            inode = [os.stat(f"/proc/self/fd/{ns.fd}").st_ino for ns in (namespace, found, here)]
            assert inode[0] == inode[1] != inode[2]

"""The Tello SDK 2.0 text protocol as the emulator speaks it: commands, replies, state.

Pure functions, no sockets. :func:`parse_command` turns a datagram's text into a
:class:`Command` with its arguments range-checked, or raises :class:`SdkError` carrying
the reply the drone sends instead; :func:`format_state` writes a state packet and
:func:`query_reply` the answer to a read command (``battery?`` ...).

Replies, as the real drone and djitellopy 2.5 have them:

* ``ok`` for a control or set command that succeeded; djitellopy counts any reply
  containing ``ok`` as success, so no error text here contains those two letters;
* ``out of range`` for an argument outside the SDK's limits (what the firmware says,
  e.g. to ``go 10 10 10 20``), ``error <reason>`` for anything else refused;
* the value for a read command, in the form djitellopy parses (whole numbers for
  ``speed?``, ``battery?``, ``time?``, ``height?``, ``temp?`` and ``baro?``; ``tof?`` in
  mm with the unit, ``attitude?`` as ``pitch:..;roll:..;yaw:..;``);
* nothing for ``rc``, ``emergency`` and ``reboot``, which djitellopy sends without
  waiting for a reply (a reply would be taken as the next command's).

Frames (see also :mod:`quadnav.hardware.bridge.frames`): ``go`` and ``curve`` points are in the
drone's heading frame at the time of the command — x forward, y left, z up, cm;
``rc a b c d`` is left/right (+ right), forward/back (+ forward), up/down (+ up) and yaw
(+ clockwise seen from above), each -100..100.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

#: UDP port the drone takes commands on (and replies from).
COMMAND_PORT = 8889
#: UDP port on the client that state packets go to.
STATE_PORT = 8890
#: Default address of the emulated drone: RFC 2544's benchmarking range 198.18.0.0/15,
#: which no real network (nor the real drone's 192.168.10.1) uses.
DEFAULT_HOST = "198.18.67.1"
#: Reply of a command that succeeded.
OK = "ok"
#: Reply of a command with an argument outside the SDK's limits.
OUT_OF_RANGE = "out of range"
#: Reply of a command that is not part of the SDK (the firmware echoes the text; the
#: emulator does not, as the text could contain "ok").
UNKNOWN = "error Unknown command"
#: Reply to a command with the wrong number or kind of arguments.
BAD_ARGUMENTS = "error Bad arguments"
#: Reply of a mission-pad command: the emulator has no mission pads to see.
NO_MARKER = "error Not valid marker"
#: Commands sent without waiting for a reply; the drone sends none.
SILENT = frozenset({"rc", "emergency", "reboot"})
#: Seconds without a command after which a flying Tello lands by itself (its safety
#: timeout; a motion in progress does not count).
AUTO_LAND_AFTER = 15.0
#: Below this battery percentage a Tello will not take off, and in flight it lands by itself.
LOW_BATTERY = 10
#: The reply to a motion, ``stop`` or ``land`` while the drone lands by itself.
AUTO_LAND = "error Auto land"
#: The reply of a motion that ``stop`` or ``emergency`` ended before its end.
MOTION_STOPPED = "error Stopped"
#: Shortest and longest curve radius, cm.
CURVE_RADIUS_CM = (50.0, 1000.0)
#: A go or curve point needs a component beyond +-this, cm.
MIN_STEP_CM = 20


class SdkError(Exception):
    """A command the drone refuses; ``reply`` is what it sends back."""

    def __init__(self, reply: str) -> None:
        super().__init__(reply)
        self.reply = reply


@dataclass(frozen=True)
class Command:
    """One parsed command: its name (``go``, ``battery?`` ...) and its checked arguments
    (ints, or words for ``flip``, ``setfps`` ...; ``mission_pad`` for the ``m1``..``m8``
    suffix of the mission-pad forms)."""

    name: str
    args: tuple[int | str, ...] = ()
    mission_pad: bool = False


def _integer(low: int, high: int) -> Callable[[str], int]:
    def check(word: str) -> int:
        try:
            value = int(word)
        except ValueError:
            raise SdkError(BAD_ARGUMENTS) from None
        if not low <= value <= high:
            raise SdkError(OUT_OF_RANGE)
        return value
    return check


def _choice(*words: str) -> Callable[[str], str]:
    def check(word: str) -> str:
        if word not in words:
            raise SdkError(OUT_OF_RANGE)
        return word
    return check


def _text(word: str) -> str:
    return word


_DISTANCE = _integer(20, 500)
_COORDINATE = _integer(-500, 500)
_ANGLE = _integer(1, 360)
_STICK = _integer(-100, 100)
_PORT = _integer(1025, 65535)
#: Argument checks per command; the mission-pad forms add a trailing ``m<id>``.
_ARGUMENTS: dict[str, tuple[Callable[[str], int | str], ...]] = {
    **{name: () for name in (
        "command", "takeoff", "land", "stop", "emergency", "keepalive", "motoron",
        "motoroff", "throwfly", "streamon", "streamoff", "reboot", "mon", "moff",
        "speed?", "battery?", "time?", "wifi?", "sdk?", "sn?", "height?", "temp?",
        "attitude?", "baro?", "tof?", "acceleration?", "active?", "hardware?")},
    **{name: (_DISTANCE,) for name in ("up", "down", "left", "right", "forward", "back")},
    "cw": (_ANGLE,), "ccw": (_ANGLE,),
    "flip": (_choice("l", "r", "f", "b"),),
    "go": (_COORDINATE,) * 3 + (_integer(10, 100),),
    "curve": (_COORDINATE,) * 6 + (_integer(10, 60),),
    "jump": (_COORDINATE,) * 3 + (_integer(10, 100), _integer(-360, 360)),
    "speed": (_integer(10, 100),),
    "rc": (_STICK,) * 4,
    "mdirection": (_integer(0, 2),),
    "wifi": (_text, _text), "ap": (_text, _text),
    "port": (_PORT, _PORT),
    "setfps": (_choice("low", "middle", "high"),),
    "setbitrate": (_integer(0, 5),),
    "setresolution": (_choice("low", "high"),),
    "downvision": (_integer(0, 1),),
}
#: How many ``m<id>`` words the mission-pad form of a command ends with.
_MISSION_PADS = {"go": 1, "curve": 1, "jump": 2}
_PAD_IDS = {f"m{i}" for i in (*range(1, 9), -1, -2)}


def _check_points(args: tuple[int | str, ...], name: str) -> None:
    """The go/curve rules beyond the ranges: no point within +-20 cm on every axis and,
    for a curve, a radius of 0.5 to 10 m through the drone and both points."""
    points = np.array(args[:-1], dtype=np.float64).reshape(-1, 3)
    if np.any(np.max(np.abs(points), axis=1) <= MIN_STEP_CM):
        raise SdkError(OUT_OF_RANGE)
    if name == "curve":
        radius = circumradius(np.zeros(3), points[0], points[1])
        if not CURVE_RADIUS_CM[0] <= radius <= CURVE_RADIUS_CM[1]:
            raise SdkError(OUT_OF_RANGE)


def circumradius(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> float:
    """Radius of the circle through three points (3,); inf when they are in a line."""
    ab, ac, bc = (float(np.linalg.norm(d)) for d in (b - a, c - a, c - b))
    twice_area = float(np.linalg.norm(np.cross(b - a, c - a)))
    return math.inf if twice_area < 1e-9 * max(ab * ac, 1e-300) else ab * ac * bc / (2 * twice_area)


def parse_command(text: str) -> Command:
    """The command in ``text`` (one datagram, surrounding white space ignored).

    Raises:
        SdkError: with the reply for an unknown command, wrong arguments, a value out
            of range or a mission-pad command (there are no pads to see).
    """
    words = text.split()
    if not words or words[0] not in _ARGUMENTS:
        raise SdkError(UNKNOWN)
    name, rest = words[0], words[1:]
    checks = _ARGUMENTS[name]
    pads = len(rest) - len(checks)
    if pads and (pads != _MISSION_PADS.get(name) or not set(rest[len(checks):]) <= _PAD_IDS):
        raise SdkError(BAD_ARGUMENTS)
    if name == "jump" and not pads:
        raise SdkError(BAD_ARGUMENTS)
    args = tuple(check(word) for check, word in zip(checks, rest, strict=False))
    if name in ("go", "curve") and not pads:
        _check_points(args, name)
    return Command(name, args, mission_pad=bool(pads))


@dataclass(frozen=True)
class Telemetry:
    """What a state packet reports, in the SDK's units and frames.

    Attributes:
        pitch: degrees, nose up positive.
        roll: degrees, right side down positive.
        yaw: degrees, clockwise seen from above, from the heading at power-on, -180..180.
        velocity: (3,) vgx, vgy, vgz in dm/s along the heading frame x forward, y right,
            z down.
        acceleration: (3,) agx, agy, agz: the specific force the IMU measures along body
            x forward, y right, z down, in thousandths of g (about (0, 0, -1000) at rest).
        height: cm above the floor the drone took off from (``h``).
        tof: cm from the downward time-of-flight sensor to the floor, at least 10.
        baro: barometric altitude, m.
        battery: percent.
        motor_time: seconds the motors have run (``time``).
        temperature: (2,) lowest and highest temperature, degrees C.
        mission_pads: whether mission pad detection is on (``mon``).
    """

    pitch: int
    roll: int
    yaw: int
    velocity: tuple[int, int, int]
    acceleration: tuple[float, float, float]
    height: int
    tof: int
    baro: float
    battery: int
    motor_time: int
    temperature: tuple[int, int]
    mission_pads: bool = False


def format_state(t: Telemetry) -> str:
    """The SDK 2.0 state packet: ``mid:..;x:..;...;agz:..;`` and CR LF.

    No mission pad is ever seen: ``mid`` -1 and x, y, z -100 with detection on, -2 and
    -200 with it off, as the firmware sends.
    """
    mid, pad = (-1, -100) if t.mission_pads else (-2, -200)
    vgx, vgy, vgz = t.velocity
    agx, agy, agz = t.acceleration
    return (f"mid:{mid};x:{pad};y:{pad};z:{pad};mpry:0,0,0;pitch:{t.pitch};roll:{t.roll};"
            f"yaw:{t.yaw};vgx:{vgx};vgy:{vgy};vgz:{vgz};templ:{t.temperature[0]};"
            f"temph:{t.temperature[1]};tof:{t.tof};h:{t.height};bat:{t.battery};"
            f"baro:{t.baro:.2f};time:{t.motor_time};agx:{agx:.2f};agy:{agy:.2f};"
            f"agz:{agz:.2f};\r\n")


def query_reply(name: str, t: Telemetry, speed_cm_s: int, serial: str) -> str:
    """The reply to the read command ``name`` (``battery?`` ...)."""
    replies = {
        "speed?": str(speed_cm_s),
        "battery?": str(t.battery),
        "time?": str(t.motor_time),
        "height?": str(t.height),
        "temp?": str(round(sum(t.temperature) / 2)),
        "attitude?": f"pitch:{t.pitch};roll:{t.roll};yaw:{t.yaw};",
        "baro?": str(round(t.baro)),
        "tof?": f"{10 * t.tof}mm",
        "acceleration?": "agx:{:.2f};agy:{:.2f};agz:{:.2f};".format(*t.acceleration),
        "wifi?": "90",
        "sdk?": "20",
        "sn?": serial,
        "active?": "1",
        "hardware?": "TELLO",
    }
    return replies[name]

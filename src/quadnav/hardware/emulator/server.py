"""A DJI Tello (SDK 2.0) emulator that the real djitellopy client drives: :class:`TelloEmulator`.

The emulated drone answers on UDP port 8889 of its own address (``host``) and sends state
packets ten times a second to port 8890 of the client that sent ``command``, exactly as
the firmware does, so djitellopy 2.5 drives it unmodified: ``Tello(host=emulator.host)``.
Its flight is quadnav's simulator (:mod:`quadnav.hardware.emulator.drone`) in real time,
or ``time_scale`` times faster: a motion's ``ok`` comes only once the motion is over.

Protocol (:mod:`quadnav.hardware.sdk`): nothing is answered and no state is sent before
``command``; every SDK 2.0 command djitellopy sends is understood, with the SDK's
argument ranges (``out of range`` otherwise). Motions (``takeoff``, ``land``, ``go``,
``curve``, ``up`` ... ``back``, ``cw``/``ccw``, ``flip``) need the drone flying and not
already busy (``error Motor stop``, ``error Busy``); ``stop`` and ``emergency`` end a
motion at once (its reply is then ``error Stopped``); ``rc`` steers a flying drone that
is not busy; read commands are answered at once, even during a motion. ``speed`` sets
the speed of ``up`` ... ``back`` (default :data:`DEFAULT_SPEED_CM_S`). Video
(``streamon``), Wi-Fi, port and mission-pad settings are accepted and have no effect;
mission-pad motions answer ``error Not valid marker``. Below
:data:`~quadnav.hardware.sdk.LOW_BATTERY` percent the drone will not take off
(``error Low battery``) and lands by itself; with no command for
:data:`~quadnav.hardware.sdk.AUTO_LAND_AFTER` emulated seconds while flying (a motion in
progress does not count), it lands by itself too. Flips need half the battery and are not
flown (the drone hovers for a second). A command takes effect at the emulated time it
arrives.

Network: the emulator runs in its own Linux network namespace, joined to the client's by
a virtual Ethernet pair (:mod:`quadnav.hardware.emulator.netns`, which explains why). The client's
end gets :func:`~quadnav.hardware.emulator.netns.peer_address` of ``host``. Needs root (or
``unshare -rn``) and iproute2.

Faults for tests (:class:`Faults`): replies dropped with a probability, every reply
late, the link dead both ways after some seconds, a low battery, an aged battery that
drains faster (so that it runs low in flight). Network faults are in
wall-clock seconds (the client's clock); flight, battery and the auto-land timer in
emulated seconds. And the imperfections a real Tello shows (:meth:`Faults.real_tello`,
from djitellopy's issues and the SDK notes), each drawn from the emulator's seed: a move
(``go``, ``curve``, ``up`` ... ``back``) that ends a few centimetres off, a takeoff
height that varies, ``vgx``/``vgy`` that read a unit off now and then, and lost replies.
(``out of range`` for a move shorter than 20 cm on every axis is the SDK's own rule, which
the emulator always keeps.)

Ground truth: with ``truth``, the emulator writes the drone's true track to that file as it
flies (:class:`~quadnav.hardware.truth.TruthWriter`: UNIX time and world position, every
:data:`~quadnav.hardware.emulator.drone.TRACK_PERIOD` emulated seconds), each sample
before the reply it precedes, so a client that has heard ``ok`` to ``land`` finds the
landing in the file. It is the one channel from the emulator's insides to a client such
as ``quadnav tello fly --truth FILE``, as a motion-capture system's file would be beside a
real drone.
"""

from __future__ import annotations

import contextlib
import dataclasses
import ipaddress
import math
import socket
import threading
import time
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cache
from pathlib import Path

import numpy as np

from quadnav.arrays import FloatArray
from quadnav.config import require
from quadnav.errors import QuadnavError
from quadnav.hardware import sdk
from quadnav.hardware.emulator.drone import FLIP_TIME, TAKEOFF_HEIGHT, EmulatedDrone
from quadnav.hardware.emulator.netns import Link, NetNamespace
from quadnav.hardware.sdk import (
    AUTO_LAND_AFTER,
    COMMAND_PORT,
    DEFAULT_HOST,
    OK,
    STATE_PORT,
    Command,
    SdkError,
)
from quadnav.hardware.truth import TruthWriter

#: Speed of ``up`` ... ``back`` until ``speed`` sets another, cm/s.
DEFAULT_SPEED_CM_S = 100
#: Wall-clock seconds between state packets (10 Hz).
STATE_PERIOD = 0.1
#: Wall-clock seconds between steps of the emulator's clock; a step never advances the
#: flight by more than :data:`MAX_STEP` wall seconds (the emulator falls behind instead).
TICK = 0.01
MAX_STEP = 0.25
#: Replies of refused motions (none contains "ok", which djitellopy takes for success).
BUSY = "error Busy"
NOT_FLYING = "error Motor stop"
ALREADY_FLYING = "error Already flying"
AUTO_LANDING = sdk.AUTO_LAND
LOW_BATTERY_REPLY = "error Low battery"
STOPPED = sdk.MOTION_STOPPED
#: Battery needed for a flip, percent.
FLIP_BATTERY = 50
#: ``up`` ... ``back`` as unit steps in the heading frame (x forward, y left, z up).
_DIRECTIONS = {"up": (0, 0, 1), "down": (0, 0, -1), "left": (0, 1, 0), "right": (0, -1, 0),
               "forward": (1, 0, 0), "back": (-1, 0, 0)}
#: Commands accepted with no effect.
_NO_EFFECT = frozenset({"keepalive", "motoron", "motoroff", "throwfly", "streamon",
                        "streamoff", "mdirection", "wifi", "ap", "port", "setfps",
                        "setbitrate", "setresolution", "downvision"})


@dataclass(frozen=True)
class Faults:
    """Faults the emulator injects, for testing a client's error handling.

    Attributes:
        drop_replies: probability that a reply is lost, in [0, 1] (drawn from the
            emulator's seed); state packets still arrive.
        reply_delay_s: wall-clock seconds every reply is held back before it is sent.
        dead_after_s: wall-clock seconds after ``command`` at which the link dies both
            ways for good (no replies, no state, commands lost), or None. The drone then
            lands by itself :data:`AUTO_LAND_AFTER` emulated seconds after the last
            command it heard.
        battery: battery at power-on, percent (below
            :data:`~quadnav.hardware.sdk.LOW_BATTERY`: too low to fly).
        battery_drain: how many times faster than a new battery it drains in flight
            (>= 1; an aged battery's charge falls faster under load; idle, it drains as a
            new one, and the drone lands by itself
            once it reports less than :data:`~quadnav.hardware.sdk.LOW_BATTERY` percent).
        move_error_m: standard deviation, m, of where a move ends, per axis (the end of a
            ``go``, ``curve`` or ``up`` ... ``back`` is off by a normal draw).
        takeoff_spread_m: ``takeoff`` climbs to
            :data:`~quadnav.hardware.emulator.drone.TAKEOFF_HEIGHT` plus a uniform draw in
            +- this, m.
        velocity_noise: probability that ``vgx`` and that ``vgy`` of a state packet read
            one unit (dm/s) off, either way.
    """

    drop_replies: float = 0.0
    reply_delay_s: float = 0.0
    dead_after_s: float | None = None
    battery: float = 100.0
    battery_drain: float = 1.0
    move_error_m: float = 0.0
    takeoff_spread_m: float = 0.0
    velocity_noise: float = 0.0

    @classmethod
    def real_tello(cls) -> Faults:
        """What a real Tello shows, as reported in djitellopy's issues and the SDK notes:
        ``go`` ends about 2 cm off per axis, takeoff leaves it 0.7-0.9 m up, a quarter of
        the velocity readings are a unit off, one reply in a hundred is lost."""
        return cls(drop_replies=0.01, move_error_m=0.02, takeoff_spread_m=0.1,
                   velocity_noise=0.25)

    def __post_init__(self) -> None:
        require([
            (0 <= self.drop_replies <= 1,
             f"Tello emulator fault drop_replies {self.drop_replies}: expected 0 to 1"),
            (math.isfinite(self.reply_delay_s) and self.reply_delay_s >= 0,
             f"Tello emulator fault reply_delay_s {self.reply_delay_s}: expected >= 0 s"),
            (self.dead_after_s is None or (math.isfinite(self.dead_after_s)
                                           and self.dead_after_s >= 0),
             f"Tello emulator fault dead_after_s {self.dead_after_s}: expected None or "
             ">= 0 s"),
            (0 <= self.battery <= 100,
             f"Tello emulator fault battery {self.battery}: expected 0 to 100 percent"),
            (math.isfinite(self.battery_drain) and 1 <= self.battery_drain <= 1000,
             f"Tello emulator fault battery_drain {self.battery_drain}: expected 1 to 1000 "
             "times a new battery's"),
            (0 <= self.move_error_m <= 0.2,
             f"Tello emulator fault move_error_m {self.move_error_m}: expected 0 to 0.2 m"),
            (0 <= self.takeoff_spread_m <= 0.3,
             f"Tello emulator fault takeoff_spread_m {self.takeoff_spread_m}: expected 0 to "
             "0.3 m"),
            (0 <= self.velocity_noise <= 1,
             f"Tello emulator fault velocity_noise {self.velocity_noise}: expected 0 to 1")])


def check_host(host: str) -> str:
    """``host`` if it is a unicast IPv4 address an emulated drone can have (not loopback,
    multicast or unspecified), else QuadnavError."""
    try:
        address = ipaddress.IPv4Address(host)
    except ValueError:
        raise QuadnavError(f"Tello emulator host {host!r}: expected an IPv4 address such as "
                           f"{DEFAULT_HOST}") from None
    if address.is_loopback or address.is_multicast or address.is_unspecified:
        raise QuadnavError(f"Tello emulator host {host}: expected a unicast address outside "
                           f"127.0.0.0/8, e.g. {DEFAULT_HOST}")
    return str(address)


def djitellopy_namespace() -> NetNamespace:
    """The network namespace of this process's djitellopy sockets.

    djitellopy keeps one command socket (UDP 8889) and one state socket (8890) per
    process, bound by the first ``Tello()`` and kept until the process ends. If it has
    not bound them yet, they are bound now in a fresh namespace of their own, where
    they clash with no other process's djitellopy (e.g. a parallel test worker). Pass
    the result as ``client_netns`` to emulators used by this process's djitellopy.
    """
    from djitellopy import tello

    if not tello.threads_initialized:
        private = NetNamespace.create()
        try:
            private.call(lambda: tello.Tello(host=DEFAULT_HOST).end())
        finally:
            private.close()
    return NetNamespace.of_socket(tello.client_socket)


class TelloEmulator:
    """An emulated Tello on a network link of its own; use it as a context manager.

    Args:
        host: the drone's IPv4 address (see :func:`check_host`).
        start: (3,) world position on the floor before takeoff, m.
        yaw: world heading of the nose at power-on, rad counter-clockwise from +x.
        time_scale: emulated seconds per wall-clock second (> 0): motions, the battery,
            the flight time and the auto-land timer run this much faster.
        faults: injected faults (default: none).
        seed: seed of the dropped replies and the imperfections (each drawn from a
            stream of its own, so a flight's moves and takeoff repeat for a seed).
        client_netns: the network namespace of the client (default: the caller's). For
            djitellopy in this process, :func:`djitellopy_namespace`.
        truth: a file to write the drone's true track to as it flies (see the module),
            or None.
    """

    def __init__(self, host: str = DEFAULT_HOST, start: Sequence[float] = (0.0, 0.0, 0.0),
                 yaw: float = 0.0, time_scale: float = 1.0, faults: Faults | None = None,
                 seed: int = 0, client_netns: NetNamespace | None = None,
                 truth: str | Path | None = None) -> None:
        if not (math.isfinite(time_scale) and time_scale > 0):
            raise QuadnavError(f"Tello emulator time scale {time_scale}: expected a number > 0")
        start_point = np.asarray(start, dtype=np.float64)
        if start_point.shape != (3,) or not np.all(np.isfinite(start_point)):
            raise QuadnavError(f"Tello emulator start {start!r}: expected 3 finite numbers, m")
        self.host = check_host(host)
        self.time_scale = float(time_scale)
        self.faults = faults or Faults()
        self._drone = EmulatedDrone(start_point, yaw, battery=self.faults.battery,
                                    battery_drain=self.faults.battery_drain)
        self._rng = np.random.default_rng(seed)
        self._move_rng, self._takeoff_rng, self._velocity_rng = (
            np.random.default_rng([seed, stream]) for stream in (1, 2, 3))
        self._client_netns = client_netns
        self._lock = threading.Lock()
        self._stopping = threading.Event()
        self._received: list[tuple[float, str]] = []
        self._outbox: list[tuple[float, str, tuple[str, int]]] = []
        self._client: tuple[str, int] | None = None
        self._connected_at: float | None = None
        self._pending: tuple[str, int] | None = None
        self._auto_landing = False
        self._mission_pads = False
        self._speed = DEFAULT_SPEED_CM_S
        self._last_command = 0.0
        self._advanced = 0.0  # wall-clock time the flight was advanced to
        self._serial = f"0TQEMU{seed % 10**8:08d}"
        self._threads: list[threading.Thread] = []
        self._namespaces: list[NetNamespace] = []
        self._link: Link | None = None
        self._socket: socket.socket | None = None
        self._truth_path = truth
        self._truth: TruthWriter | None = None
        self._truth_written = 0  # samples of the track written to it
        self._unix_offset = 0.0  # UNIX time minus the monotonic clock, s

    # --- life cycle ----------------------------------------------------------------

    def start(self) -> TelloEmulator:
        """Make the network link and the socket, and start the emulator's threads."""
        _warm_up()
        try:
            if self._truth_path is not None:
                self._truth = TruthWriter(self._truth_path)
            drone_ns = NetNamespace.create()
            self._namespaces.append(drone_ns)
            client_ns = self._client_netns
            if client_ns is None:
                client_ns = NetNamespace.current()
                self._namespaces.append(client_ns)
            self._link = Link(client_ns, drone_ns, self.host)
            self._socket = drone_ns.call(
                lambda: socket.socket(socket.AF_INET, socket.SOCK_DGRAM))
            self._socket.bind(("0.0.0.0", COMMAND_PORT))
            self._socket.settimeout(TICK)
        except BaseException:
            self.stop()
            raise
        self._advanced = time.monotonic()  # the flight's time starts now
        self._unix_offset = time.time() - self._advanced
        for target, name in ((self._receive, "receiver"), (self._run, "clock")):
            thread = threading.Thread(target=target, name=f"tello-emulator-{name}", daemon=True)
            thread.start()
            self._threads.append(thread)
        return self

    def stop(self) -> None:
        """Stop the threads, close the socket and remove the link."""
        self._stopping.set()
        for thread in self._threads:
            thread.join()
        self._threads.clear()
        if self._socket is not None:
            self._socket.close()
            self._socket = None
        if self._link is not None:
            self._link.close()
            self._link = None
        for namespace in self._namespaces:
            namespace.close()
        self._namespaces.clear()
        if self._truth is not None:
            self._truth.close()
            self._truth = None

    def __enter__(self) -> TelloEmulator:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    # --- what tests look at --------------------------------------------------------

    @property
    def time(self) -> float:
        """Emulated seconds since the emulator was made."""
        with self._lock:
            return self._drone.time

    def track(self) -> tuple[FloatArray, FloatArray]:
        """The emulated flight so far: times (N,) emulated s and world positions (N, 3) m,
        every :data:`~quadnav.hardware.emulator.drone.TRACK_PERIOD` s."""
        with self._lock:
            return self._drone.track()

    def commands_received(self) -> list[tuple[float, str]]:
        """Every datagram the drone heard: (emulated s, text), in order."""
        with self._lock:
            return list(self._received)

    def flying(self) -> bool:
        """Whether the motors are running."""
        with self._lock:
            return self._drone.flying

    # --- threads -------------------------------------------------------------------

    def _receive(self) -> None:
        """Take datagrams and answer them, until stopped."""
        assert self._socket is not None
        while not self._stopping.is_set():
            try:
                data, address = self._socket.recvfrom(2048)
            except TimeoutError:
                continue
            except OSError:
                return
            with self._lock:
                if not self._link_dead():
                    self._advance(time.monotonic())  # the command acts from its arrival
                    self._handle(data.decode("utf-8", errors="replace").strip(), address)

    def _run(self) -> None:
        """The emulator's clock: fly, finish motions, land by itself, send due replies
        and state packets, every :data:`TICK` s until stopped."""
        next_state = time.monotonic()
        while not self._stopping.wait(TICK):
            now = time.monotonic()
            with self._lock:
                self._advance(now)
                self._flush(now)
                if self._client is not None and now >= next_state:
                    next_state = max(next_state + STATE_PERIOD, now)
                    state = sdk.format_state(self._noisy(
                        self._drone.telemetry(self._mission_pads)))
                    self._send(state, (self._client[0], STATE_PORT))

    # --- protocol (called with the lock held) ---------------------------------------

    def _advance(self, now: float) -> None:
        """Fly from the last advance up to wall-clock ``now`` (at most :data:`MAX_STEP`
        of it), then finish motions and land by itself as due."""
        if now > self._advanced:
            ended = self._drone.advance(min(now - self._advanced, MAX_STEP) * self.time_scale)
            self._advanced = now
            self._write_truth(now)
            self._after_step(ended)

    def _write_truth(self, now: float) -> None:
        """Write the track's new samples to the truth file, if any, stamped with the UNIX
        time each stands for (the emulated time ``now`` stands for, less the emulated
        seconds since them over the time scale)."""
        if self._truth is None:
            return
        times, positions = self._drone.track(self._truth_written)
        if len(times):
            back = (self._drone.time - times) / self.time_scale
            self._truth.write(self._unix_offset + now - back, positions)
            self._truth_written += len(times)

    def _handle(self, text: str, address: tuple[str, int]) -> None:
        self._received.append((self._drone.time, text))
        self._last_command = self._drone.time
        if self._client is None and text != "command":
            return  # not in SDK mode yet: the firmware ignores it
        try:
            command = sdk.parse_command(text)
        except SdkError as error:
            if not sdk.SILENT.intersection(text.split()[:1]):
                self._reply(error.reply, address)
            return
        if command.name == "command":
            self._client = address
            if self._connected_at is None:
                self._connected_at = time.monotonic()
        reply = self._execute(command, address)
        if reply is not None:
            self._reply(reply, address)

    def _execute(self, command: Command, address: tuple[str, int]) -> str | None:
        """Carry out ``command``: the immediate reply, or None (none, or once the motion
        is over)."""
        name, args, drone = command.name, command.args, self._drone
        if name.endswith("?"):
            return sdk.query_reply(name, drone.telemetry(self._mission_pads), self._speed,
                                   self._serial)
        if name == "rc":
            if drone.flying and not drone.busy:
                drone.sticks(*args)
            return None
        if name == "emergency":
            self._cancel()
            drone.cut_motors()
            return None
        if name == "reboot":
            if not drone.flying:
                self._client = None
            return None
        if name == "stop":
            if self._auto_landing:
                return AUTO_LANDING
            self._cancel()
            drone.hold()
            return OK
        if name in ("mon", "moff"):
            self._mission_pads = name == "mon"
            return OK
        if name == "speed":
            self._speed = int(args[0])
            return OK
        if name in ("command", *_NO_EFFECT):
            return OK
        if command.mission_pad:
            return sdk.NO_MARKER
        refusal = self._refusal(name)
        if refusal is not None:
            return refusal
        self._start_motion(name, args)
        self._pending = address
        return None

    def _refusal(self, name: str) -> str | None:
        """Why the motion ``name`` cannot start now, or None."""
        drone = self._drone
        if name == "takeoff":
            if drone.flying or drone.busy:
                return ALREADY_FLYING
            return LOW_BATTERY_REPLY if drone.low_battery else None
        if not drone.flying:
            return NOT_FLYING
        if self._auto_landing:
            return AUTO_LANDING
        if drone.busy:
            return BUSY
        if name == "flip" and drone.battery_percent < FLIP_BATTERY:
            return LOW_BATTERY_REPLY
        return None

    def _start_motion(self, name: str, args: tuple[int | str, ...]) -> None:
        drone = self._drone
        if name == "takeoff":
            spread = self.faults.takeoff_spread_m
            drone.takeoff(TAKEOFF_HEIGHT + spread * self._takeoff_rng.uniform(-1.0, 1.0))
        elif name == "land":
            drone.land()
        elif name in _DIRECTIONS:
            offset = np.multiply(_DIRECTIONS[name], args[0]) / 100.0
            drone.move(offset + self._move_error(), self._speed / 100.0)
        elif name in ("cw", "ccw"):
            drone.turn(math.radians(args[0]) * (-1.0 if name == "cw" else 1.0))
        elif name == "go":
            drone.move(np.array(args[:3], dtype=float) / 100.0 + self._move_error(),
                       args[3] / 100.0)
        elif name == "curve":
            points = np.array(args[:6], dtype=float).reshape(2, 3) / 100.0
            drone.curve(points[0], points[1] + self._move_error(), args[6] / 100.0)
        else:  # flip
            drone.pause(FLIP_TIME)

    def _move_error(self) -> FloatArray:
        """Where the next move ends off its target, (3,) m, heading frame."""
        return self._move_rng.normal(0.0, self.faults.move_error_m, 3)

    def _noisy(self, telemetry: sdk.Telemetry) -> sdk.Telemetry:
        """``telemetry`` with ``vgx`` and ``vgy`` each a unit off at the fault's rate."""
        if not self.faults.velocity_noise:
            return telemetry
        off = self._velocity_rng.random(2) < self.faults.velocity_noise
        units = np.where(off, self._velocity_rng.choice((-1, 1), 2), 0)
        vgx, vgy, vgz = telemetry.velocity
        return dataclasses.replace(telemetry, velocity=(vgx + int(units[0]),
                                                        vgy + int(units[1]), vgz))

    def _cancel(self) -> None:
        """End the motion in progress, if any: its reply is :data:`STOPPED`."""
        if self._pending is not None:
            self._reply(STOPPED, self._pending)
            self._pending = None

    def _after_step(self, ended: bool) -> None:
        """Reply to a motion that is over, and land by itself when it must."""
        drone = self._drone
        if ended:
            self._last_command = max(self._last_command, drone.time)
            self._auto_landing = False
        if self._pending is not None and not drone.busy:
            self._reply(OK if ended else NOT_FLYING, self._pending)
            self._pending = None
        if drone.flying and not drone.busy and (
                drone.low_battery
                or drone.time - self._last_command >= AUTO_LAND_AFTER):
            drone.land()
            self._auto_landing = True

    def _link_dead(self) -> bool:
        dead_after = self.faults.dead_after_s
        return (dead_after is not None and self._connected_at is not None
                and time.monotonic() - self._connected_at >= dead_after)

    def _reply(self, text: str, address: tuple[str, int]) -> None:
        """Send a reply now or after the delay, unless it is dropped."""
        if self.faults.drop_replies and self._rng.random() < self.faults.drop_replies:
            return
        if self.faults.reply_delay_s:
            self._outbox.append((time.monotonic() + self.faults.reply_delay_s, text, address))
        else:
            self._send(text, address)

    def _flush(self, now: float) -> None:
        """Send the delayed replies that are due."""
        due = [item for item in self._outbox if item[0] <= now]
        self._outbox = [item for item in self._outbox if item[0] > now]
        for _, text, address in due:
            self._send(text, address)

    def _send(self, text: str, address: tuple[str, int]) -> None:
        if self._socket is None or self._link_dead():
            return
        with contextlib.suppress(OSError):  # no one there: a radio link loses it too
            self._socket.sendto(text.encode("utf-8"), address)


@cache
def _warm_up() -> None:
    """Compile (or load) the flight's compiled code before the clock runs, so the first
    motion is not held up by the compiler."""
    drone = EmulatedDrone((0.0, 0.0, 0.0))
    drone.telemetry()  # the state packets' attitude
    drone.takeoff()
    drone.advance(0.01)
    drone.cut_motors()
    drone.advance(0.01)

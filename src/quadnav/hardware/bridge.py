"""Flying a checked :class:`~quadnav.hardware.flight_plan.FlightPlan` on a Tello — or
printing every command a flight would send.

The sequence: ``command`` and the first state packet; the battery check (below
``min_battery`` percent the takeoff is refused and nothing flies); ``takeoff``; then

* ``waypoints`` mode: the ``go`` moves through the pruned route, made from the height the
  drone reports after takeoff (it is only *about* 0.8 m), each sent once the one before
  has answered ``ok``;
* ``rc`` mode: ``rc`` sticks at ``rc_rate`` Hz (drone time) from the trajectory's
  velocity plus a correction towards its position from the dead-reckoned estimate (see
  :mod:`quadnav.hardware.rc`), until the estimate is within :data:`GOAL_TOLERANCE` of the
  trajectory's end (or :data:`RC_SETTLE` s after it); then the sticks are centred;

then ``land``. **Safe stop**: a reply overdue by more than the link timeout, no state
packet for that long, a refused command, a dead-reckoned position outside the geofence
(``rc``) or Ctrl-C centre the sticks, send ``stop`` (hover) and then ``land``, resent up
to :data:`LAND_ATTEMPTS` times; a landing counts as confirmed by its ``ok`` or by a state
packet with the drone on the floor.

Time: the drone's seconds are the wall clock's times ``time_scale`` (1 for a real drone;
the emulator's scale in tests), see :class:`Clock`; the link timeout is wall-clock.
"""

from __future__ import annotations

import logging
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from enum import Enum
from pathlib import Path
from typing import TextIO

import numpy as np

from quadnav.errors import QuadnavError
from quadnav.hardware.dead_reckoning import DeadReckoning
from quadnav.hardware.flight_plan import TAKEOFF_HEIGHT, FlightPlan
from quadnav.hardware.frames import FloatArray
from quadnav.hardware.geofence import GeofenceError
from quadnav.hardware.link import (
    LINK_TIMEOUT,
    CommandRefusedError,
    DryRunLink,
    Link,
    LinkLostError,
)
from quadnav.hardware.moves import MoveError, go_speed
from quadnav.hardware.rc import StickRounder, stick_values, tracking_velocity
from quadnav.hardware.tello_log import LOG_NAME, TelloLog, open_log
from quadnav.world.placement import format_point

#: Flight modes.
MODES = ("waypoints", "rc")
#: Least battery, percent, to take off with.
MIN_BATTERY = 20
#: Drone seconds a takeoff, a landing and a ``stop`` may take before the reply is due.
TAKEOFF_TIME = 10.0
LAND_TIME = 10.0
STOP_TIME = 2.0
#: A ``go`` move's reply is due after MOVE_FACTOR times its length over its speed plus
#: MOVE_SETTLE drone seconds (speed ramps, settling).
MOVE_FACTOR = 1.25
MOVE_SETTLE = 3.0
#: ``rc`` mode: stick updates per drone second, and the position correction's gain, 1/s.
RC_RATE = 20.0
RC_GAIN = 1.0
#: ``rc`` mode ends once the estimate is this close to the trajectory's end, m ...
GOAL_TOLERANCE = 0.05
#: ... or this many drone seconds after the trajectory's end.
RC_SETTLE = 3.0
#: djitellopy drops an ``rc`` command sent within 1 ms of the last: the highest rate, Hz.
MAX_RC_WALL_RATE = 500.0
#: How many times a safe stop sends ``land``.
LAND_ATTEMPTS = 3
#: A reported height at or below this counts as on the floor, cm.
LANDED_HEIGHT_CM = 5
#: File name of the figure of the flight in the output folder.
TRACK_FIGURE = "tello_track.png"


class Status(Enum):
    """How a flight ended."""

    LANDED = "landed"            # flown to the end and landed
    STOPPED = "stopped"          # a fault: safe stop and landing
    REFUSED = "refused"          # takeoff refused: nothing flown
    INTERRUPTED = "interrupted"  # Ctrl-C: safe stop and landing
    DRY_RUN = "dry run"          # printed, nothing sent


@dataclass(frozen=True)
class Outcome:
    """How a flight ended, and one line saying so."""

    status: Status
    message: str


@dataclass(frozen=True)
class BridgeSettings:
    """How to fly.

    Attributes:
        mode: one of :data:`MODES`.
        min_battery: least battery to take off with, percent.
        rc_rate: ``rc`` updates per drone second, Hz (at least 20 is sensible).
        rc_gain: ``rc`` position correction, 1/s.
        link_timeout: wall-clock seconds of silence that count as a lost link.
        time_scale: drone seconds per wall-clock second (1: a real drone).
    """

    mode: str = "waypoints"
    min_battery: int = MIN_BATTERY
    rc_rate: float = RC_RATE
    rc_gain: float = RC_GAIN
    link_timeout: float = LINK_TIMEOUT
    time_scale: float = 1.0

    def __post_init__(self) -> None:
        checks = [
            (self.mode in MODES, f"unknown mode {self.mode!r}; expected one of "
                                 f"{', '.join(MODES)}"),
            (0 <= self.min_battery <= 100,
             f"battery threshold {self.min_battery}: expected 0..100 percent"),
            (self.rc_rate > 0 and (self.mode != "rc"
                                   or self.rc_rate * self.time_scale <= MAX_RC_WALL_RATE),
             f"rc rate {self.rc_rate:g} Hz at time scale {self.time_scale:g}: expected at "
             f"most {MAX_RC_WALL_RATE:g} commands per wall-clock second"),
            (self.rc_gain >= 0, f"rc gain {self.rc_gain:g}: expected >= 0 per second"),
            (self.link_timeout > 0, f"link timeout {self.link_timeout:g}: expected > 0 s"),
            (self.time_scale > 0, f"time scale {self.time_scale:g}: expected > 0"),
        ]
        for ok, message in checks:
            if not ok:
                raise QuadnavError(message)


class Clock:
    """Drone time: seconds since the clock was made, times ``time_scale``."""

    def __init__(self, time_scale: float = 1.0) -> None:
        self.time_scale = time_scale
        self._began = time.monotonic()

    def now(self) -> float:
        """Drone seconds since the start."""
        return self.time_scale * (time.monotonic() - self._began)

    def sleep_until(self, when: float) -> None:
        """Wait until drone time ``when``."""
        delay = (when - self.now()) / self.time_scale
        if delay > 0:
            time.sleep(delay)

    def wall(self, seconds: float) -> float:
        """Drone ``seconds`` in wall-clock seconds."""
        return seconds / self.time_scale


class VirtualClock(Clock):
    """A dry run's clock: waiting moves it on at once."""

    def __init__(self) -> None:
        super().__init__()
        self._now = 0.0

    def now(self) -> float:
        """Drone seconds waited so far."""
        return self._now

    def sleep_until(self, when: float) -> None:
        """Jump to ``when``."""
        self._now = max(self._now, when)


class _Flight:
    """One flight of ``plan`` over ``link`` (see the module's description)."""

    def __init__(self, plan: FlightPlan, link: Link, estimator: DeadReckoning,
                 settings: BridgeSettings, clock: Clock, log: TelloLog) -> None:
        self.plan, self.link, self.estimator = plan, link, estimator
        self.settings, self.clock, self.log = settings, clock, log

    def run(self) -> Outcome:
        link, settings = self.link, self.settings
        try:
            link.connect()
        except LinkLostError as error:
            return self._end(Status.REFUSED, f"{error}: nothing was flown")
        if link.reports_state:
            battery = link.get_battery()
            if battery < settings.min_battery:
                return self._end(Status.REFUSED, f"battery {battery} % is below the "
                                 f"{settings.min_battery} % needed: takeoff refused, "
                                 "nothing was flown")
        try:
            link.command("takeoff", self._timeout(TAKEOFF_TIME))
            done = self._follow() if settings.mode == "rc" else self._go()
        except (LinkLostError, CommandRefusedError, GeofenceError, MoveError) as error:
            return self._safe_stop(Status.STOPPED, str(error))
        except KeyboardInterrupt:
            return self._safe_stop(Status.INTERRUPTED, "interrupted (Ctrl-C)")
        where = format_point(self.plan.landing_ground)
        landed, how = self._land()
        if not link.reports_state:
            return self._end(Status.DRY_RUN, f"{done}, then land at {where}; nothing was "
                             "sent")
        if not landed:
            return self._end(Status.STOPPED, f"flew {done}, then {how}")
        return self._end(Status.LANDED, f"landed at {where} after {done}")

    def _timeout(self, drone_seconds: float) -> float:
        """Wall-clock seconds to wait for the reply to a command that takes
        ``drone_seconds``."""
        return self.clock.wall(drone_seconds) + self.settings.link_timeout

    def _go(self) -> str:
        """Fly the ``go`` moves; returns what was done, for the outcome."""
        height = (self.link.get_height() / 100.0 if self.link.reports_state
                  else TAKEOFF_HEIGHT)
        moves = self.plan.go_moves(height, go_speed(self.plan.speed))
        for move in moves:
            self.link.command(move.command,
                              self._timeout(MOVE_FACTOR * move.duration + MOVE_SETTLE))
        return f"{len(moves)} go moves"

    def _follow(self) -> str:
        """Follow the trajectory with ``rc`` sticks; returns what was done."""
        plan, link, settings, clock = self.plan, self.link, self.settings, self.clock
        trajectory, period = plan.trajectory, 1.0 / settings.rc_rate
        rounder = StickRounder()
        began, ticks = clock.now(), 0
        while True:
            t = clock.now() - began
            if link.state_age() > settings.link_timeout:
                raise LinkLostError(f"no state packet for {settings.link_timeout:g} s "
                                    f"during the rc flight (t = {t:.1f} s)")
            reference = trajectory.position(t)
            position = self.estimator.position() if link.reports_state else reference
            if not plan.fence.point_ok(position):
                raise GeofenceError(f"geofence: the dead-reckoned position "
                                    f"{format_point(position)} left the fence at "
                                    f"t = {t:.1f} s")
            miss = float(np.linalg.norm(position - trajectory.position(trajectory.duration)))
            if t >= trajectory.duration and (miss <= GOAL_TOLERANCE
                                             or t >= trajectory.duration + RC_SETTLE):
                break
            velocity = tracking_velocity(reference, trajectory.velocity(t), position,
                                         settings.rc_gain)
            self.estimator.expect(velocity)
            link.send_rc_control(*rounder(stick_values(velocity, plan.frame.yaw)))
            ticks += 1
            clock.sleep_until(began + ticks * period)
        link.send_rc_control(0, 0, 0, 0)
        self.estimator.expect(None)
        return (f"{ticks} rc commands over {t:.1f} s (estimate {100 * miss:.0f} cm from the "
                "trajectory's end)")

    def _safe_stop(self, status: Status, reason: str) -> Outcome:
        """Centre the sticks, hover, land; the outcome says why and whether it landed."""
        link = self.link
        self.log.event(f"safe stop: {reason}")
        if self.settings.mode == "rc":
            link.send_rc_control(0, 0, 0, 0)
        try:
            link.command("stop", self._timeout(STOP_TIME))
        except (LinkLostError, CommandRefusedError) as error:
            self.log.event(f"stop: {error}")
        _, how = self._land()
        return self._end(status, f"{reason}; safe stop: stopped, {how}")

    def _land(self) -> tuple[bool, str]:
        """Send ``land`` until it is confirmed: whether it was, and how it went."""
        for _ in range(LAND_ATTEMPTS):
            try:
                self.link.command("land", self._timeout(LAND_TIME))
                return True, "landed"
            except (LinkLostError, CommandRefusedError) as error:
                self.log.event(f"land: {error}")
            if self._on_floor():
                return True, "landed (seen in the state packets)"
        return False, (f"sent land {LAND_ATTEMPTS} times with no confirmation: the link is "
                       "down; a Tello lands by itself 15 s after its last command")

    def _on_floor(self) -> bool:
        """Whether fresh state packets say the drone is on the floor."""
        link = self.link
        return (link.reports_state and link.state_age() <= self.settings.link_timeout
                and link.get_height() <= LANDED_HEIGHT_CM)

    def _end(self, status: Status, message: str) -> Outcome:
        self.log.event(f"{status.value}: {message}")
        return Outcome(status, message)


def _tello_link(host: str, log: TelloLog, estimator: DeadReckoning,
                settings: BridgeSettings) -> Link:
    """djitellopy's client for the drone at ``host``; QuadnavError without djitellopy."""
    try:
        from quadnav.hardware.tello_link import TelloLink
    except ImportError:
        raise QuadnavError("flying a Tello needs djitellopy: pip install 'quadnav[tello]' "
                           "(or use --dry-run)") from None
    TelloLink.LOGGER.setLevel(logging.WARNING)  # its INFO lines repeat what the log holds
    try:
        return TelloLink(host, log, estimator.update, settings.link_timeout)
    except OSError as error:
        raise QuadnavError(f"cannot open djitellopy's UDP port 8889: {error.strerror} (is "
                           "another Tello program running?)") from None


def fly(plan: FlightPlan, settings: BridgeSettings, folder: str | Path,
        host: str | None = None, stream: TextIO = sys.stdout,
        truth: Callable[[], FloatArray] | None = None) -> tuple[Outcome, FloatArray]:
    """Fly ``plan`` on the Tello at ``host`` — or, with no host, print the commands of a
    dry run to ``stream`` — and write the log and the figure into ``folder``.

    Args:
        plan: a checked flight plan.
        settings: mode, safety thresholds, rates, time scale.
        folder: gets :data:`~quadnav.hardware.tello_log.LOG_NAME` and :data:`TRACK_FIGURE`.
        host: the drone's IPv4 address; None for a dry run.
        stream: where a dry run prints.
        truth: gives the drone's true track (N, 3), m, after the flight, when known (an
            emulator's), to draw beside the dead-reckoned one.

    Returns:
        The outcome, and the dead-reckoned track (N, 4): drone seconds, map x, y, z (m).

    Raises:
        MoveError: (waypoints mode) the route cannot be flown with ``go`` moves; nothing
            was sent.
    """
    if settings.mode == "waypoints":  # moves the SDK cannot fly: refused before anything
        plan.go_moves(TAKEOFF_HEIGHT, go_speed(plan.speed))
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    dry_run = host is None
    clock = VirtualClock() if dry_run else Clock(settings.time_scale)
    estimator = DeadReckoning(plan.frame, settings.time_scale)
    with open_log(folder / LOG_NAME, map=plan.fence.world.name, mode=settings.mode,
                  host=host, dry_run=dry_run, start=plan.problem.start.tolist(),
                  goal=plan.problem.goal.tolist(), margin_m=plan.fence.margin,
                  yaw_rad=plan.frame.yaw, speed_m_s=plan.speed,
                  time_scale=settings.time_scale) as log:
        link = DryRunLink(log, stream) if dry_run else _tello_link(host, log, estimator,
                                                                   settings)
        try:
            outcome = _Flight(plan, link, estimator, settings, clock, log).run()
        finally:
            link.close()
    from quadnav.hardware.track_figure import track_figure  # matplotlib: only when needed
    from quadnav.viz.figures import save_figure

    track = estimator.track()
    flown = {"dead reckoning (state packets)": track[:, 1:]}
    if truth is not None:
        flown["true track (emulator)"] = truth()
    save_figure(track_figure(plan, settings.mode, flown, outcome.status.value),
                folder / TRACK_FIGURE)
    return outcome, track

"""Flying a checked :class:`~quadnav.hardware.bridge.flight_plan.FlightPlan` on a Tello — or
printing every command a flight would send.

The sequence: ``command`` and the first state packet; the battery check (below
``min_battery`` percent, or too low for the flight's expected time, the takeoff is
refused and nothing flies); ``takeoff``; then

* ``waypoints`` mode: the ``go`` moves through the pruned route, made from the height the
  drone reports after takeoff (it is only *about* 0.8 m), each sent once the one before
  has answered ``ok``;
* ``curves`` mode: as ``waypoints`` through the start's and the goal's zones, and between
  them ``curve`` and ``go`` commands that follow the trajectory within a few centimetres
  (:mod:`quadnav.hardware.bridge.curves`), every centimetre of each checked against the fence;
* ``rc`` mode: ``rc`` sticks at ``rc_rate`` Hz (drone time) from the trajectory's
  velocity plus a correction towards its position from the dead-reckoned estimate (a
  dry run's drone flies the sticks exactly; see :mod:`quadnav.hardware.bridge.rc`), each
  bounded so that a link lost right after it cannot carry the drone out of the geofence
  (on a leg out of or into the margin: out of the leg's room; see
  :mod:`quadnav.hardware.bridge.lost_link`; the trajectory is followed more slowly where that
  bound bites), until the estimate is within :data:`GOAL_TOLERANCE` of the trajectory's
  end horizontally (the landing is straight down), or :data:`RC_SETTLE` s after it; then
  the sticks are centred;

then ``land``. **Where it landed**: one place, the dead-reckoned estimate when the landing
was confirmed (:mod:`quadnav.hardware.bridge.dead_reckoning`, which also takes in each move's
``ok``), with its 1-sigma uncertainty; a flight flown to its end landed at the goal when
that place lies within :data:`LANDING_TOLERANCE` of the floor under the goal, else off
it. **Safe stop**: a reply overdue by more than the link timeout, no state
packet for that long, a refused command, a dead-reckoned position outside the geofence
(``rc``; on a leg, outside the leg's room, see :meth:`_Flight._region`) or a stop
signal (Ctrl-C, SIGTERM, SIGHUP) centre the sticks, send ``stop`` (hover) and then
``land``, resent up to three times; a landing counts as confirmed by
its ``ok`` or by a state packet with the drone on the floor
(:mod:`quadnav.hardware.bridge.landing`). Once the landing has begun, further stop signals are
held until it is over (:class:`~quadnav.signals.StopSignalHandler`). **Landing by itself**: the
reply ``error Auto land``, or a battery below :data:`~quadnav.hardware.sdk.LOW_BATTERY`
percent in flight, means the Tello lands (or is about to) by itself: the bridge sends
``land`` once and waits for the state packets to show it on the floor. A landing that is
never confirmed is a **lost link**: the outcome says what the drone does if it heard
nothing more (it lands by itself 15 s after the last command it heard).

Time: the drone's seconds are the wall clock's times ``time_scale`` (1 for a real drone;
the emulator's scale in tests), see :class:`~quadnav.hardware.bridge.drone_clock.Clock`; the
link timeout is wall-clock.
"""

from __future__ import annotations

import dataclasses
import io
import logging
import signal
import warnings
from dataclasses import dataclass
from enum import Enum
from pathlib import Path
from typing import TextIO

import numpy as np

from quadnav.arrays import FloatArray
from quadnav.config import require
from quadnav.errors import QuadnavError
from quadnav.hardware.bridge.curves import Curve
from quadnav.hardware.bridge.dead_reckoning import DeadReckoning, Estimate
from quadnav.hardware.bridge.drone_clock import Clock, VirtualClock
from quadnav.hardware.bridge.flight_plan import TAKEOFF_HEIGHT, FlightPlan
from quadnav.hardware.bridge.frames import to_m
from quadnav.hardware.bridge.geofence import GeofenceError, Region
from quadnav.hardware.bridge.landing import Lander
from quadnav.hardware.bridge.link import (
    LINK_TIMEOUT,
    AutoLandingError,
    CommandRefusedError,
    DryRunLink,
    Link,
    LinkLostError,
)
from quadnav.hardware.bridge.lost_link import (
    HOLD,
    LEG_CREEP,
    LostLinkBound,
    SlowedFlight,
    run_length,
    slowed_flight,
)
from quadnav.hardware.bridge.moves import MoveError, go_speed
from quadnav.hardware.bridge.rc import StickRounder, stick_values, stick_velocity, tracking_velocity
from quadnav.hardware.bridge.tello_log import LOG_NAME, TelloLog, open_log
from quadnav.hardware.sdk import AUTO_LAND_AFTER, LOW_BATTERY
from quadnav.hardware.truth import flight_truth
from quadnav.signals import StopSignalHandler, signal_name, signal_of
from quadnav.sim.settings import SimSettings
from quadnav.world.placement import format_point

#: Flight modes.
MODES = ("waypoints", "curves", "rc")
#: Least battery, percent, to take off with.
MIN_BATTERY = 20
#: Drone seconds a full battery flies (a Tello's is about 13 minutes), and the flight
#: time a takeoff and a landing take together, for the battery check.
BATTERY_FLIGHT_TIME = 720.0
TAKEOFF_AND_LANDING = 10.0
#: Drone seconds a takeoff may take before the reply is due.
TAKEOFF_TIME = 10.0
#: A ``go`` move's reply is due after MOVE_FACTOR times its length over its speed plus
#: MOVE_SETTLE drone seconds (speed ramps, settling).
MOVE_FACTOR = 1.25
MOVE_SETTLE = 3.0
#: ``rc`` mode: stick updates per drone second, and the position correction's gain, 1/s.
RC_RATE = 20.0
RC_GAIN = 1.0
#: ``rc`` mode ends once the estimate is this close to the trajectory's end horizontally,
#: m ...
GOAL_TOLERANCE = 0.05
#: ... or this many drone seconds after the trajectory's end.
RC_SETTLE = 3.0
#: A dry ``rc`` flight that ends further than this from the trajectory's end horizontally,
#: m, is refused: the goal tolerance, plus the run of one stick percent, as far as the
#: drone stops short of a wall or block that a leg into the margin heads for.
RC_REACH = GOAL_TOLERANCE + run_length(LEG_CREEP)
#: djitellopy drops an ``rc`` command sent within 1 ms of the last: the highest rate, Hz.
MAX_RC_WALL_RATE = 500.0
#: File name of the figure of the flight in the output folder.
TRACK_FIGURE = "tello_track.png"
#: A flight flown to its end lands at the goal when the dead-reckoned landing place lies
#: this close to the floor under the goal horizontally, m: a simulated flight's goal
#: tolerance (``quadnav fly``).
LANDING_TOLERANCE = SimSettings().goal_tolerance


class Status(Enum):
    """How a flight ended."""

    LANDED = "landed"                 # flown to the end and landed at the goal
    OFF_GOAL = "landed off the goal"  # flown to the end, landed beyond the tolerance
    STOPPED = "stopped"               # a fault: safe stop, on the floor
    AUTO_LANDED = "landed by itself"  # low battery: the Tello landed by itself
    LINK_LOST = "link lost"           # no landing confirmed: the drone's end is not known
    REFUSED = "refused"               # takeoff refused: nothing flown
    INTERRUPTED = "interrupted"       # a stop signal: safe stop and landing
    DRY_RUN = "dry run"               # printed, nothing sent


@dataclass(frozen=True)
class Outcome:
    """How a flight ended, and one line saying so; ``signum``: the stop signal that
    ended it (:attr:`Status.INTERRUPTED`), else None; ``landing``: where the dead
    reckoning put the drone when its landing was confirmed (None: not flown, a dry run,
    or no landing confirmed)."""

    status: Status
    message: str
    signum: int | None = None
    landing: Estimate | None = None


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
        require(checks)


class RcModeError(QuadnavError):
    """``rc`` mode cannot fly the plan within the lost-link bound; nothing was sent."""


class _Flight:
    """One flight of ``plan`` over ``link`` (see the module's description); ``slowed`` is
    the lost-link bound's pace in ``rc`` mode. ``if_lost`` says what the drone does if
    the link dies now."""

    def __init__(self, plan: FlightPlan, link: Link, estimator: DeadReckoning,
                 settings: BridgeSettings, clock: Clock, log: TelloLog,
                 slowed: SlowedFlight | None, signals: StopSignalHandler) -> None:
        self.plan, self.link, self.estimator = plan, link, estimator
        self.settings, self.clock, self.log = settings, clock, log
        self.slowed, self.signals = slowed, signals
        self.lander = Lander(link, estimator, log, self._timeout, settings.link_timeout)
        self.if_lost = "stays on the floor"
        self.left_start = False  # rc: the drone has left its start leg for the fence
        self.rc_end = (0.0, np.zeros(3))  # rc: the last miss (m) and estimate (3,)

    # --- the sequence ------------------------------------------------------------------

    def run(self) -> Outcome:
        """Fly; the outcome, with the stop signals held during the landing."""
        outcome = with_held_signals(self._run(), self.signals.take())
        self.log.event(f"{outcome.status.value}: {outcome.message}")
        return outcome

    def _run(self) -> Outcome:
        try:
            refusal = self._preflight()
        except KeyboardInterrupt as interrupt:
            signum = signal_of(interrupt)
            return Outcome(Status.INTERRUPTED, f"{stopped_by(signum)} before takeoff: "
                           "nothing was flown", signum)
        if refusal is not None:
            return Outcome(Status.REFUSED, refusal)
        try:
            self.if_lost = "finishes its takeoff, hovers"
            self.estimator.begin_move(np.zeros(3))  # straight up
            self.link.command("takeoff", self._timeout(TAKEOFF_TIME))
            self.estimator.end_move()
            done = self._follow() if self.settings.mode == "rc" else self._go()
            self.signals.hold()
            landing = self.lander.land()
        except AutoLandingError as error:
            return self._landed_by_itself(str(error))
        except (LinkLostError, CommandRefusedError, GeofenceError, MoveError) as error:
            return self._safe_stop(Status.STOPPED, str(error))
        except KeyboardInterrupt as interrupt:
            signum = signal_of(interrupt)
            return self._safe_stop(Status.INTERRUPTED, stopped_by(signum), signum)
        if not self.link.reports_state:
            return Outcome(Status.DRY_RUN, f"{done}, then land at "
                           f"{format_point(self.plan.landing_ground)}; nothing was sent")
        if not landing.confirmed:
            return self._link_lost(f"flew {done}, then {landing.text}", Status.LINK_LOST)
        return landed(self.plan, done, landing.place)

    def _preflight(self) -> str | None:
        """Connect and check the battery: why the takeoff is refused, or None."""
        link, settings = self.link, self.settings
        try:
            link.connect()
        except LinkLostError as error:
            return f"{error}: nothing was flown"
        if not link.reports_state:
            return None
        battery = link.get_battery()
        if battery < settings.min_battery:
            return (f"battery {battery} % is below the {settings.min_battery} % needed: "
                    "takeoff refused, nothing was flown")
        lasts = (battery - LOW_BATTERY) / 100.0 * BATTERY_FLIGHT_TIME
        takes = self._expected_flight_time() + TAKEOFF_AND_LANDING
        if takes > lasts:
            slowed = (" (rc sticks slowed so that a lost link keeps the drone inside the "
                      "geofence)" if self.slowed is not None else "")
            return (f"battery {battery} % lasts about {max(lasts, 0.0):.0f} s of flight "
                    f"before the Tello lands by itself at {LOW_BATTERY} %, and this flight "
                    f"takes about {takes:.0f} s{slowed}: takeoff refused, nothing was flown")
        return None

    def _expected_flight_time(self) -> float:
        """Drone seconds from the end of the takeoff to the start of the landing."""
        if self.slowed is not None:
            return self.slowed.duration
        moves = self.plan.go_moves(TAKEOFF_HEIGHT, go_speed(self.plan.speed))
        return sum(move.duration for move in moves)

    def _timeout(self, drone_seconds: float) -> float:
        """Wall-clock seconds to wait for the reply to a command that takes
        ``drone_seconds``."""
        return self.clock.wall(drone_seconds) + self.settings.link_timeout

    # --- flying --------------------------------------------------------------------------

    def _go(self) -> str:
        """Fly the ``go`` moves (``curves`` mode: and the ``curve`` commands); returns
        what was done, for the outcome."""
        height = (self.link.settled_height() / 100.0 if self.link.reports_state
                  else TAKEOFF_HEIGHT)
        curving = self.settings.mode == "curves"
        moves = (self.plan.curve_moves(height, self.plan.speed) if curving
                 else self.plan.go_moves(height, go_speed(self.plan.speed)))
        self.if_lost = (f"finishes the {'move' if curving else 'go move'} it flies (inside "
                        "the geofence), hovers")
        for move in moves:
            self.estimator.begin_move(to_m(move.step))
            self.link.command(move.command,
                              self._timeout(MOVE_FACTOR * move.duration + MOVE_SETTLE))
            self.estimator.end_move()
        curves = sum(isinstance(move, Curve) for move in moves)
        return (f"{len(moves) - curves} go moves and {curves} "
                f"curve{'' if curves == 1 else 's'}" if curving else f"{len(moves)} go moves")

    def _follow(self) -> str:
        """Follow the trajectory with ``rc`` sticks within the lost-link bound; returns
        what was done."""
        plan, link, settings, clock = self.plan, self.link, self.settings, self.clock
        self.if_lost = ("flies on at the last sticks it heard (each bounded so that "
                        f"{HOLD:g} s of them stay inside the geofence)")
        trajectory, period, yaw = plan.trajectory, 1.0 / settings.rc_rate, plan.frame.yaw
        end = trajectory.position(trajectory.duration)
        rounder = StickRounder()
        began, ticks, tau, pace, t, finished = clock.now(), 0, 0.0, 0.0, 0.0, None
        flown = trajectory.position(0.0)  # a dry run's drone: flies the sticks exactly
        while True:
            t, before = clock.now() - began, t
            tau = min(trajectory.duration, tau + pace * (t - before))
            if link.reports_state:
                if link.state_age() > settings.link_timeout:
                    raise LinkLostError(f"no state packet for {settings.link_timeout:g} s "
                                        f"during the rc flight (t = {t:.1f} s)")
                self._check_battery()
            reference = trajectory.position(tau)
            position = self.estimator.position() if link.reports_state else flown
            region = self._region(tau, position)
            if not region.point_ok(position):
                raise GeofenceError(f"geofence: the dead-reckoned position "
                                    f"{format_point(position)} left {region.name} at "
                                    f"t = {t:.1f} s")
            miss = float(np.linalg.norm((position - end)[:2]))  # the landing is vertical
            self.rc_end = (miss, position)
            if tau >= trajectory.duration:
                finished = t if finished is None else finished
                if miss <= GOAL_TOLERANCE or t >= finished + RC_SETTLE:
                    break
            velocity_ref = trajectory.velocity(tau)
            pace = plan.reference_pace(tau)
            bound = LostLinkBound(region)
            wanted = bound.limit(position, tracking_velocity(
                reference, pace * velocity_ref, position, settings.rc_gain))
            sticks = rounder(stick_values(wanted, yaw), lambda s, p=position, b=bound: b.is_safe(
                p, stick_velocity(s, yaw)))
            velocity = stick_velocity(sticks, yaw)
            self.estimator.expect(velocity)
            link.send_rc_control(*sticks)
            flown = position + period * velocity
            ticks += 1
            clock.sleep_until(began + ticks * period)
        link.send_rc_control(0, 0, 0, 0)  # heard or not: the last sticks are safe either way
        self.estimator.expect(None)
        return (f"{ticks} rc commands over {t:.1f} s (the trajectory takes "
                f"{trajectory.duration:.1f} s; slowed where a lost link could otherwise "
                f"leave the geofence; estimate {100 * miss:.0f} cm beside its end)")

    def _region(self, tau: float, position: FloatArray) -> Region:
        """Where the drone may be at trajectory time ``tau`` s, at ``position`` (3,) m:
        where the trajectory may be then (:meth:`FlightPlan.region_at`), except that the
        start's leg room holds until the drone, behind its reference, is in the fence."""
        plan = self.plan
        self.left_start = self.left_start or (
            tau >= plan.trajectory.main_window[0] and plan.fence.point_ok(position))
        return plan.region_at(tau) if self.left_start else plan.start_room

    def _check_battery(self) -> None:
        """AutoLandingError if the state packets say the battery is below the level at
        which a Tello lands by itself (in ``rc`` mode, where no reply would say so)."""
        battery = self.link.get_battery()
        if battery < LOW_BATTERY:
            raise AutoLandingError(f"battery {battery} % in flight, below the {LOW_BATTERY} "
                                   "% at which a Tello lands by itself")

    # --- ending --------------------------------------------------------------------------

    def _safe_stop(self, status: Status, reason: str, signum: int | None = None) -> Outcome:
        """Centre the sticks, hover, land; the outcome says why and how it went."""
        self.signals.hold()
        self.log.event(f"safe stop: {reason}")
        if self.settings.mode == "rc":
            self.link.send_rc_control(0, 0, 0, 0)
        stop = self.lander.stop()
        landing = self.lander.land()
        if not landing.confirmed:
            return self._link_lost(f"{reason}; {stop}, and {landing.text}",
                                   status if signum is not None else Status.LINK_LOST,
                                   signum)
        return Outcome(status, f"{reason}; safe stop: {stop}, {landing.text}", signum,
                       landing.place)

    def _landed_by_itself(self, reason: str) -> Outcome:
        """The drone lands by itself: centre the sticks, land, wait for the floor."""
        self.signals.hold()
        self.log.event(f"landing by itself: {reason}")
        if self.settings.mode == "rc":
            self.link.send_rc_control(0, 0, 0, 0)
        landing = self.lander.land()
        if not landing.confirmed:
            return self._link_lost(f"{reason}; {landing.text}", Status.LINK_LOST)
        return Outcome(Status.AUTO_LANDED, f"{reason}; {landing.text}, battery "
                       f"{self.link.get_battery()} %", landing=landing.place)

    def _link_lost(self, what: str, status: Status, signum: int | None = None) -> Outcome:
        """The outcome of a landing never confirmed: what happened, and what the drone
        does if it heard nothing more."""
        track = self.estimator.track()
        seen = (f"; last seen at {format_point(track[-1, 1:])} (state packets)"
                if len(track) else "")
        lost = "" if status is Status.LINK_LOST else ": the link is lost"
        return Outcome(status, f"{what}{lost}; if the Tello heard none of it, it "
                       f"{self.if_lost} and lands by itself {AUTO_LAND_AFTER:g} s after "
                       f"the last command it heard{seen}", signum)


def landing_error(plan: FlightPlan, place: Estimate) -> float:
    """How far, m, the landing ``place`` lies horizontally from the floor under the goal
    of ``plan``: what the verdict judges, and metrics.json's ``final_error_m``."""
    return float(np.linalg.norm(place.point[:2] - plan.landing_ground[:2]))


def landed(plan: FlightPlan, done: str, place: Estimate) -> Outcome:
    """The outcome of a flight of ``plan`` flown to its end (``done``, in words) and
    landed at ``place``: at the goal if within :data:`LANDING_TOLERANCE` of the floor
    under it horizontally (:func:`landing_error`), else off it."""
    goal = plan.landing_ground
    off = landing_error(plan, place)
    where = f"landed at {place.text}, {off:.2f} m from the goal"
    if off <= LANDING_TOLERANCE:
        return Outcome(Status.LANDED, f"{where}, after {done}", landing=place)
    return Outcome(Status.OFF_GOAL, f"{where} {format_point(goal)}, beyond its "
                   f"{LANDING_TOLERANCE:g} m tolerance, after {done}", landing=place)


def _flight_signals() -> StopSignalHandler:
    """Stop-signal handling for one flight (install it with ``with``): the first stop
    signal raises where the program is (KeyboardInterrupt, or
    :class:`~quadnav.signals.Stopped`), so the bridge stops the drone and lands it; from
    then on, and from :meth:`~quadnav.signals.StopSignalHandler.hold` on, which the
    bridge calls before it lands, every further one is only noted: a second Ctrl-C, or a
    service manager's SIGTERM after SIGHUP, must not abort the landing. SIGKILL, which
    cannot be caught, still ends the program."""
    return StopSignalHandler(hold_after_first=True)


def stopped_by(signum: int) -> str:
    """``stopped by SIGTERM``, ``interrupted by Ctrl-C (SIGINT)``."""
    verb = "interrupted" if signum == signal.SIGINT else "stopped"
    return f"{verb} by {signal_name(signum)}"


def with_held_signals(outcome: Outcome, held: list[int]) -> Outcome:
    """``outcome`` with the stop signals ``held`` while the drone was brought down said;
    the first one makes it an interrupted flight if it was not one already."""
    if not held:
        return outcome
    names = ", ".join(signal_name(signum) for signum in held)
    message = f"{outcome.message}; {names} came later and waited until the drone was down"
    if outcome.signum is not None:
        return dataclasses.replace(outcome, message=message)
    return dataclasses.replace(outcome, status=Status.INTERRUPTED, message=message,
                               signum=held[0])


def _tello_link(host: str, log: TelloLog, estimator: DeadReckoning,
                settings: BridgeSettings) -> Link:
    """djitellopy's client for the drone at ``host``; QuadnavError without djitellopy."""
    try:
        from quadnav.hardware.bridge.tello_link import TelloLink
    except ImportError:
        raise QuadnavError("flying a Tello needs djitellopy: pip install 'quadnav[tello]' "
                           "(or use --dry-run)") from None
    TelloLink.LOGGER.setLevel(logging.WARNING)  # its INFO lines repeat what the log holds
    try:
        return TelloLink(host, log, estimator.update, settings.link_timeout)
    except OSError as error:
        raise QuadnavError(f"cannot open djitellopy's UDP port 8889: {error.strerror} (is "
                           "another Tello program running?)") from None


def rc_pace(plan: FlightPlan, settings: BridgeSettings) -> SlowedFlight:
    """How the ``rc`` flight of ``plan`` is slowed by the lost-link bound, rehearsed in a
    silent dry run (a drone that flies its sticks exactly).

    Raises:
        RcModeError: somewhere the trajectory cannot be followed at any safe speed, or the
            rehearsal ends further than :data:`RC_REACH` from the trajectory's end (e.g.
            where whole-percent sticks in a turned heading cannot run along a leg that
            hugs a wall).
    """
    slowed = slowed_flight(plan.reference_pace, plan.trajectory, settings.rc_rate)
    if slowed.stalls:
        raise RcModeError(
            f"rc mode cannot fly this plan: at {format_point(slowed.where)} the trajectory "
            f"heads for the geofence so closely that no stick speed is safe if the link "
            f"dies (the Tello would fly on for {HOLD:g} s); nothing was sent (try --mode "
            "waypoints)")
    log = TelloLog(io.StringIO())
    rehearsal = _Flight(plan, DryRunLink(log, io.StringIO()), DeadReckoning(plan.frame),
                        settings, VirtualClock(), log, slowed, _flight_signals())
    rehearsal._follow()
    miss, where = rehearsal.rc_end
    if miss > RC_REACH:
        raise RcModeError(
            f"rc mode cannot fly this plan: its sticks (whole percent in the drone's heading, "
            f"each bounded for a lost link), flown exactly, get no further than "
            f"{format_point(where)}, {100 * miss:.0f} cm from the trajectory's end; nothing "
            "was sent (try --mode waypoints)")
    return slowed


@dataclass(frozen=True, eq=False)
class Flown:
    """What :func:`fly` gives back.

    Attributes:
        outcome: how the flight ended.
        track: (N, 4) the dead-reckoned track: drone seconds from the start of the
            estimate, map x, y, z (m), at each state packet.
        truth: (K, 4) the true track in the same time (see :mod:`quadnav.hardware.truth`),
            or None when none was given or read.
    """

    outcome: Outcome
    track: FloatArray
    truth: FloatArray | None = None


def fly(plan: FlightPlan, settings: BridgeSettings, folder: str | Path,
        host: str | None = None, stream: TextIO | None = None,
        truth: str | Path | None = None) -> Flown:
    """Fly ``plan`` on the Tello at ``host`` — or, with no host, print the commands of a
    dry run to ``stream`` — and write the log and the figure into ``folder``.

    Args:
        plan: a checked flight plan.
        settings: mode, safety thresholds, rates, time scale.
        folder: gets :data:`~quadnav.hardware.bridge.tello_log.LOG_NAME` and :data:`TRACK_FIGURE`.
        host: the drone's IPv4 address; None for a dry run.
        stream: where a dry run prints (default: standard output as it is when called).
        truth: a file that something outside the bridge (the emulator) writes the drone's
            true track to (:mod:`quadnav.hardware.truth`), read after the flight and drawn
            beside the dead-reckoned track; a file that cannot be read, or holds none of
            this flight, is warned about and left out.

    Returns:
        The outcome, the dead-reckoned track and the true one.

    Raises:
        MoveError: (waypoints mode) the route cannot be flown with ``go`` moves; nothing
            was sent.
        RcModeError: (rc mode) see :func:`rc_pace`; nothing was sent.
    """
    slowed = None
    if settings.mode == "waypoints":  # moves the SDK cannot fly: refused before anything
        plan.go_moves(TAKEOFF_HEIGHT, go_speed(plan.speed))
    elif settings.mode == "curves":
        plan.curve_moves(TAKEOFF_HEIGHT, plan.speed)
    else:
        slowed = rc_pace(plan, settings)
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
        if slowed is not None:
            log.event(f"rc sticks bounded for a lost link: the flight takes about "
                      f"{slowed.duration:.0f} s (the trajectory {slowed.planned:.0f} s), "
                      f"slowest {100 * slowed.slowest:.0f} % of the trajectory's speed at "
                      f"{format_point(slowed.where)}")
        link = DryRunLink(log, stream) if dry_run else _tello_link(host, log, estimator,
                                                                   settings)
        with _flight_signals() as signals:
            try:
                outcome = _Flight(plan, link, estimator, settings, clock, log, slowed,
                                  signals).run()
            finally:
                link.close()
            track = estimator.track()
            true_track = (None if truth is None or dry_run
                          else _read_truth(truth, estimator.epoch, settings.time_scale))
            _draw(plan, settings.mode, track, true_track, outcome, folder / TRACK_FIGURE)
    return Flown(with_held_signals(outcome, signals.take()), track, true_track)


def _read_truth(path: str | Path, epoch: float, time_scale: float) -> FloatArray | None:
    """The true track in ``path`` since ``epoch`` (:func:`~quadnav.hardware.truth.
    flight_truth`), or None, with a warning, if it cannot be read or holds none."""
    try:
        truth = flight_truth(path, epoch, time_scale)
    except QuadnavError as error:
        warnings.warn(f"{error}; no true track recorded", stacklevel=3)
        return None
    if not len(truth):
        warnings.warn(f"{path}: no sample since the flight began (is the emulator writing "
                      "it, with --truth?); no true track recorded", stacklevel=3)
        return None
    return truth


def _draw(plan: FlightPlan, mode: str, track: FloatArray, truth: FloatArray | None,
          outcome: Outcome, path: Path) -> None:
    """Save the figure of the flight: planned, dead-reckoned ``track`` (N, 4) and, when
    known, the true track (K, 4)."""
    from quadnav.hardware.bridge.track_figure import track_figure  # matplotlib: only when needed
    from quadnav.viz.figures import save_figure

    flown = {"dead reckoning (state packets)": track[:, 1:]}
    if truth is not None:
        flown["true track"] = truth[:, 1:]
    save_figure(track_figure(plan, mode, flown, outcome.status.value), path)

"""Where the Tello is, from its state packets: dead reckoning in the map frame, and how
well it is known.

A state packet (see the SDK) carries ``vgx``, ``vgy``, ``vgz`` — velocity in whole dm/s
along the drone's *current* heading frame with x forward, y right and z down — ``yaw``,
in degrees clockwise from the heading at power-on, and ``h``, the height above the
takeoff floor in cm. Between two packets the drone moved (horizontally) by about the
mean of their velocities times the time between them (trapezoidal rule), turned into the
takeoff frame by the reported yaw; the height is ``h``.

Whole dm/s are coarse: at 0.46 m/s the drone reports 0.5, and integrating that drifts 4
cm every second. A reported value only says the true one lies within half a unit of it,
so the step between packets lies within half a unit times the time of the step's
trapezoid. When the bridge says which velocity it asks for (:meth:`DeadReckoning.expect`,
the ``rc`` sticks), the step is the distance those commands asked for, clipped, per
axis of the heading frame, to that interval — never further from the truth than the
reports alone, and much closer while the drone does as told. Between packets the
estimate moves on with the commands asked for (or the last reported velocity), so it
does not jump at each packet.

A move (``go``, ``curve``, and ``takeoff`` and ``land``, straight up and down:
:meth:`DeadReckoning.begin_move` when it is sent, :meth:`DeadReckoning.end_move` when
it is answered ``ok``, which the Tello sends once it has stopped at the move's end) is
taken in the same way as a whole: from the packet before the command to the ``ok``, the
drone moved horizontally by the move's step, clipped per axis of the heading frame to
within what the reports over those steps allow at most (:func:`step_bound`: their
rounding, and the motion an acceleration of at most :data:`MAX_ACCELERATION` can hide
between two packets — a whole short move, when packets come a second apart).

**Uncertainty** (:meth:`DeadReckoning.estimate`): a 1-sigma horizontal distance, m, from
the same model. The true step between two packets lies about :func:`step_slack` from
the estimated one, per axis (the rounding, and half the change of velocity between
them: it may have come anywhere in the step); taken as a uniform draw, independent from
step to step, each step adds slack^2 / 3 per axis to the variance. A move answered
``ok`` adds the smaller of its steps' summed variance and that of a move's end, which
lies within :data:`MOVE_ACCURACY` of its target per axis (uniform too). A mission pad
resets it to the pad's rounding (half a centimetre). The horizontal sigma is the square
root of the x and y variances summed.

A Tello EDU that sees a mission pad (``mid`` 1..8) reports its position over the pad in
cm as ``x``, ``y``, ``z``; with the pad placed under the start, aligned with the drone
(x forward, y left), those replace the estimate.

Packets arrive on djitellopy's receiver thread; every method is safe to call from
different threads.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from quadnav.arrays import FloatArray
from quadnav.hardware.bridge.frames import TakeoffFrame, body_to_map, map_to_body
from quadnav.world.placement import format_estimate

#: Metres per second of one unit of vgx, vgy, vgz (dm/s), and half of it: how far a
#: reported velocity may lie from the true one per axis.
VELOCITY_UNIT = 0.1
HALF_UNIT = 0.5 * VELOCITY_UNIT
#: Longest gap between packets that is integrated, wall-clock s (longer: a lost link).
MAX_GAP = 1.0
#: The most a Tello accelerates horizontally in the bridge's moves, m/s^2 (a gentle
#: indoor flight, about a 9 degree tilt, as the emulator flies).
MAX_ACCELERATION = 1.5
#: How close to its target a move answered ``ok`` ends, per axis, m: the emulator's
#: settling distance; real Tellos end ``go`` moves about 2 cm off (djitellopy's reports).
MOVE_ACCURACY = 0.05
#: Horizontal variance of a move's end and of a mission pad's fix, m^2 (uniform draws
#: within MOVE_ACCURACY and within half a centimetre, on x and on y).
MOVE_VARIANCE = 2 * MOVE_ACCURACY ** 2 / 3
PAD_VARIANCE = 2 * 0.005 ** 2 / 3


def clip_step(asked: ArrayLike, reported: ArrayLike, slack: ArrayLike) -> FloatArray:
    """The step ``asked`` (..., 3), m, clipped per axis to within ``slack`` (m, per axis
    or one for all) of the ``reported`` step (same shape, m)."""
    reported = np.asarray(reported, dtype=np.float64)
    slack = np.asarray(slack, dtype=np.float64)
    return np.clip(np.asarray(asked, dtype=np.float64), reported - slack, reported + slack)


def step_slack(before: ArrayLike, after: ArrayLike, seconds: float) -> FloatArray:
    """How far, per axis, m, the true step between two packets lies from the trapezoid of
    their reported velocities ``before`` and ``after`` (3,) m/s over ``seconds``, for the
    uncertainty: half a unit of rounding, and half their difference (the change may come
    anywhere in the step)."""
    change = np.abs(np.asarray(after, dtype=np.float64) - np.asarray(before, dtype=np.float64))
    return (HALF_UNIT + 0.5 * change) * seconds


def step_bound(seconds: float) -> float:
    """The furthest, per axis, m, the true step between two packets ``seconds`` apart may
    lie from the trapezoid of their reported velocities: half a unit of rounding, and the
    most a velocity whose rate of change stays within :data:`MAX_ACCELERATION` can stray
    from the straight line between two values (a quarter of it times the time squared)."""
    return HALF_UNIT * seconds + 0.25 * MAX_ACCELERATION * seconds ** 2


@dataclass(frozen=True)
class Estimate:
    """Where the dead reckoning puts the drone: ``point`` (3,) map m, and ``sigma``, the
    1-sigma uncertainty of its horizontal position, m (see the module)."""

    point: FloatArray
    sigma: float

    @property
    def text(self) -> str:
        """``(x, y, z) +- s m``, for messages."""
        return format_estimate(self.point, self.sigma)


@dataclass
class _Move:
    """A move under way: its ``asked`` step (3,) m in the heading frame, the takeoff-frame
    estimate ``start`` (3,) and ``heading`` (rad) at the packet before it was sent, and the
    summed bound (:func:`step_bound`, m per axis) and horizontal ``variance`` m^2 of the
    steps since."""

    asked: FloatArray
    start: FloatArray
    heading: float
    bound: float = 0.0
    variance: float = 0.0


class DeadReckoning:
    """A position estimate from state packets, its uncertainty, and its history.

    Args:
        frame: where the drone stood before takeoff and which way it faced.
        time_scale: drone seconds per wall-clock second (1 for a real drone).
        clock: the wall clock, s (the monotonic clock; a test's own, to replay packets).
    """

    def __init__(self, frame: TakeoffFrame, time_scale: float = 1.0,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self.frame = frame
        self.time_scale = time_scale
        self._clock = clock
        self._lock = threading.Lock()
        self._body = np.zeros(3)  # takeoff frame at the last packet, m
        self._velocity = np.zeros(3)  # heading frame (x forward, y left, z up), m/s
        self._heading = 0.0  # rad, counter-clockwise from the takeoff frame
        self._last: float | None = None  # wall-clock time of the last packet
        self._asked: FloatArray | None = None  # takeoff frame, m/s
        self._asked_since = 0.0  # wall-clock time the asked velocity was set
        self._asked_step = np.zeros(3)  # takeoff frame, m, since the last packet
        self._variance = 0.0  # horizontal, m^2, of the steps outside a move under way
        self._move: _Move | None = None
        self._began = clock()
        #: UNIX time, s, of the start of :meth:`track`'s time (a true track's clock).
        self.epoch = time.time()
        self._track: list[tuple[float, float, float, float]] = []

    def _drone_seconds(self, since: float, now: float) -> float:
        return (now - since) * self.time_scale

    def _close_asked(self, now: float) -> None:
        """Add the asked velocity's distance up to ``now`` to the step (lock held)."""
        if self._asked is not None:
            self._asked_step += self._drone_seconds(self._asked_since, now) * self._asked
        self._asked_since = now

    def expect(self, velocity: ArrayLike | None) -> None:
        """From now on the drone is asked for ``velocity`` (3,) m/s, map frame (None:
        nothing known)."""
        now = self._clock()
        with self._lock:
            self._close_asked(now)
            self._asked = (None if velocity is None
                           else map_to_body(velocity, self.frame.yaw))

    def begin_move(self, step: ArrayLike) -> None:
        """The drone is sent a move of ``step`` (3,) m in its heading frame (the numbers of
        the ``go`` or ``curve`` command); :meth:`end_move` once it is answered ``ok``."""
        with self._lock:
            self._variance += self._move.variance if self._move is not None else 0.0
            self._move = _Move(np.asarray(step, dtype=np.float64), self._body.copy(),
                               self._heading)

    def end_move(self) -> None:
        """The move begun last was answered ``ok``: the drone stopped at its end. The
        estimate takes it in (see the module), from the step since the last packet on."""
        now = self._clock()
        with self._lock:
            move = self._move
            if move is None or self._last is None:  # nothing reported: nothing to take in
                self._move = None
                return
            self._integrate(now, np.zeros(3), self._heading)
            self._velocity, self._last, self._move = np.zeros(3), now, None
            reported = map_to_body(self._body - move.start, move.heading)
            kept = clip_step(move.asked, reported, move.bound)
            kept[2] = reported[2]  # the height is the reported one
            self._body += body_to_map(kept - reported, move.heading)
            self._variance += min(move.variance, MOVE_VARIANCE)

    def _integrate(self, now: float, velocity: FloatArray, heading: float) -> None:
        """Move the estimate on by the step from the last packet to ``now``, where the
        drone reports ``velocity`` (3,) m/s in its ``heading`` frame (lock held)."""
        seconds = self._drone_seconds(self._last, now)
        if now - self._last > MAX_GAP:  # a lost link: the step is not known at all
            step = np.zeros(3)
            fastest = np.maximum(np.abs(self._velocity), np.abs(velocity))
            slack = (HALF_UNIT + fastest) * seconds
            bound = float(slack.max())
        else:
            step = 0.5 * seconds * (body_to_map(self._velocity, self._heading)
                                    + body_to_map(velocity, heading))
            if self._asked is not None:
                step = body_to_map(clip_step(
                    map_to_body(self._asked_step, heading),
                    map_to_body(step, heading), HALF_UNIT * seconds), heading)
            slack = step_slack(self._velocity, velocity, seconds)
            bound = step_bound(seconds)
        self._body[:2] += step[:2]
        variance = float(np.sum(slack[:2] ** 2)) / 3.0
        if self._move is not None:
            self._move.bound += bound
            self._move.variance += variance
        else:
            self._variance += variance

    def update(self, state: dict) -> None:
        """Take in one parsed state packet (ignored unless it has the fields)."""
        now = self._clock()
        try:
            pad = int(state.get("mid", -2)) > 0
            heading = -math.radians(float(state["yaw"]))  # ccw, from the takeoff frame
            velocity = VELOCITY_UNIT * np.array(  # heading frame, x forward, y left, z up
                [float(state["vgx"]), -float(state["vgy"]), -float(state["vgz"])])
            height = float(state["h"]) / 100.0
            pad_position = (np.array([float(state["x"]), float(state["y"]),
                                      float(state["z"])]) / 100.0 if pad else None)
        except (KeyError, TypeError, ValueError):
            return
        with self._lock:
            self._close_asked(now)
            if pad_position is not None:
                self._body, self._variance, self._move = pad_position, PAD_VARIANCE, None
            else:
                if self._last is not None:
                    self._integrate(now, velocity, heading)
                self._body[2] = height
            self._velocity, self._heading, self._last = velocity, heading, now
            self._asked_step = np.zeros(3)
            self._track.append((self._drone_seconds(self._began, now),
                                *self.frame.to_map(self._body)))

    def position(self) -> FloatArray:
        """(3,) the estimate now in the map frame, m: at the last packet, moved on by the
        velocity asked for since (or the last one reported), the height too."""
        return self.estimate().point

    def estimate(self) -> Estimate:
        """The estimate now (:meth:`position`) and its 1-sigma horizontal uncertainty."""
        now = self._clock()
        with self._lock:
            body = self._body.copy()
            if self._last is not None:
                if self._asked is not None:
                    ahead = self._asked_step + self._drone_seconds(
                        self._asked_since, now) * self._asked
                else:
                    ahead = self._drone_seconds(self._last, now) * body_to_map(
                        self._velocity, self._heading)
                body += ahead
            variance = self._variance + (self._move.variance if self._move else 0.0)
            return Estimate(self.frame.to_map(body), math.sqrt(variance))

    def track(self) -> FloatArray:
        """(N, 4) drone time (s, from the start of the estimate, :attr:`epoch`) and map
        position (m) at each packet."""
        with self._lock:
            return np.array(self._track, dtype=np.float64).reshape(-1, 4)

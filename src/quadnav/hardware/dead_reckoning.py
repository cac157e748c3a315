"""Where the Tello is, from its state packets: dead reckoning in the map frame.

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

import numpy as np
from numpy.typing import ArrayLike

from quadnav.arrays import FloatArray
from quadnav.hardware.frames import TakeoffFrame, body_to_map, map_to_body

#: Metres per second of one unit of vgx, vgy, vgz (dm/s).
VELOCITY_UNIT = 0.1
#: Longest gap between packets that is integrated, wall-clock s (longer: a lost link).
MAX_GAP = 1.0


def clip_step(asked: ArrayLike, reported: ArrayLike, seconds: float) -> FloatArray:
    """The step ``asked`` (..., 3), m, clipped per axis to within half a reporting unit
    times ``seconds`` of the ``reported`` step (same shape, m)."""
    reported = np.asarray(reported, dtype=np.float64)
    slack = 0.5 * VELOCITY_UNIT * seconds
    return np.clip(np.asarray(asked, dtype=np.float64), reported - slack, reported + slack)


class DeadReckoning:
    """A position estimate from state packets, and its history.

    Args:
        frame: where the drone stood before takeoff and which way it faced.
        time_scale: drone seconds per wall-clock second (1 for a real drone).
    """

    def __init__(self, frame: TakeoffFrame, time_scale: float = 1.0) -> None:
        self.frame = frame
        self.time_scale = time_scale
        self._lock = threading.Lock()
        self._body = np.zeros(3)  # takeoff frame at the last packet, m
        self._velocity = np.zeros(3)  # heading frame (x forward, y left, z up), m/s
        self._heading = 0.0  # rad, counter-clockwise from the takeoff frame
        self._last: float | None = None  # wall-clock time of the last packet
        self._asked: FloatArray | None = None  # takeoff frame, m/s
        self._asked_since = 0.0  # wall-clock time the asked velocity was set
        self._asked_step = np.zeros(3)  # takeoff frame, m, since the last packet
        self._began = time.monotonic()
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
        now = time.monotonic()
        with self._lock:
            self._close_asked(now)
            self._asked = (None if velocity is None
                           else map_to_body(velocity, self.frame.yaw))

    def update(self, state: dict) -> None:
        """Take in one parsed state packet (ignored unless it has the fields)."""
        now = time.monotonic()
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
                self._body = pad_position
            else:
                if self._last is not None and now - self._last <= MAX_GAP:
                    seconds = self._drone_seconds(self._last, now)
                    step = 0.5 * seconds * (body_to_map(self._velocity, self._heading)
                                            + body_to_map(velocity, heading))
                    if self._asked is not None:
                        step = body_to_map(clip_step(
                            map_to_body(self._asked_step, heading),
                            map_to_body(step, heading), seconds), heading)
                    self._body[:2] += step[:2]
                self._body[2] = height
            self._velocity, self._heading, self._last = velocity, heading, now
            self._asked_step = np.zeros(3)
            self._track.append((self._drone_seconds(self._began, now),
                                *self.frame.to_map(self._body)))

    def position(self) -> FloatArray:
        """(3,) the estimate now in the map frame, m: at the last packet, moved on by the
        velocity asked for since (or the last one reported), the height too."""
        now = time.monotonic()
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
            return self.frame.to_map(body)

    def track(self) -> FloatArray:
        """(N, 4) drone time (s, from the start of the estimate) and map position (m) at
        each packet."""
        with self._lock:
            return np.array(self._track, dtype=np.float64).reshape(-1, 4)

"""The emulated Tello's flight: quadnav's vehicle and cascade flying the SDK's motions.

:class:`EmulatedDrone` is the physical drone without the radio: the ``tello`` vehicle
(:mod:`quadnav.vehicle.dynamics`) flown by the cascade (:mod:`quadnav.control.cascade`)
through the compiled closed loop of the simulator (:func:`quadnav.sim.loop.fly_steps`),
advanced by :meth:`EmulatedDrone.advance` in emulated seconds. Every SDK motion becomes
a reference the cascade tracks:

* ``takeoff`` climbs :data:`TAKEOFF_HEIGHT` from the floor, ``land`` descends to it and
  stops the motors;
* ``go``, ``up``, ``forward`` ... fly a straight line and ``curve`` a circular arc, at the
  commanded speed with smooth speed ramps (:class:`SpeedProfile`, peak acceleration
  :data:`ACCELERATION`); ``cw``/``ccw`` turn on the spot likewise;
* a motion is over once the reference has ended and the drone has settled on its end
  (:data:`SETTLE_DISTANCE`, :data:`SETTLE_SPEED`, :data:`SETTLE_YAW`), or
  :data:`SETTLE_TIMEOUT` later;
* between motions the drone holds a moving setpoint that ``rc`` sticks steer (velocity
  references, slewed at :data:`ACCELERATION`); ``stop`` holds where it is;
* ``emergency`` cuts the motors and it falls to the floor.

Frames: the world frame is quadnav's (z up); the floor is the plane ``z = start[2]``
under the drone's start. SDK offsets are in the heading frame at the time of the
command — x forward, y left, z up — and a clockwise turn lowers the world yaw. Relative
moves start from the held setpoint, so they do not accumulate the tracking error.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike

from quadnav.arrays import FloatArray
from quadnav.control.gains import Gains
from quadnav.control.registry import DEFAULT_CONTROLLER, make_controller
from quadnav.hardware.arc import Arc
from quadnav.hardware.sdk import LOW_BATTERY, Telemetry
from quadnav.sim import loop
from quadnav.sim.settings import SimSettings
from quadnav.vehicle import quaternion
from quadnav.vehicle.dynamics import (
    ATTITUDE,
    POSITION,
    ROTORS,
    VELOCITY,
    hover_state,
    rk4_step,
    rk4_workspace,
    vehicle_arrays,
)
from quadnav.vehicle.params import VehicleParams, load_params

#: Height of the hover after ``takeoff`` above the floor, m (the SDK's "about 80 cm").
TAKEOFF_HEIGHT = 0.8
#: Peak climb speed of ``takeoff`` and descent speed of ``land``, m/s.
TAKEOFF_SPEED = 0.6
LAND_SPEED = 0.5
#: Peak acceleration of every motion and of the ``rc`` setpoint, m/s^2 (a gentle indoor
#: Tello, about a 9 degree tilt).
ACCELERATION = 1.5
#: Peak yaw rate and yaw acceleration of ``cw``/``ccw``, rad/s and rad/s^2.
TURN_RATE = math.radians(90.0)
TURN_ACCELERATION = math.radians(180.0)
#: Speed and yaw rate of a full ``rc`` stick (100), m/s and rad/s.
RC_SPEED = 1.0
RC_YAW_RATE = math.radians(90.0)
#: How long a ``flip`` holds the drone busy, s (the flip itself is not flown).
FLIP_TIME = 1.0
#: A motion is over once within these of its end: m, m/s, rad ...
SETTLE_DISTANCE = 0.05
SETTLE_SPEED = 0.1
SETTLE_YAW = math.radians(3.0)
#: ... or this many seconds after its reference ended.
SETTLE_TIMEOUT = 3.0
#: Seconds between the samples of :meth:`EmulatedDrone.track`.
TRACK_PERIOD = 0.02
#: Battery drain, percent per second, with the motors running and with them off.
DRAIN_FLYING = 100.0 / 720.0
DRAIN_IDLE = 100.0 / 3600.0
#: Standard gravity for the accelerometer's thousandths of g, m/s^2.
_G = 9.80665
#: Minimum-jerk shape: sigma(u) = 10u^3 - 15u^4 + 6u^5 rises from 0 to 1; its integral
#: from 0 to 1 is 1/2 and its peak slope 15/8.
_PEAK_SLOPE = 1.875


def _sigma(u: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Integral, value and slope of the minimum-jerk rise sigma at ``u`` in [0, 1]."""
    u2 = u * u
    return (u2 * u2 * (2.5 - 3.0 * u + u2), u2 * u * (10.0 - 15.0 * u + 6.0 * u2),
            30.0 * u2 * (1.0 - 2.0 * u + u2))


@dataclass(frozen=True)
class SpeedProfile:
    """Distance against time for a rest-to-rest motion of ``length`` (m or rad).

    The speed rises to ``speed`` along a minimum-jerk curve whose peak acceleration is
    ``acceleration``, cruises, and falls back the same way; a motion too short to reach
    ``speed`` peaks lower, with no cruise.
    """

    length: float
    speed: float
    acceleration: float

    @property
    def peak_speed(self) -> float:
        """Highest speed reached."""
        return min(self.speed, math.sqrt(self.length * self.acceleration / _PEAK_SLOPE))

    @property
    def ramp(self) -> float:
        """Seconds to reach the peak speed from rest."""
        return _PEAK_SLOPE * self.peak_speed / self.acceleration

    @property
    def duration(self) -> float:
        """Seconds from rest to rest."""
        return self.length / self.peak_speed + self.ramp if self.length > 0 else 0.0

    def at(self, t: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Distance, speed and acceleration (each shaped like ``t``) at times ``t`` s."""
        t = np.clip(np.asarray(t, dtype=np.float64), 0.0, self.duration)
        if self.length <= 0:
            return np.zeros_like(t), np.zeros_like(t), np.zeros_like(t)
        v, ramp, total = self.peak_speed, self.ramp, self.duration
        up = np.clip(t / ramp, 0.0, 1.0)
        down = np.clip((total - t) / ramp, 0.0, 1.0)
        s_up, v_up, a_up = _sigma(up)
        s_down, v_down, a_down = _sigma(down)
        cruise = np.clip(t - ramp, 0.0, None)
        rising, falling = t < ramp, t > total - ramp
        s = np.where(falling, self.length - v * ramp * s_down,
                     np.where(rising, v * ramp * s_up, v * ramp / 2 + v * cruise))
        speed = v * np.where(falling, v_down, np.where(rising, v_up, 1.0))
        accel = v / ramp * np.where(falling, -a_down, np.where(rising, a_up, 0.0))
        return s, speed, accel


class Shape(Protocol):
    """A path parametrised by arc length: its length (m) and, at distances ``s`` (K,),
    the points (K, 3) and their first and second derivatives with respect to ``s``."""

    length: float

    def at(self, s: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]: ...


class Line:
    """The straight line from ``start`` (3,) to ``end`` (3,), m."""

    def __init__(self, start: ArrayLike, end: ArrayLike) -> None:
        self.start = np.asarray(start, dtype=np.float64)
        step = np.asarray(end, dtype=np.float64) - self.start
        self.length = float(np.linalg.norm(step))
        self.direction = step / self.length if self.length > 0 else np.zeros(3)

    def at(self, s: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        count = len(s)
        return (self.start + s[:, None] * self.direction, np.tile(self.direction, (count, 1)),
                np.zeros((count, 3)))


#: The profile of no motion at all.
STILL = SpeedProfile(0.0, 1.0, 1.0)


@dataclass(frozen=True)
class Motion:
    """One SDK motion as a reference: along ``shape`` with ``profile`` (distance in m),
    while the yaw turns by ``turn`` rad (counter-clockwise) from ``yaw`` with
    ``turn_profile`` (distance in rad); it lasts as long as the longer of the two, and
    at least ``minimum`` s."""

    shape: Shape
    profile: SpeedProfile
    yaw: float
    turn: float = 0.0
    turn_profile: SpeedProfile = STILL
    minimum: float = 0.0

    @property
    def duration(self) -> float:
        """Seconds the reference runs."""
        return max(self.profile.duration, self.turn_profile.duration, self.minimum)

    @property
    def end(self) -> tuple[FloatArray, float]:
        """Where the reference ends: position (3,) m and yaw rad."""
        point, _, _ = self.shape.at(np.array([self.shape.length]))
        return point[0], self.yaw + self.turn

    def reference(self, t: FloatArray) -> FloatArray:
        """Reference rows (K, 11) at times ``t`` (K,) s, as the cascade takes them:
        position, velocity, acceleration, yaw, yaw rate."""
        s, ds, dds = self.profile.at(t)
        point, tangent, curvature = self.shape.at(s)
        angle, rate, _ = self.turn_profile.at(t)
        sign = math.copysign(1.0, self.turn)
        return np.column_stack([point, tangent * ds[:, None],
                                curvature * (ds * ds)[:, None] + tangent * dds[:, None],
                                self.yaw + sign * angle, sign * rate])


def _world_yaw(state: FloatArray) -> float:
    r = quaternion.to_matrix(state[ATTITUDE])
    return math.atan2(r[1, 0], r[0, 0])


def _wrap(angle: float) -> float:
    """``angle`` rad wrapped to [-pi, pi)."""
    return (angle + math.pi) % (2 * math.pi) - math.pi


class EmulatedDrone:
    """The Tello's physics and flight modes, advanced in emulated time.

    Args:
        start: (3,) world position of the drone on the floor before takeoff, m; the floor
            is the plane at its height.
        yaw: world heading of the nose at power-on, rad counter-clockwise from +x.
        battery: battery at power-on, percent.
        battery_drain: how many times faster than :data:`DRAIN_FLYING` the battery
            drains in flight (an aged battery: > 1; idle, it drains at :data:`DRAIN_IDLE`).
        params: the vehicle (default: the ``tello`` preset).
        gains: the cascade's (default: those tuned for ``params``,
            :func:`~quadnav.control.registry.controller_gains`).
        settings: the simulator's rates (default: :class:`~quadnav.sim.SimSettings`).
    """

    def __init__(self, start: ArrayLike, yaw: float = 0.0, battery: float = 100.0,
                 battery_drain: float = 1.0, params: VehicleParams | None = None,
                 gains: Gains | None = None, settings: SimSettings | None = None) -> None:
        self.params = params or load_params()
        self.settings = settings or SimSettings()
        self._vehicle = vehicle_arrays(self.params)
        self._controller = make_controller(DEFAULT_CONTROLLER, self.params, gains)
        self._dt = 1.0 / self.settings.control_rate
        self.start = np.asarray(start, dtype=np.float64).reshape(3)
        self.floor = float(self.start[2])
        self._scene = loop.scene(None, self._vehicle.half_size, floor_z=self.floor)
        self.initial_yaw = float(yaw)
        self.battery = float(battery)
        self.battery_drain = float(battery_drain)
        self.time = 0.0
        self.motor_time = 0.0
        self.flying = False
        self.motion: Motion | None = None
        self.landing = False
        self.falling = False
        self._motion_began = 0.0
        self._state = self._resting(self.start, yaw)
        self._memory = self._controller.new_memory()
        self._setpoint = (self.start.copy(), np.zeros(3), float(yaw))
        self._sticks = (np.zeros(3), 0.0)
        self._acceleration = np.zeros(3)
        self._steps = 0
        self._carry = 0.0
        self._track_t: list[float] = []
        self._track_p: list[FloatArray] = []

    # --- what the drone does -------------------------------------------------------

    @property
    def busy(self) -> bool:
        """Whether a motion (or the fall after ``emergency``) is under way."""
        return self.motion is not None or self.falling

    @property
    def battery_percent(self) -> int:
        """The battery as the drone reports it: whole percent, rounded up."""
        return math.ceil(self.battery)

    @property
    def low_battery(self) -> bool:
        """Whether the reported battery is below :data:`LOW_BATTERY`."""
        return self.battery_percent < LOW_BATTERY

    @property
    def position(self) -> FloatArray:
        """(3,) world position, m."""
        return self._state[POSITION].copy()

    @property
    def yaw(self) -> float:
        """World heading, rad."""
        return _world_yaw(self._state)

    def takeoff(self, height: float = TAKEOFF_HEIGHT) -> None:
        """Start the motors and climb ``height`` m (the drone must be landed)."""
        self.flying = True
        self._memory = self._controller.new_memory()
        p = self.position
        self._set_setpoint(p, np.zeros(3), self.yaw)
        self._begin(Line(p, p + np.array([0.0, 0.0, height])), TAKEOFF_SPEED)

    def land(self) -> None:
        """Descend to the floor below the setpoint, then stop the motors."""
        p = self._setpoint[0]
        self.landing = True
        self._begin(Line(p, [p[0], p[1], self.floor]), LAND_SPEED)

    def move(self, offset: ArrayLike, speed: float) -> None:
        """Fly the straight ``offset`` (3,) m, heading frame (x forward, y left, z up),
        at ``speed`` m/s."""
        p, _, yaw = self._setpoint
        self._begin(Line(p, p + self._to_world(offset, yaw)), speed)

    def curve(self, via: ArrayLike, end: ArrayLike, speed: float) -> None:
        """Fly the arc through ``via`` to ``end`` (each (3,) m, heading frame) at
        ``speed`` m/s."""
        p, _, yaw = self._setpoint
        self._begin(Arc(p, p + self._to_world(via, yaw), p + self._to_world(end, yaw)), speed)

    def turn(self, angle: float) -> None:
        """Turn on the spot by ``angle`` rad, counter-clockwise seen from above."""
        p, _, yaw = self._setpoint
        profile = SpeedProfile(abs(angle), TURN_RATE, TURN_ACCELERATION)
        self._start(Motion(Line(p, p), STILL, yaw, angle, profile))

    def pause(self, seconds: float) -> None:
        """Stay busy hovering for ``seconds`` (a ``flip``, which is not flown)."""
        p, _, yaw = self._setpoint
        self._start(Motion(Line(p, p), STILL, yaw, minimum=seconds))

    def hold(self) -> None:
        """``stop``: end any motion and the sticks, and hover where the drone is."""
        self.motion = None
        self.landing = False
        self._sticks = (np.zeros(3), 0.0)
        self._set_setpoint(self.position, self._state[VELOCITY].copy(), self.yaw)

    def sticks(self, right: int, forward: int, up: int, clockwise: int) -> None:
        """``rc``: the setpoint's velocity from the four sticks, each -100..100."""
        yaw = self._setpoint[2]
        horizontal = self._to_world([forward, -right, 0.0], yaw)
        self._sticks = (RC_SPEED / 100.0 * (horizontal + np.array([0.0, 0.0, up])),
                        -RC_YAW_RATE / 100.0 * clockwise)

    def cut_motors(self) -> None:
        """``emergency``: the motors stop and the drone falls to the floor."""
        self.motion = None
        self.landing = False
        self.falling = self.flying
        self.flying = False

    # --- time ------------------------------------------------------------------------

    def advance(self, seconds: float) -> bool:
        """Fly ``seconds`` of emulated time; True when a motion ended in them."""
        self._carry += seconds
        steps = int(self._carry / self._dt + 1e-9)
        if steps == 0:
            return False
        self._carry -= steps * self._dt
        times = self.time + self._dt * np.arange(steps)
        velocity = self._state[VELOCITY].copy()
        if self.falling:
            positions = self._fall(steps)
        elif self.flying:
            positions = self._fly(self._references(times))
        else:
            positions = np.tile(self._state[POSITION], (steps, 1))
        self._record(times, positions)
        elapsed = steps * self._dt
        self._acceleration = (self._state[VELOCITY] - velocity) / elapsed
        self.time += elapsed
        if self.flying:
            self.motor_time += elapsed
        self.battery = max(0.0, self.battery - elapsed * (
            self.battery_drain * DRAIN_FLYING if self.flying else DRAIN_IDLE))
        return self._check_motion_end()

    def track(self, since: int = 0) -> tuple[FloatArray, FloatArray]:
        """Times (N,) s and world positions (N, 3) m every :data:`TRACK_PERIOD` s, from
        the ``since``-th sample on."""
        return np.array(self._track_t[since:]), np.array(self._track_p[since:]).reshape(-1, 3)

    def telemetry(self, mission_pads: bool = False) -> Telemetry:
        """The state packet's values now (see :class:`~quadnav.hardware.sdk.Telemetry`)."""
        r = quaternion.to_matrix(self._state[ATTITUDE])
        yaw = self.yaw
        forward = np.array([math.cos(yaw), math.sin(yaw), 0.0])
        left = np.array([-math.sin(yaw), math.cos(yaw), 0.0])
        v = self._state[VELOCITY]
        # specific force along body x forward, y left, z up
        force = r.T @ (self._acceleration + np.array([0.0, 0.0, _G]))
        height = max(0, round(100 * (self._state[2] - self.floor)))
        heat = 1.0 - math.exp(-self.time / 600.0)
        return Telemetry(
            pitch=round(math.degrees(math.asin(max(-1.0, min(1.0, r[2, 0]))))),
            roll=round(math.degrees(math.atan2(r[2, 1], r[2, 2]))),
            yaw=round(math.degrees(_wrap(self.initial_yaw - yaw))),
            velocity=(round(10 * float(v @ forward)), round(-10 * float(v @ left)),
                      round(-10 * float(v[2]))),
            acceleration=tuple(float(x) + 0.0 for x in 1000.0 / _G * force * [1.0, -1.0, -1.0]),
            height=height, tof=max(10, height), baro=float(self._state[2]),
            battery=self.battery_percent,
            motor_time=int(self.motor_time),
            temperature=(round(40 + 40 * heat), round(43 + 40 * heat)))

    # --- inside ----------------------------------------------------------------------

    def _resting(self, position: FloatArray, yaw: float) -> FloatArray:
        """At rest on the floor below ``position``, level, heading ``yaw``, motors off."""
        state = hover_state(self.params, [position[0], position[1], self.floor], yaw)
        state[ROTORS] = 0.0
        return state

    @staticmethod
    def _to_world(offset: ArrayLike, yaw: float) -> FloatArray:
        x, y, z = np.asarray(offset, dtype=np.float64)
        c, s = math.cos(yaw), math.sin(yaw)
        return np.array([c * x - s * y, s * x + c * y, z])

    def _set_setpoint(self, position: FloatArray, velocity: FloatArray, yaw: float) -> None:
        self._setpoint = (np.array(position, dtype=np.float64), np.array(velocity), yaw)

    def _begin(self, shape: Shape, speed: float) -> None:
        """Start flying ``shape`` at ``speed`` m/s, keeping the heading."""
        self._start(Motion(shape, SpeedProfile(shape.length, speed, ACCELERATION),
                           self._setpoint[2]))

    def _start(self, motion: Motion) -> None:
        self._sticks = (np.zeros(3), 0.0)
        self.motion = motion
        self._motion_began = self.time

    def _references(self, times: FloatArray) -> FloatArray:
        """Reference rows for control steps at ``times`` (K,): the motion's, else the
        setpoint moved by the sticks (whose end becomes the new setpoint)."""
        if self.motion is not None:
            return self.motion.reference(times - self._motion_began)
        p, v, yaw = self._setpoint
        target, rate = self._sticks
        k = np.arange(len(times) + 1)[:, None]
        step = ACCELERATION * self._dt * k
        velocities = v + np.clip(target - v, -step, step)
        positions = p + self._dt * np.vstack([np.zeros(3), np.cumsum(velocities[:-1], axis=0)])
        yaws = yaw + rate * self._dt * k[:, 0]
        self._set_setpoint(positions[-1], velocities[-1], float(yaws[-1]))
        accelerations = np.diff(velocities, axis=0) / self._dt
        return np.column_stack([positions[:-1], velocities[:-1], accelerations, yaws[:-1],
                                np.full(len(times), rate)])

    def _fly(self, references: FloatArray) -> FloatArray:
        """Run the closed loop through ``references`` (K, 11); positions (K, 3) before
        each step."""
        steps = len(references)
        record = loop.new_record(steps)
        code, done = loop.run_steps(
            self._controller, self._state, self._memory, 0, steps,
            np.ascontiguousarray(references), self._vehicle, self._vehicle,
            self.settings.substeps, self._dt, self._scene, loop.still_air(steps), record)
        records = record.states
        if code != loop.RUNNING:  # diverged (e.g. tipped over): it crashes to the floor
            self.motion, self.landing, self.flying = None, False, False
            records[done:] = self._resting(records[done - 1], self.yaw)
            self._state = records[-1].copy()
            self._set_setpoint(self._state[POSITION], np.zeros(3), self.yaw)
        return records[:, POSITION]

    def _fall(self, steps: int) -> FloatArray:
        """Motors off, under gravity to the floor; positions (K, 3) before each step."""
        positions = np.empty((steps, 3))
        off, still, work = np.zeros(4), np.zeros(3), rk4_workspace()
        for k in range(steps):
            positions[k] = self._state[POSITION]
            for _ in range(self.settings.substeps):
                rk4_step(self._state, off, self._vehicle, still, still,
                         self._dt / self.settings.substeps, self.floor, work)
        if self._state[2] <= self.floor + 1e-6 and abs(self._state[5]) < 1e-6:
            self.falling = False
            self._state = self._resting(self._state[POSITION], self.yaw)
            self._set_setpoint(self._state[POSITION], np.zeros(3), self.yaw)
        return positions

    def _record(self, times: FloatArray, positions: FloatArray) -> None:
        """Keep the positions (K, 3) at times (K,) that fall on the track's period."""
        every = max(1, round(TRACK_PERIOD / self._dt))
        kept = (self._steps + np.arange(len(times))) % every == 0
        self._track_t.extend(times[kept].tolist())
        self._track_p.extend(positions[kept])
        self._steps += len(times)

    def _check_motion_end(self) -> bool:
        """End the motion once it has settled (or timed out); True if it ended now."""
        if self.motion is None:
            return False
        end, end_yaw = self.motion.end
        late = self.time - self._motion_began - self.motion.duration
        if late < 0:
            return False
        settled = (np.linalg.norm(self._state[POSITION] - end) < SETTLE_DISTANCE
                   and np.linalg.norm(self._state[VELOCITY]) < SETTLE_SPEED
                   and abs(_wrap(self.yaw - end_yaw)) < SETTLE_YAW)
        if not settled and late < SETTLE_TIMEOUT:
            return False
        self.motion = None
        self._set_setpoint(end, np.zeros(3), end_yaw)
        if self.landing:
            self.landing, self.flying = False, False
            self._state = self._resting(self._state[POSITION], self.yaw)
        return True

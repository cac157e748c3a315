"""The PX4-style cascade, compiled with numba: position -> velocity -> thrust vector ->
attitude -> body rate -> mixer -> motor commands.

One call of :func:`control` runs every loop once (the same rate for all):

1. **Position PID** (world axes): velocity setpoint = trajectory velocity (feed-forward)
   + PID of the position error; saturated to the horizontal, climb and descent limits.
2. **Velocity PID**: acceleration setpoint = trajectory acceleration (feed-forward) + P
   and I of the velocity error + D on the filtered difference between the trajectory's
   and the measured acceleration; horizontal acceleration saturated.
3. **Thrust vector** ``m (a + g e3)`` plus the drag the vehicle meets at the trajectory
   velocity; tilt limited, then magnitude limited keeping the vertical part first.
   Anti-windup: the velocity integral sees the error less what saturation took away
   (back-calculation, as PX4), and its contribution is bounded.
4. **Attitude P**: the desired attitude points body z along the thrust vector and
   heads the trajectory's yaw; rate setpoint = 2 kp times the vector part of the
   quaternion error (plus the yaw-rate feed-forward), limited per axis.
5. **Rate PID**: angular acceleration = PID of the rate error (D on the filtered
   measured rate); torque = J alpha + w x J w. The integral pauses while the mixer
   saturates.
6. **Mixer** (:func:`quadnav.vehicle.rotors.mix`): collective thrust along the current
   body z and the torques to per-rotor thrusts, then motor commands in [0, 1].

:func:`velocity_control`, :func:`attitude_control` and :func:`rate_control` enter the
cascade at step 2, 4 or 5 with a setpoint of that loop: the inner loops that a plain-Python
controller's velocity, attitude or body-rate commands go through (:mod:`.held`).

The controller's memory (integrals, filters, previous values) is a float64 array of
:data:`MEMORY_SIZE`; start from :func:`new_memory`.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from quadnav.control.contract import (
    REFERENCE_ACCELERATION,
    REFERENCE_POSITION,
    REFERENCE_VELOCITY,
    REFERENCE_YAW,
    REFERENCE_YAW_RATE,
    SATURATED,
    Controller,
)
from quadnav.control.gains import Gains
from quadnav.control.terms import add_gyroscopic, reference_drag
from quadnav.vehicle import quaternion
from quadnav.vehicle.dynamics import ATTITUDE, POSITION, RATES, VELOCITY, VehicleArrays
from quadnav.vehicle.rotors import mix

# Memory layout (slot 0 is the contract's: whether the mixer clipped the commands).
MIXER_SATURATED = SATURATED
_POSITION_INTEGRAL = 1
_VELOCITY_INTEGRAL = 4
_RATE_INTEGRAL = 7
_POSITION_ERROR_RATE = 10
_ACCELERATION = 13
_ANGULAR_ACCELERATION = 16
_PREVIOUS_POSITION_ERROR = 19
_PREVIOUS_VELOCITY = 22
_PREVIOUS_RATES = 25
_STARTED = 28
MEMORY_SIZE = 29


class GainArrays(NamedTuple):
    """:class:`~quadnav.control.gains.Gains` as plain arrays for compiled code: rows of
    (3,) per loop, limits in SI units (radians)."""

    position: np.ndarray  # (4, 3): kp, ki, kd, integral limit
    velocity: np.ndarray  # (4, 3)
    attitude_kp: np.ndarray  # (3,)
    rate: np.ndarray  # (4, 3)
    speed_limits: np.ndarray  # (3,): horizontal, up, down, m/s
    acceleration_xy: float
    tilt_max: float
    thrust_range: np.ndarray  # (2,): fractions of the total rotor thrust
    rate_max: np.ndarray  # (3,) rad/s
    derivative_cutoff: float  # Hz


def gain_arrays(gains: Gains) -> GainArrays:
    """The compiled-code form of ``gains``."""
    def rows(pid):
        return np.array([pid.kp, pid.ki, pid.kd, pid.integral_limit])
    limits = gains.limits
    return GainArrays(
        rows(gains.position), rows(gains.velocity), np.array(gains.attitude_kp),
        rows(gains.rate), np.array([limits.speed_xy, limits.speed_up, limits.speed_down]),
        limits.acceleration_xy, math.radians(limits.tilt_max_deg),
        np.array([limits.thrust_min, limits.thrust_max]), np.radians(limits.rate_max_deg),
        limits.derivative_cutoff_hz)


def cascade_controller(gains: Gains | None = None) -> Controller:
    """The cascade with ``gains`` (default: :class:`~quadnav.control.gains.Gains`) as a
    :class:`~quadnav.control.contract.Controller`."""
    return Controller("cascade", control, gain_arrays(gains or Gains()), MEMORY_SIZE)


def new_memory() -> np.ndarray:
    """Fresh controller memory: integrals and filters at zero."""
    return np.zeros(MEMORY_SIZE)


@njit(cache=True, inline="always")
def _clip(value: float, bound: float) -> float:
    return min(max(value, -bound), bound)


@njit(cache=True, inline="always")
def _scale_xy(v: np.ndarray, limit: float) -> None:
    """Scale the horizontal part of ``v`` (3,) in place to a norm of at most ``limit``."""
    norm = math.hypot(v[0], v[1])
    if norm > limit:
        v[0] *= limit / norm
        v[1] *= limit / norm


@njit(cache=True, inline="always")
def _filtered_rate(memory, at, previous_at, value, a, dt, alpha, started) -> float:
    """Low-pass filtered finite difference of ``value`` (axis ``a`` of a vector kept at
    memory[previous_at:]), kept at memory[at + a]."""
    if started:
        raw = (value - memory[previous_at + a]) / dt
        memory[at + a] += alpha * (raw - memory[at + a])
    memory[previous_at + a] = value
    return memory[at + a]


@njit(cache=True, inline="always")
def _smoothing(g: GainArrays, dt: float) -> float:
    """Weight of a new sample in the first-order filters of the derivative terms."""
    return dt / (dt + 1.0 / (2.0 * math.pi * g.derivative_cutoff))


@njit(cache=True)
def _thrust_vector(force: np.ndarray, v: VehicleArrays, g: GainArrays) -> None:
    """Limit the thrust vector ``force`` (3,) N in place: vertical part within the thrust
    range, tilt within the limit, magnitude within the largest thrust (vertical first)."""
    total = 4.0 * v.max_rotor_thrust
    low, high = g.thrust_range[0] * total, g.thrust_range[1] * total
    force[2] = min(max(force[2], low), high)
    _scale_xy(force, force[2] * math.tan(g.tilt_max))
    _scale_xy(force, math.sqrt(max(high * high - force[2] * force[2], 0.0)))


@njit(cache=True)
def _attitude_setpoint(thrust: np.ndarray, yaw: float) -> np.ndarray:
    """Attitude (4,) with body z along the nonzero vector ``thrust`` (3,) heading ``yaw``.

    The body axes are the columns of a rotation matrix: z the thrust direction, y
    perpendicular to it and to the heading ``(cos yaw, sin yaw, 0)``, x = y cross z."""
    r = np.empty((3, 3))
    z = r[:, 2]
    length = math.sqrt(thrust[0] ** 2 + thrust[1] ** 2 + thrust[2] ** 2)
    for a in range(3):  # element by element: array copies compile error messages
        z[a] = thrust[a] / length
    c, s = math.cos(yaw), math.sin(yaw)
    y = r[:, 1]  # z cross heading
    y[0], y[1], y[2] = -z[2] * s, z[2] * c, z[0] * s - z[1] * c
    norm = math.sqrt(y[0] ** 2 + y[1] ** 2 + y[2] ** 2)
    if norm < 1e-6:  # thrust horizontal along the heading: keep any level y
        y[0], y[1], y[2] = -s, c, 0.0
    else:
        y /= norm
    r[0, 0] = y[1] * z[2] - y[2] * z[1]
    r[1, 0] = y[2] * z[0] - y[0] * z[2]
    r[2, 0] = y[0] * z[1] - y[1] * z[0]
    return quaternion.from_matrix(r)


@njit(cache=True)
def control(memory: np.ndarray, state: np.ndarray, reference: np.ndarray, g: GainArrays,
            v: VehicleArrays, dt: float) -> np.ndarray:
    """Motor commands (4,) in [0, 1] for the measured ``state`` (17,; rotor speeds are not
    used) tracking ``reference`` (:data:`~quadnav.control.contract.REFERENCE_SIZE`,), ``dt``
    s after the last call.
    Updates ``memory`` in place."""
    started = memory[_STARTED] > 0.0
    alpha = _smoothing(g, dt)
    r = quaternion.to_matrix(state[ATTITUDE])
    position, reference_position = state[POSITION], reference[REFERENCE_POSITION]
    reference_velocity = reference[REFERENCE_VELOCITY]
    # the 3-vectors of the step below, as views of one array (one allocation, not three)
    work = np.empty(9)
    position_error, v_sp, raw_v = work[0:3], work[3:6], work[6:9]

    # 1. position -> velocity setpoint
    for a in range(3):
        e = reference_position[a] - position[a]
        rate = _filtered_rate(memory, _POSITION_ERROR_RATE, _PREVIOUS_POSITION_ERROR, e, a,
                              dt, alpha, started)
        position_error[a] = e
        v_sp[a] = (reference_velocity[a] + g.position[0, a] * e
                   + memory[_POSITION_INTEGRAL + a] + g.position[2, a] * rate)
    for a in range(3):  # element by element: array copies compile error messages
        raw_v[a] = v_sp[a]
    _scale_xy(v_sp, g.speed_limits[0])
    v_sp[2] = min(max(v_sp[2], -g.speed_limits[2]), g.speed_limits[1])
    for a in range(3):
        if v_sp[a] == raw_v[a]:
            memory[_POSITION_INTEGRAL + a] = _clip(
                memory[_POSITION_INTEGRAL + a] + g.position[1, a] * position_error[a] * dt,
                g.position[3, a])
    return _velocity_loops(memory, state, r, v_sp, reference, g, v, dt, alpha, started)


@njit(cache=True)
def velocity_control(memory: np.ndarray, state: np.ndarray, v_sp: np.ndarray,
                     reference: np.ndarray, g: GainArrays, v: VehicleArrays,
                     dt: float) -> np.ndarray:
    """Steps 2-6 alone: motor commands (4,) in [0, 1] that bring the measured ``state``
    (17,) to the velocity setpoint ``v_sp`` (3,) m/s, world frame, with the reference row's
    acceleration as feed-forward, the drag at its velocity, its yaw and yaw rate
    (:data:`~quadnav.control.contract.REFERENCE_SIZE`,). Updates ``memory``."""
    return _velocity_loops(memory, state, quaternion.to_matrix(state[ATTITUDE]), v_sp,
                           reference, g, v, dt, _smoothing(g, dt), memory[_STARTED] > 0.0)


@njit(cache=True)
def _velocity_loops(memory, state, r, v_sp, reference, g: GainArrays, v: VehicleArrays, dt,
                    alpha, started) -> np.ndarray:
    """Steps 2-6 of the cascade (see :func:`velocity_control`), given the body-to-world
    rotation ``r`` (3, 3) of ``state`` and the derivative filters' ``alpha``."""
    # the 3-vectors of the steps below, as views of one array (one allocation, not four)
    work = np.empty(12)
    velocity_error, a_sp, force, unlimited = work[0:3], work[3:6], work[6:9], work[9:12]
    velocity, reference_acceleration = state[VELOCITY], reference[REFERENCE_ACCELERATION]

    # 2. velocity -> acceleration setpoint
    for a in range(3):
        e = v_sp[a] - velocity[a]
        measured = _filtered_rate(memory, _ACCELERATION, _PREVIOUS_VELOCITY, velocity[a], a,
                                  dt, alpha, started)
        velocity_error[a] = e
        a_sp[a] = (reference_acceleration[a] + g.velocity[0, a] * e
                   + memory[_VELOCITY_INTEGRAL + a]
                   + g.velocity[2, a] * (reference_acceleration[a] - measured))
    _scale_xy(a_sp, g.acceleration_xy)

    # 3. thrust vector, with the drag at the reference velocity as feed-forward
    drag = reference_drag(r, v, reference)
    for a in range(3):
        force[a] = (v.mass * a_sp[a] + r[a, 0] * drag[0] + r[a, 1] * drag[1]
                    + r[a, 2] * drag[2])
    force[2] += v.mass * v.gravity
    for a in range(3):
        unlimited[a] = force[a]
    _thrust_vector(force, v, g)
    for a in range(3):  # back-calculation: integrate only the error the output can follow
        taken = (unlimited[a] - force[a]) / v.mass
        corrected = velocity_error[a] - taken / max(g.velocity[0, a], 1e-9)
        memory[_VELOCITY_INTEGRAL + a] = _clip(
            memory[_VELOCITY_INTEGRAL + a] + g.velocity[1, a] * corrected * dt,
            g.velocity[3, a])
    collective = max(force[0] * r[0, 2] + force[1] * r[1, 2] + force[2] * r[2, 2], 0.0)

    q_sp = _attitude_setpoint(force, reference[REFERENCE_YAW])
    return _inner_loops(memory, state, r, q_sp, collective, reference[REFERENCE_YAW_RATE], g,
                        v, dt, alpha, started)


@njit(cache=True)
def attitude_control(memory: np.ndarray, state: np.ndarray, q_sp: np.ndarray,
                     collective: float, yaw_rate: float, g: GainArrays, v: VehicleArrays,
                     dt: float) -> np.ndarray:
    """Steps 4-6 alone: motor commands (4,) in [0, 1] that turn the measured ``state``
    (17,) to the attitude ``q_sp`` (4,) with ``collective`` thrust N along body z, plus a
    world yaw rate feed-forward ``yaw_rate`` rad/s. Updates ``memory``."""
    return _inner_loops(memory, state, quaternion.to_matrix(state[ATTITUDE]), q_sp, collective,
                        yaw_rate, g, v, dt, _smoothing(g, dt), memory[_STARTED] > 0.0)


@njit(cache=True)
def rate_control(memory: np.ndarray, state: np.ndarray, w_sp: np.ndarray, collective: float,
                 g: GainArrays, v: VehicleArrays, dt: float) -> np.ndarray:
    """Steps 5-6 alone: motor commands (4,) in [0, 1] that bring the measured body rates
    of ``state`` (17,) to ``w_sp`` (3,) rad/s (limited per axis) with ``collective``
    thrust N along body z. Updates ``memory``."""
    return _rate_loop(memory, state, w_sp, collective, g, v, dt, _smoothing(g, dt),
                      memory[_STARTED] > 0.0)


@njit(cache=True)
def _inner_loops(memory, state, r, q_sp, collective, yaw_rate, g: GainArrays,
                 v: VehicleArrays, dt, alpha, started) -> np.ndarray:
    """Steps 4-6 of the cascade (see :func:`attitude_control`), given the body-to-world
    rotation ``r`` (3, 3) of ``state`` and the derivative filters' ``alpha``."""
    # 4. attitude -> body rate setpoint
    q_error = quaternion.multiply(quaternion.conjugate(state[ATTITUDE]), q_sp)
    sign = 1.0 if q_error[0] >= 0.0 else -1.0
    w_sp = np.empty(3)
    for b in range(3):
        w_sp[b] = 2.0 * g.attitude_kp[b] * sign * q_error[1 + b] + r[2, b] * yaw_rate
    return _rate_loop(memory, state, w_sp, collective, g, v, dt, alpha, started)


@njit(cache=True)
def _rate_loop(memory, state, w_sp, collective, g: GainArrays, v: VehicleArrays, dt, alpha,
               started) -> np.ndarray:
    """Steps 5-6 of the cascade (see :func:`rate_control`)."""
    # 5. body rate -> torque, written into the wrench the mixer takes
    wrench = np.empty(4)
    wrench[0] = collective
    torque = wrench[1:4]
    saturated = memory[MIXER_SATURATED] > 0.0
    rates = state[RATES]
    for b in range(3):
        e = _clip(w_sp[b], g.rate_max[b]) - rates[b]
        dw = _filtered_rate(memory, _ANGULAR_ACCELERATION, _PREVIOUS_RATES, rates[b], b,
                            dt, alpha, started)
        torque[b] = v.inertia[b] * (g.rate[0, b] * e + memory[_RATE_INTEGRAL + b]
                                    - g.rate[2, b] * dw)
        if not saturated:
            memory[_RATE_INTEGRAL + b] = _clip(
                memory[_RATE_INTEGRAL + b] + g.rate[1, b] * e * dt, g.rate[3, b])
    add_gyroscopic(torque, state, v)

    # 6. mixer
    thrusts, changed = mix(wrench, v.mixer, v.max_rotor_thrust)
    memory[MIXER_SATURATED] = 1.0 if changed else 0.0
    memory[_STARTED] = 1.0
    thrusts /= v.max_rotor_thrust
    return thrusts

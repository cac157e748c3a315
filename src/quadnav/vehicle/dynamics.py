"""6-DOF rigid-body dynamics of the quadrotor with motors, integrated by fixed-step RK4.

State (17,) float64, world frame z up, body frame x forward, z up:

=========  ==========  ===================================================
indices    name        meaning
=========  ==========  ===================================================
0:3        position    centre of mass, m
3:6        velocity    m/s, world frame
6:10       attitude    unit quaternion ``(w, x, y, z)``, body to world
10:13      rates       body angular velocity, rad/s
13:17      rotors      rotor speeds, rad/s (rotor order of :mod:`.rotors`)
=========  ==========  ===================================================

Forces: rotor thrust along body z, gravity, linear drag ``-R D R^T (v - w)`` on the airspeed
(``D`` the body-frame drag coefficients, ``w`` the wind's velocity, world frame) and an
external world-frame force (a steady push, gusts). A solid floor at
``floor_z`` holds the centre of mass up: on touching it, the vehicle stops sinking and
sliding and its body rates stop; :func:`rk4_step` returns the speed it met the floor at.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from quadnav.arrays import FloatArray
from quadnav.vehicle import quaternion
from quadnav.vehicle.params import VehicleParams
from quadnav.vehicle.rotors import SPIN, allocation_matrix

STATE_SIZE = 17
POSITION = slice(0, 3)
VELOCITY = slice(3, 6)
ATTITUDE = slice(6, 10)
RATES = slice(10, 13)
ROTORS = slice(13, 17)


class VehicleArrays(NamedTuple):
    """:class:`~quadnav.vehicle.params.VehicleParams` as plain numbers and arrays, the form
    compiled code takes (see :func:`vehicle_arrays`)."""

    mass: float
    inertia: np.ndarray  # (3,) kg m^2
    thrust_coefficient: float
    torque_coefficient: float
    rotor_speed_max: float
    motor_time_constant: float
    drag: np.ndarray  # (3,) N/(m/s), body axes
    gravity: float
    spin: np.ndarray  # (4,) +1 counter-clockwise
    allocation: np.ndarray  # (4, 4) thrusts -> wrench
    mixer: np.ndarray  # (4, 4) wrench -> thrusts
    max_rotor_thrust: float
    half_size: np.ndarray  # (3,) half the collision box, m


def vehicle_arrays(params: VehicleParams) -> VehicleArrays:
    """The compiled-code form of ``params``."""
    allocation = allocation_matrix(params)
    return VehicleArrays(
        params.mass, np.array(params.inertia), params.thrust_coefficient,
        params.torque_coefficient, params.rotor_speed_max, params.motor_time_constant,
        np.array(params.drag), params.gravity, SPIN.copy(), allocation,
        np.linalg.inv(allocation), params.max_rotor_thrust, 0.5 * np.array(params.body_size))


def hover_state(params: VehicleParams, position, yaw: float = 0.0) -> FloatArray:
    """State (17,) at rest at ``position`` (3,) m heading ``yaw`` rad, rotors at hover."""
    state = np.zeros(STATE_SIZE)
    state[POSITION] = position
    state[ATTITUDE] = quaternion.from_yaw(yaw)
    state[ROTORS] = params.rotor_speed_max * math.sqrt(params.hover_command)
    return state


@njit(cache=True)
def derivative(x: np.ndarray, rotor_command: np.ndarray, v: VehicleArrays,
               force: np.ndarray, wind: np.ndarray, out: np.ndarray) -> None:
    """Write d state / dt (17,) into ``out`` for rotor speed commands (4,) rad/s, an
    external force (3,) N and the wind's velocity (3,) m/s, both in the world frame.
    Scalar arithmetic only: it runs four times per RK4 step."""
    qw, qx, qy, qz = x[6], x[7], x[8], x[9]
    wx, wy, wz = x[10], x[11], x[12]
    r00, r01, r02 = 1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qw * qz), 2 * (qx * qz + qw * qy)
    r10, r11, r12 = 2 * (qx * qy + qw * qz), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qw * qx)
    r20, r21, r22 = 2 * (qx * qz - qw * qy), 2 * (qy * qz + qw * qx), 1 - 2 * (qx * qx + qy * qy)
    # drag: body-frame coefficients on the body-frame airspeed, back to the world frame
    ax, ay, az = x[3] - wind[0], x[4] - wind[1], x[5] - wind[2]
    dx = v.drag[0] * (r00 * ax + r10 * ay + r20 * az)
    dy = v.drag[1] * (r01 * ax + r11 * ay + r21 * az)
    dz = v.drag[2] * (r02 * ax + r12 * ay + r22 * az)
    total = 0.0
    tau_x = 0.0
    tau_y = 0.0
    tau_z = 0.0
    for i in range(4):
        squared = x[13 + i] * x[13 + i]
        thrust = v.thrust_coefficient * squared
        total += thrust
        tau_x += v.allocation[1, i] * thrust
        tau_y += v.allocation[2, i] * thrust
        tau_z -= v.spin[i] * v.torque_coefficient * squared
        out[13 + i] = (rotor_command[i] - x[13 + i]) / v.motor_time_constant
    out[0], out[1], out[2] = x[3], x[4], x[5]
    out[3] = (r02 * total - (r00 * dx + r01 * dy + r02 * dz) + force[0]) / v.mass
    out[4] = (r12 * total - (r10 * dx + r11 * dy + r12 * dz) + force[1]) / v.mass
    out[5] = (r22 * total - (r20 * dx + r21 * dy + r22 * dz) + force[2]) / v.mass - v.gravity
    out[6] = 0.5 * (-qx * wx - qy * wy - qz * wz)
    out[7] = 0.5 * (qw * wx + qy * wz - qz * wy)
    out[8] = 0.5 * (qw * wy - qx * wz + qz * wx)
    out[9] = 0.5 * (qw * wz + qx * wy - qy * wx)
    jx, jy, jz = v.inertia[0], v.inertia[1], v.inertia[2]
    out[10] = (tau_x - (wy * jz * wz - wz * jy * wy)) / jx
    out[11] = (tau_y - (wz * jx * wx - wx * jz * wz)) / jy
    out[12] = (tau_z - (wx * jy * wy - wy * jx * wx)) / jz


@njit(cache=True)
def rotor_speed_commands(commands: np.ndarray, v: VehicleArrays, out: np.ndarray) -> None:
    """Write into ``out`` (4,) the rotor speeds, rad/s, asked for by motor commands (4,)
    in [0, 1] (clipped)."""
    for i in range(4):
        out[i] = v.rotor_speed_max * math.sqrt(min(max(commands[i], 0.0), 1.0))


#: Rows of an RK4 workspace (:func:`rk4_workspace`): the four stages' derivatives, the
#: stage state, and the rotor speed targets in the first four entries of the last row.
_STAGES, _STAGE_STATE, _TARGETS = 0, 4, 5


@njit(cache=True)
def rk4_workspace() -> FloatArray:
    """Scratch space (6, 17) for :func:`rk4_step`, so a step allocates nothing."""
    return np.empty((6, STATE_SIZE))


@njit(cache=True)
def rk4_step(x: np.ndarray, commands: np.ndarray, v: VehicleArrays, force: np.ndarray,
             wind: np.ndarray, dt: float, floor_z: float, work: np.ndarray) -> float:
    """Advance the state ``x`` (17,) in place by ``dt`` s holding motor commands (4,), an
    external force (3,) N and the wind's velocity (3,) m/s: one RK4 step, then the
    quaternion renormalised and the floor applied. ``work`` is :func:`rk4_workspace`
    (overwritten). Returns the speed, m/s, of the centre when the floor stopped it in this
    step (the step took it below ``floor_z``): its velocity's size at the end of the step,
    before the floor took it away; -1.0 when the centre stayed at or above the floor."""
    target = work[_TARGETS, 0:4]
    rotor_speed_commands(commands, v, target)
    stage = work[_STAGE_STATE]
    derivative(x, target, v, force, wind, work[_STAGES])
    for step, weight in ((1, 0.5), (2, 0.5), (3, 1.0)):
        previous = work[_STAGES + step - 1]
        for i in range(STATE_SIZE):
            stage[i] = x[i] + weight * dt * previous[i]
        derivative(stage, target, v, force, wind, work[_STAGES + step])
    for i in range(STATE_SIZE):
        x[i] += dt / 6.0 * (work[0, i] + 2.0 * work[1, i] + 2.0 * work[2, i] + work[3, i])
    norm = math.sqrt(x[6] ** 2 + x[7] ** 2 + x[8] ** 2 + x[9] ** 2)
    for i in range(6, 10):
        x[i] /= norm
    if not x[2] < floor_z:
        return -1.0
    speed = math.sqrt(x[3] ** 2 + x[4] ** 2 + x[5] ** 2)
    x[2] = floor_z
    x[3] = 0.0
    x[4] = 0.0
    x[5] = max(x[5], 0.0)
    x[10:13] = 0.0
    return speed

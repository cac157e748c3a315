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
(``D`` the body-frame drag coefficients, ``w`` the wind's velocity, world frame), rotorpy's
aerodynamics on the same airspeed when the vehicle has them (:func:`aerodynamic_wrench`:
rotor drag, parasitic drag, translational lift, the flapping moment) and an external
world-frame force (a steady push, gusts). A solid floor at
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

#: Length of a state, and the slices of each quantity in it (see the module docstring;
#: numba kernels read these module-level constants as compile-time constants).
STATE_SIZE = 17
POSITION = slice(0, 3)
VELOCITY = slice(3, 6)
ATTITUDE = slice(6, 10)
RATES = slice(10, 13)
ROTORS = slice(13, 17)


class Aerodynamics(NamedTuple):
    """rotorpy's aerodynamic coefficients of a vehicle (see
    :class:`~quadnav.vehicle.params.VehicleParams`), as plain numbers: compiled code reads
    them fastest so."""

    rotor_drag_x: float  # N/(rad/s)/(m/s), per rotor, body axes
    rotor_drag_y: float
    rotor_drag_z: float
    parasitic_drag_x: float  # N/(m/s)^2, body axes
    parasitic_drag_y: float
    parasitic_drag_z: float
    translational_lift: float  # N/(m/s)^2, per rotor
    flapping: float  # N m/(rad/s)/(m/s), per rotor
    modelled: bool  # whether any of them is not zero


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
    aerodynamics: Aerodynamics


def vehicle_arrays(params: VehicleParams) -> VehicleArrays:
    """The compiled-code form of ``params``."""
    allocation = allocation_matrix(params)
    return VehicleArrays(
        params.mass, np.array(params.inertia), params.thrust_coefficient,
        params.torque_coefficient, params.rotor_speed_max, params.motor_time_constant,
        np.array(params.drag), params.gravity, SPIN.copy(), allocation,
        np.linalg.inv(allocation), params.max_rotor_thrust, 0.5 * np.array(params.body_size),
        aerodynamic_coefficients(params))


def aerodynamic_coefficients(params: VehicleParams) -> Aerodynamics:
    """The aerodynamic coefficients of ``params`` as compiled code takes them."""
    coefficients = [float(c) for c in (*params.rotor_drag, *params.parasitic_drag,
                                       params.translational_lift, params.flapping)]
    return Aerodynamics(*coefficients, any(c != 0 for c in coefficients))


def hover_state(params: VehicleParams, position, yaw: float = 0.0) -> FloatArray:
    """State (17,) at rest at ``position`` (3,) m heading ``yaw`` rad, rotors at hover."""
    state = np.zeros(STATE_SIZE)
    state[POSITION] = position
    state[ATTITUDE] = quaternion.from_yaw(yaw)
    state[ROTORS] = params.hover_rotor_speed
    return state


@njit(cache=True, inline="always")
def aerodynamic_wrench(x: np.ndarray, ux: float, uy: float, uz: float, v: VehicleArrays
                       ) -> tuple[float, float, float, float, float, float]:
    """rotorpy's aerodynamics (its ``Multirotor.compute_body_wrench`` with ``aero=True``)
    for the state ``x`` (17,) and the body-frame airspeed ``(ux, uy, uz)`` m/s: the force
    (N) and the torque about the centre (N m), in body axes, besides the rotors' thrust and
    yaw torque. Rotor ``i`` at ``r_i`` (in the body's x-y plane) spinning at ``w_i`` meets
    the airspeed ``h = u + w x r_i`` at its hub, there the rotor drag ``-w_i
    diag(rotor_drag) h`` and the translational lift ``translational_lift (h_x^2 + h_y^2)``
    along body z act, and it twists the body by the flapping moment ``-flapping w_i
    (h x e_z)``; the parasitic drag ``-|u| diag(parasitic_drag) u`` acts at the centre."""
    a = v.aerodynamics
    speed = math.sqrt(ux * ux + uy * uy + uz * uz)
    fx = -speed * a.parasitic_drag_x * ux
    fy = -speed * a.parasitic_drag_y * uy
    fz = -speed * a.parasitic_drag_z * uz
    mx, my, mz = 0.0, 0.0, 0.0
    wx, wy, wz = x[10], x[11], x[12]
    for i in range(4):
        px, py = -v.allocation[2, i], v.allocation[1, i]  # the hub, m
        hx, hy, hz = ux - wz * py, uy + wz * px, uz + wx * py - wy * px
        spin = x[13 + i]
        hub_x = -spin * a.rotor_drag_x * hx
        hub_y = -spin * a.rotor_drag_y * hy
        hub_z = -spin * a.rotor_drag_z * hz + a.translational_lift * (hx * hx + hy * hy)
        fx += hub_x
        fy += hub_y
        fz += hub_z
        mx += py * hub_z - a.flapping * spin * hy
        my += -px * hub_z + a.flapping * spin * hx
        mz += px * hub_y - py * hub_x
    return fx, fy, fz, mx, my, mz


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
    ax, ay, az = x[3] - wind[0], x[4] - wind[1], x[5] - wind[2]  # the airspeed
    ux = r00 * ax + r10 * ay + r20 * az  # in body axes
    uy = r01 * ax + r11 * ay + r21 * az
    uz = r02 * ax + r12 * ay + r22 * az
    # body-frame forces besides the thrust (and torques besides the rotors'): rotorpy's
    # aerodynamics, if the vehicle has them (asked here, not in the function: that way
    # round, the loop of a vehicle without them ran a quarter slower), and the linear drag
    fx, fy, fz, mx, my, mz = 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    if v.aerodynamics.modelled:
        fx, fy, fz, mx, my, mz = aerodynamic_wrench(x, ux, uy, uz, v)
    fx -= v.drag[0] * ux
    fy -= v.drag[1] * uy
    fz -= v.drag[2] * uz
    total = 0.0
    tau_x = mx
    tau_y = my
    tau_z = mz
    for i in range(4):
        squared = x[13 + i] * x[13 + i]
        thrust = v.thrust_coefficient * squared
        total += thrust
        tau_x += v.allocation[1, i] * thrust
        tau_y += v.allocation[2, i] * thrust
        tau_z -= v.spin[i] * v.torque_coefficient * squared
        out[13 + i] = (rotor_command[i] - x[13 + i]) / v.motor_time_constant
    out[0], out[1], out[2] = x[3], x[4], x[5]
    fz += total
    out[3] = (r00 * fx + r01 * fy + r02 * fz + force[0]) / v.mass
    out[4] = (r10 * fx + r11 * fy + r12 * fz + force[1]) / v.mass
    out[5] = (r20 * fx + r21 * fy + r22 * fz + force[2]) / v.mass - v.gravity
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
    x[RATES] = 0.0
    return speed

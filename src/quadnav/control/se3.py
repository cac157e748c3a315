"""The geometric controller on SE(3) of Lee, Leok and McClamroch (2010), compiled with
numba: the one MEAM620 and rotorpy use, as a second :class:`~quadnav.control.contract.Controller`
(``fly --controller se3``).

One step:

1. **Force**: ``F = m (-kx ex - kv ev + a_ref) + m g e3`` plus the drag the vehicle meets
   at the reference velocity (as the cascade), with ``ex``, ``ev`` the position and
   velocity errors and gains per axis in 1/s^2 and 1/s (so they do not depend on the
   mass); the collective thrust is ``F`` along the current body z.
2. **Attitude**: the desired body z is along ``F``, the desired heading the reference's
   yaw; ``eR = vee(Rd^T R - R^T Rd) / 2`` and ``ew = w - R^T Rd w_d`` (``w_d``: the yaw
   rate about world z); torque ``J (-kR eR - kw ew) + w x J w`` (gains in 1/s^2 and 1/s).
3. **Mixer**: :func:`quadnav.vehicle.rotors.mix`, roll and pitch first when the rotors
   cannot make the wrench; motor commands in [0, 1].

It has no integral terms, so a steady force it does not model (wind) leaves an offset.
The default gains (:class:`SE3Gains`) are rotorpy's for the Crazyflie (its ``SE3Control``'s
position gains, and the attitude gains it shipped before rotorpy 3.0, which has 310 and 57),
with a gentler yaw; in these units they suit any small quadrotor whose motors respond within
a few hundredths of a second. A TOML file sets any of them (``--gains FILE``)::

    kx = [6.5, 6.5, 15.0]      # position, 1/s^2
    kv = [4.0, 4.0, 9.0]       # velocity, 1/s
    kr = [544.0, 544.0, 100.0] # attitude, 1/s^2
    kw = [46.64, 46.64, 20.0]  # body rate, 1/s
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numba import njit

from quadnav.arrays import FloatArray
from quadnav.config import frozen_vector, require, vector_field
from quadnav.control.contract import (
    REFERENCE_ACCELERATION,
    REFERENCE_POSITION,
    REFERENCE_VELOCITY,
    REFERENCE_YAW,
    REFERENCE_YAW_RATE,
    SATURATED,
    Controller,
)
from quadnav.control.gains import gain_checks
from quadnav.control.terms import add_gyroscopic, reference_drag
from quadnav.vehicle import quaternion
from quadnav.vehicle.dynamics import ATTITUDE, POSITION, RATES, VELOCITY, VehicleArrays
from quadnav.vehicle.rotors import mix

#: Memory: only the contract's saturation flag.
MEMORY_SIZE = 1


@dataclass(frozen=True, eq=False)
class SE3Gains:
    """The geometric controller's gains, per axis (3,), each from 0 to 10,000 (defaults: rotorpy's
    ``SE3Control``'s before rotorpy 3.0, with a gentler yaw; see the module docstring).

    Attributes:
        kx: position, 1/s^2 (world axes).
        kv: velocity, 1/s (world axes).
        kr: attitude, 1/s^2 (body axes).
        kw: body rate, 1/s (body axes).
    """

    kx: FloatArray = vector_field(6.5, 6.5, 15.0)
    kv: FloatArray = vector_field(4.0, 4.0, 9.0)
    kr: FloatArray = vector_field(544.0, 544.0, 100.0)
    kw: FloatArray = vector_field(46.64, 46.64, 20.0)

    def __post_init__(self) -> None:
        for k in ("kx", "kv", "kr", "kw"):  # any three numbers, kept as read-only arrays
            object.__setattr__(self, k, frozen_vector(getattr(self, k), 3))
        require(gain_checks(self, ("kx", "kv", "kr", "kw")))


class SE3GainArrays(NamedTuple):
    """:class:`SE3Gains` as compiled code takes them: (3,) arrays."""

    kx: np.ndarray
    kv: np.ndarray
    kr: np.ndarray
    kw: np.ndarray


def se3_gain_arrays(gains: SE3Gains) -> SE3GainArrays:
    """The compiled-code form of ``gains``."""
    return SE3GainArrays(*(np.array(k, dtype=np.float64) for k in (
        gains.kx, gains.kv, gains.kr, gains.kw)))


def se3_controller(gains: SE3Gains | None = None) -> Controller:
    """The geometric controller with ``gains`` (default: :class:`SE3Gains`) as a
    :class:`~quadnav.control.contract.Controller`."""
    return Controller("se3", se3_step, se3_gain_arrays(gains or SE3Gains()), MEMORY_SIZE)


@njit(cache=True)
def se3_step(memory: np.ndarray, state: np.ndarray, reference: np.ndarray, g: SE3GainArrays,
             v: VehicleArrays, dt: float) -> np.ndarray:
    """Motor commands (4,) in [0, 1] for the measured ``state`` (17,) tracking
    ``reference`` (11,); see the module docstring."""
    r = quaternion.to_matrix(state[ATTITUDE])
    position, velocity = state[POSITION], state[VELOCITY]
    reference_position, reference_velocity = (reference[REFERENCE_POSITION],
                                              reference[REFERENCE_VELOCITY])
    reference_acceleration = reference[REFERENCE_ACCELERATION]
    force = np.empty(3)
    for a in range(3):
        force[a] = v.mass * (-g.kx[a] * (position[a] - reference_position[a])
                             - g.kv[a] * (velocity[a] - reference_velocity[a])
                             + reference_acceleration[a])
    force[2] += v.mass * v.gravity
    drag = reference_drag(r, v, reference)  # as feed-forward, in world axes
    for a in range(3):
        force[a] += r[a, 0] * drag[0] + r[a, 1] * drag[1] + r[a, 2] * drag[2]
    collective = max(force[0] * r[0, 2] + force[1] * r[1, 2] + force[2] * r[2, 2], 0.0)

    b3 = force / math.sqrt(force[0] ** 2 + force[1] ** 2 + force[2] ** 2)
    yaw = reference[REFERENCE_YAW]
    heading = np.array([math.cos(yaw), math.sin(yaw), 0.0])
    b2 = np.cross(b3, heading)
    b2 /= math.sqrt(b2[0] ** 2 + b2[1] ** 2 + b2[2] ** 2)
    b1 = np.cross(b2, b3)
    rd = np.empty((3, 3))
    for a in range(3):  # element by element: array copies compile error messages
        rd[a, 0], rd[a, 1], rd[a, 2] = b1[a], b2[a], b3[a]
    error = 0.5 * (rd.T @ r - r.T @ rd)
    e_r = np.array([error[2, 1], error[0, 2], error[1, 0]])
    w_d = r.T @ np.array([0.0, 0.0, reference[REFERENCE_YAW_RATE]])  # yaw rate, body axes
    torque = np.empty(3)
    w = state[RATES]
    for b in range(3):
        torque[b] = v.inertia[b] * (-g.kr[b] * e_r[b] - g.kw[b] * (w[b] - w_d[b]))
    add_gyroscopic(torque, state, v)

    wrench = np.array([collective, torque[0], torque[1], torque[2]])
    thrusts, changed = mix(wrench, v.mixer, v.max_rotor_thrust)
    memory[SATURATED] = 1.0 if changed else 0.0
    return thrusts / v.max_rotor_thrust

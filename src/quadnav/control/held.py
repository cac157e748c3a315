"""A compiled controller that flies the commands held in its memory through quadnav's own
inner loops: how a plain-Python controller (:mod:`.plain`) flies in the
compiled closed loop.

Before each control step the Python side writes a command mode and its numbers into the
memory (:func:`hold`); :func:`held_step`, the compiled step the loop calls, turns them into
motor commands:

================  ==========================================  ==============================
mode              command, memory[COMMAND:]                   turned into motor commands by
================  ==========================================  ==============================
MOTOR_SPEEDS      rotor speeds (4,) rad/s                     ``u = (w / w_max)^2``, ``w``
                                                              clipped to ``[0, w_max]``
MOTOR_THRUSTS     rotor thrusts (4,) N                        ``u = f / f_max`` in [0, 1]
THRUST_MOMENT     collective thrust N, body moments (3,) N m  the mixer
                                                              (:func:`~quadnav.vehicle.rotors.mix`)
THRUST_ATTITUDE   collective thrust N, attitude (w, x, y, z)  the cascade's attitude and
                                                              rate loops, the mixer
THRUST_RATES      collective thrust N, body rates (3,) rad/s  the cascade's rate loop, mixer
VELOCITY          velocity (3,) m/s, world frame              the cascade's velocity loop
                                                              and those below it
================  ==========================================  ==============================

The rotors are in quadnav's order (:mod:`quadnav.vehicle.rotors`). The inner loops are the
cascade's (:func:`~quadnav.control.cascade.velocity_control`,
:func:`~quadnav.control.cascade.attitude_control`,
:func:`~quadnav.control.cascade.rate_control`) with its gains (the vehicle's, or
``--gains``): an attitude command has no rate feed-forward; a velocity command has no
acceleration feed-forward and heads the reference's yaw at its yaw rate. The memory is the
cascade's, then :data:`MODE` and the :data:`COMMAND` slots; slot
:data:`~quadnav.control.contract.SATURATED` says whether the commands were clipped.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from quadnav.arrays import FloatArray
from quadnav.control import cascade
from quadnav.control.cascade import GainArrays, gain_arrays
from quadnav.control.contract import (
    REFERENCE_SIZE,
    REFERENCE_VELOCITY,
    REFERENCE_YAW,
    REFERENCE_YAW_RATE,
    SATURATED,
    Controller,
    PythonSide,
)
from quadnav.control.gains import Gains
from quadnav.vehicle.dynamics import VehicleArrays
from quadnav.vehicle.rotors import mix

#: Command modes (the value held in memory slot :data:`MODE`).
MOTOR_SPEEDS, MOTOR_THRUSTS, THRUST_MOMENT, THRUST_ATTITUDE, THRUST_RATES, VELOCITY = range(6)
#: Memory slot of the mode, then the command's numbers (up to :data:`COMMAND_SIZE`).
MODE = cascade.MEMORY_SIZE
COMMAND = MODE + 1
COMMAND_SIZE = 5
MEMORY_SIZE = COMMAND + COMMAND_SIZE


def held_controller(name: str, python: PythonSide, gains: Gains) -> Controller:
    """The compiled step that flies what ``python`` holds, as a
    :class:`~quadnav.control.contract.Controller` named ``name``, with the cascade's
    ``gains`` for its inner loops."""
    return Controller(name, held_step, gain_arrays(gains), MEMORY_SIZE, python)


def hold(memory: FloatArray, mode: int, command: FloatArray) -> None:
    """Write the command ``mode`` and its numbers ``command`` (at most
    :data:`COMMAND_SIZE`) into ``memory``, for the next :func:`held_step`."""
    memory[MODE] = mode
    memory[COMMAND:COMMAND + len(command)] = command


@njit(cache=True)
def held_step(memory: np.ndarray, state: np.ndarray, reference: np.ndarray, g: GainArrays,
              v: VehicleArrays, dt: float) -> np.ndarray:
    """Motor commands (4,) in [0, 1] for the command held in ``memory`` (see the module
    docstring), the measured ``state`` (17,) and the ``reference`` row (11,)."""
    mode = int(memory[MODE])
    if mode <= MOTOR_THRUSTS:  # MOTOR_SPEEDS or MOTOR_THRUSTS
        full = v.rotor_speed_max if mode == MOTOR_SPEEDS else v.max_rotor_thrust
        commands = np.empty(4)
        clipped = False
        for i in range(4):
            asked = memory[COMMAND + i]
            kept = min(max(asked, 0.0), full)
            clipped = clipped or kept != asked
            commands[i] = (kept / full) ** 2 if mode == MOTOR_SPEEDS else kept / full
        memory[SATURATED] = 1.0 if clipped else 0.0
        return commands
    thrust = memory[COMMAND]
    if mode == THRUST_MOMENT:
        wrench = np.empty(4)
        for i in range(4):
            wrench[i] = memory[COMMAND + i]
        thrusts, changed = mix(wrench, v.mixer, v.max_rotor_thrust)
        memory[SATURATED] = 1.0 if changed else 0.0
        return thrusts / v.max_rotor_thrust
    if mode == THRUST_ATTITUDE:
        attitude = np.empty(4)
        for i in range(4):
            attitude[i] = memory[COMMAND + 1 + i]
        return cascade.attitude_control(memory, state, attitude, thrust, 0.0, g, v, dt)
    if mode == THRUST_RATES:
        rates = np.empty(3)
        for b in range(3):
            rates[b] = memory[COMMAND + 1 + b]
        return cascade.rate_control(memory, state, rates, thrust, g, v, dt)
    row = np.zeros(REFERENCE_SIZE)  # VELOCITY: no acceleration feed-forward
    velocity = row[REFERENCE_VELOCITY]
    for a in range(3):
        velocity[a] = memory[COMMAND + a]
    row[REFERENCE_YAW] = reference[REFERENCE_YAW]
    row[REFERENCE_YAW_RATE] = reference[REFERENCE_YAW_RATE]
    return cascade.velocity_control(memory, state, velocity, row, g, v, dt)

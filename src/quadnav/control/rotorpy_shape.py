"""quadnav's state and reference as rotorpy's dicts, the boundary a plain-Python controller
sees (:mod:`quadnav.control.plain`).

rotorpy writes quaternions scalar last, ``(i, j, k, w)``; quadnav scalar first,
``(w, x, y, z)``. Every array handed over is a fresh copy, so a controller that changes one
changes nothing of the flight.
"""

from __future__ import annotations

import numpy as np

from quadnav.arrays import FloatArray
from quadnav.control.contract import (
    REFERENCE_ACCELERATION,
    REFERENCE_POSITION,
    REFERENCE_VELOCITY,
    REFERENCE_YAW,
    REFERENCE_YAW_RATE,
)
from quadnav.vehicle.dynamics import ATTITUDE, POSITION, RATES, ROTORS, VELOCITY


def state_dict(state: FloatArray, wind: FloatArray) -> dict[str, FloatArray]:
    """rotorpy's state dict of a quadnav state (17,) in a wind of velocity ``wind`` (3,)
    m/s: ``x`` m, ``v`` m/s, ``q`` (i, j, k, w) body to world, ``w`` body rates rad/s,
    ``wind`` m/s, ``rotor_speeds`` (4,) rad/s in quadnav's rotor order."""
    w, x, y, z = state[ATTITUDE]
    return {"x": state[POSITION].copy(), "v": state[VELOCITY].copy(),
            "q": np.array([x, y, z, w]),
            "w": state[RATES].copy(), "wind": np.array(wind, dtype=np.float64),
            "rotor_speeds": state[ROTORS].copy()}


def flat_outputs(reference: FloatArray, jerk_snap: FloatArray) -> dict[str, object]:
    """rotorpy's flat outputs of a quadnav reference row (11,: position, velocity,
    acceleration, yaw, yaw rate) and the reference's jerk and snap (6,): ``x``, ``x_dot``,
    ``x_ddot``, ``x_dddot``, ``x_ddddot`` (3,) m, m/s, ..., m/s^4; ``yaw`` rad and ``yaw_dot``
    rad/s as floats."""
    return {"x": reference[REFERENCE_POSITION].copy(),
            "x_dot": reference[REFERENCE_VELOCITY].copy(),
            "x_ddot": reference[REFERENCE_ACCELERATION].copy(),
            "x_dddot": jerk_snap[0:3].copy(), "x_ddddot": jerk_snap[3:6].copy(),
            "yaw": float(reference[REFERENCE_YAW]),
            "yaw_dot": float(reference[REFERENCE_YAW_RATE])}


def quaternion_from_rotorpy(q: FloatArray) -> FloatArray:
    """A rotorpy quaternion (i, j, k, w) as quadnav's (w, x, y, z)."""
    return np.array([q[3], q[0], q[1], q[2]])

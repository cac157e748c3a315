"""Rotor layout, the allocation matrix and the mixer that inverts it.

Rotors are numbered as PX4's quadrotor X: 1 front-right and 2 back-left spin
counter-clockwise seen from above, 3 front-left and 4 back-right clockwise (rows 0-3
here). Body frame x forward, y left, z up. The allocation matrix ``A`` (4, 4) maps
per-rotor thrusts ``f`` (N) to the wrench ``[T, tau_x, tau_y, tau_z] = A f``: collective
thrust N and body torques N m.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from quadnav.arrays import FloatArray
from quadnav.vehicle.params import VehicleParams

#: Rotor directions from the centre, as (x, y) unit multiples, rotors 1-4.
ROTOR_DIRECTIONS = np.array([[1.0, -1.0], [-1.0, 1.0], [1.0, 1.0], [-1.0, -1.0]]) / math.sqrt(2)
#: +1 for a rotor spinning counter-clockwise seen from above (it twists the body clockwise).
SPIN = np.array([1.0, 1.0, -1.0, -1.0])
#: Relative round-off allowed at the ends of the thrust range before a wrench counts as
#: out of reach.
_ROUNDING = 1e-12


def rotor_positions(params: VehicleParams) -> FloatArray:
    """(4, 3) rotor centres in the body frame, m."""
    xy = params.arm_length * ROTOR_DIRECTIONS
    return np.column_stack([xy, np.zeros(4)])


def allocation_matrix(params: VehicleParams) -> FloatArray:
    """``A`` (4, 4): per-rotor thrusts (N) to ``[T (N), tau_x, tau_y, tau_z (N m)]``."""
    positions = rotor_positions(params)
    return np.array([
        np.ones(4),
        positions[:, 1],
        -positions[:, 0],
        -SPIN * params.torque_per_thrust,
    ])


def roll_pitch_acceleration_max(params: VehicleParams) -> float:
    """The largest roll or pitch angular acceleration, rad/s^2, the rotors give while
    they hold the hover's collective thrust: each rotor's thrust moved from a quarter of
    the weight by as much as it can go both ways (to zero, or to full), on the side
    that turns the body, over the body's inertia about that axis (the smaller of the
    two). Roll and pitch moves of this kind make no yaw torque."""
    hover = params.weight / 4.0
    change = min(hover, params.max_rotor_thrust - hover)
    positions = rotor_positions(params)
    torques = change * np.abs(positions[:, [1, 0]]).sum(axis=0)  # about x, about y
    return float(np.min(torques / params.inertia[:2]))


@njit(cache=True)
def mix(wrench: np.ndarray, mixer: np.ndarray, max_thrust: float) -> tuple[np.ndarray, bool]:
    """Per-rotor thrusts (4,) N in ``[0, max_thrust]`` for a wrench ``[T, tau_x, tau_y,
    tau_z]`` (4,), and whether it had to be changed to fit.

    ``mixer`` is the inverse of the allocation matrix; a wrench the rotors can make is
    met exactly (to round-off). Otherwise, as PX4 without airmode, roll and pitch come first: their
    torques are scaled down if even the full thrust range cannot hold them, then the
    collective thrust is shifted to fit, and the yaw torque is scaled to what is left.
    """
    exact = np.empty(4)
    for i in range(4):  # mixer @ wrench, without a BLAS call for a 4 x 4 product
        exact[i] = (mixer[i, 0] * wrench[0] + mixer[i, 1] * wrench[1]
                    + mixer[i, 2] * wrench[2] + mixer[i, 3] * wrench[3])
    slack = _ROUNDING * max_thrust
    if exact.min() >= -slack and exact.max() <= max_thrust + slack:
        for i in range(4):
            exact[i] = min(max(exact[i], 0.0), max_thrust)
        return exact, False
    collective = mixer[:, 0] * wrench[0]
    roll_pitch = mixer[:, 1] * wrench[1] + mixer[:, 2] * wrench[2]
    yaw = mixer[:, 3] * wrench[3]
    changed = False
    spread = roll_pitch.max() - roll_pitch.min()
    if spread > max_thrust:
        roll_pitch *= max_thrust / spread
        changed = True
    thrusts = collective + roll_pitch
    low, high = thrusts.min(), thrusts.max()
    if low < 0.0:
        thrusts -= low
        changed = True
    elif high > max_thrust:
        thrusts -= high - max_thrust
        changed = True
    scale = 1.0
    for i in range(4):
        if yaw[i] > 0.0:
            scale = min(scale, (max_thrust - thrusts[i]) / yaw[i])
        elif yaw[i] < 0.0:
            scale = min(scale, -thrusts[i] / yaw[i])
    scale = max(scale, 0.0)
    if scale < 1.0:
        changed = True
    thrusts += scale * yaw
    return np.minimum(np.maximum(thrusts, 0.0), max_thrust), changed

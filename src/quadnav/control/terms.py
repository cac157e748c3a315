"""Terms both built-in controllers add, compiled with numba: the drag the vehicle meets at
the reference velocity (a force feed-forward) and the gyroscopic torque ``w x J w``."""

from __future__ import annotations

import numpy as np
from numba import njit

from quadnav.control.contract import REFERENCE_VELOCITY
from quadnav.vehicle.dynamics import RATES, VehicleArrays


@njit(cache=True, inline="always")
def reference_drag(r: np.ndarray, v: VehicleArrays, reference: np.ndarray) -> np.ndarray:
    """The drag (3,) N along the body axes at the reference velocity
    (``reference[REFERENCE_VELOCITY]``, m/s), for the body-to-world rotation ``r`` (3, 3)."""
    velocity = reference[REFERENCE_VELOCITY]
    drag = np.empty(3)
    for b in range(3):
        drag[b] = v.drag[b] * (r[0, b] * velocity[0] + r[1, b] * velocity[1]
                               + r[2, b] * velocity[2])
    return drag


@njit(cache=True, inline="always")
def add_gyroscopic(torque: np.ndarray, state: np.ndarray, v: VehicleArrays) -> None:
    """Add ``w x J w`` (N m) to ``torque`` (3,) in place, for the body rates of ``state``."""
    wx, wy, wz = state[RATES]
    jx, jy, jz = v.inertia[0] * wx, v.inertia[1] * wy, v.inertia[2] * wz
    torque[0] += wy * jz - wz * jy
    torque[1] += wz * jx - wx * jz
    torque[2] += wx * jy - wy * jx

"""Terms both built-in controllers add, compiled with numba: the drag the vehicle meets at
the reference velocity (a force feed-forward) and the gyroscopic torque ``w x J w``."""

from __future__ import annotations

import numpy as np
from numba import njit

from quadnav.vehicle.dynamics import VehicleArrays


@njit(cache=True, inline="always")
def reference_drag(r: np.ndarray, v: VehicleArrays, reference: np.ndarray) -> np.ndarray:
    """The drag (3,) N along the body axes at the reference velocity ``reference[3:6]``
    m/s, for the body-to-world rotation ``r`` (3, 3)."""
    drag = np.empty(3)
    for b in range(3):
        drag[b] = v.drag[b] * (r[0, b] * reference[3] + r[1, b] * reference[4]
                               + r[2, b] * reference[5])
    return drag


@njit(cache=True, inline="always")
def add_gyroscopic(torque: np.ndarray, state: np.ndarray, v: VehicleArrays) -> None:
    """Add ``w x J w`` (N m) to ``torque`` (3,) in place, for the body rates of ``state``."""
    wx, wy, wz = state[10], state[11], state[12]
    jx, jy, jz = v.inertia[0] * wx, v.inertia[1] * wy, v.inertia[2] * wz
    torque[0] += wy * jz - wz * jy
    torque[1] += wz * jx - wx * jz
    torque[2] += wx * jy - wy * jx

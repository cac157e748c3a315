"""Unit quaternions, scalar first ``(w, x, y, z)``, compiled with numba.

A quaternion ``q`` maps body-frame vectors to world-frame vectors: ``v_w = R(q) v_b``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True)
def multiply(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product ``a b`` of two (4,) quaternions."""
    return np.array((
        a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
        a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
        a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
        a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
    ))


@njit(cache=True)
def conjugate(q: np.ndarray) -> np.ndarray:
    """The inverse of a unit quaternion (4,)."""
    return np.array((q[0], -q[1], -q[2], -q[3]))


@njit(cache=True)
def to_matrix(q: np.ndarray) -> np.ndarray:
    """Rotation matrix (3, 3) of a unit quaternion (4,)."""
    w, x, y, z = q[0], q[1], q[2], q[3]
    return np.array((
        (1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)),
        (2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)),
        (2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)),
    ))


@njit(cache=True)
def from_matrix(r: np.ndarray) -> np.ndarray:
    """Unit quaternion (4,) with ``w >= 0`` of a rotation matrix (3, 3) (Shepperd's method)."""
    trace = r[0, 0] + r[1, 1] + r[2, 2]
    q = np.empty(4)
    if trace > max(r[0, 0], r[1, 1], r[2, 2]):
        s = 2.0 * math.sqrt(1.0 + trace)
        q[0] = 0.25 * s
        q[1] = (r[2, 1] - r[1, 2]) / s
        q[2] = (r[0, 2] - r[2, 0]) / s
        q[3] = (r[1, 0] - r[0, 1]) / s
    elif r[0, 0] >= r[1, 1] and r[0, 0] >= r[2, 2]:
        s = 2.0 * math.sqrt(1.0 + r[0, 0] - r[1, 1] - r[2, 2])
        q[0] = (r[2, 1] - r[1, 2]) / s
        q[1] = 0.25 * s
        q[2] = (r[0, 1] + r[1, 0]) / s
        q[3] = (r[0, 2] + r[2, 0]) / s
    elif r[1, 1] >= r[2, 2]:
        s = 2.0 * math.sqrt(1.0 + r[1, 1] - r[0, 0] - r[2, 2])
        q[0] = (r[0, 2] - r[2, 0]) / s
        q[1] = (r[0, 1] + r[1, 0]) / s
        q[2] = 0.25 * s
        q[3] = (r[1, 2] + r[2, 1]) / s
    else:
        s = 2.0 * math.sqrt(1.0 + r[2, 2] - r[0, 0] - r[1, 1])
        q[0] = (r[1, 0] - r[0, 1]) / s
        q[1] = (r[0, 2] + r[2, 0]) / s
        q[2] = (r[1, 2] + r[2, 1]) / s
        q[3] = 0.25 * s
    q *= math.copysign(1.0, q[0]) / math.sqrt(q[0] ** 2 + q[1] ** 2 + q[2] ** 2 + q[3] ** 2)
    return q


@njit(cache=True)
def from_yaw(yaw: float) -> np.ndarray:
    """The level attitude (4,) heading ``yaw`` rad (about world z)."""
    return np.array((math.cos(0.5 * yaw), 0.0, 0.0, math.sin(0.5 * yaw)))


@njit(cache=True)
def from_rotation_vector(v: np.ndarray) -> np.ndarray:
    """Unit quaternion (4,) turning by ``|v|`` rad about ``v`` (3,)."""
    angle = math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
    if angle < 1e-12:
        q = np.array((1.0, 0.5 * v[0], 0.5 * v[1], 0.5 * v[2]))
        return q / np.linalg.norm(q)
    s = math.sin(0.5 * angle) / angle
    return np.array((math.cos(0.5 * angle), s * v[0], s * v[1], s * v[2]))


def euler_angles(q: np.ndarray) -> np.ndarray:
    """Roll, pitch and yaw, rad (Z-Y-X: yaw about world z, then pitch, then roll), of
    unit quaternions (N, 4) -> (N, 3); pitch in [-pi/2, pi/2], roll and yaw in
    (-pi, pi]. Plain numpy, for figures of whole flights."""
    w, x, y, z = np.asarray(q, dtype=np.float64).T
    return np.column_stack([
        np.arctan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y)),
        np.arcsin(np.clip(2 * (w * y - z * x), -1.0, 1.0)),
        np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z)),
    ])

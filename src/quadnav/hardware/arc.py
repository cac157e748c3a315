"""The circular arc through three points, as the Tello SDK's ``curve`` flies it.

Shared by the emulator (which flies a ``curve`` along it) and the flight plan (which fits
``curve`` commands to a trajectory and checks every centimetre of each arc).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from quadnav.arrays import FloatArray


class Arc:
    """The circular arc from ``start`` through ``via`` to ``end`` (each (3,), in any one
    unit of length, not in a line); ``length`` and ``radius`` in that unit."""

    def __init__(self, start: ArrayLike, via: ArrayLike, end: ArrayLike) -> None:
        p0, p1, p2 = (np.asarray(p, dtype=np.float64) for p in (start, via, end))
        a, b = p1 - p0, p2 - p0
        normal = np.cross(a, b)
        self.centre = p0 + (a @ a * np.cross(b, normal) + b @ b * np.cross(normal, a)) / (
            2.0 * (normal @ normal))
        self.radius = float(np.linalg.norm(p0 - self.centre))
        self.normal = normal / np.linalg.norm(normal)
        self.e1 = (p0 - self.centre) / self.radius
        self.e2 = np.cross(self.normal, self.e1)
        self.length = self.radius * self.angle_of(p2)

    def angle_of(self, point: FloatArray) -> float:
        """Angle, rad in [0, 2 pi), of ``point`` (3,) on the circle from the start."""
        r = point - self.centre
        return float(np.arctan2(r @ self.e2, r @ self.e1) % (2 * math.pi))

    def at(self, s: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """At arc lengths ``s`` (K,): the points (K, 3) and their first and second
        derivatives with respect to ``s``."""
        theta = (s / self.radius)[:, None]
        c, d = np.cos(theta), np.sin(theta)
        radial = c * self.e1 + d * self.e2
        return (self.centre + self.radius * radial, -d * self.e1 + c * self.e2,
                -radial / self.radius)

    def distances(self, points: ArrayLike) -> FloatArray:
        """Distance of each point (K, 3) from the arc (the nearer end where the circle's
        nearest point is off the arc)."""
        p = np.asarray(points, dtype=np.float64).reshape(-1, 3) - self.centre
        height = p @ self.normal
        flat = p - height[:, None] * self.normal
        angle = np.arctan2(flat @ self.e2, flat @ self.e1) % (2 * math.pi)
        to_circle = np.hypot(np.linalg.norm(flat, axis=1) - self.radius, height)
        span = self.length / self.radius
        ends = np.vstack([self.centre + self.radius * self.e1,
                          self.at(np.array([self.length]))[0]])
        to_ends = np.linalg.norm((p + self.centre)[:, None, :] - ends[None], axis=2).min(axis=1)
        return np.where(angle <= span, to_circle, to_ends)

"""The map frame, the Tello's takeoff frame, and whole centimetres.

* **Map frame**: quadnav's world frame — metres, x and y horizontal, z up, the floor at
  z = :data:`GROUND_Z`.
* **Takeoff frame**: the Tello's body frame as it stood before takeoff, which is the
  frame of the SDK's relative ``go x y z`` moves — x forward, y left, z up. Its origin
  is the point on the floor where the drone was placed, under the map's start. The
  drone is placed facing map heading ``yaw`` (radians, counter-clockwise from +x seen
  from above; 0 = facing +x, pi/2 = facing +y), so a takeoff-frame vector is the map
  vector turned by ``-yaw`` about z.

The SDK takes distances in whole centimetres; :func:`to_cm` rounds to the nearest.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from quadnav.arrays import FloatArray

IntArray = NDArray[np.int64]

#: Height of the floor the drone takes off from and lands on, map frame, metres.
GROUND_Z = 0.0


def _turn(vectors: ArrayLike, angle: float) -> FloatArray:
    """Vectors (..., 3) turned by ``angle`` rad about z (counter-clockwise from above)."""
    v = np.asarray(vectors, dtype=np.float64)
    c, s = np.cos(angle), np.sin(angle)
    x, y = v[..., 0], v[..., 1]
    return np.stack([c * x - s * y, s * x + c * y, v[..., 2]], axis=-1)


def map_to_body(vectors: ArrayLike, yaw: float) -> FloatArray:
    """Map-frame vectors (..., 3) in the takeoff frame of a drone facing ``yaw`` rad."""
    return _turn(vectors, -yaw)


def body_to_map(vectors: ArrayLike, yaw: float) -> FloatArray:
    """Takeoff-frame vectors (..., 3) of a drone facing ``yaw`` rad in the map frame."""
    return _turn(vectors, yaw)


def to_cm(metres: ArrayLike) -> IntArray:
    """Lengths in metres (any shape) as whole centimetres, rounded to the nearest."""
    return np.rint(100.0 * np.asarray(metres, dtype=np.float64)).astype(np.int64)


def to_m(centimetres: ArrayLike) -> FloatArray:
    """Lengths in centimetres (any shape) in metres."""
    return np.asarray(centimetres, dtype=np.float64) / 100.0


@dataclass(frozen=True)
class TakeoffFrame:
    """Where the drone stood before takeoff and which way it faced.

    Attributes:
        origin: (3,) map-frame point on the floor under the start, metres.
        yaw: map heading the drone faces, rad.
    """

    origin: tuple[float, float, float]
    yaw: float

    @classmethod
    def under(cls, start: ArrayLike, yaw: float) -> TakeoffFrame:
        """The frame of a drone placed on the floor under ``start`` (3,) facing ``yaw``."""
        x, y, _ = np.asarray(start, dtype=np.float64)
        return cls((float(x), float(y), GROUND_Z), float(yaw))

    def to_body(self, points: ArrayLike) -> FloatArray:
        """Map points (..., 3), m, in the takeoff frame, m."""
        return map_to_body(np.asarray(points, dtype=np.float64) - self.origin, self.yaw)

    def to_map(self, points: ArrayLike) -> FloatArray:
        """Takeoff-frame points (..., 3), m, in the map frame, m."""
        return body_to_map(points, self.yaw) + np.asarray(self.origin)

    def to_body_cm(self, points: ArrayLike) -> IntArray:
        """Map points (..., 3), m, as takeoff-frame points in whole centimetres."""
        return to_cm(self.to_body(points))

    def cm_to_map(self, points: ArrayLike) -> FloatArray:
        """Takeoff-frame points (..., 3) in centimetres as map points, m."""
        return self.to_map(to_m(points))

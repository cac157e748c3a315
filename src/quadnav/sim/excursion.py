"""How far and for how long a flight's body leaves the map: :func:`body_excursion`.

The body is a box of half extents ``half`` (3,) centred on the centre of mass and turned
with the vehicle: along world axis ``i`` it reaches ``sum_j |R_ij| half_j`` from the centre
(``R`` the attitude's rotation). Between two recorded samples the centre is taken to move
straight, as the track's margin is measured
(:func:`~quadnav.world.margins.segment_box_margins`), and the body to reach the larger of
its reaches at the two samples: each such piece is measured by the bounding box of the
centre's segment grown by that reach, against each face of the boundary. The depth is how
far that box sticks out past the farthest face; the time is that of the pieces whose box
sticks out.

A flight may start with its body outside (a start on the boundary, which the path leaves
by the shortest move that brings the body inside with room,
:func:`~quadnav.planning.legs.body_inside`): until the first sample at which the body is
wholly inside, the vehicle is still leaving its start, and that is not counted — but only
while its centre stays within that move's length of where it started: a vehicle that
moves farther with its body still outside (along the wall, say) is counted from there.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from quadnav.arrays import FloatArray
from quadnav.planning.legs import body_reach
from quadnav.vehicle import quaternion
from quadnav.world.margins import rounded


@dataclass(frozen=True)
class Excursion:
    """Where a flight's body left the map after its start.

    Attributes:
        depth: how far past the boundary the body went, m (0 when it stayed inside).
        duration: how long it was outside, s: the pieces between recorded samples in which
            it was.
        since: when it first left, s from the start of the flight (None when it never did).
    """

    depth: float = 0.0
    duration: float = 0.0
    since: float | None = None

    def __bool__(self) -> bool:
        """Whether the body left the map."""
        return self.depth > 0.0


@njit(cache=True)
def body_reaches(attitudes: np.ndarray, half: np.ndarray) -> np.ndarray:
    """How far (N, 3), m, the body box of half extents ``half`` (3,) reaches from its
    centre along each world axis at each attitude (N, 4) (unit quaternions ``w, x, y, z``)."""
    out = np.empty((attitudes.shape[0], 3))
    for k in range(attitudes.shape[0]):
        r = quaternion.to_matrix(attitudes[k])
        for i in range(3):
            out[k, i] = (abs(r[i, 0]) * half[0] + abs(r[i, 1]) * half[1]
                         + abs(r[i, 2]) * half[2])
    return out


def body_excursion(t: FloatArray, positions: FloatArray, attitudes: FloatArray,
                   half: FloatArray, boundary: FloatArray) -> Excursion:
    """How far and how long the body box of half extents ``half`` (3,) m went outside
    ``boundary`` (6,) ``xmin, ymin, zmin, xmax, ymax, zmax`` over a flight recorded at
    times ``t`` (N,) s, positions (N, 3) m and attitudes (N, 4), after it left its start
    (see the module docstring). Depths are rounded to the nanometre
    (:func:`~quadnav.world.margins.rounded`): a body flown exactly onto a face is inside."""
    reach = body_reaches(np.ascontiguousarray(attitudes, dtype=np.float64),
                         np.asarray(half, dtype=np.float64))
    lower, upper = boundary[:3], boundary[3:]
    first = _start_stretch(positions, reach, half, lower, upper)
    p, r = positions[first:], reach[first:]
    if len(p) < 2:
        return Excursion()
    grown = np.maximum(r[:-1], r[1:])
    low = np.minimum(p[:-1], p[1:]) - grown
    high = np.maximum(p[:-1], p[1:]) + grown
    depths = np.round(np.maximum(lower - low, high - upper).max(axis=1), 9)
    out = np.flatnonzero(depths > 0.0)
    if out.size == 0:
        return Excursion()
    times = t[first:]
    return Excursion(depth=rounded(depths[out].max()),
                     duration=float(np.sum(times[out + 1] - times[out])),
                     since=float(times[out[0]]))


def _start_stretch(positions: FloatArray, reach: FloatArray, half: FloatArray,
                   lower: FloatArray, upper: FloatArray) -> int:
    """The first sample counted (see the module docstring): the first at which the body
    reaching ``reach`` (N, 3) m from the centres ``positions`` (N, 3) m lies within
    ``lower`` (3,) ... ``upper`` (3,), or at which the centre is farther from where it
    started than the start's move inside (for a level body of half extents ``half``)."""
    outside = np.maximum(lower - (positions - reach), positions + reach - upper).max(axis=1)
    start = positions[0]
    room = body_reach(half)
    move = float(np.linalg.norm(np.clip(start, lower + room, upper - room) - start))
    away = np.linalg.norm(positions - start, axis=1) > move + 1e-9
    ends = np.flatnonzero((np.round(outside, 9) <= 0.0) | away)
    return int(ends[0]) if ends.size else len(positions)

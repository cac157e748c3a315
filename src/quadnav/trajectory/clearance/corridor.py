"""Safe corridors: one obstacle-free axis-aligned box around each segment of a path.

A trajectory piece that stays inside its segment's box is collision-free, so a
minimum-snap QP can keep each piece in its box with linear constraints. Boxes are rows
``(xmin, ymin, zmin, xmax, ymax, zmax)`` in metres, closed, and each is disjoint from
every (closed) inflated block and strictly inside the (open) free boundary.

How a box is made (:func:`safe_corridors`):

1. **Seed.** The segment's bounding box. Where it meets an inflated block (a diagonal
   segment passing a block's edge or corner) the segment is split, adding a waypoint,
   and the pieces are retried, for up to ``max_splits`` levels. The split point is
   exact rather than the midpoint: along the segment, each face of the first block met
   is passed either for a prefix ``[0, a)`` of the segment (it starts beyond the face and
   crosses it) or for a suffix ``(b, 1]``; a free segment is beyond some face at every
   point, so the longest prefix and longest suffix overlap (``b < a``), and splitting at
   ``(a + b) / 2`` leaves each piece wholly beyond one face of that block. One split per
   block passed suffices, whereas halving needs about ``log2(length / clearance)``
   levels (13 for a 7 m segment passing a corner 1.5 mm off, as shortcut planner paths
   do) and leaves millimetre pieces behind.
2. **Growth.** In :data:`GROWTH_ROUNDS` rounds, each face in the order x-, x+, y-, y+,
   z-, z+ moves outward by up to ``max_growth / GROWTH_ROUNDS`` metres, stopping
   :data:`CLEARANCE` short of the nearest block face ahead of it (a block overlapping
   the box's closed extent on the other two axes) or of the boundary; a face already
   closer than that stays put. Each face thus moves at most ``max_growth`` in total, and
   growing in small steps lets all faces share the free space instead of the first face
   taking it all. The result is deterministic.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from quadnav.arrays import FloatArray
from quadnav.errors import QuadnavError
from quadnav.trajectory.clearance.collision import (
    checked_waypoints,
    insert_points,
    require_free_polyline,
)
from quadnav.world.model import World
from quadnav.world.placement import format_point

#: Gap, metres, that growth leaves between a box face and a block face or the boundary.
CLEARANCE = 1e-6
#: Rounds of face-by-face growth; each moves a face by at most ``max_growth / rounds``.
GROWTH_ROUNDS = 8


def safe_corridors(free_world: World, waypoints: ArrayLike, *, max_growth: float = 1.0,
                   max_splits: int = 8) -> tuple[FloatArray, FloatArray]:
    """Obstacle-free boxes around the segments of a path (see the module docstring).

    Args:
        free_world: the map already inflated by the safety margin.
        waypoints: (N, 3) path, metres, N >= 2; every segment must be free in
            ``free_world``.
        max_growth: how far each box face may move out from the bounding box, metres.
        max_splits: levels of splitting allowed to get free bounding boxes.

    Returns:
        ``(waypoints, boxes)``: the path (M, 3), M >= N, with the split points added
        (the original points in order among them), and one box (M - 1, 6) per segment
        containing it.

    Raises:
        QuadnavError: bad waypoints or options, a segment that is not free, or one whose
            pieces still meet a block after ``max_splits`` levels of splitting.
    """
    points = checked_waypoints(waypoints)
    if not (math.isfinite(max_growth) and max_growth >= 0):
        raise QuadnavError(f"corridor growth must be a finite number >= 0 m, got {max_growth}")
    if max_splits < 0:
        raise QuadnavError(f"corridor splits must be >= 0, got {max_splits}")
    require_free_polyline(free_world, points)
    points, boxes = _split_until_free(free_world.blocks, points, max_splits)
    return points, _grow(boxes, free_world, max_growth)


def _overlapping(boxes: FloatArray, blocks: FloatArray) -> np.ndarray:
    """Whether each closed box (S, 6) meets each closed block (B, 6) -> bool (S, B)."""
    meets = np.ones((len(boxes), len(blocks)), dtype=bool)
    for axis in range(3):
        meets &= boxes[:, None, axis] <= blocks[None, :, axis + 3]
        meets &= blocks[None, :, axis] <= boxes[:, None, axis + 3]
    return meets


def _bounding_boxes(points: FloatArray) -> FloatArray:
    """Bounding boxes (N - 1, 6) of the segments of the path ``points`` (N, 3)."""
    return np.concatenate([np.minimum(points[:-1], points[1:]),
                           np.maximum(points[:-1], points[1:])], axis=1)


def _split_until_free(blocks: FloatArray, start: FloatArray, max_splits: int
                      ) -> tuple[FloatArray, FloatArray]:
    """The path ``start`` (N, 3) with segments split until every bounding box misses
    ``blocks`` (B, 6) -> the path (M, 3) and its segments' bounding boxes (M - 1, 6)."""
    points = start
    origin = np.arange(len(points) - 1)  # the input segment each piece comes from
    pending = np.ones(len(origin), dtype=bool)  # pieces not yet checked
    level = 0
    while True:
        boxes = _bounding_boxes(points)
        overlap = _overlapping(boxes[pending], blocks)
        hit = np.zeros(len(boxes), dtype=bool)
        hit[pending] = overlap.any(axis=1)
        if not hit.any():
            return points, boxes
        if level == max_splits:
            bad = int(origin[np.argmax(hit)])
            raise QuadnavError(
                f"no safe corridor for waypoint segment {bad} from {format_point(start[bad])} "
                f"to {format_point(start[bad + 1])}: after {max_splits} levels of splitting "
                "its pieces still touch an inflated block")
        rows = np.flatnonzero(hit)
        first_block = np.argmax(overlap[hit[pending]], axis=1)
        fractions = _split_fractions(points[rows], points[rows + 1], blocks[first_block])
        points = insert_points(points, rows, fractions)
        origin = np.repeat(origin, 1 + hit)
        pending = np.repeat(hit, 1 + hit)
        level += 1


def _split_fractions(starts: FloatArray, ends: FloatArray, blocks: FloatArray) -> FloatArray:
    """Where to split each free segment ``starts -> ends`` (S, 3) so that both pieces'
    bounding boxes miss its block ``blocks`` (S, 6): fractions (S,) along it, in (0, 1)
    (see the module docstring; clipped to [0, 1] against rounding, so that a split point
    always lies on its segment)."""
    step = ends - starts
    moving = step != 0
    # Fraction of the way at which each coordinate reaches each face of the block.
    at_lower = np.divide(blocks[:, :3] - starts, step, out=np.zeros_like(step), where=moving)
    at_upper = np.divide(blocks[:, 3:] - starts, step, out=np.zeros_like(step), where=moving)
    # Beyond a face before reaching it (a prefix) or after leaving it (a suffix).
    prefix = np.where(step > 0, at_lower, np.where(step < 0, at_upper, -np.inf))
    suffix = np.where(step > 0, at_upper, np.where(step < 0, at_lower, np.inf))
    return np.clip(0.5 * (prefix.max(axis=1) + suffix.min(axis=1)), 0.0, 1.0)


def _grow(boxes: FloatArray, free_world: World, max_growth: float) -> FloatArray:
    """``boxes`` (S, 6), each free of blocks, grown face by face (module docstring)."""
    boxes = boxes.copy()
    # Only blocks within reach of a box's largest growth can stop one of its faces (the
    # extra clearance covers rounding in the sum of the steps).
    reach = boxes + np.repeat([-1.0, 1.0], 3) * (max_growth + CLEARANCE)
    pair_box, pair_block = np.nonzero(_overlapping(reach, free_world.blocks))
    near = free_world.blocks[pair_block]
    step = max_growth / GROWTH_ROUNDS
    for _ in range(GROWTH_ROUNDS):
        for column in range(6):
            _grow_face(boxes, column, near, pair_box, free_world.boundary[column], step)
    return boxes


def _grow_face(boxes: FloatArray, column: int, near: FloatArray, pair_box: np.ndarray,
               bound: float, step: float) -> None:
    """Move face ``column`` (0-2: lower x, y, z; 3-5: upper) of every box outward by up
    to ``step`` metres, in place, stopping :data:`CLEARANCE` short of the blocks ``near``
    (P, 6) paired with boxes ``pair_box`` (P,) and of the boundary coordinate ``bound``."""
    axis, upper = column % 3, column >= 3
    sign = 1.0 if upper else -1.0
    face = boxes[:, column]
    room = np.minimum(step, sign * (bound - face) - CLEARANCE)
    other = [a for a in range(3) if a != axis]
    owner = boxes[pair_box]
    beside = np.all((near[:, other] <= owner[:, [a + 3 for a in other]])
                    & (owner[:, other] <= near[:, [a + 3 for a in other]]), axis=1)
    # The block face that the moving face approaches, as a distance ahead of it.
    ahead = sign * (near[:, axis if upper else axis + 3] - face[pair_box])
    stops = beside & (ahead > 0)
    np.minimum.at(room, pair_box[stops], ahead[stops] - CLEARANCE)
    boxes[:, column] = face + sign * np.maximum(room, 0.0)

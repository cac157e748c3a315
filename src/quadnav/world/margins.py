"""The margin a point or a box keeps: per-axis clearance, as inflation defines it.

:meth:`World.inflate(m) <quadnav.world.model.World.inflate>` grows every block by ``m``
along each axis and shrinks the boundary by ``m``. So a point is free in the inflated
world exactly when, for every block, it lies more than ``m`` outside the block along at
least one axis, and it lies more than ``m`` inside every boundary face. The largest such
``m`` is the point's *margin*: its Chebyshev (L-infinity) distance to the nearest block,
or its distance to the nearest boundary face, whichever is smaller.

For a closed box the same holds with the box's nearest faces: the box is free in the
world inflated by ``m`` exactly when ``m`` is below the box's margin. A curve enclosed in
a box therefore keeps at least the box's margin, which makes this an exact (if slightly
conservative) check of curves, not only of sample points.

Margins are signed: negative inside a block (minus the smallest push along one axis that
gets out) or outside the boundary.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange
from numpy.typing import ArrayLike

from quadnav.arrays import FloatArray
from quadnav.world.model import World


@njit(cache=True, parallel=True)
def _box_margins(boxes, blocks, boundary, use_boundary):
    """Margin (K,) of each box (K, 6) against blocks (N, 6) and, if ``use_boundary``,
    the boundary (6,)."""
    k_count = boxes.shape[0]
    out = np.empty(k_count, dtype=np.float64)
    for k in prange(k_count):
        best = np.inf
        if use_boundary:
            for a in range(3):
                best = min(best, boxes[k, a] - boundary[a], boundary[a + 3] - boxes[k, a + 3])
        for i in range(blocks.shape[0]):
            gap = -np.inf
            for a in range(3):
                gap = max(gap, blocks[i, a] - boxes[k, a + 3], boxes[k, a] - blocks[i, a + 3])
            best = min(best, gap)
        out[k] = best
    return out


def rounded(margin: float) -> float:
    """``margin`` m to the nanometre, -0 as 0: a margin computed from coordinates carries
    rounding errors of about 1e-16 m, which mean nothing."""
    return round(float(margin), 9) + 0.0


def box_margins(world: World, boxes: ArrayLike, boundary: bool = True) -> FloatArray:
    """The margin (K,), metres, that each closed box (K, 6) ``xmin, ymin, zmin, xmax, ymax,
    zmax`` keeps from the blocks of ``world`` and, with ``boundary``, its boundary faces
    (see the module docstring; ``inf`` for no block and no boundary)."""
    b = np.ascontiguousarray(boxes, dtype=np.float64).reshape(-1, 6)
    return _box_margins(b, np.ascontiguousarray(world.blocks), world.boundary, boundary)


def point_margins(world: World, points: ArrayLike, boundary: bool = True) -> FloatArray:
    """The margin (N,), metres, of each point (N, 3) (see :func:`box_margins`)."""
    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    return box_margins(world, np.concatenate([p, p], axis=1), boundary)


def segment_box_margins(world: World, points: ArrayLike, boundary: bool = True
                        ) -> FloatArray:
    """The margin (N - 1,), metres, of the bounding box of each straight segment between
    consecutive ``points`` (N, 3), N >= 2: a lower bound on the segment's own margin (see
    :func:`box_margins`)."""
    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    return box_margins(world, np.concatenate([np.minimum(p[:-1], p[1:]),
                                              np.maximum(p[:-1], p[1:])], axis=1), boundary)


def polyline_margin(world: World, points: ArrayLike, boundary: bool = True) -> float:
    """The smallest margin, metres, along the straight segments through ``points`` (N, 3),
    N >= 1: each segment is measured exactly, to 1e-9 m.

    A segment keeps margin ``m`` exactly when it is free in the world inflated by ``m``;
    the margin is found by bisection on that exact test, between the bound the segments'
    bounding boxes give and the margin of the vertices. A polyline that touches a block
    (or, with ``boundary``, leaves the boundary) gets the bounding-box bound, at most 0.
    """
    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    vertices = float(point_margins(world, p, boundary).min())
    if len(p) == 1:
        return vertices
    segments = np.stack([p[:-1], p[1:]], axis=1)
    low = float(segment_box_margins(world, p, boundary).min())
    if low >= vertices:
        return vertices
    if not boundary:
        world = world.replace(boundary=np.concatenate([p.min(axis=0) - 2 * vertices - 1.0,
                                                       p.max(axis=0) + 2 * vertices + 1.0]))
    if not world.segments_free(segments).all():
        return min(low, 0.0)
    low, high = max(low, 0.0), vertices
    while high - low > 1e-9:
        middle = 0.5 * (low + high)
        if world.inflate(middle).segments_free(segments).all():
            low = middle
        else:
            high = middle
    return low

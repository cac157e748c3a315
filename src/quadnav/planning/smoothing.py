"""Round the corners of a collision-free polyline by gradient descent (Thrun's smoother).

The path is first made dense (a sparse polyline has too few points to bend), then each
interior point ``y_i`` is pulled towards its original position ``x_i`` and towards the
middle of its neighbours, sweep after sweep::

    y_i += weight_data * (x_i - y_i) + weight_smooth * (y_{i-1} + y_{i+1} - 2 y_i)

A point whose move would make one of its segments collide is put back and frozen, so
the path stays free under the exact check. Last, vertices that add nothing (within
a small distance of the chord that replaces them, the chord being free) are dropped.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from quadnav.arrays import FloatArray
from quadnav.config import require
from quadnav.planning.refine_kernel import simplified, smoothing_sweeps
from quadnav.planning.result import IntArray, path_length
from quadnav.planning.shortcut import free_polyline, polyline_segments
from quadnav.profiling import staged
from quadnav.world.model import World

#: Default ``max_spacing``: the path length divided by this many pieces.
DEFAULT_PIECES = 100
#: After smoothing, a vertex within this fraction of the spacing of the chord replacing
#: it is dropped (when the chord is free): the rounded corners keep their shape to well
#: under the spacing while the straight runs lose their densifying points.
KEEP_DEVIATION_FRACTION = 0.02


@staged("smoothing")
def smooth_path(world: World, path: ArrayLike, weight_data: float = 0.5,
                weight_smooth: float = 0.3, tolerance: float = 1e-6,
                max_spacing: float | None = None, max_sweeps: int = 1000) -> FloatArray:
    """A smoothed copy of a free polyline, with the same endpoints, every segment free.

    Each sweep updates the odd-indexed interior points at once, then the even-indexed
    ones (red-black order: like Thrun's in-order loop, each point sees its neighbours'
    newest positions, and the sweeps converge to the same path). The iteration is
    successive over-relaxation of ``(weight_data I + weight_smooth L) y = weight_data x``
    (``L`` the second-difference matrix) with factor ``weight_data + 2 weight_smooth``,
    hence the bounds on the weights.

    Args:
        world: the world whose free space the path must stay in (for planners, the
            inflated world).
        path: (N, 3) polyline, metres, every segment free in ``world``.
        weight_data: pull towards the original points, in [0, 1].
        weight_smooth: pull towards the neighbours' midpoint, > 0, with
            ``weight_data + 2 * weight_smooth < 2``.
        tolerance: stop when the sum over all points of the distance each moved in one
            sweep is below this, metres (> 0).
        max_spacing: densify so that consecutive points are at most this far apart,
            metres (> 0); ``None``: the path length / :data:`DEFAULT_PIECES`. Segments
            whose pieces would not pass the exact check (rounding at a tangency) are
            left whole.
        max_sweeps: stop after this many sweeps even if not converged (>= 1).

    Returns:
        (M, 3) polyline, metres, from exactly ``path[0]`` to exactly ``path[-1]``; points
        within :data:`KEEP_DEVIATION_FRACTION` of the spacing of a free chord dropped.
    """
    _check_arguments(weight_data, weight_smooth, tolerance, max_spacing, max_sweeps)
    points = free_polyline(world, path)
    length = path_length(points)
    if len(points) < 3 or length == 0.0:
        return points
    spacing = max_spacing if max_spacing is not None else length / DEFAULT_PIECES
    original = _densify(world, points, spacing)
    smoothed = smoothing_sweeps(original, world.block_grid, weight_data, weight_smooth,
                                tolerance, max_sweeps)
    return simplify_path(world, smoothed, KEEP_DEVIATION_FRACTION * spacing)


def simplify_path(world: World, path: FloatArray, deviation: float) -> FloatArray:
    """Drop vertices of a free polyline (N, 3) that lie within ``deviation`` metres of
    the straight segment replacing them, where that segment is free in ``world``.

    Ramer-Douglas-Peucker with a collision check: a run of vertices is replaced by its
    chord when every vertex in it lies within ``deviation`` of the chord and the chord
    is free; otherwise the run is split at its farthest vertex. Endpoints are kept.
    """
    if len(path) < 3:
        return path
    return path[simplified(path, world.block_grid, deviation)]


def _check_arguments(weight_data: float, weight_smooth: float, tolerance: float,
                     max_spacing: float | None, max_sweeps: int) -> None:
    """QuadnavError naming the first argument of :func:`smooth_path` out of range."""
    checks = [
        (0 <= weight_data <= 1, f"weight_data must be in [0, 1], got {weight_data}"),
        (weight_smooth > 0 and math.isfinite(weight_smooth),
         f"weight_smooth must be a number > 0, got {weight_smooth}"),
        (weight_data + 2 * weight_smooth < 2,
         f"weight_data + 2 * weight_smooth must be below 2 for the sweeps to converge, got "
         f"{weight_data} + 2 * {weight_smooth} = {weight_data + 2 * weight_smooth}"),
        (tolerance > 0 and math.isfinite(tolerance),
         f"tolerance must be a positive number of metres, got {tolerance}"),
        (max_spacing is None or (max_spacing > 0 and math.isfinite(max_spacing)),
         f"max_spacing must be a positive number of metres, got {max_spacing}"),
        (max_sweeps >= 1, f"max_sweeps must be >= 1, got {max_sweeps}"),
    ]
    require(checks)


def _densify(world: World, points: FloatArray, spacing: float) -> FloatArray:
    """The polyline (N, 3) with each segment cut into equal pieces at most ``spacing``
    metres long; a segment whose pieces do not all pass the exact check stays whole."""
    lengths = np.linalg.norm(np.diff(points, axis=0), axis=1)
    pieces = np.maximum(1, np.ceil(lengths / spacing)).astype(np.int64)
    dense, segment = _cut(points, pieces)
    blocked = np.unique(segment[~world.segments_free(polyline_segments(dense))])
    if blocked.size:
        pieces[blocked] = 1
        dense, _ = _cut(points, pieces)
    return dense


def _cut(points: FloatArray, pieces: IntArray) -> tuple[FloatArray, IntArray]:
    """(points (sum(pieces) + 1, 3), segment (sum(pieces),)): segment k of the polyline
    (N, 3) cut into ``pieces[k]`` equal pieces; ``segment`` says which segment each
    piece came from. Original vertices are kept exactly."""
    segment = np.repeat(np.arange(len(pieces)), pieces)
    first = np.repeat(np.cumsum(pieces) - pieces, pieces)
    t = (np.arange(len(segment)) - first) / pieces[segment]
    cut = points[segment] + t[:, None] * (points[segment + 1] - points[segment])
    return np.concatenate([cut, points[-1:]]), segment

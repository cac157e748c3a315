"""Shorten a collision-free polyline: greedy line of sight, then random shortcuts.

:func:`shortcut_path` never introduces a collision (every output segment passes the
exact :meth:`~quadnav.world.model.World.segments_free` check), keeps both endpoints
exactly and never makes the path longer. Its loops are compiled
(:mod:`quadnav.planning.refine_kernel`). :func:`free_polyline` and
:func:`polyline_segments` are the input check and the segment view it shares with
:mod:`quadnav.planning.smoothing`.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from quadnav.arrays import FloatArray
from quadnav.errors import QuadnavError
from quadnav.planning.refine_kernel import line_of_sight, random_shortcuts
from quadnav.planning.result import path_length
from quadnav.profiling import staged
from quadnav.world.model import World
from quadnav.world.placement import format_point

#: Default number of random shortcut attempts per vertex left by the greedy pass.
ATTEMPTS_PER_VERTEX = 100
#: Fewest random shortcut attempts made by default.
MIN_ATTEMPTS = 200
#: A random shortcut joins two points at most this fraction of the path length apart,
#: measured along the path (OMPL's ``rangeRatio``, 0.33 there). Once the greedy pass has
#: run, long shortcuts rarely pass and the gains come from cutting corners, which short
#: ones do: on the ``maze`` world 0.1 gives a 2-3 % shorter path than 0.33 for the same
#: attempts.
RANGE_RATIO = 0.1
#: A random point this close to a vertex, as a fraction of the path length, is moved
#: onto it (OMPL's ``snapToVertex``), so cutting a corner does not leave a tiny segment.
SNAP_FRACTION = 0.005
#: Length a shortcut must save to be taken, relative to the path length.
RELATIVE_EPSILON = 1e-9


def free_polyline(world: World, path: ArrayLike) -> FloatArray:
    """``path`` as a float64 (N, 3) copy, checked: QuadnavError unless every segment is
    free in ``world`` (N >= 1; a single point must itself be free)."""
    points = np.array(path, dtype=np.float64)
    if points.ndim != 2 or points.shape[1] != 3 or len(points) == 0:
        raise QuadnavError(f"path must be an (N, 3) array with N >= 1, got shape {points.shape}")
    if not np.all(np.isfinite(points)):
        raise QuadnavError("path must hold finite coordinates")
    if len(points) == 1:
        if not world.is_free(points[0]):
            raise QuadnavError(f"path: point {format_point(points[0])} is not free")
        return points
    blocked = np.flatnonzero(~world.segments_free(polyline_segments(points)))
    if blocked.size:
        i = int(blocked[0])
        raise QuadnavError(
            f"path: segment {i} {format_point(points[i])} -> {format_point(points[i + 1])} is "
            f"not free ({blocked.size} of {len(points) - 1} segments collide); post-processing "
            "needs a collision-free path")
    return points


@staged("shortcut")
def shortcut_path(world: World, path: ArrayLike, seed: int = 0,
                  attempts: int | None = None) -> FloatArray:
    """A path no longer than ``path`` with the same endpoints, every segment free.

    First a greedy line-of-sight pass: from the first vertex, jump to the farthest later
    vertex joined to it by a free straight segment, and repeat from there. Then random
    shortcuts, as OMPL's ``PathSimplifier::shortcutPath``: draw two points anywhere along
    the path (at most :data:`RANGE_RATIO` of its length apart, snapped to a vertex within
    :data:`SNAP_FRACTION` of it); when the straight segment between them is free and
    shorter than the path between them, splice it in. Last, the greedy pass again: it
    drops the vertices that splicing left on a straight line or repeated, and joins
    vertices that see each other past the corners the splices cut (as OMPL's
    ``simplify`` alternates vertex reduction and shortcuts).

    Args:
        world: the world whose free space the path must stay in (for planners, the
            inflated world).
        path: (N, 3) polyline, metres, every segment free in ``world``.
        seed: seed of the random shortcuts; the same seed gives the same path.
        attempts: random shortcuts tried; ``None``: :data:`ATTEMPTS_PER_VERTEX` times the
            vertices left by the greedy pass, at least :data:`MIN_ATTEMPTS`.

    Returns:
        (M, 3) polyline, metres, M <= N, from exactly ``path[0]`` to exactly ``path[-1]``.
    """
    points = free_polyline(world, path)
    if attempts is not None and attempts < 0:
        raise QuadnavError(f"shortcut attempts must be >= 0, got {attempts}")
    if len(points) < 3:
        return points
    grid = world.block_grid
    shorter = line_of_sight(points, grid)
    if attempts is None:
        attempts = max(MIN_ATTEMPTS, ATTEMPTS_PER_VERTEX * len(shorter))
    uniforms = np.random.default_rng(seed).random(2 * attempts)
    shorter = random_shortcuts(shorter, grid, uniforms, RANGE_RATIO, SNAP_FRACTION,
                               RELATIVE_EPSILON)
    shorter = line_of_sight(shorter, grid)
    # Each step is shorter in exact arithmetic; rounding in the sums must not undo that.
    return shorter if path_length(shorter) <= path_length(points) else points


def polyline_segments(points: FloatArray) -> FloatArray:
    """The (N - 1, 2, 3) segments of a polyline (N, 3)."""
    return np.stack([points[:-1], points[1:]], axis=1)

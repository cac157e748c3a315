"""Shorten a collision-free polyline: greedy line of sight, then random shortcuts.

:func:`shortcut_path` never introduces a collision (every output segment passes the
exact :meth:`~quadnav.world.model.World.segments_free` check), keeps both endpoints
exactly and never makes the path longer. :func:`free_polyline` and
:func:`polyline_segments` are the input check and the segment view it shares with
:mod:`quadnav.planning.smoothing`.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from quadnav.arrays import FloatArray
from quadnav.errors import QuadnavError
from quadnav.planning.result import distinct, path_length
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
    shorter = _line_of_sight(world, points)
    if attempts is None:
        attempts = max(MIN_ATTEMPTS, ATTEMPTS_PER_VERTEX * len(shorter))
    shorter = _random_shortcuts(world, shorter, np.random.default_rng(seed), attempts)
    shorter = _line_of_sight(world, shorter)
    # Each step is shorter in exact arithmetic; rounding in the sums must not undo that.
    return shorter if path_length(shorter) <= path_length(points) else points


def polyline_segments(points: FloatArray) -> FloatArray:
    """The (N - 1, 2, 3) segments of a polyline (N, 3)."""
    return np.stack([points[:-1], points[1:]], axis=1)


def _line_of_sight(world: World, points: FloatArray) -> FloatArray:
    """Greedy pass: from each kept vertex, the farthest later vertex it sees is kept next.

    The candidates of one vertex are tested in one batch; the next vertex always sees
    its neighbour, since the input's segments are free.
    """
    kept = [0]
    last = len(points) - 1
    while kept[-1] < last - 1:
        here = kept[-1]
        later = np.arange(here + 2, last + 1)
        pairs = np.stack([np.broadcast_to(points[here], (len(later), 3)), points[later]],
                         axis=1)
        visible = later[world.segments_free(pairs)]
        kept.append(int(visible[-1]) if visible.size else here + 1)
    if kept[-1] != last:
        kept.append(last)
    return points[kept]


def _random_shortcuts(world: World, points: FloatArray, rng: np.random.Generator,
                      attempts: int) -> FloatArray:
    """Try ``attempts`` random shortcuts between points along the polyline (N, 3)."""
    for _ in range(attempts):
        arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(points, axis=0),
                                                              axis=1))])
        total = arc[-1]
        s0 = rng.uniform(0.0, total)
        s1 = rng.uniform(max(0.0, s0 - RANGE_RATIO * total),
                         min(total, s0 + RANGE_RATIO * total))
        s0, s1 = min(s0, s1), max(s0, s1)
        i0, s0, p0 = _point_at(points, arc, s0)
        i1, s1, p1 = _point_at(points, arc, s1)
        # The path between p0 (on segment i0) and p1 (on segment i1) turns only at the
        # vertices i0 + 1 .. i1; on one segment there is nothing to cut.
        if i0 >= i1:
            continue
        saved = (s1 - s0) - float(np.linalg.norm(p1 - p0))
        if saved <= RELATIVE_EPSILON * total or not world.segment_free(p0, p1):
            continue
        spliced = np.concatenate([points[:i0 + 1], [p0, p1], points[i1 + 1:]])
        # The pieces of segments i0 and i1 kept are free in exact arithmetic, but p0 and
        # p1 are rounded: near a tangency a piece can touch a block, so check them too.
        # (Checked one by one: a batch this small costs more to spread over threads.)
        if world.segment_free(spliced[i0], p0) and world.segment_free(p1, spliced[i0 + 3]):
            points = distinct(spliced)
    return points


def _point_at(points: FloatArray, arc: FloatArray, s: float
              ) -> tuple[int, float, FloatArray]:
    """(segment index, distance along the path, point) for the point ``s`` metres along
    the polyline (N, 3) whose cumulative lengths are ``arc`` (N,).

    A point within :data:`SNAP_FRACTION` of the length from a vertex is that vertex,
    given as the end of the segment before it (the start of the first segment for
    vertex 0), so that cutting a corner leaves no tiny segment.
    """
    nearest = int(np.argmin(np.abs(arc - s)))
    if abs(arc[nearest] - s) <= SNAP_FRACTION * arc[-1]:
        return max(nearest - 1, 0), float(arc[nearest]), points[nearest].copy()
    i = int(np.clip(np.searchsorted(arc, s, side="right") - 1, 0, len(points) - 2))
    t = (s - arc[i]) / (arc[i + 1] - arc[i])
    return i, s, points[i] + t * (points[i + 1] - points[i])

"""The compiled loops of path refinement: the greedy line-of-sight pass and the random
shortcuts of :mod:`quadnav.planning.shortcut`, and the sweeps of the smoother of
:mod:`quadnav.planning.smoothing`, each segment checked exactly by
:func:`~quadnav.world.blockgrid.grid_segment_free` on the world's block grid.

Compiled, a shortcut attempt costs about a microsecond, against tens of microseconds in
numpy (a cumulative-length array, two searches and a Python call into the segment check
per attempt), so the default few hundred to few thousand attempts take a millisecond or
less; a smoothing sweep costs microseconds instead of a fraction of a millisecond.
The random numbers are drawn beforehand by numpy's generator from the shortcut seed, two
per attempt, and used exactly as ``Generator.uniform`` uses them, so the compiled loop
gives the same path as the numpy loop it replaced, and the same seed the same path.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from quadnav.world.blockgrid import grid_segment_free


@njit(cache=True)
def line_of_sight(points, grid):
    """Greedy pass over the free polyline ``points`` (N, 3): from each kept vertex, the
    farthest later vertex it sees is kept next (the next vertex always sees its
    neighbour). Returns the kept vertices (M, 3)."""
    last = len(points) - 1
    kept = np.empty(len(points), dtype=np.int64)
    kept[0] = 0
    count = 1
    while kept[count - 1] < last - 1:
        here = kept[count - 1]
        following = here + 1
        for later in range(last, here + 1, -1):
            if grid_segment_free(points[here], points[later], grid):
                following = later
                break
        kept[count] = following
        count += 1
    if kept[count - 1] != last:
        kept[count] = last
        count += 1
    return points[kept[:count]].copy()


@njit(cache=True)
def _arc_lengths(points):
    """Cumulative length (N,) of the polyline (N, 3) at each vertex, metres."""
    arc = np.zeros(len(points))
    for i in range(1, len(points)):
        arc[i] = arc[i - 1] + np.sqrt(np.sum((points[i] - points[i - 1]) ** 2))
    return arc


@njit(cache=True)
def _point_at(points, arc, s, snap, point):
    """Write into ``point`` (3,) the point ``s`` metres along the polyline and return
    (segment index, distance along the path); within ``snap`` metres of a vertex it is
    that vertex, given as the end of the segment before it (the start of the first
    segment for vertex 0). Plain loops: they compile in a fraction of the time
    ``argmin`` and ``searchsorted`` take."""
    nearest = 0
    for k in range(1, len(arc)):
        if abs(arc[k] - s) < abs(arc[nearest] - s):
            nearest = k
    if abs(arc[nearest] - s) <= snap:
        for axis in range(3):  # element by element: an array copy compiles error messages
            point[axis] = points[nearest, axis]
        return max(nearest - 1, 0), arc[nearest]
    i = 0
    while i < len(points) - 2 and arc[i + 1] <= s:
        i += 1
    t = (s - arc[i]) / (arc[i + 1] - arc[i])
    for axis in range(3):
        point[axis] = points[i, axis] + t * (points[i + 1, axis] - points[i, axis])
    return i, s


@njit(cache=True)
def _spliced(points, i0, p0, p1, i1):
    """The polyline with the vertices between segment i0's start and segment i1's end
    replaced by p0 and p1, consecutive repeats dropped."""
    out = np.empty((len(points) + 2, 3))
    count = 0
    for row in range(len(points) + 2):
        if row <= i0:
            vertex = points[row]
        elif row == i0 + 1:
            vertex = p0
        elif row == i0 + 2:
            vertex = p1
        elif row - 2 + i1 - i0 < len(points):
            vertex = points[row - 2 + i1 - i0]
        else:
            break
        if count == 0 or (vertex[0] != out[count - 1, 0] or vertex[1] != out[count - 1, 1]
                          or vertex[2] != out[count - 1, 2]):
            for axis in range(3):
                out[count, axis] = vertex[axis]
            count += 1
    return out[:count].copy()


@njit(cache=True)
def random_shortcuts(points, grid, uniforms, range_ratio, snap_fraction, epsilon):
    """Random shortcuts along the free polyline ``points`` (N, 3) (see
    :func:`quadnav.planning.shortcut.shortcut_path`), one per pair of ``uniforms`` (2 A,)
    drawn from [0, 1); returns the shortened polyline."""
    arc = _arc_lengths(points)
    p0, p1, checks = np.empty(3), np.empty(3), np.empty((3, 2, 3))
    for attempt in range(len(uniforms) // 2):
        total = arc[-1]
        s0 = total * uniforms[2 * attempt]  # as Generator.uniform(low, high) draws
        low, high = max(0.0, s0 - range_ratio * total), min(total, s0 + range_ratio * total)
        s1 = low + (high - low) * uniforms[2 * attempt + 1]
        s0, s1 = min(s0, s1), max(s0, s1)
        i0, s0 = _point_at(points, arc, s0, snap_fraction * total, p0)
        i1, s1 = _point_at(points, arc, s1, snap_fraction * total, p1)
        # The path between p0 (on segment i0) and p1 (on segment i1) turns only at the
        # vertices i0 + 1 .. i1; on one segment there is nothing to cut.
        if i0 >= i1:
            continue
        saved = (s1 - s0) - np.sqrt(np.sum((p1 - p0) ** 2))
        if saved <= epsilon * total:
            continue
        # The shortcut, and the pieces of segments i0 and i1 kept: those are free in exact
        # arithmetic, but p0 and p1 are rounded, and near a tangency a piece can touch a
        # block. One call site for the three checks keeps the compiled loop small.
        for axis in range(3):  # element by element: array copies compile error messages
            checks[0, 0, axis], checks[0, 1, axis] = p0[axis], p1[axis]
            checks[1, 0, axis], checks[1, 1, axis] = points[i0, axis], p0[axis]
            checks[2, 0, axis], checks[2, 1, axis] = p1[axis], points[i1 + 1, axis]
        free = True
        for k in range(3):
            if not grid_segment_free(checks[k, 0], checks[k, 1], grid):
                free = False
                break
        if not free:
            continue
        points = _spliced(points, i0, p0, p1, i1)
        arc = _arc_lengths(points)
    return points


@njit(cache=True)
def smoothing_sweeps(original, grid, weight_data, weight_smooth, tolerance, max_sweeps):
    """Sweeps of the smoother on the free polyline ``original`` (N, 3) (see
    :func:`quadnav.planning.smoothing.smooth_path`): red-black updates, then the moved
    points of every colliding segment put back and frozen until none collides; stops when
    the points moved less than ``tolerance`` metres in all in one sweep, or after
    ``max_sweeps``. The endpoints never move. Returns the smoothed polyline (N, 3)."""
    path = original.copy()
    count = len(path)
    frozen = np.zeros(count, dtype=np.bool_)
    frozen[0] = frozen[-1] = True
    before = np.empty_like(path)
    for _ in range(max_sweeps):
        for i in range(count):  # element by element: array copies compile error messages
            for axis in range(3):
                before[i, axis] = path[i, axis]
        for parity in (1, 0):  # a point's neighbours have the other parity
            for i in range(1, count - 1):
                if i % 2 == parity and not frozen[i]:
                    for axis in range(3):
                        path[i, axis] += (
                            weight_data * (original[i, axis] - path[i, axis])
                            + weight_smooth * (path[i - 1, axis] + path[i + 1, axis]
                                               - 2 * path[i, axis]))
        _revert_collisions(path, before, frozen, grid)
        moved = 0.0
        for i in range(count):
            moved += np.sqrt(np.sum((path[i] - before[i]) ** 2))
        if moved < tolerance:
            break
    return path


@njit(cache=True)
def _revert_collisions(path, before, frozen, grid):
    """Put back (and freeze) the moved points of every segment of ``path`` that collides,
    until none does; ``before`` (same shape) is the free polyline before the sweep."""
    count = len(path)
    moved = np.zeros(count, dtype=np.bool_)
    for i in range(count):
        moved[i] = np.any(path[i] != before[i])
    check = np.zeros(count - 1, dtype=np.bool_)
    for k in range(count - 1):
        check[k] = moved[k] or moved[k + 1]
    while True:
        hit = np.zeros(count - 1, dtype=np.bool_)
        for k in range(count - 1):
            hit[k] = check[k] and not grid_segment_free(path[k], path[k + 1], grid)
        if not hit.any():
            return
        for k in np.flatnonzero(hit):
            for end in (k, k + 1):
                for axis in range(3):
                    path[end, axis] = before[end, axis]
                moved[end] = False
                frozen[end] = True
        # Only segments beside a point just put back can newly collide.
        check[:] = False
        for k in np.flatnonzero(hit):
            for segment in (k - 1, k, k + 1):
                if 0 <= segment < count - 1:
                    check[segment] = moved[segment] or moved[segment + 1]


@njit(cache=True)
def simplified(path, grid, deviation):
    """Which vertices (N,) of the free polyline ``path`` (N, 3) to keep (see
    :func:`quadnav.planning.smoothing.simplify_path`): Ramer-Douglas-Peucker, a run of
    vertices replaced by its chord when each lies within ``deviation`` metres of it and
    the chord is free, else split at its farthest vertex; the endpoints are kept."""
    count = len(path)
    keep = np.zeros(count, dtype=np.bool_)
    keep[0] = keep[-1] = True
    runs = [(0, count - 1)]
    while runs:
        first, last = runs.pop()
        if last - first < 2:
            continue
        a, d = path[first], path[last] - path[first]
        squared = np.sum(d * d)
        farthest, largest = first + 1, -1.0
        for i in range(first + 1, last):
            t = 0.0 if squared == 0.0 else min(max(np.sum((path[i] - a) * d) / squared, 0.0),
                                               1.0)
            distance = np.sqrt(np.sum((path[i] - (a + t * d)) ** 2))
            if distance > largest:
                farthest, largest = i, distance
        if largest <= deviation and grid_segment_free(path[first], path[last], grid):
            continue
        keep[farthest] = True
        runs.append((first, farthest))
        runs.append((farthest, last))
    return keep

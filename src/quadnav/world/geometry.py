"""Exact geometric queries against axis-aligned boxes, compiled with numba.

Boxes are rows ``(xmin, ymin, zmin, xmax, ymax, zmax)`` in metres. The kernels take
the blocks transposed to a C-contiguous ``(6, N)`` array (one row per coordinate) so
that the inner loop over blocks reads memory in order.

Conventions, shared by every query:

* Free space is **open**: a point is free when it lies strictly inside the boundary
  box and outside every *closed* block. Touching a block face, edge or corner is a
  collision, and so is touching the boundary.
* A segment ``p -> q`` is the closed set ``p + t (q - p)`` for ``t`` in ``[0, 1]``; it
  is collision-free when every one of its points is free. The test is an exact slab
  test (no sampling); the only error is floating-point rounding at tangencies.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

#: Index that :func:`first_hits` reports for a hit on the boundary.
HIT_BOUNDARY = -1
#: Index that :func:`first_hits` reports for a segment that hits nothing.
NO_HIT = -2

# Below this, a direction component counts as zero: the segment is parallel to that slab.
_PARALLEL_EPS = 1e-300


@njit(cache=True, inline="always")
def _inverse(d: float) -> tuple[float, bool]:
    """(1 / d, False), or (0, True) for a component that counts as zero (parallel)."""
    if abs(d) < _PARALLEL_EPS:
        return 0.0, True
    return 1.0 / d, False


@njit(cache=True, inline="always")
def _axis_interval(lower, upper, p, inverse, parallel):
    """Parameters (t_enter, t_exit) where the line p + t d is in [lower, upper] on one axis.

    A line parallel to the slab is inside it for every t (if p is in [lower, upper]) or
    for none. Written without early returns so the compiler can use selects.
    """
    t1 = (lower - p) * inverse
    t2 = (upper - p) * inverse
    t_enter = min(t1, t2)
    t_exit = max(t1, t2)
    if parallel:
        inside = lower <= p and p <= upper
        t_enter = -np.inf if inside else np.inf
        t_exit = np.inf if inside else -np.inf
    return t_enter, t_exit


@njit(cache=True, inline="always")
def _slab_entry_exit(p, inverse, parallel, bt, i):
    """Parameters (t_enter, t_exit) where the line p + t d meets closed block ``i``.

    ``inverse`` and ``parallel`` are the (3,) tuples :func:`_inverses` gives for ``d``.
    """
    e0, x0 = _axis_interval(bt[0, i], bt[3, i], p[0], inverse[0], parallel[0])
    e1, x1 = _axis_interval(bt[1, i], bt[4, i], p[1], inverse[1], parallel[1])
    e2, x2 = _axis_interval(bt[2, i], bt[5, i], p[2], inverse[2], parallel[2])
    return max(e0, max(e1, e2)), min(x0, min(x1, x2))


@njit(cache=True, inline="always")
def _inverses(d):
    """Per-axis :func:`_inverse` of a direction (3,): ((3,) inverses, (3,) parallel flags)."""
    i0, p0 = _inverse(d[0])
    i1, p1 = _inverse(d[1])
    i2, p2 = _inverse(d[2])
    return (i0, i1, i2), (p0, p1, p2)


@njit(cache=True, inline="always")
def _strictly_inside(x, y, z, boundary) -> bool:
    return (
        boundary[0] < x < boundary[3]
        and boundary[1] < y < boundary[4]
        and boundary[2] < z < boundary[5]
    )


@njit(cache=True)
def point_free(x, y, z, bt, boundary) -> bool:
    """Whether the point (x, y, z) lies in open free space (serial)."""
    if not _strictly_inside(x, y, z, boundary):
        return False
    for i in range(bt.shape[1]):
        if (bt[0, i] <= x <= bt[3, i] and bt[1, i] <= y <= bt[4, i]
                and bt[2, i] <= z <= bt[5, i]):
            return False
    return True


@njit(cache=True, parallel=True)
def points_free(points, bt, boundary):
    """Batch point check: ``points`` (N, 3) -> bool (N,)."""
    n = points.shape[0]
    out = np.empty(n, dtype=np.bool_)
    for k in prange(n):
        out[k] = point_free(points[k, 0], points[k, 1], points[k, 2], bt, boundary)
    return out


@njit(cache=True, inline="always")
def _box_signed_distance(x, y, z, bt, i) -> float:
    """Signed Euclidean distance from a point to block ``i`` (negative inside)."""
    qx = max(bt[0, i] - x, x - bt[3, i])
    qy = max(bt[1, i] - y, y - bt[4, i])
    qz = max(bt[2, i] - z, z - bt[5, i])
    outside = np.sqrt(max(qx, 0.0) ** 2 + max(qy, 0.0) ** 2 + max(qz, 0.0) ** 2)
    inside = min(max(qx, max(qy, qz)), 0.0)
    return outside + inside


@njit(cache=True, parallel=True)
def clearances(points, bt, boundary):
    """Signed clearance of each point, in metres: (N, 3) -> (N,).

    Positive in free space: the distance to the nearest block surface or boundary face.
    Zero on a surface. Negative inside a block (minus the depth into the block it is
    deepest in) or outside the boundary (minus the distance past the farthest face).
    """
    n = points.shape[0]
    out = np.empty(n, dtype=np.float64)
    for k in prange(n):
        x, y, z = points[k, 0], points[k, 1], points[k, 2]
        best = min(
            min(x - boundary[0], boundary[3] - x),
            min(y - boundary[1], boundary[4] - y),
            min(z - boundary[2], boundary[5] - z),
        )
        for i in range(bt.shape[1]):
            best = min(best, _box_signed_distance(x, y, z, bt, i))
        out[k] = best
    return out


@njit(cache=True, inline="always")
def _boundary_exit(p, d, boundary) -> float:
    """Parameter t >= 0 where the ray p + t d first reaches a boundary face (p inside)."""
    t_exit = np.inf
    for a in range(3):
        if d[a] > 0.0:
            t_exit = min(t_exit, (boundary[a + 3] - p[a]) / d[a])
        elif d[a] < 0.0:
            t_exit = min(t_exit, (boundary[a] - p[a]) / d[a])
    return t_exit


@njit(cache=True)
def _first_hit(p, q, bt, boundary):
    """(t, index) of the first contact along p -> q; see :func:`first_hits`."""
    d = q - p
    if not _strictly_inside(p[0], p[1], p[2], boundary):
        best_t, best_i = 0.0, HIT_BOUNDARY
    else:
        best_t, best_i = _boundary_exit(p, d, boundary), HIT_BOUNDARY
    inverse, parallel = _inverses(d)
    for i in range(bt.shape[1]):
        t_enter, t_exit = _slab_entry_exit(p, inverse, parallel, bt, i)
        t_enter = max(t_enter, 0.0)
        if t_enter <= min(t_exit, 1.0) and t_enter < best_t:
            best_t, best_i = t_enter, i
    if best_t > 1.0:
        return np.inf, NO_HIT
    return best_t, best_i


@njit(cache=True, parallel=True)
def first_hits(segments, bt, boundary):
    """First contact along each segment: (N, 2, 3) -> (t (N,), index (N,)).

    ``t`` in [0, 1] is the fraction of the way from the first to the second point at
    which the segment first touches a block (``index`` is its row) or the boundary
    (``index == HIT_BOUNDARY``). A segment that stays free has ``t = inf`` and
    ``index == NO_HIT``. A segment starting outside free space has ``t = 0``.
    """
    n = segments.shape[0]
    ts = np.empty(n, dtype=np.float64)
    idx = np.empty(n, dtype=np.int64)
    for k in prange(n):
        ts[k], idx[k] = _first_hit(segments[k, 0], segments[k, 1], bt, boundary)
    return ts, idx

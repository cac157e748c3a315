"""A uniform grid over a world's boundary that lists the blocks touching each cell.

Planners test thousands of short segments per second against maps of thousands of
blocks; scanning every block costs about 1.4 ns per block per segment. The grid narrows
each test to the blocks registered in the cells a segment crosses, and then runs the
exact slab test of :mod:`quadnav.world.geometry` on them, so answers are those of a scan
over every block (same open free space, same touching rule).

A segment is cut into pieces no longer than the smallest cell edge; each piece's
bounding box spans at most 2 cells per axis. A block is registered in every cell its
closed box touches, and both index ranges are widened by a rounding allowance, so every
block a segment touches is among those tested.

The grid is a plain tuple (:data:`GridArrays`) so that numba-compiled callers can take
it as one argument; build it with :func:`build_block_grid`.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
from numba import njit, prange

from quadnav.profiling import staged
from quadnav.world.geometry import _inverses, _slab_entry_exit, _strictly_inside

if TYPE_CHECKING:
    from quadnav.world.model import World

#: Cells per block the grid aims for (more cells: fewer blocks per test, more cells
#: visited per segment).
CELLS_PER_BLOCK = 4
#: Batches smaller than this run on one thread: waking numba's worker threads costs more
#: than the checks, and far more when the cores are busy.
PARALLEL_FROM = 512
#: Upper bound on the number of cells.
MAX_CELLS = 1 << 20
# Widening of index ranges, in cell units, so rounding never drops a block.
_ROUNDING = 1e-9

#: ``(bt (6, N), boundary (6,), origin (3,), inverse_cell (3,), shape (3,) int64,
#: starts (cells + 1,) int64, members (M,) int64)``: blocks by coordinate, the open free
#: box, the grid's lower corner, 1 / cell edge per axis (1/m), cells per axis, and the
#: CSR lists of the blocks registered in each cell (cell id ``ix + nx (iy + ny iz)``).
GridArrays = tuple


@staged("block grid")
def build_block_grid(world: World) -> GridArrays:
    """The block grid of ``world`` (see :data:`GridArrays`)."""
    blocks = world.blocks
    extent = world.extent
    target = min(max(CELLS_PER_BLOCK * len(blocks), 1), MAX_CELLS)
    edge = float(np.cbrt(np.prod(extent) / target))
    shape = np.clip(np.ceil(extent / edge), 1, math.isqrt(MAX_CELLS)).astype(np.int64)
    inverse_cell = shape / extent
    first = _cell_index(blocks[:, :3], world.lower, inverse_cell, shape, -_ROUNDING)
    last = _cell_index(blocks[:, 3:], world.lower, inverse_cell, shape, _ROUNDING)
    starts, members = _register(first, last, shape)
    # Writable C-ordered copies, so numba compiles one signature for every world.
    return (np.array(blocks.T, order="C"), world.boundary.copy(), world.lower.copy(),
            inverse_cell, shape, starts, members)


@njit(cache=True)
def _register(first, last, shape):
    """CSR lists (starts (cells + 1,), members (M,)) of the blocks whose inclusive cell
    index ranges ``first..last`` (N, 3) cover each cell."""
    starts = np.zeros(shape[0] * shape[1] * shape[2] + 1, dtype=np.int64)
    for fill in range(2):
        members = np.empty(starts[-1], dtype=np.int64)
        cursor = starts[:-1].copy()
        for row in range(first.shape[0]):
            for iz in range(first[row, 2], last[row, 2] + 1):
                for iy in range(first[row, 1], last[row, 1] + 1):
                    for ix in range(first[row, 0], last[row, 0] + 1):
                        cell = ix + shape[0] * (iy + shape[1] * iz)
                        if fill:
                            members[cursor[cell]] = row
                            cursor[cell] += 1
                        else:
                            starts[cell + 1] += 1
        if not fill:
            starts = np.cumsum(starts)
    return starts, members


def _cell_index(points: np.ndarray, origin: np.ndarray, inverse_cell: np.ndarray,
                shape: np.ndarray, widen: float) -> np.ndarray:
    """Cell index (N, 3) of each point, widened by ``widen`` cells and clipped to the grid."""
    index = np.floor((points - origin) * inverse_cell + widen).astype(np.int64)
    return np.clip(index, 0, shape - 1)


@njit(cache=True, inline="always")
def _clipped_cell(value, origin, inverse_cell, size, widen):
    index = math.floor((value - origin) * inverse_cell + widen)
    return min(max(index, 0), size - 1)


@njit(cache=True, inline="always")
def _piece_cells(p, d, t0, t1, a, origin, inverse_cell, shape):
    """First and last cell index along axis ``a`` of the piece t in [t0, t1] of p + t d."""
    v0 = p[a] + t0 * d[a]
    v1 = p[a] + t1 * d[a]
    return (_clipped_cell(min(v0, v1), origin[a], inverse_cell[a], shape[a], -_ROUNDING),
            _clipped_cell(max(v0, v1), origin[a], inverse_cell[a], shape[a], _ROUNDING))


@njit(cache=True)
def grid_segment_free(p, q, grid) -> bool:
    """Whether the closed segment p -> q (each (3,), metres) lies in open free space.

    Free space is open: touching a block or the boundary is a collision. ``grid`` is a
    :data:`GridArrays` tuple.
    """
    bt, boundary, origin, inverse_cell, shape, starts, members = grid
    if not (_strictly_inside(p[0], p[1], p[2], boundary)
            and _strictly_inside(q[0], q[1], q[2], boundary)):
        return False
    d = q - p
    cells_along = 0.0
    for a in range(3):
        cells_along = max(cells_along, abs(d[a]) * inverse_cell[a])
    pieces = max(1, math.ceil(cells_along))
    inverse, parallel = _inverses(d)
    for k in range(pieces):
        t0 = k / pieces
        t1 = (k + 1) / pieces
        x0, x1 = _piece_cells(p, d, t0, t1, 0, origin, inverse_cell, shape)
        y0, y1 = _piece_cells(p, d, t0, t1, 1, origin, inverse_cell, shape)
        z0, z1 = _piece_cells(p, d, t0, t1, 2, origin, inverse_cell, shape)
        for iz in range(z0, z1 + 1):
            for iy in range(y0, y1 + 1):
                for ix in range(x0, x1 + 1):
                    cell = ix + shape[0] * (iy + shape[1] * iz)
                    for m in range(starts[cell], starts[cell + 1]):
                        t_enter, t_exit = _slab_entry_exit(p, inverse, parallel, bt, members[m])
                        if max(t_enter, 0.0) <= min(t_exit, 1.0):
                            return False
    return True


@njit(cache=True)
def grid_point_free(x, y, z, grid) -> bool:
    """Whether the point (x, y, z), metres, lies in open free space (see
    :func:`quadnav.world.geometry.point_free`); ``grid`` is a :data:`GridArrays` tuple."""
    bt, boundary, origin, inverse_cell, shape, starts, members = grid
    if not _strictly_inside(x, y, z, boundary):
        return False
    ix = _clipped_cell(x, origin[0], inverse_cell[0], shape[0], 0.0)
    iy = _clipped_cell(y, origin[1], inverse_cell[1], shape[1], 0.0)
    iz = _clipped_cell(z, origin[2], inverse_cell[2], shape[2], 0.0)
    cell = ix + shape[0] * (iy + shape[1] * iz)
    for m in range(starts[cell], starts[cell + 1]):
        i = members[m]
        if (bt[0, i] <= x <= bt[3, i] and bt[1, i] <= y <= bt[4, i]
                and bt[2, i] <= z <= bt[5, i]):
            return False
    return True


@njit(cache=True, parallel=True)
def grid_points_free(points, grid):
    """Batch :func:`grid_point_free`: points (N, 3) float64 -> bool (N,)."""
    out = np.empty(points.shape[0], dtype=np.bool_)
    for k in prange(points.shape[0]):
        out[k] = grid_point_free(points[k, 0], points[k, 1], points[k, 2], grid)
    return out


@njit(cache=True)
def _segments_free_range(segments, grid, out, first, stop):
    """``out[k]`` = whether segment ``k`` (of (N, 2, 3)) is free, for k in [first, stop)."""
    for k in range(first, stop):
        out[k] = grid_segment_free(segments[k, 0], segments[k, 1], grid)


@njit(cache=True, parallel=True)
def _segments_free_parallel(segments, grid, out, pieces):
    n = segments.shape[0]
    for piece in prange(pieces):
        _segments_free_range(segments, grid, out, piece * n // pieces,
                             (piece + 1) * n // pieces)


def grid_segments_free(segments: np.ndarray, grid: GridArrays) -> np.ndarray:
    """Batch :func:`grid_segment_free`: segments (N, 2, 3) float64 -> bool (N,); runs on
    several threads from :data:`PARALLEL_FROM` segments on."""
    out = np.empty(len(segments), dtype=np.bool_)
    if len(segments) < PARALLEL_FROM:
        _segments_free_range(segments, grid, out, 0, len(segments))
    else:
        _segments_free_parallel(segments, grid, out, 64)
    return out

"""Nearest-neighbour and radius queries over a growing set of tree vertices (numba).

Vertices live in a uniform grid over the search box whose cells hold linked lists
(``heads[cell]`` is a vertex, ``next_in_cell[vertex]`` the next one in the same cell, -1
ends a list). The grid is rebuilt with cells about one vertex each whenever the number of
vertices doubles, so queries look at a handful of cells at any tree size.

State (all arrays, mutated in place; see :func:`new_node_grid`):

* ``heads`` (C,) int64 — first vertex of each cell, -1 when empty; C bounds the cells.
* ``next_in_cell`` (V,) int64 — next vertex in the same cell.
* ``shape`` (4,) int64 — cells along x, y, z, and the vertex count that triggers the
  next rebuild.
* ``inverse_cell`` (1,) float64 — 1 / cell edge, 1/m.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

# Below this many vertices a linear scan beats the grid.
_LINEAR_BELOW = 64


def new_node_grid(capacity: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Empty grid state for up to ``capacity`` vertices: (heads, next_in_cell, shape,
    inverse_cell); the first :func:`insert` builds the cells."""
    return (np.full(max(capacity, 1), -1, dtype=np.int64),
            np.full(capacity, -1, dtype=np.int64),
            np.zeros(4, dtype=np.int64),
            np.ones(1, dtype=np.float64))


@njit(cache=True, inline="always")
def _cell_of(point, origin, inverse_cell, shape):
    """Cell coordinates (ix, iy, iz) of a point, clipped to the grid."""
    ix = min(max(math.floor((point[0] - origin[0]) * inverse_cell), 0), shape[0] - 1)
    iy = min(max(math.floor((point[1] - origin[1]) * inverse_cell), 0), shape[1] - 1)
    iz = min(max(math.floor((point[2] - origin[2]) * inverse_cell), 0), shape[2] - 1)
    return ix, iy, iz


@njit(cache=True, inline="always")
def _link(vertex, nodes, origin, heads, next_in_cell, shape, inverse_cell):
    ix, iy, iz = _cell_of(nodes[vertex], origin, inverse_cell[0], shape)
    cell = ix + shape[0] * (iy + shape[1] * iz)
    next_in_cell[vertex] = heads[cell]
    heads[cell] = vertex


@njit(cache=True)
def rebuild(nodes, count, origin, extent, heads, next_in_cell, shape, inverse_cell):
    """Re-grid ``count`` vertices with about one vertex per cell (at most len(heads))."""
    volume = extent[0] * extent[1] * extent[2]
    target = min(max(count, 1), heads.shape[0])
    edge = (volume / target) ** (1.0 / 3.0)
    while True:
        nx = max(1, math.ceil(extent[0] / edge))
        ny = max(1, math.ceil(extent[1] / edge))
        nz = max(1, math.ceil(extent[2] / edge))
        if nx * ny * nz <= heads.shape[0]:
            break
        edge *= 1.1
    shape[0], shape[1], shape[2] = nx, ny, nz
    shape[3] = 2 * max(count, _LINEAR_BELOW)
    inverse_cell[0] = 1.0 / edge
    heads[: nx * ny * nz] = -1
    for vertex in range(count):
        _link(vertex, nodes, origin, heads, next_in_cell, shape, inverse_cell)


@njit(cache=True)
def insert(vertex, nodes, origin, extent, heads, next_in_cell, shape, inverse_cell):
    """Add vertex ``vertex`` (its point is ``nodes[vertex]``; vertices 0..vertex-1 are in)."""
    if vertex + 1 >= shape[3]:
        rebuild(nodes, vertex + 1, origin, extent, heads, next_in_cell, shape, inverse_cell)
    else:
        _link(vertex, nodes, origin, heads, next_in_cell, shape, inverse_cell)


@njit(cache=True, inline="always")
def _distance2(a, b):
    return (a[0] - b[0]) ** 2 + (a[1] - b[1]) ** 2 + (a[2] - b[2]) ** 2


@njit(cache=True)
def _nearest_linear(query, nodes, count):
    best, best_d2 = -1, np.inf
    for vertex in range(count):
        d2 = _distance2(nodes[vertex], query)
        if d2 < best_d2:
            best, best_d2 = vertex, d2
    return best


@njit(cache=True)
def nearest(query, nodes, count, origin, heads, next_in_cell, shape, inverse_cell):
    """Index of the vertex among the first ``count`` (>= 1) nearest to ``query`` (3,).

    Scans shells of cells of growing Chebyshev radius k around the query's cell and stops
    once no unscanned cell can hold a closer vertex (every cell of shell k is at least
    (k - 1) cell edges away). Falls back to a linear scan while the tree is small or when
    the shells hold many more empty cells than there are vertices.
    """
    if count < _LINEAR_BELOW:
        return _nearest_linear(query, nodes, count)
    edge = 1.0 / inverse_cell[0]
    cx, cy, cz = _cell_of(query, origin, inverse_cell[0], shape)
    widest = max(shape[0], max(shape[1], shape[2]))
    best, best_d2 = -1, np.inf
    scanned = 0
    for k in range(widest + 1):
        if best >= 0 and best_d2 <= ((k - 1) * edge) ** 2:
            break
        for dz in range(-k, k + 1):
            iz = cz + dz
            if iz < 0 or iz >= shape[2]:
                continue
            for dy in range(-k, k + 1):
                iy = cy + dy
                if iy < 0 or iy >= shape[1]:
                    continue
                on_shell = abs(dz) == k or abs(dy) == k
                step = 1 if on_shell else max(2 * k, 1)
                for dx in range(-k, k + 1, step):
                    ix = cx + dx
                    if ix < 0 or ix >= shape[0]:
                        continue
                    scanned += 1
                    vertex = heads[ix + shape[0] * (iy + shape[1] * iz)]
                    while vertex >= 0:
                        d2 = _distance2(nodes[vertex], query)
                        if d2 < best_d2:
                            best, best_d2 = vertex, d2
                        vertex = next_in_cell[vertex]
        if scanned > 4 * count:
            return _nearest_linear(query, nodes, count)
    return best


@njit(cache=True)
def within(query, radius, nodes, count, origin, heads, next_in_cell, shape, inverse_cell,
           found, distances):
    """Vertices among the first ``count`` within ``radius`` metres of ``query`` (3,).

    Writes their indices to ``found`` and distances to ``distances`` (both at least
    ``count`` long) and returns how many there are.
    """
    n = 0
    r2 = radius * radius
    if count < _LINEAR_BELOW:
        for vertex in range(count):
            d2 = _distance2(nodes[vertex], query)
            if d2 <= r2:
                found[n], distances[n] = vertex, math.sqrt(d2)
                n += 1
        return n
    reach = math.ceil(radius * inverse_cell[0])
    cx, cy, cz = _cell_of(query, origin, inverse_cell[0], shape)
    for iz in range(max(cz - reach, 0), min(cz + reach, shape[2] - 1) + 1):
        for iy in range(max(cy - reach, 0), min(cy + reach, shape[1] - 1) + 1):
            for ix in range(max(cx - reach, 0), min(cx + reach, shape[0] - 1) + 1):
                vertex = heads[ix + shape[0] * (iy + shape[1] * iz)]
                while vertex >= 0:
                    d2 = _distance2(nodes[vertex], query)
                    if d2 <= r2:
                        found[n], distances[n] = vertex, math.sqrt(d2)
                        n += 1
                    vertex = next_in_cell[vertex]
    return n

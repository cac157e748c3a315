"""``maze``: levels of grid mazes, stacked, joined by a hole in each floor between them.

Each level is a perfect maze (one path between any two cells) carved by a randomised
depth-first search; its inner walls stand on the cell edges, merged into one box per
straight run, and the boundary is the outer wall. Between two levels lies a slab with a
hole the size of one cell's floor.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from quadnav.arrays import FloatArray
from quadnav.limits import Range
from quadnav.specs import FLOAT, GRID, INT, SEED_PARAM, Param, SpecError
from quadnav.world.builtin.base import Generator, Layout, plate_with_hole, shaded

WALL_COLOR = (0.6, 0.6, 0.62)
SLAB_COLOR = (0.35, 0.45, 0.65)
#: Thickness of walls and slabs, metres.
THICKNESS = 0.2
MAX_CELLS = 50_000

_STEPS = ((1, 0), (-1, 0), (0, 1), (0, -1))


def _passages(rng: np.random.Generator, nx: int, ny: int) -> tuple[np.ndarray, np.ndarray]:
    """A perfect maze on ``nx`` x ``ny`` cells by randomised depth-first search.

    Returns ``(east, north)``: bool (nx - 1, ny), True where cell (i, j) opens into
    (i + 1, j); and bool (nx, ny - 1), True where (i, j) opens into (i, j + 1).
    """
    east = np.zeros((nx - 1, ny), dtype=bool)
    north = np.zeros((nx, ny - 1), dtype=bool)
    visited = np.zeros((nx, ny), dtype=bool)
    visited[0, 0] = True
    stack = [(0, 0)]
    while stack:
        i, j = stack[-1]
        options = [(i + di, j + dj) for di, dj in _STEPS
                   if 0 <= i + di < nx and 0 <= j + dj < ny and not visited[i + di, j + dj]]
        if not options:
            stack.pop()
            continue
        a, b = options[rng.integers(len(options))]
        if a != i:
            east[min(a, i), j] = True
        else:
            north[i, min(b, j)] = True
        visited[a, b] = True
        stack.append((a, b))
    return east, north


def _walls(standing: np.ndarray, axis: int, cell: float, bottom: float, top: float) -> FloatArray:
    """Boxes (k, 6) for the inner walls across ``axis`` (0: x, 1: y), one per straight run.

    ``standing`` (L, M) bool is True where the wall on the line ``axis = (l + 1) cell``
    stands beside the ``m``-th cell along the other horizontal axis. Runs are lengthened
    by half a thickness at each end so that walls meeting at a corner close it.
    """
    edges = np.diff(np.pad(standing.astype(np.int8), ((0, 0), (1, 1))), axis=1)
    line, first = np.nonzero(edges == 1)
    _, stop = np.nonzero(edges == -1)
    position = (line + 1) * cell
    other = 1 - axis
    boxes = np.empty((len(line), 6))
    boxes[:, axis], boxes[:, axis + 3] = position - THICKNESS / 2, position + THICKNESS / 2
    boxes[:, other] = first * cell - THICKNESS / 2
    boxes[:, other + 3] = stop * cell + THICKNESS / 2
    boxes[:, 2], boxes[:, 5] = bottom, top
    return boxes


def _hole_cell(rng: np.random.Generator, nx: int, ny: int) -> tuple[int, int]:
    """A random cell (i, j) for a hole, away from the start and goal corners if there is
    another cell, so that a climb is never straight up from the start or onto the goal."""
    corners = {(0, 0), (nx - 1, ny - 1)}
    cells = [(i, j) for i in range(nx) for j in range(ny) if (i, j) not in corners]
    if not cells:
        cells = sorted(corners)
    return cells[rng.integers(len(cells))]


def _layout(values: dict[str, Any], rng: np.random.Generator) -> Layout:
    """Blocks: the walls of every level (grey) first, then the slabs (blue); start in the
    corner cell of the bottom level, goal in the opposite corner cell of the top level."""
    (nx, ny), levels = values["cells"], values["levels"]
    cell, storey = values["cell_size"], values["level_height"]
    if nx * ny * levels > MAX_CELLS:
        raise SpecError(f"{nx}x{ny} cells on {levels} levels is too many "
                        f"(at most {MAX_CELLS} cells in all)")
    if nx * ny * levels == 1:
        raise SpecError("a single cell on a single level leaves no room for start and goal")
    size = (nx * cell, ny * cell, levels * storey)
    walls = []
    for level in range(levels):
        east, north = _passages(rng, nx, ny)
        z = (level * storey, (level + 1) * storey)
        walls += [_walls(~east, 0, cell, *z), _walls(~north.T, 1, cell, *z)]
    slabs = []
    for level in range(1, levels):
        z = level * storey
        i, j = _hole_cell(rng, nx, ny)
        gap = THICKNESS / 2
        hole = [i * cell + gap, j * cell + gap, 0.0, (i + 1) * cell - gap, (j + 1) * cell - gap, 0]
        slab = [0.0, 0.0, z - THICKNESS / 2, size[0], size[1], z + THICKNESS / 2]
        slabs.append(plate_with_hole(slab, hole, normal=2))
    wall_blocks = np.concatenate(walls)
    blocks = np.concatenate([wall_blocks, *slabs])
    blocks[:, :3] = np.maximum(blocks[:, :3], 0.0)
    blocks[:, 3:] = np.minimum(blocks[:, 3:], size)
    colors = np.concatenate([shaded(rng, WALL_COLOR, len(wall_blocks), spread=0.05),
                             shaded(rng, SLAB_COLOR, len(blocks) - len(wall_blocks))])
    start = np.array([cell / 2, cell / 2, storey / 2])
    goal = np.array([size[0] - cell / 2, size[1] - cell / 2, size[2] - storey / 2])
    return Layout(size, blocks, colors, start, goal)


GENERATOR = Generator(
    name="maze",
    summary="stacked grid mazes joined by a hole in each floor; climb from start to goal",
    params=(
        Param("cells", GRID, (6, 6), "NxM cells on each level", Range(1, 200, whole=True)),
        Param("levels", INT, 2, "number of levels", Range(1, 20, whole=True)),
        Param("cell_size", FLOAT, 2.0, "side of a cell, wall centre to wall centre, metres",
              Range(1.0, 50.0, "m")),
        Param("level_height", FLOAT, 2.5, "height of a level, slab centre to slab centre, metres",
              Range(1.0, 500.0, "m")),
        SEED_PARAM,
    ),
    layout=_layout,
)

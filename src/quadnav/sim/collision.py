"""Exact contact between the vehicle's body box and the real (uninflated) blocks.

The body is a box of ``body_size`` centred on the centre of mass and turned with the
vehicle; a block is an axis-aligned box. They touch when no separating axis exists
(the 15-axis test for two boxes, Ericson, *Real-Time Collision Detection*, 4.4.1);
touching faces count as contact, as free space is open.

Candidate blocks come from a :mod:`~quadnav.world.blockgrid` grid of the blocks grown by
the body's circumradius: only a block whose grown box holds the centre can touch the
body, and every such block is registered in the cell holding the centre.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from quadnav.world.blockgrid import GridArrays, build_block_grid
from quadnav.world.model import World, WorldMemo

#: Added to the rotation's absolute values so nearly parallel edges give no false gap.
_PARALLEL_EPSILON = 1e-12


#: The grids :func:`body_grid` made, by world and circumradius (m).
_BODY_GRIDS: WorldMemo[float, GridArrays] = WorldMemo()


def body_grid(world: World, half_size: np.ndarray) -> GridArrays:
    """Block grid of ``world``'s blocks grown by the circumradius of a box of half sizes
    ``half_size`` (3,) m. Its block coordinates (row 0 of the tuple) are the grown ones;
    pass the real blocks separately to :func:`touched_block`. Made once per world and
    circumradius while the world lives (a world is immutable): the flights of a batch on
    one map share it."""
    radius = float(np.linalg.norm(half_size))
    grow = np.array([-radius] * 3 + [radius] * 3)
    return _BODY_GRIDS.get(
        world, lambda: build_block_grid(world.replace(blocks=world.blocks + grow)), radius)


@njit(cache=True)
def boxes_touch(center: np.ndarray, rotation: np.ndarray, half: np.ndarray,
                block: np.ndarray) -> bool:
    """Whether the box at ``center`` (3,) with axes the columns of ``rotation`` (3, 3) and
    half sizes ``half`` (3,) touches the closed axis-aligned ``block`` (6,) (min, max)."""
    extent = 0.5 * (block[3:6] - block[0:3])
    t = center - 0.5 * (block[3:6] + block[0:3])
    absolute = np.abs(rotation) + _PARALLEL_EPSILON
    for i in range(3):  # world axes
        if abs(t[i]) > extent[i] + (absolute[i, 0] * half[0] + absolute[i, 1] * half[1]
                                    + absolute[i, 2] * half[2]):
            return False
    for j in range(3):  # body axes
        distance = t[0] * rotation[0, j] + t[1] * rotation[1, j] + t[2] * rotation[2, j]
        reach = (extent[0] * absolute[0, j] + extent[1] * absolute[1, j]
                 + extent[2] * absolute[2, j])
        if abs(distance) > reach + half[j]:
            return False
    for i in range(3):  # world axis i x body axis j
        i1, i2 = (i + 1) % 3, (i + 2) % 3
        for j in range(3):
            j1, j2 = (j + 1) % 3, (j + 2) % 3
            ra = extent[i1] * absolute[i2, j] + extent[i2] * absolute[i1, j]
            rb = half[j1] * absolute[i, j2] + half[j2] * absolute[i, j1]
            if abs(t[i2] * rotation[i1, j] - t[i1] * rotation[i2, j]) > ra + rb:
                return False
    return True


@njit(cache=True)
def touched_block(center: np.ndarray, rotation: np.ndarray, half: np.ndarray,
                  blocks: np.ndarray, grid) -> int:
    """Row of a block (of ``blocks`` (N, 6)) the body box touches, or -1.

    ``grid`` is :func:`body_grid` of the same blocks; see :func:`boxes_touch`."""
    _, _, origin, inverse_cell, shape, starts, members = grid
    cell = 0
    for a in range(2, -1, -1):
        index = math.floor((center[a] - origin[a]) * inverse_cell[a])
        cell = cell * shape[a] + min(max(index, 0), shape[a] - 1)
    for m in range(starts[cell], starts[cell + 1]):
        if boxes_touch(center, rotation, half, blocks[members[m]]):
            return members[m]
    return -1

"""A conservative proof that two points are connected in a world's free space.

The boundary box is cut into a grid of equal voxels (boxes of at most ``resolution``
metres a side). A voxel is *free* when its **closed** box touches no closed block. Two
face-adjacent free voxels are joined by the segment between their centres, which lies in
the union of the two closed voxels, so it touches no block; it also lies strictly inside
the boundary, since every voxel centre does and the open box is convex. So a chain of
face-adjacent free voxels from the start's voxel to the goal's is a collision-free path:
a ``True`` answer is a proof. ``False`` means only that no proof was found at this
resolution (a passage narrower than about two voxels may be missed).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import ndimage

from quadnav.world.model import World

#: Voxel budget for the default resolution.
MAX_VOXELS = 4_000_000

# Widening, in voxel units, of each block's index range: rounding can only mark more
# voxels occupied, never fewer, so the answer stays a proof.
_ROUNDING = 1e-9


def default_resolution(extent: ArrayLike, max_voxels: int = MAX_VOXELS) -> float:
    """The finest voxel edge, metres, whose grid over a box of ``extent`` (3,) metres
    has at most ``max_voxels`` voxels (to within 2 %).

    E.g. 0.084 m for a 20 x 20 x 6 m box and 0.37 m for 100 x 100 x 20 m.
    """
    size = np.asarray(extent, dtype=np.float64)
    edge = float(np.cbrt(np.prod(size) / max_voxels))
    while np.prod(np.ceil(size / edge - _ROUNDING)) > max_voxels:
        edge *= 1.02
    return edge


def connected(
    world: World, start: ArrayLike, goal: ArrayLike, resolution: float | None = None
) -> bool:
    """Whether a collision-free path provably joins ``start`` and ``goal`` in ``world``.

    Pass the world already inflated by the safety margin. The answer is conservative:
    ``True`` is a proof (see the module docstring); ``False`` may also mean that a
    passage is too narrow for the voxel grid, or that the voxel holding ``start`` or
    ``goal`` touches a block although the point itself is free. A point that is not
    free gives ``False``.

    Args:
        world: the map; its boundary is voxelised.
        start: (3,) point, metres.
        goal: (3,) point, metres.
        resolution: largest voxel edge, metres. By default the finest edge that keeps
            the grid within :data:`MAX_VOXELS` voxels (:func:`default_resolution`).
    """
    points = np.array([start, goal], dtype=np.float64)
    if not np.all(world.points_free(points)):
        return False
    if resolution is None:
        resolution = default_resolution(world.extent)
    if not (np.isfinite(resolution) and resolution > 0):
        raise ValueError(f"resolution must be a positive number of metres, got {resolution}")
    shape = np.maximum(np.ceil(world.extent / resolution - _ROUNDING), 1).astype(np.int64)
    voxel = world.extent / shape
    occupied = _occupied(world.blocks, world.lower, voxel, shape)
    cells = np.minimum(np.floor((points - world.lower) / voxel), shape - 1).astype(np.int64)
    if occupied[tuple(cells[0])] or occupied[tuple(cells[1])]:
        return False
    labels, _ = ndimage.label(~occupied)  # default structure: face (6-) connectivity
    return bool(labels[tuple(cells[0])] == labels[tuple(cells[1])])


def _occupied(
    blocks: NDArray[np.float64],
    origin: NDArray[np.float64],
    voxel: NDArray[np.float64],
    shape: NDArray[np.int64],
) -> NDArray[np.bool_]:
    """Bool grid ``shape`` (3,): True where the closed voxel touches a closed block.

    Voxel ``i`` along an axis spans ``[origin + i v, origin + (i + 1) v]``, so it touches
    a block ``[lo, hi]`` when ``(lo - origin) / v - 1 <= i <= (hi - origin) / v``. Every
    block adds +-1 at the 8 corners of its index range in a difference array whose
    cumulative sum along the three axes counts the blocks touching each voxel.
    """
    first = np.ceil((blocks[:, :3] - origin) / voxel - 1 - _ROUNDING).astype(np.int64)
    last = np.floor((blocks[:, 3:] - origin) / voxel + _ROUNDING).astype(np.int64)
    first = np.maximum(first, 0)
    last = np.minimum(last, shape - 1)
    inside = np.all(first <= last, axis=1)
    first, stop = first[inside], last[inside] + 1
    counts = np.zeros(shape + 1, dtype=np.int32)
    for corner in np.ndindex(2, 2, 2):
        index = tuple(np.where(corner[axis], stop[:, axis], first[:, axis]) for axis in range(3))
        sign = -1 if sum(corner) % 2 else 1
        np.add.at(counts, index, sign)
    for axis in range(3):
        np.cumsum(counts, axis=axis, out=counts)
    return counts[:-1, :-1, :-1] > 0

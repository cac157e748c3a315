"""Conservative proofs that two points are connected, or disconnected, in free space.

:func:`connected` under-approximates free space; :func:`disconnected` over-approximates
it. Either answer is a proof when it is ``True``; ``False`` proves nothing.


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

from quadnav.arrays import FloatArray
from quadnav.profiling import staged
from quadnav.world.model import World, WorldMemo

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
    if not (world.is_free(points[0]) and world.is_free(points[1])):  # no threads for two
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


@staged("proof")
def disconnected(world: World, start: ArrayLike, goal: ArrayLike,
                 max_voxels: int = 1_000_000) -> bool:
    """Whether ``start`` and ``goal`` are provably in different parts of free space.

    Pass the world already inflated by the safety margin, and free points. The boundary
    box is cut into at most ``max_voxels`` voxels; a voxel is *blocked* when its closed box
    lies inside one closed block, so it holds no free point. Any free path crosses a chain
    of unblocked voxels that share a face, edge or corner; when the start's and goal's
    voxels are in different 26-connected components of unblocked voxels, no such chain and
    so no path exists: ``True`` is a proof. ``False`` proves nothing. The components of a
    world are labelled once (:func:`unblocked_components`).
    """
    points = np.array([start, goal], dtype=np.float64)
    labels, voxel = unblocked_components(world, max_voxels)
    shape = np.array(labels.shape)
    cells = np.clip(np.floor((points - world.lower) / voxel), 0, shape - 1).astype(np.int64)
    start_label, goal_label = labels[tuple(cells[0])], labels[tuple(cells[1])]
    return bool(start_label and goal_label and start_label != goal_label)


#: The components :func:`unblocked_components` labelled, by world and voxel budget.
_COMPONENTS: WorldMemo[int, tuple[NDArray[np.int32], FloatArray]] = WorldMemo()


def unblocked_components(world: World, max_voxels: int) -> tuple[NDArray[np.int32],
                                                                   FloatArray]:
    """The 26-connected components of the unblocked voxels of ``world`` cut into at most
    ``max_voxels`` voxels (see :func:`disconnected`): a label per voxel (0: blocked), and
    the voxel's size (3,), m. Labelled once per world while it lives (a world is
    immutable): the missions of a batch on one map and margin share them."""
    return _COMPONENTS.get(world, lambda: _labelled(world, max_voxels), max_voxels)


@staged("proof labels")
def _labelled(world: World, max_voxels: int) -> tuple[NDArray[np.int32], FloatArray]:
    """The components of :func:`unblocked_components`, labelled."""
    shape = np.maximum(np.ceil(world.extent / default_resolution(world.extent, max_voxels)
                               - _ROUNDING), 1).astype(np.int64)
    voxel = world.extent / shape
    # Voxel i is inside [lo, hi] when lo <= origin + i v and origin + (i + 1) v <= hi;
    # rounding shrinks the index range, so it can only leave more voxels unblocked.
    first = np.ceil((world.blocks[:, :3] - world.lower) / voxel + _ROUNDING)
    last = np.floor((world.blocks[:, 3:] - world.lower) / voxel - 1 - _ROUNDING)
    blocked = _covered(first.astype(np.int64), last.astype(np.int64), shape)
    labels, _ = ndimage.label(~blocked, structure=np.ones((3, 3, 3), dtype=bool))
    labels.flags.writeable = False
    return labels, voxel


def _occupied(
    blocks: NDArray[np.float64],
    origin: NDArray[np.float64],
    voxel: NDArray[np.float64],
    shape: NDArray[np.int64],
) -> NDArray[np.bool_]:
    """Bool grid ``shape`` (3,): True where the closed voxel touches a closed block.

    Voxel ``i`` along an axis spans ``[origin + i v, origin + (i + 1) v]``, so it touches
    a block ``[lo, hi]`` when ``(lo - origin) / v - 1 <= i <= (hi - origin) / v``.
    """
    first = np.ceil((blocks[:, :3] - origin) / voxel - 1 - _ROUNDING).astype(np.int64)
    last = np.floor((blocks[:, 3:] - origin) / voxel + _ROUNDING).astype(np.int64)
    return _covered(first, last, shape)


def _covered(first: NDArray[np.int64], last: NDArray[np.int64], shape: NDArray[np.int64]
             ) -> NDArray[np.bool_]:
    """Bool grid ``shape`` (3,): True in every voxel of some index box ``first..last``.

    ``first`` and ``last`` are (N, 3) inclusive index ranges, clipped here to the grid.
    Every box adds +-1 at the 8 corners of its range in a difference array whose
    cumulative sum along the three axes counts the boxes covering each voxel.
    """
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

"""The :class:`World`: a boundary box, box obstacles and, optionally, a start and goal.

Geometry conventions (see :mod:`quadnav.world.geometry`): free space is open — a
point on a block face or on the boundary is *not* free; boxes are rows
``(xmin, ymin, zmin, xmax, ymax, zmax)`` in metres, world frame z up.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Hashable
from dataclasses import dataclass, field
from functools import cached_property
from typing import Generic, TypeVar
from weakref import WeakKeyDictionary

import numpy as np
from numpy.typing import ArrayLike, NDArray

from quadnav.arrays import FloatArray, read_only
from quadnav.errors import QuadnavError
from quadnav.limits import MARGIN, MAX_BLOCKS, WORLD_COORDINATE
from quadnav.profiling import stage
from quadnav.world import blockgrid, geometry, volume

#: Boxes the exact free volume may visit (30-90 ns each) before it is estimated instead.
EXACT_BUDGET = 5_000_000
#: Uniform points of an estimated free volume (two standard errors: 0.32 % at most).
ESTIMATE_POINTS = 100_000
#: Seed of the estimate's points (not 0, which the layouts of many maps come from).
ESTIMATE_SEED = 7919
#: Colour given to blocks whose map file names none (RGB in [0, 1]).
DEFAULT_BLOCK_COLOR = (0.6, 0.6, 0.6)
#: Safety margin, metres, of a query on a map without a margin of its own; the margin
#: built-in worlds recommend and are proven flyable with.
DEFAULT_MARGIN = 0.2
#: Inflated worlds a world keeps, the last margins asked (:meth:`World.inflate`).
KEPT_INFLATIONS = 4


def _frozen(values: ArrayLike, shape: tuple[int, ...], what: str,
            low: float = WORLD_COORDINATE.low, high: float = WORLD_COORDINATE.high
            ) -> FloatArray:
    """A read-only float64 copy of ``values`` with the given shape (-1 = any), every
    value in ``[low, high]`` (by default :data:`~quadnav.limits.WORLD_COORDINATE`)."""
    try:
        array = np.array(values, dtype=np.float64)
    except (TypeError, ValueError, OverflowError):
        raise QuadnavError(f"{what} must be numbers") from None
    if array.size == 0 and shape[0] == -1:
        array = array.reshape((0, *shape[1:]))
    if array.ndim != len(shape) or any(
            s not in (-1, n) for s, n in zip(shape, array.shape, strict=True)):
        raise QuadnavError(f"{what} must have shape {shape}, got {array.shape}")
    if not np.all(np.isfinite(array)):
        raise QuadnavError(f"{what} must be finite")
    if not np.all((low <= array) & (array <= high)):
        raise QuadnavError(f"{what} must be from {low:g} to {high:g}")
    return read_only(array)


def _check_boxes(boxes: FloatArray, what: str) -> None:
    if np.any(boxes[..., :3] >= boxes[..., 3:]):
        raise QuadnavError(f"{what}: every min must be below its max")


@dataclass(frozen=True)
class FreeVolume:
    """The free fraction of a world's boundary volume (see :meth:`World.free_volume`).

    Attributes:
        fraction: free volume / boundary volume, in [0, 1].
        error: 0 when exact; else two standard errors of the Monte-Carlo estimate.
    """

    fraction: float
    error: float

    @property
    def exact(self) -> bool:
        """Whether the fraction is exact (up to rounding) rather than estimated."""
        return self.error == 0.0


@dataclass(frozen=True, eq=False)
class Hit:
    """The first contact of a segment with an obstacle.

    Attributes:
        t: fraction of the way along the segment, in [0, 1].
        point: the contact point (3,), metres.
        block: row of the block touched, or ``None`` for the boundary.
    """

    t: float
    point: FloatArray
    block: int | None


@dataclass(frozen=True, eq=False)
class World:
    """A 3D map of box obstacles.

    Attributes:
        boundary: (6,) ``xmin, ymin, zmin, xmax, ymax, zmax`` of the flyable box, metres.
        blocks: (N, 6) obstacle boxes in the same layout, metres.
        colors: (N, 3) block colours, RGB in [0, 1].
        start: (3,) default start position, or ``None``.
        goal: (3,) default goal position, or ``None``.
        margin: safety margin the map recommends, metres, or ``None``.
        name: where the world came from (a file path or built-in spec), for messages.
    """

    boundary: FloatArray
    blocks: FloatArray = field(default_factory=lambda: np.zeros((0, 6)))
    colors: FloatArray | None = None
    start: FloatArray | None = None
    goal: FloatArray | None = None
    margin: float | None = None
    name: str = "<world>"

    def __post_init__(self) -> None:
        """Check every value (QuadnavError): coordinates finite and within
        :data:`~quadnav.limits.WORLD_COORDINATE`, every min below its max, a boundary of
        positive volume, at most :data:`~quadnav.limits.MAX_BLOCKS` blocks, colours in
        [0, 1], a margin in :data:`~quadnav.limits.MARGIN`."""
        set_ = object.__setattr__
        set_(self, "boundary", _frozen(self.boundary, (6,), "boundary"))
        _check_boxes(self.boundary, "boundary")
        if not np.prod(self.extent) > 0:
            size = " x ".join(f"{e:g}" for e in self.extent)
            raise QuadnavError(f"boundary: a box of size {size} m has no volume")
        set_(self, "blocks", _frozen(self.blocks, (-1, 6), "blocks"))
        _check_boxes(self.blocks, "blocks")
        if len(self.blocks) > MAX_BLOCKS:
            raise QuadnavError(f"{len(self.blocks):,} blocks: expected at most {MAX_BLOCKS:,}")
        if self.colors is None:
            colors = np.tile(DEFAULT_BLOCK_COLOR, (len(self.blocks), 1))
        else:
            colors = self.colors
        set_(self, "colors", _frozen(colors, (len(self.blocks), 3), "colors", 0.0, 1.0))
        for name in ("start", "goal"):
            value = getattr(self, name)
            if value is not None:
                set_(self, name, _frozen(value, (3,), name))
        if self.margin is not None:
            set_(self, "margin", float(MARGIN.check(self.margin, "margin")))

    def __getstate__(self) -> dict[str, object]:
        """The fields and what was computed from them, but the inflated worlds kept
        (:meth:`inflate`), which a copy sent to a worker would carry for nothing."""
        return {name: value for name, value in self.__dict__.items() if name != "_inflated"}

    def __setstate__(self, state: dict[str, object]) -> None:
        """Restore an unpickled world (a batch worker's copy of a mission): numpy unpickles
        arrays writable, so the fields are made read-only again, as the constructor makes
        them. (Compiled queries are specialised on read-only arrays apart: a writable copy
        would compile them a second time.)"""
        names = {spec.name for spec in dataclasses.fields(self)}
        for name, value in state.items():
            if name in names and isinstance(value, np.ndarray):
                value = read_only(value)
            object.__setattr__(self, name, value)

    # ----------------------------------------------------------------- basics
    @property
    def lower(self) -> FloatArray:
        """(3,) lower corner of the boundary, metres."""
        return self.boundary[:3]

    @property
    def upper(self) -> FloatArray:
        """(3,) upper corner of the boundary, metres."""
        return self.boundary[3:]

    @property
    def extent(self) -> FloatArray:
        """(3,) size of the boundary box, metres."""
        return self.upper - self.lower

    def __len__(self) -> int:
        return len(self.blocks)

    @cached_property
    def _blocks_by_coordinate(self) -> FloatArray:
        """Blocks transposed to a C-contiguous (6, N) array for the kernels."""
        return np.ascontiguousarray(self.blocks.T)

    def replace(self, **changes: object) -> World:
        """A copy with some fields changed (see :func:`dataclasses.replace`)."""
        return dataclasses.replace(self, **changes)

    def margin_for(self, given: float | None = None) -> float:
        """The safety margin a query on this map keeps, m: ``given``, else the map's own,
        else :data:`DEFAULT_MARGIN` (the one rule of every command and the library)."""
        if given is not None:
            return given
        return self.margin if self.margin is not None else DEFAULT_MARGIN

    def inflate(self, margin: float) -> World:
        """A World whose blocks grow and whose boundary shrinks by ``margin`` metres.

        Each block grows by ``margin`` along every axis (the Minkowski sum with a cube,
        which contains the one with a ball), so every point within ``margin`` of an
        obstacle or of the boundary is outside the inflated world's free space.

        A world is immutable, so the inflated world of each of the last
        :data:`KEPT_INFLATIONS` margins asked is made once and kept, with what it computes
        once (its block grid): the missions of a batch on one map share them.
        """
        if not (np.isfinite(margin) and margin >= 0):
            raise ValueError(f"margin must be a finite number >= 0, got {margin}")
        kept = self._inflated
        if margin in kept:
            kept[margin] = kept.pop(margin)  # the most recently asked last
            return kept[margin]
        grow = np.array([-margin] * 3 + [margin] * 3)
        boundary = self.boundary - grow
        if np.any(boundary[:3] >= boundary[3:]):
            raise QuadnavError(
                f"{self.name}: margin {margin:g} m leaves no free space in a boundary of size "
                f"{' x '.join(f'{e:g}' for e in self.extent)} m"
            )
        with stage("inflated world"):
            kept[margin] = self.replace(boundary=boundary, blocks=self.blocks + grow)
        if len(kept) > KEPT_INFLATIONS:
            del kept[next(iter(kept))]
        return kept[margin]

    @cached_property
    def _inflated(self) -> dict[float, World]:
        """The inflated worlds :meth:`inflate` keeps, by margin, the oldest asked first."""
        return {}

    # ---------------------------------------------------------------- queries
    def points_free(self, points: ArrayLike) -> NDArray[np.bool_]:
        """Whether each point (N, 3) is in open free space -> bool (N,)."""
        pts = _points(points)
        return geometry.points_free(pts, self._blocks_by_coordinate, self.boundary)

    def is_free(self, point: ArrayLike) -> bool:
        """Whether one point (3,) is in open free space."""
        x, y, z = np.asarray(point, dtype=np.float64)
        return geometry.point_free(x, y, z, self._blocks_by_coordinate, self.boundary)

    @cached_property
    def block_grid(self) -> blockgrid.GridArrays:
        """The blocks sorted into a uniform grid, for fast segment checks (a
        :data:`~quadnav.world.blockgrid.GridArrays` tuple that compiled code takes)."""
        return blockgrid.build_block_grid(self)

    def segments_free(self, segments: ArrayLike) -> NDArray[np.bool_]:
        """Whether each closed segment (N, 2, 3) lies wholly in free space -> bool (N,)."""
        return blockgrid.grid_segments_free(_segments(segments), self.block_grid)

    def segment_free(self, start: ArrayLike, end: ArrayLike) -> bool:
        """Whether the closed segment start -> end (each (3,)) lies wholly in free space."""
        p = np.array(start, dtype=np.float64)
        q = np.array(end, dtype=np.float64)
        return blockgrid.grid_segment_free(p, q, self.block_grid)

    def clearances(self, points: ArrayLike) -> FloatArray:
        """Signed clearance (N,) of points (N, 3), metres.

        Positive in free space: the distance to the nearest block surface or boundary
        face. Zero on a surface; negative inside a block or outside the boundary.
        """
        pts = _points(points)
        return geometry.clearances(pts, self._blocks_by_coordinate, self.boundary)

    def clearance(self, point: ArrayLike) -> float:
        """Signed clearance of one point (3,), metres (see :meth:`clearances`)."""
        return float(self.clearances(np.reshape(point, (1, 3)))[0])

    def first_hits(self, segments: ArrayLike) -> tuple[FloatArray, NDArray[np.int64]]:
        """First contact along each segment (N, 2, 3).

        Returns ``(t, index)``, both (N,): ``t`` in [0, 1] is the fraction along the
        segment, ``index`` the block row, :data:`~quadnav.world.geometry.HIT_BOUNDARY`
        for the boundary, or :data:`~quadnav.world.geometry.NO_HIT` (with ``t = inf``)
        for a segment that stays free.
        """
        segs = _segments(segments)
        return geometry.first_hits(segs, self._blocks_by_coordinate, self.boundary)

    def first_hit(self, start: ArrayLike, end: ArrayLike) -> Hit | None:
        """The first contact along start -> end, or ``None`` if the segment is free."""
        p, q = np.asarray(start, dtype=np.float64), np.asarray(end, dtype=np.float64)
        ts, index = self.first_hits(np.stack([p, q])[None])
        if index[0] == geometry.NO_HIT:
            return None
        t = float(ts[0])
        block = None if index[0] == geometry.HIT_BOUNDARY else int(index[0])
        return Hit(t=t, point=p + t * (q - p), block=block)

    def blocks_containing(self, point: ArrayLike) -> NDArray[np.int64]:
        """Rows of every closed block that contains the point (3,)."""
        p = np.asarray(point, dtype=np.float64)
        inside = np.all((self.blocks[:, :3] <= p) & (p <= self.blocks[:, 3:]), axis=1)
        return np.flatnonzero(inside)

    def in_boundary(self, point: ArrayLike) -> bool:
        """Whether the point (3,) lies in the closed boundary box."""
        p = np.asarray(point, dtype=np.float64)
        return bool(np.all((self.lower <= p) & (p <= self.upper)))

    def free_volume(self, budget: int = EXACT_BUDGET) -> FreeVolume:
        """The fraction of the boundary volume not covered by blocks (overlaps once).

        Exact (:func:`~quadnav.world.volume.union_volume`, ``O(N^1.5 log N)`` for N
        blocks) unless that would visit more than ``budget`` boxes, which at 100,000
        blocks happens only for contrived layouts such as long thin sticks along all
        three axes; then estimated from :data:`ESTIMATE_POINTS` uniform points (seeded,
        so the same every time), with two standard errors as the stated error. Either
        way well under a second for 100,000 blocks.
        """
        occupied = volume.union_volume(self.blocks, self.boundary, budget)
        if np.isfinite(occupied):
            return FreeVolume(1.0 - occupied / float(np.prod(self.extent)), 0.0)
        rng = np.random.default_rng(ESTIMATE_SEED)
        points = rng.uniform(self.lower, self.upper, (ESTIMATE_POINTS, 3))
        fraction = float(np.mean(blockgrid.grid_points_free(points, self.block_grid)))
        spread = max(fraction * (1.0 - fraction), 1.0 / ESTIMATE_POINTS)
        return FreeVolume(fraction, 2.0 * float(np.sqrt(spread / ESTIMATE_POINTS)))

    def free_volume_fraction(self) -> float:
        """The fraction of :meth:`free_volume` (exact but for contrived maps)."""
        return self.free_volume().fraction

    def sample_free(self, n: int, seed: int | np.random.Generator | None = 0) -> FloatArray:
        """``n`` points (n, 3) drawn uniformly from free space, reproducibly by ``seed``."""
        rng = np.random.default_rng(seed)
        found: list[FloatArray] = []
        count = 0
        batch = max(64, 2 * n)
        for _ in range(1000):
            candidates = rng.uniform(self.lower, self.upper, size=(batch, 3))
            free = candidates[self.points_free(candidates)]
            found.append(free)
            count += len(free)
            if count >= n:
                return np.concatenate(found)[:n]
        raise ValueError(f"{self.name}: found only {count} free points in {1000 * batch} draws")


def _compiled_input(values: ArrayLike) -> FloatArray:
    """``values`` as a C-contiguous, writable float64 array (copied only when it is not):
    compiled code is specialised on read-only arrays apart, so one kind is passed."""
    return np.require(values, dtype=np.float64, requirements=["C", "W"])


def _points(points: ArrayLike) -> FloatArray:
    pts = _compiled_input(points)
    if pts.ndim != 2 or pts.shape[1] != 3:
        raise ValueError(f"points must have shape (N, 3), got {pts.shape}")
    return pts


def _segments(segments: ArrayLike) -> FloatArray:
    segs = _compiled_input(segments)
    if segs.ndim != 3 or segs.shape[1:] != (2, 3):
        raise ValueError(f"segments must have shape (N, 2, 3), got {segs.shape}")
    return segs


Key = TypeVar("Key", bound=Hashable)
Value = TypeVar("Value")


class WorldMemo(Generic[Key, Value]):
    """Values made from a world once per key (say a radius or a voxel budget) and kept
    while the world lives: a world is immutable, so the missions of a batch on one map
    share them."""

    def __init__(self) -> None:
        self._kept: WeakKeyDictionary[World, dict[Key, Value]] = WeakKeyDictionary()

    def get(self, world: World, make: Callable[[], Value], key: Key | None = None) -> Value:
        """The value kept for ``world`` and ``key``, made by ``make()`` the first time."""
        kept = self._kept.setdefault(world, {})
        if key not in kept:
            kept[key] = make()
        return kept[key]

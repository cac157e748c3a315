"""The geofence: where a commanded drone may go, with quadnav's exact box geometry.

Inside the fence means in the free space of the map inflated by the margin: strictly
inside the boundary shrunk by the margin, and outside every block grown by it (see
:meth:`quadnav.world.World.inflate`). Segments are checked exactly (a slab test, no
sampling). The only way below the fence's floor is a vertical *column* — the climb
after takeoff or the descent to land — which must still keep the margin from every
block and the boundary's walls.

A :class:`Region` is any such space with its checks; the :class:`Geofence` is one, and
the room of a start's or goal's leg (:mod:`quadnav.hardware.bridge.leg_room`) is another.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike

from quadnav.arrays import FloatArray
from quadnav.errors import QuadnavError
from quadnav.hardware.bridge.frames import GROUND_Z
from quadnav.world.model import Hit, World
from quadnav.world.placement import format_box, format_point

#: How far below the ground a column's floor lies, m, so that the ground itself is free.
_GROUND_SLACK = 1e-9


class GeofenceError(QuadnavError):
    """A command that would take the drone out of the geofence; nothing was sent."""


class Region:
    """Where the drone may go: the free space of :attr:`free_world`, checked exactly.

    Subclasses give :attr:`world` (the map as read), :attr:`free_world`, :attr:`name`
    (for messages) and :meth:`kept` (the distance kept from what a move hit).
    """

    world: World
    name: str

    @cached_property
    def free_world(self) -> World:
        """The world whose free space is the region."""
        raise NotImplementedError

    def kept(self, hit: Hit | None) -> float:
        """Metres the region keeps from what ``hit`` hit (None: the boundary)."""
        raise NotImplementedError

    @cached_property
    def _column_world(self) -> World:
        """:attr:`free_world` with its floor lowered to just below the ground (so the
        ground itself is free, and nothing under it), for columns."""
        boundary = self.free_world.boundary.copy()
        boundary[2] = min(GROUND_Z, self.world.lower[2]) - _GROUND_SLACK
        return self.free_world.replace(boundary=boundary)

    def contains(self, points: ArrayLike) -> np.ndarray:
        """Whether each point (N, 3), m, is inside the region -> bool (N,)."""
        return self.free_world.points_free(np.reshape(points, (-1, 3)))

    def point_ok(self, point: ArrayLike) -> bool:
        """Whether one point (3,), m, is inside the region."""
        return self.free_world.is_free(point)

    def segment_ok(self, start: ArrayLike, end: ArrayLike) -> bool:
        """Whether the straight move start -> end (each (3,), m) stays inside the region."""
        return self.free_world.segment_free(start, end)

    def column_ok(self, low: ArrayLike, high: ArrayLike) -> bool:
        """Whether the vertical move between ``low`` and ``high`` (each (3,), m, same x
        and y) stays inside the region, its floor aside."""
        low, high = np.asarray(low, dtype=np.float64), np.asarray(high, dtype=np.float64)
        return bool(np.array_equal(low[:2], high[:2])
                    and self._column_world.segment_free(low, high))

    def check_column(self, low: ArrayLike, high: ArrayLike, what: str) -> None:
        """Raise :class:`GeofenceError` unless :meth:`column_ok`; ``what`` names the move."""
        if not self.column_ok(low, high):
            raise GeofenceError(self._refusal(self._column_world, low, high, what))

    def check_track(self, points: ArrayLike, what: str) -> None:
        """Raise :class:`GeofenceError` unless every segment between consecutive points
        (N, 3), m, stays inside the region (a densely sampled trajectory, say)."""
        pts = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        free = self.free_world.segments_free(np.stack([pts[:-1], pts[1:]], axis=1))
        if not free.all():
            bad = int(np.flatnonzero(~free)[0])
            raise GeofenceError(self._refusal(self.free_world, pts[bad], pts[bad + 1], what))

    def _refusal(self, fence: World, start: ArrayLike, end: ArrayLike, what: str) -> str:
        """One line: which move leaves the region, where, and through what."""
        start = np.asarray(start, dtype=np.float64)
        end = np.asarray(end, dtype=np.float64)
        hit = fence.first_hit(start, end)
        where: FloatArray = start if hit is None else hit.point
        through = ("the boundary" if hit is None or hit.block is None
                   else f"block {hit.block} {format_box(self.world.blocks[hit.block])}")
        kept = self.kept(hit)
        near = f"comes within {kept:g} m of" if kept > 0 else "goes outside"
        return (f"geofence: {what} from {format_point(start)} to {format_point(end)} {near} "
                f"{through} at {format_point(where)}; nothing was sent")


@dataclass(frozen=True, eq=False)
class Geofence(Region):
    """The map's free space shrunk by ``margin``.

    Attributes:
        world: the map as read, blocks not inflated.
        margin: distance kept from every block and boundary face, metres.
    """

    world: World
    margin: float
    name = "the geofence"

    @cached_property
    def free_world(self) -> World:
        """The map inflated by the margin: its free space is the inside of the fence."""
        return self.world.inflate(self.margin)

    def kept(self, hit: Hit | None) -> float:
        """The margin, from blocks and boundary alike."""
        return self.margin

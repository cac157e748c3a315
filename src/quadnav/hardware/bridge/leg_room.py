"""The room of a leg: where the Tello may come closer than the geofence's margin.

A start (or goal) inside the safety margin is left (or entered) by the planner's *leg*
(:mod:`quadnav.planning.legs`), the only part of a flight allowed inside the margin. On a
Tello the leg is joined to the floor by a vertical column: the takeoff under the start,
the climb or descent to the leg (and, at the goal, the descent to land). These, the leg
and every ``go`` move or trajectory stretch that stands in for them stay in the leg's
*room*, :class:`LegRoom`, checked exactly like the fence:

* outside every block grown by the leg's clearance — the start's own per-axis distance to
  the blocks less the planner's sliver (:data:`~quadnav.planning.legs.
  LEG_CLEARANCE_SLIVER`), at most the margin — as the planner's legs are;
* inside the closed boundary where the leg lies in a face's margin (as the planner's legs
  may run along the boundary), inside the boundary shrunk by the margin at the faces whose
  margin the leg keeps.

So nothing there comes closer to a block than the start itself does, nor goes outside the
boundary, and a wall is approached only where the leg must; where the start is free of
the margin the room is the fence. The columns may pass the floor's margin down to the
ground, as in the fence.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from quadnav.arrays import FloatArray
from quadnav.hardware.bridge.geofence import Geofence, Region
from quadnav.planning.legs import BOUNDARY_SLACK, own_clearance
from quadnav.world.model import Hit, World


@dataclass(frozen=True, eq=False)
class LegRoom(Region):
    """The room of the leg ``leg`` within ``fence`` (see the module's description).

    Attributes:
        fence: the geofence; its margin caps every distance kept.
        leg: (K, 3) the planner's leg, the start (or goal) first, m; just the point (1, 3)
            when it is free.
        label: ``"start"`` or ``"goal"``, for messages.
    """

    fence: Geofence
    leg: FloatArray
    label: str

    @property
    def world(self) -> World:
        """The map as read."""
        return self.fence.world

    @property
    def name(self) -> str:
        """The room, in words."""
        return f"the room of the {self.label} leg"

    @cached_property
    def clearance(self) -> float:
        """Metres kept from every block: the point's own per-axis distance to the blocks
        less the sliver (and a nanometre, for rounding errors), at most the margin."""
        return min(self.fence.margin, own_clearance(self.world, self.leg[0]) - BOUNDARY_SLACK)

    @cached_property
    def face_room(self) -> FloatArray:
        """(6,) metres kept from each boundary face (xmin, ymin, zmin, xmax, ymax, zmax):
        the margin where the whole leg keeps it, else none (``-1e-9``: a point on the
        face is inside)."""
        leg, inner = np.asarray(self.leg, dtype=np.float64), self.fence.free_world
        entered = np.concatenate([leg.min(axis=0) <= inner.lower,
                                  leg.max(axis=0) >= inner.upper])
        return np.where(entered, -BOUNDARY_SLACK, self.fence.margin)

    @cached_property
    def free_world(self) -> World:
        """The map with its blocks grown by :attr:`clearance` and its boundary shrunk by
        :attr:`face_room`: its free space is the room."""
        grow = np.repeat([-self.clearance, self.clearance], 3)
        room = self.face_room
        return self.world.replace(blocks=self.world.blocks + grow,
                                  boundary=self.world.boundary
                                  + np.concatenate([room[:3], -room[3:]]))

    def kept(self, hit: Hit | None) -> float:
        """The clearance from a block, or the room kept from the boundary face nearest
        the hit."""
        if hit is not None and hit.block is not None:
            return self.clearance
        if hit is None:
            return float(self.face_room.min())
        faces = np.abs(np.concatenate([hit.point, hit.point]) - self.free_world.boundary)
        return float(self.face_room[int(np.argmin(faces))])

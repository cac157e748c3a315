"""Where a trajectory may go, and the margin it keeps, measured exactly.

A :class:`SafeSpace` is a map and a safety margin. A path through it has two parts:

* the **legs**: where a start or goal lies inside the margin (on the boundary, or near a
  block), the first waypoints, up to the first one that keeps the margin, are the leg out
  of it, and the last ones the leg into the goal. Only the legs may come closer than the
  margin; they may not touch a block nor leave the boundary;
* the **rest**, which keeps the whole margin: every segment is free in the map inflated by
  the margin.

:func:`trajectory_margins` measures the margin a trajectory keeps, on and off the legs,
exactly: each stretch between two check samples is enclosed in the bounding box of its
Bernstein coefficients (a polynomial lies in the convex hull of them), and the box's
per-axis clearance from every real block and the boundary
(:func:`~quadnav.world.margins.box_margins`) bounds the stretch's from below.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from weakref import WeakKeyDictionary

import numpy as np
from numpy.typing import ArrayLike
from scipy.interpolate import BPoly, PPoly

from quadnav.arrays import FloatArray
from quadnav.errors import QuadnavError
from quadnav.planning.legs import leg_world
from quadnav.trajectory.clearance.collision import check_samples
from quadnav.trajectory.model import Trajectory
from quadnav.trajectory.references.plain import FlatOutputReference
from quadnav.world.margins import box_margins, rounded, segment_box_margins
from quadnav.world.model import World, WorldMemo
from quadnav.world.placement import format_point

#: :attr:`SafeSpace.legs_world` of each map.
_LEGS_WORLDS: WorldMemo[None, World] = WorldMemo()


@dataclass(frozen=True, eq=False)
class SafeSpace:
    """A map and the safety margin a trajectory through it keeps outside the legs.

    Attributes:
        world: the real map, blocks not inflated.
        margin: safety margin, metres, >= 0.
    """

    world: World
    margin: float

    @cached_property
    def inflated(self) -> World:
        """The map inflated by the margin: everything but the legs stays in its free space."""
        return self.world.inflate(self.margin)

    @property
    def legs_world(self) -> World:
        """Where legs may go: off every real block, inside the closed boundary (made once
        per map while it lives, with its block grid: the trajectories of a batch on one
        map share it)."""
        return _LEGS_WORLDS.get(self.world, lambda: leg_world(self.world))

    def split(self, waypoints: ArrayLike) -> tuple[int, int]:
        """``(head, tail)``: ``waypoints[:head + 1]`` is the start leg and
        ``waypoints[tail:]`` the goal leg of a path (N, 3) (``head == 0``, ``tail == N - 1``
        without legs). QuadnavError when a leg touches a block or leaves the boundary, or
        a segment between the legs comes closer than the margin."""
        points = np.asarray(waypoints, dtype=np.float64).reshape(-1, 3)
        keeps = np.flatnonzero(self.inflated.points_free(points))
        if keeps.size == 0:
            raise QuadnavError(f"no waypoint of the path keeps the {self.margin:g} m margin "
                               f"in {self.world.name}; a path must leave the margin")
        head, tail = int(keeps[0]), int(keeps[-1])
        segments = np.stack([points[:-1], points[1:]], axis=1)
        on_leg = np.zeros(len(segments), dtype=bool)
        on_leg[:head] = on_leg[tail:] = True
        for rows, world, where in ((np.arange(len(segments)), self.legs_world,
                                    "touches a block or leaves the boundary"),
                                   (np.flatnonzero(~on_leg), self.inflated,
                                    f"comes within the {self.margin:g} m margin of an "
                                    "obstacle, and is not a leg out of it")):
            blocked = rows[~world.segments_free(segments[rows])] if rows.size else rows
            if blocked.size:
                bad = int(blocked[0])
                raise QuadnavError(f"path segment {bad} from {format_point(points[bad])} to "
                                   f"{format_point(points[bad + 1])} {where}")
        return head, tail


def stretch_boxes(trajectory: Trajectory, t: FloatArray) -> FloatArray:
    """Boxes (K - 1, 6) enclosing the trajectory between consecutive times ``t`` (K,),
    ascending, the breaks among them: the bounding boxes of each stretch's Bernstein
    coefficients."""
    order = trajectory.poly.c.shape[0] - 1
    derivatives = [trajectory.poly]
    for _ in range(order):
        derivatives.append(derivatives[-1].derivative())
    factorials = np.cumprod([1.0, *range(1, order + 1)])
    local = np.stack([derivatives[j](t[:-1]) / factorials[j] for j in range(order, -1, -1)])
    bernstein = BPoly.from_power_basis(PPoly(local, t)).c  # (order + 1, K - 1, 3)
    return np.concatenate([bernstein.min(axis=0), bernstein.max(axis=0)], axis=1)


def trajectory_margins(trajectory: Trajectory, world: World, spacing: float = 0.005
                       ) -> tuple[float, float | None]:
    """The margin (per axis, metres) the trajectory keeps from the real blocks and the
    boundary of ``world``, measured exactly (see the module docstring), ``(off the legs,
    on the legs)``; the second is None without legs.

    The stretches measured are the check samples of
    :func:`~quadnav.trajectory.clearance.collision.check_samples`, at most ``spacing`` metres apart;
    the bound is below the true margin by about the stretches' bend, under 0.5 mm at the
    default 5 mm. Values are rounded as by :func:`windowed_margins`.
    """
    t, _ = check_samples(trajectory, spacing)
    margins = box_margins(world, stretch_boxes(trajectory, t))
    return windowed_margins(t, margins, trajectory.main_window)


#: The margins :func:`reference_margins` measured, by reference and world.
_MEASURED: WeakKeyDictionary[Trajectory | FlatOutputReference,
                             WeakKeyDictionary[World, tuple[float, float | None]]] = (
    WeakKeyDictionary())


def reference_margins(reference: Trajectory | FlatOutputReference, world: World
                      ) -> tuple[float, float | None]:
    """The margin (per axis, m) ``reference`` keeps from the real blocks and the boundary of
    ``world``, ``(off the legs, on the legs)`` (:meth:`main_window`): a
    :class:`~quadnav.trajectory.model.Trajectory` by :func:`trajectory_margins`; a
    trajectory class's samples
    (:class:`~quadnav.trajectory.references.plain.FlatOutputReference`, what the closed
    loop flies, at the control rate) taken as straight between consecutive samples, each
    stretch measured by its bounding box, as a flight's track is. Measured once for a
    reference and a world while both live (both are immutable): the missions of a batch
    that fly one trajectory share it."""
    measured = _MEASURED.setdefault(reference, WeakKeyDictionary())
    if world not in measured:
        if isinstance(reference, Trajectory):
            measured[world] = trajectory_margins(reference, world)
        else:
            samples = reference.samples
            measured[world] = windowed_margins(
                samples.t, segment_box_margins(world, samples.position),
                reference.main_window)
    return measured[world]


def within_window(t: FloatArray, window: tuple[float, float]) -> np.ndarray:
    """(K - 1,) whether each stretch between times ``t`` (K,) s lies wholly within
    ``window`` (begin, end) s."""
    return (t[:-1] >= window[0]) & (t[1:] <= window[1])


def windowed_margins(t: FloatArray, margins: FloatArray, window: tuple[float, float]
                     ) -> tuple[float, float | None]:
    """The least of the margins (K - 1,) m of the stretches between times ``t`` (K,) s,
    ``(of those wholly within window, of the others)``, rounded to the nanometre
    (:func:`~quadnav.world.margins.rounded`; a leg from the boundary keeps 0, not a
    rounding error below it); ``inf`` for none within, None for no others."""
    within = within_window(t, window)
    off = rounded(margins[within].min()) if within.any() else float("inf")
    return off, rounded(margins[~within].min()) if (~within).any() else None

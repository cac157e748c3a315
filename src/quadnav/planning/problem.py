"""A planning query: a world, a safety margin, a start and a goal, checked and prepared.

:func:`make_problem` turns what the user gave into a :class:`PlanningProblem`:

* a start or goal outside the boundary or inside a real block is an error naming it;
* one inside the safety margin (on the boundary, or close to a block) is usable: the
  path leaves the margin by a short straight *leg* to the nearest free point found (the
  leg avoids every real block) and a :class:`~quadnav.errors.PlanningWarning` says so;
* a start and goal provably in different parts of free space are an error, found fast.

Planners search the inflated world between :attr:`PlanningProblem.search_start` and
:attr:`PlanningProblem.search_goal`; :meth:`PlanningProblem.full_path` adds the legs.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from quadnav.errors import PlanningWarning, QuadnavError
from quadnav.world.connectivity import disconnected
from quadnav.world.model import FloatArray, World
from quadnav.world.placement import classify_point, format_point

#: How far past a margin face a leg ends, metres, so its end is strictly free.
LEG_CLEARANCE = 1e-6
#: Rounds of face projection tried when leaving overlapping margins.
_LEG_DEPTH = 3


@dataclass(frozen=True, eq=False)
class PlanningProblem:
    """A checked planning query.

    Attributes:
        world: the map as read, blocks not inflated.
        margin: safety margin, metres.
        free_world: ``world`` inflated by ``margin``; planners search its free space.
        start: (3,) where the path starts, metres, exactly as given.
        goal: (3,) where the path ends, metres, exactly as given.
        search_start: (3,) free point where the search starts (``start`` when it is free).
        search_goal: (3,) free point where the search ends (``goal`` when it is free).
    """

    world: World
    margin: float
    free_world: World
    start: FloatArray
    goal: FloatArray
    search_start: FloatArray
    search_goal: FloatArray

    def full_path(self, search_path: ArrayLike) -> FloatArray:
        """The path (N, 3) from ``start`` to ``goal`` around a ``search_path`` (M, 3)
        that runs from ``search_start`` to ``search_goal``: the legs are added."""
        points = [np.asarray(search_path, dtype=np.float64).reshape(-1, 3)]
        if not np.array_equal(self.start, self.search_start):
            points.insert(0, self.start[None])
        if not np.array_equal(self.goal, self.search_goal):
            points.append(self.goal[None])
        return np.concatenate(points)


def make_problem(world: World, start: ArrayLike | None, goal: ArrayLike | None,
                 margin: float) -> PlanningProblem:
    """Check a query and prepare it for planners; raises QuadnavError for bad input.

    Args:
        world: the map, blocks not inflated.
        start: (3,) metres, or ``None`` for the map's own start.
        goal: (3,) metres, or ``None`` for the map's own goal.
        margin: safety margin, metres, >= 0.
    """
    free_world = world.inflate(margin)
    ends = []
    for label, point, own in (("start", start, world.start), ("goal", goal, world.goal)):
        if point is None:
            point = own
        if point is None:
            raise QuadnavError(f"{world.name}: the map has no {label}; give --{label} X Y Z")
        report = classify_point(world, point, margin, label)
        if not report.usable:
            verb = "start" if label == "start" else "end"
            raise QuadnavError(f"{report}; a path must {verb} in free space")
        ends.append((report.point, _leave_margin(world, free_world, report.point, label)))
    (start_point, search_start), (goal_point, search_goal) = ends
    if disconnected(free_world, search_start, search_goal):
        raise QuadnavError(
            f"{world.name}: start {format_point(start_point)} and goal "
            f"{format_point(goal_point)} are disconnected with a {margin:g} m margin: "
            "no path exists")
    return PlanningProblem(world, float(margin), free_world, start_point, goal_point,
                           search_start, search_goal)


def _leave_margin(world: World, free_world: World, point: FloatArray, label: str
                  ) -> FloatArray:
    """The nearest free point found by a straight leg from ``point`` that avoids real
    blocks (``point`` itself when free); warns when a leg is needed."""
    if free_world.is_free(point):
        return point
    # The leg may run along the boundary where the point itself lies on it.
    blocks_only = world.replace(boundary=world.boundary + np.repeat([-1.0, 1.0], 3))
    exits = [c for c in _margin_exits(free_world, point)
             if blocks_only.segment_free(point, c)]
    if not exits:
        raise QuadnavError(
            f"{label} {format_point(point)} is inside the safety margin and no straight way "
            "out of it avoids the blocks; move it or lower --margin")
    exit_point = min(exits, key=lambda c: float(np.linalg.norm(c - point)))
    warnings.warn(
        f"{label} {format_point(point)} is inside the safety margin; the path leaves it "
        f"by a straight {np.linalg.norm(exit_point - point):.3g} m leg to "
        f"{format_point(exit_point)}", PlanningWarning, stacklevel=3)
    return exit_point


def _margin_exits(free_world: World, point: FloatArray) -> list[FloatArray]:
    """Free points reached from ``point`` by moving straight out of the inflated blocks
    and boundary that hold it: each round projects every candidate still not free onto
    the faces of what holds it, up to :data:`_LEG_DEPTH` rounds."""
    inner_lower = free_world.lower + LEG_CLEARANCE
    inner_upper = free_world.upper - LEG_CLEARANCE
    found: list[FloatArray] = []
    frontier = [point]
    for _ in range(_LEG_DEPTH):
        moved: list[FloatArray] = []
        for candidate in frontier:
            clamped = np.clip(candidate, inner_lower, inner_upper)
            if not np.array_equal(clamped, candidate):
                moved.append(clamped)
            for row in free_world.blocks_containing(candidate):
                box = free_world.blocks[row]
                for axis in range(3):
                    for face, push in ((box[axis], -LEG_CLEARANCE),
                                       (box[axis + 3], LEG_CLEARANCE)):
                        projected = candidate.copy()
                        projected[axis] = face + push
                        moved.append(projected)
        free = free_world.points_free(moved) if moved else np.zeros(0, dtype=bool)
        found.extend(m for m, ok in zip(moved, free, strict=True) if ok)
        frontier = [m for m, ok in zip(moved, free, strict=True) if not ok]
    return found

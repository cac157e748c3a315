"""A planning query: a world, a safety margin, a start and a goal, checked and prepared.

:func:`make_problem` turns what the user gave into a :class:`PlanningProblem`:

* a start or goal outside the boundary or inside a real block is an error naming it, and
  so is a start equal to the goal;
* one inside the safety margin (on the boundary, or close to a block) is usable: the
  path leaves the margin by a short *leg* (:mod:`quadnav.planning.legs`), the only part
  of the flight allowed inside the margin, and a :class:`~quadnav.errors.PlanningWarning`
  says so;
* a start and goal provably in different parts of free space are an error, found fast.

Planners search the inflated world between :attr:`PlanningProblem.search_start` and
:attr:`PlanningProblem.search_goal`; :meth:`PlanningProblem.full_path` adds the legs.
Every entry point (``plan``, ``fly``, ``traj``, ``kino``, ``tello fly``) checks its query
here, so they accept and refuse the same starts and goals.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from quadnav.arrays import FloatArray
from quadnav.errors import PlanningWarning, QuadnavError
from quadnav.planning.legs import find_leg
from quadnav.planning.result import path_length
from quadnav.world.connectivity import disconnected
from quadnav.world.model import World
from quadnav.world.placement import classify_point, format_point


@dataclass(frozen=True, eq=False)
class PlanningProblem:
    """A checked planning query.

    Attributes:
        world: the map as read, blocks not inflated.
        margin: safety margin, metres.
        free_world: ``world`` inflated by ``margin``; planners search its free space.
        start_leg: (K, 3) polyline from the start, exactly as given, out of the margin to
            :attr:`search_start`; just the start (1, 3) when it is free.
        goal_leg: (K, 3) polyline from :attr:`search_goal` into the margin to the goal,
            exactly as given; just the goal (1, 3) when it is free.
    """

    world: World
    margin: float
    free_world: World
    start_leg: FloatArray
    goal_leg: FloatArray

    def __post_init__(self) -> None:
        for name in ("start_leg", "goal_leg"):
            leg = np.array(getattr(self, name), dtype=np.float64).reshape(-1, 3)
            leg.flags.writeable = False
            object.__setattr__(self, name, leg)

    @classmethod
    def free(cls, world: World, free_world: World, start: ArrayLike, goal: ArrayLike,
             margin: float = 0.0) -> PlanningProblem:
        """A query between two points already free in ``free_world`` (no legs)."""
        return cls(world, margin, free_world, np.reshape(start, (1, 3)),
                   np.reshape(goal, (1, 3)))

    @property
    def start(self) -> FloatArray:
        """(3,) where the path starts, metres."""
        return self.start_leg[0]

    @property
    def goal(self) -> FloatArray:
        """(3,) where the path ends, metres."""
        return self.goal_leg[-1]

    @property
    def search_start(self) -> FloatArray:
        """(3,) free point where the search starts (``start`` when it is free)."""
        return self.start_leg[-1]

    @property
    def search_goal(self) -> FloatArray:
        """(3,) free point where the search ends (``goal`` when it is free)."""
        return self.goal_leg[0]

    def full_path(self, search_path: ArrayLike) -> FloatArray:
        """The path (N, 3) from ``start`` to ``goal`` around a ``search_path`` (M, 3)
        that runs from ``search_start`` to ``search_goal``: the legs are added."""
        search = np.asarray(search_path, dtype=np.float64).reshape(-1, 3)
        return np.concatenate([self.start_leg[:-1], search, self.goal_leg[1:]])

    def search_part(self, path: ArrayLike) -> FloatArray:
        """The part (M, 3) of a full path (N, 3) from ``search_start`` to ``search_goal``;
        QuadnavError unless the path has exactly the legs :meth:`full_path` adds."""
        points = np.asarray(path, dtype=np.float64).reshape(-1, 3)
        head, tail = len(self.start_leg) - 1, len(self.goal_leg) - 1
        if len(points) < head + tail + 1:
            raise QuadnavError(f"a path of {len(points)} points cannot hold the legs out "
                               "of the safety margin")
        if not (np.array_equal(points[:head + 1], self.start_leg)
                and np.array_equal(points[len(points) - tail - 1:], self.goal_leg)):
            raise QuadnavError("the path does not begin with the problem's start leg and "
                               "end with its goal leg (from "
                               f"{format_point(self.start)} to {format_point(self.goal)})")
        return points[head:len(points) - tail]


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
    reports = []
    for label, point, own in (("start", start, world.start), ("goal", goal, world.goal)):
        if point is None:
            point = own
        if point is None:
            raise QuadnavError(f"{world.name}: the map has no {label}; give --{label} X Y Z")
        report = classify_point(world, point, margin, label)
        if not report.usable:
            verb = "start" if label == "start" else "end"
            raise QuadnavError(f"{report}; a path must {verb} in free space")
        reports.append(report)
    start_point, goal_point = (report.point for report in reports)
    if np.array_equal(start_point, goal_point):
        raise QuadnavError(f"start and goal are the same point {format_point(start_point)}: "
                           "there is nothing to fly; give a different --goal")
    start_leg = find_leg(world, free_world, start_point, margin, "start")
    goal_leg = find_leg(world, free_world, goal_point, margin, "goal")[::-1]
    for label, leg in (("start", start_leg), ("goal", goal_leg[::-1])):
        if len(leg) > 1:
            _warn_leg(label, leg, margin)
    problem = PlanningProblem(world, float(margin), free_world, start_leg, goal_leg)
    if disconnected(free_world, problem.search_start, problem.search_goal):
        raise QuadnavError(
            f"{world.name}: start {format_point(start_point)} and goal "
            f"{format_point(goal_point)} are disconnected with a {margin:g} m margin: "
            "no path exists")
    return problem


def _warn_leg(label: str, leg: FloatArray, margin: float) -> None:
    """Say that the point ``leg[0]`` lies in the margin and how the leg leaves it."""
    shape = "straight" if len(leg) == 2 else f"{len(leg) - 1}-segment"
    warnings.warn(
        f"{label} {format_point(leg[0])} is inside the {margin:g} m safety margin; "
        f"only the {shape} {path_length(leg):.3g} m leg "
        f"{'out of it, to' if label == 'start' else 'into it, from'} {format_point(leg[-1])}, "
        f"may come closer; the rest of the flight keeps {margin:g} m", PlanningWarning,
        stacklevel=3)

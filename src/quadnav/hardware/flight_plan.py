"""What the Tello will fly, planned and checked before anything is sent.

:func:`plan_flight` plans like ``quadnav fly`` (the same query check, planner, shortcut
and smoothing, trajectory generator and settings), then shapes the result for a drone
that starts and ends on the floor:

* the drone stands on the floor under the start (see
  :class:`~quadnav.hardware.frames.TakeoffFrame`), takes off straight up to about
  :data:`TAKEOFF_HEIGHT`, then moves straight up or down to the first waypoint's height;
* the **route** is the refined path between its first and last vertex inside the
  geofence (a start or goal on the floor lies in the margin, so its straight leg is
  flown as the takeoff or landing instead), ending straight above the goal;
* the drone lands straight down from there.

The path is planned with the margin plus :data:`TRACKING_ALLOWANCE`, the geofence is the
margin itself, so rounding to centimetres and tracking errors do not breach the fence.
The trajectory (for ``rc`` mode and the plot) runs through the takeoff point and the
route; the ``go`` moves run through the route *pruned* to the vertices a straight move
needs. Every column, move and densely sampled trajectory point is checked against the
geofence.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from quadnav.errors import PlanningWarning, QuadnavError
from quadnav.hardware.frames import GROUND_Z, FloatArray, IntArray, TakeoffFrame, to_cm
from quadnav.hardware.geofence import Geofence
from quadnav.hardware.moves import Move, go_moves
from quadnav.planning import (
    PlannerSettings,
    PlanningProblem,
    PlanResult,
    Progress,
    make_problem,
    plan,
)
from quadnav.planning.refine import refine
from quadnav.trajectory.generate import TrajectorySettings, make_trajectory
from quadnav.trajectory.model import Trajectory
from quadnav.trajectory.space import SafeSpace
from quadnav.world.model import World

#: Height the Tello's ``takeoff`` leaves it at, about, metres above the floor.
TAKEOFF_HEIGHT = 0.8
#: Extra margin the path keeps beyond the geofence's, metres.
TRACKING_ALLOWANCE = 0.1
#: Largest distance between trajectory points checked against the fence, metres.
CHECK_SPACING = 0.01


class NoPathError(QuadnavError):
    """The planner found no path within its budget."""


@dataclass(frozen=True, eq=False)
class FlightPlan:
    """A checked plan for the Tello, in the map frame (metres) unless said otherwise.

    Attributes:
        problem: the planning query, with the margin plus :data:`TRACKING_ALLOWANCE`.
        result: the planner's refined result (its path runs start -> goal).
        fence: the geofence, with the margin asked for.
        frame: where the drone stands before takeoff and which way it faces.
        route: (N, 3) from straight above the start to straight above the goal.
        pruned: (M, 3) the route's vertices that straight moves need.
        trajectory: through :attr:`takeoff_point` and the route.
        speed: cruise speed, m/s.
    """

    problem: PlanningProblem
    result: PlanResult
    fence: Geofence
    frame: TakeoffFrame
    route: FloatArray
    pruned: FloatArray
    trajectory: Trajectory
    speed: float

    @property
    def takeoff_ground(self) -> FloatArray:
        """(3,) where the drone stands before takeoff."""
        return np.array(self.frame.origin)

    @property
    def takeoff_point(self) -> FloatArray:
        """(3,) where the takeoff leaves the drone, nominally."""
        return self.frame.to_map([0.0, 0.0, TAKEOFF_HEIGHT])

    @property
    def landing_ground(self) -> FloatArray:
        """(3,) where the drone lands: on the floor under the end of the route."""
        return np.array([*self.route[-1, :2], GROUND_Z])

    def go_moves(self, height: float, speed: int) -> list[Move]:
        """The ``go`` moves from the takeoff column at ``height`` m above the floor
        through the pruned route, at ``speed`` cm/s; each is checked against the fence.

        Raises:
            MoveError: a move that the SDK or the geofence does not allow.
        """
        points = np.vstack([to_cm([0.0, 0.0, height]), self.frame.to_body_cm(self.pruned)])
        return go_moves(points, speed, self._allowed)

    def _allowed(self, start: IntArray, end: IntArray) -> bool:
        """Whether a move between takeoff-frame points (cm) stays in the fence, or in the
        takeoff column (x = y = 0) for the climb from a low takeoff."""
        a, b = self.frame.cm_to_map(start), self.frame.cm_to_map(end)
        in_takeoff_column = not (np.any(start[:2]) or np.any(end[:2]))
        return self.fence.segment_ok(a, b) or (in_takeoff_column
                                               and self.fence.column_ok(a, b))

    def planned_track(self) -> FloatArray:
        """(N, 3) the trajectory sampled at most :data:`CHECK_SPACING` m apart."""
        count = max(2, int(np.ceil(self.trajectory.duration * self.speed / CHECK_SPACING)))
        return self.trajectory.position(np.linspace(0.0, self.trajectory.duration, count))

    def planned_points(self, mode: str) -> FloatArray:
        """(N, 3) what is to be flown, takeoff to landing: through the pruned route
        (``waypoints`` mode) or along the trajectory (``rc``)."""
        middle = self.pruned if mode == "waypoints" else self.planned_track()
        return np.vstack([self.takeoff_ground, self.takeoff_point, middle,
                          self.landing_ground])

    def check(self) -> None:
        """Check the takeoff, the route, the landing and the trajectory against the fence.

        Raises:
            GeofenceError: the first part that leaves the fence.
        """
        _check_route(self.fence, self.frame, self.route)
        self.fence.check_track(self.pruned, "the pruned route")
        self.fence.check_track(self.planned_track(), "the trajectory")


def _check_route(fence: Geofence, frame: TakeoffFrame, route: FloatArray) -> None:
    """Check the takeoff from under the start, the climb or descent to the route, the
    route and the landing under its end against ``fence`` (GeofenceError if not)."""
    takeoff = frame.to_map([0.0, 0.0, TAKEOFF_HEIGHT])
    fence.check_column(frame.origin, takeoff, "the takeoff")
    fence.check_track([takeoff, route[0]], "the climb to the route")
    fence.check_track(route, "the route")
    fence.check_column([*route[-1, :2], GROUND_Z], route[-1], "the landing")


def prune(points: ArrayLike, world: World) -> FloatArray:
    """The fewest of ``points`` (N, 3), first and last kept, found greedily such that
    the straight line between consecutive kept ones is free in ``world``."""
    pts = np.asarray(points, dtype=np.float64)
    kept = [0]
    while kept[-1] < len(pts) - 1:
        here = kept[-1]
        reach = next((j for j in range(len(pts) - 1, here + 1, -1)
                      if world.segment_free(pts[here], pts[j])), here + 1)
        kept.append(reach)
    return pts[kept]


def _route(path: FloatArray, fence: Geofence) -> FloatArray:
    """The path's vertices from its first to its last inside the fence, from straight
    above the start to straight above the goal (consecutive repeats dropped)."""
    inside = np.flatnonzero(fence.contains(path))
    if len(inside) == 0:
        raise QuadnavError("the path never enters the geofence: nothing to fly")
    air = path[inside[0]:inside[-1] + 1]
    above_start = [*path[0, :2], air[0, 2]]
    above_goal = [*path[-1, :2], air[-1, 2]]
    route = np.vstack([above_start, air, above_goal])
    return route[np.concatenate([[True], np.any(np.diff(route, axis=0) != 0, axis=1)])]


def plan_flight(world: World, start: ArrayLike | None, goal: ArrayLike | None,
                margin: float, yaw: float, planner: str = "rrtstar",
                planning: PlannerSettings | None = None,
                trajectory: TrajectorySettings | None = None,
                progress: Progress | None = None) -> FlightPlan:
    """Plan, shape and check a flight (see the module's description).

    Args:
        world: the map, blocks not inflated.
        start: (3,) m, or None for the map's own.
        goal: (3,) m, or None for the map's own.
        margin: the geofence's margin, m; the path keeps :data:`TRACKING_ALLOWANCE` more.
        yaw: map heading the drone faces on the floor, rad.
        planner: planner name, as for ``quadnav fly``.
        planning: the planner's budget and seed.
        trajectory: generator and limits; ``v_max`` is the cruise speed.
        progress: called with (fraction of the planning budget, best length m).

    Raises:
        QuadnavError: a bad query; NoPathError: no path; GeofenceError: a part of the
            flight that leaves the fence.
    """
    trajectory = trajectory or TrajectorySettings()
    with warnings.catch_warnings():  # the legs out of the margin become takeoff and landing
        warnings.simplefilter("ignore", PlanningWarning)
        problem = make_problem(world, start, goal, margin + TRACKING_ALLOWANCE)
    result = plan(problem, planning, planner, progress)
    if not result.solved:
        raise NoPathError(f"{world.name}: no path found: {result.message}")
    result = refine(problem, result)
    fence = Geofence(world, margin)
    route = _route(result.path, fence)
    frame = TakeoffFrame.under(problem.start, yaw)
    _check_route(fence, frame, route)
    waypoints = np.vstack([frame.to_map([0.0, 0.0, TAKEOFF_HEIGHT]), route])
    reference = make_trajectory(waypoints, trajectory, SafeSpace(world, problem.margin))
    flight = FlightPlan(problem, result, fence, frame, route,
                        prune(route, problem.free_world), reference, trajectory.v_max)
    flight.check()
    return flight

"""What the Tello will fly, planned and checked before anything is sent.

:func:`plan_flight` plans like ``quadnav fly`` (the same query check, so it accepts and
refuses the same starts and goals; the same planner, shortcut and smoothing, trajectory
generator and settings), then shapes the result for a drone that starts and ends on the
floor:

* the drone stands on the floor under the start (see
  :class:`~quadnav.hardware.bridge.frames.TakeoffFrame`), takes off straight up to about
  :data:`TAKEOFF_HEIGHT`, then moves straight up or down to the start's height;
* the **route** (:class:`Route`) runs from there along the planner's start leg, the
  planned path and the goal leg, ending at the goal; a leg's part in the floor's margin
  (from a start or to a goal on the floor) is raised to the height where the leg leaves
  the fence's floor, below which the takeoff and landing columns take over;
* the drone lands straight down from there.

The path is planned with the margin plus :data:`TRACKING_ALLOWANCE`, the geofence is the
margin itself, so rounding to centimetres and tracking errors do not breach the fence.
Only the start's *zone* — the takeoff column, the climb or descent to the leg and the
leg — and the goal's — the leg and the landing column — may come closer than the margin;
they stay in the leg's room (:mod:`quadnav.hardware.bridge.leg_room`: never closer to a block
than the start or goal itself, never outside the boundary, near a wall only where the leg
is), everything else in the fence. The trajectory (for ``rc`` mode and the plot) runs
through the takeoff point and the route, each zone flown straight from rest to rest at
the generator's leg speed (unless it lies in the free space of the planning margin); the
``go`` moves run through the route *pruned* to the vertices a straight move needs (every
zone vertex kept), rounded to whole centimetres where the moves stay (see
:meth:`FlightPlan.go_moves`). Every column, move and densely sampled trajectory point is
checked, the zones' against their room, the rest against the fence.

A plan made elsewhere (:class:`SavedPlan`: a saved path, or a saved trajectory that
``rc`` mode follows as timed) replaces the planner's result and goes through the same
shaping and checks.
"""

from __future__ import annotations

import itertools
import warnings
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike

from quadnav.arrays import FloatArray
from quadnav.errors import PlanningWarning, QuadnavError
from quadnav.hardware.arc import Arc
from quadnav.hardware.bridge.curves import CURVE_SPEED, Curve, fit_commands
from quadnav.hardware.bridge.frames import GROUND_Z, IntArray, TakeoffFrame, to_cm
from quadnav.hardware.bridge.geofence import Geofence, Region
from quadnav.hardware.bridge.leg_room import LegRoom
from quadnav.hardware.bridge.lost_link import LostLinkBound, creeping_pace
from quadnav.hardware.bridge.moves import Move, MoveError, go_moves, go_speed
from quadnav.planning import (
    PlannerSettings,
    PlanningProblem,
    PlanResult,
    Progress,
    make_problem,
    plan,
)
from quadnav.planning.refine import refine
from quadnav.planning.result import PlanStats, distinct, path_length
from quadnav.trajectory.clearance.space import SafeSpace
from quadnav.trajectory.generate import (
    TrajectorySettings,
    join_legs,
    leg_pieces,
    make_trajectory,
)
from quadnav.trajectory.model import Trajectory
from quadnav.world.margins import polyline_margin
from quadnav.world.model import World
from quadnav.world.placement import format_point

#: The planner name of a saved path flown as given (:func:`saved_plan`).
SAVED_PLANNER = "saved path"
#: Fastest a saved trajectory may start or end, m/s: it starts and ends at rest.
AT_REST = 0.05
#: Height the Tello's ``takeoff`` leaves it at, about, metres above the floor.
TAKEOFF_HEIGHT = 0.8
#: Extra margin the path keeps beyond the geofence's, metres.
TRACKING_ALLOWANCE = 0.1
#: Largest distance between trajectory points checked against the fence, metres.
CHECK_SPACING = 0.01
#: Largest distance between the trajectory samples ``curves`` mode follows, metres.
CURVE_SAMPLE_SPACING = 0.02
#: The eight ways to round a point (3,) down or up on each axis.
_ROUNDINGS = np.array(list(itertools.product((0.0, 1.0), repeat=3)))


class NoPathError(QuadnavError):
    """The planner found no path within its budget."""


@dataclass(frozen=True, eq=False)
class SavedPlan:
    """A plan made elsewhere, flown instead of planning one (``tello fly --path`` and
    ``--trajectory``).

    Attributes:
        points: (N >= 2, 3) its path, m, from the start to the goal (a saved trajectory's:
            its samples' positions).
        source: the file it came from, for messages.
        motion: a saved trajectory's motion, which ``rc`` mode follows as timed; None for
            a path (every corner of which ``go`` moves keep).
    """

    points: FloatArray
    source: str
    motion: Trajectory | None = None


@dataclass(frozen=True, eq=False)
class Route:
    """Waypoints (N, 3), map frame, m, with the start's and the goal's zones marked.

    Attributes:
        points: (N, 3) from the start (raised out of the floor's margin) to the goal
            (likewise).
        head: ``points[:head + 1]`` is the start's zone: its leg, ending where the
            planner's search began.
        tail: ``points[tail:]`` is the goal's zone: from where the search ended, its leg.
            Between the zones the route is in the fence.
    """

    points: FloatArray
    head: int
    tail: int

    def parts(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        """The start's zone, the part between the zones, the goal's zone (each (K, 3);
        consecutive parts share their end points)."""
        p = self.points
        return p[:self.head + 1], p[self.head:self.tail + 1], p[self.tail:]


@dataclass(frozen=True, eq=False)
class FlightPlan:
    """A checked plan for the Tello, in the map frame (metres) unless said otherwise.

    Attributes:
        problem: the planning query, with the margin plus :data:`TRACKING_ALLOWANCE`.
        result: the planner's refined result (its path runs start -> goal).
        fence: the geofence, with the margin asked for.
        frame: where the drone stands before takeoff and which way it faces.
        route: from the start to the goal, legs included (see :class:`Route`).
        pruned: the route's vertices that straight moves need (the zones' all kept).
        trajectory: through :attr:`takeoff_point` and the route; its ``legs`` are the
            zones flown straight (see :meth:`region_at`).
        speed: cruise speed, m/s.
    """

    problem: PlanningProblem
    result: PlanResult
    fence: Geofence
    frame: TakeoffFrame
    route: Route
    pruned: Route
    trajectory: Trajectory
    speed: float

    @cached_property
    def _rooms(self) -> tuple[LegRoom, LegRoom]:
        """The rooms of the start's leg and of the goal's."""
        return leg_rooms(self.fence, self.problem)

    @property
    def start_room(self) -> LegRoom:
        """Where the start's zone may go."""
        return self._rooms[0]

    @property
    def goal_room(self) -> LegRoom:
        """Where the goal's zone may go."""
        return self._rooms[1]

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
        return np.array([*self.route.points[-1, :2], GROUND_Z])

    def region_at(self, tau: float) -> Region:
        """Where the trajectory may be at time ``tau`` s: the start's room on its first
        leg, the goal's on its last, else the fence."""
        begin, end = self.trajectory.main_window
        if tau < begin:
            return self.start_room
        return self.goal_room if tau > end else self.fence

    def reference_pace(self, tau: float) -> float:
        """The fraction of its own speed at which ``rc`` mode follows the trajectory at
        ``tau`` s: the lost-link bound's pace where it may be then (:meth:`region_at`),
        on a leg never slower than a creep (:func:`~quadnav.hardware.bridge.lost_link.
        creeping_pace`)."""
        region = self.region_at(tau)
        velocity = self.trajectory.velocity(tau)
        pace = LostLinkBound(region).pace(self.trajectory.position(tau), velocity)
        if region is self.fence:
            return pace
        return creeping_pace(pace, float(np.linalg.norm(velocity)))

    # --- go moves ----------------------------------------------------------------------

    def go_moves(self, height: float, speed: int) -> list[Move]:
        """The ``go`` moves from the takeoff column at ``height`` m above the floor
        through the pruned route, at ``speed`` cm/s; each is checked against the fence or,
        in a zone, the leg's room, and so is the landing under their end. The route's
        vertices are rounded to whole centimetres of the takeoff frame: to the nearest,
        unless moves between them would then leave where they must stay, when one of the
        eight centimetres around each vertex is chosen so that none do.

        Raises:
            MoveError: a move that the SDK, the fence or a leg's room does not allow.
        """
        pruned, fits = self._pruned_cm
        points = np.vstack([to_cm([0.0, 0.0, height]), pruned])
        try:
            moves = go_moves(points, speed, self._allowed, self._rule)
        except MoveError as error:
            if fits:
                raise
            raise MoveError(f"{error} (whole centimetres in the frame of the drone's "
                            f"heading, {np.degrees(self.frame.yaw):.3g} degrees, cannot "
                            "follow the route where it must stay: try a heading along the "
                            "map's axes)") from None
        self._check_landing(points[-1])
        return moves

    def curve_moves(self, height: float, speed: float) -> list[Move | Curve]:
        """``curves`` mode: :meth:`go_moves` through the start's zone and the goal's, and
        between them ``curve`` and ``go`` commands that follow the trajectory within
        :data:`~quadnav.hardware.bridge.curves.TOLERANCE_CM`
        (:func:`~quadnav.hardware.bridge.curves.fit_commands`), every centimetre of each
        checked against the fence; ``speed`` m/s, a curve's clamped to the SDK's 0.6 m/s
        at most.

        Raises:
            MoveError: a part that no allowed command flies.
        """
        pruned, _ = self._pruned_cm
        head, tail = self.pruned.head, self.pruned.tail
        go = go_speed(speed)
        start = go_moves(np.vstack([to_cm([0.0, 0.0, height]), pruned[:head + 1]]), go,
                         self._allowed, self._rule)

        def shifted(segments: range) -> range:
            return range(segments.start + tail + 1, segments.stop + tail + 1)

        end = go_moves(pruned[tail:], go, lambda a, b, k: self._allowed(a, b, shifted(k)),
                       lambda k: self._rule(shifted(k)))
        samples = 100.0 * self.frame.to_body(self.trajectory.position(self._fence_times()))
        samples[0], samples[-1] = pruned[head], pruned[tail]
        middle = fit_commands(samples, go, int(np.clip(go, *CURVE_SPEED)),
                              self._arc_in_fence, self._line_in_fence)
        self._check_landing(pruned[-1])
        return [*start, *middle, *end]

    def _fence_times(self) -> FloatArray:
        """Trajectory times, s, every :data:`CURVE_SAMPLE_SPACING` m or closer, from where
        it reaches the route's first vertex in the fence (the end of the start's zone) to
        where it reaches the last (the start of the goal's)."""
        trajectory, route = self.trajectory, self.route
        at = [np.flatnonzero(np.all(np.isclose(trajectory.waypoints, point, atol=1e-9),
                                    axis=1)) for point in route.points[[route.head, route.tail]]]
        begin, end = trajectory.breaks[at[0][0]], trajectory.breaks[at[1][-1]]
        coarse = np.linspace(begin, end, 1000)
        length = path_length(trajectory.position(coarse))
        return np.linspace(begin, end, max(2, int(np.ceil(length / CURVE_SAMPLE_SPACING)) + 1))

    def _arc_in_fence(self, start: IntArray, via: IntArray, end: IntArray) -> bool:
        """Whether every centimetre of the arc through three takeoff-frame points (cm)
        is inside the fence."""
        arc = Arc(start, via, end)
        s = np.linspace(0.0, arc.length, max(2, int(np.ceil(arc.length)) + 1))
        return bool(self.fence.contains(self.frame.cm_to_map(arc.at(s)[0])).all())

    def _line_in_fence(self, start: IntArray, end: IntArray) -> bool:
        """Whether the straight move between two takeoff-frame points (cm) is inside the
        fence."""
        return self.fence.segment_ok(self.frame.cm_to_map(start), self.frame.cm_to_map(end))

    def _check_landing(self, end_cm: IntArray) -> None:
        """MoveError unless the landing column under ``end_cm`` (takeoff frame) stays in
        the goal's room."""
        end = self.frame.cm_to_map(end_cm)
        if not self.goal_room.column_ok([*end[:2], GROUND_Z], end):
            raise MoveError(f"the landing under the last move's end {end_cm.tolist()} cm "
                            f"leaves {self.goal_room.name}")

    def _segment_region(self, segment: int) -> Region:
        """Where ``go`` segment ``segment`` may go (segment 0 climbs from the takeoff
        height to the pruned route's first vertex, segment k + 1 follows its k-th)."""
        if segment <= self.pruned.head:
            return self.start_room
        return self.goal_room if segment > self.pruned.tail else self.fence

    def _move_regions(self, segments: range) -> list[Region]:
        """Where a straight move in place of ``go`` segments ``segments`` must stay: the
        fence between the zones, else the room of every zone it touches."""
        regions = list(dict.fromkeys(self._segment_region(k) for k in segments))
        return regions if len(regions) == 1 else [r for r in regions if r is not self.fence]

    def _allowed(self, start: IntArray, end: IntArray, segments: range) -> bool:
        """Whether a move between takeoff-frame points (cm) in place of ``segments`` stays
        where it must, or in its column under the takeoff (x = y = 0, the floor aside)."""
        a, b = self.frame.cm_to_map(start), self.frame.cm_to_map(end)
        in_takeoff_column = not (np.any(start[:2]) or np.any(end[:2]))
        return all(region.segment_ok(a, b) or (in_takeoff_column and region.column_ok(a, b))
                   for region in self._move_regions(segments))

    def _rule(self, segments: range) -> str:
        """Where a move in place of ``segments`` must stay, in words."""
        return " and ".join(region.name for region in self._move_regions(segments))

    @cached_property
    def _pruned_cm(self) -> tuple[IntArray, bool]:
        """(M, 3) the pruned route as takeoff-frame points in whole centimetres: of the
        eight around each vertex, those nearest to the vertices in sum (a shortest path
        over them) such that each lies where the moves on either side of it must stay
        (the last one above a landing column that does) and so does each straight move
        between them, and True; the nearest ones and False when there are none such."""
        body = 100.0 * self.frame.to_body(self.pruned.points)
        around = np.floor(body)[:, None, :] + _ROUNDINGS  # (M, 8, 3)
        order = np.argsort(np.linalg.norm(around - np.rint(body)[:, None, :], axis=2),
                           axis=1, kind="stable")  # the nearest rounding first
        around = np.take_along_axis(around, order[:, :, None], axis=1).astype(np.int64)
        cost = np.where([[self._vertex_ok(k, c) for c in row] for k, row in enumerate(around)],
                        np.linalg.norm(around - body[:, None, :], axis=2), np.inf)
        total, back = cost[0], []
        for k in range(1, len(body)):
            step = np.array([[total[i] + cost[k, j] if np.isfinite(total[i] + cost[k, j])
                              and self._allowed(around[k - 1, i], around[k, j], range(k, k + 1))
                              else np.inf for i in range(len(_ROUNDINGS))]
                             for j in range(len(_ROUNDINGS))])
            back.append(np.argmin(step, axis=1))
            total = step.min(axis=1)
        if not np.isfinite(total.min()):
            return np.rint(body).astype(np.int64), False
        chosen = [int(np.argmin(total))]
        for previous in reversed(back):
            chosen.append(int(previous[chosen[-1]]))
        return around[np.arange(len(body)), chosen[::-1]], True

    def _vertex_ok(self, k: int, point: IntArray) -> bool:
        """Whether takeoff-frame ``point`` (cm) may stand for pruned vertex ``k``: it lies
        where the ``go`` segments on either side of it must stay (and, for the last, above
        a landing column that does)."""
        where = self.frame.cm_to_map(point)
        last = len(self.pruned.points) - 1
        regions = {self._segment_region(k), self._segment_region(min(k + 1, last))}
        return all(region.point_ok(where) for region in regions) and (
            k < last or self.goal_room.column_ok([*where[:2], GROUND_Z], where))

    # --- the trajectory ------------------------------------------------------------------

    def _track_times(self) -> FloatArray:
        """Times (N,), s, at most :data:`CHECK_SPACING` m of flight apart, with the ends of
        the trajectory's straight legs among them."""
        duration = self.trajectory.duration
        count = max(2, int(np.ceil(duration * self.speed / CHECK_SPACING)))
        return np.union1d(np.linspace(0.0, duration, count), self.trajectory.main_window)

    def planned_track(self) -> FloatArray:
        """(N, 3) the trajectory sampled at most :data:`CHECK_SPACING` m apart."""
        return self.trajectory.position(self._track_times())

    def planned_points(self, mode: str) -> FloatArray:
        """(N, 3) what is to be flown, takeoff to landing: through the pruned route
        (``waypoints`` mode) or along the trajectory (``curves``, ``rc``)."""
        return self.between_columns(self.pruned.points if mode == "waypoints"
                                    else self.planned_track())

    def between_columns(self, middle: FloatArray) -> FloatArray:
        """(N, 3) ``middle`` (K, 3) m with the takeoff column before it (the floor under
        the start, the takeoff point) and the floor under the landing after it."""
        return np.vstack([self.takeoff_ground, self.takeoff_point, middle,
                          self.landing_ground])

    # --- checks --------------------------------------------------------------------------

    def check(self) -> None:
        """Check the takeoff, the route, the landing and the trajectory against the fence
        and, in the zones, the legs' rooms.

        Raises:
            GeofenceError: the first part that leaves where it must stay.
        """
        check_route(self.fence, self._rooms, self.frame, self.route, self.pruned)
        t = self._track_times()
        track = self.trajectory.position(t)
        begin, end = self.trajectory.main_window
        for region, inside in ((self.start_room, t <= begin),
                               (self.fence, (t >= begin) & (t <= end)),
                               (self.goal_room, t >= end)):
            region.check_track(track[inside], _in_zone("the trajectory", region))

#: How a Tello flight's segments are timed: each from rest to rest, as the drone's ``go``
#: commands fly them (and within what its ``rc`` sticks can follow under the lost-link
#: bound); the ``fastest`` timing of simulated flights does not stop at waypoints.
TELLO_TIMING = "rest-to-rest"

def leg_rooms(fence: Geofence, problem: PlanningProblem) -> tuple[LegRoom, LegRoom]:
    """The rooms of the start's leg and of the goal's within ``fence``."""
    return (LegRoom(fence, problem.start_leg, "start"),
            LegRoom(fence, problem.goal_leg[::-1], "goal"))


def check_route(fence: Geofence, rooms: tuple[LegRoom, LegRoom], frame: TakeoffFrame,
                route: Route, pruned: Route) -> None:
    """Check the takeoff from under the start, the climb or descent to the route, the
    route, the ``pruned`` route and the landing under the route's end (GeofenceError if
    one leaves the fence or, in a zone, its leg's room)."""
    start_room, goal_room = rooms
    takeoff, points = frame.to_map([0.0, 0.0, TAKEOFF_HEIGHT]), route.points
    start_room.check_column(frame.origin, takeoff, "the takeoff")
    start_room.check_column(takeoff, [*takeoff[:2], points[0, 2]], "the climb to the route")
    for what, path in (("the route", route), ("the pruned route", pruned)):
        for region, part in zip((start_room, fence, goal_room), path.parts(), strict=True):
            region.check_track(part, _in_zone(what, region))
    goal_room.check_column([*points[-1, :2], GROUND_Z], points[-1], "the landing")


def _in_zone(what: str, region: Region) -> str:
    """``what`` ("the route"), or its part in a leg's room ("the start leg of the
    route")."""
    return f"the {region.label} leg of {what}" if isinstance(region, LegRoom) else what


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


def _joined(start_zone: FloatArray, middle: FloatArray, goal_zone: FloatArray) -> Route:
    """The route through ``start_zone`` (ending where ``middle`` begins), ``middle`` and
    ``goal_zone`` (beginning where ``middle`` ends), each (K, 3)."""
    head = len(start_zone) - 1
    if len(middle) == 1:  # the search started where it ended
        return Route(np.vstack([start_zone, goal_zone[1:]]), head, head)
    points = np.vstack([start_zone, middle[1:-1], goal_zone])
    return Route(points, head, head + len(middle) - 1)


def _raised(leg: FloatArray, floor: float) -> FloatArray:
    """The start ``leg`` (K, 3) with its vertices before the first one above ``floor``
    (the fence's floor, m) raised to that one's height: the part of a leg in the floor's
    margin, flown at the height where the leg leaves it."""
    first = int(np.flatnonzero(leg[:, 2] > floor)[0])
    raised = leg.copy()
    raised[:first, 2] = leg[first, 2]
    return distinct(raised)


def _route(problem: PlanningProblem, path: FloatArray, fence: Geofence,
           pruned: bool = True) -> tuple[Route, Route]:
    """The route of the planner's ``path`` (N, 3), and the route pruned (see the
    module's description; with ``pruned`` False, every corner kept, as for a saved path):
    the legs' parts in the floor's margin raised to where they leave it, below which the
    takeoff and landing columns take over."""
    floor = fence.free_world.lower[2]
    start_zone = _raised(problem.start_leg, floor)
    goal_zone = _raised(problem.goal_leg[::-1], floor)[::-1]
    middle = distinct(problem.search_part(path))
    kept = prune(middle, problem.free_world) if pruned else middle
    return _joined(start_zone, middle, goal_zone), _joined(start_zone, kept, goal_zone)


def _trajectory(takeoff: FloatArray, route: Route, settings: TrajectorySettings,
                space: SafeSpace, motion: Trajectory | None = None) -> Trajectory:
    """The trajectory from ``takeoff`` (3,) through ``route``: each zone (the start's
    from ``takeoff``) straight from rest to rest at :data:`~quadnav.trajectory.generate.
    LEG_SLOW_DOWN` of the limits, as the generator flies legs, unless it lies in the free
    space of ``space``'s margin; between them, the generator's trajectory in ``space``
    (or a saved ``motion`` from the route's start to its end, the zones then always
    flown straight)."""
    start_zone, middle, goal_zone = route.parts()
    start_zone = distinct([takeoff, *start_zone])

    def flown_straight(zone: FloatArray) -> list[Trajectory] | None:
        """The zone's straight pieces, or None when it lies in the free space."""
        if motion is None and space.inflated.segments_free(
                np.stack([zone[:-1], zone[1:]], axis=1)).all():
            return None
        return leg_pieces(zone, settings)

    first, last = flown_straight(start_zone), flown_straight(goal_zone)
    if motion is not None:
        return join_legs(first, [motion], last, settings)
    points = distinct(np.vstack([start_zone if first is None else start_zone[-1:],
                                  middle[1:-1],
                                  goal_zone if last is None else goal_zone[:1]]))
    main = [make_trajectory(points, settings, space)] if len(points) > 1 else []
    return join_legs(first or [], main, last or [], settings)


def saved_plan(problem: PlanningProblem, path: ArrayLike, source: str) -> PlanResult:
    """A saved path (N >= 2, 3) m from ``problem``'s start to its goal, as a plan: its
    inner vertices, between the search's start and goal (a start or goal inside the
    margin is left or entered by the problem's leg, as a planned path's is). Every
    segment between the legs must keep the problem's margin, checked exactly; else
    QuadnavError naming ``source`` and the first segment that does not."""
    points = np.asarray(path, dtype=np.float64).reshape(-1, 3)
    search = distinct(np.vstack([problem.search_start, points[1:-1], problem.search_goal]))
    free = problem.free_world.segments_free(np.stack([search[:-1], search[1:]], axis=1))
    if not free.all():
        k = int(np.argmin(free))
        kept = polyline_margin(problem.world, search)
        advice = (f"fly it with --margin {kept - TRACKING_ALLOWANCE:.3g} or less, or plan it"
                  if kept > TRACKING_ALLOWANCE else "plan it again")
        raise QuadnavError(
            f"{source}: the segment {format_point(search[k])} -> "
            f"{format_point(search[k + 1])} comes closer than {problem.margin:g} m (the "
            f"margin plus {TRACKING_ALLOWANCE:g} m for tracking) to a block or the boundary: "
            f"the path keeps {max(kept, 0.0):.3g} m; {advice} with a margin of "
            f"{problem.margin:g} m")
    stats = PlanStats(iterations=0, nodes=0, seconds=0.0, time_to_first=None)
    return PlanResult(SAVED_PLANNER, True, problem.full_path(search), np.zeros((0, 3)),
                      np.zeros(0, dtype=np.int64), stats, 0)


def _check_saved_motion(problem: PlanningProblem, saved: SavedPlan) -> None:
    """A saved trajectory starts and ends at rest outside the margin; else QuadnavError
    naming its file."""
    motion = saved.motion
    for leg, point, end, t in ((problem.start_leg, problem.start, "starts", 0.0),
                               (problem.goal_leg, problem.goal, "ends", motion.duration)):
        if len(leg) > 1:
            raise QuadnavError(
                f"{saved.source}: the trajectory {end} at {format_point(point)}, "
                f"inside the {problem.margin:g} m margin (the margin plus "
                f"{TRACKING_ALLOWANCE:g} m for tracking): a saved trajectory must start and "
                "end outside it (the takeoff and landing columns reach it); fly its path "
                "with --path, which leaves and enters the margin by quadnav's legs")
        speed = float(np.linalg.norm(motion.velocity(t)))
        if speed > AT_REST:
            raise QuadnavError(f"{saved.source}: the trajectory {end} at {speed:.3g} m/s: "
                               f"expected it to {end[:-1]} at rest (at most {AT_REST:g} m/s)")


def plan_flight(world: World, start: ArrayLike | None, goal: ArrayLike | None,
                margin: float, yaw: float, planner: str = "rrtstar",
                planning: PlannerSettings | None = None,
                trajectory: TrajectorySettings | None = None,
                progress: Progress | None = None,
                saved: SavedPlan | None = None) -> FlightPlan:
    """Plan, shape and check a flight (see the module's description).

    Args:
        world: the map, blocks not inflated.
        start: (3,) m, or None for the map's own (or, with ``saved``, its first point).
        goal: (3,) m, or None for the map's own (or, with ``saved``, its last point).
        margin: the geofence's margin, m; the path keeps :data:`TRACKING_ALLOWANCE` more.
        yaw: map heading the drone faces on the floor, rad.
        planner: planner name, as for ``quadnav fly``.
        planning: the planner's budget and seed.
        trajectory: generator and limits; ``v_max`` is the cruise speed; the timing is
            always :data:`TELLO_TIMING`.
        progress: called with (fraction of the planning budget, best length m).
        saved: a saved path or trajectory, flown instead of a planned one (see
            :func:`saved_plan`) through the same checks: a path with every corner kept
            (``go`` moves are not pruned to fewer), a trajectory as timed (``rc`` mode;
            ``go`` moves through its path's corners), which must start and end at rest
            outside the margin (the takeoff and landing columns reach it).

    Raises:
        QuadnavError: a bad query or saved path; NoPathError: no path; GeofenceError: a
            part of the flight that leaves the fence (or, in a zone, the leg's room).
    """
    trajectory = (trajectory or TrajectorySettings()).replace(timing=TELLO_TIMING)
    if saved is not None:
        start = saved.points[0] if start is None else start
        goal = saved.points[-1] if goal is None else goal
    with warnings.catch_warnings():  # the legs are flown as legs: no need to warn
        warnings.simplefilter("ignore", PlanningWarning)
        problem = make_problem(world, start, goal, margin + TRACKING_ALLOWANCE)
    if saved is not None:
        result = saved_plan(problem, saved.points, saved.source)
        if saved.motion is not None:
            _check_saved_motion(problem, saved)
    else:
        result = plan(problem, planning, planner, progress)
        if not result.solved:
            raise NoPathError(f"{world.name}: no path found: {result.message}")
        result = refine(problem, result)
    fence = Geofence(world, margin)
    keep_corners = saved is not None and saved.motion is None
    route, pruned = _route(problem, result.path, fence, pruned=not keep_corners)
    frame = TakeoffFrame.under(problem.start, yaw)
    # Checked before the trajectory is made: the first refusal is the clearest.
    check_route(fence, leg_rooms(fence, problem), frame, route, pruned)
    reference = _trajectory(frame.to_map([0.0, 0.0, TAKEOFF_HEIGHT]), route, trajectory,
                            SafeSpace(world, problem.margin),
                            None if saved is None else saved.motion)
    flight = FlightPlan(problem, result, fence, frame, route, pruned, reference,
                        trajectory.v_max)
    flight.check()
    return flight

"""A planning query: a world, a safety margin, a start and a goal, checked and prepared.

:func:`make_problem` turns what the user gave into a :class:`PlanningProblem`:

* a start or goal outside the boundary or inside a real block is an error naming it, and
  so is a start equal to the goal;
* one inside the safety margin (on the boundary, or close to a block) is usable: the
  path leaves the margin by a short *leg* (:mod:`quadnav.planning.legs`), the only part
  of the flight allowed inside the margin, and a :class:`~quadnav.errors.PlanningWarning`
  says so;
* a start and goal provably in different parts of free space are an error, found fast;
* given the vehicle's body (its half extents), a start closer to the boundary than the
  body reaches is left by the shortest move that brings the body inside (the first part
  of its leg), and such a goal is replaced by the nearest point where the body fits, with
  a :class:`~quadnav.errors.PlanningWarning` naming both points; the legs keep the body
  inside (:mod:`quadnav.planning.legs`).

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
from quadnav.planning.legs import BODY_ROOM, body_inside, body_reach, find_leg
from quadnav.planning.result import path_length
from quadnav.profiling import staged
from quadnav.world.connectivity import disconnected
from quadnav.world.model import World
from quadnav.world.placement import classify_point, format_box, format_point


@dataclass(frozen=True, eq=False)
class PlanningProblem:
    """A checked planning query.

    Attributes:
        world: the map as read, blocks not inflated.
        margin: safety margin, metres.
        free_world: ``world`` inflated by ``margin``; planners search its free space.
        start_leg: (K, 3) polyline from the start, exactly as given, out of the margin to
            :attr:`search_start`; just the start (1, 3) when it is free.
        goal_leg: (K, 3) polyline from :attr:`search_goal` into the margin to the goal
            flown to; just the goal (1, 3) when it is free.
        asked_goal: (3,) the goal as given, when the body did not fit there and the goal
            flown to (:attr:`goal`) is the nearest point where it does; else None.
    """

    world: World
    margin: float
    free_world: World
    start_leg: FloatArray
    goal_leg: FloatArray
    asked_goal: FloatArray | None = None

    def __post_init__(self) -> None:
        for name in ("start_leg", "goal_leg", "asked_goal"):
            if getattr(self, name) is None:
                continue
            leg = np.array(getattr(self, name), dtype=np.float64).reshape(-1, 3)
            leg.flags.writeable = False
            object.__setattr__(self, name, leg[0] if name == "asked_goal" else leg)

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
        """(3,) where the path ends, metres: the goal flown to."""
        return self.goal_leg[-1]

    @property
    def goal_asked(self) -> FloatArray:
        """(3,) the goal as given, metres (:attr:`goal` unless it was moved)."""
        return self.goal if self.asked_goal is None else self.asked_goal

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


@staged("query")
def make_problem(world: World, start: ArrayLike | None, goal: ArrayLike | None,
                 margin: float, body: ArrayLike = (0.0, 0.0, 0.0)) -> PlanningProblem:
    """Check a query and prepare it for planners; raises QuadnavError for bad input.

    Args:
        world: the map, blocks not inflated.
        start: (3,) metres, or ``None`` for the map's own start.
        goal: (3,) metres, or ``None`` for the map's own goal.
        margin: safety margin, metres, >= 0.
        body: the vehicle's body box half extents (3,) along x, y and z, metres, as it
            flies (level, at its heading); zeros (the default): a point. The start's
            move inside, the legs and the goal keep the body inside the boundary with
            :data:`~quadnav.planning.legs.BODY_ROOM` to spare.
    """
    free_world = world.inflate(margin)
    half = np.asarray(body, dtype=np.float64)
    if half.shape != (3,) or not np.all(np.isfinite(half) & (half >= 0)):
        raise QuadnavError(f"body: expected 3 half extents >= 0 m, got {body!r}")
    points = []
    for label, point, own in (("start", start, world.start), ("goal", goal, world.goal)):
        if point is None:
            point = own
        if point is None:
            raise QuadnavError(f"{world.name}: the map has no {label}; give --{label} X Y Z")
        points.append(_usable(world, point, margin, label))
    start_point, asked_goal = points
    if np.array_equal(start_point, asked_goal):
        raise QuadnavError(f"start and goal are the same point {format_point(start_point)}: "
                           "there is nothing to fly; give a different --goal")
    goal_point = _fitting(world, asked_goal, margin, half, "goal")
    moved = not np.array_equal(goal_point, asked_goal)
    if moved:
        _warn_goal_moved(asked_goal, goal_point, half)
        if np.array_equal(start_point, goal_point):
            raise QuadnavError(f"goal {format_point(asked_goal)} is flown to "
                               f"{format_point(goal_point)}, the start itself: there is "
                               "nothing to fly; give a different --goal")
    start_leg = _start_leg(world, free_world, start_point, margin, half)
    goal_leg = find_leg(world, free_world, goal_point, margin, "goal", half)[::-1]
    for label, leg in (("start", start_leg), ("goal", goal_leg[::-1])):
        if len(leg) > 1:
            _warn_leg(label, leg, margin, free_world.is_free(leg[0]))
    problem = PlanningProblem(world, float(margin), free_world, start_leg, goal_leg,
                              asked_goal if moved else None)
    if disconnected(free_world, problem.search_start, problem.search_goal):
        raise QuadnavError(
            f"{world.name}: start {format_point(start_point)} and goal "
            f"{format_point(goal_point)} are disconnected with a {margin:g} m margin: "
            "no path exists")
    return problem


def _usable(world: World, point: ArrayLike, margin: float, label: str) -> FloatArray:
    """``point`` (3,) checked (:func:`~quadnav.world.placement.classify_point`):
    QuadnavError unless it is free or only inside the margin."""
    report = classify_point(world, point, margin, label)
    if not report.usable:
        verb = "start" if label == "start" else "end"
        raise QuadnavError(f"{report}; a path must {verb} in free space")
    return report.point


def _fitting(world: World, point: FloatArray, margin: float, body: FloatArray, label: str
             ) -> FloatArray:
    """The point (3,) nearest ``point`` where the body box of half extents ``body`` (3,) m
    lies :data:`~quadnav.planning.legs.BODY_ROOM` inside the boundary
    (:func:`~quadnav.planning.legs.body_inside`; ``point`` itself when it does);
    QuadnavError when the body touches a block there."""
    fitted = _usable(world, body_inside(world, point, body_reach(body), label), margin, label)
    touched = world.replace(blocks=world.blocks + np.concatenate([-body, body])
                            ).blocks_containing(fitted)
    if np.any(body > 0) and touched.size:
        moved = ("" if np.array_equal(fitted, point) else
                 f" moved inside the boundary, to {format_point(fitted)},")
        raise QuadnavError(
            f"{label} {format_point(point)}: the vehicle's {_size(body)} m body does not fit "
            f"there:{moved} it touches block {touched[0]} "
            f"{format_box(world.blocks[touched[0]])}; move the {label}")
    return fitted


def _size(body: FloatArray) -> str:
    """``a x b x c``: the size of a body box of half extents ``body`` (3,), metres."""
    return " x ".join(f"{2 * v:g}" for v in body)


def _start_leg(world: World, free_world: World, start: FloatArray, margin: float,
               body: FloatArray) -> FloatArray:
    """The start's leg (K, 3): the shortest move that brings the body box of half extents
    ``body`` (3,) m inside the boundary with room (none when it is), then the leg out of
    the margin from there, the two one segment when they run on in the same direction."""
    moved = _fitting(world, start, margin, body, "start")
    leg = find_leg(world, free_world, moved, margin, "start", body)
    if np.array_equal(moved, start):
        return leg
    if len(leg) > 1 and _runs_on(start, moved, leg[1]):
        return np.vstack([start, leg[1:]])
    return np.vstack([start, leg])


def _runs_on(a: FloatArray, b: FloatArray, c: FloatArray) -> bool:
    """Whether ``b`` lies on the segment from ``a`` to ``c`` (3,) each, up to rounding."""
    first, second = b - a, c - b
    scale = float(np.linalg.norm(first) * np.linalg.norm(second))
    return (float(np.dot(first, second)) > 0.0
            and float(np.linalg.norm(np.cross(first, second))) <= 1e-9 * scale)


def _warn_goal_moved(asked: FloatArray, flown: FloatArray, body: FloatArray) -> None:
    """Say, in one line, that the body box of half extents ``body`` (3,) m does not fit
    at goal ``asked`` (3,) and the flight ends at ``flown`` (3,) instead."""
    warnings.warn(
        f"goal {format_point(asked)} is too close to the boundary for the vehicle's "
        f"{_size(body)} m body; flying to {format_point(flown)} instead, the nearest point "
        f"where it fits with {100 * BODY_ROOM:g} cm to spare", PlanningWarning, stacklevel=3)


def _warn_leg(label: str, leg: FloatArray, margin: float, free: bool) -> None:
    """Say that the point ``leg[0]`` lies in the margin (or, when ``free``, only too close
    to the boundary for the body) and how the leg leaves it."""
    shape = "straight" if len(leg) == 2 else f"{len(leg) - 1}-segment"
    where = ("too close to the boundary for the vehicle's body" if free
             else f"inside the {margin:g} m safety margin")
    warnings.warn(
        f"{label} {format_point(leg[0])} is {where}; "
        f"only the {shape} {path_length(leg):.3g} m leg "
        f"{'out of it, to' if label == 'start' else 'into it, from'} {format_point(leg[-1])}, "
        f"may come closer; the rest of the flight keeps {margin:g} m", PlanningWarning,
        stacklevel=3)

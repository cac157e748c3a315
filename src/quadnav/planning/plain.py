"""Plain-Python planners: a function ``planner(world, start, goal, margin, **kwargs) ->
path (N, 3)``, named where it is (``module:function`` or ``path/to/file.py:function``,
optionally with literal keyword arguments, :mod:`quadnav.plugins`), flown beside the
registered planners: :class:`PlainPlanner`.

The function is called with the real map (:class:`~quadnav.world.model.World`, blocks not
inflated), the start and goal of the search (:attr:`~quadnav.planning.problem.
PlanningProblem.search_start` and ``search_goal``, (3,) m: the query's own start and goal
when they keep the margin, else the ends of the short legs out of it, which quadnav adds
around the path), the margin in metres, the spec's keyword arguments (a list of numbers as
a numpy array, :func:`~quadnav.plugins.literal_arrays`) and, when the function has a
``seed`` parameter the spec does not set, the planner's seed. It is always called (the
built-in planners join a goal in sight of the start directly, without a search).

What it returns is checked exactly before anything flies it (:func:`path_fault`): an
array (N, 3) of finite numbers, N >= 2, from the start to the goal (each within
:data:`END_TOLERANCE`, then moved onto them exactly), every segment free in the map
inflated by the margin (the exact segment test of
:meth:`~quadnav.world.model.World.segments_free`). A path that is not is a failed plan,
as a search that found none: the :class:`~quadnav.planning.result.PlanResult` is not
solved, its message says which segment is at fault and where, and its tree holds the path
returned, to draw. ``None`` (or an empty path) is a plan that found no path. An exception
in the function is a :class:`~quadnav.plugins.PluginError` with its own traceback (exit 1).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from quadnav.limits import MAX_WAYPOINTS
from quadnav.planning.problem import PlanningProblem
from quadnav.planning.result import PlanResult, PlanStats, Progress, distinct, path_length
from quadnav.planning.settings import PlannerSettings
from quadnav.plugins import check_call, literal_arrays, raised_in, takes_keyword
from quadnav.world.margins import polyline_margin
from quadnav.world.model import World
from quadnav.world.placement import format_box, format_point

#: How far, m, a returned path may begin from the start and end from the goal; its ends
#: are then moved onto them exactly.
END_TOLERANCE = 1e-6
#: The arguments quadnav calls a plain planner with, in order.
ARGUMENTS = ("world", "start", "goal", "margin")


@dataclass(frozen=True, eq=False)
class PlainPlanner:
    """A plain function as a :data:`~quadnav.planning.contract.Planner`
    (``(problem, settings, progress) -> PlanResult``; see the module docstring).

    Attributes:
        text: the spec as given (``"my_astar.py:astar(resolution=0.25)"``): the planner's
            name in results.
        function: the function it names.
        kwargs: the spec's keyword arguments, as the function gets them.
    """

    text: str
    function: Callable[..., Any]
    kwargs: Mapping[str, Any]

    @classmethod
    def named(cls, text: str, function: Callable[..., Any], kwargs: Mapping[str, Any]
              ) -> PlainPlanner:
        """The planner ``text`` names; QuadnavError (exit 2) when ``function`` is not
        callable as ``function(world, start, goal, margin, **kwargs)``."""
        arguments = literal_arrays(kwargs)
        check_call("planner", text, function, ARGUMENTS, arguments)
        return cls(text, function, arguments)

    def __call__(self, problem: PlanningProblem, settings: PlannerSettings,
                 progress: Progress | None = None) -> PlanResult:
        """Call the function on ``problem`` and check what it returns (``progress`` is not
        reported: the function runs as one call)."""
        kwargs = dict(self.kwargs)
        if "seed" not in kwargs and takes_keyword(self.function, "seed"):
            kwargs["seed"] = settings.seed
        start, goal = problem.search_start.copy(), problem.search_goal.copy()
        began = time.perf_counter()
        try:
            returned = self.function(problem.world, start, goal, problem.margin, **kwargs)
        except Exception as error:
            raise raised_in("planner", self.text, None, error) from None
        seconds = time.perf_counter() - began
        path, fault = checked_path(problem, returned)
        if fault is not None:
            nodes = np.zeros((0, 3)) if path is None else path
            stats = PlanStats(iterations=0, nodes=len(nodes), seconds=seconds,
                              time_to_first=None)
            return PlanResult(self.text, False, np.zeros((0, 3)), nodes,
                              np.arange(len(nodes)) - 1, stats, settings.seed,
                              f"planner {self.text} {fault}")
        stats = PlanStats(iterations=0, nodes=len(path), seconds=seconds, time_to_first=seconds,
                          cost_history=[[seconds, path_length(path)]])
        return PlanResult(self.text, True, problem.full_path(path), path,
                          np.arange(len(path)) - 1, stats, settings.seed)


def checked_path(problem: PlanningProblem, returned: Any) -> tuple[Any, str | None]:
    """``(path, fault)`` for what a plain planner returned: the path (N, 3) from exactly
    ``problem.search_start`` to exactly ``problem.search_goal`` (consecutive repeats
    dropped) and None when it is a path :func:`path_fault` finds no fault in; else the
    points returned (None when they are not an (N, 3) array) and the fault."""
    if returned is None:
        return None, "found no path (it returned None)"
    try:
        points = np.array(returned, dtype=np.float64)
    except (TypeError, ValueError):
        return None, (f"returned {type(returned).__name__} {str(returned)[:40]!r}: expected "
                      "a path, an array (N, 3) of numbers")
    if points.size == 0:
        return None, "found no path (it returned an empty path)"
    if points.ndim != 2 or points.shape[1] != 3 or not 2 <= len(points) <= MAX_WAYPOINTS:
        return None, (f"returned an array of shape {points.shape}: expected a path (N, 3), "
                      f"2 <= N <= {MAX_WAYPOINTS:,}")
    if not np.isfinite(points).all():
        row = int(np.flatnonzero(~np.isfinite(points).all(axis=1))[0])
        return None, f"returned point {row} {format_point(points[row])}: expected finite numbers"
    for name, row, end in (("starts", 0, problem.search_start),
                           ("ends", -1, problem.search_goal)):
        if np.linalg.norm(points[row] - end) > END_TOLERANCE:
            where = "start" if row == 0 else "goal"
            return points, (f"returned a path that {name} at {format_point(points[row])}, "
                            f"not at the {where} of the search {format_point(end)} "
                            f"(within {END_TOLERANCE * 1e6:g} um)")
    points[0], points[-1] = problem.search_start, problem.search_goal
    path = distinct(points)
    fault = path_fault(problem.world, problem.margin, path, problem.free_world)
    return path, None if fault is None else f"returned a path whose {fault}"


def path_fault(world: World, margin: float, path: np.ndarray, inflated: World | None = None
               ) -> str | None:
    """What is wrong with the polyline ``path`` (N, 3) in ``world`` with a ``margin`` m,
    measured exactly, or None: its first segment not free in the map inflated by the
    margin (``inflated``, given when already made), with where it first touches a real
    block or leaves the map, else the block or boundary face whose margin it enters and the
    margin it keeps (:func:`~quadnav.world.margins.polyline_margin`)."""
    inflated = world.inflate(margin) if inflated is None else inflated
    segments = np.stack([path[:-1], path[1:]], axis=1)
    blocked = np.flatnonzero(~inflated.segments_free(segments))
    if not blocked.size:
        return None
    k = int(blocked[0])
    a, b = segments[k]
    segment = f"segment {k} from {format_point(a)} to {format_point(b)}"
    hit = world.first_hit(a, b)
    if hit is not None:
        if hit.block is None:
            return (f"{segment} leaves the map {format_box(world.boundary)} at "
                    f"{format_point(hit.point)}")
        return (f"{segment} passes through block {hit.block} "
                f"{format_box(world.blocks[hit.block])}, entering it at "
                f"{format_point(hit.point)}")
    near = inflated.first_hit(a, b)
    what = "the boundary" if near is None or near.block is None else (
        f"block {near.block} {format_box(world.blocks[near.block])}")
    at = "" if near is None else f" at {format_point(near.point)}"
    return (f"{segment} comes within the {margin:g} m margin of {what}{at}, keeping "
            f"{polyline_margin(world, segments[k]):.3g} m")

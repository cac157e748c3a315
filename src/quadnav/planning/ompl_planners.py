"""OMPL's geometric planners behind quadnav's planner interface (the optional ``ompl`` wheel).

:func:`plan_ompl` runs OMPL 2's RRT*, Informed RRT*, BIT*, RRT-Connect or PRM* on a
:class:`~quadnav.planning.problem.PlanningProblem` (:func:`ompl_planner`: one of them as a
planner, the registry's ``ompl:NAME``); :func:`simplify_ompl` runs OMPL's path
simplifier on a path. Both check states and motions *exactly*, with quadnav's numba kernels
(:func:`~quadnav.world.blockgrid.grid_point_free`,
:func:`~quadnav.world.blockgrid.grid_segment_free`, the same our RRT* uses)
instead of OMPL's sampled motion checks, so their paths are collision-free in the same sense
as ours and their lengths compare fairly. The bindings call back into Python for every
check: about 0.8 us per motion and 0.2 us per state on top of the kernel itself.

What OMPL 2.0.1's bindings allow, and so what these functions do:

* **Settings.** ``time_limit``; ``step`` as the range of RRT*, Informed RRT* and RRT-Connect
  (pass ``step = 0.2 * diagonal`` of the inflated boundary for OMPL's own default);
  ``goal_bias`` for RRT* and Informed RRT*; ``rewire_factor`` for RRT*, Informed RRT* and
  BIT*; ``max_iterations``, ``improve_iterations`` and ``stall`` for RRT*, Informed RRT* and
  BIT* (the planners that count their iterations: quadnav's RRT* stopping rules; RRT-Connect
  and PRM* ignore them); ``stop_at_first`` as a cost threshold of
  +inf, which any solution meets. ``goal_tolerance`` and ``informed`` are ignored: the goal
  is reached exactly, and the planner's name says whether it samples informed.
* **Seeds.** OMPL seeds each random generator it creates from one process-wide seed
  generator, which ``RNG.setSeed`` reseeds; everything is built right after it, so the same
  seed draws the same numbers. A search of RRT*, Informed RRT*, BIT* or RRT-Connect is then
  repeatable when it ends at a fixed point — its first solution (``stop_at_first``, and
  RRT-Connect always), an iteration count or the stall rule — before the time limit; a
  search ended by the clock stops at a different iteration each run. PRM* grows its
  roadmap while a second thread looks for solutions, so it is not repeatable. OMPL's seeds
  are nonzero 32-bit numbers: seed ``s`` is passed as ``1 + s mod (2^32 - 1)``.
* **Statistics and progress.** The bindings cannot take OMPL's intermediate-solution
  callback. RRT*, Informed RRT*, BIT* and RRT-Connect are given a termination condition
  written in Python, which OMPL evaluates every iteration: it reads the planner's best
  cost (for ``cost_history`` and the time to the first solution), calls ``progress`` every
  :data:`PROGRESS_PERIOD` s and ends the search. RRT-Connect returns at its first solution,
  so its one history row is at the end of the search. PRM* evaluates its termination
  condition in a second thread, where a Python one deadlocks (the search holds the GIL),
  so PRM* runs under OMPL's timed condition: first until its first solution, then in
  slices of 1 / :data:`PRM_SLICES` of the budget, recording the best length and calling
  ``progress`` after each slice.
* **Tree.** The explored graph comes from OMPL's planner data: a tree for RRT*, Informed
  RRT* and RRT-Connect (its two trees joined), a breadth-first spanning forest of the
  roadmap for PRM*. BIT* gives none: OMPL 2.0.1's BIT* puts every vertex it reports into a
  process-wide static set (``ImplicitGraph::getGraphAsPlannerData``), which keeps each
  search's vertices, space and validity checkers alive until exit; its ``nodes`` is 0.
* **Output.** OMPL's console log is silenced during each call (the level is restored
  after). Nanobind prints "leaked instances" at exit when an OMPL object outlives the
  interpreter; every OMPL object here is local to a call and released when it returns, so
  nothing is printed (this wheel does not expose nanobind's ``set_leak_warnings``).
"""

from __future__ import annotations

import math
import time
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from itertools import chain

import numpy as np
from numpy.typing import ArrayLike
from ompl import base as ob
from ompl import geometric as og
from ompl import util as ou
from scipy.sparse import coo_array
from scipy.sparse.csgraph import breadth_first_order, connected_components

from quadnav.arrays import FloatArray
from quadnav.errors import QuadnavError
from quadnav.planning.contract import OMPL_PLANNERS, OMPL_PREFIX, Planner
from quadnav.planning.problem import PlanningProblem
from quadnav.planning.result import (
    IntArray,
    PlanResult,
    PlanStats,
    Progress,
    no_path_message,
    path_length,
)
from quadnav.planning.settings import PlannerSettings
from quadnav.planning.stall import StallWatch
from quadnav.world.blockgrid import grid_point_free, grid_segment_free
from quadnav.world.model import World

#: A state this close to the goal, metres, reaches it (the path then ends at the goal).
GOAL_THRESHOLD = 1e-9
#: Wall time between two progress reports of a search, s.
PROGRESS_PERIOD = 0.05
#: PRM* searches the budget left after its first solution in this many slices.
PRM_SLICES = 20
#: Planners that evaluate their termination condition in a thread of their own.
_THREADED = frozenset({"PRMstar"})
#: Planners whose graph is not read: OMPL 2.0.1's BIT* keeps every vertex it reports in a
#: process-wide static set, so reading it would keep each search's memory for good.
_GRAPH_KEPT_FOREVER = frozenset({"BITstar"})
#: A search records (wall time s, path length m) rows, one per improvement.
_History = list[tuple[float, float]]


@contextmanager
def _quiet() -> Iterator[None]:
    """Silence OMPL's console log inside the block; restore the level after."""
    level = ou.getLogLevel()
    ou.setLogLevel(ou.LOG_NONE)
    try:
        yield
    finally:
        ou.setLogLevel(level)


def _ompl_seed(seed: int) -> int:
    """OMPL's seed for ``seed`` in [0, 2^63): a nonzero 32-bit number."""
    return 1 + seed % (2**32 - 1)


class _ExactMotionValidator(ob.MotionValidator):
    """OMPL motion validator that checks the segment between two states exactly."""

    def __init__(self, si: ob.SpaceInformation, world: World) -> None:
        super().__init__(si)
        self._grid = world.block_grid
        self._p = np.empty(3)
        self._q = np.empty(3)

    def checkMotion(self, s1: ob.State, s2: ob.State) -> bool:  # noqa: N802 (OMPL's name)
        """Whether the closed segment s1 -> s2 lies in the world's open free space."""
        p, q = self._p, self._q
        p[0] = s1[0]
        p[1] = s1[1]
        p[2] = s1[2]
        q[0] = s2[0]
        q[1] = s2[1]
        q[2] = s2[2]
        return grid_segment_free(p, q, self._grid)


def _space_information(world: World) -> ob.SpaceInformation:
    """OMPL's view of ``world``: R^3 within its boundary, states and motions checked exactly."""
    space = ob.RealVectorStateSpace(3)
    bounds = ob.RealVectorBounds(3)
    bounds.low = world.lower.tolist()
    bounds.high = world.upper.tolist()
    space.setBounds(bounds)
    si = ob.SpaceInformation(space)
    grid = world.block_grid
    # Compile the checks (or load them from numba's cache) now, not inside a timed search.
    grid_point_free(*world.lower, grid)
    grid_segment_free(np.array(world.lower), np.array(world.upper), grid)
    si.setStateValidityChecker(lambda s: grid_point_free(s[0], s[1], s[2], grid))
    si.setMotionValidator(_ExactMotionValidator(si, world))
    si.setup()
    return si


def _state(si: ob.SpaceInformation, point: ArrayLike) -> ob.State:
    """An OMPL state at ``point`` (3,), metres."""
    state = si.allocState()
    state[0:3] = np.asarray(point, dtype=np.float64).tolist()
    return state


def _points(states: Sequence[ob.State]) -> FloatArray:
    """The (N, 3) coordinates of N OMPL states, metres."""
    return np.array([s[0:3] for s in states], dtype=np.float64).reshape(-1, 3)


def _problem_definition(si: ob.SpaceInformation, start: FloatArray, goal: FloatArray,
                        stop_at_first: bool) -> ob.ProblemDefinition:
    """Start, goal (each (3,), metres) and path length as the objective; with
    ``stop_at_first`` any solution meets the objective's cost threshold."""
    pdef = ob.ProblemDefinition(si)
    pdef.setStartAndGoalStates(_state(si, start), _state(si, goal), GOAL_THRESHOLD)
    objective = ob.PathLengthOptimizationObjective(si)
    if stop_at_first:
        objective.setCostThreshold(ob.Cost(math.inf))
    pdef.setOptimizationObjective(objective)
    return pdef


def _planner(name: str, si: ob.SpaceInformation, pdef: ob.ProblemDefinition,
             settings: PlannerSettings, step: float) -> ob.Planner:
    """OMPL's planner ``name``, given each setting it has a setter for, set up for ``pdef``."""
    planner = getattr(og, name)(si)
    if hasattr(planner, "setRange"):
        planner.setRange(step)
    if hasattr(planner, "setGoalBias"):
        planner.setGoalBias(settings.goal_bias)
    if hasattr(planner, "setRewireFactor"):
        planner.setRewireFactor(settings.rewire_factor)
    planner.setProblemDefinition(pdef)
    planner.setup()
    return planner


def _report(progress: Progress | None, elapsed: float, settings: PlannerSettings,
            history: _History) -> None:
    """Call ``progress`` (if any) with the fraction of the budget used and the best length."""
    if progress is not None:
        progress(min(elapsed / settings.time_limit, 1.0), history[-1][1] if history else math.inf)


def _solve_polled(planner: ob.Planner, pdef: ob.ProblemDefinition, settings: PlannerSettings,
                  progress: Progress | None) -> tuple[_History, float, str]:
    """Search under a Python termination condition that OMPL evaluates every iteration:
    the time limit and, for a planner that counts its iterations, quadnav's own sample
    rules, as RRT* stops: the cap and ``improve_iterations`` after the first solution
    (:meth:`~quadnav.planning.settings.PlannerSettings.limit_after_first`), and the stall
    rule (:mod:`~quadnav.planning.stall`), checked at the iteration counts it names.

    Returns the improvements of the planner's best cost, the search's wall time, s, and
    what stopped it (``"time"``, ``"iterations"``, ``"improvement"`` or ``"stall"``).
    """
    best_cost = getattr(planner, "bestCost", None)
    iterations = getattr(planner, "numIterations", None)
    cap = settings.max_iterations or math.inf
    limit = cap if iterations is not None else math.inf
    history: _History = []
    watch: StallWatch | None = None
    stalled = False
    next_report = PROGRESS_PERIOD
    clock = time.perf_counter()

    def done() -> bool:
        nonlocal next_report, limit, watch, stalled
        elapsed = time.perf_counter() - clock
        if best_cost is not None:
            cost = best_cost().value()
            if cost < (history[-1][1] if history else math.inf):
                if not history and iterations is not None:
                    limit = settings.limit_after_first(iterations())
                    if settings.stall is not None:
                        watch = StallWatch(settings.stall, iterations(), cost)
                history.append((elapsed, cost))
            if watch is not None and iterations() >= watch.next_check:
                stalled = watch.stalled(cost)
        if elapsed >= next_report:
            next_report = elapsed + PROGRESS_PERIOD
            _report(progress, elapsed, settings, history)
        return stalled or elapsed >= settings.time_limit or (
            iterations is not None and iterations() >= limit)

    planner.solve(ob.PlannerTerminationCondition(done))
    seconds = time.perf_counter() - clock
    if stalled:
        return history, seconds, "stall"
    if iterations is None or iterations() < limit:
        return history, seconds, "time"
    return history, seconds, "iterations" if iterations() >= cap else "improvement"


def _solve_sliced(planner: ob.Planner, pdef: ob.ProblemDefinition, settings: PlannerSettings,
                  progress: Progress | None) -> tuple[_History, float, str]:
    """Search under OMPL's timed termination condition: until the first solution, then in
    slices of the budget left. Returns the lengths after each slice that improved, the
    search's wall time, s, and what stopped it: ``"time"`` (PRM* counts no samples)."""
    objective = pdef.getOptimizationObjective()
    threshold = objective.getCostThreshold()
    objective.setCostThreshold(ob.Cost(math.inf))
    history: _History = []
    clock = time.perf_counter()
    elapsed = 0.0
    while elapsed < settings.time_limit and not (history and settings.stop_at_first):
        left = settings.time_limit - elapsed
        budget = min(left, settings.time_limit / PRM_SLICES) if history else left
        planner.solve(ob.timedPlannerTerminationCondition(budget))
        elapsed = time.perf_counter() - clock
        if pdef.hasExactSolution():
            length = pdef.getSolutionPath().length()
            if length < (history[-1][1] if history else math.inf):
                history.append((elapsed, length))
            objective.setCostThreshold(threshold)
        _report(progress, elapsed, settings, history)
    return history, elapsed, "time"


def _solution(world: World, pdef: ob.ProblemDefinition, goal: FloatArray) -> FloatArray | None:
    """The exact solution's points (N, 3) ending exactly at ``goal`` (a last free segment
    is added to a path that stops within :data:`GOAL_THRESHOLD` of it), or ``None``."""
    if not pdef.hasExactSolution():
        return None
    points = _points(pdef.getSolutionPath().getStates())
    if len(points) >= 2 and np.array_equal(points[-1], goal):
        return points
    return np.vstack([points, goal]) if world.segment_free(points[-1], goal) else None


def _tree(planner: ob.Planner, si: ob.SpaceInformation) -> tuple[FloatArray, IntArray]:
    """The planner's vertices (M, 3) and one parent per vertex (M,), -1 for a root.

    The parents form a breadth-first spanning forest of the planner's graph, ignoring edge
    directions, rooted at the start vertex (or, in a component without one, at its first
    vertex): for a tree that is the tree itself; for a roadmap, some of its edges.
    """
    data = ob.PlannerData(si)
    planner.getPlannerData(data)
    count = data.numVertices()
    nodes = _points([data.getVertex(i).getState() for i in range(count)])
    outgoing = [data.getEdges(i) for i in range(count)]
    tails = np.repeat(np.arange(count), [len(edges) for edges in outgoing])
    heads = np.fromiter(chain.from_iterable(outgoing), dtype=np.int64, count=len(tails))
    graph = coo_array((np.ones(len(tails)), (tails, heads)), shape=(count, count))
    _, component = connected_components(graph, directed=False)
    roots = np.unique(component, return_index=True)[1]
    for k in range(data.numStartVertices()):
        start = data.getStartIndex(k)
        roots[component[start]] = start
    # A virtual vertex joined to every root makes one breadth-first search span the forest.
    forest = coo_array(
        (np.ones(len(tails) + len(roots)),
         (np.concatenate([tails, np.full(len(roots), count)]),
          np.concatenate([heads, roots]))),
        shape=(count + 1, count + 1)).tocsr()
    _, predecessors = breadth_first_order(forest, count, directed=False,
                                          return_predecessors=True)
    parents = predecessors[:count].astype(np.int64)
    parents[parents == count] = -1
    return nodes, parents


def plan_ompl(problem: PlanningProblem, settings: PlannerSettings, name: str,
              progress: Progress | None = None) -> PlanResult:
    """Plan a path for ``problem`` with OMPL's geometric planner ``name``.

    Args:
        problem: a checked query; OMPL searches ``problem.free_world``.
        settings: budget, seed and tuning (see the module docstring for what each planner
            uses).
        name: one of ``RRTstar``, ``InformedRRTstar``, ``BITstar``, ``RRTConnect``,
            ``PRMstar``.
        progress: called now and then with (fraction of the time budget used, best
            length so far in metres or inf).

    Returns:
        The result, planner ``"ompl:" + name``; its path (N, 3) runs from exactly
        ``problem.start`` to exactly ``problem.goal``.
    """
    if name not in OMPL_PLANNERS:
        raise QuadnavError(f"unknown OMPL planner {name!r}; expected one of "
                           f"{', '.join(OMPL_PLANNERS)}")
    world = problem.free_world
    with _quiet():
        ou.RNG.setSeed(_ompl_seed(settings.seed))
        setup_began = time.perf_counter()
        si = _space_information(world)
        pdef = _problem_definition(si, problem.search_start, problem.search_goal,
                                   settings.stop_at_first)
        planner = _planner(name, si, pdef, settings, settings.step_for(world))
        setup_seconds = time.perf_counter() - setup_began
        solve = _solve_sliced if name in _THREADED else _solve_polled
        history, seconds, stopped_by = solve(planner, pdef, settings, progress)
        search_path = _solution(world, pdef, problem.search_goal)
        nodes, parents = ((np.zeros((0, 3)), np.zeros(0, dtype=np.int64))
                          if name in _GRAPH_KEPT_FOREVER else _tree(planner, si))
        iterations = planner.numIterations() if hasattr(planner, "numIterations") else 0
    if search_path is None:
        history = []
    elif not history or path_length(search_path) < history[-1][1]:
        history.append((seconds, path_length(search_path)))
    stats = PlanStats(iterations=int(iterations), nodes=len(nodes), seconds=seconds,
                      time_to_first=history[0][0] if history else None,
                      cost_history=np.array(history).reshape(-1, 2),
                      stopped_by=stopped_by,
                      setup_seconds=setup_seconds)
    return PlanResult(
        planner=OMPL_PREFIX + name,
        solved=search_path is not None,
        path=problem.full_path(search_path) if search_path is not None else np.zeros((0, 3)),
        tree_nodes=nodes,
        tree_parents=parents,
        stats=stats,
        seed=settings.seed,
        message="" if search_path is not None else no_path_message(
            stats, settings.max_iterations, settings.time_limit),
    )


def ompl_planner(name: str) -> Planner:
    """OMPL's planner ``name`` (one of :data:`~quadnav.planning.contract.OMPL_PLANNERS`) as
    a :data:`~quadnav.planning.contract.Planner`: what the registry's ``ompl:NAME`` is."""

    def planner(problem: PlanningProblem, settings: PlannerSettings,
                progress: Progress | None) -> PlanResult:
        return plan_ompl(problem, settings, name, progress)

    return planner


def simplify_ompl(problem: PlanningProblem, path: ArrayLike, time_limit: float = 1.0,
                  seed: int = 0) -> FloatArray:
    """Shorten a path with OMPL's path simplifier, checking motions exactly.

    OMPL's ``PathSimplifier.simplify`` (vertex reduction, shortcuts, then B-spline
    smoothing, which adds vertices) runs on the search part of the path, from
    ``problem.search_start`` to ``problem.search_goal``; the legs are added back.

    Args:
        problem: the query the path solves.
        path: (N, 3) collision-free path from ``problem.start`` to ``problem.goal``, metres.
        time_limit: wall-time budget of the simplifier, s.
        seed: seed of the simplifier's random choices.

    Returns:
        (M, 3) collision-free path with the same ends, not longer than ``path``.
    """
    points = np.asarray(path, dtype=np.float64).reshape(-1, 3)
    search = problem.search_part(points)
    with _quiet():
        ou.RNG.setSeed(_ompl_seed(seed))
        si = _space_information(problem.free_world)
        geometric = og.PathGeometric(si, [_state(si, p) for p in search])
        og.PathSimplifier(si).simplify(geometric, time_limit)
        simplified = _points(geometric.getStates())
    # OMPL keeps only changes that shorten the path; rounding could still add a few ulps.
    return problem.full_path(simplified if path_length(simplified) <= path_length(search)
                             else search)


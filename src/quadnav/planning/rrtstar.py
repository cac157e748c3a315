"""RRT* over the inflated world: :func:`plan_rrtstar`.

The iterations run in numba (:mod:`quadnav.planning.rrtstar_kernel`) in chunks; between
chunks this driver checks the wall clock, grows the arrays, records improvements,
applies the stall rule (:mod:`quadnav.planning.stall`; a chunk ends at each of its checks)
and reports progress. Chunks start small and double while they take under
:data:`CHUNK_SECONDS`, so the time to the first solution is measured to within a chunk
of a few iterations and the time budget is kept to within a few milliseconds. The arrays
grow only when full, so the search does not depend on where the chunks end: the same seed
and sample budget give the same tree, to the last bit, however fast the machine.

The near radius follows OMPL (see the kernel's docstring).
"""

from __future__ import annotations

import functools
import time

import numpy as np

from quadnav.limits import PLAN_ITERATIONS
from quadnav.planning.nodegrid import new_node_grid, rebuild
from quadnav.planning.problem import PlanningProblem
from quadnav.planning.result import PlanResult, PlanStats, Progress, no_path_message
from quadnav.planning.rrtstar_kernel import (
    BEST_COST,
    BEST_VERTEX,
    ITERATIONS,
    NODES,
    Query,
    Tree,
    grow,
    start_tree,
)
from quadnav.planning.settings import PlannerSettings
from quadnav.planning.stall import StallWatch
from quadnav.profiling import stage
from quadnav.world.model import World

#: Name of this planner in results and on the command line.
NAME = "rrtstar"
#: A chunk of iterations doubles while it takes less than this, s.
CHUNK_SECONDS = 0.002
_FIRST_CHUNK = 16
_MAX_CHUNK = 1 << 16
_INITIAL_CAPACITY = 1 << 12


def _frame(start: np.ndarray, goal: np.ndarray) -> np.ndarray:
    """A rotation (3, 3) whose first column points from start to goal."""
    axis = goal - start
    norm = float(np.linalg.norm(axis))
    if norm == 0.0:
        return np.eye(3)
    # QR of [axis, the two unit vectors least aligned with it] is an orthonormal frame.
    others = np.eye(3)[:, np.argsort(np.abs(axis))[:2]]
    q, r = np.linalg.qr(np.column_stack([axis / norm, others]))
    return q * np.sign(np.diag(r))


def empty_tree(capacity: int) -> Tree:
    """Arrays for ``capacity`` vertices, nothing in them (no solution yet)."""
    return Tree(
        nodes=np.zeros((capacity, 3)),
        cost=np.zeros(capacity),
        parent=np.full(capacity, -1, dtype=np.int64),
        first_child=np.full(capacity, -1, dtype=np.int64),
        next_sibling=np.full(capacity, -1, dtype=np.int64),
        goal_distance=np.full(capacity, np.inf),
        near=np.zeros(capacity, dtype=np.int64),
        near_distance=np.zeros(capacity),
        near_order=np.zeros(capacity),
        stack=np.zeros(capacity, dtype=np.int64),
        node_grid=new_node_grid(capacity),
        counts=np.zeros(2, dtype=np.int64),
        best=np.array([np.inf, -1.0]),
    )


def grown_tree(tree: Tree, capacity: int, origin: np.ndarray, extent: np.ndarray) -> Tree:
    """A copy of the full ``tree`` with room for ``capacity`` vertices, whose node grid over
    the box ``origin`` (3,), ``extent`` (3,) is rebuilt; counts and best are shared."""
    count = int(tree.counts[NODES])
    bigger = empty_tree(capacity)._replace(counts=tree.counts, best=tree.best)
    for name in ("nodes", "cost", "parent", "first_child", "next_sibling", "goal_distance"):
        getattr(bigger, name)[:count] = getattr(tree, name)[:count]
    rebuild(bigger.nodes, count, origin, extent, *bigger.node_grid)
    return bigger


def path_to(tree: Tree, vertex: int) -> np.ndarray:
    """Vertices (K, 3) from the root to ``vertex``."""
    chain = []
    while vertex >= 0:
        chain.append(vertex)
        vertex = int(tree.parent[vertex])
    return tree.nodes[chain[::-1]].copy()


@functools.cache
def _load_kernels() -> None:
    """Compile, or load from numba's cache, every kernel the search calls, by running
    them once on a one-block world, so that loading is not charged to a search."""
    world = World(boundary=np.array([0.0, 0.0, 0.0, 1.0, 1.0, 1.0]),
                  blocks=np.array([[0.4, 0.4, 0.4, 0.6, 0.6, 0.6]]))
    start, goal = np.array([0.1, 0.1, 0.1]), np.array([0.9, 0.9, 0.9])
    problem = PlanningProblem.free(world, world, start, goal)
    _search(problem, PlannerSettings(max_iterations=200, seed=0, time_limit=3600.0), None)
    tree = empty_tree(1)
    tree.counts[NODES] = 1
    grown_tree(tree, 2, world.lower.copy(), world.extent.copy())  # writable, as _search's


def plan_rrtstar(problem: PlanningProblem, settings: PlannerSettings,
                 progress: Progress | None = None) -> PlanResult:
    """Search ``problem`` with RRT* (see the module docstring) under ``settings``.

    The kernels are compiled (or loaded from numba's cache) before the clock starts.
    """
    _load_kernels()
    return _search(problem, settings, progress)


def _search(problem: PlanningProblem, settings: PlannerSettings,
            progress: Progress | None) -> PlanResult:
    """RRT* proper; see :func:`plan_rrtstar`. The set-up (block grid, sampling frame,
    random generator, empty tree) is timed apart from the search, as OMPL's is."""
    setup_began = time.perf_counter()
    world = problem.free_world
    # Writable copies, so numba sees the same array types whatever the caller passed.
    start, goal = np.array(problem.search_start), np.array(problem.search_goal)
    step = settings.step_for(world)
    goal_tolerance = settings.goal_tolerance_for(world)
    tuning = np.array([step, settings.goal_bias, goal_tolerance,
                       settings.rewire_factor,
                       1.0 if settings.informed else 0.0])
    grid = world.block_grid
    rotation = _frame(start, goal)
    origin, extent = world.lower.copy(), world.extent.copy()
    rng = np.random.default_rng(settings.seed)
    cap = settings.max_iterations or PLAN_ITERATIONS.high  # also bounds the tree's memory
    limit = cap
    stopped_by = None
    watch: StallWatch | None = None
    query = Query(start, goal, tuning, rotation, grid, origin, extent)
    tree = empty_tree(min(_INITIAL_CAPACITY, limit + 1))
    counts, best = tree.counts, tree.best
    start_tree(query, tree)
    history: list[tuple[float, float]] = []
    time_to_first = None
    chunk = _FIRST_CHUNK
    clock = time.perf_counter()
    setup_seconds = clock - setup_began
    while True:
        now = time.perf_counter() - clock
        if best[BEST_VERTEX] >= 0 and (not history or best[BEST_COST] < history[-1][1]):
            if not history:  # the kernel returns at the first solution: this count is exact
                first = int(counts[ITERATIONS])
                limit = min(limit, settings.limit_after_first(first))
                if settings.stall is not None:
                    watch = StallWatch(settings.stall, first, float(best[BEST_COST]))
            history.append((now, float(best[BEST_COST])))
            time_to_first = history[0][0]
        if progress is not None:
            progress(min(now / settings.time_limit, 1.0), float(best[BEST_COST]))
        if (watch is not None and counts[ITERATIONS] == watch.next_check
                and watch.stalled(float(best[BEST_COST]))):
            stopped_by = "stall"
        elif counts[ITERATIONS] >= limit:
            capped = limit == cap and time_to_first is None
            stopped_by = "iterations" if capped else "improvement"
        elif now >= settings.time_limit:
            stopped_by = "time"
        else:
            stopped_by = None
        if stopped_by is not None:
            break
        if counts[NODES] == len(tree.cost):  # full: grow at a count the seed fixes
            tree = grown_tree(tree, 2 * len(tree.cost), origin, extent)
        # An iteration adds at most one vertex: a chunk never outgrows the arrays, so they
        # grow (and the node grid is rebuilt) at the same iteration however long chunks take.
        # A chunk also ends at the stall rule's next check, so each check sees the sample
        # count it names.
        end = limit if watch is None else min(limit, watch.next_check)
        chunk = int(min(chunk, end - counts[ITERATIONS], len(tree.cost) - counts[NODES]))
        began = time.perf_counter()
        unsolved = bool(best[BEST_VERTEX] < 0)
        with stage("first path" if unsolved else "improvement"):
            grow(rng, chunk, unsolved, query, tree)
        if time.perf_counter() - began < CHUNK_SECONDS:
            chunk = min(2 * chunk, _MAX_CHUNK)
    count = int(counts[NODES])
    stats = PlanStats(iterations=int(counts[ITERATIONS]), nodes=count,
                      seconds=time.perf_counter() - clock, time_to_first=time_to_first,
                      cost_history=np.array(history).reshape(-1, 2), stopped_by=stopped_by,
                      setup_seconds=setup_seconds)
    explored = (tree.nodes[:count].copy(), tree.parent[:count].copy())
    if best[BEST_VERTEX] < 0:
        return PlanResult(NAME, False, np.zeros((0, 3)), *explored, stats, settings.seed,
                          no_path_message(stats, cap, settings.time_limit))
    search_path = path_to(tree, int(best[BEST_VERTEX]))
    if not np.array_equal(search_path[-1], goal):
        search_path = np.vstack([search_path, goal])
    return PlanResult(NAME, True, problem.full_path(search_path), *explored, stats,
                      settings.seed)

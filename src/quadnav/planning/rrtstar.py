"""RRT* over the inflated world: :func:`plan_rrtstar`.

The iterations run in numba (:mod:`quadnav.planning.rrtstar_kernel`) in chunks; between
chunks this driver checks the wall clock, grows the arrays, records improvements and
reports progress. Chunks start small and double while they take under
:data:`CHUNK_SECONDS`, so the time to the first solution is measured to within a chunk
of a few iterations and the time budget is kept to within a few milliseconds. The arrays
grow only when full, so the search does not depend on where the chunks end: the same seed
and sample budget give the same tree, to the last bit, however fast the machine.

The near radius follows OMPL (see the kernel's docstring).
"""

from __future__ import annotations

import functools
import time
from dataclasses import dataclass

import numpy as np

from quadnav.limits import PLAN_ITERATIONS
from quadnav.planning.nodegrid import new_node_grid, rebuild
from quadnav.planning.problem import PlanningProblem
from quadnav.planning.registry import Progress
from quadnav.planning.result import PlanResult, PlanStats, no_path_message
from quadnav.planning.rrtstar_kernel import (
    BEST_COST,
    BEST_VERTEX,
    ITERATIONS,
    NODES,
    grow,
    start_tree,
)
from quadnav.planning.settings import PlannerSettings
from quadnav.world.blockgrid import build_block_grid
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


@dataclass
class TreeState:
    """The arrays the kernel reads and writes; grown by doubling when full."""

    nodes: np.ndarray
    cost: np.ndarray
    parent: np.ndarray
    first_child: np.ndarray
    next_sibling: np.ndarray
    goal_vertices: np.ndarray
    near: np.ndarray
    near_distance: np.ndarray
    near_order: np.ndarray
    stack: np.ndarray
    node_grid: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]

    @classmethod
    def empty(cls, capacity: int) -> TreeState:
        """Arrays for ``capacity`` vertices, nothing in them."""
        return cls(
            nodes=np.zeros((capacity, 3)),
            cost=np.zeros(capacity),
            parent=np.full(capacity, -1, dtype=np.int64),
            first_child=np.full(capacity, -1, dtype=np.int64),
            next_sibling=np.full(capacity, -1, dtype=np.int64),
            goal_vertices=np.zeros(capacity, dtype=np.int64),
            near=np.zeros(capacity, dtype=np.int64),
            near_distance=np.zeros(capacity),
            near_order=np.zeros(capacity),
            stack=np.zeros(capacity, dtype=np.int64),
            node_grid=new_node_grid(capacity),
        )

    @property
    def capacity(self) -> int:
        """How many vertices fit."""
        return len(self.cost)

    def grown(self, count: int, capacity: int, origin: np.ndarray, extent: np.ndarray
               ) -> TreeState:
        """A copy with room for ``capacity`` vertices holding the first ``count``, whose
        node grid over the box ``origin`` (3,), ``extent`` (3,) is rebuilt."""
        bigger = TreeState.empty(capacity)
        for name in ("nodes", "cost", "parent", "first_child", "next_sibling",
                     "goal_vertices"):
            getattr(bigger, name)[:count] = getattr(self, name)[:count]
        rebuild(bigger.nodes, count, origin, extent, *bigger.node_grid)
        return bigger

    def path_to(self, vertex: int) -> np.ndarray:
        """Vertices (K, 3) from the root to ``vertex``."""
        chain = []
        while vertex >= 0:
            chain.append(vertex)
            vertex = int(self.parent[vertex])
        return self.nodes[chain[::-1]].copy()


@functools.cache
def _load_kernels() -> None:
    """Compile, or load from numba's cache, every kernel the search calls, by running
    them once on a one-block world, so that loading is not charged to a search."""
    world = World(boundary=np.array([0.0, 0.0, 0.0, 1.0, 1.0, 1.0]),
                  blocks=np.array([[0.4, 0.4, 0.4, 0.6, 0.6, 0.6]]))
    start, goal = np.array([0.1, 0.1, 0.1]), np.array([0.9, 0.9, 0.9])
    problem = PlanningProblem.free(world, world, start, goal)
    _search(problem, PlannerSettings(max_iterations=200, seed=0, time_limit=3600.0), None)
    TreeState.empty(1).grown(1, 2, world.lower, world.extent)


def plan_rrtstar(problem: PlanningProblem, settings: PlannerSettings,
                 progress: Progress | None = None) -> PlanResult:
    """Search ``problem`` with RRT* (see the module docstring) under ``settings``.

    The kernels are compiled (or loaded from numba's cache) before the clock starts.
    """
    _load_kernels()
    return _search(problem, settings, progress)


def _search(problem: PlanningProblem, settings: PlannerSettings,
            progress: Progress | None) -> PlanResult:
    """RRT* proper; see :func:`plan_rrtstar`."""
    clock = time.perf_counter()
    world = problem.free_world
    # Writable copies, so numba sees the same array types whatever the caller passed.
    start, goal = np.array(problem.search_start), np.array(problem.search_goal)
    step = settings.step_for(world)
    goal_tolerance = settings.goal_tolerance_for(world)
    tuning = np.array([step, settings.goal_bias, goal_tolerance,
                       settings.rewire_factor,
                       1.0 if settings.informed else 0.0])
    grid = build_block_grid(world)
    rotation = _frame(start, goal)
    origin, extent = world.lower.copy(), world.extent.copy()
    rng = np.random.default_rng(settings.seed)
    cap = settings.max_iterations or PLAN_ITERATIONS.high  # also bounds the tree's memory
    limit = cap
    stopped_by = None
    state = TreeState.empty(min(_INITIAL_CAPACITY, limit + 1))
    counts = np.zeros(3, dtype=np.int64)
    best = np.array([np.inf, -1.0])
    start_tree(start, goal, goal_tolerance, grid, state.nodes, state.cost, state.parent,
               state.first_child, state.next_sibling, origin, extent, state.node_grid,
               state.goal_vertices, counts, best)
    history: list[tuple[float, float]] = []
    time_to_first = None
    chunk = _FIRST_CHUNK
    while True:
        now = time.perf_counter() - clock
        if best[BEST_VERTEX] >= 0 and (not history or best[BEST_COST] < history[-1][1]):
            if not history:  # the kernel returns at the first solution: this count is exact
                limit = min(limit, settings.limit_after_first(int(counts[ITERATIONS])))
            history.append((now, float(best[BEST_COST])))
            time_to_first = history[0][0]
        if progress is not None:
            progress(min(now / settings.time_limit, 1.0), float(best[BEST_COST]))
        if counts[ITERATIONS] >= limit:
            capped = limit == cap and time_to_first is None
            stopped_by = "iterations" if capped else "improvement"
        elif now >= settings.time_limit:
            stopped_by = "time"
        else:
            stopped_by = None
        if stopped_by is not None:
            break
        if counts[NODES] == state.capacity:  # full: grow at a count the seed fixes
            state = state.grown(int(counts[NODES]), 2 * state.capacity, origin, extent)
        # An iteration adds at most one vertex: a chunk never outgrows the arrays, so they
        # grow (and the node grid is rebuilt) at the same iteration however long chunks take.
        chunk = int(min(chunk, limit - counts[ITERATIONS], state.capacity - counts[NODES]))
        began = time.perf_counter()
        grow(rng, chunk, bool(best[BEST_VERTEX] < 0), start, goal, tuning, rotation, grid,
             state.nodes, state.cost, state.parent, state.first_child, state.next_sibling,
             origin, extent, state.node_grid, state.goal_vertices, counts, best, state.near,
             state.near_distance, state.near_order, state.stack)
        if time.perf_counter() - began < CHUNK_SECONDS:
            chunk = min(2 * chunk, _MAX_CHUNK)
    count = int(counts[NODES])
    stats = PlanStats(iterations=int(counts[ITERATIONS]), nodes=count,
                      seconds=time.perf_counter() - clock, time_to_first=time_to_first,
                      cost_history=np.array(history).reshape(-1, 2), stopped_by=stopped_by)
    tree = (state.nodes[:count].copy(), state.parent[:count].copy())
    if best[BEST_VERTEX] < 0:
        return PlanResult(NAME, False, np.zeros((0, 3)), *tree, stats, settings.seed,
                          no_path_message(stats, cap, settings.time_limit))
    search_path = state.path_to(int(best[BEST_VERTEX]))
    if not np.array_equal(search_path[-1], goal):
        search_path = np.vstack([search_path, goal])
    return PlanResult(NAME, True, problem.full_path(search_path), *tree, stats, settings.seed)

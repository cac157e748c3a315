"""What every planner returns: :class:`PlanResult`, with :class:`PlanStats`.

A planner's result is plain data — the path, the explored tree (for drawing) and how the
search went — so that any planner (ours, OMPL's) can be drawn, compared and post-processed
the same way.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from quadnav.arrays import FloatArray, frozen, read_only
from quadnav.limits import PLAN_ITERATIONS

IntArray = NDArray[np.int64]
#: ``progress(fraction of the budget used in [0, 1], how close the search is)``, called
#: while a search runs: the second number is the best path length so far in metres (inf
#: before one is found) for a path planner, the distance in metres from the goal to the
#: tree's closest state for a kinodynamic one.
Progress = Callable[[float, float], None]


def path_length(path: FloatArray) -> float:
    """Sum of the segment lengths of a polyline (N, 3), metres (0 for N < 2)."""
    points = np.asarray(path, dtype=np.float64)
    if len(points) < 2:
        return 0.0
    return float(np.linalg.norm(np.diff(points, axis=0), axis=1).sum())


def distinct(points: ArrayLike) -> FloatArray:
    """``points`` (N, 3) as float64 with consecutive repeats dropped."""
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    return pts[np.concatenate([[True], np.any(np.diff(pts, axis=0) != 0, axis=1)])]


def nearest_on_polyline(points: ArrayLike, polyline: ArrayLike) -> FloatArray:
    """The nearest point (N, 3) of the polyline (M >= 1, 3) to each of ``points`` (N, 3)."""
    p = np.asarray(points, dtype=np.float64).reshape(-1, 1, 3)
    line = np.asarray(polyline, dtype=np.float64).reshape(-1, 3)
    if len(line) == 1:
        return np.repeat(line, p.shape[0], axis=0)
    a, b = line[:-1], line[1:]
    ab = b - a
    along = np.einsum("nkd,kd->nk", p - a, ab) / np.maximum(np.einsum("kd,kd->k", ab, ab),
                                                             1e-300)
    foot = a + np.clip(along, 0.0, 1.0)[..., None] * ab  # (N, K, 3)
    best = np.argmin(np.sum((foot - p) ** 2, axis=2), axis=1)
    return foot[np.arange(len(best)), best]


@dataclass(frozen=True)
class PostStep:
    """One post-processing step applied to a path.

    Attributes:
        name: what was done, e.g. ``"shortcut"`` or ``"smooth"``.
        length: path length after the step, metres.
        vertices: number of path vertices after the step.
        seconds: wall time the step took.
    """

    name: str
    length: float
    vertices: int
    seconds: float


@dataclass(frozen=True, eq=False)
class PlanStats:
    """How a search went.

    Attributes:
        iterations: samples drawn (for OMPL planners: as reported, else 0).
        nodes: vertices in the tree or roadmap.
        seconds: wall time of the search, s, after its set-up.
        time_to_first: wall time from the end of the set-up until the first solution, s;
            ``None`` if none was found.
        cost_history: (K, 2) rows ``(time s, path length m)``, one per improvement of
            the best solution, in time order; (0, 2) when there was no solution.
        post: post-processing steps applied after the search, in order.
        stopped_by: what ended the search: ``"iterations"`` (the sample cap),
            ``"improvement"`` (the samples allowed after the first solution),
            ``"stall"`` (the best length stopped improving:
            :mod:`~quadnav.planning.stall`), ``"time"`` (the time budget), ``"direct"``
            (the goal was in sight of the start), or ``None`` when the planner does not say.
        setup_seconds: wall time of the set-up before the search's clock started, s
            (spatial indexes, the planner's arrays or objects; 0 when not measured).
    """

    iterations: int
    nodes: int
    seconds: float
    time_to_first: float | None
    cost_history: FloatArray = field(default_factory=lambda: np.zeros((0, 2)))
    post: tuple[PostStep, ...] = ()
    stopped_by: str | None = None
    setup_seconds: float = 0.0

    def __post_init__(self) -> None:
        history = np.array(self.cost_history, dtype=np.float64).reshape(-1, 2)
        object.__setattr__(self, "cost_history", read_only(history))


@dataclass(frozen=True, eq=False)
class PlanResult:
    """The outcome of one planning query.

    Attributes:
        planner: the planner's name, e.g. ``"rrtstar"`` or ``"ompl:BITstar"``.
        solved: whether a collision-free path was found.
        path: (N, 3) polyline in metres from exactly the start to exactly the goal;
            (0, 3) when not solved.
        tree_nodes: (M, 3) explored vertices, metres (may be (0, 3)).
        tree_parents: (M,) index of each vertex's parent in ``tree_nodes``, -1 for a root
            (for a roadmap, edges are given the same way, one parent per vertex).
        stats: how the search went.
        seed: the seed the planner ran with.
        message: one line for the user, e.g. why there is no path.
    """

    planner: str
    solved: bool
    path: FloatArray
    tree_nodes: FloatArray
    tree_parents: IntArray
    stats: PlanStats
    seed: int
    message: str = ""

    def __post_init__(self) -> None:
        # A result made from another (``replace``) shares its frozen tree, not a copy.
        path = frozen(self.path, np.float64).reshape(-1, 3)
        nodes = frozen(self.tree_nodes, np.float64).reshape(-1, 3)
        parents = frozen(self.tree_parents, np.int64).reshape(-1)
        if len(parents) != len(nodes):
            raise ValueError(f"tree_parents has {len(parents)} entries for {len(nodes)} nodes")
        if self.solved != (len(path) >= 2):
            raise ValueError("a solved result needs a path of at least 2 points, else none")
        object.__setattr__(self, "path", path)
        object.__setattr__(self, "tree_nodes", nodes)
        object.__setattr__(self, "tree_parents", parents)

    @property
    def length(self) -> float:
        """Path length in metres (``inf`` when not solved)."""
        return path_length(self.path) if self.solved else float("inf")

    def replace(self, **changes: object) -> PlanResult:
        """A copy with some fields changed (see :func:`dataclasses.replace`)."""
        return dataclasses.replace(self, **changes)

    def tree_edges(self) -> FloatArray:
        """(E, 2, 3) segments from each non-root vertex to its parent, for drawing."""
        return tree_edges(self.tree_nodes, self.tree_parents)


def tree_edges(nodes: FloatArray, parents: IntArray) -> FloatArray:
    """(E, 2, 3) segments from each vertex of ``nodes`` (N, 3), m, to its parent (row in
    ``parents`` (N,), -1 for a root)."""
    child = np.flatnonzero(parents >= 0)
    return np.stack([nodes[child], nodes[parents[child]]], axis=1).reshape(-1, 2, 3)


def no_path_message(stats: PlanStats, max_iterations: int | None, time_limit: float) -> str:
    """One line saying that a search found no path, which limit ended it and the
    command-line flag that lifts it."""
    if stats.stopped_by == "iterations" and max_iterations is None:
        return (f"no path found in {stats.iterations:,} samples ({stats.seconds:.3g} s), the "
                "most a search may take; passages may be too narrow for the margin: try "
                "quadnav map check, a smaller --margin or another --seed")
    if stats.stopped_by == "iterations":
        return (f"no path found: the search stopped at its cap of {max_iterations:,} samples "
                f"after {stats.seconds:.3g} s of its {time_limit:g} s; raise --iterations "
                f"(at most {PLAN_ITERATIONS.high:,}; 0: the time budget alone)")
    return (f"no path found in {stats.seconds:.3g} s ({stats.iterations:,} samples): the "
            "time budget ran out; raise --time")

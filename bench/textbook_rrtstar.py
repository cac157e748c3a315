"""Baseline for ``bench/planning.py``: RRT* written the way course reports write it.

Correct but slow on purpose — it is what quadnav's planner is measured against:

* the tree is a Python list of :class:`Node` objects; nearest and near searches loop
  over every node in Python;
* collision checks sample points along each segment every :data:`RESOLUTION` metres
  and test each point against every inflated block in a Python loop (closed boxes, and
  the open boundary box, as in :mod:`quadnav.world.geometry`);
* goal bias, steer by ``step``, near radius ``gamma (log n / n)^(1/3)`` capped by the
  step, choose parent, rewire (cost changes pass down to the descendants), and a vertex
  within the goal tolerance is joined to the goal by a straight segment.

Sampled checks are approximate: a segment may cut a corner of an inflated block by a
chord shorter than :data:`RESOLUTION`. Any segment that reaches a *real* block crosses
at least ``2 x margin`` of its inflated block, so with ``RESOLUTION <= 2 x margin``
(0.1 m against the usual 0.2 m margin) paths never touch a real block; they may only
dip into the safety margin.
"""

from __future__ import annotations

import math
import random
import time
from dataclasses import dataclass, field

import numpy as np

from quadnav.planning import PlannerSettings, PlanningProblem, PlanResult, PlanStats

#: Spacing of the points checked along a segment, metres (see the module docstring).
RESOLUTION = 0.1

Point = tuple[float, float, float]
Box = tuple[float, float, float, float, float, float]


@dataclass
class Node:
    """A tree vertex: position (metres), parent index (-1 for the root), cost from the
    root (metres) and the indices of its children."""

    position: Point
    parent: int
    cost: float
    children: list[int] = field(default_factory=list)


def _distance(a: Point, b: Point) -> float:
    return math.sqrt((a[0] - b[0]) ** 2 + (a[1] - b[1]) ** 2 + (a[2] - b[2]) ** 2)


def _point_free(p: Point, blocks: list[Box], boundary: Box) -> bool:
    """Whether ``p`` is strictly inside the boundary and outside every closed block."""
    x, y, z = p
    if not (boundary[0] < x < boundary[3] and boundary[1] < y < boundary[4]
            and boundary[2] < z < boundary[5]):
        return False
    for x0, y0, z0, x1, y1, z1 in blocks:
        if x0 <= x <= x1 and y0 <= y <= y1 and z0 <= z <= z1:
            return False
    return True


def _segment_free(a: Point, b: Point, blocks: list[Box], boundary: Box) -> bool:
    """Whether the points every :data:`RESOLUTION` metres from ``a`` to ``b`` (both
    ends included) are all free."""
    count = max(1, math.ceil(_distance(a, b) / RESOLUTION))
    for i in range(count + 1):
        t = i / count
        point = (a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), a[2] + t * (b[2] - a[2]))
        if not _point_free(point, blocks, boundary):
            return False
    return True


def _steer(a: Point, b: Point, step: float) -> Point:
    """``b``, or the point ``step`` metres from ``a`` towards it when it is farther."""
    d = _distance(a, b)
    if d <= step:
        return b
    s = step / d
    return (a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1]), a[2] + s * (b[2] - a[2]))


def _reparent(nodes: list[Node], child: int, parent: int, cost: float) -> None:
    """Hang ``child`` under ``parent`` with the new ``cost``; pass the change down."""
    old = nodes[child]
    nodes[old.parent].children.remove(child)
    nodes[parent].children.append(child)
    old.parent = parent
    delta = cost - old.cost
    stack = [child]
    while stack:
        node = nodes[stack.pop()]
        node.cost += delta
        stack.extend(node.children)


def _gamma(boundary: Box, rewire_factor: float) -> float:
    """``rewire_factor`` times the smallest asymptotically optimal RRT* constant in 3D,
    with the boundary box volume as the free volume (metres)."""
    volume = (boundary[3] - boundary[0]) * (boundary[4] - boundary[1]) * (boundary[5] - boundary[2])
    unit_ball = 4.0 / 3.0 * math.pi
    return rewire_factor * (2.0 * (1.0 + 1.0 / 3.0) * volume / unit_ball) ** (1.0 / 3.0)


def plan_textbook(problem: PlanningProblem, settings: PlannerSettings) -> PlanResult:
    """Plan with the textbook RRT* in ``problem.free_world`` (see the module docstring).

    Honours ``settings.seed``, ``time_limit``, ``max_iterations``, ``stop_at_first``,
    ``step``, ``goal_bias``, ``goal_tolerance`` and ``rewire_factor``; the result's
    planner is ``"textbook"`` and its path (N, 3) runs from exactly the start to the goal.
    """
    t0 = time.perf_counter()
    world = problem.free_world
    blocks: list[Box] = [tuple(map(float, row)) for row in world.blocks]
    boundary: Box = tuple(map(float, world.boundary))
    start: Point = tuple(map(float, problem.search_start))
    goal: Point = tuple(map(float, problem.search_goal))
    step = settings.step_for(world)
    tolerance = settings.goal_tolerance_for(world)
    gamma = _gamma(boundary, settings.rewire_factor)
    legs = (float(np.linalg.norm(problem.start - problem.search_start))
            + float(np.linalg.norm(problem.goal - problem.search_goal)))
    rng = random.Random(settings.seed)

    nodes = [Node(start, -1, 0.0)]
    goal_parents: list[int] = []  # vertices joined to the goal by a free segment
    best_parent, best_cost = -1, math.inf
    history: list[tuple[float, float]] = []
    time_to_first: float | None = None
    iterations = 0

    def try_goal(index: int) -> None:
        position = nodes[index].position
        if _distance(position, goal) <= tolerance and _segment_free(position, goal, blocks,
                                                                     boundary):
            goal_parents.append(index)

    try_goal(0)
    while True:
        if goal_parents:
            parent = min(goal_parents,
                         key=lambda i: nodes[i].cost + _distance(nodes[i].position, goal))
            cost = nodes[parent].cost + _distance(nodes[parent].position, goal)
            if cost < best_cost:
                best_parent, best_cost = parent, cost
                elapsed = time.perf_counter() - t0
                history.append((elapsed, cost + legs))
                if time_to_first is None:
                    time_to_first = elapsed
        if ((settings.stop_at_first and time_to_first is not None)
                or time.perf_counter() - t0 >= settings.time_limit
                or (settings.max_iterations is not None
                    and iterations >= settings.max_iterations)):
            break
        iterations += 1

        if rng.random() < settings.goal_bias:
            sample = goal
        else:
            sample = (rng.uniform(boundary[0], boundary[3]), rng.uniform(boundary[1], boundary[4]),
                      rng.uniform(boundary[2], boundary[5]))
        nearest = 0
        nearest_distance = math.inf
        for i, node in enumerate(nodes):
            d = _distance(node.position, sample)
            if d < nearest_distance:
                nearest, nearest_distance = i, d
        if nearest_distance == 0.0:
            continue
        new = _steer(nodes[nearest].position, sample, step)
        if not _segment_free(nodes[nearest].position, new, blocks, boundary):
            continue

        n = len(nodes) + 1
        radius = min(step, gamma * (math.log(n) / n) ** (1.0 / 3.0))
        near = [i for i, node in enumerate(nodes) if _distance(node.position, new) <= radius]

        parent = nearest
        cost = nodes[nearest].cost + _distance(nodes[nearest].position, new)
        for i in near:
            c = nodes[i].cost + _distance(nodes[i].position, new)
            if c < cost and _segment_free(nodes[i].position, new, blocks, boundary):
                parent, cost = i, c
        index = len(nodes)
        nodes.append(Node(new, parent, cost))
        nodes[parent].children.append(index)

        for i in near:
            c = cost + _distance(new, nodes[i].position)
            if c < nodes[i].cost and _segment_free(new, nodes[i].position, blocks, boundary):
                _reparent(nodes, i, index, c)
        try_goal(index)

    tree_nodes = np.array([node.position for node in nodes], dtype=np.float64)
    tree_parents = np.array([node.parent for node in nodes], dtype=np.int64)
    stats = PlanStats(iterations=iterations, nodes=len(nodes),
                      seconds=time.perf_counter() - t0, time_to_first=time_to_first,
                      cost_history=np.array(history, dtype=np.float64))
    if best_parent < 0:
        return PlanResult("textbook", False, np.zeros((0, 3)), tree_nodes, tree_parents, stats,
                          settings.seed, f"textbook RRT* found no path in {iterations} "
                          f"iterations ({stats.seconds:.3g} s)")
    chain = []
    i = best_parent
    while i >= 0:
        chain.append(nodes[i].position)
        i = nodes[i].parent
    chain.reverse()
    if chain[-1] != goal:
        chain.append(goal)
    return PlanResult("textbook", True, problem.full_path(chain), tree_nodes, tree_parents,
                      stats, settings.seed)

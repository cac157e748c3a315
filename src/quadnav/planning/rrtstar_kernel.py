"""The RRT* iteration, compiled with numba; driven in chunks by :mod:`quadnav.planning.rrtstar`.

One iteration, as the course reports and Karaman & Frazzoli (2011) describe it:

1. sample: the goal with probability ``goal_bias``; else, once a solution of length c
   exists and informed sampling is on, a point of the prolate ellipsoid of points x with
   ``|x - start| + |x - goal| < c`` (Gammell et al. 2014); else a point of the box;
2. nearest vertex; steer towards the sample by at most ``step`` metres;
3. exact segment check (:func:`quadnav.world.blockgrid.grid_segment_free`);
4. near set: vertices within ``min(gamma (log n / n)^(1/3), step)``, with OMPL's
   ``gamma = rewire_factor (2 (1 + 1/3) volume / unit-ball volume)^(1/3)``; the volume is
   the box's, or once a solution exists and sampling is informed, that of the ellipsoid
   if smaller (as OMPL does with its pruned measure);
5. choose parent: the near vertex giving the cheapest cost-to-come through a free edge
   (candidates tried cheapest first, so most edges are never checked);
6. rewire: near vertices that get cheaper through the new vertex are re-parented, and the
   change of cost is pushed down to their descendants;
7. goal: a vertex within ``goal_tolerance`` of the goal with a free straight segment to
   it joins the goal set; the best solution is the cheapest vertex of that set plus its
   last segment. A rewire only lowers costs, so the best is kept by offering it each goal
   vertex whose cost fell (while the change is pushed down), not by a scan of the set.

All state lives in arrays owned by the caller (see :class:`TreeState` in ``rrtstar.py``)
so that the search can be run in chunks between wall-clock checks.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from quadnav.planning.nodegrid import insert, nearest, within
from quadnav.world.blockgrid import grid_segment_free

# Counters in the ``counts`` array.
NODES, ITERATIONS = 0, 1
# Entries of the ``best`` array: length of the best solution (inf if none) and its last
# tree vertex (-1 if none).
BEST_COST, BEST_VERTEX = 0, 1
# Tries at drawing an informed sample inside the box before using the box itself.
_INFORMED_TRIES = 64
# A rewire must save at least this much, metres, so rounding cannot make it cycle.
_REWIRE_EPS = 1e-12


@njit(cache=True, inline="always")
def _norm(a, b):
    return math.sqrt((a[0] - b[0]) ** 2 + (a[1] - b[1]) ** 2 + (a[2] - b[2]) ** 2)


@njit(cache=True)
def _box_sample(rng, lower, extent, out):
    for a in range(3):
        out[a] = lower[a] + rng.random() * extent[a]


@njit(cache=True)
def _inside(point, lower, extent):
    for a in range(3):  # noqa: SIM110 - numba compiles a loop, not all() over a generator
        if not (lower[a] <= point[a] <= lower[a] + extent[a]):
            return False
    return True


@njit(cache=True, inline="always")
def _ellipsoid_volume(cost, focal):
    """Volume, m^3, of the points whose distances to two foci ``focal`` metres apart sum
    to less than ``cost`` metres."""
    return math.pi / 6.0 * cost * (cost * cost - focal * focal)


@njit(cache=True)
def _informed_sample(rng, cost, start, goal, rotation, lower, extent, out):
    """A sample where a path shorter than ``cost`` could pass, inside the box.

    Draws uniformly from the prolate ellipsoid (foci start and goal, major axis ``cost``)
    when it is smaller than the box, else from the box with rejection; falls back to a
    plain box sample after a few failed tries.
    """
    focal = _norm(start, goal)
    a = 0.5 * cost
    b = 0.5 * math.sqrt(max(cost * cost - focal * focal, 0.0))
    ellipsoid = _ellipsoid_volume(cost, focal)
    box = extent[0] * extent[1] * extent[2]
    for _ in range(_INFORMED_TRIES):
        if ellipsoid < box:
            u0, u1, u2 = rng.standard_normal(), rng.standard_normal(), rng.standard_normal()
            scale = rng.random() ** (1.0 / 3.0) / math.sqrt(u0 * u0 + u1 * u1 + u2 * u2)
            local = (a * u0 * scale, b * u1 * scale, b * u2 * scale)
            for k in range(3):
                out[k] = 0.5 * (start[k] + goal[k]) + (rotation[k, 0] * local[0]
                                                       + rotation[k, 1] * local[1]
                                                       + rotation[k, 2] * local[2])
            if _inside(out, lower, extent):
                return
        else:
            _box_sample(rng, lower, extent, out)
            if _norm(out, start) + _norm(out, goal) < cost:
                return
    _box_sample(rng, lower, extent, out)


@njit(cache=True)
def _unlink_child(vertex, parent, first_child, next_sibling):
    """Remove ``vertex`` from its parent's list of children."""
    p = parent[vertex]
    if first_child[p] == vertex:
        first_child[p] = next_sibling[vertex]
        return
    c = first_child[p]
    while next_sibling[c] != vertex:
        c = next_sibling[c]
    next_sibling[c] = next_sibling[vertex]


@njit(cache=True, inline="always")
def _link_child(vertex, new_parent, parent, first_child, next_sibling):
    parent[vertex] = new_parent
    next_sibling[vertex] = first_child[new_parent]
    first_child[new_parent] = vertex


@njit(cache=True, inline="always")
def _offer(vertex, cost, goal_distance, best):
    """Make ``vertex`` the best solution's last vertex if it is a goal vertex (a finite
    ``goal_distance``) whose path is shorter than the best."""
    total = cost[vertex] + goal_distance[vertex]
    if total < best[BEST_COST]:
        best[BEST_COST], best[BEST_VERTEX] = total, vertex


@njit(cache=True)
def _shift_subtree_cost(root, delta, cost, first_child, next_sibling, stack, goal_distance,
                        best):
    """Add ``delta`` metres (< 0) to the cost of every descendant of ``root`` (not root),
    offering each to the best solution."""
    top = 0
    c = first_child[root]
    while c >= 0:
        stack[top] = c
        top += 1
        c = next_sibling[c]
    while top > 0:
        top -= 1
        v = stack[top]
        cost[v] += delta
        _offer(v, cost, goal_distance, best)
        c = first_child[v]
        while c >= 0:
            stack[top] = c
            top += 1
            c = next_sibling[c]


@njit(cache=True)
def _try_goal(vertex, goal, goal_tolerance, nodes, cost, grid, goal_distance, best):
    """Add ``vertex`` to the goal set if it reaches the goal by a free straight segment,
    and offer it to the best solution."""
    distance = _norm(nodes[vertex], goal)
    if distance <= goal_tolerance and grid_segment_free(nodes[vertex], goal, grid):
        goal_distance[vertex] = distance
        _offer(vertex, cost, goal_distance, best)


class Query(NamedTuple):
    """What the search is for, as the kernels take it."""

    start: np.ndarray  # (3,) m
    goal: np.ndarray  # (3,) m
    settings: np.ndarray  # (5,): step m, goal bias, goal tolerance m, rewire factor, informed
    rotation: np.ndarray  # (3, 3) whose first column points from start to goal
    grid: tuple  # the block grid of the inflated world (quadnav.world.blockgrid)
    origin: np.ndarray  # (3,) lower corner of the sampled box, m
    extent: np.ndarray  # (3,) its size, m


class Tree(NamedTuple):
    """The tree's arrays, written in place (room for ``len(cost)`` vertices)."""

    nodes: np.ndarray  # (C, 3) vertices, m
    cost: np.ndarray  # (C,) path length from the root, m
    parent: np.ndarray  # (C,) parent vertex, -1 for the root
    first_child: np.ndarray  # (C,) children as linked lists
    next_sibling: np.ndarray  # (C,)
    goal_distance: np.ndarray  # (C,) m from a goal vertex to the goal, inf for the others
    near: np.ndarray  # (C,) scratch: the near vertices of a new one
    near_distance: np.ndarray  # (C,) scratch
    near_order: np.ndarray  # (C,) scratch
    stack: np.ndarray  # (C,) scratch: subtree walk
    node_grid: tuple  # the vertices by cell (quadnav.planning.nodegrid)
    counts: np.ndarray  # (2,) int: NODES, ITERATIONS
    best: np.ndarray  # (2,): BEST_COST m, BEST_VERTEX (-1: none)


@njit(cache=True)
def start_tree(query: Query, tree: Tree) -> None:
    """Make the query's start the root (vertex 0) and check whether it reaches the goal at
    once."""
    start, goal, settings, _, grid, origin, extent = query
    goal_tolerance = settings[2]
    nodes, cost, parent, first_child, next_sibling, goal_distance = tree[:6]
    node_grid, counts, best = tree.node_grid, tree.counts, tree.best
    heads, next_in_cell, shape, inverse_cell = node_grid
    # The root's index is read from the (empty) tree's counts, so it has the type of the
    # indices grow passes: a literal 0 would compile insert and _try_goal once more.
    root = counts[NODES]
    for a in range(3):  # not nodes[root] = start, whose shape check compiles messages
        nodes[root, a] = start[a]
    cost[root] = 0.0
    parent[root] = -1
    first_child[root] = -1
    next_sibling[root] = -1
    counts[NODES] = root + 1
    insert(root, nodes, origin, extent, heads, next_in_cell, shape, inverse_cell)
    _try_goal(root, goal, goal_tolerance, nodes, cost, grid, goal_distance, best)


@njit(cache=True)
def grow(rng, iterations: int, stop_on_solution: bool, query: Query, tree: Tree) -> None:
    """Run up to ``iterations`` RRT* iterations; returns early when ``stop_on_solution``
    and a solution exists. Capacity for ``iterations`` more vertices must be free."""
    start, goal, settings, rotation, grid, origin, extent = query
    nodes, cost, parent, first_child, next_sibling, goal_distance = tree[:6]
    near, near_distance, near_order, stack = tree[6:10]
    node_grid, counts, best = tree.node_grid, tree.counts, tree.best
    heads, next_in_cell, shape, inverse_cell = node_grid
    step, goal_bias, goal_tolerance, rewire_factor, informed = (
        settings[0], settings[1], settings[2], settings[3], settings[4])
    box = extent[0] * extent[1] * extent[2]
    focal = _norm(start, goal)
    sample = np.empty(3)
    new = np.empty(3)
    for _ in range(iterations):
        if stop_on_solution and best[BEST_VERTEX] >= 0:
            return
        counts[ITERATIONS] += 1
        n = counts[NODES]
        if rng.random() < goal_bias:
            for a in range(3):  # element by element: an array copy compiles error messages
                sample[a] = goal[a]
        elif informed > 0 and best[BEST_VERTEX] >= 0:
            _informed_sample(rng, best[BEST_COST], start, goal, rotation, origin, extent,
                             sample)
        else:
            _box_sample(rng, origin, extent, sample)
        closest = nearest(sample, nodes, n, origin, heads, next_in_cell, shape, inverse_cell)
        distance = _norm(sample, nodes[closest])
        if distance == 0.0:
            continue
        reach = min(1.0, step / distance)
        for a in range(3):
            new[a] = nodes[closest, a] + reach * (sample[a] - nodes[closest, a])
        if not grid_segment_free(nodes[closest], new, grid):
            continue
        volume = box
        if informed > 0 and best[BEST_VERTEX] >= 0:
            volume = min(box, _ellipsoid_volume(best[BEST_COST], focal))
        gamma = rewire_factor * (8.0 / 3.0 * volume / (4.0 / 3.0 * math.pi)) ** (1.0 / 3.0)
        radius = min(gamma * (math.log(n + 1) / (n + 1)) ** (1.0 / 3.0), step)
        m = within(new, radius, nodes, n, origin, heads, next_in_cell, shape, inverse_cell,
                   near, near_distance)
        # Choose the parent: cheapest cost-to-come first; the nearest vertex is known free.
        best_parent = closest
        best_cost = cost[closest] + _norm(nodes[closest], new)
        for k in range(m):
            near_order[k] = cost[near[k]] + near_distance[k]
        checked = np.zeros(m, dtype=np.int8)  # 0 unknown, 1 free, 2 blocked
        while True:  # the cheapest untried candidate, by a scan: the first is usually free
            k = -1
            for i in range(m):
                if checked[i] == 0 and (k < 0 or near_order[i] < near_order[k]):
                    k = i
            if k < 0 or near_order[k] >= best_cost:
                break
            if grid_segment_free(nodes[near[k]], new, grid):
                best_parent, best_cost = near[k], near_order[k]
                checked[k] = 1
                break
            checked[k] = 2
        v = n
        for a in range(3):
            nodes[v, a] = new[a]
        cost[v] = best_cost
        first_child[v] = -1
        _link_child(v, best_parent, parent, first_child, next_sibling)
        counts[NODES] = n + 1
        insert(v, nodes, origin, extent, heads, next_in_cell, shape, inverse_cell)
        # Rewire the near vertices that get cheaper through the new one.
        for k in range(m):
            u = near[k]
            through = best_cost + near_distance[k]
            if u == best_parent or through >= cost[u] - _REWIRE_EPS or checked[k] == 2:
                continue
            if checked[k] == 1 or grid_segment_free(new, nodes[u], grid):
                _unlink_child(u, parent, first_child, next_sibling)
                _link_child(u, v, parent, first_child, next_sibling)
                _shift_subtree_cost(u, through - cost[u], cost, first_child, next_sibling,
                                    stack, goal_distance, best)
                cost[u] = through
                _offer(u, cost, goal_distance, best)
        _try_goal(v, goal, goal_tolerance, nodes, cost, grid, goal_distance, best)

"""Legs: the short way out of the safety margin from a start or goal that lies inside it.

Course maps put starts on the boundary (RBE595: ``x = xmin``) or close to a wall (MEAM620
``test_window``). Such a point is usable, but only the *leg* that leaves the margin may be
inside it; the rest of the flight keeps the whole margin. A leg is a polyline from the
point to the nearest free point of the inflated world found as follows:

1. **Straight**: the point is projected onto the faces of the inflated blocks and
   boundary that hold it (and the projections again, a few rounds, for overlapping
   margins); the nearest projection reached by a straight segment that stays in the
   *leg world* is the leg.
2. **Around**: when no straight segment does (a start on the boundary with a block a few
   centimetres in front of it), a breadth-first search on a fine grid anchored at the
   point, in the leg world, finds the fewest-steps way to a free grid point; the grid
   path is then shortened by line of sight. Only when that search exhausts its budget is
   the point refused, with one line saying why.

The *leg world* is the real map with every block grown by the leg clearance — the point's
own distance to the blocks (per axis), or the margin if that is less, minus a sliver —
and the boundary shrunk by the body's *reach* (:func:`body_reach`: its half extents plus
:data:`BODY_ROOM`; nothing for a point): a leg never comes closer to a block than the
point it starts from (a vehicle that fits there fits all along its leg), and keeps the
whole body inside the boundary. A start too close to the boundary for that is first moved
inside by the shortest move (:func:`body_inside`), and the leg starts there.
"""

from __future__ import annotations

import itertools

import clarabel
import numpy as np
from numpy.typing import ArrayLike

from quadnav.arrays import FloatArray
from quadnav.errors import QuadnavError
from quadnav.planning.result import path_length
from quadnav.world.margins import box_margins
from quadnav.world.model import World
from quadnav.world.placement import format_box, format_point

#: How far past the margin a leg ends, as a fraction of the margin, where there is room:
#: the trajectory that starts there at rest then has room to curve without entering it.
LEG_END_DEPTH = 0.05
#: How far past a margin face a leg ends where there is no such room, metres.
LEG_END_CLEARANCE = 1e-6
#: The sliver, as a fraction, by which a leg may come closer to the blocks than its point.
LEG_CLEARANCE_SLIVER = 1e-3
#: Widening of the boundary in the leg world, metres, so a point on it is free.
BOUNDARY_SLACK = 1e-9
#: How far, metres, legs, moved starts and moved goals keep the vehicle's body inside
#: the boundary: room for the tracking error of a leg flown straight from rest to rest
#: (the stop at its end overshoots by up to about 1.7 cm, at the speeds flown).
BODY_ROOM = 0.03
#: Rounds of face projection tried when leaving overlapping margins.
_PROJECTION_ROUNDS = 3
#: Half-size of the first box searched around a point, in margins; it doubles.
_FIRST_REACH = 8.0
#: Grid lines closer than this, metres, are one line.
_SAME_LINE = 1e-7
#: Most cells of the box grid searched around a point.
MAX_CELLS = 2_000_000


def body_reach(body: ArrayLike) -> FloatArray:
    """How far (3,), metres, per axis, legs keep the centre from the boundary for a body
    of half extents ``body`` (3,) m: those plus :data:`BODY_ROOM`; zeros for a point (a
    body of zeros)."""
    half = np.asarray(body, dtype=np.float64).reshape(3)
    return half + BODY_ROOM if np.any(half > 0) else np.zeros(3)


def body_inside(world: World, point: FloatArray, reach: FloatArray, label: str
                ) -> FloatArray:
    """The point (3,) nearest ``point`` at least ``reach`` (3,) m inside the boundary of
    ``world`` on every axis (``point`` itself when it is); QuadnavError when the map is
    too narrow for that."""
    lower, upper = world.lower + reach, world.upper - reach
    if np.any(lower > upper):
        raise QuadnavError(f"{label} {format_point(point)}: the vehicle's body (reaching "
                           f"{format_point(reach)} m from its centre with room) does not fit "
                           f"inside the boundary {format_box(world.boundary)}")
    return np.clip(point, lower, upper)


def find_leg(world: World, free_world: World, point: FloatArray, margin: float,
             label: str, body: ArrayLike | None = None) -> FloatArray:
    """The leg (K, 3) from ``point`` out of the margin, ``point`` first and a free point
    of ``free_world`` (``world`` inflated by ``margin``) last; just ``point`` (1, 3) when
    it is free already. QuadnavError when no way out is found.

    ``body``: the half extents (3,), metres, of the vehicle's body box (default: a
    point). The leg keeps it :data:`BODY_ROOM` inside the boundary (:func:`body_reach`;
    ``point`` must lie that far in, see :func:`body_inside`) and never brings it closer to
    a block than it is at ``point`` (:func:`own_clearance`), or than the margin less the
    largest half extent if that is less."""
    if free_world.is_free(point):
        return point[None].copy()
    half = np.zeros(3) if body is None else np.asarray(body, dtype=np.float64).reshape(3)
    clearance = max(0.0, min((1.0 - LEG_CLEARANCE_SLIVER) * (margin - half.max()),
                             own_clearance(world, point, half)))
    legs = leg_world(world, clearance, body_reach(half), half)
    for push in (LEG_END_DEPTH * margin, LEG_END_CLEARANCE):
        exits = [c for c in _projections(free_world, point, push)
                 if legs.segment_free(point, c)]
        if exits:
            nearest = min(exits, key=lambda c: float(np.linalg.norm(c - point)))
            return np.stack([point, nearest])
    leg = _search_around(legs, free_world, point, margin, label)
    deeper = free_world.inflate(0.5 * LEG_END_DEPTH * margin)  # the leg ends deeper still
    return _end_at_margin(deeper if deeper.is_free(leg[-1]) else free_world, leg)


def leg_world(world: World, clearance: float = 0.0, reach: ArrayLike | None = None,
              body: ArrayLike | None = None) -> World:
    """Where a leg may go: ``world`` with every block grown by the ``body`` half extents
    (3,) m (default 0) plus ``clearance`` metres per axis, and the boundary shrunk by
    ``reach`` (3,) m (default 0), then widened by :data:`BOUNDARY_SLACK`, so a point on
    its faces is free."""
    inward = np.zeros(3) if reach is None else np.asarray(reach, dtype=np.float64)
    grow = clearance + (np.zeros(3) if body is None else np.asarray(body, dtype=np.float64))
    shrink = np.concatenate([inward - BOUNDARY_SLACK, BOUNDARY_SLACK - inward])
    return world.replace(blocks=world.blocks + np.concatenate([-grow, grow]),
                         boundary=world.boundary + shrink)


def own_clearance(world: World, point: FloatArray, body: ArrayLike | None = None) -> float:
    """How close, per axis, a leg from ``point`` (3,) may bring the body box of half
    extents ``body`` (3,) m (default: a point) to the blocks of ``world``, metres: the
    box's own margin from them there (:func:`~quadnav.world.margins.box_margins`), less
    the sliver (:data:`LEG_CLEARANCE_SLIVER`); ``inf`` without blocks."""
    if not len(world.blocks):
        return float("inf")
    half = np.zeros(3) if body is None else np.asarray(body, dtype=np.float64)
    box = np.concatenate([point - half, point + half])
    return (1.0 - LEG_CLEARANCE_SLIVER) * float(box_margins(world, box, boundary=False)[0])


def _projections(free_world: World, point: FloatArray, push: float) -> list[FloatArray]:
    """Free points reached from ``point`` by moving straight out of the inflated blocks
    and boundary that hold it to ``push`` metres past their faces: each round projects
    every candidate still not free so, up to :data:`_PROJECTION_ROUNDS` rounds."""
    inner_lower = free_world.lower + push
    inner_upper = free_world.upper - push
    found: list[FloatArray] = []
    frontier = [point]
    for _ in range(_PROJECTION_ROUNDS):
        moved: list[FloatArray] = []
        for candidate in frontier:
            clamped = np.clip(candidate, inner_lower, inner_upper)
            if not np.array_equal(clamped, candidate):
                moved.append(clamped)
            for row in free_world.blocks_containing(candidate):
                box = free_world.blocks[row]
                for axis in range(3):
                    for face in (box[axis] - push, box[axis + 3] + push):
                        projected = candidate.copy()
                        projected[axis] = face
                        moved.append(projected)
        free = free_world.points_free(moved) if moved else np.zeros(0, dtype=bool)
        found.extend(m for m, ok in zip(moved, free, strict=True) if ok)
        frontier = [m for m, ok in zip(moved, free, strict=True) if not ok]
    return found


def _search_around(legs: World, free_world: World, point: FloatArray, margin: float,
                   label: str) -> FloatArray:
    """The shortest leg through the cells of the local box grid (module docstring, step
    2), then shortened by line of sight; the search box doubles until a way out appears
    or the grid grows too big."""
    reach = _FIRST_REACH * margin
    found = None
    while True:
        lower = np.maximum(point - reach, legs.lower + BOUNDARY_SLACK)
        upper = np.minimum(point + reach, legs.upper - BOUNDARY_SLACK)
        lines = [_grid_lines(axis, point, lower, upper, legs, free_world) for axis in range(3)]
        if np.prod([len(x) - 1 for x in lines]) > MAX_CELLS:
            break
        cells = _shortest_way_out(legs, free_world, point, lines)
        leg = None if cells is None else _line_of_sight(legs, _taut_leg(
            point, cells, LEG_END_DEPTH * margin))
        if leg is not None and legs.segments_free(np.stack([leg[:-1], leg[1:]], axis=1)).all():
            found = leg
            # No way out through the box's open sides can be shorter than this.
            cut = np.concatenate([np.where(lower > legs.lower + BOUNDARY_SLACK,
                                           point - lower, np.inf),
                                  np.where(upper < legs.upper - BOUNDARY_SLACK,
                                           upper - point, np.inf)])
            if path_length(leg) <= cut.min():
                return found
        if np.all(lower <= legs.lower + BOUNDARY_SLACK) and np.all(
                upper >= legs.upper - BOUNDARY_SLACK):
            break
        reach *= 2.0
    if found is not None:
        return found
    raise QuadnavError(
        f"{label} {format_point(point)} is inside the {margin:g} m safety margin and there "
        f"is no way out of it that keeps clear of the blocks (searched up to {reach:.3g} m "
        "away): the vehicle cannot leave it; move it or lower --margin")


def _grid_lines(axis: int, point: FloatArray, lower: FloatArray, upper: FloatArray,
                legs: World, free_world: World) -> np.ndarray:
    """Sorted coordinates along ``axis`` of every face of the leg world's and the inflated
    world's blocks and boundaries inside [lower, upper], and of that box."""
    faces = np.concatenate([legs.blocks[:, [axis, axis + 3]].ravel(),
                            free_world.blocks[:, [axis, axis + 3]].ravel(),
                            free_world.boundary[[axis, axis + 3]],
                            [lower[axis], upper[axis]]])
    lines = np.unique(faces[(faces >= lower[axis]) & (faces <= upper[axis])])
    # Faces computed two ways (2 - 0.2 and 5 - 3.2) may differ by a rounding error.
    return lines[np.concatenate([[True], np.diff(lines) > _SAME_LINE])]


def _shortest_way_out(legs: World, free_world: World, point: FloatArray,
                      lines: list[np.ndarray]) -> FloatArray | None:
    """The chain of face-adjacent cells (C, 6) of the grid on ``lines`` from one holding
    ``point`` to the nearest cell free in ``free_world``, all free in ``legs``, measured
    between cell centres; None when there is none in the grid."""
    shape = tuple(len(x) - 1 for x in lines)
    mids = [0.5 * (x[:-1] + x[1:]) for x in lines]
    centres = np.stack(np.meshgrid(*mids, indexing="ij"), axis=-1).reshape(-1, 3)
    open_cells = legs.points_free(centres)
    exits = open_cells & free_world.points_free(centres)
    index = np.arange(len(centres)).reshape(shape)
    rows, cols = [], []
    for axis in range(3):
        here = np.take(index, np.arange(shape[axis] - 1), axis=axis).ravel()
        there = np.take(index, np.arange(1, shape[axis]), axis=axis).ravel()
        both = open_cells[here] & open_cells[there]
        rows.append(here[both])
        cols.append(there[both])
    # The point sees the open cells whose closed boxes hold it (one, or up to 8 when it
    # lies on their faces).
    holding = [np.flatnonzero((x[:-1] <= p) & (p <= x[1:])) for x, p in zip(lines, point,
                                                                               strict=True)]
    around = [index[i, j, k] for i in holding[0] for j in holding[1] for k in holding[2]
              if open_cells[index[i, j, k]]]
    source = len(centres)
    rows.append(np.full(len(around), source))
    cols.append(np.array(around, dtype=np.int64))
    nodes = np.vstack([centres, point])
    row, col = np.concatenate(rows), np.concatenate(cols)
    weight = np.linalg.norm(nodes[row] - nodes[col], axis=1)
    from scipy.sparse import coo_matrix  # only here: most plans need no way around
    from scipy.sparse.csgraph import dijkstra

    graph = coo_matrix((weight, (row, col)), shape=(len(nodes), len(nodes))).tocsr()
    distance, predecessor = dijkstra(graph, directed=False, indices=source,
                                     return_predecessors=True)
    reachable = np.flatnonzero(exits & np.isfinite(distance[:-1]))
    if reachable.size == 0:
        return None
    chain = [int(reachable[np.argmin(distance[reachable])])]
    while predecessor[chain[-1]] != source:
        chain.append(int(predecessor[chain[-1]]))
    ijk = np.array(np.unravel_index(chain[::-1], shape)).T
    return np.concatenate([np.stack([lines[a][ijk[:, a]] for a in range(3)], axis=1),
                           np.stack([lines[a][ijk[:, a] + 1] for a in range(3)], axis=1)],
                          axis=1)


def _taut_leg(point: FloatArray, cells: FloatArray, depth: float) -> FloatArray:
    """The shortest polyline (K, 3) from ``point`` through the chain of face-adjacent
    cells (C, 6), ``point`` on the first cell, ending inside the last cell (``depth``
    metres from its sides where it is wide enough): each vertex lies on the face two
    cells share, so each segment lies in one cell. A second-order cone program (sum of
    segment lengths), solved with Clarabel."""
    inner = _SAME_LINE
    boxes = []
    for before, after in itertools.pairwise(cells):
        face = np.concatenate([np.maximum(before[:3], after[:3]),
                               np.minimum(before[3:], after[3:])])
        boxes.append(_shrunk(face, inner))
    boxes.append(_shrunk(cells[-1], np.minimum(depth, 0.5 * (cells[-1][3:] - cells[-1][:3])
                                               - inner)))
    m = len(boxes)
    n = 3 * m + m  # vertices x_1..x_m, then the segment lengths t_0..t_{m-1}
    rows, b, cones = [], [], []
    box_rows = np.zeros((6 * m, n))
    box_b = np.zeros(6 * m)
    for i, box in enumerate(boxes):
        for a in range(3):
            box_rows[6 * i + a, 3 * i + a] = -1.0
            box_b[6 * i + a] = -box[a]
            box_rows[6 * i + 3 + a, 3 * i + a] = 1.0
            box_b[6 * i + 3 + a] = box[a + 3]
    rows.append(box_rows)
    b.append(box_b)
    cones.append(clarabel.NonnegativeConeT(6 * m))
    for i in range(m):
        cone = np.zeros((4, n))
        rhs = np.zeros(4)
        cone[0, 3 * m + i] = -1.0
        cone[1:, 3 * i:3 * i + 3] = -np.eye(3)
        if i == 0:
            rhs[1:] = -point
        else:
            cone[1:, 3 * (i - 1):3 * i] = np.eye(3)
        rows.append(cone)
        b.append(rhs)
        cones.append(clarabel.SecondOrderConeT(4))
    q = np.concatenate([np.zeros(3 * m), np.ones(m)])
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    from scipy.sparse import csc_matrix  # only here: most plans need no leg around

    solver = clarabel.DefaultSolver(csc_matrix((n, n)), q, csc_matrix(np.vstack(rows)),
                                    np.concatenate(b), cones, settings)
    solution = solver.solve()
    vertices = np.array(solution.x[:3 * m]).reshape(m, 3)
    return np.vstack([point, np.clip(vertices, [box[:3] for box in boxes],
                                     [box[3:] for box in boxes])])


def _shrunk(box: FloatArray, by: FloatArray | float) -> FloatArray:
    """``box`` (6,) shrunk by ``by`` (scalar or (3,)) on every side where it is wider than
    twice that; a flat side stays flat."""
    grow = np.broadcast_to(np.asarray(by, dtype=np.float64), (3,))
    wide = box[3:] - box[:3] > 2 * grow
    return np.concatenate([np.where(wide, box[:3] + grow, box[:3]),
                           np.where(wide, box[3:] - grow, box[3:])])


def _end_at_margin(free_world: World, leg: FloatArray) -> FloatArray:
    """``leg`` (K, 3), whose last point is free in ``free_world``, with its last segment
    cut just past where it enters that free space."""
    last, before = leg[-1], leg[-2]
    hit = free_world.first_hit(last, before)
    if hit is None:
        return leg
    end = last + max(0.0, hit.t - LEG_END_CLEARANCE / max(
        float(np.linalg.norm(before - last)), LEG_END_CLEARANCE)) * (before - last)
    return np.vstack([leg[:-1], end]) if free_world.is_free(end) else leg


def _line_of_sight(world: World, chain: FloatArray) -> FloatArray:
    """``chain`` (K, 3) shortened greedily: from each kept vertex, jump to the farthest
    later vertex a free segment reaches. The first and last vertices stay."""
    kept = [0]
    while kept[-1] < len(chain) - 1:
        here = kept[-1]
        later = np.arange(here + 1, len(chain))
        free = world.segments_free(np.stack([np.broadcast_to(chain[here], (len(later), 3)),
                                             chain[later]], axis=1))
        kept.append(int(later[np.flatnonzero(free)[-1]]))
    return chain[kept]

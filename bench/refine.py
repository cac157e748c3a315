"""Benchmark: refining a path (shortcuts, then smoothing), compiled, against the numpy
implementation quadnav had before (kept here as the baseline, measured in the same run).

Run: ``python bench/refine.py [--repeats 20]``, or ``--quick`` (5 repeats).

Problems: RRT* paths (seed 0, 20,000 iterations, 0.2 m margin) on the built-in ``forest``,
``window`` and ``maze`` and on the course map ``rbe595/map1.txt`` (from (0, -5, 0.5) to
(8, 18, 3)) when ``../shared/maps`` is beside the project. Each is refined by
:func:`quadnav.planning.refine.refine` (compiled loops, :mod:`quadnav.planning.refine_kernel`)
and by the baseline: the same steps and settings written with numpy and a Python call
into the exact segment check per test (the former :mod:`quadnav.planning.shortcut` and
:mod:`quadnav.planning.smoothing` loops), over shortcut seeds 0..repeats-1. Both draw the
same random numbers, so they give the same paths (checked: the largest difference of the
refined lengths is printed). Prints the median time of each, the ratio, and the median
lengths.
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from quadnav.arrays import FloatArray
from quadnav.planning import PlannerSettings, make_problem, plan
from quadnav.planning.refine import refine
from quadnav.planning.result import distinct, path_length
from quadnav.planning.shortcut import (
    ATTEMPTS_PER_VERTEX,
    MIN_ATTEMPTS,
    RANGE_RATIO,
    RELATIVE_EPSILON,
    SNAP_FRACTION,
    free_polyline,
)
from quadnav.planning.smoothing import DEFAULT_PIECES, KEEP_DEVIATION_FRACTION, _densify
from quadnav.world import World, load_world

MAPS = Path(__file__).resolve().parents[2] / "shared" / "maps"


def baseline_refine(world: World, path: np.ndarray, seed: int) -> np.ndarray:
    """The former numpy refinement: line of sight, random shortcuts, line of sight, then
    densify, smoothing sweeps and simplification, with the default settings."""
    points = free_polyline(world, path)
    shorter = _line_of_sight(world, points)
    attempts = max(MIN_ATTEMPTS, ATTEMPTS_PER_VERTEX * len(shorter))
    shorter = _random_shortcuts(world, shorter, np.random.default_rng(seed), attempts)
    shorter = _line_of_sight(world, shorter)
    spacing = path_length(shorter) / DEFAULT_PIECES
    original = _densify(world, shorter, spacing)
    smoothed = _descend(world, original, 0.5, 0.3, 1e-6, 1000)
    return simplify_path(world, smoothed, KEEP_DEVIATION_FRACTION * spacing)


def _line_of_sight(world: World, points: FloatArray) -> FloatArray:
    """Greedy pass: from each kept vertex, the farthest later vertex it sees is kept next.

    The candidates of one vertex are tested in one batch; the next vertex always sees
    its neighbour, since the input's segments are free.
    """
    kept = [0]
    last = len(points) - 1
    while kept[-1] < last - 1:
        here = kept[-1]
        later = np.arange(here + 2, last + 1)
        pairs = np.stack([np.broadcast_to(points[here], (len(later), 3)), points[later]],
                         axis=1)
        visible = later[world.segments_free(pairs)]
        kept.append(int(visible[-1]) if visible.size else here + 1)
    if kept[-1] != last:
        kept.append(last)
    return points[kept]


def _random_shortcuts(world: World, points: FloatArray, rng: np.random.Generator,
                      attempts: int) -> FloatArray:
    """Try ``attempts`` random shortcuts between points along the polyline (N, 3)."""
    for _ in range(attempts):
        arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(points, axis=0),
                                                              axis=1))])
        total = arc[-1]
        s0 = rng.uniform(0.0, total)
        s1 = rng.uniform(max(0.0, s0 - RANGE_RATIO * total),
                         min(total, s0 + RANGE_RATIO * total))
        s0, s1 = min(s0, s1), max(s0, s1)
        i0, s0, p0 = _point_at(points, arc, s0)
        i1, s1, p1 = _point_at(points, arc, s1)
        # The path between p0 (on segment i0) and p1 (on segment i1) turns only at the
        # vertices i0 + 1 .. i1; on one segment there is nothing to cut.
        if i0 >= i1:
            continue
        saved = (s1 - s0) - float(np.linalg.norm(p1 - p0))
        if saved <= RELATIVE_EPSILON * total or not world.segment_free(p0, p1):
            continue
        spliced = np.concatenate([points[:i0 + 1], [p0, p1], points[i1 + 1:]])
        # The pieces of segments i0 and i1 kept are free in exact arithmetic, but p0 and
        # p1 are rounded: near a tangency a piece can touch a block, so check them too.
        # (Checked one by one: a batch this small costs more to spread over threads.)
        if world.segment_free(spliced[i0], p0) and world.segment_free(p1, spliced[i0 + 3]):
            points = distinct(spliced)
    return points


def _point_at(points: FloatArray, arc: FloatArray, s: float
              ) -> tuple[int, float, FloatArray]:
    """(segment index, distance along the path, point) for the point ``s`` metres along
    the polyline (N, 3) whose cumulative lengths are ``arc`` (N,).

    A point within :data:`SNAP_FRACTION` of the length from a vertex is that vertex,
    given as the end of the segment before it (the start of the first segment for
    vertex 0), so that cutting a corner leaves no tiny segment.
    """
    nearest = int(np.argmin(np.abs(arc - s)))
    if abs(arc[nearest] - s) <= SNAP_FRACTION * arc[-1]:
        return max(nearest - 1, 0), float(arc[nearest]), points[nearest].copy()
    i = int(np.clip(np.searchsorted(arc, s, side="right") - 1, 0, len(points) - 2))
    t = (s - arc[i]) / (arc[i + 1] - arc[i])
    return i, s, points[i] + t * (points[i + 1] - points[i])

def _descend(world: World, original: FloatArray, weight_data: float, weight_smooth: float,
             tolerance: float, max_sweeps: int) -> FloatArray:
    """Sweeps of the smoother on the free polyline ``original`` (N, 3), reverting and
    freezing points whose segments would collide; the endpoints never move."""
    path = original.copy()
    frozen = np.zeros(len(path), dtype=bool)
    frozen[[0, -1]] = True
    interior = np.arange(1, len(path) - 1)
    for _ in range(max_sweeps):
        before = path.copy()
        for parity in (1, 0):
            i = interior[(interior % 2 == parity) & ~frozen[interior]]
            path[i] += (weight_data * (original[i] - path[i])
                        + weight_smooth * (path[i - 1] + path[i + 1] - 2 * path[i]))
        _revert_collisions(world, path, before, frozen)
        if np.linalg.norm(path - before, axis=1).sum() < tolerance:
            break
    return path


def _revert_collisions(world: World, path: FloatArray, before: FloatArray,
                       frozen: NDArray[np.bool_]) -> None:
    """Put back (and freeze) the moved points of every segment of ``path`` that collides,
    until none does; ``before`` (same shape) is the free polyline before the sweep."""
    moved = np.any(path != before, axis=1)
    touched = np.flatnonzero(moved[:-1] | moved[1:])
    while touched.size:
        hit = touched[~world.segments_free(np.stack([path[touched], path[touched + 1]],
                                                     axis=1))]
        ends = np.concatenate([hit, hit + 1])
        path[ends] = before[ends]
        moved[ends] = False
        frozen[ends] = True
        # Only segments beside a point just put back can newly collide.
        touched = np.intersect1d(np.concatenate([ends - 1, ends]),
                                 np.flatnonzero(moved[:-1] | moved[1:]))

def simplify_path(world: World, path: FloatArray, deviation: float) -> FloatArray:
    """The former numpy :func:`quadnav.planning.smoothing.simplify_path` (same rule: a run
    of vertices within ``deviation`` m of its free chord is replaced by the chord)."""
    if len(path) < 3:
        return path
    keep = np.zeros(len(path), dtype=bool)
    keep[[0, -1]] = True
    runs = [(0, len(path) - 1)]
    while runs:
        first, last = runs.pop()
        if last - first < 2:
            continue
        distances = _distances_to_segment(path[first + 1:last], path[first], path[last])
        farthest = first + 1 + int(np.argmax(distances))
        if distances.max() <= deviation and world.segment_free(path[first], path[last]):
            continue
        keep[farthest] = True
        runs += [(first, farthest), (farthest, last)]
    return path[keep]


def _distances_to_segment(points: FloatArray, a: FloatArray, b: FloatArray) -> FloatArray:
    """Distance (K,) from each point (K, 3) to the closed segment a -> b, metres."""
    d = b - a
    squared = float(d @ d)
    t = np.zeros(len(points)) if squared == 0.0 else np.clip((points - a) @ d / squared, 0, 1)
    return np.linalg.norm(points - (a + t[:, None] * d), axis=1)


def problems() -> dict[str, tuple]:
    """name -> (problem, planned result)."""
    cases = {name: (name, None, None) for name in ("forest", "window", "maze")}
    if MAPS.is_dir():
        cases["rbe595/map1.txt"] = (str(MAPS / "rbe595/map1.txt"), (0, -5, 0.5), (8, 18, 3))
    found = {}
    for name, (spec, start, goal) in cases.items():
        world = load_world(spec)
        problem = make_problem(world, world.start if start is None else start,
                               world.goal if goal is None else goal, 0.2)
        result = plan(problem, PlannerSettings(seed=0, max_iterations=20_000, time_limit=60))
        found[name] = (problem, result)
    return found


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=20)
    parser.add_argument("--quick", action="store_true", help="5 repeats")
    args = parser.parse_args()
    repeats = 5 if args.quick else args.repeats
    print("| problem | raw m | refined m | refine ms | baseline ms | speed-up | "
          "largest length difference m |")
    print("|---|---|---|---|---|---|---|")
    for name, (problem, result) in problems().items():
        search = problem.search_part(result.path)
        refine(problem, result)  # load the compiled loops
        ours, theirs, ours_m, theirs_m = [], [], [], []
        for seed in range(repeats):  # alternate, so both see the same machine load
            began = time.perf_counter()
            refined = refine(problem, result, seed=seed)
            ours.append(time.perf_counter() - began)
            ours_m.append(refined.stats.post[-1].length)
            began = time.perf_counter()
            path = problem.full_path(baseline_refine(problem.free_world, search, seed))
            theirs.append(time.perf_counter() - began)
            theirs_m.append(path_length(path))
        mine, base = statistics.median(ours), statistics.median(theirs)
        difference = float(np.max(np.abs(np.subtract(ours_m, theirs_m))))
        print(f"| {name} | {result.length:.3f} | {statistics.median(ours_m):.3f} | "
              f"{1000 * mine:.2f} | {1000 * base:.1f} | {base / mine:.0f}x | "
              f"{difference:.1e} |", flush=True)


if __name__ == "__main__":
    main()

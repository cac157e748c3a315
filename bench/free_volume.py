"""Benchmark: the free-volume figure of ``quadnav map info`` on maps of up to 100,000 blocks.

Run: ``python bench/free_volume.py`` (about 2 minutes, most of it the baseline at 10,000
blocks), or ``--quick`` (a smoke run without the 10,000-block baseline).

Prints medians over repeated runs of ``World(...).free_volume()`` (the map's World made
afresh each time, so nothing is cached) on:

* random boxes, 0.1-3 m a side, in a 100 m cube: 1,000, 10,000 and 100,000 of them;
* the built-in forest ``forest:size=700x700x10,density=0.07`` (about 100,000 trunks and
  branches);
* a contrived layout: 100,000 sticks 5 cm thick, each spanning the cube along x, y or z
  (the exact figure would take seconds here; quadnav estimates it and says so).

The baseline, measured in the same run on the same random boxes (not at 100,000: it
would take over 5 minutes), is the implementation quadnav had before: a sweep over x with
the cross-section's area found by a sweep over y, ``O(N^2)`` to ``O(N^3)``
(:func:`sweep_volume`). Target: under 1 s for 100,000 blocks. Nothing is asserted.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from geometry import median_seconds
from numba import njit

from quadnav.world import World, load_world

CUBE = np.array([0.0, 0.0, 0.0, 100.0, 100.0, 100.0])


@njit(cache=True)
def _union_length(starts, ends) -> float:
    """Total length of the union of intervals [starts[i], ends[i]]."""
    order = np.argsort(starts)
    total = 0.0
    cur_start = -np.inf
    cur_end = -np.inf
    for j in order:
        if starts[j] > cur_end:
            if cur_end > cur_start:
                total += cur_end - cur_start
            cur_start, cur_end = starts[j], ends[j]
        else:
            cur_end = max(cur_end, ends[j])
    if cur_end > cur_start:
        total += cur_end - cur_start
    return total


@njit(cache=True)
def _union_area_yz(boxes, active):
    """Area of the union of the (y, z) rectangles of boxes[active]."""
    ys = np.unique(np.concatenate((boxes[active, 1], boxes[active, 4])))
    area = 0.0
    for k in range(ys.size - 1):
        ya, yb = ys[k], ys[k + 1]
        spanning = active[(boxes[active, 1] <= ya) & (boxes[active, 4] >= yb)]
        if spanning.size:
            area += (yb - ya) * _union_length(boxes[spanning, 2], boxes[spanning, 5])
    return area


@njit(cache=True)
def sweep_volume(boxes) -> float:
    """Baseline: volume of the union of boxes (N, 6), m^3, by the former sweep.

    Between consecutive box faces along x the cross-section is constant, and its area is
    found the same way one dimension down.
    """
    if boxes.shape[0] == 0:
        return 0.0
    xs = np.unique(np.concatenate((boxes[:, 0], boxes[:, 3])))
    all_rows = np.arange(boxes.shape[0])
    volume = 0.0
    for k in range(xs.size - 1):
        xa, xb = xs[k], xs[k + 1]
        active = all_rows[(boxes[:, 0] <= xa) & (boxes[:, 3] >= xb)]
        if active.size:
            volume += (xb - xa) * _union_area_yz(boxes, active)
    return volume


def random_boxes(n: int, seed: int) -> np.ndarray:
    """(n, 6) boxes 0.1-3 m a side at uniform places in :data:`CUBE`, cut to it."""
    rng = np.random.default_rng(seed)
    lower = rng.uniform(0.0, 100.0, (n, 3))
    return np.minimum(np.hstack([lower, lower + rng.uniform(0.1, 3.0, (n, 3))]), 100.0)


def sticks(n: int, seed: int, width: float = 0.05) -> np.ndarray:
    """(n, 6) sticks ``width`` thick spanning :data:`CUBE`, a third along each axis."""
    rng = np.random.default_rng(seed)
    parts = []
    for axis in range(3):
        lower = rng.uniform(0.0, 100.0 - width, (n // 3 + (axis < n % 3), 3))
        upper = lower + width
        lower[:, axis], upper[:, axis] = 0.0, 100.0
        parts.append(np.hstack([lower, upper]))
    return np.vstack(parts)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--quick", action="store_true",
                        help="1 repeat, no baseline at 10,000 blocks")
    args = parser.parse_args()
    repeats = 1 if args.quick else args.repeats

    forest = load_world("forest:size=700x700x10,density=0.07")
    maps = [(f"random boxes, {n:,}", CUBE, random_boxes(n, seed=n)) for n in
            (1_000, 10_000, 100_000)]
    maps += [(f"forest, {len(forest):,}", forest.boundary, forest.blocks),
             ("sticks, 100,000", CUBE, sticks(100_000, seed=1))]
    World(boundary=CUBE, blocks=random_boxes(10, 0)).free_volume()  # compile or load
    sweep_volume(random_boxes(10, 0))
    print(f"World(...).free_volume(), medians over {repeats} runs")
    for label, boundary, blocks in maps:
        result = World(boundary=boundary, blocks=blocks).free_volume()
        ours = median_seconds(lambda b=boundary, k=blocks: World(b, k).free_volume(),
                              repeats)
        how = "exact" if result.exact else f"estimated, +-{100 * result.error:.2f} %"
        line = (f"  {label + ':':<22} {100 * result.fraction:.4f} % free ({how}): "
                f"{ours:.3f} s")
        if len(blocks) <= (1_000 if args.quick else 10_000) and boundary is CUBE:
            t0 = time.perf_counter()
            old = 1.0 - sweep_volume(np.ascontiguousarray(blocks)) / 1e6
            baseline = time.perf_counter() - t0
            line += (f"; baseline {baseline:.3f} s ({100 * old:.4f} %), "
                     f"{baseline / ours:.0f}x faster")
        print(line + f"; target < 1 s: {'met' if ours < 1.0 else 'MISSED'}")


if __name__ == "__main__":
    main()

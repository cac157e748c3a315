"""Benchmark: exact batch segment checks, 100,000 segments against 1,000 blocks.

Run: ``python bench/geometry.py``. Prints medians over repeated runs of quadnav's
compiled batch check, and of a plain-numpy slab test (broadcast over blocks, in
chunks of segments) measured in the same run on the same input as the baseline.
Target: under 0.5 s for the batch on a 2-core machine.
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections.abc import Callable

import numpy as np

from quadnav.world import World


def forest_of_boxes(n_blocks: int, seed: int) -> World:
    """``n_blocks`` random trunks, 0.3-1 m wide and full height, in a 100 x 100 x 20 m box."""
    rng = np.random.default_rng(seed)
    lower = rng.uniform([0, 0, 0], [99, 99, 0], size=(n_blocks, 3))
    size = np.column_stack([rng.uniform(0.3, 1.0, (n_blocks, 2)), np.full(n_blocks, 20.0)])
    return World(boundary=[0, 0, 0, 100, 100, 20], blocks=np.hstack([lower, lower + size]))


def random_segments(world: World, n: int, max_length: float, seed: int) -> np.ndarray:
    """(n, 2, 3) segments from uniform points, random directions, 0.1..max_length long."""
    rng = np.random.default_rng(seed)
    start = rng.uniform(world.lower, world.upper, size=(n, 3))
    direction = rng.normal(size=(n, 3))
    direction /= np.linalg.norm(direction, axis=1, keepdims=True)
    end = start + direction * rng.uniform(0.1, max_length, size=(n, 1))
    end = np.clip(end, world.lower + 1e-3, world.upper - 1e-3)
    return np.stack([start, end], axis=1)


def numpy_segments_free(world: World, segments: np.ndarray, chunk: int = 2000) -> np.ndarray:
    """Baseline: the same exact slab test written with numpy broadcasting."""
    lower, upper = world.blocks[None, :, :3], world.blocks[None, :, 3:]
    out = np.empty(len(segments), dtype=bool)
    for s in range(0, len(segments), chunk):
        p, q = segments[s:s + chunk, 0], segments[s:s + chunk, 1]
        d = q - p
        with np.errstate(divide="ignore", invalid="ignore"):
            inverse = np.where(np.abs(d) > 1e-30, 1.0 / d, 1e30)[:, None, :]
        t1, t2 = (lower - p[:, None]) * inverse, (upper - p[:, None]) * inverse
        enter = np.maximum(np.minimum(t1, t2).max(axis=2), 0.0)
        leave = np.minimum(np.maximum(t1, t2).min(axis=2), 1.0)
        inside = np.all((p > world.lower) & (p < world.upper) & (q > world.lower)
                        & (q < world.upper), axis=1)
        out[s:s + chunk] = inside & ~np.any(enter <= leave, axis=1)
    return out


def median_seconds(function: Callable[[], object], repeats: int) -> float:
    """Median wall time of ``repeats`` calls, in seconds."""
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        function()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--segments", type=int, default=100_000)
    parser.add_argument("--blocks", type=int, default=1_000)
    parser.add_argument("--repeats", type=int, default=11)
    args = parser.parse_args()

    world = forest_of_boxes(args.blocks, seed=1)
    print(f"{args.segments:,} segments against {args.blocks:,} blocks "
          f"(100 x 100 x 20 m forest), medians over {args.repeats} runs")
    for max_length in (5.0, 50.0):
        segments = random_segments(world, args.segments, max_length, seed=2)
        ours = world.segments_free(segments)  # compiles (or loads the cache) once
        assert np.array_equal(ours, numpy_segments_free(world, segments)), "results differ"
        t_ours = median_seconds(lambda s=segments: world.segments_free(s), args.repeats)
        t_numpy = median_seconds(lambda s=segments: numpy_segments_free(world, s), 3)
        print(f"  segments up to {max_length:>4g} m ({100 * ours.mean():.0f}% free): "
              f"quadnav {t_ours:.3f} s, numpy baseline {t_numpy:.3f} s, "
              f"{t_numpy / t_ours:.0f}x faster; target < 0.5 s: "
              f"{'met' if t_ours < 0.5 else 'MISSED'}")
    single = random_segments(world, 1000, 5.0, seed=3)
    t_single = median_seconds(lambda: [world.segment_free(p, q) for p, q in single], 5) / 1000
    print(f"  one segment at a time (World.segment_free): {1e6 * t_single:.1f} us per call")


if __name__ == "__main__":
    main()

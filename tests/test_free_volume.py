"""The free-volume figure: exact (checked against a brute-force count on random maps and
against known answers at 100,000 blocks), or an estimate that says so."""

from __future__ import annotations

import numpy as np
import pytest

from quadnav.cli.main import main
from quadnav.cli.map_commands import free_volume_text
from quadnav.world import World
from quadnav.world.model import FreeVolume
from quadnav.world.volume import union_volume


def grid_volume(boxes: np.ndarray) -> float:
    """Volume of the union of ``boxes`` (N, 6), m^3, by brute force: the faces cut space
    into cells, and a slab of cells at a time along x is marked covered by the boxes
    through it (a cell is covered or not, so the sum is exact up to rounding)."""
    edges = [np.unique(np.concatenate([boxes[:, axis], boxes[:, axis + 3]]))
             for axis in range(3)]
    first = np.column_stack([np.searchsorted(edges[a], boxes[:, a]) for a in range(3)])
    last = np.column_stack([np.searchsorted(edges[a], boxes[:, a + 3]) for a in range(3)])
    dx, dy, dz = (np.diff(e) for e in edges)
    volume = 0.0
    for i in range(len(dx)):
        covered = np.zeros((len(dy), len(dz)), dtype=bool)
        through = (first[:, 0] <= i) & (last[:, 0] > i)
        for (_, j0, k0), (_, j1, k1) in zip(first[through], last[through], strict=True):
            covered[j0:j1, k0:k1] = True
        volume += dx[i] * float(dy @ covered @ dz)
    return volume


def random_boxes(rng: np.random.Generator, n: int, largest: float,
                 grid: float | None = None) -> np.ndarray:
    """(n, 6) boxes up to ``largest`` m a side in a 10 m cube; with ``grid``, every
    coordinate a multiple of it (many shared faces, the hard case for rounding)."""
    lower = rng.uniform(0.0, 10.0, (n, 3))
    upper = lower + rng.uniform(0.01, largest, (n, 3))
    boxes = np.hstack([lower, upper])
    if grid is not None:
        boxes = np.round(boxes / grid) * grid
        boxes[:, 3:] = np.maximum(boxes[:, 3:], boxes[:, :3] + grid)
    return boxes


@pytest.mark.parametrize(("n", "largest", "grid"), [
    (30, 4.0, None), (200, 2.0, None), (300, 6.0, None), (200, 3.0, 0.5), (400, 10.0, 1.0),
])
def test_union_volume_matches_a_brute_force_count_on_random_maps(n, largest, grid):
    rng = np.random.default_rng(n)
    within = np.array([1.0, 0.5, 2.0, 9.0, 9.5, 8.0])
    for _ in range(5):
        boxes = random_boxes(rng, n, largest, grid)
        clipped = np.hstack([np.maximum(boxes[:, :3], within[:3]),
                             np.minimum(boxes[:, 3:], within[3:])])
        clipped = clipped[np.all(clipped[:, :3] < clipped[:, 3:], axis=1)]
        expected = grid_volume(clipped)
        assert union_volume(boxes, within) == pytest.approx(expected, rel=1e-12, abs=1e-12)


def test_slabs_sticks_and_nested_boxes_are_exact():
    cube = [0.0, 0.0, 0.0, 4.0, 4.0, 4.0]
    # z from 1 to 3 (32 m^3) and x from 1 to 2 (16 m^3), which overlap in 8 m^3.
    slabs = [[0, 0, 1, 4, 4, 2], [0, 0, 1.5, 4, 4, 3], [1, 0, 0, 2, 4, 4]]
    assert union_volume(slabs, cube) == pytest.approx(32 + 16 - 8)
    sticks = [[0, 1, 1, 4, 2, 2], [1, 0, 1, 2, 4, 2], [1, 1, 0, 2, 2, 4]] * 4  # repeated
    assert union_volume(sticks, cube) == pytest.approx(3 * 4 - 2)
    nested = [[0, 0, 0, 4, 4, 4], [1, 1, 1, 2, 2, 2]]
    assert union_volume(nested, cube) == pytest.approx(64)
    assert union_volume(np.zeros((0, 6)), cube) == 0.0


def test_100000_blocks_are_measured_exactly():
    # 50,000 unit cubes on a lattice 2 m apart, each with a copy shifted 0.5 m along x:
    # every pair covers 1.5 m^3 and no two pairs touch.
    i, j, k = np.meshgrid(np.arange(50), np.arange(50), np.arange(20), indexing="ij")
    lower = 2.0 * np.column_stack([i.ravel(), j.ravel(), k.ravel()])
    cubes = np.hstack([lower, lower + 1.0])
    boxes = np.vstack([cubes, cubes + np.array([0.5, 0, 0, 0.5, 0, 0])])
    world = World(boundary=[0, 0, 0, 100, 100, 40], blocks=boxes)
    result = world.free_volume()
    assert len(world) == 100_000 and result.exact
    assert result.fraction == pytest.approx(1 - 50_000 * 1.5 / 400_000, abs=1e-12)


def test_a_map_too_costly_to_measure_exactly_is_estimated_and_says_so():
    rng = np.random.default_rng(4)
    world = World(boundary=[0, 0, 0, 10, 10, 10], blocks=np.minimum(
        random_boxes(rng, 300, 4.0), 10.0))
    exact = world.free_volume()
    estimate = world.free_volume(budget=100)
    assert exact.exact and exact.error == 0
    assert not estimate.exact and 0 < estimate.error < 0.004
    assert abs(estimate.fraction - exact.fraction) < estimate.error
    assert exact.fraction == pytest.approx(1 - grid_volume(world.blocks) / 1000, rel=1e-12)
    assert world.free_volume(budget=100) == estimate  # seeded: the same every time


def test_map_info_prints_the_free_volume(tmp_path, capsys):
    path = tmp_path / "m.txt"
    path.write_text("boundary 0 0 0 10 10 5\nblock 0 0 0 5 10 5\nblock 4 0 0 6 10 5\n")
    assert main(["map", "info", str(path)]) == 0
    assert "free volume: 40.00 %\n" in capsys.readouterr().out


def test_an_estimate_is_printed_with_its_error():
    assert free_volume_text(FreeVolume(0.4, 0.0)) == "40.00 %"
    assert free_volume_text(FreeVolume(0.97532, 0.00098)) == (
        "97.53 % +- 0.10 % (estimated from 100,000 random points; the exact figure would "
        "take too long)")

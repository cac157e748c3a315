"""The block grid answers exactly like a scan over every block; the node grid like a scan."""

from __future__ import annotations

import numpy as np
import pytest
from numba import njit

from quadnav.planning.nodegrid import insert, nearest, new_node_grid, within
from quadnav.world import World, geometry, load_world
from quadnav.world.blockgrid import build_block_grid, grid_point_free, grid_segment_free


@njit(cache=True)
def _grid_answers(segments, grid):
    out = np.empty((len(segments), 2), dtype=np.bool_)
    for k in range(len(segments)):
        out[k, 0] = grid_segment_free(segments[k, 0], segments[k, 1], grid)
        p = segments[k, 0]
        out[k, 1] = grid_point_free(p[0], p[1], p[2], grid)
    return out


def tricky_segments(world: World, count: int, seed: int) -> np.ndarray:
    """Random segments of all lengths, plus ones along and ending on block faces."""
    rng = np.random.default_rng(seed)
    p = world.lower + rng.random((count, 3)) * world.extent
    q = p + rng.normal(size=(count, 3)) * rng.choice([0.05, 0.5, 3, 30], size=(count, 1))
    segments = [np.stack([p, q], axis=1)]
    if len(world.blocks):
        rows = rng.integers(len(world.blocks), size=count)
        faces = world.blocks[rows]
        on_face = p.copy()
        axis = rng.integers(3, size=count)
        on_face[np.arange(count), axis] = faces[np.arange(count), axis + 3 * rng.integers(2)]
        along = on_face.copy()
        other = (axis + 1) % 3
        along[np.arange(count), other] += rng.normal(size=count) * 2
        segments += [np.stack([on_face, q], axis=1), np.stack([on_face, along], axis=1)]
    return np.concatenate(segments)


@pytest.mark.parametrize("spec", ["forest", "forest:size=60x60x10,density=0.1", "maze",
                                  "window", "empty"])
def test_block_grid_matches_brute_force(spec):
    world = load_world(spec).inflate(0.2)
    segments = tricky_segments(world, 20000, seed=len(spec))
    grid = build_block_grid(world)
    answers = _grid_answers(segments, grid)
    _, first_hit = world.first_hits(segments)  # scans every block
    assert np.array_equal(answers[:, 0], first_hit == geometry.NO_HIT)
    assert np.array_equal(answers[:, 0], world.segments_free(segments))
    assert np.array_equal(answers[:, 1], world.points_free(segments[:, 0]))
    assert 0.05 < answers[:, 0].mean() < 0.95  # both answers are well represented


def test_block_grid_of_one_block_touching_the_boundary():
    world = World(boundary=np.array([0.0, 0, 0, 4, 4, 4]),
                  blocks=np.array([[0.0, 0, 0, 4, 1, 4]]))
    grid = build_block_grid(world)
    touching = np.array([[[2.0, 1.0, 2.0], [2.0, 3.0, 2.0]]])  # starts on the block's face
    clear = np.array([[[2.0, 1.5, 2.0], [3.0, 3.0, 3.0]]])
    assert not _grid_answers(touching, grid)[0, 0]
    assert _grid_answers(clear, grid)[0, 0]


@pytest.mark.parametrize("spread", [0.2, 1.0])
def test_node_grid_nearest_and_radius_queries_match_a_scan(spread):
    rng = np.random.default_rng(4)
    origin, extent = np.zeros(3), np.array([20.0, 20.0, 6.0])
    capacity = 3000
    nodes = np.zeros((capacity, 3))
    state = new_node_grid(capacity)
    found, distances = np.zeros(capacity, dtype=np.int64), np.zeros(capacity)
    for count in range(1, capacity + 1):
        nodes[count - 1] = rng.random(3) * extent * spread  # clustered, then uniform
        insert(count - 1, nodes, origin, extent, *state)
        if count % 7:
            continue
        query = rng.random(3) * extent
        scan = np.linalg.norm(nodes[:count] - query, axis=1)
        assert scan[nearest(query, nodes, count, origin, *state)] == scan.min()
        radius = rng.uniform(0.1, 3.0)
        n = within(query, radius, nodes, count, origin, *state, found, distances)
        assert sorted(found[:n]) == list(np.flatnonzero(scan <= radius))
        assert np.allclose(distances[:n], scan[found[:n]])

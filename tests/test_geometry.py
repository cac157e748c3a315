"""Exact geometry: points, segments, clearance, first hit, inflation, volume, sampling."""

from __future__ import annotations

import pickle

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from quadnav.errors import QuadnavError
from quadnav.world import World
from quadnav.world.volume import union_volume

BOUNDARY = np.array([0.0, 0.0, 0.0, 10.0, 10.0, 10.0])


def reference_signed_distance(points: np.ndarray, boxes: np.ndarray) -> np.ndarray:
    """Signed distance (P, B) from points (P, 3) to closed boxes (B, 6), by plain numpy."""
    lower, upper = boxes[None, :, :3], boxes[None, :, 3:]
    p = points[:, None, :]
    outside = np.maximum(np.maximum(lower - p, p - upper), 0.0)
    inside_depth = np.minimum(p - lower, upper - p).min(axis=2)
    inside = np.all((lower <= p) & (p <= upper), axis=2)
    return np.where(inside, -inside_depth, np.linalg.norm(outside, axis=2))


@st.composite
def worlds(draw, max_blocks: int = 6) -> World:
    """Random worlds in a 10 m cube with up to ``max_blocks`` blocks of 0.1..4 m."""
    n = draw(st.integers(0, max_blocks))
    lower = draw(arrays(np.float64, (n, 3), elements=st.floats(0, 8)))
    size = draw(arrays(np.float64, (n, 3), elements=st.floats(0.1, 4)))
    return World(boundary=BOUNDARY, blocks=np.hstack([lower, np.minimum(lower + size, 10)]))


coordinates = st.floats(0.05, 9.95)
points = st.tuples(coordinates, coordinates, coordinates).map(np.array)


def dense_segment_verdict(world: World, p: np.ndarray, q: np.ndarray) -> bool | None:
    """Free / not free by dense sampling, or None when the case is too close to call."""
    n = 4000
    samples = p + np.linspace(0, 1, n)[:, None] * (q - p)
    step = np.linalg.norm(q - p) / (n - 1)
    if len(world.blocks) == 0:
        return True
    distance = reference_signed_distance(samples, world.blocks).min(axis=1)
    if distance.min() > step:  # every point of the segment is > step / 2 from every block
        return True
    if distance.min() < -1e-6:  # some sample is strictly inside a block
        return False
    return None


@settings(max_examples=300, deadline=None)
@given(worlds(), points, points)
def test_exact_segment_check_agrees_with_dense_sampling(world, p, q):
    verdict = dense_segment_verdict(world, p, q)
    assume(verdict is not None)
    assert world.segment_free(p, q) == verdict


@settings(max_examples=100, deadline=None)
@given(worlds(), arrays(np.float64, (20, 2, 3), elements=st.floats(-1, 11)))
def test_batch_forms_agree_with_single_forms(world, segments):
    free = world.segments_free(segments)
    ts, _ = world.first_hits(segments)
    for k, (p, q) in enumerate(segments):
        assert free[k] == world.segment_free(p, q)
        hit = world.first_hit(p, q)
        assert (hit is None) == (ts[k] == np.inf)
    np.testing.assert_array_equal(world.points_free(segments[:, 0]),
                                  [world.is_free(p) for p in segments[:, 0]])
    np.testing.assert_array_equal(world.clearances(segments[:, 0]),
                                  [world.clearance(p) for p in segments[:, 0]])


@settings(max_examples=200, deadline=None)
@given(worlds(), points, points)
def test_first_hit_is_the_first_contact(world, p, q):
    hit = world.first_hit(p, q)
    if hit is None:
        assert world.segment_free(p, q)
        return
    assert not world.segment_free(p, q)
    assert 0 <= hit.t <= 1
    np.testing.assert_allclose(hit.point, p + hit.t * (q - p))
    if not world.is_free(p):
        assert hit.t == 0  # a segment that starts in collision is hit at once
    elif hit.block is not None:  # the first contact is on the block's surface
        assert abs(reference_signed_distance(hit.point[None], world.blocks[[hit.block]])[0, 0]) < 1e-9
    if hit.t > 1e-6:  # everything before the hit is free
        assert world.segment_free(p, p + (hit.t - 1e-6) * (q - p))


@settings(max_examples=200, deadline=None)
@given(worlds(), arrays(np.float64, (50, 3), elements=st.floats(-1, 11)))
def test_points_and_clearance_match_a_reference(world, pts):
    inside_boundary = np.all((pts > 0) & (pts < 10), axis=1)
    boundary_distance = np.minimum(pts, 10 - pts).min(axis=1)
    if len(world.blocks):
        distance = reference_signed_distance(pts, world.blocks)
        lower, upper = world.blocks[None, :, :3], world.blocks[None, :, 3:]
        in_block = np.any(np.all((lower <= pts[:, None]) & (pts[:, None] <= upper), axis=2), axis=1)
        expected_clearance = np.minimum(boundary_distance, distance.min(axis=1))
    else:
        in_block = np.zeros(len(pts), dtype=bool)
        expected_clearance = boundary_distance
    np.testing.assert_array_equal(world.points_free(pts), inside_boundary & ~in_block)
    np.testing.assert_allclose(world.clearances(pts), expected_clearance, atol=1e-12)


@settings(max_examples=200, deadline=None)
@given(worlds(), st.floats(0, 1), arrays(np.float64, (50, 3), elements=st.floats(-1, 11)))
def test_inflated_world_contains_the_original(world, margin, pts):
    inflated = world.inflate(margin)
    assert np.all(inflated.blocks[:, :3] <= world.blocks[:, :3])
    assert np.all(inflated.blocks[:, 3:] >= world.blocks[:, 3:])
    free_inflated = inflated.points_free(pts)
    assert not np.any(free_inflated & ~world.points_free(pts))
    # ... and keeps exactly the points at least `margin` from every obstacle.
    clear = world.clearances(pts)
    assert np.all(clear[free_inflated] >= margin - 1e-9)


def test_free_space_is_open():
    world = World(boundary=BOUNDARY, blocks=[[4, 4, 4, 6, 6, 6]])
    assert not world.is_free([4, 5, 5])          # on a face
    assert not world.is_free([4, 4, 4])          # on a corner
    assert not world.is_free([0, 5, 5])          # on the boundary
    assert world.is_free([3.999, 5, 5])
    assert world.segment_free([3, 3, 5], [5, 3, 5])  # passes beside it
    assert not world.segment_free([3, 4, 5], [7, 4, 5])  # slides along a face
    assert not world.segment_free([3, 5, 3], [5, 5, 4])  # ends on the bottom face
    assert not world.segment_free([3, 3, 6], [5, 5, 6])  # runs onto the top face
    assert not world.segment_free([2, 2, 2], [4, 4, 4])  # touches a corner
    assert world.segment_free([2, 2, 2], [3.99, 3.99, 3.99])
    assert not world.segment_free([5, 5, 0.5], [5, 5, 0])  # ends on the boundary
    assert world.clearance([5, 5, 7]) == pytest.approx(1.0)
    assert world.clearance([5, 5, 5]) == pytest.approx(-1.0)
    assert world.clearance([5, 5, 9.5]) == pytest.approx(0.5)


def test_segment_parallel_to_an_axis_and_degenerate_segment():
    world = World(boundary=BOUNDARY, blocks=[[4, 4, 4, 6, 6, 6]])
    assert not world.segment_free([5, 5, 1], [5, 5, 9])
    assert world.segment_free([5, 7, 1], [5, 7, 9])
    assert world.segment_free([1, 1, 1], [1, 1, 1])
    assert not world.segment_free([5, 5, 5], [5, 5, 5])


def test_first_hit_reports_block_and_boundary():
    world = World(boundary=BOUNDARY, blocks=[[4, 4, 4, 6, 6, 6], [7, 4, 4, 8, 6, 6]])
    hit = world.first_hit([1, 5, 5], [9, 5, 5])
    assert hit.block == 0 and hit.t == pytest.approx(3 / 8)
    np.testing.assert_allclose(hit.point, [4, 5, 5])
    hit = world.first_hit([9, 5, 5], [1, 5, 5])
    assert hit.block == 1
    hit = world.first_hit([5, 5, 8], [5, 5, 12])
    assert hit.block is None and hit.t == pytest.approx(0.5)
    hit = world.first_hit([5, 5, -1], [5, 5, 2])
    assert hit.block is None and hit.t == 0
    assert world.first_hit([1, 1, 1], [2, 2, 2]) is None


def test_inflate_shrinks_the_boundary_and_refuses_too_much():
    world = World(boundary=BOUNDARY, blocks=[[4, 4, 4, 6, 6, 6]], name="box")
    inflated = world.inflate(0.5)
    np.testing.assert_array_equal(inflated.boundary, [0.5, 0.5, 0.5, 9.5, 9.5, 9.5])
    np.testing.assert_array_equal(inflated.blocks, [[3.5, 3.5, 3.5, 6.5, 6.5, 6.5]])
    assert world.inflate(0).segment_free([1, 1, 1], [2, 2, 2])
    with pytest.raises(QuadnavError, match="box: margin 5 m leaves no free space"):
        world.inflate(5)
    with pytest.raises(ValueError):
        world.inflate(-1)


def test_union_volume_is_exact_for_integer_boxes():
    rng = np.random.default_rng(7)
    for _ in range(20):
        lower = rng.integers(0, 8, size=(12, 3))
        boxes = np.hstack([lower, lower + rng.integers(1, 4, size=(12, 3))]).astype(float)
        grid = np.zeros((12, 12, 12), dtype=bool)
        for b in boxes.astype(int):
            grid[b[0]:b[3], b[1]:b[4], b[2]:b[5]] = True
        assert union_volume(boxes, [0, 0, 0, 12, 12, 12]) == grid.sum()


def test_sample_free_is_seeded_uniform_and_free():
    world = World(boundary=BOUNDARY, blocks=[[0, 0, 0, 10, 5, 10]])
    a = world.sample_free(2000, seed=3)
    np.testing.assert_array_equal(a, world.sample_free(2000, seed=3))
    assert not np.array_equal(a, world.sample_free(2000, seed=4))
    assert a.shape == (2000, 3) and world.points_free(a).all()
    assert np.all(a[:, 1] > 5)
    # Uniform: each half of the free region along x gets about half the points.
    assert abs(np.mean(a[:, 0] < 5) - 0.5) < 0.05


def test_sample_free_gives_up_on_a_full_world():
    world = World(boundary=BOUNDARY, blocks=[[0, 0, 0, 10, 10, 10]], name="full")
    with pytest.raises(ValueError, match="full: found only 0 free points"):
        world.sample_free(1)


def test_world_values_are_immutable():
    world = World(boundary=BOUNDARY, blocks=[[4, 4, 4, 6, 6, 6]])
    with pytest.raises(ValueError):
        world.blocks[0, 0] = 1
    with pytest.raises(AttributeError):
        world.name = "x"


def test_an_unpickled_world_stays_immutable_and_answers_the_same():
    # A batch worker gets its missions' worlds pickled; numpy unpickles arrays writable,
    # and a compiled query would then be compiled again for writable arrays.
    world = World(boundary=BOUNDARY, blocks=[[4, 4, 4, 6, 6, 6]], start=[1, 1, 1], name="w")
    points = np.array([[1.0, 1.0, 1.0], [5.0, 5.0, 7.0]])
    world.clearances(points)  # fills the cached per-coordinate blocks, pickled with it
    copy = pickle.loads(pickle.dumps(world))
    for name in ("boundary", "blocks", "colors", "start"):
        assert not getattr(copy, name).flags.writeable, name
    assert np.array_equal(copy.clearances(points), world.clearances(points))
    assert copy.name == "w" and copy.goal is None


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"boundary": [0, 0, 0, 1, 1]}, "boundary must have shape"),
    ({"boundary": [0, 0, 0, 1, 1, np.nan]}, "boundary must be finite"),
    ({"boundary": [0, 0, 2, 1, 1, 1]}, "boundary: every min must be below its max"),
    ({"boundary": BOUNDARY, "blocks": [[0, 0, 0, 1, 1]]}, "blocks must have shape"),
    ({"boundary": BOUNDARY, "blocks": [[0, 0, 0, 1, 1, 1]], "colors": [[1, 0, 0]] * 2}, "colors must have shape"),
])
def test_world_rejects_bad_values(kwargs, message):
    with pytest.raises(QuadnavError, match=message):
        World(**kwargs)

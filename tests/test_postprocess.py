"""Path post-processing: shortcuts, gradient-descent smoothing and ``refine``.

Input paths are built here without the planners: shortest paths on a 26-connected
lattice (jagged, with many vertices), hand-made zig-zags and seeded random walks.
"""

from __future__ import annotations

import dataclasses
import itertools
import warnings
from functools import cache

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra

from quadnav.errors import PlanningWarning, QuadnavError
from quadnav.planning import PlanResult, PlanStats, PostStep, make_problem, path_length
from quadnav.planning.refine import refine
from quadnav.planning.shortcut import polyline_segments, shortcut_path
from quadnav.planning.smoothing import simplify_path, smooth_path
from quadnav.world import World, load_world

BUILTIN = ("forest", "window", "maze")
EMPTY = World(boundary=[0, 0, 0, 10, 10, 4])
#: A wall across y < 6 at x = 5: from y = 1 on one side to the other, a path must pass
#: its two edges at (4.9, 6) and (5.1, 6).
WALL = World(boundary=[0, 0, 0, 10, 10, 2], blocks=[[4.9, 0, 0, 5.1, 6, 2]])
WALL_SHORTEST = 2 * np.hypot(3.9, 5.0) + 0.2


def lattice_path(world: World, start, goal, spacing: float) -> np.ndarray:
    """Shortest path (N, 3) from ``start`` to ``goal`` through the free nodes of a
    lattice of the given spacing, 26-connected, every segment free in ``world``."""
    axes = [np.arange(lo + spacing, hi, spacing) for lo, hi in zip(world.lower, world.upper,
                                                                      strict=True)]
    shape = tuple(len(a) for a in axes)
    nodes = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    index = np.arange(len(nodes)).reshape(shape)
    ends = np.array([start, goal], dtype=np.float64)
    points = np.concatenate([nodes, ends])
    pairs = []
    for step in itertools.product((-1, 0, 1), repeat=3):
        if step > (0, 0, 0):
            src = index[tuple(slice(0, n - s) if s >= 0 else slice(-s, n)
                              for s, n in zip(step, shape, strict=True))]
            dst = index[tuple(slice(s, n) if s >= 0 else slice(0, n + s)
                              for s, n in zip(step, shape, strict=True))]
            pairs.append(np.stack([src.ravel(), dst.ravel()], axis=1))
    for k, end in enumerate(ends):
        near = np.flatnonzero(np.linalg.norm(nodes - end, axis=1) <= 1.8 * spacing)
        pairs.append(np.stack([np.full(len(near), len(nodes) + k), near], axis=1))
    pairs = np.concatenate(pairs)
    pairs = pairs[world.segments_free(points[pairs])]
    weights = np.linalg.norm(points[pairs[:, 0]] - points[pairs[:, 1]], axis=1)
    graph = coo_matrix((weights, (pairs[:, 0], pairs[:, 1])), shape=(len(points),) * 2)
    _, previous = dijkstra(graph.tocsr(), directed=False, indices=len(nodes),
                           return_predecessors=True)
    chain = [len(nodes) + 1]
    while chain[-1] != len(nodes):
        assert chain[-1] >= 0, "the lattice does not join start and goal"
        chain.append(previous[chain[-1]])
    return points[chain[::-1]]


@cache
def builtin_case(name: str) -> tuple[World, np.ndarray]:
    """The inflated built-in world and a jagged free lattice path between its ends."""
    world = load_world(name)
    free = world.inflate(world.margin)
    return free, lattice_path(free, world.start, world.goal, 0.5)


def random_walk(world: World, start, steps: int, reach: float, seed: int) -> np.ndarray:
    """A free polyline of up to ``steps`` + 1 points: random moves of at most ``reach``
    metres from ``start``, each kept only if its segment is free."""
    rng = np.random.default_rng(seed)
    walk = [np.asarray(start, dtype=np.float64)]
    for _ in range(steps):
        candidates = walk[-1] + rng.uniform(-reach, reach, size=(8, 3))
        free = [c for c in candidates if world.segment_free(walk[-1], c)]
        if free:
            walk.append(free[0])
    return np.array(walk)


def turning_angles(path: np.ndarray) -> np.ndarray:
    """Angle (radians) the direction turns by at each interior vertex (N - 2,)."""
    d = np.diff(path, axis=0)
    d /= np.linalg.norm(d, axis=1)[:, None]
    return np.arccos(np.clip(np.sum(d[:-1] * d[1:], axis=1), -1.0, 1.0))


def assert_free_with_ends(world: World, path: np.ndarray, original: np.ndarray) -> None:
    assert path.shape[1:] == (3,) and len(path) >= 2
    assert world.segments_free(polyline_segments(path)).all()
    assert np.array_equal(path[0], original[0])
    assert np.array_equal(path[-1], original[-1])


# ---------------------------------------------------------------------------- shortcut
@pytest.mark.parametrize("name", BUILTIN)
def test_shortcut_on_builtin_worlds_is_free_and_shorter(name):
    world, path = builtin_case(name)
    short = shortcut_path(world, path, seed=1)
    assert_free_with_ends(world, short, path)
    assert path_length(short) < path_length(path)
    assert len(short) < len(path) // 3


def test_greedy_line_of_sight_joins_visible_ends_directly():
    zigzag = np.array([[1, 1, 1], [2, 3, 1], [3, 1, 2], [4, 3, 1], [8, 8, 3]], dtype=float)
    for attempts in (0, None):
        short = shortcut_path(EMPTY, zigzag, attempts=attempts)
        assert np.array_equal(short, zigzag[[0, -1]])


def test_greedy_line_of_sight_alone_keeps_vertices():
    # A path around the wall: the ends do not see each other; line of sight alone keeps
    # lattice vertices (no new points), random shortcuts then cut the corner further.
    path = lattice_path(WALL, (1, 1, 1), (9, 1, 1), 0.5)
    greedy = shortcut_path(WALL, path, attempts=0)
    assert all((path == vertex).all(axis=1).any() for vertex in greedy)
    short = shortcut_path(WALL, path)
    assert_free_with_ends(WALL, short, path)
    assert WALL_SHORTEST < path_length(short) < path_length(greedy) < path_length(path)
    assert path_length(short) < 1.01 * WALL_SHORTEST


def test_shortcut_is_reproducible_by_seed():
    world, path = builtin_case("maze")
    first = shortcut_path(world, path, seed=7, attempts=500)
    assert np.array_equal(first, shortcut_path(world, path, seed=7, attempts=500))
    assert not np.array_equal(first, shortcut_path(world, path, seed=8, attempts=500))


def test_duplicate_and_collinear_vertices_are_dropped_where_the_chord_is_free():
    path = np.array([[1, 1, 1], [1, 1, 1], [1, 5, 1], [1, 9, 1], [1, 9, 1]], dtype=float)
    assert np.array_equal(shortcut_path(EMPTY, path), path[[0, -1]])
    assert np.array_equal(simplify_path(EMPTY, path, 0.0), path[[0, -1]])
    around = np.array([[1, 1, 1], [5, 6.5, 1], [9, 1, 1]], dtype=float)
    assert np.array_equal(simplify_path(WALL, around, 100.0), around)


def test_shortcut_short_paths_pass_through():
    two = np.array([[1, 1, 1], [2, 2, 2]], dtype=float)
    assert np.array_equal(shortcut_path(EMPTY, two), two)
    assert np.array_equal(shortcut_path(EMPTY, two[:1]), two[:1])


@pytest.mark.parametrize(("path", "attempts", "message"), [
    ([[1, 1, 1], [9, 1, 1]], None, r"segment 0 \(1, 1, 1\) -> \(9, 1, 1\) is not free"),
    ([[1, 1, 1], [1, 2, 1]], -1, "attempts must be >= 0, got -1"),
    ([1, 1, 1], None, r"must be an \(N, 3\) array"),
    ([[1, 1, np.nan], [1, 2, 1]], None, "finite"),
])
def test_shortcut_rejects_bad_input(path, attempts, message):
    with pytest.raises(QuadnavError, match=message):
        shortcut_path(WALL, np.array(path, dtype=float), attempts=attempts)


# --------------------------------------------------------------------------- smoothing
@pytest.mark.parametrize("name", BUILTIN)
def test_smoothing_lattice_paths_stays_free_and_rounds_corners(name):
    world, path = builtin_case(name)
    smooth = smooth_path(world, path)
    assert_free_with_ends(world, smooth, path)
    before, after = turning_angles(path), turning_angles(smooth)
    # The sharpest corners are spread over several vertices (where they have room).
    assert after.max() < 0.95 * before.max()
    assert after.sum() < 0.97 * before.sum()


@pytest.mark.parametrize("name", BUILTIN)
def test_smoothing_after_shortcut_stays_free(name):
    world, path = builtin_case(name)
    short = shortcut_path(world, path)
    smooth = smooth_path(world, short)
    assert_free_with_ends(world, smooth, short)
    assert turning_angles(smooth).sum() <= turning_angles(short).sum() + 1e-6


def test_smoothing_a_zigzag_in_open_space():
    x = np.linspace(1, 9, 9)
    zigzag = np.stack([x, 5 + 0.5 * (-1.0) ** np.arange(9), np.full(9, 2.0)], axis=1)
    smooth = smooth_path(EMPTY, zigzag)
    assert_free_with_ends(EMPTY, smooth, zigzag)
    assert np.degrees(turning_angles(smooth).max()) < 60  # every corner turns 90 deg
    assert path_length(smooth) < path_length(zigzag)
    # With no pull towards the data the path relaxes towards the straight line.
    string = smooth_path(EMPTY, zigzag, weight_data=0.0, weight_smooth=0.8, max_spacing=1.0)
    assert path_length(string) < 1.001 * np.linalg.norm(zigzag[-1] - zigzag[0])


def test_smoothing_cuts_a_corner_by_about_the_spacing():
    corner = np.array([[1, 1, 1], [5, 1, 1], [5, 5, 1]], dtype=float)
    smooth = smooth_path(EMPTY, corner, max_spacing=0.2)
    assert not (smooth == corner[1]).all(axis=1).any()
    cut = np.linalg.norm(smooth - corner[1], axis=1).min()
    assert 0.02 < cut < 0.6
    assert len(smooth) < 40  # the straight runs lose their densifying points


def test_smoothing_beside_a_block_freezes_points_instead_of_colliding():
    # A block fills the inside of the turn, 1 mm from both legs: every move that rounds
    # the corner collides, so the points are put back and the path comes out unchanged.
    block = World(boundary=[0, 0, 0, 10, 10, 4], blocks=[[1, 1.001, 0, 4.999, 9, 4]])
    corner = np.array([[1.5, 1, 2], [5, 1, 2], [5, 5, 2]], dtype=float)
    assert np.array_equal(smooth_path(block, corner, max_spacing=0.1), corner)
    # With room, the same corner is rounded.
    assert not np.array_equal(smooth_path(EMPTY, corner, max_spacing=0.1), corner)


def test_smoothing_is_deterministic_and_keeps_straight_paths():
    world, path = builtin_case("window")
    assert np.array_equal(smooth_path(world, path), smooth_path(world, path))
    line = np.array([[1, 1, 1], [3, 3, 3]], dtype=float)
    assert np.array_equal(smooth_path(EMPTY, line), line)


@pytest.mark.parametrize(("options", "message"), [
    ({"weight_data": -0.1}, r"weight_data must be in \[0, 1\], got -0.1"),
    ({"weight_data": 1.5}, r"weight_data must be in \[0, 1\], got 1.5"),
    ({"weight_smooth": 0.0}, "weight_smooth must be a number > 0, got 0.0"),
    ({"weight_data": 1.0, "weight_smooth": 0.5}, "must be below 2 for the sweeps to converge"),
    ({"tolerance": 0.0}, "tolerance must be a positive number of metres, got 0.0"),
    ({"tolerance": float("nan")}, "tolerance must be a positive number of metres, got nan"),
    ({"max_spacing": -1.0}, "max_spacing must be a positive number of metres, got -1.0"),
    ({"max_sweeps": 0}, "max_sweeps must be >= 1, got 0"),
])
def test_smoothing_rejects_bad_options(options, message):
    with pytest.raises(QuadnavError, match=message):
        smooth_path(EMPTY, [[1, 1, 1], [2, 2, 2], [3, 2, 2]], **options)


# ------------------------------------------------------------------------------ refine
@cache
def margin_case() -> tuple[object, PlanResult]:
    """Forest with the start and goal on the boundary (so inside the margin), and a
    result holding a lattice path between the search ends, with the legs."""
    world = load_world("forest")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PlanningWarning)
        problem = make_problem(world, (0, 1, 1), (20, 19, 3), world.margin)
    search = lattice_path(problem.free_world, problem.search_start, problem.search_goal, 0.5)
    stats = PlanStats(iterations=10, nodes=10, seconds=0.5, time_to_first=0.1,
                      post=(PostStep("earlier", 1.0, 2, 0.0),))
    result = PlanResult("lattice", True, problem.full_path(search), np.zeros((0, 3)),
                        np.zeros(0, dtype=np.int64), stats, seed=5)
    return problem, result


def test_refine_keeps_the_legs_out_of_the_margin_and_records_steps():
    problem, result = margin_case()
    refined = refine(problem, result)
    path = refined.path
    assert np.array_equal(path[:2], result.path[:2])  # start, then the search start
    assert np.array_equal(path[-2:], result.path[-2:])
    assert not np.array_equal(problem.start, problem.search_start)
    assert problem.free_world.segments_free(polyline_segments(path[1:-1])).all()
    assert refined.length < result.length
    earlier, shortcut, smooth = refined.stats.post
    assert earlier == result.stats.post[0]
    assert (shortcut.name, smooth.name) == ("shortcut", "smooth")
    assert smooth.length == pytest.approx(path_length(path), abs=1e-12)
    assert smooth.vertices == len(path)
    only_shortcut = refine(problem, result, smooth=False)
    assert only_shortcut.stats.post[1:] == (dataclasses.replace(
        shortcut, seconds=only_shortcut.stats.post[1].seconds),)
    assert shortcut.length == pytest.approx(only_shortcut.length, abs=1e-12)
    assert shortcut.vertices == len(only_shortcut.path)
    assert refined.stats.iterations == result.stats.iterations
    assert refined.seed == result.seed and refined.planner == result.planner


def test_refine_uses_the_result_seed_by_default():
    problem, result = margin_case()
    assert np.array_equal(refine(problem, result, smooth=False).path,
                          refine(problem, result, seed=5, smooth=False).path)
    assert not np.array_equal(refine(problem, result, smooth=False).path,
                              refine(problem, result, seed=6, smooth=False).path)


def test_refine_passes_smoothing_options_and_checks_them():
    problem, result = margin_case()
    loose = refine(problem, result, max_spacing=2.0)
    assert loose.stats.post[-1].name == "smooth"
    with pytest.raises(QuadnavError, match="weight_data"):
        refine(problem, result, weight_data=2.0)
    with pytest.raises(QuadnavError, match="smoothing options max_spacing given with smooth=False"):
        refine(problem, result, smooth=False, max_spacing=2.0)


def test_refine_leaves_an_unsolved_result_alone():
    problem, _ = margin_case()
    failed = PlanResult("lattice", False, np.zeros((0, 3)), np.zeros((0, 3)),
                        np.zeros(0, dtype=np.int64), PlanStats(1, 1, 0.1, None), seed=0)
    assert refine(problem, failed) is failed


def test_refine_rejects_a_path_that_skips_the_legs():
    problem, result = margin_case()
    without_legs = result.replace(path=result.path[1:-1])
    with pytest.raises(QuadnavError, match=r"does not begin with the problem's start leg .* \(from \(0, 1, 1\)"):
        refine(problem, without_legs)


# ---------------------------------------------------------------------- random worlds
@st.composite
def worlds_and_walks(draw) -> tuple[World, np.ndarray]:
    """A 4 m cube with up to 5 random boxes and a free random walk in it."""
    corners = draw(st.lists(st.tuples(*[st.floats(0.3, 3.0)] * 3, *[st.floats(0.2, 1.5)] * 3),
                            max_size=5))
    blocks = np.array([[x, y, z, x + dx, y + dy, z + dz] for x, y, z, dx, dy, dz in corners]
                      ).reshape(-1, 6)
    world = World(boundary=[0, 0, 0, 4, 4, 4], blocks=blocks)
    start = world.sample_free(1, seed=draw(st.integers(0, 2**16)))[0]
    walk = random_walk(world, start, draw(st.integers(2, 15)), 1.5,
                       seed=draw(st.integers(0, 2**16)))
    return world, walk


@settings(max_examples=20, deadline=None)
@given(worlds_and_walks(), st.integers(0, 2**16))
def test_post_processing_random_worlds(case, seed):
    world, walk = case
    short = shortcut_path(world, walk, seed=seed, attempts=100)
    assert path_length(short) <= path_length(walk)
    smooth = smooth_path(world, walk, max_spacing=0.3, tolerance=1e-4)
    for path in (short, smooth):
        assert world.segments_free(polyline_segments(path)).all()
        assert np.array_equal(path[0], walk[0]) and np.array_equal(path[-1], walk[-1])

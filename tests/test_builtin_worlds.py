"""Built-in worlds (quadnav.world.builtin) and the connectivity proof they rely on."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from quadnav.errors import MapError
from quadnav.world import builtin
from quadnav.world.builtin import (
    DEFAULT_MARGIN,
    DEFAULT_WORLD_SPEC,
    build_world,
    describe_worlds,
    is_builtin_spec,
    world_names,
)
from quadnav.world.builtin.base import plate_with_hole
from quadnav.world.builtin.forest import CLEAR
from quadnav.world.builtin.maze import _passages
from quadnav.world.connectivity import connected, default_resolution
from quadnav.world.model import World

SPECS = [
    "empty",
    "empty:size=3x5x2",
    "forest",
    "forest:size=30x12x4,density=0.15,branches=4,seed=7",
    "window",
    "window:size=4x12x3,walls=5,seed=2",
    "maze",
    "maze:cells=4x7,levels=3,cell_size=1.5,level_height=1.8,seed=5",
]


def trunks(world: World) -> np.ndarray:
    """Blocks that run from the floor to the ceiling: a forest's trunks (branches never do)."""
    full = (world.blocks[:, 2] == world.lower[2]) & (world.blocks[:, 5] == world.upper[2])
    return world.blocks[full]


def assert_flyable(world: World) -> None:
    """Start and goal are free at the default margin and provably connected."""
    inflated = world.inflate(DEFAULT_MARGIN)
    assert inflated.is_free(world.start)
    assert inflated.is_free(world.goal)
    assert connected(inflated, world.start, world.goal)


@pytest.fixture(scope="module")
def built() -> dict[str, World]:
    return {spec: build_world(spec) for spec in SPECS}


# ------------------------------------------------------------------ every world
@pytest.mark.parametrize("name", world_names())
def test_every_world_builds_with_defaults(name: str) -> None:
    world = build_world(name)
    assert world.name.startswith(f"{name}:")
    assert world.margin == DEFAULT_MARGIN
    assert world.start is not None and world.goal is not None
    assert np.linalg.norm(world.goal - world.start) > 1.0
    assert_flyable(world)


@pytest.mark.parametrize("spec", SPECS)
def test_blocks_are_valid_and_inside_the_boundary(built: dict[str, World], spec: str) -> None:
    world = built[spec]
    assert np.all(world.blocks[:, :3] < world.blocks[:, 3:])
    assert np.all(world.blocks[:, :3] >= world.lower)
    assert np.all(world.blocks[:, 3:] <= world.upper)
    assert world.colors.shape == (len(world.blocks), 3)
    assert np.all((world.colors >= 0) & (world.colors <= 1))


@pytest.mark.parametrize("spec", SPECS)
def test_start_and_goal_are_free_and_connected(built: dict[str, World], spec: str) -> None:
    assert_flyable(built[spec])


@pytest.mark.parametrize("spec", SPECS)
def test_canonical_name_rebuilds_the_same_world(built: dict[str, World], spec: str) -> None:
    world = built[spec]
    again = build_world(world.name)
    assert again.name == world.name
    np.testing.assert_array_equal(again.blocks, world.blocks)
    np.testing.assert_array_equal(again.colors, world.colors)
    np.testing.assert_array_equal(again.start, world.start)
    np.testing.assert_array_equal(again.goal, world.goal)


def test_canonical_name_lists_every_parameter() -> None:
    assert build_world("forest:seed=3").name == (
        "forest:size=20x20x6,density=0.1,trunk_min=0.3,trunk_max=0.6,gap=0.8,branches=2,seed=3"
    )
    assert build_world(" window : walls = 2 ").name == "window:size=10x20x6,walls=2,seed=0"


@pytest.mark.parametrize("name", ["forest", "window", "maze"])
def test_same_seed_same_world_and_other_seed_other_world(name: str) -> None:
    first, again = build_world(f"{name}:seed=4"), build_world(f"{name}:seed=4")
    other = build_world(f"{name}:seed=5")
    np.testing.assert_array_equal(first.blocks, again.blocks)
    assert first.blocks.shape != other.blocks.shape or not np.array_equal(
        first.blocks, other.blocks)


# ------------------------------------------------------------------------ forest
def test_forest_trunk_count_follows_density(built: dict[str, World]) -> None:
    world = built["forest"]  # 20 x 20 m at 0.1 trunks per square metre
    assert 30 <= len(trunks(world)) <= 50
    assert len(world.blocks) > len(trunks(world))  # and some branches


def test_large_forest_has_about_800_trunks() -> None:
    world = build_world("forest:size=100x100x20,density=0.08")
    assert 760 <= len(trunks(world)) <= 840
    assert_flyable(world)


def test_forest_trunks_keep_their_gap_and_the_clear_zones() -> None:
    world = build_world("forest:size=25x25x5,density=0.15,gap=1.1,seed=1")
    boxes = trunks(world)
    # Between any two trunks there is a gap of at least 1.1 m along x or along y.
    low, high = boxes[:, None, :2], boxes[None, :, 3:5]
    gaps = np.max(np.maximum(low - high, np.swapaxes(low - high, 0, 1)), axis=2)
    np.fill_diagonal(gaps, np.inf)
    assert gaps.min() >= 1.1 - 1e-9
    # Nothing, trunk or branch, stands within CLEAR of start or goal (in plan view).
    for point in (world.start, world.goal):
        low, high = world.blocks[:, :2], world.blocks[:, 3:5]
        away = (high < point[:2] - CLEAR) | (low > point[:2] + CLEAR)
        assert np.all(np.any(away, axis=1))


def test_forest_branches_are_thin_horizontal_boxes() -> None:
    world = build_world("forest:branches=5,seed=2")
    branches = world.blocks[len(trunks(world)):]
    assert len(branches) > 50
    sides = np.sort(branches[:, 3:] - branches[:, :3], axis=1)
    assert np.all(sides[:, 0] <= 0.15 + 1e-9)  # thickness
    assert np.all(branches[:, 5] - branches[:, 2] <= 0.15 + 1e-9)  # horizontal
    assert np.all(sides[:, 2] > 0.2)  # sticks out of its trunk (perhaps cut by the boundary)


def test_forest_without_branches_has_only_trunks() -> None:
    world = build_world("forest:branches=0")
    assert len(trunks(world)) == len(world.blocks)


# ------------------------------------------------------------------ window, maze
def test_window_walls_are_four_blocks_around_a_window() -> None:
    world = build_world("window:walls=4,seed=3")
    assert len(world.blocks) == 16
    for wall in np.split(world.blocks, 4):
        assert np.ptp(wall[:, [1, 4]]) <= 0.4 + 1e-9  # one slab across y
        below, above = wall[wall[:, 5] - wall[:, 2] < world.extent[2]]  # beside the window
        np.testing.assert_array_equal(below[[0, 3]], above[[0, 3]])
        assert 1.0 <= below[3] - below[0] <= 1.6  # window width
        assert 1.0 <= above[2] - below[5] <= 1.6  # window height
    ys = world.blocks[:, [1, 4]]
    assert np.all(ys > world.start[1]) and np.all(ys < world.goal[1])


@pytest.mark.parametrize(("nx", "ny"), [(1, 1), (1, 5), (6, 6), (9, 4)])
def test_maze_passages_form_a_spanning_tree(nx: int, ny: int) -> None:
    east, north = _passages(np.random.default_rng(nx * ny), nx, ny)
    assert east.sum() + north.sum() == nx * ny - 1  # a tree has one edge fewer than cells
    reached, frontier = {(0, 0)}, [(0, 0)]
    while frontier:
        i, j = frontier.pop()
        steps = [(i + 1, j, i < nx - 1 and east[i, j]), (i - 1, j, i > 0 and east[i - 1, j]),
                 (i, j + 1, j < ny - 1 and north[i, j]), (i, j - 1, j > 0 and north[i, j - 1])]
        for a, b, open_ in steps:
            if open_ and (a, b) not in reached:
                reached.add((a, b))
                frontier.append((a, b))
    assert len(reached) == nx * ny


def test_maze_goal_is_on_the_top_level_and_levels_need_the_holes() -> None:
    world = build_world("maze:levels=3,seed=1")
    assert world.start[2] < 2.5 < 5.0 < world.goal[2]
    holeless = world.replace(blocks=np.vstack([world.blocks, [0, 0, 2.4, 12, 12, 2.6]]),
                             colors=None)
    assert not connected(holeless.inflate(DEFAULT_MARGIN), world.start, world.goal)


def test_plate_with_hole_covers_the_plate_minus_the_hole() -> None:
    plate = np.array([0.0, 1.0, 0.0, 10.0, 1.3, 6.0])
    pieces = plate_with_hole(plate, [2.0, 0.0, 1.0, 3.5, 0.0, 2.2], normal=1)
    volumes = np.prod(pieces[:, 3:] - pieces[:, :3], axis=1)
    assert len(pieces) == 4
    assert np.isclose(volumes.sum(), 0.3 * (60 - 1.5 * 1.2))
    overlap = np.minimum(pieces[:, None, 3:], pieces[None, :, 3:]) - np.maximum(
        pieces[:, None, :3], pieces[None, :, :3])
    assert not np.any(np.all(overlap > 0, axis=2) & ~np.eye(4, dtype=bool))  # no overlaps
    world = World(boundary=[-1, -1, -1, 11, 11, 11], blocks=pieces)
    assert world.segment_free([2.75, 0.0, 1.6], [2.75, 2.0, 1.6])  # through the hole
    assert not world.segment_free([5.0, 0.0, 1.6], [5.0, 2.0, 1.6])


# -------------------------------------------------------------------- spec parsing
@pytest.mark.parametrize(
    ("spec", "message"),
    [
        ("jungle", "unknown built-in world 'jungle' (known: empty, forest, window, maze)"),
        ("forest:dens=0.1", "unknown parameter 'dens' (valid: size, density, trunk_min"),
        ("forest:density", "expected key=value, got 'density'"),
        ("forest:", "empty parameter: expected key=value"),
        ("forest:seed=1,,density=0.1", "empty parameter"),
        ("forest:seed=1,seed=2", "parameter 'seed' given twice"),
        ("forest:density=lots", "density: expected a number, got 'lots'"),
        ("forest:density=nan", "density: expected a number"),
        ("forest:density=0", "density: expected above 0, at most 10 per m^2, got 0"),
        ("forest:density=-0.1", "density: expected above 0"),
        ("forest:density=11", "density: expected above 0, at most 10 per m^2, got 11"),
        ("forest:gap=1e308", "gap: expected from 0 to 100 m, got 1e308"),
        ("forest:branches=1e9", "branches: expected from 0 to 5, got 1e9"),
        ("forest:trunk_max=101", "trunk_max: expected from 0.2 to 100 m"),
        ("forest:density=2", "density 2 is too high for trunks 0.3-0.6 m wide"),
        ("forest:size=4x4x2,density=0.28", "placed only 3 of 4 trunks"),
        ("forest:size=2000x2000x10,density=0.05", "too many"),
        ("forest:size=10x10x3,density=1,gap=0,trunk_min=0.6", "no layout in 20 attempts"),
        ("forest:trunk_min=0.7", "trunk_min (0.7) must be <= trunk_max (0.6)"),
        ("forest:size=20x20", "size: expected WxDxH (3 numbers joined by 'x'), got '20x20'"),
        ("forest:size=0x20x6", "size: expected every part from 2 to 10,000 m, got 0x20x6"),
        ("forest:size=20x20x1e5", "size: expected every part from 2 to 10,000 m"),
        ("forest:seed=1.5", "seed: expected an integer, got '1.5'"),
        ("forest:seed=-1", "seed: expected a whole number from 0 to 9,223,372,036,854,775,807"),
        ("forest:seed=" + "9" * 5000, "seed: expected an integer"),
        ("empty:size=10x10x-4", "size: expected every part from 1 to 10,000 m"),
        ("empty:seed=1", "unknown parameter 'seed' (valid: size)"),
        ("window:walls=0", "walls: expected a whole number from 1 to 100, got 0"),
        ("window:size=10x6x6", "a depth of 6 m is too small for 3 walls (need at least 8.5 m)"),
        ("maze:cells=6", "cells: expected NxM (2 integers joined by 'x'), got '6'"),
        ("maze:cells=2.5x3", "cells: expected NxM"),
        ("maze:cells=300x3", "cells: expected every part a whole number from 1 to 200"),
        ("maze:cells=1x1,levels=1", "no room for start and goal"),
        ("maze:cell_size=0.5", "cell_size: expected from 1 to 50 m"),
        ("maze:level_height=1e20", "level_height: expected from 1 to 500 m, got 1e20"),
    ],
)
def test_bad_specs_raise_one_line_map_errors(spec: str, message: str) -> None:
    with pytest.raises(MapError) as caught:
        build_world(spec)
    assert caught.value.source == spec
    assert message in caught.value.reason
    assert "\n" not in str(caught.value)


def test_is_builtin_spec() -> None:
    assert is_builtin_spec("forest")
    assert is_builtin_spec("maze:cells=3x3")
    assert is_builtin_spec("window:nonsense")  # names a world; the parameters come later
    assert not is_builtin_spec("forest.txt")
    assert not is_builtin_spec("maps/forest")
    assert not is_builtin_spec("jungle:size=1x1x1")
    assert not is_builtin_spec("")


def test_describe_worlds_lists_parameters_whose_defaults_build() -> None:
    infos = describe_worlds()
    assert [info.name for info in infos] == world_names()
    forest = next(info for info in infos if info.name == "forest")
    size = forest.params[0]
    assert (size.name, size.type, size.default) == ("size", "WxDxH", "20x20x6")
    assert "metres" in size.help
    for info in infos:
        assert info.summary and all(p.help for p in info.params)
        spec = f"{info.name}:" + ",".join(f"{p.name}={p.default}" for p in info.params)
        assert build_world(spec).name == spec


def test_default_world_spec_is_a_builtin_world() -> None:
    assert DEFAULT_WORLD_SPEC == "forest"
    assert is_builtin_spec(DEFAULT_WORLD_SPEC)
    assert builtin.DEFAULT_MARGIN == 0.2


# ---------------------------------------------------------------------- connected
BOX = [0.0, 0.0, 0.0, 10.0, 10.0, 4.0]
START, GOAL = [5.0, 1.0, 2.0], [5.0, 9.0, 2.0]


def test_connected_in_an_open_box() -> None:
    assert connected(World(boundary=BOX), START, GOAL)


def test_not_connected_across_a_wall_that_splits_the_box() -> None:
    wall = [0.0, 4.9, 0.0, 10.0, 5.1, 4.0]
    assert not connected(World(boundary=BOX, blocks=[wall]), START, GOAL)


def test_a_slit_is_found_only_when_the_voxels_are_fine_enough() -> None:
    # A wall across y with a 0.3 m slit through it at x in [5, 5.3].
    wall = [[0.0, 4.9, 0.0, 5.0, 5.1, 4.0], [5.3, 4.9, 0.0, 10.0, 5.1, 4.0]]
    world = World(boundary=BOX, blocks=wall)
    assert connected(world, START, GOAL, resolution=0.1)
    assert not connected(world, START, GOAL, resolution=0.5)  # conservative, never wrong
    # Inflating by 0.2 m closes the slit altogether.
    assert not connected(world.inflate(0.2), START, GOAL, resolution=0.05)


def test_connected_is_false_for_a_point_that_is_not_free() -> None:
    block = [4.0, 0.0, 1.0, 6.0, 2.0, 3.0]  # around START
    world = World(boundary=BOX, blocks=[block])
    assert not connected(world, START, GOAL)
    assert not connected(World(boundary=BOX), [5.0, 10.0, 2.0], GOAL)  # on the boundary


def test_connected_rejects_a_bad_resolution() -> None:
    with pytest.raises(ValueError, match="resolution"):
        connected(World(boundary=BOX), START, GOAL, resolution=0.0)


def test_default_resolution_keeps_the_grid_within_budget() -> None:
    for extent in ([20, 20, 6], [100, 100, 20], [1000, 1000, 0.01], [0.1, 0.1, 0.1]):
        edge = default_resolution(extent, max_voxels=4_000_000)
        cells = np.prod(np.ceil(np.asarray(extent) / edge - 1e-9))
        assert 3_500_000 < cells <= 4_000_000


# ------------------------------------------------------------------------ property
@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    width=st.floats(8.0, 40.0),
    depth=st.floats(8.0, 40.0),
    height=st.floats(2.0, 10.0),
    density=st.floats(0.01, 0.15),
    seed=st.integers(0, 2**32),
)
def test_random_forests_are_flyable(
    width: float, depth: float, height: float, density: float, seed: int
) -> None:
    spec = f"forest:size={width:.3f}x{depth:.3f}x{height:.3f},density={density:.4f},seed={seed}"
    world = build_world(spec)
    assert_flyable(world)
    assert np.all(world.blocks[:, 3:] <= world.upper)

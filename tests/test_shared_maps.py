"""Every real map in ../shared/maps parses with the right block count and numbers."""

from __future__ import annotations

import numpy as np
import pytest

from quadnav.world import read_map, read_start_goal
from quadnav.world.model import DEFAULT_BLOCK_COLOR

# Block counts from ../shared/maps/README.md.
BLOCK_COUNTS = {
    "rbe595/map1.txt": 8,
    "rbe595/map4.txt": 2,
    "rbe595/p2b_map1.txt": 3,
    "meam620/test_window.json": 8,
    "meam620/test_empty.json": 0,
    "meam620/test_impossible.json": 1,
    "meam620/grid_forest.json": 12,
    "meam620/map_2017_boundary9fields.txt": 7,
    "meam620/map_2017_nocolor_blocks.txt": 13,
    "meam620/single_cube.txt": 1,
    "rotorpy/pillar.json": 1,
    "rotorpy/double_pillar.json": 2,
}
START_GOAL_FILES = {"rbe595/p2b_startandgoal_map1.txt"}


def test_every_map_file_is_known_and_parses(shared_maps):
    # The corpus' own README.md and SOURCES.json (the provenance) sit at its top; maps are
    # in a folder per course.
    files = {str(p.relative_to(shared_maps)) for p in shared_maps.rglob("*/*") if p.is_file()}
    assert files - START_GOAL_FILES == set(BLOCK_COUNTS), "a map in the corpus is not listed"
    for name, count in BLOCK_COUNTS.items():
        world = read_map(shared_maps / name)
        assert len(world) == count, name
        assert world.name.endswith(name)


@pytest.mark.parametrize(("name", "bounds"), [
    ("rbe595/map1.txt", [0, -5, 0, 10, 20, 6]),
    ("rbe595/map4.txt", [0, 0, 0, 45, 35, 6]),
    ("rbe595/p2b_map1.txt", [-1.73, -1.15, 0, 1.73, 7.4, 2]),
    ("meam620/map_2017_boundary9fields.txt", [0, 0, 0, 20, 5, 6]),
    ("meam620/map_2017_nocolor_blocks.txt", [0, 0, 0, 20, 20, 1]),
    ("meam620/single_cube.txt", [-5, -5, -5, 10, 10, 10]),
    ("meam620/test_window.json", [0, -5, 0, 10, 20, 6]),
    ("rotorpy/double_pillar.json", [-3.5, -5, -0.5, 3.5, 5, 3]),
])
def test_bounds(shared_maps, name, bounds):
    np.testing.assert_array_equal(read_map(shared_maps / name).boundary, bounds)


def test_text_and_json_copies_of_the_window_map_agree(shared_maps):
    text = read_map(shared_maps / "rbe595/map1.txt")
    json_ = read_map(shared_maps / "meam620/test_window.json")
    np.testing.assert_array_equal(text.boundary, json_.boundary)
    np.testing.assert_array_equal(text.blocks, json_.blocks)
    np.testing.assert_array_equal(text.colors, np.tile([1.0, 0, 0], (8, 1)))


def test_json_keeps_start_goal_and_margin(shared_maps):
    world = read_map(shared_maps / "meam620/test_window.json")
    np.testing.assert_array_equal(world.start, [0.1, -4.9, 0.2])
    np.testing.assert_array_equal(world.goal, [8.0, 18.0, 3.0])
    assert world.margin == 0.3
    impossible = read_map(shared_maps / "meam620/test_impossible.json")
    np.testing.assert_array_equal(impossible.blocks, [[0, 2.4, 0, 2, 2.6, 1]])


def test_quirky_files(shared_maps):
    nine = read_map(shared_maps / "meam620/map_2017_boundary9fields.txt")
    np.testing.assert_array_equal(nine.blocks[0], [3.1, 0, 2.1, 3.9, 5, 6])
    np.testing.assert_array_equal(nine.colors[3], [0, 0, 1])
    nocolor = read_map(shared_maps / "meam620/map_2017_nocolor_blocks.txt")
    np.testing.assert_array_equal(nocolor.colors, np.tile(DEFAULT_BLOCK_COLOR, (13, 1)))
    np.testing.assert_array_equal(nocolor.blocks[4], [13.75, 4.5, 0, 14.5, 5.5, 1])
    grid = read_map(shared_maps / "meam620/grid_forest.json")
    assert grid.start is None and grid.margin is None


def test_start_goal_file(shared_maps):
    start, goal = read_start_goal(shared_maps / "rbe595/p2b_startandgoal_map1.txt")
    np.testing.assert_array_equal(start, [0, 0, 0])
    np.testing.assert_array_equal(goal, [-0.59, 6.81, 0])


def test_free_volume_of_the_window_map(shared_maps):
    # Eight disjoint blocks of 118.2 m^3 in a 10 x 25 x 6 m box.
    world = read_map(shared_maps / "rbe595/map1.txt")
    assert world.free_volume_fraction() == pytest.approx(1 - 118.2 / 1500, abs=1e-12)


def test_free_volume_matches_a_voxel_count(shared_maps):
    # Every coordinate of this map is a multiple of 0.25 m, so a 0.25 m voxel count is exact.
    world = read_map(shared_maps / "meam620/map_2017_nocolor_blocks.txt")
    step = 0.25
    centres = np.mgrid[0:20:step, 0:20:step, 0:1:step].reshape(3, -1).T + step / 2
    covered = np.zeros(len(centres), dtype=bool)
    for box in world.blocks:
        covered |= np.all((box[:3] <= centres) & (centres <= box[3:]), axis=1)
    assert world.free_volume_fraction() == pytest.approx(1 - covered.mean(), abs=1e-12)

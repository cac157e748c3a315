"""The public course maps that have a path, and the start and goal each is flown with."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from quadnav.world import World, load_world, read_start_goal

MAPS = [
    "meam620/grid_forest.json", "meam620/map_2017_boundary9fields.txt",
    "meam620/map_2017_nocolor_blocks.txt", "meam620/single_cube.txt", "meam620/test_empty.json",
    "meam620/test_window.json", "rbe595/map1.txt", "rbe595/map4.txt", "rbe595/p2b_map1.txt",
    "rotorpy/double_pillar.json", "rotorpy/pillar.json",
]
#: Start and goal files that go with a map.
START_GOAL_FILES = {"rbe595/p2b_map1.txt": "rbe595/p2b_startandgoal_map1.txt"}
#: Starts and goals the courses use with a map that does not carry them (maps/README.md).
START_GOAL_POINTS = {"rbe595/map1.txt": ((0.1, -4.9, 0.2), (8.0, 18.0, 3.0)),
                     "rbe595/map4.txt": ((5.0, 16.0, 3.0), (24.0, 16.0, 3.0))}


def far_apart_free_points(free_world: World) -> tuple[np.ndarray, np.ndarray]:
    """A deterministic start and goal: the two most distant of 300 seeded free samples."""
    points = free_world.sample_free(300, seed=0)
    distances = np.linalg.norm(points[:, None] - points[None], axis=2)
    i, j = np.unravel_index(np.argmax(distances), distances.shape)
    return points[i], points[j]


def course_query(folder: Path, name: str) -> tuple[World, np.ndarray, np.ndarray, float]:
    """The map ``name`` under ``folder`` with its start, goal and margin: the map's own,
    else the course's (files or points), else two far-apart free points."""
    world = load_world(folder / name)
    margin = world.margin if world.margin is not None else 0.2
    start, goal = world.start, world.goal
    if name in START_GOAL_FILES:
        start, goal = read_start_goal(folder / START_GOAL_FILES[name])
    if name in START_GOAL_POINTS:
        start, goal = (np.array(p) for p in START_GOAL_POINTS[name])
    if start is None:
        start, goal = far_apart_free_points(world.inflate(margin))
    return world, start, goal, margin

"""``window``: walls across the y axis, each with one rectangular window to fly through."""

from __future__ import annotations

from typing import Any

import numpy as np

from quadnav.limits import Range
from quadnav.specs import INT, SEED_PARAM, SIZE, Param, SpecError
from quadnav.world.builtin.base import (
    Generator,
    Layout,
    corner_start_goal,
    plate_with_hole,
    shaded,
    sizes,
)

WALL_COLOR = (0.75, 0.68, 0.55)
#: Range of a wall's thickness (along y) and of a window's width and height, metres.
WALL_THICKNESS = (0.2, 0.4)
WINDOW_SIDE = (1.0, 1.6)
#: Least wall left around a window, metres.
FRAME = 0.2
#: Depth, metres, kept free of walls at each end (start side and goal side).
END = 2.0
#: Least depth of map, metres, per wall.
SLOT = 1.5


def _layout(values: dict[str, Any], rng: np.random.Generator) -> Layout:
    """``walls`` walls spread evenly along y between the start and goal ends.

    Each wall spans the map's full width and height and is 4 blocks around its window.
    """
    size = values["size"]
    width, depth, height = size
    count = values["walls"]
    needed = 2 * END + count * SLOT
    if depth < needed:
        raise SpecError(f"size: a depth of {depth:g} m is too small for {count} walls "
                        f"(need at least {needed:g} m)")
    slot = (depth - 2 * END) / count
    jitter = rng.uniform(-0.25, 0.25, count) * (slot - SLOT)
    middles = END + slot * (np.arange(count) + 0.5) + jitter
    thickness = rng.uniform(*WALL_THICKNESS, count)
    sides = rng.uniform(*WINDOW_SIDE, (count, 2))  # window width (x) and height (z)
    corners = rng.uniform(FRAME, np.array([width, height]) - FRAME - sides)
    walls = []
    for y, t, (w, h), (x, z) in zip(middles, thickness, sides, corners, strict=True):
        wall = [0.0, y - t / 2, 0.0, width, y + t / 2, height]
        walls.append(plate_with_hole(wall, [x, 0.0, z, x + w, 0.0, z + h], normal=1))
    colors = np.repeat(shaded(rng, WALL_COLOR, count), [len(w) for w in walls], axis=0)
    start, goal = corner_start_goal(size)
    return Layout(size, np.concatenate(walls), colors, start, goal)


GENERATOR = Generator(
    name="window",
    summary="walls across the y axis, each with one window; start before, goal after",
    params=(
        Param("size", SIZE, (10.0, 20.0, 6.0), "WxDxH of the map, metres",
              sizes(WINDOW_SIDE[1] + 2 * FRAME)),
        Param("walls", INT, 3, "number of walls", Range(1, 100, whole=True)),
        SEED_PARAM,
    ),
    layout=_layout,
)

"""``empty``: a boundary box with no obstacles."""

from __future__ import annotations

from typing import Any

import numpy as np

from quadnav.specs import SIZE, Param
from quadnav.world.builtin.base import Generator, Layout, corner_start_goal, sizes


def _layout(values: dict[str, Any], rng: np.random.Generator) -> Layout:
    """No blocks; start and goal near opposite corners (``rng`` is unused)."""
    start, goal = corner_start_goal(values["size"])
    return Layout(values["size"], np.zeros((0, 6)), np.zeros((0, 3)), start, goal)


GENERATOR = Generator(
    name="empty",
    summary="an empty box, start and goal near opposite corners",
    params=(Param("size", SIZE, (10.0, 10.0, 4.0), "WxDxH of the map, metres", sizes(1.0)),),
    layout=_layout,
)

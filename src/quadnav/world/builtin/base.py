"""What a world generator is, and geometry helpers that several generators share.

A generator turns parameter values and a random generator into a :class:`Layout`; the
registry (:mod:`quadnav.world.builtin`) makes the World, checks that it is flyable and
retries with a fresh random generator if it is not.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from quadnav.arrays import FloatArray
from quadnav.limits import COORDINATE, Range
from quadnav.specs import Param


@dataclass(frozen=True)
class Layout:
    """The obstacles of a generated world, whose boundary is ``[0, size]``.

    Attributes:
        size: (3,) width (x), depth (y) and height (z) of the boundary box, metres.
        blocks: (N, 6) boxes ``xmin, ymin, zmin, xmax, ymax, zmax``, metres.
        colors: (N, 3) RGB in [0, 1].
        start: (3,) start point, metres.
        goal: (3,) goal point, metres.
    """

    size: tuple[float, float, float]
    blocks: FloatArray
    colors: FloatArray
    start: FloatArray
    goal: FloatArray


@dataclass(frozen=True)
class Generator:
    """A built-in world.

    Attributes:
        name: the world's name, the part of a spec before ``:``.
        summary: one line saying what the world looks like.
        params: its parameters, in the order the canonical spec lists them.
        layout: ``layout(values, rng) -> Layout``; may raise
            :class:`~quadnav.specs.SpecError` for values it cannot build.
    """

    name: str
    summary: str
    params: tuple[Param, ...]
    layout: Callable[[dict[str, Any], np.random.Generator], Layout]


def sizes(least: float) -> Range:
    """The range of a map's side: ``least`` to the coordinate range's 10 km, metres."""
    return Range(least, COORDINATE.high, "m")


def corner_start_goal(size: Sequence[float]) -> tuple[FloatArray, FloatArray]:
    """Start near the ``(0, 0)`` corner and goal near the opposite one, each (3,) metres.

    Both are 1 m in from the walls (less in a map under 4 m wide); the start is 1 m up
    (or at mid height if lower), the goal at mid height.
    """
    width, depth, height = size
    inset = np.minimum([width, depth], 4.0) / 4
    start = np.array([inset[0], inset[1], min(1.0, height / 2)])
    goal = np.array([width - inset[0], depth - inset[1], height / 2])
    return start, goal


def plate_with_hole(plate: ArrayLike, hole: ArrayLike, normal: int) -> FloatArray:
    """The box ``plate`` (6,) minus a hole through it -> up to 4 boxes (k, 6).

    ``hole`` (6,) is a box inside ``plate`` on the two axes other than ``normal``; its
    extent along ``normal`` is ignored (the hole goes right through). The pieces are the
    two strips beside the hole (full length along the second in-plane axis) and the two
    strips above and below it; empty pieces are left out.
    """
    plate = np.asarray(plate, dtype=np.float64)
    hole = np.asarray(hole, dtype=np.float64)
    u, v = (axis for axis in range(3) if axis != normal)
    pieces = []
    for axis, cut_low in ((u, True), (u, False), (v, True), (v, False)):
        piece = plate.copy()
        if axis == v:  # the strips above and below span only the hole's width along u
            piece[[u, u + 3]] = hole[[u, u + 3]]
        if cut_low:
            piece[axis + 3] = hole[axis]
        else:
            piece[axis] = hole[axis + 3]
        pieces.append(piece)
    boxes = np.array(pieces)
    return boxes[np.all(boxes[:, :3] < boxes[:, 3:], axis=1)]


def shaded(rng: np.random.Generator, color: Sequence[float], count: int,
           spread: float = 0.1) -> FloatArray:
    """(count, 3) copies of an RGB ``color`` whose brightness varies by +-``spread``."""
    scale = rng.uniform(1 - spread, 1 + spread, size=(count, 1))
    return np.clip(np.asarray(color) * scale, 0.0, 1.0)

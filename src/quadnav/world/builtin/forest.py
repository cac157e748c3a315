"""``forest``: full-height square trunks with thin horizontal branches.

Trunks are placed by dart throwing: a candidate is kept when it leaves at least ``gap``
metres of clear floor between itself and every kept trunk along x or y (so an
axis-aligned corridor at least ``gap`` wide separates any two trunks), and when it stays
out of the clear squares around the start and goal. Each trunk gets a Poisson number of
branches at random heights, each pointing along +-x or +-y.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from quadnav.arrays import FloatArray
from quadnav.limits import Range
from quadnav.specs import FLOAT, SEED_PARAM, SIZE, Param, SpecError
from quadnav.world.builtin.base import Generator, Layout, corner_start_goal, shaded, sizes

TRUNK_COLOR = (0.45, 0.3, 0.15)
BRANCH_COLOR = (0.3, 0.55, 0.2)
#: Half-width, metres, of the full-height squares around start and goal kept clear.
CLEAR = 1.0
#: Range of a branch's length beyond the trunk face and of its thickness, metres.
BRANCH_LENGTH = (0.5, 1.5)
BRANCH_THICKNESS = (0.1, 0.15)
#: Lowest branch bottom and least gap between a branch top and the ceiling, metres.
BRANCH_CLEARANCE = 0.5
#: Shortest stub, metres, left of a branch cut by the boundary (shorter ones are dropped).
MIN_STUB = 0.1
#: Largest fraction of the floor that the trunks' exclusion squares may cover (random
#: sequential packing of squares jams near 0.56).
MAX_COVERAGE = 0.45
MAX_TRUNKS = 100_000
#: Candidates thrown per trunk asked for before giving up.
TRIES_PER_TRUNK = 50


def _layout(values: dict[str, Any], rng: np.random.Generator) -> Layout:
    """Blocks: the trunks (brown) first, then the branches (green); start and goal at
    opposite corners."""
    if values["trunk_min"] > values["trunk_max"]:
        raise SpecError(f"trunk_min ({values['trunk_min']:g}) must be <= trunk_max "
                        f"({values['trunk_max']:g})")
    size = values["size"]
    start, goal = corner_start_goal(size)
    clear = np.array([[*(p[:2] - CLEAR), *(p[:2] + CLEAR)] for p in (start, goal)])
    trunks = _trunks(rng, values, clear)
    branches = _branches(rng, trunks, values["branches"], np.asarray(size), clear)
    blocks = np.concatenate([trunks, branches])
    colors = np.concatenate([shaded(rng, TRUNK_COLOR, len(trunks)),
                             shaded(rng, BRANCH_COLOR, len(branches))])
    return Layout(size, blocks, colors, start, goal)


def _overlapping(footprints: FloatArray, areas: FloatArray) -> np.ndarray:
    """Whether each closed rectangle (n, 4) ``xmin, ymin, xmax, ymax`` touches any of
    ``areas`` (k, 4) -> bool (n,)."""
    a, b = footprints[:, None, :], areas[None, :, :]
    touching = (a[..., :2] <= b[..., 2:]) & (b[..., :2] <= a[..., 2:])
    return np.any(np.all(touching, axis=2), axis=1)


def _trunks(rng: np.random.Generator, values: dict[str, Any], clear: FloatArray) -> FloatArray:
    """(n, 6) full-height trunk boxes, n = round(density x floor area); SpecError if the
    density is too high to place them."""
    width, depth, height = values["size"]
    density, gap = values["density"], values["gap"]
    low, high = values["trunk_min"], values["trunk_max"]
    if high >= min(width, depth) / 2:
        raise SpecError(f"trunk_max ({high:g} m) must be under half the map's width and depth")
    count = round(density * width * depth)
    if count > MAX_TRUNKS:
        raise SpecError(f"{count} trunks is too many (at most {MAX_TRUNKS}): lower density or size")
    limit = MAX_COVERAGE / ((low + high) / 2 + gap) ** 2
    if density > limit:
        raise SpecError(f"density {density:g} is too high for trunks {low:g}-{high:g} m wide "
                        f"with {gap:g} m gaps: at most {limit:.3g} trunks per square metre")
    cell = high + gap  # a trunk too close to another is less than this away along x and y
    grid: dict[tuple[int, int], list[int]] = {}
    kept: list[tuple[float, float, float]] = []  # centre x, y and width of each trunk
    for _ in range(TRIES_PER_TRUNK):
        if len(kept) == count:
            break
        widths = rng.uniform(low, high, count)
        half = widths[:, None] / 2
        centres = rng.uniform(half, np.array([width, depth]) - half)
        free = ~_overlapping(np.hstack([centres - half, centres + half]), clear)
        for (x, y), w in zip(centres[free], widths[free], strict=True):
            key = (int(x // cell), int(y // cell))
            neighbours = (kept[j] for i in (-1, 0, 1) for k in (-1, 0, 1)
                          for j in grid.get((key[0] + i, key[1] + k), ()))
            if all(max(abs(x - nx), abs(y - ny)) >= (w + nw) / 2 + gap
                   for nx, ny, nw in neighbours):
                grid.setdefault(key, []).append(len(kept))
                kept.append((x, y, w))
                if len(kept) == count:
                    break
    if len(kept) < count:
        raise SpecError(f"density {density:g} is too high: placed only {len(kept)} of {count} "
                        f"trunks with {gap:g} m gaps")
    x, y, w = np.array(kept, dtype=np.float64).reshape(-1, 3).T
    return np.column_stack([x - w / 2, y - w / 2, np.zeros_like(x),
                            x + w / 2, y + w / 2, np.full_like(x, height)])


def _branches(rng: np.random.Generator, trunks: FloatArray, mean: float, size: FloatArray,
              clear: FloatArray) -> FloatArray:
    """(m, 6) branch boxes, a Poisson(``mean``) number per trunk (n, 6).

    A branch runs from its trunk's axis out along +-x or +-y to 0.5-1.5 m beyond the trunk
    face, is cut at the boundary ``[0, size]`` (size (3,) metres), and is dropped if it
    touches a ``clear`` (k, 4) area or keeps less than :data:`MIN_STUB` outside its trunk.
    """
    parents = trunks[np.repeat(np.arange(len(trunks)), rng.poisson(mean, len(trunks)))]
    n = len(parents)
    rows = np.arange(n)
    along = rng.integers(0, 2, n)  # 0: the branch points along x, 1: along y
    across = 1 - along
    centre = (parents[:, :2] + parents[:, 3:5]) / 2
    half = (parents[:, 3] - parents[:, 0]) / 2
    tip = centre[rows, along] + rng.choice([-1.0, 1.0], n) * (half + rng.uniform(*BRANCH_LENGTH, n))
    thickness = rng.uniform(*BRANCH_THICKNESS, n)
    middle = centre[rows, across] + rng.uniform(-1, 1, n) * (half - thickness / 2)
    bottom = rng.uniform(BRANCH_CLEARANCE, size[2] - BRANCH_CLEARANCE - thickness, n)
    boxes = np.empty((n, 6))
    boxes[rows, along] = np.minimum(centre[rows, along], tip)
    boxes[rows, along + 3] = np.maximum(centre[rows, along], tip)
    boxes[rows, across] = middle - thickness / 2
    boxes[rows, across + 3] = middle + thickness / 2
    boxes[:, 2], boxes[:, 5] = bottom, bottom + thickness
    boxes[:, :3] = np.maximum(boxes[:, :3], 0.0)
    boxes[:, 3:] = np.minimum(boxes[:, 3:], size)
    outside = boxes[rows, along + 3] - boxes[rows, along] - half
    keep = (outside >= MIN_STUB) & ~_overlapping(boxes[:, [0, 1, 3, 4]], clear)
    return boxes[keep]


GENERATOR = Generator(
    name="forest",
    summary="full-height tree trunks with thin branches; start and goal at opposite corners",
    params=(
        Param("size", SIZE, (20.0, 20.0, 6.0), "WxDxH of the map, metres", sizes(2.0)),
        Param("density", FLOAT, 0.1, "trunks per square metre of floor",
              Range(0.0, 10.0, "per m^2", above_low=True)),
        Param("trunk_min", FLOAT, 0.3, "width of the thinnest trunk, metres",
              Range(0.2, 100.0, "m")),
        Param("trunk_max", FLOAT, 0.6, "width of the thickest trunk, metres",
              Range(0.2, 100.0, "m")),
        Param("gap", FLOAT, 0.8, "least clear gap between two trunks, metres",
              Range(0.0, 100.0, "m")),
        Param("branches", FLOAT, 2.0, "mean number of branches per trunk", Range(0.0, 5.0)),
        SEED_PARAM,
    ),
    layout=_layout,
)

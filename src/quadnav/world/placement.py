"""Where a start or goal point lies: free, inside the safety margin, in a block, outside.

Course maps put starts on the boundary (RBE595: ``x = xmin``) or inside the margin
(MEAM620 ``test_window``). Such points are usable — planners leave the margin by the
shortest free way — while a point in a real block or outside the boundary is not.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

import numpy as np
from numpy.typing import ArrayLike

from quadnav.errors import QuadnavError
from quadnav.world.model import World


class Placement(Enum):
    """Where a point lies relative to a world and its safety margin."""

    FREE = "free"
    IN_MARGIN = "in the margin"
    IN_BLOCK = "in a block"
    OUTSIDE = "outside the boundary"

    @property
    def usable(self) -> bool:
        """Whether a planner can start or end at such a point."""
        return self in (Placement.FREE, Placement.IN_MARGIN)


@dataclass(frozen=True)
class PointReport:
    """The placement of one named point, with a sentence for the user."""

    label: str
    point: np.ndarray
    placement: Placement
    detail: str

    @property
    def usable(self) -> bool:
        """Whether a planner can start or end here (free, or only inside the margin)."""
        return self.placement.usable

    def __str__(self) -> str:
        return f"{self.label} {format_point(self.point)}: {self.detail}"


def format_point(point: ArrayLike, spec: str = ".4g") -> str:
    """``(x, y, z)``, each coordinate in the format ``spec`` (by default 4 significant
    digits), for messages."""
    return "(" + ", ".join(f"{v:{spec}}" for v in np.asarray(point, dtype=float)) + ")"


def format_estimate(point: ArrayLike, sigma: float) -> str:
    """``(x, y, z) +- s m``: a point and its 1-sigma uncertainty (m), for messages."""
    return f"{format_point(point)} +- {sigma:.2f} m"


def format_box(box: ArrayLike) -> str:
    """``[xmin, xmax] x [ymin, ymax] x [zmin, zmax]`` for messages."""
    b = np.asarray(box, dtype=float)
    return " x ".join(f"[{b[a]:g}, {b[a + 3]:g}]" for a in range(3))


def _block_names(rows: np.ndarray, world: World) -> str:
    return ", ".join(f"block {i} {format_box(world.blocks[i])}" for i in rows)


def classify_point(world: World, point: ArrayLike, margin: float, label: str = "point"
                   ) -> PointReport:
    """Where ``point`` (3,) lies in ``world`` (not inflated) with a ``margin`` in metres."""
    p = np.asarray(point, dtype=np.float64)
    if p.shape != (3,) or not np.all(np.isfinite(p)):
        raise QuadnavError(f"{label}: expected 3 finite numbers x y z, got {point!r}")
    if not world.in_boundary(p):
        return PointReport(label, p, Placement.OUTSIDE,
                           f"outside the boundary {format_box(world.boundary)}")
    inside = world.blocks_containing(p)
    if inside.size:
        return PointReport(label, p, Placement.IN_BLOCK, f"inside {_block_names(inside, world)}")
    inflated = world.inflate(margin)
    if inflated.is_free(p):
        return PointReport(label, p, Placement.FREE,
                           f"free, {world.clearance(p):.3g} m from the nearest obstacle")
    near = inflated.blocks_containing(p)
    reasons = []
    if np.any(p <= inflated.lower) or np.any(p >= inflated.upper):
        on = np.any(p == world.lower) or np.any(p == world.upper)
        reasons.append("on the boundary" if on else "near the boundary")
    if near.size:
        reasons.append("near " + _block_names(near, world))
    return PointReport(label, p, Placement.IN_MARGIN,
                       f"inside the {margin:g} m safety margin ({'; '.join(reasons)}); "
                       "usable: a planner leaves the margin by the shortest free way")

"""Planar worlds of rectangles for ground robots: :class:`World2D`, slices and 2D map files.

A :class:`World2D` is a boundary rectangle and rectangular obstacles, rows
``(xmin, ymin, xmax, ymax)`` in metres. Its queries are exact and follow the 3D
conventions of :mod:`quadnav.world`: free space is **open**, so a point on a rectangle's
edge or on the boundary is not free. They run on the 3D machinery: the world holds an
equivalent 3D :class:`~quadnav.world.World` whose blocks are the rectangles extruded
over a thin slab ``|z| <= SLAB``, and a 2D point is that world's point at ``z = 0``.

Worlds come from

* :func:`slice_world` — a horizontal cut of any 3D world at a chosen height;
* :func:`read_map2d` — a 2D map file (extension ``.map2d``) of text lines::

      # comment (whole line or trailing)
      boundary xmin ymin xmax ymax
      rect     xmin ymin xmax ymax

  in metres, exactly one ``boundary`` line anywhere, any number of ``rect`` lines,
  blank lines allowed. A rectangle may reach past the boundary: only its part inside
  matters;
* :func:`load_world2d` — a ``.map2d`` file, or anything :func:`quadnav.world.load_world`
  takes (3D map files, built-in world specs) sliced at a height.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from quadnav.arrays import FloatArray, read_only
from quadnav.errors import MapError, QuadnavError
from quadnav.world import World, load_world
from quadnav.world.reading import (
    check_coordinates,
    decode_text,
    keyword_lines,
    order_extents,
    parse_float,
    read_file,
)

#: Half thickness of the slab the equivalent 3D world spans, metres.
SLAB = 1.0
#: File extension of 2D map files.
MAP2D_SUFFIX = ".map2d"


def _frozen(values: ArrayLike, shape: tuple[int, int] | tuple[int], what: str) -> FloatArray:
    """A read-only float64 copy of rectangles with min below max in both axes."""
    array = np.array(values, dtype=np.float64).reshape(shape)
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{what} must be finite")
    if np.any(array[..., :2] >= array[..., 2:]):
        raise ValueError(f"{what}: every min must be below its max")
    return read_only(array)


@dataclass(frozen=True, eq=False)
class World2D:
    """A planar map of rectangular obstacles.

    Attributes:
        boundary: (4,) ``xmin, ymin, xmax, ymax`` of the drivable rectangle, metres.
        rects: (N, 4) obstacle rectangles in the same layout, metres.
        name: where the world came from, for messages.
    """

    boundary: FloatArray
    rects: FloatArray = field(default_factory=lambda: np.zeros((0, 4)))
    name: str = "<world2d>"

    def __post_init__(self) -> None:
        object.__setattr__(self, "boundary", _frozen(self.boundary, (4,), "boundary"))
        object.__setattr__(self, "rects", _frozen(self.rects, (-1, 4), "rects"))

    @property
    def lower(self) -> FloatArray:
        """(2,) lower corner of the boundary, metres."""
        return self.boundary[:2]

    @property
    def upper(self) -> FloatArray:
        """(2,) upper corner of the boundary, metres."""
        return self.boundary[2:]

    @property
    def extent(self) -> FloatArray:
        """(2,) size of the boundary, metres."""
        return self.upper - self.lower

    def __len__(self) -> int:
        return len(self.rects)

    @cached_property
    def world3d(self) -> World:
        """The equivalent 3D world: :meth:`lifted` over ``|z| <= SLAB``."""
        return self.lifted(SLAB)

    def lifted(self, slab: float) -> World:
        """This world in 3D: every rectangle, cut to the boundary (only the part inside
        matters), extruded over ``|z| <= slab`` metres, as is the boundary."""
        def lift(boxes: FloatArray) -> FloatArray:
            n = len(boxes)
            return np.column_stack([boxes[:, :2], np.full(n, -slab), boxes[:, 2:],
                                    np.full(n, slab)])
        rects = np.hstack([np.maximum(self.rects[:, :2], self.lower),
                           np.minimum(self.rects[:, 2:], self.upper)])
        rects = rects[np.all(rects[:, :2] < rects[:, 2:], axis=1)]
        return World(boundary=lift(self.boundary[None])[0], blocks=lift(rects),
                     name=self.name)

    def inflate(self, margin: float) -> World2D:
        """A new world whose rectangles grow and whose boundary shrinks by ``margin`` m.

        Growing by ``margin`` along both axes is the Minkowski sum with a square, which
        contains the one with a disc: every point within ``margin`` of an obstacle or of
        the boundary is outside the inflated world's free space.
        """
        if not (math.isfinite(margin) and margin >= 0):
            raise ValueError(f"margin must be a finite number >= 0, got {margin}")
        grow = np.array([-margin, -margin, margin, margin])
        boundary = self.boundary - grow
        if np.any(boundary[:2] >= boundary[2:]):
            raise QuadnavError(
                f"{self.name}: margin {margin:g} m leaves no free space in a boundary of size "
                f"{' x '.join(f'{e:g}' for e in self.extent)} m")
        return dataclasses.replace(self, boundary=boundary, rects=self.rects + grow)

    def points_free(self, points: ArrayLike) -> NDArray[np.bool_]:
        """Whether each point (N, 2) is in open free space -> bool (N,)."""
        return self.world3d.points_free(_lift(points, (-1, 2)))

    def is_free(self, point: ArrayLike) -> bool:
        """Whether one point (2,) is in open free space."""
        return bool(self.points_free(np.reshape(point, (1, 2)))[0])

    def segments_free(self, segments: ArrayLike) -> NDArray[np.bool_]:
        """Whether each closed segment (N, 2, 2) lies wholly in free space -> bool (N,)."""
        return self.world3d.segments_free(_lift(segments, (-1, 2, 2)))

    def in_boundary(self, point: ArrayLike) -> bool:
        """Whether the point (2,) lies in the closed boundary rectangle."""
        p = np.asarray(point, dtype=np.float64)
        return bool(np.all((self.lower <= p) & (p <= self.upper)))

    def rects_containing(self, point: ArrayLike) -> NDArray[np.int64]:
        """Rows of every closed rectangle that contains the point (2,)."""
        p = np.asarray(point, dtype=np.float64)
        inside = np.all((self.rects[:, :2] <= p) & (p <= self.rects[:, 2:]), axis=1)
        return np.flatnonzero(inside)


def _lift(values: ArrayLike, shape: tuple[int, ...]) -> FloatArray:
    """Points (..., 2) in the given shape, with z = 0 appended: (..., 3)."""
    array = np.asarray(values, dtype=np.float64)
    if array.ndim != len(shape) or any(s not in (-1, n) for s, n in
                                       zip(shape, array.shape, strict=True)):
        raise ValueError(f"expected shape {shape}, got {array.shape}")
    return np.concatenate([array, np.zeros((*array.shape[:-1], 1))], axis=-1)


def format_rect(rect: ArrayLike) -> str:
    """``[xmin, xmax] x [ymin, ymax]`` for messages."""
    r = np.asarray(rect, dtype=float)
    return f"[{r[0]:g}, {r[2]:g}] x [{r[1]:g}, {r[3]:g}]"


def slice_world(world: World, height: float) -> World2D:
    """The horizontal cut of ``world`` at ``height`` (m) as a :class:`World2D`.

    Keeps every block whose closed z-range contains ``height`` (a block whose top or
    bottom face lies in the plane counts: touching is a collision). ``height`` must lie
    strictly inside the boundary's z-range, where the open free space is; otherwise a
    QuadnavError.
    """
    zmin, zmax = world.boundary[2], world.boundary[5]
    if not (math.isfinite(height) and zmin < height < zmax):
        raise QuadnavError(f"{world.name}: slice height {height:g} m is outside the "
                           f"boundary's z-range ({zmin:g}, {zmax:g}) m")
    blocks = world.blocks
    kept = blocks[(blocks[:, 2] <= height) & (height <= blocks[:, 5])]
    return World2D(boundary=world.boundary[[0, 1, 3, 4]], rects=kept[:, [0, 1, 3, 4]],
                   name=f"{world.name} at z = {height:g} m")


def parse_map2d(text: str, source: str) -> World2D:
    """Parse the text of a 2D map file; raises MapError naming ``source`` and the line."""
    boundary: list[float] | None = None
    boundary_line = 0
    rects: list[list[float]] = []
    saw_content = False
    for number, keyword, values in keyword_lines(text, source, ("boundary", "rect")):
        saw_content = True
        if len(values) != 4:
            raise MapError(source, f"{keyword}: expected 4 numbers (xmin ymin xmax ymax), "
                           f"got {len(values)} fields", number)
        ordered = order_extents([parse_float(v, source, number, keyword) for v in values],
                                source, number, keyword, boundary=keyword == "boundary")
        if ordered is None:
            continue
        box = ordered[0] + ordered[1]
        if keyword == "rect":
            rects.append(box)
        elif boundary is not None:
            raise MapError(source, f"a second boundary line (the first is line "
                           f"{boundary_line}): expected exactly one", number)
        else:
            boundary = check_coordinates(box, source, number, keyword)
            boundary_line = number
    if not saw_content:
        raise MapError(source, "empty map: expected a 'boundary' line and 'rect' lines")
    if boundary is None:
        raise MapError(source, "no 'boundary xmin ymin xmax ymax' line")
    return World2D(boundary=boundary, rects=np.reshape(rects, (-1, 4)), name=source)


def read_map2d(path: str | Path) -> World2D:
    """A World2D from a 2D map file; MapError naming the file and line if bad."""
    return parse_map2d(decode_text(read_file(path), str(path)), str(path))


def load_world2d(source: str | Path | World, height: float | None = None) -> World2D:
    """A planar world from a MAP argument.

    Args:
        source: a path ending in ``.map2d`` (read as a 2D map; ``height`` is not used),
            or anything :func:`quadnav.world.load_world` takes: a 3D map file, a
            built-in world spec or a :class:`~quadnav.world.World`.
        height: where to slice a 3D world, metres; ``None``: half way up its boundary.
    """
    if not isinstance(source, World) and str(source).lower().endswith(MAP2D_SUFFIX):
        return read_map2d(source)
    world = load_world(source)
    if height is None:
        height = 0.5 * float(world.boundary[2] + world.boundary[5])
    return slice_world(world, height)

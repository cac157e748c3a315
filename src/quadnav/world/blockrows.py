"""The blocks of a map as a reader finds them, kept in flat arrays (8 bytes a number, 80 bytes
a block) rather than one Python object per block, and checked many at a time.

A million-block map read into lists of lists held about 2 KB a block; :class:`BlockRows`
holds what the :class:`~quadnav.world.World` keeps and the line of each block, for the
warnings of :func:`~quadnav.world.reading.assemble_world`.
"""

from __future__ import annotations

from array import array
from collections.abc import Callable, Sequence

import numpy as np

from quadnav.arrays import FloatArray
from quadnav.world.reading import order_extents

#: The line of a block read from a source that knows none (JSON read by the compiled decoder).
NO_LINE = 0


class BlockRows:
    """Blocks read so far: boxes ``xmin, ymin, zmin, xmax, ymax, zmax`` (metres), colours
    in 0..1 and the 1-based line of each (:data:`NO_LINE`: none), in the order read."""

    def __init__(self) -> None:
        self._boxes = array("d")
        self._colors = array("d")
        self._lines = array("q")

    def __len__(self) -> int:
        return len(self._lines)

    def add(self, box: Sequence[float], color: Sequence[float], line: int | None) -> None:
        """One block: ``box`` (6,) as mins then maxes, ``color`` (3,) in 0..1."""
        self._boxes.extend(box)
        self._colors.extend(color)
        self._lines.append(NO_LINE if line is None else line)

    def extend(self, boxes: FloatArray, colors: FloatArray, lines: np.ndarray) -> None:
        """Blocks ``boxes`` (k, 6) as mins then maxes, ``colors`` (k, 3) in 0..1, ``lines``
        (k,) int."""
        self._boxes.frombytes(_bytes_of(boxes, np.float64))
        self._colors.frombytes(_bytes_of(colors, np.float64))
        self._lines.frombytes(_bytes_of(lines, np.int64))

    def arrays(self) -> tuple[FloatArray, FloatArray, np.ndarray]:
        """``boxes`` (n, 6), ``colors`` (n, 3) and ``lines`` (n,) int64, viewing the rows'
        memory (no copy; add no more rows while they are in use)."""
        return (np.frombuffer(self._boxes, dtype=np.float64).reshape(-1, 6),
                np.frombuffer(self._colors, dtype=np.float64).reshape(-1, 3),
                np.frombuffer(self._lines, dtype=np.int64))


def _bytes_of(values: np.ndarray, dtype: type) -> memoryview:
    """The bytes of ``values`` as ``dtype`` in C order (no copy when they are so already)."""
    return memoryview(np.ascontiguousarray(values, dtype=dtype).reshape(-1)).cast("B")


def order_rows(boxes: FloatArray, colors: FloatArray, lines: np.ndarray, source: str,
               what: Callable[[int], str]) -> tuple[FloatArray, FloatArray, np.ndarray]:
    """Blocks ``boxes`` (k, 6) given as mins then maxes, ``colors`` (k, 3), ``lines`` (k,)
    (:data:`NO_LINE`: none), with every row whose min is not below its max on some axis
    put through :func:`~quadnav.world.reading.order_extents` (called for those rows alone,
    in order, with ``what(row)`` naming it): read as the box between, or dropped, with its
    warning. The arrays given are returned when no row is such."""
    odd = np.flatnonzero(np.any(boxes[:, :3] >= boxes[:, 3:], axis=1))
    if odd.size == 0:
        return boxes, colors, lines
    boxes = boxes.copy()
    keep = np.ones(len(boxes), dtype=bool)
    for row in odd.tolist():
        line = int(lines[row])
        ordered = order_extents(boxes[row].tolist(), source,
                                None if line == NO_LINE else line, what(row))
        if ordered is None:
            keep[row] = False
        else:
            boxes[row] = ordered[0] + ordered[1]
    return boxes[keep], colors[keep], lines[keep]

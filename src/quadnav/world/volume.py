"""The exact volume of a union of boxes (Klee's measure problem in 3D), compiled with numba.

:func:`union_volume` follows Chan's "Klee's measure problem made easy" (FOCS 2013): a
cell of space and the boxes that meet it, clipped to it, are

1. **simplified**: a box that covers the cell settles it (the cell's volume); a box
   that covers it along two axes but not the third is a *slab*. The union of the slabs
   along axis ``a`` is a union of intervals of ``a``; the slabs are counted (the cell's
   volume less that of the cell with those intervals cut out of it) and removed, and
   the cell and the other boxes are *compressed*: every ``a`` coordinate ``x`` becomes
   ``x`` minus the length of the slabs' intervals below it. The part of the cell outside
   every slab is a product of intervals, so the compression keeps its volume and that
   of every box within it. Repeat until no slab is left;
2. **cut** in two at the median of the box faces inside the cell along one axis, and
   each half measured the same way (an explicit stack, no recursion). Cells with at most
   :data:`FEW` boxes are measured by inclusion-exclusion instead.

After the simplification every box left has an edge inside the cell. Chan cuts along the
axes in turn and shows that each three cuts halve the edges per cell, so the work is
``T(n) = 8 T(n / 4) + O(n)``, that is ``O(n^1.5)`` box visits for ``n`` boxes whatever
their layout. Here the cut is along the axis with the most faces inside the cell, which
measured the same or better on every layout tried and much better on forests (full-height
trunks are then cut, not copied into both halves); ``bench/free_volume.py`` measures it on
random boxes, forests and contrived layouts such as long thin sticks along all three axes.
Answers are exact up to floating-point rounding.
"""

from __future__ import annotations

import numpy as np
from numba import njit

#: Cells with at most this many boxes are measured by inclusion-exclusion.
FEW = 5


@njit(cache=True)
def _few_volume(boxes) -> float:
    """Exact volume of the union of a few boxes (k, 6) by inclusion-exclusion over the
    ``2^k - 1`` non-empty subsets."""
    k = boxes.shape[0]
    total = 0.0
    for subset in range(1, 1 << k):
        volume, sign = 1.0, -1.0
        for a in range(3):
            low, high = -np.inf, np.inf
            for b in range(k):
                if subset >> b & 1:
                    low = max(low, boxes[b, a])
                    high = min(high, boxes[b, a + 3])
                    if a == 0:
                        sign = -sign
            volume *= max(0.0, high - low)
        total += sign * volume
    return total


@njit(cache=True)
def _cell_volume(cell) -> float:
    return (cell[3] - cell[0]) * (cell[4] - cell[1]) * (cell[5] - cell[2])


@njit(cache=True)
def _merged(starts, ends):
    """The union of intervals as sorted disjoint intervals (starts, ends), each (M,), and
    the length of the union below each one (prefix (M,))."""
    order = np.argsort(starts)
    merged_starts = np.empty(starts.size)
    merged_ends = np.empty(starts.size)
    count = 0
    for j in order:
        if count and starts[j] <= merged_ends[count - 1]:
            merged_ends[count - 1] = max(merged_ends[count - 1], ends[j])
        else:
            merged_starts[count] = starts[j]
            merged_ends[count] = ends[j]
            count += 1
    prefix = np.empty(count)
    covered = 0.0
    for j in range(count):
        prefix[j] = covered
        covered += merged_ends[j] - merged_starts[j]
    return merged_starts[:count], merged_ends[:count], prefix


@njit(cache=True)
def _compressed(x, starts, ends, prefix) -> float:
    """``x`` less the length of the intervals (starts, ends) below it; every ``x`` in an
    interval (its ends included) maps to the same value, rounding or not."""
    j = np.searchsorted(starts, x, side="right") - 1
    if j < 0:
        return x
    if x <= ends[j]:
        return starts[j] - prefix[j]
    return x - (prefix[j] + (ends[j] - starts[j]))


#: Outcomes of :func:`_simplify`.
_COVERED, _NO_SLAB, _SQUEEZED = 0, 1, 2
#: What :func:`_slab_axis` says of a box that covers the cell, and of one that is no slab.
_FULL, _NOT_SLAB = -2, -1


@njit(cache=True, inline="always")
def _slab_axis(boxes, b, cell) -> int:
    """The axis along which box ``b`` is a slab of the cell (covering it along the other
    two), :data:`_FULL` if it covers the cell, :data:`_NOT_SLAB` otherwise."""
    partial, axis = 0, _FULL
    for a in range(3):
        if boxes[b, a] > cell[a] or boxes[b, a + 3] < cell[a + 3]:
            partial += 1
            axis = a
    return axis if partial <= 1 else _NOT_SLAB


@njit(cache=True)
def _simplify(boxes, cell):
    """One round of step 1 of the module's algorithm on boxes (k, 6) in ``cell`` (6,).

    Returns ``(outcome, volume, boxes, cell)``: :data:`_COVERED` (a box covers the cell;
    ``volume`` is the cell's), :data:`_NO_SLAB` (nothing changed) or :data:`_SQUEEZED`
    (``volume`` of the slabs removed, the boxes left and the compressed cell, new arrays).
    """
    k = boxes.shape[0]
    slabs = 0
    for b in range(k):
        partial = _slab_axis(boxes, b, cell)
        if partial == _FULL:
            return _COVERED, _cell_volume(cell), boxes, cell
        slabs += partial >= 0
    if slabs == 0:
        return _NO_SLAB, 0.0, boxes, cell
    slab_axis = np.empty(k, dtype=np.int64)
    for b in range(k):
        slab_axis[b] = _slab_axis(boxes, b, cell)
    others = boxes[slab_axis < 0].copy()
    squeezed = cell.copy()
    for a in range(3):
        chosen = slab_axis == a
        if not np.any(chosen):
            continue
        starts, ends, prefix = _merged(boxes[chosen, a], boxes[chosen, a + 3])
        for b in range(others.shape[0]):
            others[b, a] = _compressed(others[b, a], starts, ends, prefix)
            others[b, a + 3] = _compressed(others[b, a + 3], starts, ends, prefix)
        squeezed[a + 3] = _compressed(cell[a + 3], starts, ends, prefix)
    keep = np.ones(others.shape[0], dtype=np.bool_)
    for b in range(others.shape[0]):
        for a in range(3):  # clipped, in case rounding moved a face past the cell's
            others[b, a] = max(others[b, a], squeezed[a])
            others[b, a + 3] = min(others[b, a + 3], squeezed[a + 3])
            keep[b] &= others[b, a] < others[b, a + 3]
    return _SQUEEZED, _cell_volume(cell) - _cell_volume(squeezed), others[keep], squeezed


@njit(cache=True)
def _cut_axis(boxes, cell):
    """The axis of the next cut: the one with the most box faces strictly inside the cell
    (after simplification every box has some)."""
    counts = np.zeros(3, dtype=np.int64)
    for b in range(boxes.shape[0]):
        for a in range(3):
            for side in (a, a + 3):
                counts[a] += cell[a] < boxes[b, side] < cell[a + 3]
    return np.argmax(counts)


@njit(cache=True)
def _measure(boxes, cell, budget) -> float:
    """Volume of the union of boxes (k, 6), each clipped to ``cell`` (6,) and of positive
    volume; NaN once more than ``budget`` boxes were visited (summed over the cells)."""
    stack = [(boxes, cell)]
    volume = 0.0
    visited = 0
    while stack:
        boxes, cell = stack.pop()
        visited += boxes.shape[0]
        if visited > budget:
            return np.nan
        outcome = _SQUEEZED
        while outcome == _SQUEEZED and boxes.shape[0] > FEW:
            outcome, part, boxes, cell = _simplify(boxes, cell)
            volume += part
        if outcome == _COVERED:
            continue
        if boxes.shape[0] <= FEW:
            volume += _few_volume(boxes)
            continue
        a = _cut_axis(boxes, cell)
        cut = _median_face(boxes, cell, a)
        below, above = cell.copy(), cell.copy()
        below[a + 3] = cut
        above[a] = cut
        stack.append((_half(boxes, a, cut, False), above))
        stack.append((_half(boxes, a, cut, True), below))
    return volume


@njit(cache=True)
def _median_face(boxes, cell, a) -> float:
    """The median of the box faces strictly inside the cell along axis ``a``."""
    faces = np.empty(2 * boxes.shape[0])
    count = 0
    for b in range(boxes.shape[0]):
        for side in (a, a + 3):
            if cell[a] < boxes[b, side] < cell[a + 3]:
                faces[count] = boxes[b, side]
                count += 1
    return np.sort(faces[:count])[count // 2]


@njit(cache=True)
def _half(boxes, a, cut, below):
    """The boxes (k, 6) that reach below (or above) ``cut`` on axis ``a``, cut there."""
    count = 0
    for b in range(boxes.shape[0]):
        count += boxes[b, a] < cut if below else boxes[b, a + 3] > cut
    out = np.empty((count, 6))
    row = 0
    for b in range(boxes.shape[0]):
        if boxes[b, a] < cut if below else boxes[b, a + 3] > cut:
            out[row] = boxes[b]
            if below:
                out[row, a + 3] = min(boxes[b, a + 3], cut)
            else:
                out[row, a] = max(boxes[b, a], cut)
            row += 1
    return out


def union_volume(boxes: np.ndarray, within: np.ndarray, budget: int = 2**62) -> float:
    """Exact volume, m^3, of the union of boxes (N, 6) within the box ``within`` (6,)
    (overlaps counted once; the parts of boxes outside ``within`` are not counted).

    NaN when the computation would visit more than ``budget`` boxes (the sum over the
    cells of the boxes in each; 30-90 ns each).
    """
    boxes = np.asarray(boxes, dtype=np.float64).reshape(-1, 6)
    cell = np.array(within, dtype=np.float64)
    clipped = np.hstack([np.maximum(boxes[:, :3], cell[:3]), np.minimum(boxes[:, 3:], cell[3:])])
    clipped = clipped[np.all(clipped[:, :3] < clipped[:, 3:], axis=1)]
    return float(_measure(np.ascontiguousarray(clipped), cell, budget))

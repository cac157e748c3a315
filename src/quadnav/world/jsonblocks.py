"""The block objects of a JSON map kept as rows of flat arrays while it is decoded.

Python's JSON decoder builds a dict and two lists for every block (about 1 KB each); a
million-block map held a gigabyte of them before a single check. The decoders of
:mod:`quadnav.world.jsonmap` hand every object to :meth:`BlockTable.compact` as soon as it is
decoded: one shaped as a block, ``{"extents": [6 numbers]}`` or ``{"extents": [6 numbers],
"color": [3 numbers]}`` (in this order, nothing else), becomes a row of :class:`BlockTable`
(81 bytes) and the decoded value holds the row's number in its place, an ``int``, which no
value of a map decodes to (numbers are read as floats). :meth:`BlockTable.restore` gives the
object back where one is needed as it was written.
"""

from __future__ import annotations

from array import array
from typing import Any

import numpy as np

from quadnav.arrays import FloatArray
from quadnav.world.blockrows import NO_LINE

_FLOAT = {float}
_NO_COLOR = [0.0, 0.0, 0.0]
#: The columns of a block's interleaved extents in the order mins then maxes.
_MINS_THEN_MAXES = np.array([0, 2, 4, 1, 3, 5])


def _floats(value: Any, count: int) -> bool:
    """Whether ``value`` is a list of ``count`` plain floats (not a subclass keeping the
    digits of a number too large for one)."""
    return type(value) is list and len(value) == count and set(map(type, value)) == _FLOAT


class BlockTable:
    """Block objects decoded so far: extents (n, 6) as the file interleaves them, colours
    (n, 3) (zeros where none is given), whether each gave one and the line each starts on."""

    def __init__(self) -> None:
        self.clear()

    def compact(self, pairs: list[tuple[str, Any]], line: int | None) -> int | None:
        """The row number of a block object given by its ``(key, value)`` pairs, added to
        the table; ``None`` for an object of another shape (kept as a dict)."""
        if not pairs or pairs[0][0] != "extents":
            return None
        if len(pairs) == 1:
            color = _NO_COLOR
        elif len(pairs) == 2 and pairs[1][0] == "color" and _floats(pairs[1][1], 3):
            color = pairs[1][1]
        else:
            return None
        if not _floats(pairs[0][1], 6):
            return None
        self._extents.extend(pairs[0][1])
        self._colors.extend(color)
        self._colored.append(color is not _NO_COLOR)
        self._lines.append(NO_LINE if line is None else line)
        return len(self._lines) - 1

    def rows(self, numbers: np.ndarray
             ) -> tuple[FloatArray, FloatArray, np.ndarray, np.ndarray]:
        """Of the rows ``numbers`` (k,): boxes (k, 6) as mins then maxes (``xmin, ymin,
        zmin, xmax, ymax, zmax``), colours (k, 3), whether each gave a colour (k,) and
        lines (k,)."""
        return (self._extents_view()[numbers[:, None], _MINS_THEN_MAXES],
                np.frombuffer(self._colors, dtype=np.float64).reshape(-1, 3)[numbers],
                np.frombuffer(self._colored, dtype=np.bool_)[numbers],
                np.frombuffer(self._lines, dtype=np.int64)[numbers])

    def clear(self) -> None:
        """Forget every row (their memory is freed once no array viewing it is left)."""
        self._extents = array("d")
        self._colors = array("d")
        self._colored = bytearray()
        self._lines = array("q")

    def _extents_view(self) -> FloatArray:
        return np.frombuffer(self._extents, dtype=np.float64).reshape(-1, 6)

    def restore(self, value: Any, make_dict: type[dict] = dict) -> Any:
        """``value`` with every row number in it turned back into the object it stands for
        (a ``make_dict`` carrying its ``line`` when the table knows it)."""
        if type(value) is int:
            obj = make_dict(extents=self._extents_view()[value].tolist())
            if self._colored[value]:
                obj["color"] = self._colors[3 * value:3 * value + 3].tolist()
            if self._lines[value] != NO_LINE:
                obj.line = self._lines[value]
            return obj
        if type(value) is list:
            return [self.restore(v, make_dict) for v in value]
        if isinstance(value, dict):
            restored = make_dict((k, self.restore(v, make_dict)) for k, v in value.items())
            if hasattr(value, "line"):
                restored.line = value.line
            return restored
        return value

"""Reading a path file: CSV with the header ``x,y,z`` and one waypoint per row, metres."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from quadnav.arrays import FloatArray
from quadnav.errors import MapError
from quadnav.limits import COORDINATE, MAX_WAYPOINTS
from quadnav.world.reading import (
    check_line_length,
    decode_text,
    is_number_text,
    read_file,
    text_lines,
)

#: The header ``quadnav plan`` writes and this reader expects.
HEADER = ["x", "y", "z"]


def read_path_csv(path: str | Path) -> FloatArray:
    """Waypoints (N, 3), metres, from a path CSV (as ``quadnav plan`` writes it).

    Raises a one-line :class:`~quadnav.errors.MapError` naming the file and line for a
    missing file, a wrong header, a row that is not three numbers within
    :data:`~quadnav.limits.COORDINATE`, fewer than two rows or more than
    :data:`~quadnav.limits.MAX_WAYPOINTS`.
    """
    source = str(path)
    lines = text_lines(decode_text(read_file(path), source))
    for number, line in enumerate(lines, start=1):
        check_line_length(line, source, number)
    rows = [(n, row) for n, row in enumerate(csv.reader(lines), start=1)
            if row and any(cell.strip() for cell in row)]
    if not rows or [cell.strip().lower() for cell in rows[0][1]] != HEADER:
        raise MapError(source, "expected the header line 'x,y,z'", rows[0][0] if rows else 1)
    points = []
    for line, row in rows[1:]:
        cells = [cell.strip() for cell in row]
        values = [float(cell) for cell in cells] if all(map(is_number_text, cells)) else []
        if len(values) != 3 or not all(v in COORDINATE for v in values):
            raise MapError(source, f"expected three numbers x,y,z {COORDINATE.describe()}, "
                           f"got {','.join(row)[:60]!r}", line)
        if len(points) == MAX_WAYPOINTS:
            raise MapError(source, f"more than {MAX_WAYPOINTS:,} waypoints: expected at most "
                           f"{MAX_WAYPOINTS:,}", line)
        points.append(values)
    if len(points) < 2:
        raise MapError(source, f"expected at least 2 waypoints, got {len(points)}")
    return np.array(points, dtype=np.float64)

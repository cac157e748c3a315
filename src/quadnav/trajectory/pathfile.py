"""Reading a path file: CSV with the header ``x,y,z`` and one waypoint per row, metres."""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np

from quadnav.errors import MapError
from quadnav.world.model import FloatArray

#: The header ``quadnav plan`` writes and this reader expects.
HEADER = ["x", "y", "z"]


def read_path_csv(path: str | Path) -> FloatArray:
    """Waypoints (N, 3), metres, from a path CSV (as ``quadnav plan`` writes it).

    Raises a one-line :class:`~quadnav.errors.MapError` naming the file and line for a
    missing file, a wrong header, a row that is not three finite numbers, or fewer than
    two rows.
    """
    source = str(path)
    try:
        text = Path(path).read_text(encoding="utf-8-sig")
    except OSError as error:
        raise MapError(source, f"cannot read: {error.strerror}") from None
    except UnicodeDecodeError:
        raise MapError(source, "expected a text CSV file") from None
    rows = [(n, row) for n, row in enumerate(csv.reader(text.splitlines()), start=1)
            if row and any(cell.strip() for cell in row)]
    if not rows or [cell.strip().lower() for cell in rows[0][1]] != HEADER:
        raise MapError(source, "expected the header line 'x,y,z'", rows[0][0] if rows else 1)
    points = []
    for line, row in rows[1:]:
        try:
            values = [float(cell) for cell in row]
        except ValueError:
            values = []
        if len(values) != 3 or not all(math.isfinite(v) for v in values):
            raise MapError(source, f"expected three finite numbers x,y,z, got {','.join(row)!r}",
                           line)
        points.append(values)
    if len(points) < 2:
        raise MapError(source, f"expected at least 2 waypoints, got {len(points)}")
    return np.array(points, dtype=np.float64)

"""Many polylines drawn as one line: a search tree's thousands of edges.

A ``LineCollection`` keeps one matplotlib ``Path`` per segment and, in 3D, builds them all
again at every draw (about 60,000 per ``quadnav fly`` figure); one line through every
polyline, with a NaN point between two of them (where matplotlib lifts the pen), is one
path, drawn in a fraction of the time. Overlapping edges then do not darken each other:
the tree is drawn once, in its light colour.
"""

from __future__ import annotations

import numpy as np
from matplotlib.axes import Axes
from matplotlib.lines import Line2D
from mpl_toolkits.mplot3d import Axes3D

from quadnav.arrays import FloatArray


def joined(polylines: FloatArray) -> FloatArray:
    """Polylines (E, P, D) as one (E * (P + 1) - 1, D) array of their points, a row of NaN
    between two polylines."""
    count, points, dims = polylines.shape
    rows = np.full((count, points + 1, dims), np.nan)
    rows[:, :points] = polylines
    return rows.reshape(-1, dims)[:-1]


def draw_polylines(ax: Axes, polylines: FloatArray, **style) -> Line2D:
    """Draw polylines (E, P, 3), m, as one line with ``style`` (``Line2D`` properties): in
    3D on a 3D axes, else seen from above (x, y); returns the line."""
    points = joined(np.asarray(polylines, dtype=np.float64))
    if isinstance(ax, Axes3D):
        return ax.plot(points[:, 0], points[:, 1], points[:, 2], **style)[0]
    return ax.plot(points[:, 0], points[:, 1], **style)[0]

"""A reference sampled to text: a plain CSV table, and the course's ``MP.csv`` layout.

Numbers are written with ``%.9g`` (nine significant digits: below a micrometre for
positions up to 100 m, and a microsecond for times up to 1000 s), comma-separated, one
line per row ending in ``\\n``. The table's samples are those of ``reference.sample(dt)``:
every ``dt`` s from 0 and the end time; MP.csv, which has no times, is sampled at exactly
``k dt`` (:func:`~quadnav.trajectory.references.contract.grid_times`), so that its columns are
uniform and :mod:`quadnav.trajectory.references.sampled` reads it back exactly.
"""

from __future__ import annotations

import io
import math

import numpy as np

from quadnav.arrays import FloatArray
from quadnav.errors import QuadnavError
from quadnav.trajectory.references.contract import Reference, grid_times, samples_at

#: Header of :func:`trajectory_csv`: time s, position m, velocity m/s, acceleration
#: m/s^2, yaw rad.
CSV_HEADER = "t,x,y,z,vx,vy,vz,ax,ay,az,yaw"
#: Number format of every value written.
NUMBER_FORMAT = "%.9g"
#: Rows of :func:`mp_csv`, top to bottom.
MP_ROWS = ("x", "y", "z", "vx", "vy", "vz", "ax", "ay", "az")


def _check_interval(dt: float) -> None:
    if not (math.isfinite(dt) and dt > 0):
        raise QuadnavError(f"sample interval dt must be a finite number > 0 s, got {dt}")


def csv_table(rows: FloatArray, header: str = "") -> str:
    """Rows (N, K) as CSV text in :data:`NUMBER_FORMAT`, after a header line if given."""
    buffer = io.StringIO()
    np.savetxt(buffer, rows, fmt=NUMBER_FORMAT, delimiter=",", header=header, comments="")
    return buffer.getvalue()


def trajectory_csv(reference: Reference, dt: float) -> str:
    """The reference sampled every ``dt`` s (and at its end) as CSV text: the header
    :data:`CSV_HEADER`, then one row per sample ``t, x, y, z, vx, vy, vz, ax, ay, az, yaw``
    (SI units, rad)."""
    _check_interval(dt)
    s = reference.sample(dt)
    return csv_table(np.column_stack([s.t, s.position, s.velocity, s.acceleration, s.yaw]),
                     CSV_HEADER)


def mp_csv(reference: Reference, dt: float) -> str:
    """The reference in the course's ``MP.csv`` layout: no header, the 9 rows
    :data:`MP_ROWS` (m, m/s, m/s^2) and one column per sample, at exactly ``k dt`` s for
    k = 0 .. ceil(duration / dt) (the times are implied by the column number; past the
    end the reference holds still, so the last column is the end state)."""
    _check_interval(dt)
    s = samples_at(reference, grid_times(reference.duration, dt))
    return csv_table(np.vstack([s.position.T, s.velocity.T, s.acceleration.T]))

"""A trajectory sampled to text: a plain CSV table, and the course's ``MP.csv`` layout.

Numbers are written with ``%.9g`` (nine significant digits: below a micrometre for
positions up to 100 m, and a microsecond for times up to 1000 s), comma-separated, one
line per row ending in ``\\n``. Samples are those of :meth:`Trajectory.sample`: every
``dt`` s from 0 and the end time.
"""

from __future__ import annotations

import io
import math

import numpy as np

from quadnav.errors import QuadnavError
from quadnav.trajectory.model import FloatArray, Samples, Trajectory

#: Header of :func:`trajectory_csv`: time s, position m, velocity m/s, acceleration
#: m/s^2, yaw rad.
CSV_HEADER = "t,x,y,z,vx,vy,vz,ax,ay,az,yaw"
#: Number format of every value written.
NUMBER_FORMAT = "%.9g"


def _samples(trajectory: Trajectory, dt: float) -> Samples:
    if not (math.isfinite(dt) and dt > 0):
        raise QuadnavError(f"sample interval dt must be a finite number > 0 s, got {dt}")
    return trajectory.sample(dt)


def csv_table(rows: FloatArray, header: str = "") -> str:
    """Rows (N, K) as CSV text in :data:`NUMBER_FORMAT`, after a header line if given."""
    buffer = io.StringIO()
    np.savetxt(buffer, rows, fmt=NUMBER_FORMAT, delimiter=",", header=header, comments="")
    return buffer.getvalue()


def trajectory_csv(trajectory: Trajectory, dt: float) -> str:
    """The trajectory sampled every ``dt`` s as CSV text: the header :data:`CSV_HEADER`,
    then one row per sample ``t, x, y, z, vx, vy, vz, ax, ay, az, yaw`` (SI units, rad)."""
    s = _samples(trajectory, dt)
    return csv_table(np.column_stack([s.t, s.position, s.velocity, s.acceleration, s.yaw]),
                  CSV_HEADER)


def mp_csv(trajectory: Trajectory, dt: float) -> str:
    """The trajectory sampled every ``dt`` s in the course's ``MP.csv`` layout: no header,
    9 rows ``px, py, pz, vx, vy, vz, ax, ay, az`` (m, m/s, m/s^2) and one column per
    sample (times are implied: ``k * dt``, the last column the end time)."""
    s = _samples(trajectory, dt)
    return csv_table(np.vstack([s.position.T, s.velocity.T, s.acceleration.T]))

"""A reference read from samples in a file: quadnav's ``trajectory.csv`` or the course's
``MP.csv``: :func:`read_reference_file`.

* ``trajectory.csv`` (:func:`~quadnav.trajectory.references.export.trajectory_csv`): the header
  ``t,x,y,z,vx,vy,vz,ax,ay,az,yaw``, then one sample per line at its own time (the first
  0 s, each after the one before).
* ``MP.csv`` (:func:`~quadnav.trajectory.references.export.mp_csv`, the course's layout): no header,
  9 rows ``x, y, z, vx, vy, vz, ax, ay, az`` and one column per sample, with no times: the
  columns are read as every ``1 / rate`` s from 0. The course's starter code (the
  Blender ``usercode.py`` of RBE595's tree-planning project) moves on by one column per
  call of its ``step``, which its ``main.py`` makes every ``user_dt`` = 0.05 s, so column
  ``k`` is the setpoint for ``t = k * 0.05`` s: :data:`COURSE_MP_RATE` is the default rate.
  ``quadnav traj`` writes its MP.csv every ``--dt`` s (0.01 by default: rate 100 Hz).

Between samples the reference is the quintic Hermite interpolation of the position,
velocity and acceleration at the samples
(:func:`~quadnav.trajectory.polynomials.quintic.hermite_trajectory`): exact at every
sample, and with continuous acceleration. Yaw is linear between samples (MP.csv has none: 0).

Every problem is one :class:`~quadnav.errors.MapError` naming the file and the line (and
column) at fault.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from quadnav.arrays import FloatArray
from quadnav.errors import MapError
from quadnav.inputfiles import special_file
from quadnav.limits import COORDINATE, MAX_DURATION, MAX_SAMPLES, Range
from quadnav.trajectory.model import Trajectory
from quadnav.trajectory.polynomials.quintic import hermite_trajectory
from quadnav.trajectory.references.contract import Samples, Sampling
from quadnav.trajectory.references.export import CSV_HEADER, MP_ROWS
from quadnav.world.reading import decode_text, is_number_text, read_file, shown_text, text_lines

#: Columns per second of an MP.csv that the course's code plays (one every 0.05 s), Hz.
COURSE_MP_RATE = 20.0
#: Rates an MP.csv may be read at, Hz.
MP_RATE = Range(0.1, 100_000.0, "Hz")
#: The two layouts.
MP_FORMAT = "MP.csv"
TABLE_FORMAT = "trajectory.csv"


@dataclass(frozen=True, eq=False)
class SampledReference(Sampling):
    """A :class:`~quadnav.trajectory.references.contract.Reference` through samples read
    from a file.

    Attributes:
        name: where the samples came from (the file's path).
        format: :data:`TABLE_FORMAT` or :data:`MP_FORMAT`.
        samples: the samples as read (times as given, or ``k / rate`` for an MP.csv).
        motion: the quintic Hermite interpolation of the samples' position, velocity and
            acceleration (method: the format).
        info: how the file was read, JSON-ready: its format, sample count and, for an
            MP.csv, the sample interval used, s.
    """

    name: str
    format: str
    samples: Samples
    motion: Trajectory
    info: dict = field(default_factory=dict)

    @property
    def duration(self) -> float:
        """Time of the last sample, s."""
        return self.motion.duration

    def position(self, t: ArrayLike) -> FloatArray:
        """Position, m, at ``t`` s: scalar -> (3,), (N,) -> (N, 3)."""
        return self.motion.position(t)

    def velocity(self, t: ArrayLike) -> FloatArray:
        """Velocity, m/s, at ``t`` s."""
        return self.motion.velocity(t)

    def acceleration(self, t: ArrayLike) -> FloatArray:
        """Acceleration, m/s^2, at ``t`` s."""
        return self.motion.acceleration(t)

    def yaw(self, t: ArrayLike) -> FloatArray:
        """Yaw, rad, at ``t`` s: linear between the samples' (unwrapped) yaws, the first
        and last held outside."""
        return np.interp(t, self.samples.t, np.unwrap(self.samples.yaw))


def sampled_reference(name: str, format: str, samples: Samples, info: dict
                      ) -> SampledReference:
    """The reference through ``samples`` (at least 2, times from 0 and increasing)."""
    states = np.stack([samples.position, samples.velocity, samples.acceleration], axis=1)
    motion = hermite_trajectory(states, np.diff(samples.t), format, {})
    return SampledReference(name, format, samples, motion, info)


def read_reference_file(path: str | Path, rate: float = COURSE_MP_RATE) -> SampledReference:
    """The reference in the file at ``path``: a ``trajectory.csv`` table if its first line
    is the header, else an ``MP.csv`` whose columns are ``1 / rate`` s apart (``rate`` in
    :data:`MP_RATE`, Hz).

    Raises:
        MapError: the file cannot be read, or is not one of the two layouts: the message
            names the file, the line and column, and what was expected.
    """
    source = str(path)
    lines = text_lines(decode_text(read_file(path), source))
    first = next((line.strip() for line in lines if line.strip()), "")
    if first[:1].isalpha():
        return _read_table(lines, source)
    return _read_mp(lines, source, MP_RATE.check(rate, "MP.csv rate"))


def _rows(lines: list[str], source: str, skip: int = 0) -> list[tuple[int, FloatArray]]:
    """``(line number, values)`` of each non-blank line after the first ``skip`` lines:
    comma-separated finite numbers; MapError naming the line and column of the first that
    is not one."""
    rows = []
    for number, line in enumerate(lines[skip:], start=skip + 1):
        if not line.strip():
            continue
        cells = [cell.strip() for cell in line.split(",")]
        column = next((k for k, cell in enumerate(cells, 1) if not is_number_text(cell)), 0)
        if column:
            raise MapError(source, f"column {column}: expected a number, got "
                           f"{shown_text(cells[column - 1])!r}", number)
        values = np.array(cells, dtype=np.float64)
        bad = np.flatnonzero(~np.isfinite(values))
        if len(bad):
            raise MapError(source, f"column {bad[0] + 1}: expected a finite number, got "
                           f"{shown_text(cells[bad[0]])!r}", number)
        rows.append((number, values))
    return rows


def _check_count(count: int, source: str, what: str) -> None:
    """MapError for fewer than 2 or more than :data:`~quadnav.limits.MAX_SAMPLES` samples."""
    if count < 2:
        raise MapError(source, f"expected at least 2 samples ({what}), got {count}")
    if count > MAX_SAMPLES:
        raise MapError(source, f"{count:,} samples ({what}): expected at most {MAX_SAMPLES:,}")


def _position_error(value: float, axis: int, source: str, line: int, column: int
                    ) -> MapError:
    """The error naming the line and column of a position ``value`` (m, along ``axis``)
    outside :data:`~quadnav.limits.COORDINATE`."""
    return MapError(source, f"column {column}: {'xyz'[axis]} = {value:g} m, expected "
                    f"{COORDINATE.describe()}", line)


def _outside(position: FloatArray) -> tuple[int, int] | None:
    """``(sample, axis)`` of the first of the positions (N, 3), m, outside
    :data:`~quadnav.limits.COORDINATE`, or None."""
    found = np.argwhere(np.abs(position) > COORDINATE.high)
    return (int(found[0, 0]), int(found[0, 1])) if len(found) else None


def _check_duration(duration: float, source: str, advice: str) -> None:
    if duration > MAX_DURATION:
        raise MapError(source, f"the samples last {duration:.6g} s, longer than the "
                       f"{MAX_DURATION:g} s a reference may last{advice}")


def _read_table(lines: list[str], source: str) -> SampledReference:
    """A trajectory.csv table (see the module docstring)."""
    number = next(n for n, line in enumerate(lines, 1) if line.strip())
    header = lines[number - 1].strip().replace(" ", "")
    if header != CSV_HEADER:
        raise MapError(source, f"expected the header {CSV_HEADER!r} (or an MP.csv: 9 rows "
                       f"of numbers), got {header[:60]!r}", number)
    rows = _rows(lines, source, skip=number)
    for line, values in rows:
        if len(values) != len(CSV_HEADER.split(",")):
            raise MapError(source, f"expected {len(CSV_HEADER.split(','))} values "
                           f"({CSV_HEADER}), got {len(values)}", line)
    _check_count(len(rows), source, "rows")
    where = [line for line, _ in rows]
    table = np.array([values for _, values in rows])
    t = table[:, 0]
    if t[0] != 0:
        raise MapError(source, f"column 1: the first time is {t[0]:g} s, expected 0",
                       where[0])
    stalled = np.flatnonzero(np.diff(t) <= 0)
    if len(stalled):
        k = stalled[0] + 1
        raise MapError(source, f"column 1: t = {t[k]:.9g} s is not after the time before it "
                       f"({t[k - 1]:.9g} s): expected increasing times", where[k])
    _check_duration(float(t[-1]), source, "")
    if (outside := _outside(table[:, 1:4])) is not None:
        sample, axis = outside
        raise _position_error(table[sample, 1 + axis], axis, source, where[sample], 2 + axis)
    samples = Samples(t, table[:, 1:4], table[:, 4:7], table[:, 7:10], table[:, 10])
    return sampled_reference(source, TABLE_FORMAT, samples,
                             {"format": TABLE_FORMAT, "samples": len(t)})


def _read_mp(lines: list[str], source: str, rate: float) -> SampledReference:
    """An MP.csv (see the module docstring), its columns ``1 / rate`` s apart."""
    rows = _rows(lines, source)
    if len(rows) != len(MP_ROWS):
        raise MapError(source, f"expected {len(MP_ROWS)} rows ({', '.join(MP_ROWS)}: the "
                       f"course's MP.csv) or a trajectory.csv header, got {len(rows)} rows")
    (first, values), *rest = rows
    for line, other in rest:
        if len(other) != len(values):
            raise MapError(source, f"{len(other):,} values, but line {first} has "
                           f"{len(values):,}: expected one column per sample, as many on "
                           "every row", line)
    _check_count(len(values), source, "columns")
    dt = 1.0 / rate
    _check_duration((len(values) - 1) * dt, source, f" read every {dt:g} s: raise the rate")
    table = np.array([values for _, values in rows])
    position = table[0:3].T
    if (outside := _outside(position)) is not None:
        sample, axis = outside
        raise _position_error(position[sample, axis], axis, source, rows[axis][0], sample + 1)
    samples = Samples(np.arange(len(values)) * dt, position, table[3:6].T, table[6:9].T,
                      np.zeros(len(values)))
    return sampled_reference(source, MP_FORMAT, samples,
                             {"format": MP_FORMAT, "samples": len(values),
                              "sample_interval_s": dt, "rate_hz": rate})


def is_reference_file(path: str | Path) -> bool:
    """Whether ``path`` names an existing file, or something there that is not a folder (a
    FIFO, read as a file is, is refused as what it is); a name too long to be one is not."""
    try:
        return Path(path).is_file() or special_file(path) not in (None, "a folder")
    except OSError:
        return False


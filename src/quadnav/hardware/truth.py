"""The true track of a Tello flight, from whatever outside the bridge knows it: the
emulator (``quadnav tello emulate --truth FILE``) or, beside a real drone, a
motion-capture system that writes the same file.

The file (:data:`TRUTH_FILE_HEADER`) is CSV: one row per sample, the UNIX time in
seconds (the clock the bridge and the writer share; the bridge never asks the writer for
anything else) and the drone's position in the map frame, m. The writer appends rows as
the drone flies and flushes them (:class:`TruthWriter`), so a flight that has landed
finds every sample up to its landing. The emulator's positions are in its world frame:
the map frame when it stands on the floor under the map's start (``--start``, as the
bridge's takeoff), facing ``--yaw`` as the flight's.

:func:`flight_truth` keeps the rows from the start of the bridge's dead reckoning on, in
its time: drone seconds since its :attr:`~quadnav.hardware.bridge.dead_reckoning.DeadReckoning.
epoch` (UNIX seconds since it, times the time scale), which is flight.csv's time; the run
folder's ``truth.csv`` holds them (:data:`~quadnav.runs.TRUTH_HEADER`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from quadnav.arrays import FloatArray
from quadnav.errors import QuadnavError
from quadnav.runs import read_table

#: The first line of a true-track file.
TRUTH_FILE_HEADER = "unix_time_s,x,y,z"


class TruthWriter:
    """Appends a true track to a file as it is flown (see the module); close when done.

    Raises:
        QuadnavError: the file cannot be written.
    """

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        try:
            self._file = self.path.open("w", encoding="utf-8")
        except OSError as error:
            raise QuadnavError(f"{path}: cannot write the true track: "
                               f"{error.strerror}") from None
        self._write(TRUTH_FILE_HEADER + "\n")

    def write(self, unix_times: ArrayLike, positions: ArrayLike) -> None:
        """Append samples at ``unix_times`` (N,) s of ``positions`` (N, 3) m, and flush."""
        rows = np.column_stack([unix_times, np.asarray(positions).reshape(-1, 3)])
        self._write("".join(f"{t:.6f},{x:.6f},{y:.6f},{z:.6f}\n" for t, x, y, z in rows))

    def _write(self, text: str) -> None:
        self._file.write(text)
        self._file.flush()

    def close(self) -> None:
        """Close the file."""
        self._file.close()


def read_truth_file(path: str | Path) -> FloatArray:
    """(N, 4) the rows of the true-track file ``path`` written so far: UNIX time s, x, y,
    z m (a last line still being written is left out). QuadnavError (naming the file) if
    it cannot be read or is not such a file."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as error:
        raise QuadnavError(f"{path}: cannot read the true track: {error.strerror}") from None
    whole = text[:text.rfind("\n") + 1]  # a line without its newline is being written
    return read_table(path, TRUTH_FILE_HEADER, whole)


def flight_truth(path: str | Path, epoch: float, time_scale: float) -> FloatArray:
    """(N, 4) the true track in ``path`` from UNIX time ``epoch`` s on: drone seconds since
    it (times ``time_scale``), x, y, z m. QuadnavError as :func:`read_truth_file`."""
    rows = read_truth_file(path)
    rows = rows[rows[:, 0] >= epoch]
    return np.column_stack([(rows[:, 0] - epoch) * time_scale, rows[:, 1:4]])

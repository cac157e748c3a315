"""The tree both kinodynamic RRTs grow: :class:`ControlTree`.

Each vertex is a state reached by holding one control for a duration from its parent's
state; row 0 is the start (no parent, no control). The arrays grow as needed; only the
first :attr:`~ControlTree.size` rows are vertices.
"""

from __future__ import annotations

import numpy as np

from quadnav.arrays import FloatArray

#: Vertices the arrays hold before they first grow.
INITIAL_CAPACITY = 1024


class ControlTree:
    """Growable arrays of a tree of controlled motions (a subclass that keeps more
    per-vertex arrays names them in :attr:`COLUMNS`).

    Attributes:
        size: vertices so far.
        states: (capacity, S) each vertex's state (rows ``size`` and on unused).
        parents: (capacity,) each vertex's parent row, -1 for the start.
        controls: (capacity, C) the control held from the parent to the vertex.
        durations: (capacity,) how long it was held, s.
    """

    #: The per-vertex arrays, grown together.
    COLUMNS: tuple[str, ...] = ("states", "parents", "controls", "durations")

    def __init__(self, start_state: FloatArray, control_size: int,
                 capacity: int = INITIAL_CAPACITY) -> None:
        start_state = np.asarray(start_state, dtype=np.float64)
        self.size = 1
        self.states = np.zeros((capacity, len(start_state)))
        self.parents = np.full(capacity, -1, dtype=np.int64)
        self.controls = np.zeros((capacity, control_size))
        self.durations = np.zeros(capacity)
        self.states[0] = start_state

    def add(self, parent: int, state: FloatArray, control: FloatArray, duration: float
            ) -> int:
        """Add the vertex reached from row ``parent`` by holding ``control`` for
        ``duration`` s; returns its row."""
        if self.size == len(self.states):
            for name in self.COLUMNS:
                old = getattr(self, name)
                grown = np.zeros((2 * len(old), *old.shape[1:]), dtype=old.dtype)
                grown[:len(old)] = old
                setattr(self, name, grown)
        index = self.size
        self.states[index], self.parents[index] = state, parent
        self.controls[index], self.durations[index] = control, duration
        self.size += 1
        return index

    def branch(self, leaf: int) -> list[int]:
        """Rows from the start to ``leaf``."""
        rows = [leaf]
        while self.parents[rows[-1]] >= 0:
            rows.append(int(self.parents[rows[-1]]))
        return rows[::-1]

    def arrays(self) -> tuple[FloatArray, np.ndarray, FloatArray, FloatArray]:
        """Copies of the vertices' rows: states, parents, controls, durations."""
        n = self.size
        return (self.states[:n].copy(), self.parents[:n].copy(), self.controls[:n].copy(),
                self.durations[:n].copy())

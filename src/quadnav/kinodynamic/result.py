"""What a kinodynamic planner returns: :class:`KinoResult`.

Unlike a geometric path, a kinodynamic plan is a sequence of *controls*, each held for a
duration, whose integrated motion joins the start to the goal region and, where the planner
closes it, on to the goal itself. The tree is kept as
states with the control and duration that led to each one, so its edges can be drawn as
the curves the robot would follow.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from quadnav.arrays import FloatArray, read_only

IntArray = NDArray[np.int64]


@dataclass(frozen=True, eq=False)
class KinoResult:
    """The outcome of one kinodynamic planning query.

    Attributes:
        planner: e.g. ``"diffdrive"``, ``"quadrotor"`` or ``"ompl:control-RRT"``.
        solved: whether a state inside the goal region was reached (and, for a planner
            that closes its plans, the plan closed onto the goal).
        states: (K, d) states along the plan from the start to its last state: the one
            reached in the goal region, or the goal itself when the plan is closed;
            (0, d) when not solved. Units as the model states them (SI).
        controls: (K - 1, c) control held on each edge of the plan.
        durations: (K - 1,) seconds each control is held.
        tree_states: (M, d) every state of the tree, the start first.
        tree_parents: (M,) index of each state's parent, -1 for the start.
        tree_controls: (M, c) the control that led to each state (zeros for the start).
        tree_durations: (M,) seconds that control was held (0 for the start).
        iterations: extensions tried.
        seconds: wall time of the search, s.
        time_to_goal: wall time until the goal region was reached, s, or ``None``.
        seed: the seed the search ran with.
        message: one line for the user, e.g. why there is no plan.
        leg_controls: how many of the first controls fly the leg out of the safety margin
            at the start (0 without a leg); the rest of the plan keeps the whole margin
            but for the goal leg.
        closing_controls: how many controls, after the state reached in the goal region
            and before the goal leg, take the plan onto the goal, or to where the goal leg
            begins (the quadrotor's closing stop, which ends there at rest; the
            differential drive's turn and straight drive to the leg); 0 when the plan ends
            where it reached the goal region.
        goal_leg_controls: how many of the last controls fly the leg into the safety
            margin to a goal inside it (0 without a leg).
    """

    planner: str
    solved: bool
    states: FloatArray
    controls: FloatArray
    durations: FloatArray
    tree_states: FloatArray
    tree_parents: IntArray
    tree_controls: FloatArray
    tree_durations: FloatArray
    iterations: int
    seconds: float
    time_to_goal: float | None
    seed: int
    message: str = ""
    leg_controls: int = 0
    closing_controls: int = 0
    goal_leg_controls: int = 0

    def __post_init__(self) -> None:
        for name in ("states", "controls", "durations", "tree_states", "tree_parents",
                     "tree_controls", "tree_durations"):
            value = getattr(self, name)
            dtype = np.int64 if name == "tree_parents" else np.float64
            object.__setattr__(self, name, read_only(np.array(value, dtype=dtype)))
        if len(self.controls) != max(len(self.states) - 1, 0) or len(self.durations) != len(
                self.controls):
            raise ValueError("a plan of K states needs K - 1 controls and durations")
        if not (len(self.tree_states) == len(self.tree_parents) == len(self.tree_controls)
                == len(self.tree_durations)):
            raise ValueError("tree arrays must have one row per state")

    @property
    def duration(self) -> float:
        """Total time of the plan, s (0 when not solved)."""
        return float(self.durations.sum())

"""Settings shared by the kinodynamic planners."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from quadnav.limits import KINO_ITERATIONS, LENGTH, PLAN_TIME, SEED, UNIT_INTERVAL, Range

#: How long one sampled control may be held, s, and how many are sampled per extension.
_DURATION = Range(1e-3, 10.0, "s")
_CONTROLS = Range(1, 1000, whole=True)


@dataclass(frozen=True)
class KinoSettings:
    """How a kinodynamic RRT searches.

    Attributes:
        max_iterations: extensions tried at most.
        time_limit: wall-time budget, s.
        seed: seed of every random choice; the same seed gives the same plan.
        biased: goal-biased sampling (a Gaussian around the goal whose spread is
            proportional to the distance from the goal to the tree's closest state);
            ``False``: uniform sampling over the map.
        goal_bias: with ``biased``, the probability of drawing from that Gaussian (else
            uniform), in [0, 1].
        goal_radius: the goal region, metres around the goal position.
        duration: how long each sampled control is held, s.
        controls_per_extension: controls sampled per extension; the one whose end is
            nearest the sampled point is kept.
    """

    max_iterations: int = 20000
    time_limit: float = 10.0
    seed: int = 0
    biased: bool = True
    goal_bias: float = 0.5
    goal_radius: float = 0.5
    duration: float = 0.5
    controls_per_extension: int = 10

    def __post_init__(self) -> None:
        KINO_ITERATIONS.check(self.max_iterations, "max iterations")
        PLAN_TIME.check(self.time_limit, "time limit")
        SEED.check(self.seed, "seed")
        UNIT_INTERVAL.check(self.goal_bias, "goal bias")
        LENGTH.check(self.goal_radius, "goal radius")
        _DURATION.check(self.duration, "control duration")
        _CONTROLS.check(self.controls_per_extension, "controls per extension")

    def budget_used(self, iterations: int, elapsed: float) -> float:
        """Share of the budget used after ``iterations`` extensions and ``elapsed`` s:
        of the iterations or of the time, whichever is further, at most 1."""
        return min(max(iterations / self.max_iterations, elapsed / self.time_limit), 1.0)

    def replace(self, **changes: object) -> KinoSettings:
        """A copy with some fields changed (see :func:`dataclasses.replace`)."""
        return dataclasses.replace(self, **changes)

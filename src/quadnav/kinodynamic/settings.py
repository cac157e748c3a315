"""Settings shared by the kinodynamic planners."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

from quadnav.errors import QuadnavError


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
        checks = [
            (self.max_iterations >= 1, f"max iterations must be >= 1, got {self.max_iterations}"),
            (math.isfinite(self.time_limit) and self.time_limit > 0,
             f"time limit must be > 0 s, got {self.time_limit}"),
            (0 <= self.seed < 2**63, f"seed must be in [0, 2^63), got {self.seed}"),
            (0 <= self.goal_bias <= 1, f"goal bias must be in [0, 1], got {self.goal_bias}"),
            (math.isfinite(self.goal_radius) and self.goal_radius > 0,
             f"goal radius must be > 0 m, got {self.goal_radius}"),
            (math.isfinite(self.duration) and self.duration > 0,
             f"control duration must be > 0 s, got {self.duration}"),
            (self.controls_per_extension >= 1,
             f"controls per extension must be >= 1, got {self.controls_per_extension}"),
        ]
        for ok, message in checks:
            if not ok:
                raise QuadnavError(message)

    def replace(self, **changes: object) -> KinoSettings:
        """A copy with some fields changed (see :func:`dataclasses.replace`)."""
        return dataclasses.replace(self, **changes)

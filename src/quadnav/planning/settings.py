"""Settings shared by every planner, with defaults scaled to the map.

One :class:`PlannerSettings` drives every planner; each uses the fields that apply to it
(OMPL's RRT* uses ``step`` as its range and ``goal_bias``; PRM* ignores both).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from quadnav.errors import QuadnavError
from quadnav.limits import LENGTH, PLAN_ITERATIONS, PLAN_TIME, SEED, Range
from quadnav.planning.stall import StallRule
from quadnav.world.model import World

#: Default wall-time budget of a search, s.
DEFAULT_TIME_LIMIT = 1.0
#: Default step as a fraction of the diagonal of the (inflated) boundary box.
STEP_FRACTION = 0.05
#: OMPL's default rewiring factor: the near radius is this times the smallest radius
#: that keeps RRT* asymptotically optimal.
DEFAULT_REWIRE_FACTOR = 1.1
_REWIRE_FACTOR = Range(1.0, 100.0)
_IMPROVE = Range(0, PLAN_ITERATIONS.high, whole=True)


@dataclass(frozen=True)
class PlannerSettings:
    """How long and how a planner searches.

    Attributes:
        time_limit: wall-time budget of the search, s (:data:`~quadnav.limits.PLAN_TIME`).
        max_iterations: stop after this many samples (``None``: only the time limit and
            :data:`~quadnav.limits.PLAN_ITERATIONS`, the most any search takes).
        improve_iterations: once a first solution is found, stop after this many more
            samples (``None``: no such limit). With no ``max_iterations``, the search then
            takes as long as a first solution needs (within ``time_limit``) and is still
            repeatable: the same seed gives the same path.
        stall: once a first solution is found, stop when the best length has stopped
            improving by this rule (:mod:`~quadnav.planning.stall`; ``None``: no such
            rule, the search runs its whole budget). Binds by samples, as
            ``improve_iterations`` does, which stays the ceiling. RRT* and OMPL's planners
            that count iterations.
        seed: seed of every random choice; the same seed gives the same result.
        stop_at_first: return as soon as a first solution is found.
        step: largest edge a tree grows by in one iteration, metres (``None``: scaled to
            the map, :data:`STEP_FRACTION` of the boundary diagonal).
        goal_bias: probability of sampling the goal instead of a random point, in [0, 1).
        goal_tolerance: a vertex this close to the goal, metres, is joined to it by a
            straight segment when that segment is free (``None``: the step).
        rewire_factor: multiplies the asymptotically optimal near radius
            ``gamma * (log n / n)^(1/3)`` (which is then capped by the step); >= 1.
        informed: after a first solution, sample only where a shorter path could pass
            (the prolate ellipsoid with the start and goal as foci).
    """

    time_limit: float = DEFAULT_TIME_LIMIT
    max_iterations: int | None = None
    improve_iterations: int | None = None
    stall: StallRule | None = None
    seed: int = 0
    stop_at_first: bool = False
    step: float | None = None
    goal_bias: float = 0.05
    goal_tolerance: float | None = None
    rewire_factor: float = DEFAULT_REWIRE_FACTOR
    informed: bool = True

    def __post_init__(self) -> None:
        PLAN_TIME.check(self.time_limit, "time limit")
        if self.max_iterations is not None:
            PLAN_ITERATIONS.check(self.max_iterations, "max iterations")
        if self.improve_iterations is not None:
            _IMPROVE.check(self.improve_iterations, "iterations after the first solution")
        SEED.check(self.seed, "seed")
        for name in ("step", "goal_tolerance"):
            if getattr(self, name) is not None:
                LENGTH.check(getattr(self, name), name.replace("_", " "))
        if not 0 <= self.goal_bias < 1:
            raise QuadnavError(f"goal bias must be in [0, 1), got {self.goal_bias}")
        _REWIRE_FACTOR.check(self.rewire_factor, "rewire factor")

    def replace(self, **changes: object) -> PlannerSettings:
        """A copy with some fields changed (see :func:`dataclasses.replace`)."""
        return dataclasses.replace(self, **changes)

    def limit_after_first(self, first: int) -> int:
        """The sample cap of a search whose first solution came at sample ``first``."""
        cap = self.max_iterations or np.iinfo(np.int64).max
        if self.stop_at_first:
            return min(cap, first)
        if self.improve_iterations is None:
            return cap
        return min(cap, first + self.improve_iterations)

    def step_for(self, world: World) -> float:
        """The step in metres for ``world``: the set one, else scaled to its boundary."""
        if self.step is not None:
            return self.step
        return STEP_FRACTION * float(np.linalg.norm(world.extent))

    def goal_tolerance_for(self, world: World) -> float:
        """The goal tolerance in metres for ``world``: the set one, else the step."""
        return self.goal_tolerance if self.goal_tolerance is not None else self.step_for(world)

"""What a planner is: the :data:`Planner` signature (with
:data:`~quadnav.planning.result.Progress`, the callback of every search), and the names of
OMPL's planners. Kept apart from :mod:`quadnav.planning.registry`, so that the
planners themselves need not import the registry that names them."""

from __future__ import annotations

from collections.abc import Callable

from quadnav.planning.problem import PlanningProblem
from quadnav.planning.result import PlanResult, Progress
from quadnav.planning.settings import PlannerSettings

#: ``planner(problem, settings, progress or None) -> PlanResult``.
Planner = Callable[[PlanningProblem, PlannerSettings, Progress | None], PlanResult]

#: Prefix of the names of OMPL planners.
OMPL_PREFIX = "ompl:"
#: OMPL geometric planners offered through ``ompl:NAME``.
OMPL_PLANNERS = ("RRTstar", "InformedRRTstar", "BITstar", "RRTConnect", "PRMstar")

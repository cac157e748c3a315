"""Path stage: plan a collision-free path through a World.

* :func:`make_problem` — check a start, goal and margin against a world.
* :func:`plan` — run a planner by name (``rrtstar``, ``ompl:RRTstar``, ...).
* :class:`PlannerSettings` — budget, seed, step, goal bias, ...
* :class:`PlanResult` — path (N, 3), explored tree and statistics.
"""

from quadnav.planning.problem import PlanningProblem, make_problem
from quadnav.planning.registry import Progress, get_planner, planner_names
from quadnav.planning.result import PlanResult, PlanStats, PostStep, path_length
from quadnav.planning.settings import PlannerSettings

__all__ = [
    "PlanResult",
    "PlanStats",
    "PlannerSettings",
    "PlanningProblem",
    "PostStep",
    "Progress",
    "get_planner",
    "make_problem",
    "path_length",
    "plan",
    "planner_names",
]


def plan(problem: PlanningProblem, settings: PlannerSettings | None = None,
         planner: str = "rrtstar", progress: Progress | None = None) -> PlanResult:
    """Plan a path for ``problem`` with the planner called ``planner``.

    Args:
        problem: a checked query (:func:`make_problem`).
        settings: budget, seed and tuning; defaults scaled to the map when ``None``.
        planner: ``rrtstar`` or ``ompl:NAME`` (see :func:`planner_names`).
        progress: called now and then with (fraction of the budget used, best length).
    """
    return get_planner(planner)(problem, settings or PlannerSettings(), progress)

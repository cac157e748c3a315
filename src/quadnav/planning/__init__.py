"""Path stage: plan a collision-free path through a World.

* :func:`make_problem` — check a start, goal and margin against a world.
* :func:`plan` — run a planner by name (``rrtstar``, ``ompl:RRTstar``, ...) or a plain
  function (``my_astar.py:astar``, :mod:`quadnav.planning.plain`); a goal in sight of the
  start is joined at once, without a search, but for a plain function, always called.
* :class:`PlannerSettings` — budget, seed, step, goal bias, ...
* :class:`StallRule` — stop a search once its best length has stopped improving.
* :class:`PlanResult` — path (N, 3), explored tree and statistics.
"""

import time

import numpy as np

from quadnav.planning.plain import PlainPlanner
from quadnav.planning.problem import PlanningProblem, make_problem
from quadnav.planning.registry import get_planner, planner_names, register_planner
from quadnav.planning.result import PlanResult, PlanStats, PostStep, Progress, path_length
from quadnav.planning.settings import PlannerSettings
from quadnav.planning.stall import StallRule
from quadnav.profiling import staged

__all__ = [
    "PlainPlanner",
    "PlanResult",
    "PlanStats",
    "PlannerSettings",
    "PlanningProblem",
    "PostStep",
    "Progress",
    "StallRule",
    "direct_result",
    "get_planner",
    "make_problem",
    "path_length",
    "plan",
    "planner_names",
    "register_planner",
]


@staged("search")
def plan(problem: PlanningProblem, settings: PlannerSettings | None = None,
         planner: str = "rrtstar", progress: Progress | None = None) -> PlanResult:
    """Plan a path for ``problem`` with the planner called ``planner``.

    Args:
        problem: a checked query (:func:`make_problem`).
        settings: budget, seed and tuning; defaults scaled to the map when ``None``.
        planner: ``rrtstar``, ``ompl:NAME`` (see :func:`planner_names`), or a plain
            function, ``module:function`` or ``path/to/file.py:function``
            (:mod:`quadnav.planning.plain`).
        progress: called now and then with (fraction of the budget used, best length).
    """
    search = get_planner(planner)
    settings = settings or PlannerSettings()
    direct = None if isinstance(search, PlainPlanner) else direct_result(problem, planner,
                                                                          settings)
    return direct or search(problem, settings, progress)


def direct_result(problem: PlanningProblem, planner: str, settings: PlannerSettings
                  ) -> PlanResult | None:
    """The straight path when the search goal is in sight of the search start (a free
    segment in the inflated world): no search can do better. ``None`` otherwise."""
    began = time.perf_counter()
    ends = np.stack([problem.search_start, problem.search_goal])
    if not problem.free_world.segment_free(*ends):
        return None
    seconds = time.perf_counter() - began
    length = path_length(ends)
    stats = PlanStats(iterations=0, nodes=2, seconds=seconds, time_to_first=seconds,
                      cost_history=np.array([[seconds, length]]), stopped_by="direct")
    return PlanResult(planner, True, problem.full_path(ends), ends, np.array([-1, 0]), stats,
                      settings.seed, "the goal is in sight of the start: joined directly")

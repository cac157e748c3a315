"""Planners by name: ``rrtstar`` (ours), ``ompl:NAME`` (the optional OMPL wheel), any
planner registered by :func:`register_planner` or by a package's entry point, and a plain
function named where it is, ``module:function`` or ``path/to/file.py:function``
(:mod:`quadnav.planning.plain`: ``function(world, start, goal, margin) -> path (N, 3)``).

Every planner is a function with the :data:`Planner` signature. It searches
``problem.free_world`` (the map with its blocks grown by the margin) from
``problem.search_start`` to ``problem.search_goal`` and returns a
:class:`~quadnav.planning.result.PlanResult` whose path runs from exactly
``problem.start`` to exactly ``problem.goal`` (:meth:`PlanningProblem.full_path` adds
the legs out of the margin). ``examples/custom_planner.py`` is a template.

A planner is known by name in the process that registers it
(``register_planner("mine", plan_mine)``), so :func:`quadnav.mission.fly_mission` and
:func:`quadnav.planning.plan` fly it. To make it known to the ``quadnav`` command and to
batch workers too, a package declares it as an entry point in its ``pyproject.toml``::

    [project.entry-points."quadnav.planners"]
    mine = "my_package.my_module:plan_mine"
"""

from __future__ import annotations

import importlib.util
from collections.abc import Callable

from quadnav.errors import QuadnavError
from quadnav.planning.plain import PlainPlanner
from quadnav.planning.problem import PlanningProblem
from quadnav.planning.result import PlanResult, Progress
from quadnav.planning.settings import PlannerSettings
from quadnav.plugins import Registry, parse_spec

#: ``planner(problem, settings, progress or None) -> PlanResult``.
Planner = Callable[[PlanningProblem, PlannerSettings, Progress | None], PlanResult]

#: Prefix of the names of OMPL planners.
OMPL_PREFIX = "ompl:"
#: OMPL geometric planners offered through ``ompl:NAME``.
OMPL_PLANNERS = ("RRTstar", "InformedRRTstar", "BITstar", "RRTConnect", "PRMstar")


def _rrtstar(problem: PlanningProblem, settings: PlannerSettings,
             progress: Progress | None) -> PlanResult:
    from quadnav.planning.rrtstar import plan_rrtstar

    return plan_rrtstar(problem, settings, progress)


#: Planners by name: ours, those registered, those of installed packages' entry points.
PLANNERS: Registry[Planner] = Registry("planner", "quadnav.planners", {"rrtstar": _rrtstar})


def register_planner(name: str, planner: Planner, replace: bool = False) -> None:
    """Make ``planner`` known as ``name`` in this process, wherever a planner is chosen by
    name (see :meth:`quadnav.plugins.Registry.register`)."""
    PLANNERS.register(name, planner, replace)


def planner_names() -> list[str]:
    """Every planner name ``get_planner`` accepts (OMPL's whether installed or not)."""
    return [*PLANNERS.names(), *(OMPL_PREFIX + name for name in OMPL_PLANNERS)]


def ompl_available() -> bool:
    """Whether the optional ``ompl`` wheel is installed."""
    return importlib.util.find_spec("ompl") is not None


def get_planner(name: str) -> Planner:
    """The planner called ``name``: a registered one, ``ompl:NAME``, or a plain function
    named ``module:function`` or ``path/to/file.py:function``, with keyword arguments
    (a :class:`~quadnav.planning.plain.PlainPlanner`, loaded in this process).
    QuadnavError naming the choices if there is none, and for a function that cannot be
    loaded or called as a planner (a :class:`~quadnav.plugins.PluginError` when loading it
    raised)."""
    if name in PLANNERS:
        return PLANNERS.get(name)
    if name.startswith(OMPL_PREFIX) and name[len(OMPL_PREFIX):] in OMPL_PLANNERS:
        if not ompl_available():
            raise QuadnavError(f"planner {name!r} needs the optional OMPL wheel: "
                               "python -m pip install 'quadnav[ompl]'")
        from quadnav.planning.ompl_planners import plan_ompl

        ompl_name = name[len(OMPL_PREFIX):]
        return lambda problem, settings, progress: plan_ompl(problem, settings, ompl_name,
                                                             progress)
    if not name.startswith(OMPL_PREFIX) and parse_spec(name, "planner").is_located:
        function, kwargs = PLANNERS.load(name)
        return PlainPlanner.named(name, function, kwargs)
    raise QuadnavError(f"unknown planner {name!r}; expected one of {', '.join(planner_names())}"
                       ", or module:FUNCTION or path/to/file.py:FUNCTION")

"""Planners by name: ``rrtstar`` (ours), ``ompl:NAME`` (the optional OMPL wheel), any
planner registered by :func:`register_planner` or by a package's entry point, and a plain
function named where it is, ``module:function`` or ``path/to/file.py:function``
(:mod:`quadnav.planning.plain`: ``function(world, start, goal, margin) -> path (N, 3)``).

Every planner is a function with the :data:`~quadnav.planning.contract.Planner` signature.
It searches ``problem.free_world`` (the map with its blocks grown by the margin) from
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

Only the planner asked for is imported: OMPL's when one of them is (it checks for the
wheel first), an entry point's when it is (one that cannot be imported names itself, and
the others still fly).
"""

from __future__ import annotations

from quadnav.planning.contract import OMPL_PLANNERS, OMPL_PREFIX, Planner
from quadnav.planning.plain import PlainPlanner
from quadnav.plugins import Lazy, OptionalWheel, Registry

#: The optional package OMPL's planners need.
OMPL_WHEEL = OptionalWheel("ompl", "OMPL", "ompl")

#: Planners by name: ours, OMPL's (each imported when first used, which needs the optional
#: wheel: :func:`~quadnav.planning.ompl_planners.ompl_planner`), those of installed
#: packages' entry points, those registered.
PLANNERS: Registry[Planner] = Registry("planner", "quadnav.planners", {
    "rrtstar": "quadnav.planning.rrtstar:plan_rrtstar",
    **{OMPL_PREFIX + name: Lazy("quadnav.planning.ompl_planners:ompl_planner", (name,),
                                needs=OMPL_WHEEL) for name in OMPL_PLANNERS},
}, located="module:FUNCTION or path/to/file.py:FUNCTION")


def register_planner(name: str, planner: Planner, replace: bool = False) -> None:
    """Make ``planner`` known as ``name`` in this process, wherever a planner is chosen by
    name (see :meth:`quadnav.plugins.Registry.register`)."""
    PLANNERS.register(name, planner, replace)


def planner_names() -> list[str]:
    """Every planner name ``get_planner`` accepts (OMPL's whether installed or not)."""
    return PLANNERS.names()


def ompl_available() -> bool:
    """Whether the optional ``ompl`` wheel is installed."""
    return not OMPL_WHEEL.missing()


def get_planner(name: str) -> Planner:
    """The planner called ``name``: a registered one (``rrtstar``, ``ompl:NAME``, ...), or a
    plain function named ``module:function`` or ``path/to/file.py:function``, with keyword
    arguments (a :class:`~quadnav.planning.plain.PlainPlanner`, loaded in this process).
    QuadnavError naming the choices if there is none, and for a function that cannot be
    loaded or called as a planner (a :class:`~quadnav.plugins.PluginError` when loading it
    raised, or for an OMPL planner without the optional wheel)."""
    if name in PLANNERS:
        return PLANNERS.get(name)
    if PLANNERS.is_located(name):
        function, kwargs = PLANNERS.load(name)
        return PlainPlanner.named(name, function, kwargs)
    raise PLANNERS.unknown(name)

"""One mission, described once: :class:`MissionConfig`, what ``fly``, ``batch`` (each of its
missions), ``tune``, ``tello fly``, ``refly`` and the library build a mission from, and what a
run folder keeps as ``mission.toml`` so that it flies again exactly.

A mission file is TOML; every key is optional, and those left out are ``quadnav fly``'s
defaults::

    map = "course:rbe595/map1"    # a map file, a built-in world spec or a course map
    seed = 0                      # the planner's, the gusts', the vehicle spread's
    vehicle = "tello"             # a preset, a vehicle TOML file, a rotorpy dict
                                  # (module:NAME, file.py:NAME), or a [vehicle] table

    [query]
    start = [0.1, -4.9, 0.2]      # m; default: the start/goal file's, else the map's own
    goal = [8.0, 18.0, 3.0]
    start_goal = "start_goal.txt" # an RBE595 start/goal file or a course one
    margin = 0.2                  # m; default: the map's own, else 0.2

    [planner]
    name = "rrtstar"              # a planner's name (ompl:NAME) or a plug-in spec
    time = 10.0                   # s, the search's wall-time cap
    iterations = 0                # samples in all, 0: no cap
    improve = 50000               # samples after the first path, at most
    stall = 5000                  # stop when the best length shortened by at most
    stall_fraction = 0.005        # this fraction over this many samples (0: a fixed budget)
    refine = true                 # shortcut and smooth the path

    [trajectory]
    method = "minsnap"
    timing = "fastest"
    speed = 2.0                   # m/s, or "max"
    accel = 3.0                   # m/s^2
    reference = "my_ref.py:Circle(radius=2)"   # a trajectory class flown instead
    duration = 10.0               # s, how long the reference is flown (default: its own)

    [controller]
    name = "cascade"              # or "se3", or a plug-in spec (a plain-Python class)
    gains = "my_gains.toml"       # a gains file, a course gain table, or a [controller.gains]
                                  # table (a plain-Python class's: its inner loops')

    [simulation]
    physics_rate = 1000.0         # Hz
    control_rate = 1000.0         # Hz
    settle = 2.0                  # s flown after the reference ends
    seed = 7                      # the gusts' and the spread's alone (default: the mission's)

    [disturbances]
    wind = [0.0, 0.0, 0.0]        # N, world frame
    wind_model = "my_wind.py:Gusty(speed=3)"   # a wind class (a velocity), beside the force
    gusts = 0.0                   # N, standard deviation per axis
    spread = 0.0                  # or {mass = 0.1, thrust = 0.05, drag = 0.2}

Every key is checked by a pydantic schema against the ranges the flags have
(:mod:`quadnav.limits`); a mistake in a file is one :class:`~quadnav.errors.QuadnavError`
naming the file, the line and the key (:func:`read_mission`). Plug-ins (the planner, the
controller, the reference, the wind model, a vehicle named by a spec) travel as their text:
each is loaded and checked with the mission (a bad one is refused before any work) and
built where it is used. Relative paths are resolved against the file's folder.

:meth:`MissionConfig.settings` is the one builder of
:class:`~quadnav.mission.MissionSettings` and :meth:`MissionConfig.problem` of the checked
query; :meth:`MissionConfig.flown` is what a run folder keeps (:meth:`MissionConfig.toml`).
"""

from quadnav.missionconfig.config import (
    MISSION_FILE,
    SPREAD_STREAM,
    MissionConfig,
    MissionFiles,
    read_mission,
    read_run_mission,
    spread_factors,
    spread_plant,
    vehicle_from,
)
from quadnav.missionconfig.sections import (
    SPREAD_PARTS,
    Controller,
    Disturbances,
    Planner,
    Query,
    Simulation,
    Spread,
    Trajectory,
)

__all__ = [
    "MISSION_FILE",
    "SPREAD_PARTS",
    "SPREAD_STREAM",
    "Controller",
    "Disturbances",
    "MissionConfig",
    "MissionFiles",
    "Planner",
    "Query",
    "Simulation",
    "Spread",
    "Trajectory",
    "read_mission",
    "read_run_mission",
    "spread_factors",
    "spread_plant",
    "vehicle_from",
]

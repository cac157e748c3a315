"""How the flags of a command that flies a mission become one
(:class:`~quadnav.missionconfig.MissionConfig`): a mission file (``--mission FILE``) or the
command's defaults, with every flag given set on top, so that ``fly``, ``tello fly`` and a
mission file build the same mission from the same settings."""

from __future__ import annotations

import argparse
from typing import Any

from quadnav.cli.flight_args import wind_arguments
from quadnav.missionconfig import MISSION_FILE, MissionConfig, read_mission

#: Each flag that sets a mission, by its argparse dest: its name and the key of a mission
#: file it sets (``--wind`` sets the wind model's key too: :func:`flag_keys`).
MISSION_FLAGS = {
    "map": ("MAP", "map"),
    "seed": ("--seed", "seed"),
    "params": ("--params", "vehicle"),
    "start": ("--start", "query.start"),
    "goal": ("--goal", "query.goal"),
    "start_goal": ("--start-goal", "query.start_goal"),
    "margin": ("--margin", "query.margin"),
    "planner": ("--planner", "planner.name"),
    "time": ("--time", "planner.time"),
    "iterations": ("--iterations", "planner.iterations"),
    "improve": ("--improve", "planner.improve"),
    "stall": ("--stall", "planner.stall"),
    "stall_fraction": ("--stall-fraction", "planner.stall_fraction"),
    "method": ("--method", "trajectory.method"),
    "timing": ("--timing", "trajectory.timing"),
    "speed": ("--speed", "trajectory.speed"),
    "accel": ("--accel", "trajectory.accel"),
    "reference": ("--reference", "trajectory.reference"),
    "duration": ("--duration", "trajectory.duration"),
    "controller": ("--controller", "controller.name"),
    "gains": ("--gains", "controller.gains"),
    "physics_rate": ("--physics-rate", "simulation.physics_rate"),
    "control_rate": ("--control-rate", "simulation.control_rate"),
    "settle": ("--settle", "simulation.settle"),
    "wind": ("--wind", "disturbances.wind"),
    "gusts": ("--gusts", "disturbances.gusts"),
}


def add_mission_argument(parser: argparse.ArgumentParser) -> None:
    """--mission FILE: the mission file the other flags are set on top of."""
    parser.add_argument("--mission", metavar="FILE",
                        help="fly the mission this file describes (a mission TOML file, e.g. "
                             f"a run folder's {MISSION_FILE}); the flags given set their keys "
                             "on top of it")


def mission_config(args: argparse.Namespace, base: MissionConfig | None = None
                   ) -> MissionConfig:
    """The mission the flags describe: ``--mission FILE`` if given, else ``base`` (default:
    :class:`MissionConfig`'s defaults), with every flag of :data:`MISSION_FLAGS` that was
    given (not None) set on top. QuadnavError naming the file and line, or the flag."""
    mission_file = getattr(args, "mission", None)
    if mission_file is not None:
        base = read_mission(mission_file)
    given = {dest: getattr(args, dest) for dest in MISSION_FLAGS
             if getattr(args, dest, None) is not None}
    changes = {key: value for dest, value in given.items()
               for key, value in flag_keys(dest, value).items()}
    names = {key: MISSION_FLAGS[dest][0] for dest, value in given.items()
             for key in flag_keys(dest, value)}
    return (base or MissionConfig()).with_changes(changes, names)


def flag_keys(dest: str, value: Any) -> dict[str, Any]:
    """The keys of a mission that the flag ``dest`` given as ``value`` sets: its key of
    :data:`MISSION_FLAGS`; for ``--wind``, FX FY FZ or one wind model's spec, the whole
    wind, the steady force and the wind model (one of them none)."""
    if dest == "wind":
        force, model = wind_arguments(value)
        return {"disturbances.wind": force, "disturbances.wind_model": model}
    return {MISSION_FLAGS[dest][1]: value}

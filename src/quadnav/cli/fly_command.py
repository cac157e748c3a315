"""``quadnav fly``: plan, smooth, fly in simulation and report — the main job."""

from __future__ import annotations

import argparse
from pathlib import Path

from quadnav.cli.args import (
    acceleration,
    add_map_argument,
    add_margin_argument,
    add_planner_arguments,
    add_run_output_arguments,
    add_start_goal_arguments,
    speed_or_max,
)
from quadnav.cli.commands import command_help
from quadnav.cli.flight_args import (
    add_controller_argument,
    add_duration_argument,
    add_simulation_arguments,
    add_strict_argument,
    add_timing_arguments,
    add_vehicle_arguments,
)
from quadnav.cli.flight_lines import (
    clearance_text,
    flight_failed,
    simulation_time,
    tracking_errors,
    warn_margin_shortfall,
)
from quadnav.cli.mission_args import add_mission_argument, mission_config
from quadnav.cli.progress import fraction_bar, planning_bar
from quadnav.control.registry import DEFAULT_CONTROLLER
from quadnav.limits import ACCELERATION, SPEED
from quadnav.mission import (
    DEFAULT_ACCELERATION,
    DEFAULT_IMPROVE,
    DEFAULT_SPEED,
    DEFAULT_TIME_CAP,
    Mission,
    failure_reason,
    fly_problem,
)
from quadnav.missionconfig import MissionConfig
from quadnav.report.run_writer import write_run
from quadnav.runfolder import check_output_folder
from quadnav.runs import FIGURES, REPORT

#: Exit code of a flight that collided, missed the goal or found no path.
EXIT_FAILED = 1


def fly(args: argparse.Namespace) -> int:
    """Run the mission, write the outputs; exit 1 unless it reached the goal cleanly."""
    config = mission_config(args)
    folder = check_output_folder(args.output)
    settings = config.settings()
    problem = config.problem(config.world(), settings.body)
    with planning_bar(f"plan ({config.planner.name})", args.quiet) as planning, \
            fraction_bar("fly", args.quiet) as flying:
        mission = fly_problem(problem, settings, planning, flying)
    return write_mission(mission, config, folder, figures=not args.no_figures, html=args.html,
                         strict=args.strict)


def write_mission(mission: Mission, config: MissionConfig, folder: Path, figures: bool,
                  html: bool, strict: bool = False) -> int:
    """Write the run folder of ``mission`` (built from ``config``), print its summary;
    returns the exit code: 0 when it reached the goal cleanly (and, if ``strict``, kept the
    whole margin asked), else :data:`EXIT_FAILED` (saying why on stderr)."""
    written = write_run(mission, folder, figures=figures, html=html, config=config)
    short = print_summary(mission)
    print("wrote " + ", ".join(str(folder / name) for name in written))
    failure = None if mission.success else failure_reason(mission)
    return EXIT_FAILED if flight_failed(failure, short, strict) else 0


def print_summary(mission: Mission) -> bool:
    """Print the outcome and headline figures of ``mission``, a few lines, and a warning
    line on stderr when the flight kept less margin than asked; returns whether it did."""
    m = mission.metrics()
    controller, reference = mission.settings.controller, mission.settings.reference
    flown_by = "" if controller == DEFAULT_CONTROLLER else f", controller {controller}"
    along = (f"top speed {m['speed_m_s']:.3g} m/s" if reference is None
             else f"reference {reference}")
    print(f"{m['map']}: {'success' if m['success'] else 'FAILED'}, {m['planner']} seed "
          f"{m['seed']}, vehicle {m['vehicle']}{flown_by}, {along}")
    if mission.flight is None:
        print(f"  no path after {m['planning_time_s']:.2f} s of planning")
        return False
    print(f"  path {m['path_length_m']:.2f} m, trajectory {m['trajectory_duration_s']:.2f} s, "
          f"flight {m['ending']} after {m['flight_time_s']:.2f} s")
    print(f"  {tracking_errors(m)}; {clearance_text(m)}")
    legs = ("" if m["trajectory_leg_margin_m"] is None else
            f"; on the legs out of it {m['trajectory_leg_margin_m']:.3f} m")
    print(f"  margin kept {m['trajectory_margin_m']:.3f} m by the trajectory and "
          f"{m['flight_margin_m']:.3f} m by the flight (asked {m['margin_m']:g} m){legs}")
    short = warn_margin_shortfall(m, mission.flight.t, mission.flight.position)
    print(f"  wall time: planning {m['planning_time_s']:.2f} s, trajectory "
          f"{m['trajectory_time_s']:.2f} s, {simulation_time(m)}")
    return short


def add_fly_command(subparsers: argparse._SubParsersAction) -> None:
    """Register ``quadnav fly`` on the top-level subparsers."""
    p = subparsers.add_parser(
        "fly", help=command_help("fly"),
        description="The whole pipeline: plan a path with RRT* through MAP, shortcut and "
                    "smooth it, make a trajectory (minimum snap by default) that cruises at "
                    "the top speed, and fly "
                    "it with a PX4-style cascaded controller on a simulated quadrotor. Writes "
                    "DIR/metrics.json, DIR/parameters.json, DIR/mission.toml (the mission, "
                    "which --mission flies again), DIR/map.json, DIR/tree.csv, "
                    "DIR/path.csv, DIR/trajectory.csv, DIR/flight.csv and the figures "
                    f"{', '.join(FIGURES)} and the report {REPORT}. Exit 0 when the vehicle "
                    "reaches the goal (within the goal tolerance of the point flown to) "
                    "without touching a block or hitting the floor, its body inside the map; "
                    "1 on a collision, hitting the floor, the body leaving the map, a missed "
                    "goal or no path (metrics.json is still written), and with --strict when "
                    "the flight kept less margin than asked; 2 on bad input.")
    add_map_argument(p, optional=True, unset=True)
    add_mission_argument(p)
    add_start_goal_arguments(p)
    add_margin_argument(p)
    p.add_argument("--speed", type=speed_or_max, metavar="V|max",
                   help=f"top speed of the trajectory, {SPEED.describe()}: never exceeded, "
                        "cruised at wherever the turns allow; max: as fast as the vehicle "
                        f"can follow on the path (default: {DEFAULT_SPEED:g})")
    p.add_argument("--accel", type=acceleration, metavar="A",
                   help=f"largest size of the acceleration vector, {ACCELERATION.describe()}"
                        ": one budget for speeding up, braking and turning (default: "
                        f"{DEFAULT_ACCELERATION:g}; ignored with --speed max)")
    add_timing_arguments(p, unset=True)
    p.add_argument("--reference", metavar="SPEC",
                   help="fly a trajectory class of your own instead of quadnav's trajectory "
                        "(--speed, --accel, --method and --timing then do not apply): "
                        "module:Class or path/to/file.py:Class in rotorpy's shape, optionally "
                        "with literal keyword arguments, Class(key=value, ...); built with "
                        "the path (shortcut, not smoothed) as points=(N, 3) when it takes "
                        "points, its update(t) sampled at the control rate")
    add_duration_argument(p)
    add_vehicle_arguments(p, unset=True)
    add_controller_argument(p, unset=True)
    add_planner_arguments(p, time=DEFAULT_TIME_CAP, iterations=0, improve=DEFAULT_IMPROVE,
                          unset=True)
    add_simulation_arguments(p, unset=True)
    add_strict_argument(p)
    add_run_output_arguments(p, "flight", REPORT)
    p.set_defaults(handler=fly)

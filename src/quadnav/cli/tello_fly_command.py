"""``quadnav tello fly``: plan like ``quadnav fly``, check, and fly it on a Tello.

Exit codes: 0 landed at the goal (the dead-reckoned landing place within the tolerance of
it), or a dry run printed; 1 no path, a landing off the goal, a safe stop (lost replies,
refused command, geofence) with the drone on the floor, a landing by itself (low
battery) or a refused takeoff (low battery); 2 bad input, including a plan that would
leave the geofence or that ``rc`` mode cannot fly; 3 a lost link: no landing confirmed;
128 + the signal after a stop signal (130 Ctrl-C, 143 SIGTERM, 129 SIGHUP), after the safe
stop.
"""

from __future__ import annotations

import argparse
import ipaddress
import math
import sys

from quadnav.cli.args import (
    acceleration,
    add_map_argument,
    add_margin_argument,
    add_planner_arguments,
    add_start_goal_arguments,
    heading_degrees,
    number_in,
    output_path,
    time_scale,
)
from quadnav.cli.mission_args import mission_config
from quadnav.cli.progress import planning_bar
from quadnav.errors import QuadnavError
from quadnav.hardware.bridge.flight import (
    LANDING_TOLERANCE,
    MIN_BATTERY,
    MODES,
    TRACK_FIGURE,
    BridgeSettings,
    Outcome,
    Status,
    fly,
)
from quadnav.hardware.bridge.flight_plan import (
    TRACKING_ALLOWANCE,
    NoPathError,
    SavedPlan,
    plan_flight,
)
from quadnav.hardware.bridge.link import TELLO_IP
from quadnav.hardware.bridge.rc import RC_FULL_SPEED
from quadnav.hardware.bridge.run_record import tello_run_content
from quadnav.hardware.bridge.tello_log import LOG_NAME
from quadnav.hardware.truth import TRUTH_FILE_HEADER, read_truth_file
from quadnav.limits import ACCELERATION, HEADING_DEGREES, SPEED, TIME_SCALE, Range
from quadnav.mission import DEFAULT_IMPROVE, DEFAULT_TIME_CAP
from quadnav.missionconfig import MissionConfig, Trajectory
from quadnav.report.run_writer import write_run
from quadnav.runfolder import check_output_folder, replaced_folder
from quadnav.runs import RUN_FILES
from quadnav.trajectory.pathfile import read_path_csv
from quadnav.trajectory.references.sampled import read_reference_file

#: Cruise speed and acceleration of a Tello flight, m/s and m/s^2 (indoors, gently).
DEFAULT_SPEED = 0.5
DEFAULT_ACCELERATION = 1.0
#: Exit codes besides 0 and 128 + a stop signal.
EXIT_FAILED = 1
EXIT_LINK_LOST = 3
#: The files tello fly writes.
TELLO_FILES = (LOG_NAME, TRACK_FIGURE)
_EXIT_CODES = {Status.LANDED: 0, Status.DRY_RUN: 0, Status.OFF_GOAL: EXIT_FAILED,
               Status.STOPPED: EXIT_FAILED, Status.AUTO_LANDED: EXIT_FAILED,
               Status.REFUSED: EXIT_FAILED, Status.LINK_LOST: EXIT_LINK_LOST}


#: Cruise speeds, m/s: up to the Tello's go and rc limit.
TELLO_SPEED = Range(SPEED.low, RC_FULL_SPEED, "m/s")
#: argparse type of --speed.
tello_speed = number_in(TELLO_SPEED)


def ipv4(text: str) -> str:
    """argparse type: an IPv4 address."""
    try:
        return str(ipaddress.IPv4Address(text))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an IPv4 address, got {text!r}") from None


def percent(text: str) -> int:
    """argparse type: a whole percentage, 0..100."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole percentage, got {text!r}") from None
    if not 0 <= value <= 100:
        raise argparse.ArgumentTypeError(f"expected 0..100 percent, got {text!r}")
    return value


def exit_code(outcome: Outcome) -> int:
    """The exit code of a flight that ended with ``outcome`` (see the module)."""
    if outcome.signum is not None:
        return 128 + outcome.signum
    return _EXIT_CODES[outcome.status]


def _saved_plan(args: argparse.Namespace) -> SavedPlan | None:
    """The saved path or trajectory the flags name, or None: plan one."""
    if args.path is None and args.trajectory is None:
        return None
    flag, file = ("--path", args.path) if args.path is not None else (
        "--trajectory", args.trajectory)
    if args.path is not None and args.trajectory is not None:
        raise QuadnavError("--path and --trajectory: give one saved plan")
    if any(v is not None for v in (args.start, args.goal, args.start_goal)):
        raise QuadnavError(f"{flag} {file}: its ends are the start and goal; leave out "
                           "--start, --goal and --start-goal")
    if args.path is not None:
        return SavedPlan(read_path_csv(args.path), args.path)
    reference = read_reference_file(args.trajectory)
    return SavedPlan(reference.samples.position, args.trajectory, reference.motion)


#: A Tello mission's defaults: :class:`MissionConfig`'s with a gentle indoor speed.
TELLO_MISSION = MissionConfig(trajectory=Trajectory(speed=DEFAULT_SPEED,
                                                    accel=DEFAULT_ACCELERATION))


def tello_fly(args: argparse.Namespace) -> int:
    """Plan, check and fly (or print) the mission; the exit code says how it ended."""
    config = mission_config(args, TELLO_MISSION)
    mission = config.settings()
    settings = BridgeSettings(mode=args.mode, min_battery=args.min_battery,
                              time_scale=args.time_scale)
    folder = check_output_folder(args.output)
    if args.truth is not None:
        read_truth_file(args.truth)  # a file that cannot be read is bad input: before flying
    world = config.world()
    saved = _saved_plan(args)
    start, goal = (None, None) if saved is not None else config.ends(world)
    try:
        with planning_bar(f"plan ({mission.planner})", args.quiet or saved is not None
                          ) as progress:
            plan = plan_flight(world, start, goal, config.margin(world), math.radians(args.yaw),
                               mission.planner, mission.planning, mission.trajectory, progress,
                               saved)
    except NoPathError as error:
        print(f"quadnav: tello: {error}", file=sys.stderr)
        return EXIT_FAILED
    # The log is written as the flight goes: whatever ends the flight (a safe stop, an
    # error, Ctrl-C, SIGTERM), the folder gets the new log and, if it was drawn, the figure.
    # A dry run flies nothing: one that fails leaves the folder as it was.
    # The earlier run's folder files go with the new log: the run folder written next
    # (what report, view, animate and blender read) is never another flight's.
    host = None if args.dry_run else args.host
    with replaced_folder(folder, (*TELLO_FILES, *RUN_FILES), keep_partial=host is not None
                         ) as staging:
        flown = fly(plan, settings, staging, host=host, truth=args.truth)
    written = write_run(tello_run_content(plan, settings, flown, host), folder,
                        figures=not args.no_figures)
    outcome, code = flown.outcome, exit_code(flown.outcome)
    print(f"quadnav: tello: {outcome.status.value}: {outcome.message}",
          file=sys.stdout if code == 0 else sys.stderr)
    print(f"wrote {', '.join(str(folder / name) for name in (LOG_NAME, TRACK_FIGURE, *written))}")
    return code


def add_tello_fly_command(subparsers: argparse._SubParsersAction) -> None:
    """Register ``quadnav tello fly``."""
    p = subparsers.add_parser(
        "fly", help="plan a flight as 'quadnav fly' does and fly it on a Tello",
        description="Plan a path through MAP as 'quadnav fly' does, with the margin plus "
                    f"{TRACKING_ALLOWANCE:g} m; check every move against the geofence (the "
                    "map shrunk by the margin; a start or goal inside the margin is left or "
                    "entered by the planner's leg, which with the takeoff or landing column "
                    "may come no closer to a block than the start or goal itself and never "
                    "leave the boundary); then take off from the floor under the "
                    "start (the drone facing --yaw), fly it with 'go' moves (waypoints), "
                    "'curve' and 'go' commands along the trajectory (curves) or "
                    "'rc' sticks following the trajectory (rc; each stick slow enough that "
                    "a link lost for the Tello's 15 s keeps the drone inside the geofence), "
                    "and land on the floor under the goal. Below --min-battery, or too low "
                    "for the flight, the takeoff is refused; no reply or state for 1 s, a "
                    "refused command, Ctrl-C, SIGTERM or SIGHUP stop the drone and land it; "
                    "below 10 % battery in flight the Tello lands by itself and the bridge "
                    f"waits for it. Writes DIR/{LOG_NAME} (every command, reply and state "
                    f"packet), DIR/{TRACK_FIGURE} (planned against flown) and a run folder "
                    "as 'quadnav fly' does (map, tree, planned path and trajectory, the "
                    "flown track as flight.csv, metrics, figures, report), which 'quadnav "
                    "report', 'view', 'animate' and 'blender' read. The last line gives "
                    "the landing place the bridge's dead reckoning puts the drone at, with "
                    "its 1-sigma uncertainty. Exit 0 when landed at the goal (that place "
                    f"within {LANDING_TOLERANCE:g} m of it); 1 on a landing off the goal, a "
                    "safe stop, a landing by itself, a refused "
                    "takeoff or no path; 2 on bad input; 3 when the link was lost and no "
                    "landing was confirmed; 128 + the signal (130 Ctrl-C, 143 SIGTERM, 129 "
                    "SIGHUP) after a stop signal.")
    add_map_argument(p)
    add_start_goal_arguments(p)
    add_margin_argument(p)
    p.add_argument("--path", metavar="CSV",
                   help="fly this saved path (header x,y,z, one waypoint per row in metres, "
                        "e.g. your own planner's output or 'quadnav plan' path.csv) instead "
                        "of planning one: its first and last rows are the start and goal, and "
                        "it goes through the same checks (every segment keeps the margin plus "
                        f"{TRACKING_ALLOWANCE:g} m, except the legs out of and into the margin "
                        "at a start or goal inside it)")
    p.add_argument("--trajectory", metavar="FILE",
                   help="fly this saved trajectory (a 'quadnav traj' trajectory.csv, or the "
                        "course's MP.csv read at 20 Hz) instead of planning one: its first "
                        "and last samples are the start and goal, which must be at rest "
                        "outside the margin; its samples' path goes through the same checks "
                        "as --path, and the trajectory itself through the geofence's; rc mode "
                        "follows it as timed, waypoints mode flies go moves through its "
                        "corners")
    p.add_argument("--mode", choices=MODES, default="waypoints",
                   help="'go' moves through the path's corners; 'curve' and 'go' commands "
                        "following the trajectory within 5 cm (curves); or 'rc' sticks at 20 "
                        "Hz following the trajectory (default: waypoints)")
    p.add_argument("--yaw", type=heading_degrees, default=0.0, metavar="DEG",
                   help="map heading the drone faces on the floor, counter-clockwise from "
                        f"+x, {HEADING_DEGREES.describe()} (default: 0, facing +x)")
    p.add_argument("--speed", type=tello_speed, metavar="V",
                   help=f"cruise speed, {TELLO_SPEED.describe()} (the Tello's go and rc "
                        f"limit; default: {DEFAULT_SPEED:g})")
    p.add_argument("--accel", type=acceleration, metavar="A",
                   help=f"largest acceleration of the trajectory, {ACCELERATION.describe()} "
                        f"(default: {DEFAULT_ACCELERATION:g})")
    add_planner_arguments(p, time=DEFAULT_TIME_CAP, iterations=0, improve=DEFAULT_IMPROVE,
                          unset=True)
    p.add_argument("--dry-run", action="store_true",
                   help="print every command instead of sending it (needs no drone)")
    p.add_argument("--host", type=ipv4, default=TELLO_IP, metavar="IP",
                   help=f"the drone's address (default: {TELLO_IP}, the Tello's own Wi-Fi)")
    p.add_argument("--min-battery", type=percent, default=MIN_BATTERY, metavar="PCT",
                   help=f"refuse to take off below this battery (default: {MIN_BATTERY} %%)")
    p.add_argument("--time-scale", type=time_scale, default=1.0, metavar="K",
                   help=f"drone seconds per wall-clock second, {TIME_SCALE.describe()}: 1 "
                        "for a real drone, the emulator's --time-scale for an emulated one "
                        "(default: 1)")
    p.add_argument("--truth", metavar="FILE",
                   help="the drone's true track, as 'quadnav tello emulate --truth FILE' "
                        "writes it while it flies (or a motion-capture system beside a real "
                        f"drone: header {TRUTH_FILE_HEADER}, UNIX seconds and map metres): "
                        "after the landing, its rows from this flight are copied into DIR/"
                        "truth.csv, and the metrics, report and view show the estimate "
                        "against it")
    p.add_argument("--no-figures", action="store_true",
                   help="write the run folder's data files but not its figures and report")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument("-o", "--output", type=output_path, default="tello_flight", metavar="DIR",
                   help="folder to write into, created if needed (default: tello_flight)")
    p.set_defaults(handler=tello_fly)

"""``quadnav track``: fly a given reference — a built-in one, a trajectory.csv, the course's
MP.csv or a trajectory class of your own — and report how well it was tracked (the course's
gain-tuning workflow)."""

from __future__ import annotations

import argparse
import sys

from quadnav.cli.args import (
    add_run_output_arguments,
    add_seed_argument,
    number_in,
)
from quadnav.cli.commands import command_help
from quadnav.cli.flight_args import (
    add_controller_argument,
    add_duration_argument,
    add_simulation_arguments,
    add_vehicle_arguments,
    simulation_settings,
    vehicle_and_gains,
)
from quadnav.cli.flight_lines import simulation_time, tracking_errors
from quadnav.cli.fly_command import EXIT_FAILED
from quadnav.cli.progress import fraction_bar
from quadnav.errors import QuadnavError
from quadnav.mission import flight_failure
from quadnav.runfolder import check_output_folder
from quadnav.runs import FIGURES, REPORT
from quadnav.sim.settings import SimSettings
from quadnav.trajectory.references.contract import Reference
from quadnav.trajectory.references.plain import FORMAT as CLASS_FORMAT
from quadnav.trajectory.references.plain import is_trajectory_class
from quadnav.trajectory.references.sampled import COURSE_MP_RATE, MP_FORMAT, MP_RATE, TABLE_FORMAT


def track(args: argparse.Namespace) -> int:
    """Read the reference, fly it, write the run folder; exit 1 unless the flight ran to
    the end and finished within the goal tolerance of the reference's end."""
    from quadnav.report.run_writer import write_run
    from quadnav.tracking import track_reference
    from quadnav.trajectory.references.builtin import load_reference

    folder = check_output_folder(args.output)
    vehicle, gains = vehicle_and_gains(args)
    settings = simulation_settings(args)
    if args.duration is not None and not is_trajectory_class(args.reference):
        raise QuadnavError(f"--duration: applies only to a trajectory class of your own "
                           f"(module:Class or path/to/file.py:Class), not to {args.reference}")
    reference = load_reference(args.reference, args.rate or COURSE_MP_RATE,
                               1.0 / settings.control_rate, args.duration)
    if args.rate is not None and getattr(reference, "format", None) != MP_FORMAT:
        raise QuadnavError(f"--rate: applies only to an MP.csv file (which has no times), "
                           f"not to {args.reference}")
    print(how_read(reference))
    with fraction_bar("fly", args.quiet) as flying:
        tracking = track_reference(reference, vehicle, gains, settings, flying,
                                   args.controller)
    written = write_run(tracking, folder, figures=not args.no_figures, html=args.html)
    _print_summary(tracking.metrics())
    print("wrote " + ", ".join(str(folder / name) for name in written))
    if not tracking.success:
        failure = flight_failure(tracking.flight, settings.goal_tolerance,
                                 "the reference's end")
        print(f"quadnav: flight failed: {failure}", file=sys.stderr)
        return EXIT_FAILED
    return 0


def how_read(reference: Reference) -> str:
    """One line: the reference's name, how a file's samples were timed, and its duration."""
    info = getattr(reference, "info", {})
    duration = f"a {reference.duration:.2f} s reference"
    if info.get("format") == MP_FORMAT:
        return (f"{reference.name}: {info['samples']:,} samples read as every "
                f"{info['sample_interval_s']:g} s (--rate {info['rate_hz']:g} Hz): {duration}")
    if info.get("format") == TABLE_FORMAT:
        return (f"{reference.name}: {info['samples']:,} samples at their own times "
                f"(column t): {duration}")
    if info.get("format") == CLASS_FORMAT:
        said = {"given": "--duration", "duration": "its duration",
                "t_keyframes": "its t_keyframes"}[info["duration_from"]]
        return (f"{reference.name}: update(t) sampled {info['samples']:,} times, every "
                f"{info['sample_interval_s']:g} s (the control rate): {duration} ({said})")
    return f"{reference.name}: {duration}"


def _print_summary(m: dict) -> None:
    from quadnav.tracking import step_summary

    print(f"{m['reference']}: {'success' if m['success'] else 'FAILED'}, vehicle "
          f"{m['vehicle']}, flight {m['ending']} after {m['flight_time_s']:.2f} s")
    print(f"  {tracking_errors(m)}; max velocity error "
          f"{m['max_velocity_error_m_s']:.3f} m/s; mixer saturated "
          f"{100 * m['mixer_saturation']:.1f} % of steps")
    if "overshoot_percent" in m:
        print(f"  {step_summary(m)}")
    print(f"  wall time: {simulation_time(m)}")


def add_track_command(subparsers: argparse._SubParsersAction) -> None:
    """Register ``quadnav track`` on the top-level subparsers."""
    p = subparsers.add_parser(
        "track", help=command_help("track"),
        description="Fly a reference with the PX4-style cascaded controller on the "
                    "simulated quadrotor, from a hover at its start, in an empty box round "
                    "it (1 m beyond its bounding box; the floor at z = 0 when it stays "
                    "0.3 m above it), and report how well it was tracked: the course's "
                    "gain-tuning workflow. Writes DIR/metrics.json (with overshoot, rise "
                    "and settling times and steady-state error for a step), "
                    "DIR/parameters.json, DIR/map.json, DIR/trajectory.csv, DIR/flight.csv, "
                    f"the figures {', '.join(FIGURES)} and the report {REPORT}. Exit 0 when "
                    "the flight runs to the end and finishes within "
                    f"{100 * SimSettings.goal_tolerance:g} cm of the reference's end; 1 when "
                    "it does not (it diverged, left the box, hit the floor, its body "
                    "left the box or it ended too far); 2 on bad input.")
    p.add_argument("reference", metavar="REF",
                   help="a built-in reference spec (quadnav references lists them), e.g. "
                        "step:axis=z,size=0.5 or helix:radius=2,speed=1.5; or a file: "
                        "quadnav's trajectory.csv (header t,x,y,...,yaw: its own times) "
                        "or the course's MP.csv (9 rows x, y, z, vx, vy, vz, ax, ay, az, one "
                        "column per sample, read as every 1/--rate s); or a trajectory "
                        "class of your own in rotorpy's shape, module:Class or "
                        "path/to/file.py:Class, optionally with literal keyword arguments, "
                        "Class(key=value, ...): update(t) returns the flat outputs x, x_dot, "
                        "x_ddot, yaw, yaw_dot, sampled at the control rate")
    p.add_argument("--rate", type=number_in(MP_RATE), metavar="HZ",
                   help=f"columns per second of an MP.csv, {MP_RATE.describe()} (default: "
                        f"{COURSE_MP_RATE:g}, as the course's code plays it: one column every "
                        f"{1 / COURSE_MP_RATE:g} s; quadnav traj writes one every --dt, 0.01 "
                        "s by default: --rate 100)")
    add_duration_argument(p)
    add_vehicle_arguments(p)
    add_controller_argument(p)
    add_seed_argument(p, "seed of the gusts")
    add_simulation_arguments(p)
    add_run_output_arguments(p, "track", REPORT)
    p.set_defaults(handler=track)

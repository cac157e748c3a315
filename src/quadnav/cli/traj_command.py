"""``quadnav traj``: a trajectory through a path: CSV, MP.csv, JSON summary, figures."""

from __future__ import annotations

import argparse
import json

from quadnav.cli.args import (
    acceleration,
    add_map_argument,
    add_margin_argument,
    number_in,
    output_path,
    resolve_margin,
    speed,
)
from quadnav.cli.commands import command_help
from quadnav.cli.flight_args import (
    add_timing_arguments,
)
from quadnav.limits import (
    ACCELERATION,
    MAX_DURATION,
    MAX_SAMPLES,
    SAMPLE_INTERVAL,
    SPEED,
    check_count,
    check_duration,
)
from quadnav.planning.result import path_length
from quadnav.runfolder import check_output_folder, replaced_folder
from quadnav.trajectory.clearance.space import SafeSpace, trajectory_margins
from quadnav.trajectory.feasibility import Limits, feasibility
from quadnav.trajectory.generate import TrajectorySettings, make_trajectory
from quadnav.trajectory.model import YawMode
from quadnav.trajectory.pathfile import read_path_csv
from quadnav.trajectory.references.export import mp_csv, trajectory_csv
from quadnav.trajectory.references.sampled import COURSE_MP_RATE
from quadnav.trajectory.timing.segment_times import DEFAULT_A_MAX, DEFAULT_V_MAX
from quadnav.world import load_world

#: Default sample interval of the CSV outputs, s.
DEFAULT_DT = 0.01
#: The files traj writes.
TRAJ_FILES = ("trajectory.csv", "MP.csv", "trajectory.json", "trajectory.png", "states.png")


def traj(args: argparse.Namespace) -> int:
    """Make the trajectory, check it, and write the five output files."""
    from quadnav.viz.figures import save_figure
    from quadnav.viz.trajectory_figures import states_figure, trajectory_3d_figure

    folder = check_output_folder(args.output)
    settings = TrajectorySettings(method=args.method, v_max=args.speed, a_max=args.accel,
                                  timing=args.timing, corridor=args.corridor,
                                  yaw=YawMode(args.yaw))
    world = load_world(args.map)
    path = read_path_csv(args.path)
    shortest = path_length(path) / args.speed
    check_duration(shortest, "raise --speed", at_least=True)
    finest = min(args.dt, args.mp_dt)
    check_count(shortest / finest + 1, MAX_SAMPLES, f"a trajectory of at least "
                f"{shortest:.6g} s sampled every {finest:g} s gives samples",
                "raise --dt, --mp-dt or --speed")
    space = SafeSpace(world, resolve_margin(args, world))
    trajectory = make_trajectory(path, settings, space)
    check_duration(trajectory.duration, "raise --speed or --accel")
    # Clearance to the real blocks; a path may start on the boundary itself.
    limits = Limits(v_max=args.speed, a_max=args.accel)
    report = feasibility(trajectory, space.legs_world, limits, dt=args.dt)
    kept, kept_on_legs = trajectory_margins(trajectory, world)
    summary = {
        "map": world.name, "path": str(args.path), "method": trajectory.method,
        "timing": settings.timing, "speed": settings.v_max, "acceleration": settings.a_max,
        "margin": space.margin, "margin_kept": kept, "margin_kept_on_legs": kept_on_legs,
        "legs": list(trajectory.legs), "duration": trajectory.duration,
        "waypoints_in": len(path), "waypoints": len(trajectory.waypoints),
        "segment_times": trajectory.segment_times.tolist(), "yaw": settings.yaw.value,
        "info": trajectory.info, "feasibility": report.as_dict(),
    }
    with replaced_folder(folder, TRAJ_FILES) as staging:
        for name, text in (("trajectory.csv", trajectory_csv(trajectory, args.dt)),
                           ("MP.csv", mp_csv(trajectory, args.mp_dt)),
                           ("trajectory.json", json.dumps(summary, indent=2) + "\n")):
            (staging / name).write_text(text)
        save_figure(trajectory_3d_figure(world, trajectory, path), staging / "trajectory.png")
        save_figure(states_figure(trajectory, args.speed, args.accel), staging / "states.png")
    print(f"{world.name}: {trajectory.method} through {len(trajectory.waypoints)} waypoints "
          f"({len(path)} in the path), {trajectory.duration:.2f} s")
    print(report.summary())
    print(f"  margin kept {kept:.3g} m (asked {space.margin:g} m)" + (
        "" if kept_on_legs is None else f", {kept_on_legs:.3g} m on the legs out of it"))
    print("wrote " + ", ".join(str(folder / name) for name in TRAJ_FILES))
    return 0


def add_traj_command(subparsers: argparse._SubParsersAction) -> None:
    """Register ``quadnav traj`` on the top-level subparsers."""
    p = subparsers.add_parser(
        "traj", help=command_help("traj"),
        description="Turn a path (e.g. DIR/path.csv from quadnav plan) into a smooth, timed "
                    "trajectory that stays in the map's free space, and write "
                    "DIR/trajectory.csv, DIR/MP.csv (the course layout), DIR/trajectory.json "
                    "(summary and feasibility), DIR/trajectory.png and DIR/states.png.")
    add_map_argument(p)
    p.add_argument("--path", required=True, metavar="CSV",
                   help="waypoints: a CSV with header x,y,z (as quadnav plan writes)")
    add_margin_argument(p)
    p.add_argument("--speed", "--vmax", type=speed, default=DEFAULT_V_MAX, metavar="V",
                   help=f"top speed, {SPEED.describe()}, as for quadnav fly (default: "
                        f"{DEFAULT_V_MAX:g})")
    p.add_argument("--accel", "--amax", type=acceleration, default=DEFAULT_A_MAX,
                   metavar="A", help=f"largest size of the acceleration vector, "
                                     f"{ACCELERATION.describe()} (default: {DEFAULT_A_MAX:g})")
    add_timing_arguments(p)
    p.add_argument("--corridor", action="store_true",
                   help="minsnap as a QP inside safe corridors around the path")
    p.add_argument("--yaw", choices=[m.value for m in YawMode], default="constant",
                   help="yaw reference (default: constant)")
    p.add_argument("--dt", type=number_in(SAMPLE_INTERVAL), default=DEFAULT_DT, metavar="S",
                   help=f"sample interval of trajectory.csv, {SAMPLE_INTERVAL.describe()} "
                        f"(default: {DEFAULT_DT:g}); the trajectory may last at most "
                        f"{MAX_DURATION:g} s and give at most {MAX_SAMPLES:,} samples")
    p.add_argument("--mp-dt", type=number_in(SAMPLE_INTERVAL), default=1 / COURSE_MP_RATE,
                   metavar="S",
                   help="sample interval of MP.csv, which has no times: the course's code "
                        f"plays one column every {1 / COURSE_MP_RATE:g} s, and quadnav track "
                        f"reads one at that rate by default (default: {1 / COURSE_MP_RATE:g})")
    p.add_argument("-o", "--output", type=output_path, default="traj", metavar="DIR",
                   help="folder to write into, created if needed (default: traj)")
    p.set_defaults(handler=traj)

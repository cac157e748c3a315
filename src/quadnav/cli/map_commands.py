"""``quadnav map info|check|show|convert|list|fetch`` (``maps`` is another name for ``map``)."""

from __future__ import annotations

import argparse

from quadnav.cli.args import (
    add_map_argument,
    add_margin_argument,
    add_start_goal_arguments,
    output_path,
    plan_time,
    resolve_margin,
    resolve_start_goal,
)
from quadnav.cli.commands import COMMANDS, command_help
from quadnav.cli.course_commands import add_course_commands
from quadnav.errors import QuadnavError
from quadnav.limits import PLAN_TIME
from quadnav.planning import PlannerSettings, make_problem
from quadnav.planning import plan as run_planner
from quadnav.world import load_world, write_map
from quadnav.world.model import ESTIMATE_POINTS, FreeVolume
from quadnav.world.placement import classify_point, format_point

#: Exit code of ``map check`` when neither a path nor a proof that none exists was found.
EXIT_UNDECIDED = 1
#: Default time ``map check`` searches for a path, s.
CHECK_TIME = 5.0


def free_volume_text(free: FreeVolume) -> str:
    """``"97.53 %"``, or for an estimate ``"97.53 % +- 0.10 % (estimated from 100,000
    random points; the exact figure would take too long)"``."""
    if free.exact:
        return f"{100 * free.fraction:.2f} %"
    return (f"{100 * free.fraction:.2f} % +- {100 * free.error:.2f} % (estimated from "
            f"{ESTIMATE_POINTS:,} random points; the exact figure would take too long)")


def info(args: argparse.Namespace) -> int:
    """Print bounds, block count, free-volume fraction, and start/goal/margin if present."""
    world = load_world(args.map)
    lower, upper = world.lower, world.upper
    print(f"map:         {world.name}")
    print("bounds:      " + ", ".join(f"{a} {lower[i]:g} .. {upper[i]:g}"
                                      for i, a in enumerate("xyz")) + " m")
    print("size:        " + " x ".join(f"{e:g}" for e in world.extent) + " m")
    print(f"blocks:      {len(world)}")
    print(f"free volume: {free_volume_text(world.free_volume())}")
    for label, point in (("start", world.start), ("goal", world.goal)):
        if point is not None:
            print(f"{label + ':':<12} {format_point(point)}")
    if world.margin is not None:
        print(f"margin:      {world.margin:g} m")
    return 0


def check(args: argparse.Namespace) -> int:
    """Say where start and goal lie and whether a path joins them; exit 2 if one is in a
    block or outside the boundary, or no path exists; 1 if the search could not decide."""
    world = load_world(args.map)
    margin = resolve_margin(args, world)
    start, goal = resolve_start_goal(args, world)
    points = [(label, p) for label, p in (("start", start), ("goal", goal)) if p is not None]
    if not points:
        raise QuadnavError(f"{world.name}: the map has no start or goal; "
                           "pass --start X Y Z and/or --goal X Y Z")
    reports = [classify_point(world, point, margin, label) for label, point in points]
    print(f"{world.name}: margin {margin:g} m")
    for report in reports:
        print(report)
    bad = [r for r in reports if not r.usable]
    if bad:
        names = " and ".join(f"{r.label} {format_point(r.point)} is {r.placement.value}"
                             for r in bad)
        raise QuadnavError(f"{world.name}: {names}; expected points inside the boundary "
                           "and outside every block")
    if len(points) < 2:
        return 0
    problem = make_problem(world, start, goal, margin)  # a proven disconnection: exit 2
    result = run_planner(problem, PlannerSettings(stop_at_first=True, time_limit=args.time))
    if not result.solved:
        print(f"connected: undecided: {result.message}; and no proof that no path exists "
              "was found")
        return EXIT_UNDECIDED
    print(f"connected: yes, a path of {result.length:.3f} m joins them (found in "
          f"{result.stats.seconds:.3g} s)")
    return 0


def show(args: argparse.Namespace) -> int:
    """Write a 3D figure of the map with start (red) and goal (green)."""
    from quadnav.viz.figures import check_figure_path, save_figure
    from quadnav.viz.map3d import world_figure

    check_figure_path(args.output)
    world = load_world(args.map)
    start, goal = resolve_start_goal(args, world)
    save_figure(world_figure(world, start, goal), args.output)
    print(f"wrote {args.output}")
    return 0


def convert(args: argparse.Namespace) -> int:
    """Write a map in the format named by the output's extension (.json or .txt)."""
    world = load_world(args.input)
    write_map(world, args.output)
    print(f"wrote {args.output} ({len(world)} blocks)")
    return 0


def add_map_commands(subparsers: argparse._SubParsersAction) -> None:
    """Register ``quadnav map ...`` (and its other name ``maps``) on the top-level
    subparsers."""
    parser = subparsers.add_parser("map", help=command_help("map"),
                                   aliases=COMMANDS["map"].aliases,
                                   description="Inspect, check, draw and convert maps; list "
                                               "and fetch the public course maps. 'quadnav "
                                               "maps' is another name for 'quadnav map'.")
    commands = parser.add_subparsers(dest="map_command", metavar="COMMAND", required=True)

    p = commands.add_parser("info", help="bounds, block count, free volume, start/goal",
                            description="Print a map's bounds, block count, free-volume "
                                        "fraction and, if it has them, start, goal and margin.")
    add_map_argument(p)
    p.set_defaults(handler=info)

    p = commands.add_parser("check", help="where start and goal lie, and whether a path "
                                          "joins them",
                            description="Say whether start and goal lie in free space, inside "
                                        "the safety margin, inside a block (which one) or "
                                        "outside the boundary, and whether a path joins them "
                                        "(proved by finding one, or disproved by a voxel "
                                        "over-approximation of free space). Exit 0 when one "
                                        "does; 2 if a point is unusable or provably no path "
                                        "exists; 1 if the search ran out of time undecided.")
    add_map_argument(p)
    add_margin_argument(p)
    add_start_goal_arguments(p)
    p.add_argument("--time", type=plan_time, default=CHECK_TIME, metavar="S",
                   help=f"time to search for a path, {PLAN_TIME.describe()} "
                        f"(default: {CHECK_TIME:g})")
    p.set_defaults(handler=check)

    p = commands.add_parser("show", help="draw the map in 3D",
                            description="Draw the map in 3D: blocks in their colours, the "
                                        "boundary transparent, start red, goal green.")
    add_map_argument(p, optional=True)
    add_start_goal_arguments(p)
    p.add_argument("-o", "--output", type=output_path, default="map.png", metavar="FILE",
                   help="image to write (.png, .pdf, .svg; default: map.png)")
    p.set_defaults(handler=show)

    p = commands.add_parser("convert", help="text <-> JSON",
                            description="Convert a map between the text and JSON formats; the "
                                        "output's extension picks the format (.json or "
                                        ".txt). IN may be a built-in world spec or a "
                                        "course map.")
    p.add_argument("input", metavar="IN", help="map file, built-in world spec or course map")
    p.add_argument("output", metavar="OUT", help="file to write (.json or .txt)")
    p.set_defaults(handler=convert)

    add_course_commands(commands)


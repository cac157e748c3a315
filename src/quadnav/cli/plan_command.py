"""``quadnav plan``: plan a path, post-process it, write path.csv, plan.json, plan.png."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from quadnav.cli.args import (
    add_map_argument,
    add_margin_argument,
    add_planner_arguments,
    add_start_goal_arguments,
    length,
    output_path,
    planner_budget,
    probability,
    resolve_margin,
    resolve_start_goal,
)
from quadnav.cli.commands import command_help
from quadnav.cli.progress import planning_bar
from quadnav.limits import LENGTH
from quadnav.planning import PlannerSettings, PlanningProblem, PlanResult, get_planner, make_problem
from quadnav.planning import plan as run_planner
from quadnav.planning.refine import refine
from quadnav.planning.report import path_csv, plan_summary
from quadnav.planning.settings import DEFAULT_TIME_LIMIT
from quadnav.runfolder import check_output_folder, replaced_folder
from quadnav.world import load_world

#: Exit code when the search ends without a path (the input itself was fine).
EXIT_NO_PATH = 1
#: The files plan writes (path.csv only with a path).
PLAN_FILES = ("path.csv", "plan.json", "plan.png")


def settings_from(args: argparse.Namespace) -> PlannerSettings:
    """Planner settings from the command-line flags."""
    return planner_budget(args).replace(stop_at_first=args.first, step=args.step,
                                        goal_bias=args.goal_bias,
                                        goal_tolerance=args.goal_tolerance)


def plan(args: argparse.Namespace) -> int:
    """Plan, refine and write the output files; exit 1 if no path was found."""
    get_planner(args.planner)
    folder = check_output_folder(args.output)
    settings = settings_from(args)
    world = load_world(args.map)
    start, goal = resolve_start_goal(args, world)
    problem = make_problem(world, start, goal, resolve_margin(args, world))
    with planning_bar(args.planner, args.quiet) as progress:
        result = run_planner(problem, settings, args.planner, progress)
    raw_length = result.length
    if not args.no_refine:
        result = refine(problem, result)
    with replaced_folder(folder, PLAN_FILES) as staging:
        if result.solved:
            (staging / "path.csv").write_text(path_csv(result.path))
        (staging / "plan.json").write_text(
            json.dumps(plan_summary(problem, result, settings, raw_length), indent=2) + "\n")
        if not args.no_figures:
            _save_plan_figure(problem, result, staging / "plan.png")
    _print_summary(problem.world.name, result, raw_length)
    written = [name for name in PLAN_FILES if (folder / name).exists()]
    print("wrote " + ", ".join(str(folder / name) for name in written))
    if not result.solved:
        print(f"quadnav: no path: {result.message}", file=sys.stderr)
        return EXIT_NO_PATH
    return 0


def _save_plan_figure(problem: PlanningProblem, result: PlanResult, path: Path) -> None:
    """Draw the tree and path into the image file ``path`` (matplotlib loads only here)."""
    from quadnav.viz.figures import save_figure
    from quadnav.viz.plan_figure import plan_figure

    save_figure(plan_figure(problem, result), path)


def _print_summary(name: str, result, raw_length: float) -> None:
    stats = result.stats
    first = ("no solution" if stats.time_to_first is None
             else f"first after {1e3 * stats.time_to_first:.3g} ms")
    print(f"{name}: {result.planner}, seed {result.seed}: {stats.iterations:,} iterations, "
          f"{stats.nodes:,} nodes in {stats.seconds:.3g} s, {first}")
    if result.solved:
        print(f"  search:   {raw_length:.3f} m")
        for step in stats.post:
            print(f"  {step.name + ':':<9} {step.length:.3f} m ({step.vertices} vertices)")


def add_plan_command(subparsers: argparse._SubParsersAction) -> None:
    """Register ``quadnav plan`` on the top-level subparsers."""
    p = subparsers.add_parser(
        "plan", help=command_help("plan"),
        description="Plan a collision-free path through MAP with RRT* (or an OMPL planner), "
                    "shortcut and smooth it, and write DIR/path.csv (x,y,z per vertex), "
                    "DIR/plan.json (statistics) and DIR/plan.png (tree and path; not with "
                    "--no-figures). Exit 1 "
                    "when no path is found within the budget (plan.json and plan.png are "
                    "still written), 2 on bad input.")
    add_map_argument(p, optional=True)
    add_start_goal_arguments(p)
    add_margin_argument(p)
    add_planner_arguments(p, time=DEFAULT_TIME_LIMIT, iterations=0, improve=None)
    p.add_argument("--first", action="store_true",
                   help="stop at the first solution instead of improving it")
    p.add_argument("--step", type=length, metavar="M",
                   help=f"largest tree edge, {LENGTH.describe()} (default: 5%% of the map's "
                        "diagonal)")
    p.add_argument("--goal-bias", type=probability, default=PlannerSettings.goal_bias,
                   metavar="P", help="probability of sampling the goal (default: 0.05)")
    p.add_argument("--goal-tolerance", type=length, metavar="M",
                   help=f"join the goal from vertices this close, {LENGTH.describe()} "
                        "(default: the step)")
    p.add_argument("--no-refine", action="store_true",
                   help="skip shortcut pruning and smoothing")
    p.add_argument("--no-figures", action="store_true",
                   help="skip plan.png (matplotlib is not even loaded: the fastest plan)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument("-o", "--output", type=output_path, default="plan", metavar="DIR",
                   help="folder to write into, created if needed (default: plan)")
    p.set_defaults(handler=plan)

"""Arguments shared by several commands: MAP, --margin, --start/--goal."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

from quadnav.planning import PlannerSettings, planner_names
from quadnav.runfolder import check_output_folder
from quadnav.world import World, read_start_goal
from quadnav.world.builtin import DEFAULT_MARGIN, DEFAULT_WORLD_SPEC


def finite_float(text: str) -> float:
    """argparse type: a finite number."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"expected a finite number, got {text!r}")
    return value


def positive_float(text: str) -> float:
    """argparse type: a finite number > 0."""
    value = finite_float(text)
    if value <= 0:
        raise argparse.ArgumentTypeError(f"expected a number > 0, got {text!r}")
    return value


def _at_least_zero(text: str, expected: str) -> float:
    """A finite number >= 0 from ``text``; otherwise an error saying ``expected``."""
    value = finite_float(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected {expected}, got {text!r}")
    return value


def nonnegative_float(text: str) -> float:
    """argparse type: a finite number >= 0."""
    return _at_least_zero(text, "a number >= 0")


def natural(text: str) -> int:
    """argparse type: an integer >= 0."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected a whole number >= 0, got {text!r}")
    return value


def probability(text: str) -> float:
    """argparse type: a number in [0, 1)."""
    value = finite_float(text)
    if not 0 <= value < 1:
        raise argparse.ArgumentTypeError(f"expected a number in [0, 1), got {text!r}")
    return value


def output_folder(path: str) -> Path:
    """The output folder ``path``, checked before any work: QuadnavError (one line) if a
    file is in the way or the folder cannot be written or created
    (:func:`~quadnav.runfolder.check_output_folder`)."""
    return check_output_folder(path)


def margin_value(text: str) -> float:
    """argparse type: a margin in metres, >= 0."""
    return _at_least_zero(text, "a margin >= 0 m")


def add_map_argument(parser: argparse.ArgumentParser, optional: bool = False) -> None:
    """MAP: a map file or a built-in world spec (optional: defaults to the built-in world)."""
    help_text = "map file (.txt or .json) or built-in world spec, e.g. forest:seed=3"
    if optional:
        parser.add_argument("map", nargs="?", default=DEFAULT_WORLD_SPEC, metavar="MAP",
                            help=f"{help_text} (default: {DEFAULT_WORLD_SPEC})")
    else:
        parser.add_argument("map", metavar="MAP", help=help_text)


def add_margin_argument(parser: argparse.ArgumentParser) -> None:
    """--margin M, defaulting to the map's own margin or DEFAULT_MARGIN."""
    parser.add_argument("--margin", type=margin_value, metavar="M",
                        help="safety margin in metres (default: the map's own, "
                             f"else {DEFAULT_MARGIN:g})")


def add_start_goal_arguments(parser: argparse.ArgumentParser) -> None:
    """--start X Y Z, --goal X Y Z and --start-goal FILE."""
    parser.add_argument("--start", nargs=3, type=finite_float, metavar=("X", "Y", "Z"),
                        help="start position in metres (default: the map's own)")
    parser.add_argument("--goal", nargs=3, type=finite_float, metavar=("X", "Y", "Z"),
                        help="goal position in metres (default: the map's own)")
    parser.add_argument("--start-goal", metavar="FILE",
                        help="RBE595 start/goal file with lines 'start: (x, y, z)', "
                             "'goal: (x, y, z)'")


def resolve_margin(args: argparse.Namespace, world: World) -> float:
    """The margin flag, else the map's own margin, else DEFAULT_MARGIN."""
    if args.margin is not None:
        return args.margin
    return world.margin if world.margin is not None else DEFAULT_MARGIN


def resolve_start_goal(args: argparse.Namespace, world: World
                       ) -> tuple[np.ndarray | None, np.ndarray | None]:
    """Start and goal from the flags, else the start/goal file, else the map."""
    start, goal = world.start, world.goal
    if args.start_goal is not None:
        start, goal = read_start_goal(args.start_goal)
    if args.start is not None:
        start = np.array(args.start)
    if args.goal is not None:
        goal = np.array(args.goal)
    return start, goal



def add_planner_arguments(parser: argparse.ArgumentParser, time: float, iterations: int,
                          improve: int | None) -> None:
    """--planner NAME, --time S, --seed N, --iterations N and --improve N with the given
    defaults (``iterations`` 0: no cap; ``improve`` None: no limit)."""
    parser.add_argument("--planner", default="rrtstar", metavar="NAME",
                        help=f"one of {', '.join(planner_names())} (default: rrtstar)")
    parser.add_argument("--time", type=positive_float, default=time, metavar="S",
                        help=f"search time budget in seconds (default: {time:g})")
    parser.add_argument("--seed", type=natural, default=0, metavar="N",
                        help="random seed; the same seed gives the same result (default: 0)")
    budget = f"{iterations:,} samples" if iterations else "no cap"
    parser.add_argument("--iterations", type=natural, default=iterations, metavar="N",
                        help=f"stop after N samples in all; 0: no cap (default: {budget})")
    until = (f"{improve:,} samples after it" if improve is not None
             else "until the time or iteration budget ends")
    parser.add_argument("--improve", type=natural, default=improve, metavar="N",
                        help="once a first path is found, improve it for N more samples, "
                             "then stop (rrtstar; the same seed then gives the same path "
                             f"however fast the machine; default: {until})")


def planner_budget(args: argparse.Namespace) -> PlannerSettings:
    """The search budget and seed from the flags of :func:`add_planner_arguments`."""
    return PlannerSettings(time_limit=args.time, max_iterations=args.iterations or None,
                           improve_iterations=args.improve, seed=args.seed)

"""Arguments shared by several commands: MAP, --margin, --start/--goal, the vehicle, the
simulation and the run folder's flags of ``fly`` and ``track``, and the argparse types of
numbers, each checked against its stated range (:mod:`quadnav.limits`)."""

from __future__ import annotations

import argparse
from collections.abc import Callable

import numpy as np

from quadnav.limits import (
    ACCELERATION,
    COORDINATE,
    HEADING_DEGREES,
    LENGTH,
    MARGIN,
    PLAN_ITERATIONS,
    PLAN_TIME,
    SAMPLES,
    SEED,
    SPEED,
    STALL_FRACTION,
    TIME_SCALE,
    Range,
    Speed,
    speed_value,
)
from quadnav.planning import PlannerSettings, planner_names
from quadnav.planning.stall import (
    CHECKS,
    DEFAULT_STALL_FRACTION,
    DEFAULT_STALL_SAMPLES,
    stall_rule,
)
from quadnav.world import World
from quadnav.world.builtin import DEFAULT_MARGIN, DEFAULT_WORLD_SPEC
from quadnav.world.startgoal import query_ends


def number_in(allowed: Range) -> Callable[[str], float]:
    """An argparse type: a number in ``allowed`` (a whole number if it says so).

    argparse puts the flag's name before the message, e.g. ``argument --speed: expected
    from 0.01 to 100 m/s, got '1e9'``.
    """
    def parse(text: str) -> float:
        try:
            value = int(text) if allowed.whole else float(text)
        except ValueError:
            value = None
        if value is None or value not in allowed:
            raise argparse.ArgumentTypeError(f"expected {allowed.describe()}, got {text[:40]!r}")
        return value
    return parse


def probability(text: str) -> float:
    """argparse type: a number in [0, 1)."""
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not 0 <= value < 1:
        raise argparse.ArgumentTypeError(f"expected a number in [0, 1), got {text[:40]!r}")
    return value


#: argparse types of the numbers several commands take.
coordinate = number_in(COORDINATE)
margin_value = number_in(MARGIN)
seed_value = number_in(SEED)
samples = number_in(SAMPLES)
stall_fraction = number_in(STALL_FRACTION)
plan_time = number_in(PLAN_TIME)
length = number_in(LENGTH)
speed = number_in(SPEED)
acceleration = number_in(ACCELERATION)
heading_degrees = number_in(HEADING_DEGREES)
time_scale = number_in(TIME_SCALE)


def output_path(text: str) -> str:
    """An ``-o`` path: any non-blank text (an empty one would write into the current
    folder, or nowhere)."""
    if not text.strip():
        raise argparse.ArgumentTypeError(f"expected a file or folder name, got {text!r}")
    return text


def speed_or_max(text: str) -> Speed:
    """argparse type of ``--speed V|max``: a top speed in :data:`SPEED`, or ``"max"`` (as
    fast as the vehicle can follow; :func:`~quadnav.limits.speed_value`)."""
    try:
        value = speed_value(float(text))
    except ValueError:
        value = speed_value(text)
    if value is None:
        raise argparse.ArgumentTypeError(f"expected {SPEED.describe()} or max, got "
                                         f"{text[:40]!r}")
    return value


def add_map_argument(parser: argparse.ArgumentParser, optional: bool = False,
                     unset: bool = False) -> None:
    """MAP: a map file, a built-in world spec or a course map (optional: defaults to the
    built-in world; with ``unset``, left None for the command to fill in)."""
    help_text = ("map file (.txt or .json), built-in world spec (e.g. forest:seed=3) or "
                 "course map (e.g. course:rbe595/map1; quadnav maps list)")
    if optional:
        parser.add_argument("map", nargs="?", default=None if unset else DEFAULT_WORLD_SPEC,
                            metavar="MAP",
                            help=f"{help_text} (default: {DEFAULT_WORLD_SPEC})")
    else:
        parser.add_argument("map", metavar="MAP", help=help_text)


def add_margin_argument(parser: argparse.ArgumentParser) -> None:
    """--margin M, defaulting to the map's own margin or DEFAULT_MARGIN."""
    parser.add_argument("--margin", type=margin_value, metavar="M",
                        help=f"safety margin, {MARGIN.describe()} (default: the map's own, "
                             f"else {DEFAULT_MARGIN:g})")


def add_start_goal_arguments(parser: argparse.ArgumentParser, file: bool = True) -> None:
    """--start X Y Z, --goal X Y Z and (if ``file``) --start-goal FILE."""
    parser.add_argument("--start", nargs=3, type=coordinate, metavar=("X", "Y", "Z"),
                        help=f"start position, each {COORDINATE.describe()} (default: the "
                             "map's own)")
    parser.add_argument("--goal", nargs=3, type=coordinate, metavar=("X", "Y", "Z"),
                        help=f"goal position, each {COORDINATE.describe()} (default: the "
                             "map's own)")
    if file:
        parser.add_argument("--start-goal", metavar="FILE",
                            help="RBE595 start/goal file with lines 'start: (x, y, z)', "
                                 "'goal: (x, y, z)', or a course one (e.g. "
                                 "course:rbe595/p2b_startandgoal_map1)")


def resolve_margin(args: argparse.Namespace, world: World) -> float:
    """The margin flag, else the map's own margin, else DEFAULT_MARGIN
    (:meth:`~quadnav.world.World.margin_for`)."""
    return world.margin_for(args.margin)


def resolve_start_goal(args: argparse.Namespace, world: World
                       ) -> tuple[np.ndarray | None, np.ndarray | None]:
    """Start and goal from the flags, else the start/goal file, else the map
    (:func:`~quadnav.world.startgoal.query_ends`)."""
    return query_ends(world, args.start, args.goal, args.start_goal)



def add_planner_arguments(parser: argparse.ArgumentParser, time: float, iterations: int,
                          improve: int | None, unset: bool = False) -> None:
    """--planner NAME, --time S, --seed N, --iterations N and --improve N with the given
    defaults (``iterations`` 0: no cap; ``improve`` None: no limit), and --stall N and
    --stall-fraction F with the stall rule's (:mod:`quadnav.planning.stall`); with
    ``unset``, the flags not given are left None and the defaults only shown (the
    command's mission fills them in)."""
    def default(value):
        return None if unset else value

    parser.add_argument("--planner", default=default("rrtstar"), metavar="NAME|SPEC",
                        help=f"one of {', '.join(planner_names())}, or a function of your "
                             "own, module:FUNCTION or path/to/file.py:FUNCTION, optionally "
                             "with literal keyword arguments, FUNCTION(key=value, ...), called "
                             "as FUNCTION(world, start, goal, margin) -> path (N, 3) "
                             "(default: rrtstar)")
    parser.add_argument("--time", type=plan_time, default=default(time), metavar="S",
                        help=f"search time budget, {PLAN_TIME.describe()} (default: {time:g})")
    add_seed_argument(parser, "random seed", unset)
    budget = f"{iterations:,} samples" if iterations else "no cap"
    parser.add_argument("--iterations", type=samples, default=default(iterations), metavar="N",
                        help=f"stop after N samples in all, at most {PLAN_ITERATIONS.high:,}; "
                             f"0: no cap but {PLAN_ITERATIONS.high:,} (default: {budget})")
    until = (f"{improve:,} samples after it" if improve is not None
             else "until the time or iteration budget ends")
    parser.add_argument("--improve", type=samples, default=default(improve), metavar="N",
                        help="once a first path is found, improve it for N more samples, "
                             f"at most {PLAN_ITERATIONS.high:,}, then stop, unless --stall "
                             "stops it sooner (rrtstar; the same seed then gives the same "
                             f"path however fast the machine; default: {until})")
    parser.add_argument("--stall", type=samples, default=default(DEFAULT_STALL_SAMPLES),
                        metavar="N",
                        help="once a first path is found, stop when the best length has "
                             "shortened by at most --stall-fraction over the last N samples "
                             f"(checked every N/{CHECKS}; rrtstar and the OMPL planners that "
                             "count samples; the same seed gives the same path); 0: no such "
                             "rule, the search runs its whole budget "
                             f"(default: {DEFAULT_STALL_SAMPLES:,})")
    parser.add_argument("--stall-fraction", type=stall_fraction,
                        default=default(DEFAULT_STALL_FRACTION), metavar="F",
                        help=f"the fraction of --stall, {STALL_FRACTION.describe()} "
                             f"(default: {DEFAULT_STALL_FRACTION:g}, 0.5 %%)")


def planner_budget(args: argparse.Namespace) -> PlannerSettings:
    """The search budget and seed from the flags of :func:`add_planner_arguments`."""
    return PlannerSettings(time_limit=args.time, max_iterations=args.iterations or None,
                           improve_iterations=args.improve,
                           stall=stall_rule(args.stall, args.stall_fraction), seed=args.seed)


def add_seed_argument(parser: argparse.ArgumentParser, what: str, unset: bool = False) -> None:
    """--seed N, 0 to 2^63 - 1 (default 0; with ``unset``, None when not given); ``what``
    says what it seeds."""
    parser.add_argument("--seed", type=seed_value, default=None if unset else 0, metavar="N",
                        help=f"{what}, 0 to 2^63 - 1; the same seed gives the same result "
                             "(default: 0)")


def add_run_output_arguments(parser: argparse.ArgumentParser, folder: str, report: str) -> None:
    """--no-figures, --html, --quiet and -o DIR (default ``folder``) of a command that
    writes a run folder with the report file ``report``."""
    parser.add_argument("--no-figures", action="store_true",
                        help=f"skip the figures and {report} (faster, e.g. for batches of "
                             "runs; quadnav report DIR writes the report later)")
    parser.add_argument("--html", action="store_true",
                        help="also write DIR/view.html, an interactive 3D page of the run "
                             "that works offline (the same as quadnav view DIR)")
    parser.add_argument("--quiet", action="store_true", help="no progress bars")
    parser.add_argument("-o", "--output", default=folder, metavar="DIR", type=output_path,
                        help=f"folder to write into, created if needed (default: {folder})")


#: Local worker processes of ``batch`` and ``tune``.
WORKERS = Range(1, 1024, whole=True)


def add_executor_arguments(parser: argparse.ArgumentParser) -> None:
    """``--workers N`` and ``--ray [ADDRESS]``: where the jobs of ``batch`` and ``tune``
    run (:func:`quadnav.batch.executor.open_executor`)."""
    parser.add_argument("--workers", type=number_in(WORKERS), metavar="N",
                        help=f"local worker processes, {WORKERS.describe()} (default: one per "
                             "CPU)")
    parser.add_argument("--ray", nargs="?", const="", metavar="ADDRESS",
                        help="run on the Ray cluster at ADDRESS (e.g. HEAD:6379); without one, "
                             "on a local Ray started for the run (needs quadnav[ray])")


def workers_description(args: argparse.Namespace) -> str:
    """``local worker{s}``, ``CPU{s} of a local Ray`` or ``CPU{s} of the Ray cluster at
    ADDRESS``, to be formatted with the plural ``s``."""
    if args.ray is None:
        return "local worker{s}"
    return f"CPU{{s}} of the Ray cluster at {args.ray}" if args.ray else "CPU{s} of a local Ray"

"""``quadnav batch``: many missions over a grid, on local workers or on Ray, into a table
and a summary; ``quadnav refly``: one mission of a batch again, with figures."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from tqdm import tqdm

from quadnav.batch.compare import contender_rows, varying_axes
from quadnav.batch.grid import (
    DEFAULT_METHOD,
    NO_REFERENCE,
    BatchSpec,
    read_spec,
    spec_from_table,
)
from quadnav.batch.run import BatchRun
from quadnav.batch.summary import percent_text, rate
from quadnav.cli.args import (
    acceleration,
    add_executor_arguments,
    add_margin_argument,
    add_start_goal_arguments,
    number_in,
    output_path,
    speed_or_max,
    workers_description,
)
from quadnav.cli.commands import command_help
from quadnav.cli.compare_command import leaderboard
from quadnav.cli.flight_args import force_or_spec, wind_arguments
from quadnav.cli.progress import terminal_bar
from quadnav.control.registry import DEFAULT_CONTROLLER
from quadnav.errors import QuadnavError
from quadnav.limits import Range
from quadnav.mission import DEFAULT_ACCELERATION, DEFAULT_SPEED
from quadnav.planning import planner_names
from quadnav.runfolder import check_output_folder
from quadnav.signals import interrupted_exit_code
from quadnav.trajectory.generate import METHODS
from quadnav.vehicle.params import DEFAULT_PRESET, vehicle_forms

#: Seeds of the simple case when --seeds is not given.
DEFAULT_SEEDS = 10
#: Flags that set the grid or the fixed settings: a TOML spec sets them instead.
GRID_FLAGS = {"seeds": "--seeds", "speeds": "--speeds", "accel": "--accel",
              "margin": "--margin", "start": "--start", "goal": "--goal",
              "start_goal": "--start-goal", "params": "--params", "gains": "--gains",
              "planners": "--planner", "controllers": "--controller", "methods": "--method",
              "references": "--reference", "winds": "--wind"}
#: The grid's lists of contenders that flags set as they are.
CONTENDER_FLAGS = ("planners", "controllers", "methods", "references")


def batch_spec(args: argparse.Namespace) -> BatchSpec:
    """The spec: the TOML file given, or the maps and flags of the simple case."""
    inputs = args.inputs
    toml = [name for name in inputs if name.lower().endswith(".toml")]
    if toml:
        if len(inputs) > 1:
            raise QuadnavError(f"{toml[0]}: a spec file comes alone, without maps: list the "
                               "maps in its maps key")
        given = [flag for key, flag in GRID_FLAGS.items() if getattr(args, key) is not None]
        if given:
            raise QuadnavError(f"{given[0]}: set it in the spec {toml[0]} instead (a spec "
                               "holds the whole grid and its settings)")
        return read_spec(toml[0])
    query = {key: getattr(args, key) for key in ("start", "goal", "start_goal")
             if getattr(args, key) is not None}
    table = {"maps": [{"map": name} | query for name in inputs],
             "seeds": DEFAULT_SEEDS if args.seeds is None else args.seeds,
             "speeds": [DEFAULT_SPEED] if args.speeds is None else args.speeds,
             "vehicle": args.params or DEFAULT_PRESET}
    optional = {"accel": args.accel, "margin": args.margin,
                "gains": None if args.gains is None else [args.gains],
                "winds": None if args.winds is None else [_wind(w) for w in args.winds]}
    optional |= {key: getattr(args, key) for key in CONTENDER_FLAGS}
    table |= {key: value for key, value in optional.items() if value is not None}
    return spec_from_table(table, Path.cwd(), "the command line")


def _wind(values: list[float | str]) -> list[float] | str:
    """One ``--wind``'s values as a ``winds`` entry: the force [fx, fy, fz] N or the wind
    class's spec."""
    force, model = wind_arguments(values)
    return force if model is None else model


class _Progress:
    """What a batch says as it runs: one line once its workers are ready, then a progress
    bar of the missions done, with the ETA and the running success rate."""

    def __init__(self, run: BatchRun, where: str, quiet: bool) -> None:
        self.run = run
        self.where = where
        self.quiet = quiet
        self.bar: tqdm | None = None
        # counted as rows come (a rate over every row at each row took O(N^2) time)
        self.finished = len(run.rows)
        self.successes = sum(bool(row["success"]) for row in run.rows.values())

    def started(self, workers: int, threads: int) -> None:
        run = self.run
        print(f"{len(run.missions)} missions, {len(run.rows)} already in {run.folder}; flying "
              f"{len(run.todo)} on {workers} {self.where.format(s='s' if workers > 1 else '')}"
              f" x {threads} numba thread{'s' if threads > 1 else ''}", flush=True)
        self.bar = terminal_bar(self.quiet, total=len(run.todo), desc="batch", unit="mission",
                                dynamic_ncols=True)

    def row(self, row: dict) -> None:
        self.finished += 1
        self.successes += bool(row["success"])
        assert self.bar is not None
        self.bar.set_postfix_str(f"success {100 * self.successes / self.finished:.1f} % of "
                                 f"{self.finished}", refresh=False)
        self.bar.update(1)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def batch(args: argparse.Namespace) -> int:
    """Run the batch; exit 0 once every mission has a row, whatever the success rate."""
    spec = batch_spec(args)
    if args.compare and not spec.contender_keys:
        raise QuadnavError("--compare: the batch has a single contender (one controller, "
                           "planner, method or reference, wind and gains); expected two or "
                           "more of one of them")
    folder = check_output_folder(args.output)
    run = BatchRun(spec, folder, restart=args.restart)
    done_before = len(run.rows)
    where = workers_description(args)
    if not run.todo:
        print(f"{len(run.missions)} missions, all already in {folder}")
    progress = _Progress(run, where, args.quiet)
    began = time.perf_counter()
    try:
        written = run.run(workers=args.workers, ray=args.ray is not None,
                          address=args.ray or None, on_start=progress.started,
                          on_row=progress.row)
    except KeyboardInterrupt as interrupt:
        progress.close()
        print(f"quadnav: stopped: kept {len(run.rows)} of {len(run.missions)} missions in "
              f"{folder / 'results.csv'}; run the same command again to resume",
              file=sys.stderr)
        return interrupted_exit_code(interrupt)
    finally:
        progress.close()
    seconds = time.perf_counter() - began
    overall = rate(run.finished)
    print(f"{overall['successes']} of {overall['n']} missions reached the goal with no "
          f"contact, the body inside the map: {percent_text(overall['success_rate'])} % "
          "(95 % interval "
          f"{percent_text(overall['ci_low'])} to {percent_text(overall['ci_high'])} %); "
          f"{overall['errors']} refused; {overall['short_of_margin']} kept less margin than "
          "asked")
    _print_contenders(run.finished, folder)
    print(f"flew {len(run.rows) - done_before} missions in {seconds:.1f} s{_retried(run)}")
    print("wrote " + ", ".join(str(folder / name) for name in written))
    if args.compare:
        leaderboard(folder, run.finished, None)
    return 0


def _retried(run: BatchRun) -> str:
    """The end of the ``flew`` line: how many missions flew again because the worker
    process flying them died, when any did."""
    if not run.retried:
        return ""
    them = "it" if run.retried == 1 else "them"
    return f"; {run.retried} flown again after the worker process flying {them} died"


def _print_contenders(rows: list[dict], folder: Path) -> None:
    """The success rate of each contender of ``rows`` when the batch has several."""
    by = varying_axes(rows)
    if not by:
        return
    print(f"per {', '.join(by)} (quadnav compare {folder} draws the leaderboard):")
    for name, group in contender_rows(rows, by).items():
        found = rate(group)
        print(f"  {name}: {found['successes']} of {found['n']}, "
              f"{percent_text(found['success_rate'])} % ({percent_text(found['ci_low'])} to "
              f"{percent_text(found['ci_high'])} %)")


def add_batch_command(subparsers: argparse._SubParsersAction) -> None:
    """Register ``quadnav batch`` on the top-level subparsers."""
    p = subparsers.add_parser(
        "batch", help=command_help("batch"),
        description="Monte-Carlo evaluation: fly every mission of a grid on local worker "
                    "processes (or a Ray cluster) without figures, and write DIR/results.parquet "
                    "and DIR/results.csv (one row per mission), DIR/summary.json (success rate "
                    "per group with Wilson 95 % intervals) and DIR/summary.html. Give maps and "
                    "flags for the simple case, or one TOML spec for the full grid (see the "
                    "README); several controllers, planners, methods, references or winds "
                    "are contenders, ranked by quadnav compare DIR (or --compare). A re-run "
                    "into the same DIR skips the missions already done; Ctrl-C keeps every "
                    "finished row. Exit 0 when every mission has a row, 2 on "
                    "bad input, 130/143 when stopped.")
    p.add_argument("inputs", nargs="+", metavar="MAP|SPEC.toml",
                   help="map files or built-in world specs, or one TOML spec")
    p.add_argument("--seeds", type=number_in(Range(1, 1_000_000, whole=True)), metavar="N",
                   help=f"seeds 0 to N - 1 for every map and speed (default: {DEFAULT_SEEDS})")
    p.add_argument("--speeds", type=speed_or_max, nargs="+", metavar="V|max",
                   help=f"top speeds, m/s, or max (default: {DEFAULT_SPEED:g})")
    p.add_argument("--accel", type=acceleration, metavar="A",
                   help=f"largest acceleration, m/s^2 (default: {DEFAULT_ACCELERATION:g})")
    add_margin_argument(p)
    add_start_goal_arguments(p)
    p.add_argument("--params", metavar="NAME|FILE",
                   help=f"vehicle: {vehicle_forms()} (default: {DEFAULT_PRESET})")
    p.add_argument("--gains", metavar="NAME|FILE",
                   help="controller gains: a TOML file or a course gain table (as in fly)")
    p.add_argument("--planner", dest="planners", nargs="+", metavar="NAME|SPEC",
                   help=f"planners, each one of {', '.join(planner_names())}, or a function "
                        "of your own, module:FUNCTION or path/to/file.py:FUNCTION (as in fly; "
                        "default: rrtstar)")
    p.add_argument("--controller", dest="controllers", nargs="+", metavar="NAME|SPEC",
                   help="controllers, each cascade, se3 or a class of your own, module:Class "
                        "or path/to/file.py:Class(key=value, ...) (as in fly; default: "
                        f"{DEFAULT_CONTROLLER})")
    p.add_argument("--method", dest="methods", nargs="+", choices=METHODS.names(),
                   metavar="METHOD",
                   help=f"trajectory methods, each one of {', '.join(METHODS.names())} "
                        f"(default: {DEFAULT_METHOD})")
    p.add_argument("--reference", dest="references", nargs="+", metavar="none|SPEC",
                   help=f"{NO_REFERENCE} (the trajectory of each --method) or a trajectory "
                        "class of your own flown instead, module:Class or "
                        "path/to/file.py:Class (as fly --reference; default: "
                        f"{NO_REFERENCE})")
    p.add_argument("--wind", dest="winds", action="append", nargs="+", type=force_or_spec,
                   metavar=("FX|SPEC", "FY FZ"),
                   help="one wind of the grid per --wind: a steady force FX FY FZ, N, or a "
                        "wind class's spec (as in fly); repeat it for more: --wind 0 0 0 "
                        "--wind 0.02 0 0 --wind my_wind.py:Gust (default: no wind)")
    add_executor_arguments(p)
    p.add_argument("--compare", action="store_true",
                   help="then print and write the leaderboard of its contenders, as quadnav "
                        "compare DIR does (refused up front for a batch of one contender)")
    p.add_argument("--restart", action="store_true",
                   help="replace a different batch already in DIR instead of refusing")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument("-o", "--output", type=output_path, default="batch", metavar="DIR",
                   help="folder to write into, created if needed (default: batch)")
    p.set_defaults(handler=batch)


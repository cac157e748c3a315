"""``quadnav kino``: kinodynamic RRT for a differential-drive robot or a quadrotor.

``quadnav kino diffdrive`` plans on a 2D world (a ``.map2d`` file, or a 3D map or built-in
world sliced at ``--height``, by default half way up its z range); ``quadnav kino
quadrotor`` plans in a 3D map. Both write into the output folder:

* ``kino.json`` — the query, the outcome and the search statistics, the settings and the
  vehicle's parameters; for the quadrotor also how far the controls replayed open loop
  through the point-mass model end from the planned positions (``replay``) and, with
  ``--fly``, the closed-loop flight's headline figures (``flight``);
* ``states.csv`` — the planned states, one row per tree state on the plan: ``t`` (s from
  the start) then the state's coordinates;
* ``controls.csv`` — one row per control of the plan: ``t_start``, ``duration`` (s) and
  the control (for the differential drive also the two wheel speeds);
* ``kino.png`` (tree and plan) and ``controls.png`` (the control profiles);
* for the differential drive also ``tracks.csv`` (the centre and both wheel paths) and,
  with ``--compare``, ``biased_vs_unbiased.png``;
* for the quadrotor with ``--fly``, the run folder ``DIR/flight`` of the plan flown
  closed loop (:mod:`quadnav.kinoflight`), the same files as ``quadnav fly -o DIR``
  writes, read by ``report``, ``view``, ``animate`` and ``blender``.

Exit 0 when the goal region is reached (and, with ``--fly``, the flight succeeded); 1 when
it is not or the flight failed, or with ``--strict`` kept less margin than asked (the CSV
files are removed when there is no plan, and the rest is still written); 2 on bad input, as
one line on stderr with nothing written.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import warnings
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from quadnav.arrays import FloatArray
from quadnav.cli.args import (
    add_map_argument,
    add_margin_argument,
    add_start_goal_arguments,
    coordinate,
    length,
    margin_value,
    number_in,
    output_path,
    plan_time,
    resolve_margin,
    seed_value,
)
from quadnav.cli.commands import command_help
from quadnav.cli.flight_args import (
    add_controller_argument,
    add_strict_argument,
    add_vehicle_arguments,
    vehicle_and_gains,
)
from quadnav.cli.progress import fraction_bar, percent_bar
from quadnav.errors import QuadnavError
from quadnav.files import numbers_csv
from quadnav.kinodynamic.diffdrive import DiffDrive, plan_diffdrive, wheel_tracks
from quadnav.kinodynamic.pointmass import SampledQuadrotor
from quadnav.kinodynamic.quadrotor import REPLAY_TOLERANCE, plan_quadrotor, replay
from quadnav.kinodynamic.result import KinoResult
from quadnav.kinodynamic.settings import KinoSettings
from quadnav.kinodynamic.world2d import MAP2D_SUFFIX, World2D, load_world2d
from quadnav.limits import (
    COORDINATE,
    HEADING_RADIANS,
    KINO_ITERATIONS,
    LENGTH,
    MARGIN,
    PLAN_TIME,
)
from quadnav.planning.result import Progress
from quadnav.runfolder import check_output_folder, replaced_folder
from quadnav.world import load_world

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from quadnav.control.gains import Gains
    from quadnav.kinoflight import KinoFlight
    from quadnav.vehicle.params import VehicleParams
    from quadnav.world.model import World

#: Exit code when the search ends without reaching the goal region (the input was fine).
EXIT_NOT_REACHED = 1
#: Files that only a plan that reaches the goal region has; removed when it does not.
PLAN_FILES = ("states.csv", "controls.csv", "tracks.csv")
#: The figure of ``--compare``; removed when a run does not draw it.
COMPARE_FIGURE = "biased_vs_unbiased.png"
#: Every file kino writes.
KINO_FILES = ("kino.json", *PLAN_FILES, "kino.png", "controls.png", COMPARE_FIGURE)
#: The run folder of ``kino quadrotor --fly``, inside the output folder.
FLIGHT_FOLDER = "flight"
#: The flight's figures copied into kino.json (all of them are in flight/metrics.json).
FLIGHT_KEYS = ("success", "reached_goal", "ending", "flight_time_s", "rms_tracking_error_m",
               "max_tracking_error_m", "final_error_m", "min_clearance_m", "flight_margin_m",
               "rotor_energy_j")
#: Largest deviation, m, of the wheel tracks in tracks.csv from the true wheel paths.
TRACK_TOLERANCE = 0.01


def settings_from(args: argparse.Namespace) -> KinoSettings:
    """Search settings from the command-line flags."""
    return KinoSettings(max_iterations=args.iterations, time_limit=args.time, seed=args.seed,
                        biased=not args.unbiased, goal_radius=args.goal_radius)


def search(label: str, quiet: bool, planner: Callable[[Progress], KinoResult]) -> KinoResult:
    """Run ``planner(progress)`` under a progress bar on stderr (:func:`~quadnav.cli.
    progress.percent_bar`: drawn from the first report, so input the planner rejects before
    searching leaves stderr to the one-line error)."""
    with percent_bar(label, quiet) as progress:
        return planner(lambda fraction, closest: progress(fraction,
                                                          f"closest {closest:.2f} m"))


def state_times(result: KinoResult) -> FloatArray:
    """Time (K,) of each planned state, s from the start."""
    return np.concatenate([[0.0], np.cumsum(result.durations)])[:len(result.states)]


def plan_tables(result: KinoResult, state_names: Sequence[str],
                control_columns: dict[str, FloatArray]) -> dict[str, str]:
    """``states.csv`` and ``controls.csv`` of a plan: ``t`` and the states; ``t_start``,
    ``duration`` and the named control columns (each (K - 1,))."""
    times = state_times(result)
    return {
        "states.csv": numbers_csv(["t", *state_names],
                                  np.column_stack([times, *result.states.T])),
        "controls.csv": numbers_csv(["t_start", "duration", *control_columns],
                                    np.column_stack([times[:-1], result.durations,
                                                     *control_columns.values()])),
    }


def run_stats(result: KinoResult) -> dict[str, Any]:
    """The outcome and statistics of one search, JSON-ready (times in s)."""
    return {
        "planner": result.planner, "seed": result.seed, "solved": result.solved,
        "message": result.message, "iterations": result.iterations,
        "nodes": len(result.tree_states), "seconds": result.seconds,
        "time_to_goal": result.time_to_goal, "duration": result.duration,
        "controls": len(result.controls),
    }


def summary(vehicle: str, map_name: str, result: KinoResult, settings: KinoSettings,
            model: object, query: dict[str, Any]) -> dict[str, Any]:
    """``kino.json``: the query, the outcome, the settings and the model's parameters."""
    return {"vehicle": vehicle, "map": map_name, **query, **run_stats(result),
            "settings": dataclasses.asdict(settings), "model": dataclasses.asdict(model)}


def write_outputs(folder: Path, result: KinoResult, data: dict[str, Any],
                  tables: dict[str, str], figures: dict[str, Callable[[], Figure]]) -> list[str]:
    """Write kino.json, the plan's tables (only when solved) and the figures, whole or not
    at all (:func:`~quadnav.runfolder.replaced_folder`: the plan files and the comparison
    figure of an earlier run that this one does not write are removed). Returns the names
    written, in order."""
    from quadnav.viz.figures import save_figure

    written = list(tables) if result.solved else []
    with replaced_folder(folder, KINO_FILES) as staging:
        for name in written:
            (staging / name).write_text(tables[name])
        (staging / "kino.json").write_text(json.dumps(data, indent=2) + "\n")
        written.append("kino.json")
        for name, draw in figures.items():
            save_figure(draw(), staging / name)
            written.append(name)
    return written


def finish(folder: Path, map_name: str, runs: Sequence[tuple[str, KinoResult]],
           written: list[str]) -> int:
    """Print one line per search and the files written; the exit code of the first search
    (0 when it reached the goal region, :data:`EXIT_NOT_REACHED` when not)."""
    for label, result in runs:
        reached = (f"goal region reached after {result.time_to_goal:.3g} s, "
                   f"{len(result.controls)} controls lasting {result.duration:.3g} s"
                   if result.solved else "goal region not reached")
        print(f"{map_name}: {result.planner}, {label} sampling, seed {result.seed}: "
              f"{result.iterations:,} iterations, {len(result.tree_states):,} states in "
              f"{result.seconds:.3g} s; {reached}")
    print("wrote " + ", ".join(str(folder / name) for name in written))
    result = runs[0][1]
    if not result.solved:
        print(f"quadnav: no plan: {result.message}; a larger --iterations or --time may "
              "reach it", file=sys.stderr)
        return EXIT_NOT_REACHED
    return 0


def sampling(settings: KinoSettings) -> str:
    """``"biased"`` or ``"unbiased"``."""
    return "biased" if settings.biased else "unbiased"


# ------------------------------------------------------------------ diffdrive
def slice_for(map_source: str, height: float | None) -> tuple[World2D, float | None]:
    """The 2D world of MAP and the slice height used (``None`` for a ``.map2d`` file).

    A 3D map or built-in world is sliced at ``height``, by default half way up its
    boundary's z range.
    """
    if map_source.lower().endswith(MAP2D_SUFFIX):
        if height is not None:
            warnings.warn(f"--height is ignored for the 2D map {map_source}", stacklevel=2)
        return load_world2d(map_source), None
    world = load_world(map_source)
    if height is None:
        height = 0.5 * float(world.lower[2] + world.upper[2])
    return load_world2d(world, height), height


def diffdrive(args: argparse.Namespace) -> int:
    """Plan for the differential-drive robot and write its files; exit 1 if the goal
    region was not reached."""
    from quadnav.viz.kino2d import (
        biased_vs_unbiased_figure,
        diffdrive_controls_figure,
        diffdrive_figure,
    )

    HEADING_RADIANS.check(args.start[2], "argument --start: THETA")
    folder = check_output_folder(args.output)
    settings = settings_from(args)
    world, height = slice_for(args.map, args.height)
    model = DiffDrive()

    def plan(run_settings: KinoSettings) -> KinoResult:
        return search(f"diffdrive ({sampling(run_settings)})", args.quiet,
                      lambda progress: plan_diffdrive(world, args.start, args.goal,
                                                      run_settings, model, args.margin,
                                                      progress))

    runs = [(sampling(settings), plan(settings))]
    if args.compare:
        other = settings.replace(biased=not settings.biased)
        runs.append((sampling(other), plan(other)))
    result = runs[0][1]
    query = {"start": list(args.start), "goal": list(args.goal), "height": height,
             "margin": args.margin}
    data = summary("diffdrive", world.name, result, settings, model, query)
    left_speed, right_speed = model.wheel_speeds(result.controls)
    tables = plan_tables(result, ("x", "y", "theta"),
                         {"v": result.controls[:, 0], "omega": result.controls[:, 1],
                          "left_speed": left_speed, "right_speed": right_speed})
    centre, left, right, t = wheel_tracks(result, model, TRACK_TOLERANCE)
    tables["tracks.csv"] = numbers_csv(
        ["t", "x", "y", "left_x", "left_y", "right_x", "right_y"],
        np.column_stack([t, *centre.T, *left.T, *right.T]))
    goal_region = (args.goal, settings.goal_radius)
    figures = {"kino.png": lambda: diffdrive_figure(world, result, model, *goal_region),
               "controls.png": lambda: diffdrive_controls_figure(result, model)}
    if args.compare:
        data["compare"] = {label: run_stats(r) for label, r in runs}
        by_label = dict(runs)
        figures[COMPARE_FIGURE] = lambda: biased_vs_unbiased_figure(
            world, by_label["biased"], by_label["unbiased"], model, *goal_region)
    written = write_outputs(folder, result, data, tables, figures)
    return finish(folder, world.name, runs, written)


# ------------------------------------------------------------------ quadrotor
def replay_errors(result: KinoResult, times: FloatArray, positions: FloatArray) -> FloatArray:
    """Distances (K,), m, between the planned positions and a replay's positions (N, 3) at
    its times (N,) s nearest the planned states' times."""
    planned = state_times(result)
    rows = np.clip(np.searchsorted(times, planned), 1, len(times) - 1)
    rows -= (planned - times[rows - 1]) < (times[rows] - planned)
    return np.linalg.norm(positions[rows] - result.states[:, :3], axis=1)


def replay_error(model: SampledQuadrotor, result: KinoResult) -> float | None:
    """Largest distance, m, between the planned positions and those of the plan's controls
    flown open loop from its first state (:func:`~quadnav.kinodynamic.quadrotor.replay`),
    at the replay's samples nearest the planned states' times; ``None`` without a plan."""
    if not result.solved:
        return None
    times, states = replay(model, result.states[0], result.controls, result.durations)
    return float(np.max(replay_errors(result, times, states[:, :3])))


def quadrotor(args: argparse.Namespace) -> int:
    """Plan for the quadrotor and write its files; exit 1 if the goal region was not
    reached."""
    from quadnav.viz.kino3d import quadrotor_controls_figure, quadrotor_figure

    folder = check_output_folder(args.output)
    settings = settings_from(args)
    world = load_world(args.map)
    ends = []
    for label, given, own in (("start", args.start, world.start),
                              ("goal", args.goal, world.goal)):
        if given is None and own is None:
            raise QuadnavError(f"{world.name}: the map has no {label}; give --{label} X Y Z")
        ends.append(np.array(given if given is not None else own, dtype=np.float64))
    start, goal = ends
    margin = resolve_margin(args, world)
    vehicle, gains = vehicle_and_gains(args)  # bad files are refused before planning
    model = SampledQuadrotor()
    result = search(f"quadrotor ({sampling(settings)})", args.quiet,
                    lambda progress: plan_quadrotor(world, start, goal, settings, model,
                                                    margin, progress,
                                                    vehicle.half_extents(model.yaw)))
    query = {"start": start.tolist(), "goal": goal.tolist(), "margin": margin}
    data = summary("quadrotor", world.name, result, settings, model, query)
    data["replay"] = {"max_position_error": replay_error(model, result),
                      "tolerance": REPLAY_TOLERANCE}
    flown = fly_plan(args, world.replace(start=start, goal=goal, margin=margin), result, model,
                     settings, vehicle, gains) if args.fly and result.solved else None
    if flown is not None:
        flown_metrics = flown.metrics()
        data["flight"] = {key: flown_metrics[key] for key in FLIGHT_KEYS}
    tables = plan_tables(result, ("x", "y", "z", "vx", "vy", "vz"),
                         dict(zip(("phi", "theta", "thrust"), result.controls.T, strict=True)))
    track = None if flown is None else flown.flight.position
    figures = {"kino.png": lambda: quadrotor_figure(world, result, model, goal, track),
               "controls.png": lambda: quadrotor_controls_figure(result, model)}
    written = write_outputs(folder, result, data, tables, {} if args.no_figures else figures)
    code = finish(folder, world.name, [(sampling(settings), result)], written)
    if flown is None:
        return code
    return write_flight(flown, folder / FLIGHT_FOLDER, args.strict, not args.no_figures)


def fly_plan(args: argparse.Namespace, world: World, result: KinoResult,
             model: SampledQuadrotor, settings: KinoSettings, vehicle: VehicleParams,
             gains: Gains) -> KinoFlight:
    """Fly the solved plan closed loop with ``vehicle``, ``gains`` and the controller of
    the flags, under a progress bar."""
    from quadnav.kinoflight import fly_kino_plan
    from quadnav.sim.settings import SimSettings

    with fraction_bar("fly", args.quiet) as progress:
        return fly_kino_plan(world, result, model, settings, vehicle, gains,
                             SimSettings(seed=settings.seed, goal_tolerance=settings.goal_radius),
                             args.controller, progress)


def write_flight(flown: KinoFlight, folder: Path, strict: bool = False,
                 figures: bool = True) -> int:
    """Write the run folder of the flight (with its figures and report if ``figures``),
    print its headline figures (and a warning line when it kept less margin than asked); 0
    when it succeeded (and, if ``strict``, kept the whole margin), else
    :data:`EXIT_NOT_REACHED` (saying why on stderr)."""
    from quadnav.cli.flight_lines import (
        clearance_text,
        flight_failed,
        tracking_errors,
        warn_margin_shortfall,
    )
    from quadnav.mission import flight_failure
    from quadnav.report.run_writer import write_run
    from quadnav.runs import RunContent

    result, m = flown.result, flown.metrics()
    content = RunContent(flown.world, m, flown.parameters(),
                         (result.tree_states[:, :3], result.tree_parents),
                         result.states[:, :3], flown.trajectory, flown.flight)
    written = write_run(content, folder, figures=figures)
    print(f"flown closed loop by the {flown.controller} controller on the {m['vehicle']} "
          f"vehicle: {'success' if m['success'] else 'FAILED'}, flight {m['ending']} after "
          f"{m['flight_time_s']:.2f} s (plan {m['plan_duration_s']:.2f} s, ending with a "
          f"{m['stop_s']:.2f} s stop at the goal)")
    print(f"  {tracking_errors(m)}; {clearance_text(m)}")
    print(f"  margin kept {m['trajectory_margin_m']:.3f} m by the plan and "
          f"{m['flight_margin_m']:.3f} m by the flight (asked {m['margin_m']:g} m); "
          f"rotor energy {m['rotor_energy_j']:.1f} J")
    short = warn_margin_shortfall(m, flown.flight.t, flown.flight.position)
    print("wrote " + ", ".join(str(folder / name) for name in written))
    failure = (None if m["success"]
               else flight_failure(flown.flight, flown.settings.goal_tolerance))
    return EXIT_NOT_REACHED if flight_failed(failure, short, strict) else 0


# ------------------------------------------------------------------ arguments
def _add_search_arguments(parser: argparse.ArgumentParser) -> None:
    """--seed, --iterations, --time, --unbiased, --goal-radius, --quiet, -o."""
    defaults = KinoSettings()
    parser.add_argument("--seed", type=seed_value, default=defaults.seed, metavar="N",
                        help="random seed, 0 to 2^63 - 1; the same seed gives the same plan "
                             "(default: 0)")
    parser.add_argument("--iterations", type=number_in(KINO_ITERATIONS),
                        default=defaults.max_iterations, metavar="N",
                        help=f"extensions tried at most, {KINO_ITERATIONS.describe()} "
                             f"(default: {defaults.max_iterations})")
    parser.add_argument("--time", type=plan_time, default=defaults.time_limit,
                        metavar="S", help=f"search time budget, {PLAN_TIME.describe()} "
                                          f"(default: {defaults.time_limit:g})")
    parser.add_argument("--unbiased", action="store_true",
                        help="sample uniformly over the map instead of around the goal")
    parser.add_argument("--goal-radius", type=length, default=defaults.goal_radius,
                        metavar="R", help=f"the goal region: metres around the goal, "
                                          f"{LENGTH.describe()} "
                                          f"(default: {defaults.goal_radius:g})")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    parser.add_argument("-o", "--output", type=output_path, default="kino", metavar="DIR",
                        help="folder to write into, created if needed (default: kino)")


def add_kino_command(subparsers: argparse._SubParsersAction) -> None:
    """Register ``quadnav kino diffdrive`` and ``quadnav kino quadrotor``."""
    kino = subparsers.add_parser(
        "kino", help=command_help("kino"),
        description="Grow a tree of sampled controls through a vehicle's motion model until "
                    "it reaches the goal region. Writes DIR/kino.json (statistics, settings, "
                    "model), DIR/states.csv, DIR/controls.csv, DIR/kino.png and "
                    "DIR/controls.png. Exit 1 when the goal region is not reached (the CSV "
                    "files are not written), 2 on bad input.")
    vehicles = kino.add_subparsers(dest="vehicle", metavar="VEHICLE", required=True)

    p = vehicles.add_parser(
        "diffdrive", help="differential-drive robot on a 2D map or a slice of a 3D map",
        description="Plan for a differential-drive robot (wheel base 0.3 m, radius 0.2 m, "
                    "speed -0.2 to 1 m/s, turn rate up to 1.5 rad/s; controls held 0.5 s). "
                    "Besides the common files, DIR/tracks.csv holds the centre and both "
                    "wheel paths (t, x, y, left_x, left_y, right_x, right_y; within "
                    f"{TRACK_TOLERANCE:g} m of the true curves) and DIR/controls.csv the "
                    "wheel speeds; --compare also writes DIR/biased_vs_unbiased.png.")
    p.add_argument("map", metavar="MAP",
                   help="2D map file (.map2d: lines 'boundary xmin ymin xmax ymax' and "
                        "'rect xmin ymin xmax ymax'), or a 3D map file or built-in world "
                        "spec sliced at --height")
    p.add_argument("--start", nargs=3, type=coordinate, required=True,
                   metavar=("X", "Y", "THETA"),
                   help=f"start position, each {COORDINATE.describe()}, and heading, "
                        f"{HEADING_RADIANS.describe()}")
    p.add_argument("--goal", nargs=2, type=coordinate, required=True, metavar=("X", "Y"),
                   help=f"centre of the goal region, each {COORDINATE.describe()}")
    p.add_argument("--height", type=coordinate, metavar="Z",
                   help=f"slice height of a 3D map, {COORDINATE.describe()} (default: half "
                        "way up its z range)")
    p.add_argument("--margin", type=margin_value, default=0.0, metavar="M",
                   help=f"clearance kept beyond the robot's radius, {MARGIN.describe()} "
                        "(default: 0)")
    p.add_argument("--compare", action="store_true",
                   help="also run the other sampling (biased / unbiased) with the same seed")
    _add_search_arguments(p)
    p.set_defaults(handler=diffdrive)

    p = vehicles.add_parser(
        "quadrotor", help="quadrotor steered by sampled roll, pitch and thrust in a 3D map",
        description="Plan for a quadrotor point mass steered by roll, pitch and thrust "
                    "(80 g, tilt up to 0.35 rad, thrust 0.5 to 1.5 times its weight, at "
                    "most 2 m/s; controls held 0.5 s), from rest. DIR/states.csv holds "
                    "positions and velocities, DIR/controls.csv phi, theta (rad) and thrust "
                    "(N); kino.json also gives how closely the controls replayed through "
                    "the point-mass model reproduce the planned positions (to round-off). "
                    "The plan ends with a stop planned exactly onto the goal. --fly also "
                    "flies it closed loop (its states as the reference) on the simulated "
                    "vehicle, as quadnav fly flies a trajectory, judges it reached when it "
                    "ends within --goal-radius of the goal, and writes that run folder to "
                    "DIR/flight.")
    add_map_argument(p)
    add_start_goal_arguments(p, file=False)
    add_margin_argument(p)
    _add_search_arguments(p)
    p.add_argument("--fly", action="store_true",
                   help="also fly the plan closed loop on the simulated vehicle and write "
                        "its run folder to DIR/flight (exit 1 if the flight fails)")
    p.add_argument("--no-figures", action="store_true",
                   help="skip kino.png, controls.png and the flight's figures and report "
                        "(quadnav report DIR/flight writes the report later)")
    add_strict_argument(p)
    add_vehicle_arguments(p)
    add_controller_argument(p)
    p.set_defaults(handler=quadrotor)

"""Benchmark: trajectory timings — today's allocation, the new ones and TOPP-RA on the same paths.

Run: ``python bench/trajectory.py [--repeats 5]``, or ``python bench/trajectory.py --quick``
for a smoke run (1 repeat, two maps). TOPP-RA needs the ``bench`` extra
(``pip install 'quadnav[bench]'``, or ``pip install toppra``); without it its column is skipped.

Paths: every public course map with a path (``../shared/maps`` beside the repository, see
``tests/publicmaps.py``; skipped with a note when the folder is absent) and every built-in
world, each planned and refined once as ``quadnav fly`` does (the mission's planner
settings, seed 0). On each path, at 1, 2 and 3 m/s with a 3 m/s^2 limit (top speed and
largest size of the acceleration vector), each contender makes a trajectory:

* ``today``: minimum snap, each segment the time of a rest-to-rest trapezoid, then all
  times stretched alike until the peaks are within the limits (the baseline);
* ``minsnap snap-time``: minimum snap with times minimising snap + weight x total time;
* ``minsnap``, ``quintic``, ``cubic`` with the ``fastest`` timing (the new default);
* ``toppra``: TOPP-RA (``toppra.algorithm.TOPPRA``, its default spline output) along
  toppra's cubic spline through the same waypoints, knots at the cumulative chord length
  (not the same curve, and not checked for collisions). Its limits are per axis (a box),
  so it gets ``v`` and ``a`` on each axis, and its result is then stretched uniformly in
  time (speeds / k, accelerations / k^2) until the sampled peak norms are within ``v``
  and ``a``; the duration shown is the stretched one.

Printed per path and speed: the median wall time of the whole call over the repeats
(quadnav's includes the margin refinement and the exact collision checks), the duration,
its ratio to the rest-to-rest bound along the trajectory's own curve, ``L / v + v / a``
(``2 sqrt(L / a)`` when ``L < v^2 / a``) with ``L`` the curve length (speed integrated over
20,001 samples), the mean speed ``L / duration``, the sampled peak speed and acceleration
norms, and the margin kept from the real blocks and the boundary off the legs: exact for
quadnav (:func:`~quadnav.trajectory.clearance.space.trajectory_margins`), sampled every 5 mm of
chord for toppra's spline. Then a summary per contender: median and largest ratio (and
where), median mean speed at each speed, and the median over the runs of the compute time
relative to ``today``'s in the same run — over the course maps, then over all paths.
Nothing is asserted.
"""

from __future__ import annotations

import argparse
import importlib.util
import math
import statistics
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from planning import cell, table

from quadnav.errors import PlanningWarning, QuadnavError
from quadnav.mission import MissionSettings
from quadnav.planning import make_problem, plan
from quadnav.planning.refine import refine
from quadnav.planning.result import distinct
from quadnav.trajectory.clearance.space import SafeSpace, trajectory_margins
from quadnav.trajectory.generate import TrajectorySettings, make_trajectory
from quadnav.trajectory.timing.segment_times import rest_to_rest_duration
from quadnav.world import World, load_world
from quadnav.world.builtin import world_names
from quadnav.world.margins import point_margins

try:
    import toppra
except ImportError:
    toppra = None

REPOSITORY = Path(__file__).resolve().parents[1]
#: The public course maps, beside the repository (never copied into it).
MAPS_FOLDER = REPOSITORY.parent / "shared" / "maps"
#: Top speeds, m/s, and the acceleration limit, m/s^2, every contender is asked for.
SPEEDS = (1.0, 2.0, 3.0)
ACCELERATION = 3.0
#: quadnav's contenders: (name, method, timing); the first is the baseline.
QUADNAV = (("today", "minsnap", "rest-to-rest"), ("minsnap snap-time", "minsnap", "snap-time"),
           ("minsnap", "minsnap", "fastest"), ("quintic", "quintic", "fastest"),
           ("cubic", "cubic", "fastest"))
BASELINE = QUADNAV[0][0]
TOPPRA = "toppra"
#: Samples of a trajectory for its length and peaks.
SAMPLES = 20001
#: Spacing of the samples of toppra's curve whose margins are measured, m of chord.
MARGIN_SPACING = 0.005
#: The paths of a ``--quick`` run.
QUICK = ("rbe595/map1.txt", "window")


@dataclass(frozen=True)
class Case:
    """A refined path (N, 3), m, through ``world``, flown keeping ``margin`` m."""

    name: str
    world: World
    margin: float
    path: np.ndarray


@dataclass(frozen=True)
class Figures:
    """One contender on one path at one speed ``v`` m/s: compute time s, duration s,
    curve length m, sampled peak speed m/s and acceleration m/s^2, margin m (nan: not
    measured); ``error`` says why there is no trajectory (then the rest is nan)."""

    v: float
    seconds: float
    duration: float = math.nan
    length: float = math.nan
    peak_speed: float = math.nan
    peak_acceleration: float = math.nan
    margin: float = math.nan
    error: str = ""

    @property
    def ratio(self) -> float:
        """Duration over the rest-to-rest bound along the curve, ``L / v + v / a``."""
        if math.isnan(self.length):
            return math.nan
        return self.duration / float(rest_to_rest_duration(self.length, self.v, ACCELERATION))

    @property
    def mean_speed(self) -> float:
        """Curve length over duration, m/s."""
        return self.length / self.duration


def timed(function: Callable[[], object], repeats: int) -> tuple[object, float]:
    """The last result of ``repeats`` calls and their median wall time, s."""
    seconds = []
    for _ in range(repeats):
        began = time.perf_counter()
        result = function()
        seconds.append(time.perf_counter() - began)
    return result, statistics.median(seconds)


def refined_path(name: str, world: World, start: np.ndarray, goal: np.ndarray, margin: float
                 ) -> Case | None:
    """The path ``quadnav fly`` flies (mission planner settings, seed 0, refined), None
    when the planner finds none."""
    settings = MissionSettings()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PlanningWarning)
        problem = make_problem(world, start, goal, margin)
        result = plan(problem, settings.planning, settings.planner)
        if not result.solved:
            return None
        path = refine(problem, result).path
    return Case(name, world, margin, distinct(path))


def course_maps(names: list[str] | None) -> list[tuple[str, World, np.ndarray, np.ndarray, float]]:
    """The course maps (all, or those in ``names``) with their start, goal and margin
    (``tests/publicmaps.py``); none, with a note, when the maps folder is absent."""
    if not MAPS_FOLDER.is_dir():
        print(f"note: {MAPS_FOLDER} is absent; the course maps are skipped")
        return []
    spec = importlib.util.spec_from_file_location("publicmaps",
                                                  REPOSITORY / "tests" / "publicmaps.py")
    publicmaps = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(publicmaps)
    return [(name, *publicmaps.course_query(MAPS_FOLDER, name)) for name in publicmaps.MAPS
            if names is None or name in names]


def queries(quick: bool) -> list[tuple[str, World, np.ndarray, np.ndarray, float]]:
    """(name, world, start, goal, margin) of every course map with a path and every
    built-in world (a few with ``quick``)."""
    names = list(QUICK) if quick else None
    found = course_maps(names)
    for name in world_names():
        if names is None or name in names:
            world = load_world(name)
            found.append((name, world, world.start, world.goal, world.margin))
    return found


def cases(quick: bool) -> list[Case]:
    """The refined paths of the course maps and the built-in worlds (a few with ``quick``)."""
    found_queries = queries(quick)
    found = [refined_path(*query) for query in found_queries]
    for query, case in zip(found_queries, found, strict=True):
        if case is None:
            print(f"note: no path found on {query[0]}; skipped")
    return [case for case in found if case is not None]


def peaks(t: np.ndarray, velocity: np.ndarray, acceleration: np.ndarray
          ) -> tuple[float, float, float]:
    """Curve length m (speed integrated over ``t`` (K,) s), peak speed m/s and peak
    acceleration m/s^2 of the samples (K, 3)."""
    speed = np.linalg.norm(velocity, axis=1)
    return (float(np.trapezoid(speed, t)), float(speed.max()),
            float(np.linalg.norm(acceleration, axis=1).max()))


def quadnav_figures(case: Case, method: str, timing: str, v: float, repeats: int) -> Figures:
    """``make_trajectory`` with ``method`` and ``timing`` at ``v`` m/s on ``case``."""
    settings = TrajectorySettings(method=method, v_max=v, a_max=ACCELERATION, timing=timing)
    try:
        trajectory, seconds = timed(
            lambda: make_trajectory(case.path, settings, SafeSpace(case.world, case.margin)),
            repeats)
    except QuadnavError as error:
        return Figures(v, math.nan, error=str(error))
    t = np.linspace(0.0, trajectory.duration, SAMPLES)
    length, speed, acceleration = peaks(t, trajectory.velocity(t), trajectory.acceleration(t))
    return Figures(v, seconds, trajectory.duration, length, speed, acceleration,
                   trajectory_margins(trajectory, case.world)[0])


def toppra_figures(case: Case, v: float, repeats: int) -> Figures:
    """TOPP-RA at ``v`` m/s and :data:`ACCELERATION` per axis on ``case``, stretched
    uniformly until the norms are within them (see the module docstring)."""
    chord = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(case.path, axis=0),
                                                            axis=1))])

    def run() -> tuple[object, object]:
        curve = toppra.SplineInterpolator(chord, case.path)
        limits = [toppra.constraint.JointVelocityConstraint(np.tile([-v, v], (3, 1))),
                  toppra.constraint.JointAccelerationConstraint(
                      np.tile([-ACCELERATION, ACCELERATION], (3, 1)))]
        return curve, toppra.algorithm.TOPPRA(limits, curve).compute_trajectory(0, 0)

    (curve, timed_curve), seconds = timed(run, repeats)
    if timed_curve is None:
        return Figures(v, seconds, error="TOPP-RA found no parameterisation")
    begin, end = timed_curve.path_interval
    t = np.linspace(begin, end, SAMPLES)
    length, speed, acceleration = peaks(t, timed_curve(t, 1), timed_curve(t, 2))
    stretch = max(1.0, speed / v, math.sqrt(acceleration / ACCELERATION))
    head, tail = SafeSpace(case.world, case.margin).split(case.path)
    s = np.linspace(chord[head], chord[tail],
                    max(2, math.ceil((chord[tail] - chord[head]) / MARGIN_SPACING) + 1))
    margin = float(point_margins(case.world, curve(s)).min())
    return Figures(v, seconds, stretch * (end - begin), length, speed / stretch,
                   acceleration / stretch**2, margin)


def measure(case: Case, repeats: int) -> dict[str, list[Figures]]:
    """Every contender's figures on ``case`` at each of :data:`SPEEDS`."""
    figures = {name: [quadnav_figures(case, method, timing, v, repeats) for v in SPEEDS]
               for name, method, timing in QUADNAV}
    if toppra is not None:
        figures[TOPPRA] = [toppra_figures(case, v, repeats) for v in SPEEDS]
    return figures


def warm_up(case: Case) -> None:
    """Run every contender once on ``case``, untimed, so compiled kernels are loaded (or
    compiled) before the clock starts."""
    for _, method, timing in QUADNAV:
        quadnav_figures(case, method, timing, SPEEDS[0], 1)
    if toppra is not None:
        toppra_figures(case, SPEEDS[0], 1)


def case_table(case: Case, figures: dict[str, list[Figures]]) -> str:
    """One path's figures as a markdown table, a row per speed and contender."""
    rows = []
    for i, v in enumerate(SPEEDS):
        for name, runs in figures.items():
            f = runs[i]
            if f.error:
                rows.append([f"{v:g}", name, "fail: " + f.error, *["-"] * 6])
                continue
            rows.append([f"{v:g}", name, f"{1e3 * f.seconds:.1f}", f"{f.duration:.2f}",
                         f"{f.ratio:.3f}", f"{f.mean_speed:.2f}", f"{f.peak_speed:.2f}",
                         f"{f.peak_acceleration:.2f}", cell(f.margin, 4)])
    header = ["v m/s", "contender", "compute ms", "duration s", "ratio", "mean m/s",
              "peak v", "peak a", "margin m"]
    return (f"{case.name}: {len(case.path)} waypoints, margin {case.margin:g} m\n\n"
            + table(header, rows))


def summary(all_figures: dict[str, dict[str, list[Figures]]]) -> str:
    """Per contender over every path (by name) and speed: ratios, mean speeds, relative
    compute time."""
    speeds = "/".join(f"{v:g}" for v in SPEEDS)
    header = ["contender", "runs", "median ratio", "max ratio", "max at",
              f"median mean speed at {speeds} m/s", "median compute ms", f"compute / {BASELINE}"]
    rows = []
    for name in next(iter(all_figures.values())):
        runs = [(path, f) for path, figures in all_figures.items() for f in figures[name]]
        done = [f for _, f in runs if not f.error]
        relative = [f.seconds / base.seconds for figures in all_figures.values()
                    for f, base in zip(figures[name], figures[BASELINE], strict=True)
                    if not (f.error or base.error)]
        worst_path, worst = max(((path, f) for path, f in runs if not f.error),
                                key=lambda run: run[1].ratio)
        rows.append([name, f"{len(done)}/{len(runs)}",
                     cell(statistics.median([f.ratio for f in done]), 3), cell(worst.ratio, 3),
                     f"{worst_path}, {worst.v:g} m/s",
                     " / ".join(cell(statistics.median([f.mean_speed for f in done
                                                        if f.v == v]), 3) for v in SPEEDS),
                     cell(1e3 * statistics.median([f.seconds for f in done]), 3),
                     f"{statistics.median(relative):.3g}x"])
    return table(header, rows)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5, help="timed calls per figure")
    parser.add_argument("--quick", action="store_true", help="1 repeat, two paths")
    args = parser.parse_args()
    repeats = 1 if args.quick else args.repeats
    if toppra is None:
        print("note: toppra is not installed; its column is skipped "
              "(pip install 'quadnav[bench]', or pip install toppra)")
    began = time.perf_counter()
    paths = cases(args.quick)
    warm_up(paths[0])
    all_figures = {}
    for case in paths:
        all_figures[case.name] = measure(case, repeats)
        print(case_table(case, all_figures[case.name]) + "\n", flush=True)
    print(f"{repeats} repeats, {time.perf_counter() - began:.0f} s in all.")
    course = {name: figures for name, figures in all_figures.items() if "/" in name}
    for title, chosen in (("the course maps", course), ("all paths", all_figures)):
        if chosen:
            print(f"\nSummary over {title}: {len(chosen)} paths x {len(SPEEDS)} speeds, "
                  f"a = {ACCELERATION:g} m/s^2\n\n{summary(chosen)}")


if __name__ == "__main__":
    main()

"""Benchmark: the stall rule against the fixed budget of 50,000 samples after the first path.

Run: ``python bench/planning_budget.py [--seeds 10]``, or ``--quick`` for a smoke run (2
seeds, two maps).

On every course map with a search to make (``../shared/maps``, when it is there: those whose
goal is in sight of the start are joined without a search and left out) and every built-in
world, each with its own start, goal and margin, seeds 0 to N - 1, it plans as ``quadnav
fly`` does (RRT*, then shortcut and smooth) twice per seed, in turn: with the baseline,
``fly``'s budget before the stall rule (50,000 samples after the first path, ``--stall
0``), and with ``fly``'s default (the stall rule, :mod:`quadnav.planning.stall`, with those
50,000 as its ceiling). Printed per map: the median refined length of each, m; the mean
and the largest over the seeds of the ratio stall / fixed of the same seed's refined
lengths; the median samples and CPU milliseconds (plan and refine, this process's CPU
time) of each and their ratio; and how many searches the stall rule ended. Then the median
and the worst map's mean ratio against the acceptance bounds (1 % and 2 % longer). Every
kernel runs once before the timed runs, so compilation is not counted.
"""

from __future__ import annotations

import argparse
import statistics
import time
import warnings
from dataclasses import dataclass

from planning import table
from trajectory import queries

from quadnav.errors import PlanningWarning
from quadnav.mission import MissionSettings
from quadnav.planning import PlannerSettings, PlanningProblem, direct_result, make_problem, plan
from quadnav.planning.refine import refine

#: The acceptance bounds: the stall rule's refined length at most this much longer than
#: the fixed budget's on the median map, and on the worst map.
MEDIAN_BOUND, WORST_BOUND = 1.01, 1.02
#: Seed of the warm-up runs, outside the range of the timed seeds.
WARM_UP_SEED = 10**6


@dataclass(frozen=True)
class Run:
    """One plan and refine: refined length m, samples drawn, CPU s, what ended the search."""

    length: float
    samples: int
    cpu: float
    stopped_by: str


def budgets() -> tuple[PlannerSettings, PlannerSettings]:
    """The baseline (``fly``'s samples with no stall rule) and ``fly``'s default."""
    default = MissionSettings().planning
    return default.replace(stall=None), default


def run(problem: PlanningProblem, settings: PlannerSettings) -> Run:
    """Plan and refine ``problem`` as ``quadnav fly`` does, timed in CPU seconds."""
    began = time.process_time()
    result = plan(problem, settings)
    refined = refine(problem, result)
    cpu = time.process_time() - began
    return Run(refined.length, result.stats.iterations, cpu, str(result.stats.stopped_by))


def measure(problem: PlanningProblem, seeds: int) -> tuple[list[Run], list[Run]]:
    """The fixed and stall runs of ``problem``, seed by seed in turn, after a warm-up."""
    fixed, stall = budgets()
    run(problem, stall.replace(seed=WARM_UP_SEED))
    pairs = [(run(problem, fixed.replace(seed=seed)), run(problem, stall.replace(seed=seed)))
             for seed in range(seeds)]
    return [pair[0] for pair in pairs], [pair[1] for pair in pairs]


def row(name: str, fixed: list[Run], stall: list[Run]) -> tuple[list[str], float]:
    """The table row of one map and its mean ratio of refined lengths, stall / fixed."""
    ratios = [s.length / f.length for f, s in zip(fixed, stall, strict=True)]
    mean_ratio = statistics.fmean(ratios)

    def median(runs: list[Run], field: str) -> float:
        return statistics.median(getattr(r, field) for r in runs)

    cpu_fixed, cpu_stall = median(fixed, "cpu"), median(stall, "cpu")
    stalled = sum(r.stopped_by == "stall" for r in stall)
    return [name, f"{median(fixed, 'length'):.3f}", f"{median(stall, 'length'):.3f}",
            f"{100 * (mean_ratio - 1):+.2f} %", f"{100 * (max(ratios) - 1):+.2f} %",
            f"{median(fixed, 'samples'):,.0f}", f"{median(stall, 'samples'):,.0f}",
            f"{1e3 * cpu_fixed:.0f}", f"{1e3 * cpu_stall:.0f}", f"{cpu_stall / cpu_fixed:.2f}",
            f"{stalled}/{len(stall)}"], mean_ratio


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args()
    seeds = 2 if args.quick else args.seeds
    rows, ratios = [], []
    for name, world, start, goal, margin in queries(args.quick):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", PlanningWarning)
            problem = make_problem(world, start, goal, margin)
        if direct_result(problem, "rrtstar", PlannerSettings()) is not None:
            print(f"note: {name}: the goal is in sight of the start, no search; left out")
            continue
        cells, mean_ratio = row(name, *measure(problem, seeds))
        rows.append(cells)
        ratios.append(mean_ratio)
    print(f"refined lengths and CPU of plan + refine, {seeds} seeds, fixed = 50,000 samples "
          "after the first path, stall = fly's default\n")
    print(table(["map", "fixed m", "stall m", "stall/fixed mean", "worst seed",
                 "fixed samples", "stall samples", "fixed CPU ms", "stall CPU ms",
                 "CPU ratio", "ended by stall"], rows))
    median_map, worst_map = statistics.median(ratios), max(ratios)
    print(f"\nmedian map {100 * (median_map - 1):+.2f} % (bound "
          f"{100 * (MEDIAN_BOUND - 1):.0f} %), worst map {100 * (worst_map - 1):+.2f} % "
          f"(bound {100 * (WORST_BOUND - 1):.0f} %): "
          f"{'within' if median_map <= MEDIAN_BOUND and worst_map <= WORST_BOUND else 'OUT OF'}"
          " bounds")


if __name__ == "__main__":
    main()

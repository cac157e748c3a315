"""Benchmark: quadnav's RRT* against OMPL's RRT* and a textbook RRT*, on the same queries.

Run: ``python bench/planning.py [--seeds 20] [--baseline-seeds N] [--json FILE]``, or
``python bench/planning.py --quick`` for a smoke run (3 seeds, short budgets).

For each map (the public ``rbe595/map1.txt`` when ``../shared/maps`` is there, the
built-in ``forest`` and a 100 x 100 x 20 m forest of about 2,400 trunks), with the same
start, goal, step, goal bias and 0.2 m margin for every planner, it prints medians over
the seeds of:

* the time to the first solution (``stats.time_to_first``, each planner stopping at its
  first solution) of ours, compiled OMPL (``bench/ompl_rrtstar.cpp``: C++ RRT* with an
  exact box checker, built against Debian's ``libompl-dev``; its column is left out, with
  the reason, where that is not installed), OMPL through its Python bindings, and the
  textbook baseline (``bench/textbook_rrtstar.py``), with the ratios against ours; a run
  that finds nothing within its limit counts as "more than the limit". As OMPL measures
  it, each planner's set-up (spatial indexes, arrays, OMPL's space information and
  planner set-up) is outside the clock; it is reported in a table of its own;
* the path length after a fixed budget, raw and post-processed: ours then
  :func:`quadnav.planning.refine.refine`, OMPL's then
  :func:`quadnav.planning.ompl_planners.simplify_ompl`, and the ratio OMPL / ours.

Every planner with compiled code runs once on each map before the timed runs, so
compilation is not counted; the textbook baseline is plain Python and needs no warm-up.
Seeds interleave the planners so that a slow spell of the machine hits them alike; the
compiled driver runs as one process per seed (OMPL seeds its generator once per process)
and times itself.
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import sys
import tempfile
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from compiled_ompl import FirstRun, compiled_ompl, run_compiled, write_problem
from textbook_rrtstar import plan_textbook

from quadnav.planning import (
    PlannerSettings,
    PlanningProblem,
    PlanResult,
    make_problem,
    path_length,
    plan,
)
from quadnav.planning.refine import refine
from quadnav.planning.registry import ompl_available
from quadnav.world import load_world

#: Public course maps, beside the checkout.
SHARED_MAPS = Path(__file__).resolve().parents[1].parent / "shared" / "maps"
#: Safety margin of every query, metres.
MARGIN = 0.2
#: Seed of the warm-up runs, outside the range of the timed seeds.
WARM_UP_SEED = 10**6

#: Column labels: OMPL is OMPL's RRT* through its Python bindings, OMPL_CPP compiled.
OURS, OMPL_CPP, OMPL, TEXTBOOK = "ours", "OMPL C++", "OMPL py", "textbook"


@dataclass(frozen=True)
class Case:
    """One benchmark query: a map and a start and goal (``None``: the map's own)."""

    label: str
    source: str | Path
    start: tuple[float, float, float] | None = None
    goal: tuple[float, float, float] | None = None


CASES = (
    Case("rbe595/map1", SHARED_MAPS / "rbe595" / "map1.txt", (0.5, -4.5, 0.5), (8.0, 18.0, 3.0)),
    Case("forest", "forest"),
    Case("forest 100 m", "forest:size=100x100x20,density=0.08"),
)


@dataclass(frozen=True)
class Budgets:
    """Time limits, s: for a first solution (ours, OMPL), the textbook's cap, and the
    search budget of the path length runs."""

    first: float
    textbook: float
    length: float


@dataclass
class Figures:
    """Per-seed figures of one map: ``values[name]`` lists one number per run (``inf``
    for a run that found no path), in seed order."""

    label: str
    blocks: int
    straight: float
    values: dict[str, list[float]] = field(default_factory=dict)

    def add(self, kind: str, planner: str, value: float) -> None:
        """Record one run's ``kind`` figure (e.g. ``"first"``) for ``planner``."""
        self.values.setdefault(f"{kind} {planner}", []).append(value)

    def runs(self, kind: str, planner: str) -> list[float]:
        """The ``kind`` figures of ``planner``, one per run (none when not measured)."""
        return self.values.get(f"{kind} {planner}", [])


def _first_run(result: PlanResult, setup_measured: bool = True) -> FirstRun:
    """The figures of a :class:`PlanResult` stopped at its first solution."""
    found = result.stats.time_to_first
    return FirstRun(math.inf if found is None else found,
                    result.stats.setup_seconds if setup_measured else math.nan,
                    result.length if result.solved else math.inf)


def first_solution_runners(budgets: Budgets, with_ompl: bool, compiled: Path | None,
                           problem_file: Path
                           ) -> dict[str, Callable[[PlanningProblem, int], FirstRun]]:
    """Planner label -> ``run(problem, seed)`` that stops at the first solution; the
    compiled driver reads the problem from ``problem_file``."""
    def settings(seed: int, limit: float) -> PlannerSettings:
        return PlannerSettings(seed=seed, stop_at_first=True, time_limit=limit)

    def ours(problem: PlanningProblem, seed: int) -> FirstRun:
        return _first_run(plan(problem, settings(seed, budgets.first), "rrtstar"))

    runners = {OURS: ours}
    if compiled is not None:
        runners[OMPL_CPP] = lambda p, s: run_compiled(compiled, problem_file, p, s,
                                                      budgets.first)
    if with_ompl:
        runners[OMPL] = lambda p, s: _first_run(
            plan(p, settings(s, budgets.first), "ompl:RRTstar"))
    runners[TEXTBOOK] = lambda p, s: _first_run(
        plan_textbook(p, settings(s, budgets.textbook)), setup_measured=False)
    return runners


def lengths_ours(problem: PlanningProblem, seed: int, budget: float) -> tuple[float, float]:
    """(raw, refined) path length, metres, of our RRT* after ``budget`` seconds."""
    result = plan(problem, PlannerSettings(seed=seed, time_limit=budget), "rrtstar")
    if not result.solved:
        return math.inf, math.inf
    return result.length, refine(problem, result).length


def lengths_ompl(problem: PlanningProblem, seed: int, budget: float) -> tuple[float, float]:
    """(raw, simplified) path length, metres, of OMPL's RRT* after ``budget`` seconds."""
    from quadnav.planning.ompl_planners import simplify_ompl  # OMPL is optional

    result = plan(problem, PlannerSettings(seed=seed, time_limit=budget), "ompl:RRTstar")
    if not result.solved:
        return math.inf, math.inf
    return result.length, path_length(simplify_ompl(problem, result.path, seed=seed))


def measure(case: Case, seeds: int, baseline_seeds: int, budgets: Budgets, with_ompl: bool,
            compiled: Path | None, scratch: Path) -> Figures:
    """Run every planner on one map for the given numbers of seeds (the compiled
    driver, when there is one, reads the problem from a file in ``scratch``)."""
    world = load_world(case.source)
    problem = make_problem(world, case.start, case.goal, MARGIN)
    figures = Figures(case.label, len(world.blocks),
                      float(np.linalg.norm(problem.goal - problem.start)))
    problem_file = scratch / "problem.txt"
    write_problem(problem, PlannerSettings(), problem_file)
    runners = first_solution_runners(budgets, with_ompl, compiled, problem_file)
    length_runs = {OURS: lengths_ours}
    if with_ompl:
        length_runs[OMPL] = lengths_ompl
    for name, run in runners.items():
        if name != TEXTBOOK:
            run(problem, WARM_UP_SEED)
    for run in length_runs.values():
        run(problem, WARM_UP_SEED, budgets.length)

    for seed in range(seeds):
        print(f"  {case.label}: seed {seed + 1}/{seeds}", file=sys.stderr, flush=True)
        for name, run in runners.items():
            if name == TEXTBOOK and seed >= baseline_seeds:
                continue
            run_figures = run(problem, seed)
            figures.add("first", name, run_figures.first)
            figures.add("setup", name, run_figures.setup)
            figures.add("first length", name, run_figures.length)
        for name, run in length_runs.items():
            raw, post = run(problem, seed, budgets.length)
            figures.add("raw", name, raw)
            figures.add("post", name, post)
    return figures


# ------------------------------------------------------------------- reporting
def median(values: list[float]) -> float:
    """Median of the runs (``inf`` runs count as the longest), ``nan`` if there are none."""
    return statistics.median(values) if values else math.nan


def solved(values: list[float]) -> str:
    """``found/runs``."""
    return f"{sum(math.isfinite(v) for v in values)}/{len(values)}"


def _digits(value: float, digits: int) -> str:
    """``value`` to ``digits`` significant digits, trailing zeros kept (``1.00``); whole
    numbers from ``10^digits`` on (``1340``)."""
    if abs(value) >= 10**digits:
        return f"{value:.0f}"
    return f"{value:#.{digits}g}".rstrip(".")


def cell(value: float, digits: int, cap: float | None = None) -> str:
    """A figure for the table: ``-`` when not measured, ``> cap`` or ``none`` when
    the median run found nothing."""
    if math.isnan(value):
        return "-"
    if math.isinf(value):
        return f"> {cap:g}" if cap is not None else "none"
    return _digits(value, digits)


def ratio(numerator: float, denominator: float, cap: float | None = None) -> str:
    """``numerator / denominator`` as ``3.2x``; ``> Nx`` when only the numerator hit its
    cap; ``-`` when it cannot be told."""
    if math.isnan(numerator) or math.isnan(denominator) or not math.isfinite(denominator):
        return "-"
    if math.isinf(numerator):
        return f"> {cap / denominator:.3g}x" if cap is not None else "-"
    return f"{_digits(numerator / denominator, 3)}x"


def table(header: list[str], rows: list[list[str]]) -> str:
    """A markdown table with columns padded to their widest entry."""
    widths = [max(len(r[i]) for r in [header, *rows]) for i in range(len(header))]

    def line(row: list[str]) -> str:
        return "| " + " | ".join(v.ljust(w) for v, w in zip(row, widths, strict=True)) + " |"

    return "\n".join([line(header), line(["-" * w for w in widths]), *map(line, rows)])


def report(all_figures: list[Figures], budgets: Budgets, names: list[str]) -> str:
    """The figures of the planners ``names`` (ours first) as three markdown tables, with
    how many runs each median is over."""
    with_ompl = OMPL in names
    searched = [OURS, *([OMPL] if with_ompl else [])]  # path length after a budget
    caps = {n: budgets.textbook if n == TEXTBOOK else budgets.first for n in names}
    first_rows, call_rows, length_rows = [], [], []
    for f in all_figures:
        first = {n: median(f.runs("first", n)) for n in names}
        first_rows.append(
            [f.label, str(f.blocks)]
            + [f"{cell(first[n], 3, caps[n])} ({solved(f.runs('first', n))})" for n in names]
            + [ratio(first[n], first[OURS], caps[n]) for n in names[1:]])
        call_rows.append(
            [f.label]
            + [cell(median(f.runs("setup", n)), 3) for n in names]
            + [cell(median(f.runs("first length", n)), 4) for n in names])
        raw = {n: median(f.runs("raw", n)) for n in searched}
        post = {n: median(f.runs("post", n)) for n in searched}
        length_rows.append(
            [f.label, f"{f.straight:.4g}"]
            + [f"{cell(raw[n], 4)} / {cell(post[n], 4)} ({solved(f.runs('post', n))})"
               for n in searched]
            + ([ratio(raw[OMPL], raw[OURS]), ratio(post[OMPL], post[OURS])] if with_ompl else []))
    runs = all_figures[0].runs  # every map has the same numbers of runs
    counts = ", ".join(f"{n} {len(runs('first', n))}" for n in names)
    return "\n".join([
        f"## Time to first solution, s (median; runs per map: {counts}; limit "
        f"{budgets.first:g} s, textbook cap {budgets.textbook:g} s)",
        "",
        table(["map", "blocks", *(f"{n} (found)" for n in names),
               *(f"{n}/ours" for n in names[1:])], first_rows),
        "",
        "## The same runs: set-up outside the clock, s, and first path length, m",
        "",
        table(["map", *(f"set-up {n}" for n in names), *(f"length {n}" for n in names)],
              call_rows),
        "",
        f"## Path length, m, after a {budgets.length:g} s search (median over "
        f"{len(runs('post', OURS))} runs; "
        "post = ours refined, OMPL simplified)",
        "",
        table(["map", "straight line", *(f"{n} raw / post (found)" for n in searched),
               *(["OMPL/ours raw", "OMPL/ours post"] if with_ompl else [])], length_rows),
    ])


def as_json(all_figures: list[Figures], budgets: Budgets, seeds: int, baseline_seeds: int
            ) -> dict[str, object]:
    """Every per-seed figure and its median; runs that found nothing are ``null``."""
    def finite(value: float) -> float | None:
        return value if math.isfinite(value) else None

    return {
        "margin": MARGIN, "seeds": seeds, "baseline_seeds": baseline_seeds,
        "budgets_s": {"first": budgets.first, "textbook_cap": budgets.textbook,
                      "length": budgets.length},
        "maps": [{"map": f.label, "blocks": f.blocks, "straight_line_m": f.straight,
                  "figures": {name: {"median": finite(median(values)),
                                     "found": sum(math.isfinite(v) for v in values),
                                     "runs": [finite(v) for v in values]}
                              for name, values in f.values.items()}}
                 for f in all_figures],
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=20, help="seeds per planner (20)")
    parser.add_argument("--baseline-seeds", type=int, default=None,
                        help="seeds of the textbook baseline (default: --seeds)")
    parser.add_argument("--quick", action="store_true",
                        help="smoke run: 3 seeds and short budgets")
    parser.add_argument("--first-limit", type=float, default=None,
                        help="time limit of a first-solution run, s (10; quick 2)")
    parser.add_argument("--baseline-cap", type=float, default=None,
                        help="time limit of a textbook run, s (60; quick 5)")
    parser.add_argument("--length-budget", type=float, default=None,
                        help="search budget of the path length runs, s (1; quick 0.3)")
    parser.add_argument("--json", type=Path, help="also write the figures to this JSON file")
    args = parser.parse_args()

    seeds = 3 if args.quick else args.seeds
    baseline_seeds = min(seeds, args.baseline_seeds if args.baseline_seeds is not None
                         else seeds)
    budgets = Budgets(
        first=args.first_limit or (2.0 if args.quick else 10.0),
        textbook=args.baseline_cap or (5.0 if args.quick else 60.0),
        length=args.length_budget or (0.3 if args.quick else 1.0))
    with_ompl = ompl_available()
    if not with_ompl:
        print("OMPL's Python bindings are not installed (pip install 'quadnav[ompl]'): "
              f"the {OMPL} columns are left out")
    compiled, why_not = compiled_ompl()
    if compiled is None:
        print(f"compiled OMPL: {why_not}; the {OMPL_CPP} column is left out")
    names = [OURS, *([OMPL_CPP] if compiled else []), *([OMPL] if with_ompl else []), TEXTBOOK]

    all_figures = []
    for case in CASES:
        if isinstance(case.source, Path) and not case.source.is_file():
            print(f"{case.label}: skipped, {case.source} not found")
            continue
        with tempfile.TemporaryDirectory() as scratch:
            all_figures.append(measure(case, seeds, baseline_seeds, budgets, with_ompl,
                                       compiled, Path(scratch)))
    print(f"margin {MARGIN:g} m; each map's start and goal are the same for every planner\n")
    print(report(all_figures, budgets, names))
    if args.json:
        args.json.write_text(json.dumps(as_json(all_figures, budgets, seeds, baseline_seeds),
                                        indent=2) + "\n", encoding="utf-8")
        print(f"\nfigures written to {args.json}")


if __name__ == "__main__":
    main()

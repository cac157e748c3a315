"""Benchmark: ``quadnav batch`` against a shell loop of ``quadnav fly --no-figures`` processes
flying the same missions, in missions per CPU-second.

Run: ``python bench/batch.py [--missions 20] [--repeats 3] [--workers 2] [--improve N]``,
or ``--quick`` for a smoke run (4 missions, one repeat).

``--cases`` runs instead issue 29's cases on the course map rbe595/map1 (from
``../shared/maps``, with the course's start and goal), with gusts of 0.02 N at 2 m/s and
3 m/s^2: (a) 20 planner seeds x 10 simulation seeds (``seeds = {plan = 20, sim = 10}``), 200
missions whose plans and trajectories are each made once, and (b) 200 planner seeds, each
mission its own plan. It prints per case the median CPU seconds per mission, the medians of
the rows' stage times (planning, trajectory, flight), the successes, the plans made, and the
minutes 10,000 such missions would take on the workers' cores.

``--stages`` flies the missions of both cases (the first ``--missions`` of each; all by
default, 20 with ``--quick``) in this process, one after the other, as one batch worker
flies them (one numba thread, its kernels loaded, maps loaded afresh and a fresh stage
cache for each case, so each case pays the work a map needs once again), and prints per
case where a mission's CPU time goes (:mod:`quadnav.profiling`): per stage the runs, the
missions that ran it, the median and mean ms per mission, the ms of all the missions and
its share of the CPU; then how many missions ran the work a map needs once, and the
median CPU per mission profiled against a baseline pass over the same missions
unprofiled (flown first, which also loads the kernels the missions use).

The missions: the built-in worlds ``forest`` and ``window`` alternately, each with its own
start and goal, seeds 0, 1, 2, ... (half the missions each), at 2 m/s with 3 m/s^2 and
``fly``'s search budget (the stall rule, with at most 50,000 samples of improvement after
the first path; ``--improve`` sets another ceiling, for both) with a 60 s time cap, the
default vehicle and gains. Each repeat runs, in this order:

* ``quadnav batch SPEC --workers W --quiet -o DIR`` (a fresh DIR): one process that spawns
  W workers, each loading the compiled kernels once;
* the baseline: one ``bash`` script that runs ``quadnav fly MAP --seed S --speed 2 --accel 3
  --time 60 --improve N --no-figures --quiet -o DIR`` for each mission in turn (each a new
  process that loads the kernels again and writes its run folder).

CPU seconds are user + system time of every process each started (children included:
``resource.getrusage(RUSAGE_CHILDREN)`` before and after). Printed: the medians over the
repeats of CPU seconds, missions per CPU-second and wall seconds of each, the ratio of
missions per CPU-second (target: at least 5x), and whether every ``fly`` run gave the
metrics of the batch's row (wall times aside). Nothing is asserted.
"""

from __future__ import annotations

import argparse
import json
import resource
import shlex
import statistics
import subprocess
import sys
import tempfile
import time
from contextlib import nullcontext
from dataclasses import dataclass
from pathlib import Path

from planning import table

from quadnav.batch.fly_one import flown_row, load_context, warm_up
from quadnav.batch.folder import PLANS
from quadnav.batch.grid import read_spec
from quadnav.batch.stages import StageCache
from quadnav.batch.table import RESULTS_CSV, WALL_TIME_COLUMNS, read_rows
from quadnav.batch.threads import use_numba_threads
from quadnav.mission import DEFAULT_IMPROVE
from quadnav.profiling import StageProfile, profiled

#: The console script beside this Python.
QUADNAV = str(Path(sys.executable).with_name("quadnav"))
MAPS = ("forest", "window")
SPEED = 2.0
ACCELERATION = 3.0
TIME_CAP = 60.0
TARGET = 5.0
#: Case (a) of issue 29: a course map, its start and goal, and the seeds and gusts.
SHARED_MAP = Path(__file__).resolve().parents[2] / "shared" / "maps" / "rbe595" / "map1.txt"
SHARED_QUERY = {"start": [0.1, -4.9, 0.2], "goal": [8.0, 18.0, 3.0]}
PLAN_SEEDS, SIM_SEEDS, GUSTS = 20, 10, 0.02


@dataclass(frozen=True)
class Measure:
    """One timed run: CPU seconds (children included) and wall seconds."""

    cpu: float
    wall: float


def timed(command: list[str]) -> Measure:
    """Run ``command``, checking it succeeds; its CPU and wall seconds."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    began = time.perf_counter()
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL)
    wall = time.perf_counter() - began
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return Measure(cpu, wall)


def missions(count: int) -> list[tuple[str, int]]:
    """(map, seed) of each mission, in the batch's order (map, then seed)."""
    seeds = count // len(MAPS)
    return [(name, seed) for name in MAPS for seed in range(seeds)]


def write_spec(folder: Path, count: int, improve: int) -> Path:
    """The batch spec of :func:`missions`."""
    path = folder / "spec.toml"
    path.write_text(f"seeds = {count // len(MAPS)}\nspeeds = [{SPEED}]\naccel = {ACCELERATION}"
                    f"\ntime_cap = {TIME_CAP}\nimprove = {improve}\n"
                    f"maps = {json.dumps(list(MAPS))}\n")
    return path


def fly_script(jobs: list[tuple[str, int]], folder: Path, improve: int) -> str:
    """The shell loop: one ``quadnav fly`` per mission, into ``folder``/k."""
    lines = [shlex.join([QUADNAV, "fly", name, "--seed", str(seed), "--speed", str(SPEED),
                         "--accel", str(ACCELERATION), "--time", str(TIME_CAP),
                         "--improve", str(improve),
                         "--no-figures", "--quiet", "-o", str(folder / str(k))]) + " >/dev/null"
             for k, (name, seed) in enumerate(jobs)]
    return "set -e\n" + "\n".join(lines) + "\n"


def same_results(batch_folder: Path, fly_folder: Path, count: int) -> bool:
    """Whether each ``fly`` run's metrics equal its batch row where both have the key
    (wall times aside)."""
    rows = read_rows(batch_folder / RESULTS_CSV)
    for k, row in enumerate(rows[:count]):
        metrics = json.loads((fly_folder / str(k) / "metrics.json").read_text())
        for key, value in metrics.items():
            if (key in row and key not in ("map", "start", "goal", *WALL_TIME_COLUMNS)
                    and row[key] != value):
                return False
    return True


def study_arguments(description: str, parser: argparse.ArgumentParser | None = None
                    ) -> tuple[argparse.Namespace, int, int]:
    """The flags of a batch bench (``--missions``, ``--repeats``, ``--workers``,
    ``--improve``, ``--quick``, on ``parser`` when given, which may hold others), and the
    missions (a multiple of the maps) and repeats they ask for."""
    parser = parser or argparse.ArgumentParser(description=description)
    parser.add_argument("--missions", type=int, default=None, help="missions (20; quick 4)")
    parser.add_argument("--repeats", type=int, default=None, help="repeats (3; quick 1)")
    parser.add_argument("--workers", type=int, default=2, help="local workers (2)")
    parser.add_argument("--improve", type=int, default=DEFAULT_IMPROVE,
                        help=f"search samples after the first path ({DEFAULT_IMPROVE:,})")
    parser.add_argument("--quick", action="store_true", help="smoke run: 4 missions, once")
    args = parser.parse_args()
    count = args.missions or (4 if args.quick else 20)
    return args, count - count % len(MAPS), args.repeats or (1 if args.quick else 3)


#: Case (b): every mission its own plan.
OWN_PLANS = 200
#: The study the cases are projected to, missions.
PROJECTED = 10_000
#: Columns of a row timed per stage (wall seconds inside a worker: one numba thread, so
#: about its CPU seconds).
STAGES = ("planning_time_s", "trajectory_time_s", "sim_wall_time_s")


#: The cases: name, seeds as written in the spec, missions.
CASES = (("(a) shared plans", f"{{plan = {PLAN_SEEDS}, sim = {SIM_SEEDS}}}",
          PLAN_SEEDS * SIM_SEEDS),
         ("(b) own plans", str(OWN_PLANS), OWN_PLANS))


def case_spec(seeds: str, improve: int) -> str:
    """A batch spec of the cases on the course map, its start and goal, ``seeds`` as
    written in the spec."""
    return (f"seeds = {seeds}\nspeeds = [{SPEED}]\ngusts = [{GUSTS}]\n"
            f"accel = {ACCELERATION}\ntime_cap = {TIME_CAP}\nimprove = {improve}\n"
            f"maps = [{{map = {json.dumps(str(SHARED_MAP))}, start = {SHARED_QUERY['start']}, "
            f"goal = {SHARED_QUERY['goal']}}}]\n")


def run_case(name: str, seeds: str, count: int, workers: int, improve: int, repeats: int,
             scratch: Path) -> list[str]:
    """One case flown ``repeats`` times by ``quadnav batch``: its line of the table (median
    CPU seconds per mission, the stages' medians from the rows, successes, plans made and
    the projection to :data:`PROJECTED` missions on ``workers`` cores)."""
    spec = scratch / f"{name}.toml"
    spec.write_text(case_spec(seeds, improve))
    runs, stages, outcomes = [], {stage: [] for stage in STAGES}, set()
    for k in range(repeats):
        out = scratch / f"{name}-{k}"
        runs.append(timed([QUADNAV, "batch", str(spec), "--workers", str(workers), "--quiet",
                           "-o", str(out)]))
        rows = read_rows(out / RESULTS_CSV)
        for stage in STAGES:
            stages[stage] += [row[stage] for row in rows if row[stage] is not None]
        outcomes.add((sum(bool(row["success"]) for row in rows), len(rows),
                      len(list((out / PLANS).iterdir()))))
    per_mission = statistics.median(run.cpu for run in runs) / count
    minutes = per_mission * PROJECTED / workers / 60
    successes, flown, plans = sorted(outcomes)[0]
    return [name, f"{per_mission:.3f}",
            *(f"{1000 * statistics.median(stages[stage]):.1f}" for stage in STAGES),
            f"{successes} of {flown}" + ("" if len(outcomes) == 1 else " (varied)"),
            str(plans), f"{minutes:.1f}"]


def cases(workers: int, improve: int, repeats: int) -> None:
    """Cases (a) and (b) of issue 29 (see the module docstring), timed."""
    with tempfile.TemporaryDirectory() as scratch:
        lines = [run_case(name, seeds, count, workers, improve, repeats, Path(scratch))
                 for name, seeds, count in CASES]
    print(f"{SHARED_MAP.name} with the course's start and goal, gusts {GUSTS:g} N, "
          f"{SPEED:g} m/s, {ACCELERATION:g} m/s^2, fly's search budget (at most {improve:,} "
          f"samples of improvement), quadnav batch --workers {workers}, medians of {repeats} "
          f"repeats; (a) {PLAN_SEEDS} planner seeds x {SIM_SEEDS} simulation seeds, (b) "
          f"{OWN_PLANS} planner seeds. Stages: medians over the rows, ms (a shared plan's "
          f"planning and trajectory times are those of the mission that made it)\n")
    print(table(["case", "CPU s per mission", "planning ms", "trajectory ms", "flight ms",
                 "successes", "plans made", f"{PROJECTED:,} missions, min"], lines))


#: The stages of a mission (quadnav.profiling's names) in the order they run, as the
#: table names them; a stage not listed here is shown by its own name, last.
STAGE_LABELS = {
    "query": "query: checks and legs",
    "proof": "query: connectivity proof",
    "search": "search: set-up and bookkeeping",
    "first path": "search: first path",
    "improvement": "search: improvement",
    "shortcut": "refinement: shortcut",
    "smoothing": "refinement: smoothing",
    "trajectory": "trajectory: all but its timing",
    "fastest timing": "trajectory: fastest timing",
    "simulation": "closed-loop simulation",
    "metrics": "metrics",
    "row": "row",
    "inflated world": "once per map: inflated world",
    "block grid": "once per map: block grid",
    "proof labels": "once per map: proof's voxel labels",
}
#: The stages a map needs once (made where they are made, not where they are found).
ONCE_PER_MAP = ("inflated world", "block grid", "proof labels")
#: The row of the CPU spent outside every stage (settings, keys, the stage cache).
OTHER = "other (settings, keys, caches)"


@dataclass(frozen=True)
class Flown:
    """One mission flown in this process: its CPU seconds and its stages' (empty when
    it was not profiled)."""

    cpu: float
    stages: StageProfile


def fly_in_process(spec_text: str, limit: int | None, scratch: Path, profile: bool
                   ) -> list[Flown]:
    """The first ``limit`` (None: all) missions of the batch spec ``spec_text`` flown one
    after the other in this process as a batch worker flies them: its maps loaded afresh,
    :func:`warm_up`, a fresh stage cache keeping its plans under ``scratch``; each mission
    timed (CPU seconds) and, with ``profile``, profiled."""
    scratch.mkdir(parents=True, exist_ok=True)
    spec_path = scratch / "spec.toml"
    spec_path.write_text(spec_text)
    spec = read_spec(spec_path)
    context = load_context(spec)
    warm_up(context)
    cache = StageCache(scratch / PLANS)
    flown = []
    for mission in spec.missions()[:limit]:
        with profiled() if profile else nullcontext(StageProfile()) as stages:
            began = time.process_time()
            flown_row(context, mission, cache)
            cpu = time.process_time() - began
        flown.append(Flown(cpu, stages))
    return flown


def stage_lines(flown: list[Flown]) -> list[list[str]]:
    """The lines of the stage table of the profiled missions ``flown``: per stage (in
    the order of :data:`STAGE_LABELS`) its runs, the missions that ran it, the median and
    mean ms per mission, the ms of all missions and its share of the CPU; then the CPU
    outside every stage and the total."""
    total = sum(mission.cpu for mission in flown)
    ran = {name for mission in flown for name in mission.stages.runs}
    names = [*(name for name in STAGE_LABELS if name in ran), *sorted(ran - set(STAGE_LABELS))]

    def line(label: str, runs: str, missions: str, seconds: list[float]) -> list[str]:
        return [label, runs, missions, f"{1000 * statistics.median(seconds):.2f}",
                f"{1000 * statistics.mean(seconds):.2f}", f"{1000 * sum(seconds):.1f}",
                f"{100 * sum(seconds) / total:.1f} %"]

    lines = [line(STAGE_LABELS.get(name, name),
                  str(sum(mission.stages.runs[name] for mission in flown)),
                  str(sum(name in mission.stages.runs for mission in flown)),
                  [mission.stages.seconds.get(name, 0.0) for mission in flown])
             for name in names]
    other = [mission.cpu - sum(mission.stages.seconds.values()) for mission in flown]
    return [*lines, line(OTHER, "", "", other),
            line("total", "", str(len(flown)), [mission.cpu for mission in flown])]


def once_per_map(flown: list[Flown]) -> str:
    """How many of the missions ``flown`` ran the work a map needs once, and its runs."""
    ran = [mission for mission in flown
           if any(mission.stages.runs[name] for name in ONCE_PER_MAP)]
    runs = ", ".join(f"{name} {sum(mission.stages.runs[name] for mission in flown)}"
                     for name in ONCE_PER_MAP)
    return (f"work a map needs once ran in {len(ran)} of {len(flown)} missions "
            f"(runs: {runs})")


def stage_profiles(improve: int, limit: int | None) -> None:
    """Cases (a) and (b)'s missions (the first ``limit`` of each) flown and profiled in
    this process (see the module docstring)."""
    use_numba_threads(1)
    print(f"{SHARED_MAP.name} with the course's start and goal, gusts {GUSTS:g} N, "
          f"{SPEED:g} m/s, {ACCELERATION:g} m/s^2, fly's search budget (at most {improve:,} "
          f"samples of improvement), flown in one process with one numba thread as a "
          f"batch worker flies them; CPU ms per mission (process time) by stage, each "
          f"stage's own (the stages it runs excluded)")
    for name, seeds, count in CASES:
        with tempfile.TemporaryDirectory() as scratch:
            baseline = fly_in_process(case_spec(seeds, improve), limit, Path(scratch) / "base",
                                      profile=False)
            flown = fly_in_process(case_spec(seeds, improve), limit, Path(scratch) / "prof",
                                   profile=True)
        plain = statistics.median(mission.cpu for mission in baseline)
        profiled_cpu = statistics.median(mission.cpu for mission in flown)
        print(f"\n{name}: {len(flown)} of its {count} missions\n")
        print(table(["stage", "runs", "missions", "median ms per mission",
                     "mean ms per mission", "ms in all", "share of CPU"], stage_lines(flown)))
        print(f"\n{once_per_map(flown)}; median CPU per mission {1000 * profiled_cpu:.1f} ms "
              f"profiled, {1000 * plain:.1f} ms unprofiled ({profiled_cpu / plain:.2f}x)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", action="store_true",
                        help="cases (a) 200 missions sharing 20 plans and (b) 200 missions "
                             "of their own plans on rbe595/map1, with the projection")
    parser.add_argument("--stages", action="store_true",
                        help="where a mission's CPU goes, stage by stage: the missions of "
                             "both cases profiled in this process (the first --missions of "
                             "each; all without it)")
    args, count, repeats = study_arguments("", parser)
    if args.stages:
        stage_profiles(args.improve, args.missions or (20 if args.quick else None))
        return
    if args.cases:
        cases(args.workers, args.improve, repeats)
        return
    jobs = missions(count)
    batch_runs, fly_runs, agree = [], [], []
    with tempfile.TemporaryDirectory() as scratch:
        root = Path(scratch)
        spec = write_spec(root, count, args.improve)
        for k in range(repeats):
            print(f"  repeat {k + 1}/{repeats}: quadnav batch, then the fly loop",
                  file=sys.stderr, flush=True)
            out = root / f"batch-{k}"
            batch_runs.append(timed([QUADNAV, "batch", str(spec), "--workers",
                                     str(args.workers), "--quiet", "-o", str(out)]))
            script = root / f"fly-{k}.sh"
            script.write_text(fly_script(jobs, root / f"fly-{k}", args.improve))
            fly_runs.append(timed(["bash", str(script)]))
            agree.append(same_results(out, root / f"fly-{k}", count))

    def row(name: str, runs: list[Measure]) -> list[str]:
        cpu = statistics.median(m.cpu for m in runs)
        wall = statistics.median(m.wall for m in runs)
        return [name, f"{cpu:.1f}", f"{count / cpu:.3f}", f"{wall:.1f}"]

    print(f"{count} missions ({', '.join(MAPS)}, seeds 0-{count // len(MAPS) - 1}, "
          f"{SPEED:g} m/s, {ACCELERATION:g} m/s^2, {args.improve:,} samples of improvement); "
          f"medians of {repeats} repeats\n")
    print(table(["run", "CPU s", "missions per CPU-s", "wall s"],
                [row(f"quadnav batch --workers {args.workers}", batch_runs),
                 row("shell loop of quadnav fly --no-figures", fly_runs)]))
    ratio = statistics.median(f.cpu / b.cpu for b, f in zip(batch_runs, fly_runs, strict=True))
    print(f"\nmissions per CPU-second, batch / fly loop: {ratio:.1f}x (target >= {TARGET:g}x)")
    print(f"every fly run gave its batch row's metrics: {'yes' if all(agree) else 'NO'}")


if __name__ == "__main__":
    main()

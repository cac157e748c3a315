"""Benchmark: the CPU a batch's local workers spend with one numba thread each (what
``quadnav batch`` does) against numba's own thread count in each (one per CPU: the
baseline), on the same missions in the same run.

Run: ``python bench/worker_threads.py [--missions 20] [--repeats 3] [--workers 2]
[--improve N]``, or ``--quick`` for a smoke run (4 missions, one repeat).

The missions are ``bench/batch.py``'s (``forest`` and ``window`` alternately, each with its
own start and goal, seeds 0, 1, 2, ..., 2 m/s, 3 m/s^2, ``fly``'s search budget unless
``--improve``). Each repeat flies them on ``--workers`` spawned workers
(:func:`quadnav.batch.executor.open_executor`) twice, the baseline first, then one thread
per worker. CPU seconds are the workers' user + system time (``RUSAGE_CHILDREN`` around
each run, the workers' start-up and warm-up included). Printed: the medians over the
repeats, the ratio of one thread's CPU to the baseline's (the median of each repeat's
ratio), and whether both gave the same rows (wall times aside). Nothing is asserted.
"""

from __future__ import annotations

import resource
import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numba
from batch import MAPS, Measure, study_arguments, write_spec
from planning import table

from quadnav.batch.executor import open_executor
from quadnav.batch.fly_one import fly_row, load_context, warm_up
from quadnav.batch.grid import read_spec
from quadnav.batch.table import same_row


def fly(spec_path: Path, workers: int, threads: int) -> tuple[Measure, list[dict[str, Any]]]:
    """The spec's missions on ``workers`` local workers of ``threads`` numba threads each:
    the workers' CPU and the wall seconds, and the rows in the spec's order."""
    spec = read_spec(spec_path)
    missions = spec.missions()
    rows: list[dict[str, Any]] = [{}] * len(missions)
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    began = time.perf_counter()
    with open_executor(load_context(spec), warm_up, workers, threads=threads) as executor:
        for index, row in executor.map_unordered(fly_row, missions):
            rows[index] = row
    wall = time.perf_counter() - began
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return Measure(cpu, wall), rows


def main() -> None:
    args, count, repeats = study_arguments(__doc__.splitlines()[0])
    own = numba.config.NUMBA_NUM_THREADS
    runs: dict[int, list[Measure]] = {own: [], 1: []}
    same = []
    with tempfile.TemporaryDirectory() as scratch:
        spec = write_spec(Path(scratch), count, args.improve)
        for k in range(repeats):
            print(f"  repeat {k + 1}/{repeats}: {own} numba threads per worker, then 1",
                  file=sys.stderr, flush=True)
            flown = {}
            for threads in runs:
                measure, flown[threads] = fly(spec, args.workers, threads)
                runs[threads].append(measure)
            same.append(all(same_row(a, b) for a, b in zip(*flown.values(), strict=True)))

    def row(name: str, measures: list[Measure]) -> list[str]:
        cpu = statistics.median(m.cpu for m in measures)
        return [name, f"{cpu:.1f}", f"{cpu / count:.3f}",
                f"{statistics.median(m.wall for m in measures):.1f}"]

    print(f"{count} missions ({', '.join(MAPS)}, {args.improve:,} samples of improvement) on "
          f"{args.workers} local workers; medians of {repeats} repeats, start-up included\n")
    print(table(["numba threads per worker", "CPU s", "CPU s per mission", "wall s"],
                [row(f"{own} (numba's own: the baseline)", runs[own]), row("1", runs[1])]))
    ratio = statistics.median(one.cpu / base.cpu
                              for base, one in zip(runs[own], runs[1], strict=True))
    print(f"\nCPU with 1 thread / baseline: {ratio:.2f} ({100 * (1 - ratio):.0f} % less)")
    print(f"the same rows with 1 thread as with {own}: {'yes' if all(same) else 'NO'}")


if __name__ == "__main__":
    main()

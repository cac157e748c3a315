"""Run a batch into its folder: :class:`BatchRun`.

The spec's files are loaded and the folder checked first (nothing is written for bad
input); then the missions not yet in the journal fly on the executor's workers, each
finished row journaled at once; the tables and summaries are written at the end, and also
when the run is stopped (Ctrl-C, SIGTERM), from every row finished by then.

Missions that may share a plan (the same map, planner and seed) are sent to one worker
together (:func:`plan_jobs`), so that it plans once for them all; local workers keep the
plans in the folder's ``plans/`` for a resumed run, a Ray cluster's each in its memory.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import replace
from functools import partial
from pathlib import Path
from typing import Any

from quadnav.batch.executor import cpu_count, open_executor
from quadnav.batch.fly_one import fly_rows, load_context, refused_rows, warm_up
from quadnav.batch.folder import (
    PLANS,
    batch_record,
    begin,
    finished_rows,
    ordered_rows,
    write_outputs,
)
from quadnav.batch.grid import BatchSpec, MissionSpec
from quadnav.batch.table import RESULTS_CSV, Journal, compact_row

#: Jobs per worker a batch is cut into at least, when its missions allow: a group of
#: missions that share a plan is cut (each part planning again) so that every worker has
#: work to the end.
JOBS_PER_WORKER = 4
#: The fewest missions of a part of a group cut: fewer are not worth planning again.
LEAST_JOB = 4


def plan_jobs(missions: Sequence[MissionSpec], workers: int) -> list[list[MissionSpec]]:
    """``missions`` cut into jobs for ``workers`` workers: those that may share a plan
    (the same map entry, planner and seed) together, in the order each group first comes;
    a group is cut into parts of at least :data:`LEAST_JOB` missions when there are fewer
    than :data:`JOBS_PER_WORKER` groups a worker."""
    groups: dict[tuple, list[MissionSpec]] = {}
    for mission in missions:
        groups.setdefault((mission.map, mission.planner, mission.seed), []).append(mission)
    parts = math.ceil(workers * JOBS_PER_WORKER / max(len(groups), 1))
    jobs = []
    for group in groups.values():
        size = max(LEAST_JOB, math.ceil(len(group) / parts))
        jobs += [group[k:k + size] for k in range(0, len(group), size)]
    return jobs


def one_by_one(job: list[MissionSpec]) -> list[list[MissionSpec]]:
    """A job whose worker died, as the jobs it runs again as: each mission alone, so that
    only a mission that kills its worker every time is given up."""
    return [[mission] for mission in job]


class BatchRun:
    """A batch about to run into ``folder``: its context loaded, its folder checked.

    Attributes:
        spec: the batch.
        folder: where it writes.
        missions: every mission of the batch, in the grid's order.
        rows: the finished rows by mission key (those of an earlier run first).
        todo: the missions still to fly.
        retried: the missions this run flew again because the worker process flying them
            died (None before it runs, or when it flew none).
    """

    def __init__(self, spec: BatchSpec, folder: str | Path, restart: bool = False) -> None:
        """Load the spec's files and check the folder (QuadnavError for bad input, with
        nothing written)."""
        self.spec = spec
        self.folder = Path(folder)
        self.restart = restart
        self.context = load_context(spec)
        self.record = batch_record(spec, self.context)
        self.missions = spec.missions()
        self.rows: dict[str, dict[str, Any]] = {
            row["mission_key"]: row
            for row in finished_rows(self.folder, self.record, self.missions, restart)}
        self.todo = [m for m in self.missions if m.key not in self.rows]
        self.retried: int | None = None

    def run(self, workers: int | None = None, ray: bool = False, address: str | None = None,
            on_start: Callable[[int, int], None] | None = None,
            on_row: Callable[[dict[str, Any]], None] | None = None) -> list[str]:
        """Fly the missions still to fly and write the outputs; returns the names written.

        Args:
            workers: local worker processes (default: one per CPU), or the CPUs of a local
                Ray; no more than the jobs the missions make.
            ray: run on Ray, at ``address`` (None: a local Ray started for the run).
            address: a Ray cluster's address.
            on_start: called with the number of workers and the numba threads of each
                once they are ready.
            on_row: called with each row as it is journaled.

        A stop (KeyboardInterrupt) or error still writes the outputs from the rows finished,
        then goes on. A mission whose worker process died is flown again (at most
        :data:`~quadnav.batch.executor.RETRIES` times, then its row is refused with the
        reason), counted in :attr:`retried`.
        """
        executor = flying = None
        ran_on = None
        workers = workers or cpu_count()
        jobs = plan_jobs(self.todo, workers)
        if jobs:
            # the plans kept on disk where the workers share the driver's disk
            plans = None if ray and address is not None else self.folder / PLANS
            # no more workers than jobs: a worker without one would only start and end
            executor = flying = open_executor(replace(self.context, plans=plans), warm_up,
                                              min(workers, len(jobs)), ray, address)
            ran_on = {"workers": executor.workers, "numba_threads": executor.numba_threads}
        try:
            begin(self.folder, self.record, self.restart, list(self.rows.values()))
            journal = Journal(self.folder / RESULTS_CSV)
            try:
                if executor is not None:
                    if on_start is not None:
                        on_start(executor.workers, executor.numba_threads)
                    for _, rows in executor.map_unordered(
                            fly_rows, jobs, partial(refused_rows, self.context),
                            one_by_one):
                        for row in rows:
                            row = compact_row(row)
                            journal.append(row)
                            self.rows[row["mission_key"]] = row
                            if on_row is not None:
                                on_row(row)
            except BaseException:
                if executor is not None:  # stop the workers before writing the outputs
                    executor.close(cancel=True)
                    executor = None
                raise
            finally:
                journal.close()
                self.retried = (None if flying is None
                                else sum(len(job) for job in flying.retried_jobs))
                written = write_outputs(self.folder, self.finished, len(self.missions),
                                        ran_on, self.retried)
        finally:
            if executor is not None:
                executor.close()
        return written

    @property
    def finished(self) -> list[dict[str, Any]]:
        """The finished rows in the grid's order."""
        return ordered_rows(self.missions, self.rows)

"""Grade a submission into a folder: :class:`Grade`.

The course is checked first with quadnav's own parts (every map read, every query and
setting checked: a mistake there is the grader's input, refused before anything is
written); then each mission flies with the submission's parts, and with quadnav's own
(the baseline) unless the course says not to, on the batch executor's local worker
processes (:func:`~quadnav.batch.executor.open_executor`), one or more: whatever a
submission's code does to its process (``os._exit``, a crash in compiled code, an endless
loop) ends or stops only a worker, never the grader. A mission whose worker died each time
it flew it, or that ran longer than the course's time limit, fails
(:func:`~quadnav.grading.grade_one.lost_row`). Each mission keeps its row in its folder as
it finishes; the grade's files (:func:`~quadnav.grading.report.write_grade`) are written
at the end, and also when the run is stopped, from every mission finished.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Iterator
from functools import partial
from pathlib import Path
from typing import Any

from quadnav.batch.executor import open_executor
from quadnav.batch.fly_one import warm_up
from quadnav.errors import QuadnavError
from quadnav.grading.course import PART_KEYS, Course, GradedMission, submission_spec
from quadnav.grading.grade_one import (
    BASELINE,
    SUBMISSION,
    GradeContext,
    GradeJob,
    grade_mission,
    job_fingerprint,
    kept_row,
    lost_row,
)
from quadnav.grading.report import write_grade


class Grade:
    """A submission about to be graded on a course into ``output``.

    Attributes:
        course: the course.
        context: what every mission shares (the folders, strict grading).
        missions: the course's missions, map by map, seed by seed.
        jobs: every mission to fly: the submission's, then the baseline's.
        rows: the finished rows by (part, key), those kept from an earlier run first.
    """

    def __init__(self, course: Course, submission: str | Path, output: str | Path) -> None:
        """Check the course and the submission's folder (QuadnavError for bad input, with
        nothing written)."""
        folder = Path(submission)
        if not folder.is_dir():
            raise QuadnavError(f"{submission}: expected the submission's folder")
        parts = {PART_KEYS[key]: submission_spec(spec, folder.resolve())
                 for key, spec in course.parts.given().items()}
        if not parts:
            raise QuadnavError("nothing of the submission to grade: name its parts ([parts] "
                               "in the course file, or --controller, --planner, --reference)")
        self.course = course
        self.context = GradeContext(folder.resolve(), Path(output).resolve(), course.strict)
        self.missions = course.missions()
        self.jobs: list[GradeJob] = []
        for mission in self.missions:
            table = _checked(mission, course)
            self.jobs.append(GradeJob(SUBMISSION, mission.key, mission.entry.map, mission.seed,
                                      table, parts,
                                      job_fingerprint(table, parts, course.strict,
                                                      self.context.submission)))
        if course.baseline:
            self.jobs += [GradeJob(BASELINE, job.key, job.map, job.seed, job.table,
                                   fingerprint=job_fingerprint(job.table, {}, course.strict,
                                                               None))
                          for job in self.jobs]
        self.rows: dict[tuple[str, str], dict[str, Any]] = {}
        for job in self.jobs:
            row = kept_row(self.context, job)
            if row is not None:
                self.rows[job.part, job.key] = row
        self.todo = [job for job in self.jobs if (job.part, job.key) not in self.rows]

    def run(self, workers: int = 1, on_row: Callable[[dict[str, Any]], None] | None = None
            ) -> list[str]:
        """Fly the missions still to fly on ``workers`` local worker processes, then write
        the grade's files; returns their names. A stop (Ctrl-C) or an error still writes
        them from the missions finished, then goes on."""
        try:
            for row in self._flown(workers):
                self.rows[row["part"], row["key"]] = row
                if on_row is not None:
                    on_row(row)
        finally:
            written = write_grade(self.context.output, self.course, self.context.submission,
                                  self.finished, len(self.jobs))
        return written

    def _flown(self, workers: int) -> Iterator[dict[str, Any]]:
        if not self.todo:
            return
        limit = self.course.mission_time_limit or None
        with open_executor(self.context, _warm_up, min(workers, len(self.todo))) as executor:
            for _, row in executor.map_unordered(grade_mission, self.todo,
                                                 partial(lost_row, self.context, limit),
                                                 time_limit=limit):
                yield row

    @property
    def finished(self) -> list[dict[str, Any]]:
        """The finished rows in the order of :attr:`jobs`."""
        return [self.rows[job.part, job.key] for job in self.jobs
                if (job.part, job.key) in self.rows]


def _warm_up(context: GradeContext) -> None:
    """Load the compiled kernels in a worker before its first mission."""
    warm_up(None)


def _checked(mission: GradedMission, course: Course) -> dict[str, Any]:
    """The table of ``mission`` with quadnav's own parts, checked: its settings built,
    its map read and its query checked (QuadnavError naming the map and seed: the
    course's input; warnings are left to the mission's row)."""
    config = mission.config(course)
    try:
        with warnings.catch_warnings():  # each mission's row keeps its warnings
            warnings.simplefilter("ignore")
            settings = config.settings()
            config.problem(config.world(), settings.body)
    except QuadnavError as error:
        raise QuadnavError(f"the course's map {mission.entry.map} (seed {mission.seed}): "
                           f"{error}") from None
    return config.table()

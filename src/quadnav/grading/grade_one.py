"""One graded mission: :func:`grade_mission` flies a :class:`GradeJob` (a mission of the
course, with the submission's parts or quadnav's own) through the library's one mission
path (:meth:`~quadnav.missionconfig.MissionConfig.fly`), writes its run folder (figures and
report included) and returns its row of the grade.

Whatever the submission's code does is the mission's outcome, never the grader's crash: a
part that cannot be loaded, raises, returns NaN commands or the wrong keys, or plans through
a block fails that mission with the error's line and the part's own traceback
(:data:`OUTCOMES`). The row is also kept in the mission's folder (:data:`RESULT_FILE`), so
an interrupted grade keeps every mission finished and a re-run flies only the others.

A mission flies in a worker process of the grade (:mod:`quadnav.grading.run`): one whose
process died each time, or that ran past the time limit, gets its row from the grader
instead (:func:`lost_row`), which is not kept: a re-run flies it again.
"""

from __future__ import annotations

import hashlib
import json
import os
import sys
import traceback
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from quadnav.batch.executor import time_limit_reason
from quadnav.errors import QuadnavError
from quadnav.files import atomic_output
from quadnav.grading.course import PART_KEYS
from quadnav.mission import Mission, failure_reason
from quadnav.missionconfig import MissionConfig
from quadnav.plugins import user_traceback
from quadnav.report.run_writer import write_run
from quadnav.runfolder import replaced_folder
from quadnav.runs import FIGURES, REPORT, RUN_FILES
from quadnav.sim.flight import Ending

#: The row of a mission, JSON, in its folder.
RESULT_FILE = "grade-result.json"
#: The error and traceback of a mission whose part failed, text, in its folder.
ERROR_FILE = "error.txt"
#: The parts of a grade: the submission's, and quadnav's own on the same missions.
SUBMISSION, BASELINE = "submission", "baseline"
#: A mission's outcome: passed, or the first thing that failed it.
OUTCOMES = {
    "passed": "reached the goal with no contact, its body inside the map",
    "part error": "a part of the submission could not be loaded, raised, or returned what "
                  "cannot be flown (NaN commands, wrong keys, a reference off the start or "
                  "goal)",
    "no path": "no path was found, or the planner's path was refused (through a block, "
               "into the margin, off the start or goal)",
    "crashed": "the flight touched a block, hit the floor, left the map's boundary or "
               "diverged",
    "body outside": "the vehicle's body left the map",
    "missed goal": "the flight ended farther from the goal than the goal tolerance",
    "margin": "the flight kept less margin than asked off the legs (strict grading)",
    "process died": "the process flying the mission died each time it flew it (os._exit, "
                    "a crash in compiled code, killed by a signal or for want of memory)",
    "time limit": "the mission ran longer than the course's time limit (an endless loop, "
                  "a part far too slow)",
}
#: The figures of a mission, the first embedded in the grade for a failed mission.
FIGURE = FIGURES[0]
#: The numbers of metrics.json a row keeps.
ROW_METRICS = ("path_length_m", "trajectory_duration_s", "time_to_goal_s", "flight_time_s",
               "rms_tracking_error_m", "max_tracking_error_m", "final_error_m",
               "flight_margin_m", "margin_m", "margin_shortfall_m", "goal_tolerance_m",
               "contact_block", "contact_time_s", "planning_time_s", "sim_wall_time_s")


@dataclass(frozen=True)
class GradeContext:
    """What every mission of a grade shares.

    Attributes:
        submission: the submission's folder (absolute), put on Python's path while its
            parts fly, so its files may import each other by module name.
        output: the grade's folder (absolute).
        strict: a flight that kept less margin than asked fails too.
    """

    submission: Path
    output: Path
    strict: bool = False


@dataclass(frozen=True)
class GradeJob:
    """One mission to grade.

    Attributes:
        part: :data:`SUBMISSION` or :data:`BASELINE`.
        key: ``LABEL/seed-N`` (:attr:`~quadnav.grading.course.GradedMission.key`).
        map: the map as the course names it.
        seed: the mission's seed.
        table: the mission with quadnav's own parts (:meth:`MissionConfig.table`).
        parts: the keys of a mission file that the submission's parts set, with their
            specs (empty for the baseline).
        fingerprint: what the row depends on (the mission, the grading rule, the
            submission's files), to tell whether a row kept in the folder is still this
            mission's (:func:`job_fingerprint`).
    """

    part: str
    key: str
    map: str
    seed: int
    table: dict[str, Any]
    parts: dict[str, str] = field(default_factory=dict)
    fingerprint: str = ""

    @property
    def folder(self) -> str:
        """Its folder in the grade's folder (POSIX, relative)."""
        return f"missions/{self.part}/{self.key}"


def job_fingerprint(table: Mapping[str, Any], parts: Mapping[str, str], strict: bool,
                    submission: Path | None) -> str:
    """A digest of the mission ``table``, the ``parts``, the grading rule (``strict``)
    and, with a ``submission`` folder, the contents of every Python file in it."""
    digest = hashlib.sha256(json.dumps([table, parts, strict], sort_keys=True).encode())
    if submission is not None:
        for path in sorted(submission.rglob("*.py")):
            digest.update(str(path.relative_to(submission)).encode())
            digest.update(path.read_bytes())
    return digest.hexdigest()[:16]


def kept_row(context: GradeContext, job: GradeJob) -> dict[str, Any] | None:
    """The row kept in ``job``'s folder by an earlier grade of the same mission, else
    None."""
    try:
        row = json.loads((context.output / job.folder / RESULT_FILE).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return row if isinstance(row, dict) and row.get("fingerprint") == job.fingerprint else None


def grade_mission(context: GradeContext, job: GradeJob) -> dict[str, Any]:
    """Fly ``job``, write its run folder and its row (:data:`RESULT_FILE`); returns the
    row, its reason and traceback naming the submission's files relative to its folder.
    Never raises for the mission's own failure (see the module docstring)."""
    folder = context.output / job.folder
    if job.part == SUBMISSION and str(context.submission) not in sys.path:
        sys.path.insert(0, str(context.submission))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            config = MissionConfig.from_table(job.table, source="the course")
            if job.parts:
                config = config.with_changes(job.parts, {
                    key: f"the submission's {part}" for part, key in PART_KEYS.items()})
            mission = config.fly()
        except (Exception, SystemExit) as error:  # the submission's code may do anything
            row = _error_row(job, error)
            with replaced_folder(folder, (*RUN_FILES, ERROR_FILE)) as staging:
                (staging / ERROR_FILE).write_text(
                    "\n".join(filter(None, [row["traceback"], row["reason"]])) + "\n",
                    encoding="utf-8")
        else:
            (folder / ERROR_FILE).unlink(missing_ok=True)
            write_run(mission, folder, figures=True, config=config)
            row = _flown_row(job, mission, context.strict)
    row["warnings"] = sorted({str(warning.message) for warning in caught})
    inside = f"{context.submission}{os.sep}"  # the student's files named as they know them
    for key in ("reason", "traceback"):
        row[key] = row[key] and row[key].replace(inside, "")
    with atomic_output(folder / RESULT_FILE) as tmp:
        tmp.write_text(json.dumps(row, indent=1) + "\n", encoding="utf-8")
    return row


def _base_row(job: GradeJob) -> dict[str, Any]:
    return {"part": job.part, "key": job.key, "map": job.map, "seed": job.seed,
            "parts": dict(job.parts), "folder": job.folder, "fingerprint": job.fingerprint}


def _error_row(job: GradeJob, error: BaseException) -> dict[str, Any]:
    """The row of a mission whose part failed: its one line and its own traceback (the
    whole traceback for an error quadnav did not expect)."""
    if isinstance(error, QuadnavError):  # quadnav's own line
        reason, details = str(error), getattr(error, "details", None)
    else:
        reason = f"{type(error).__name__}: {error}"
        details = user_traceback(error) or "".join(traceback.format_exception(error))
    return _base_row(job) | {"passed": False, "outcome": "part error", "reason": reason,
                             "traceback": details, "report": None, "figure": None,
                             "metrics": {}}


def lost_row(context: GradeContext, time_limit: float | None, job: GradeJob, reason: str
             ) -> dict[str, Any]:
    """The row of ``job`` given up by the grader (``lost`` of
    :meth:`~quadnav.batch.executor.Executor.map_unordered`, ``reason`` saying why): its
    worker process died each time it flew it, or it ran past ``time_limit`` s. Its folder
    gets :data:`ERROR_FILE` with the reason in place of what the worker left; no
    :data:`RESULT_FILE`, so that a re-run flies it again."""
    timed_out = time_limit is not None and reason == time_limit_reason(time_limit)
    with replaced_folder(context.output / job.folder, (*RUN_FILES, ERROR_FILE, RESULT_FILE)
                         ) as staging:
        (staging / ERROR_FILE).write_text(reason + "\n", encoding="utf-8")
    return _base_row(job) | {"passed": False,
                             "outcome": "time limit" if timed_out else "process died",
                             "reason": reason, "traceback": None, "report": None,
                             "figure": None, "metrics": {}, "warnings": []}


def _flown_row(job: GradeJob, mission: Mission, strict: bool) -> dict[str, Any]:
    metrics = mission.metrics()
    outcome, reason = verdict(mission, metrics, strict)
    return _base_row(job) | {
        "passed": outcome == "passed", "outcome": outcome, "reason": reason,
        "traceback": None, "report": f"{job.folder}/{REPORT}",
        "figure": f"{job.folder}/{FIGURE}",
        "metrics": {key: metrics.get(key) for key in ROW_METRICS}}


def verdict(mission: Mission, metrics: Mapping[str, Any], strict: bool) -> tuple[str, str]:
    """The outcome of a flown ``mission`` (a key of :data:`OUTCOMES`) and one line saying
    why (:func:`~quadnav.mission.failure_reason`; empty when it passed)."""
    flight = mission.flight
    if flight is None:
        return "no path", failure_reason(mission)
    if not mission.success:
        outcome = ("crashed" if flight.ending is not Ending.COMPLETED else
                   "body outside" if flight.body_outside else "missed goal")
        return outcome, failure_reason(mission)
    if strict and metrics["margin_shortfall_m"]:
        return "margin", (f"kept {metrics['flight_margin_m']:.3f} m of the "
                          f"{metrics['margin_m']:g} m margin asked off the legs, least at t = "
                          f"{metrics['flight_margin_time_s']:.2f} s")
    return "passed", ""

"""``quadnav grade``: a submission's parts graded on a course's maps and seeds, with the
report a TA hands back (docs/grading.md)."""

from __future__ import annotations

import argparse
import os
import sys
from typing import Any

from quadnav.cli.args import (
    add_start_goal_arguments,
    number_in,
    output_path,
    speed_or_max,
)
from quadnav.cli.commands import command_help
from quadnav.errors import QuadnavError
from quadnav.grading import Grade, read_course
from quadnav.grading.course import MISSION_TIME_LIMIT, SEED_COUNT, Course
from quadnav.grading.grade_one import BASELINE, RESULT_FILE
from quadnav.limits import Range
from quadnav.missionconfig.checks import located
from quadnav.runfolder import check_output_folder
from quadnav.signals import interrupted_exit_code

#: Exit code when a mission of the submission failed.
EXIT_FAILED = 1
#: Local worker processes of a grade.
WORKERS = Range(1, 1024, whole=True)
#: Each flag that sets a key of the course, by its argparse dest: its name and the key.
COURSE_FLAGS = {"seeds": ("--seeds", "seeds"), "controller": ("--controller", "parts.controller"),
                "planner": ("--planner", "parts.planner"),
                "reference": ("--reference", "parts.reference"),
                "speed": ("--speed", "mission.trajectory.speed"),
                "mission_time_limit": ("--mission-time-limit", "mission_time_limit")}


def course_from(args: argparse.Namespace) -> Course:
    """The course file given (or none), with the flags given set on top."""
    changes: dict[str, Any] = {key: getattr(args, dest) for dest, (_, key) in COURSE_FLAGS.items()
                               if getattr(args, dest) is not None}
    names = {key: flag for dest, (flag, key) in COURSE_FLAGS.items()
             if getattr(args, dest) is not None}
    if args.maps is not None:
        query = {key: getattr(args, key) for key in ("start", "goal")
                 if getattr(args, key) is not None}
        changes["maps"] = [{"map": located(name, os.getcwd())} | query for name in args.maps]
        names["maps"] = "--maps"
    elif args.start is not None or args.goal is not None:
        raise QuadnavError("--start and --goal apply to the maps of --maps; give a course "
                           "file's maps their own start and goal")
    if args.strict:
        changes["strict"] = True
    if args.no_baseline:
        changes["baseline"] = False
    return read_course(args.course, changes, names)


def grade(args: argparse.Namespace) -> int:
    """Grade the submission; exit 0 when every mission passed, 1 when one failed."""
    course = course_from(args)
    folder = check_output_folder(args.output)
    run = Grade(course, args.submission, folder)
    maps, seeds = len(course.maps), len(course.seeds)
    baseline = ", and quadnav's own parts on them" if course.baseline else ""
    print(f"grading {args.submission} on {len(run.missions)} mission"
          f"{'s' * (len(run.missions) > 1)} ({maps} map"
          f"{'s' * (maps > 1)} x {seeds} seed{'s' * (seeds > 1)}){baseline}: "
          f"{len(run.todo)} to fly, {len(run.rows)} kept from an earlier grade in {folder}",
          flush=True)
    try:
        written = run.run(workers=args.workers, on_row=None if args.quiet else _print_row)
    except KeyboardInterrupt as interrupt:
        print(f"quadnav: stopped: kept {len(run.rows)} of {len(run.jobs)} missions (each "
              f"folder's {RESULT_FILE}) and wrote the grade so far; grade again into "
              f"{folder} to finish", file=sys.stderr)
        return interrupted_exit_code(interrupt)
    rows = [row for row in run.finished if row["part"] != BASELINE]
    passed = sum(row["passed"] for row in rows)
    base = [row for row in run.finished if row["part"] == BASELINE]
    beside = (f" (quadnav's own parts: {sum(row['passed'] for row in base)} of {len(base)})"
              if base else "")
    print(f"score: {passed} of {len(rows)} missions passed{beside}")
    print("wrote " + ", ".join(str(folder / name) for name in written))
    return 0 if passed == len(rows) else EXIT_FAILED


def _print_row(row: dict[str, Any]) -> None:
    result = "pass" if row["passed"] else f"FAIL ({row['outcome']}): {row['reason']}"
    print(f"  {row['part']} {row['key']}: {result}", flush=True)


def add_grade_command(subparsers: argparse._SubParsersAction) -> None:
    """Register ``quadnav grade`` on the top-level subparsers."""
    p = subparsers.add_parser(
        "grade", help=command_help("grade"),
        description="Grade a submission: the student's parts (a controller, a planner, a "
                    "trajectory class, in plain Python, named by file.py:Name in the "
                    "SUBMISSION folder) fly every map x seed of a course, each mission "
                    "through quadnav's mission path into a run folder DIR/missions/..., with "
                    "quadnav's own parts beside them (the baseline). Writes DIR/grade.html "
                    "(the score, the pass rule, what failed where and why, with the flight), "
                    "DIR/grade.json and DIR/grade.csv. A failure in the student's code "
                    "fails its mission, with its traceback; so does code that ends its "
                    "process or runs past the time limit. A re-run into the same DIR flies "
                    "only the missions not finished (or whose files changed). Exit 0 when "
                    "every mission passed, 1 when one failed, 2 on bad input (the course, "
                    "the flags, a submission folder that is not there), 130/143 when "
                    "stopped.")
    p.add_argument("submission", metavar="SUBMISSION_DIR",
                   help="the submission's folder; its files may import each other by module "
                        "name")
    p.add_argument("--course", metavar="FILE",
                   help="the course file (grade.toml): maps with their queries, seeds, the "
                        "parts a submission provides, the missions' settings")
    p.add_argument("--maps", nargs="+", metavar="MAP",
                   help="grade on these maps (files, built-in worlds, course:NAME) instead of "
                        "the course's, each with its own start and goal or --start/--goal")
    add_start_goal_arguments(p, file=False)
    p.add_argument("--seeds", type=number_in(SEED_COUNT), metavar="N",
                   help="seeds 0 to N - 1 on every map (default: the course's, else 2)")
    p.add_argument("--controller", metavar="SPEC",
                   help="the submission's controller class, file.py:Class in its folder "
                        "(rotorpy's shape), over the course's")
    p.add_argument("--planner", metavar="SPEC",
                   help="the submission's planner function, file.py:function in its folder, "
                        "over the course's")
    p.add_argument("--reference", metavar="SPEC",
                   help="the submission's trajectory class, file.py:Class in its folder "
                        "(rotorpy's shape), over the course's")
    p.add_argument("--speed", type=speed_or_max, metavar="V|max",
                   help="top speed of quadnav's trajectories, m/s, or max, over the course's")
    p.add_argument("--mission-time-limit", type=number_in(MISSION_TIME_LIMIT),
                   metavar="SECONDS",
                   help="stop a mission that runs longer and fail it (an endless loop in "
                        "the submission), over the course's (default: the course's, else "
                        "300; 0: no limit)")
    p.add_argument("--strict", action="store_true",
                   help="a flight that kept less margin than asked off the legs fails too")
    p.add_argument("--no-baseline", action="store_true",
                   help="do not fly quadnav's own parts on the same missions")
    p.add_argument("--workers", type=number_in(WORKERS), default=1, metavar="N",
                   help="missions flown at once on local worker processes (default: 1)")
    p.add_argument("--quiet", action="store_true", help="no line per mission")
    p.add_argument("-o", "--output", type=output_path, default="grade", metavar="DIR",
                   help="folder to write into, created if needed (default: grade)")
    p.set_defaults(handler=grade)

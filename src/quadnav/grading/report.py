"""The grade a TA hands back: ``grade.json`` (everything), ``grade.csv`` (a line per
mission) and ``grade.html`` (the score, the pass rule, a map x seed table of what passed
and why not, links to each mission's run folder, the flight figure of each failed mission
embedded, and the submission beside quadnav's own parts on the same missions), written
from the rows of :func:`~quadnav.grading.grade_one.grade_mission`."""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from quadnav import __version__
from quadnav.files import atomic_output, csv_text
from quadnav.grading.course import Course
from quadnav.grading.grade_one import BASELINE, OUTCOMES, SUBMISSION
from quadnav.pages import figure, render
from quadnav.report.html_report import CAPTIONS

GRADE_JSON, GRADE_CSV, GRADE_HTML = "grade.json", "grade.csv", "grade.html"
#: Every file a grade writes into its folder, besides ``missions/``.
GRADE_FILES = (GRADE_JSON, GRADE_CSV, GRADE_HTML)
#: The columns of grade.csv: the mission, the submission's result, the baseline's.
CSV_COLUMNS = ("map", "seed", "passed", "outcome", "reason", "time_to_goal_s",
               "rms_tracking_error_m", "flight_margin_m", "baseline_passed",
               "baseline_time_to_goal_s", "baseline_rms_tracking_error_m", "folder")


def pass_rule(strict: bool) -> str:
    """The rule a mission passes by, in words: ``quadnav fly``'s success (exit 0), and with
    ``strict`` the whole margin kept (``fly --strict``)."""
    rule = ("A mission passes when its flight reaches the goal (within the goal tolerance) "
            "with no contact with a block or the floor and the vehicle's body inside the "
            "map throughout: quadnav fly's success")
    return rule + (", and keeps the whole margin asked off the legs (fly --strict)."
                   if strict else "; the margin kept is reported, not graded.")


def grade_content(course: Course, submission: Path, rows: Sequence[dict[str, Any]],
                  expected: int) -> dict[str, Any]:
    """What grade.json holds: the course, the pass rule, the score, and each mission with
    the submission's row and the baseline's (None when not flown)."""
    by_part = {(row["part"], row["key"]): row for row in rows}
    missions = []
    for mission in course.missions():
        own = by_part.get((SUBMISSION, mission.key))
        base = by_part.get((BASELINE, mission.key))
        if own is not None or base is not None:
            missions.append({"map": mission.entry.map, "label": mission.label,
                             "seed": mission.seed, "key": mission.key,
                             SUBMISSION: own, BASELINE: base})
    own_rows = [m[SUBMISSION] for m in missions if m[SUBMISSION] is not None]
    base_rows = [m[BASELINE] for m in missions if m[BASELINE] is not None]
    total = len(course.missions())
    return {
        "quadnav": __version__, "submission": str(submission),
        "parts": course.parts.given(), "strict": course.strict, "rule": pass_rule(course.strict),
        "outcomes": OUTCOMES, "complete": len(rows) == expected,
        "score": {"passed": sum(row["passed"] for row in own_rows), "graded": len(own_rows),
                  "total": total},
        "baseline": None if not course.baseline else {
            "passed": sum(row["passed"] for row in base_rows), "flown": len(base_rows),
            "total": total},
        "comparison": comparison(missions),
        "course": course.model_dump(mode="json", exclude_none=True),
        "missions": missions,
    }


def comparison(missions: Sequence[dict[str, Any]]) -> dict[str, Any] | None:
    """Over the missions both the submission and the baseline passed: how many, and the
    mean time to goal (s) and RMS tracking error (m) of each; None without such
    missions."""
    both = [m for m in missions if m[BASELINE] is not None and m[SUBMISSION] is not None
            and m[SUBMISSION]["passed"] and m[BASELINE]["passed"]]
    if not both:
        return None

    def mean(part: str, key: str) -> float:
        return sum(m[part]["metrics"][key] for m in both) / len(both)

    return {"missions": len(both),
            **{f"{part}_{key}": mean(part, key) for part in (SUBMISSION, BASELINE)
               for key in ("time_to_goal_s", "rms_tracking_error_m")}}


def write_grade(folder: Path, course: Course, submission: Path,
                rows: Sequence[dict[str, Any]], expected: int) -> list[str]:
    """Write grade.json, grade.csv and grade.html of ``rows`` (of ``expected`` in all)
    into ``folder``, each atomically; returns their names."""
    content = grade_content(course, submission, rows, expected)
    folder.mkdir(parents=True, exist_ok=True)
    texts = {GRADE_JSON: json.dumps(content, indent=1) + "\n", GRADE_CSV: grade_csv(content),
             GRADE_HTML: grade_html(content, folder)}
    for name, text in texts.items():
        with atomic_output(folder / name) as tmp:
            tmp.write_text(text, encoding="utf-8")
    return list(texts)


def grade_csv(content: dict[str, Any]) -> str:
    """grade.csv: a line per mission graded (:data:`CSV_COLUMNS`)."""
    rows = []
    for mission in content["missions"]:
        own, base = mission[SUBMISSION], mission[BASELINE] or {}
        if own is None:
            continue
        metrics, base_metrics = own["metrics"], base.get("metrics", {})
        rows.append([mission["map"], mission["seed"], own["passed"], own["outcome"],
                     own["reason"], metrics.get("time_to_goal_s"),
                     metrics.get("rms_tracking_error_m"), metrics.get("flight_margin_m"),
                     base.get("passed"), base_metrics.get("time_to_goal_s"),
                     base_metrics.get("rms_tracking_error_m"), own["folder"]])
    return csv_text(CSV_COLUMNS, rows)


# ------------------------------------------------------------------------------ the page
def _number(value: float | None, scale: float = 1.0, digits: int = 2) -> str:
    return "\u2013" if value is None else f"{scale * value:.{digits}f}"


def _beside(metrics: dict[str, Any], base: dict[str, Any] | None, key: str,
            scale: float = 1.0) -> str:
    """The submission's value of ``key``, with the baseline's in brackets when flown."""
    ours = _number(metrics.get(key), scale)
    return ours if base is None else f"{ours} ({_number(base.get(key), scale)})"


def _matrix(content: dict[str, Any]) -> list[tuple[str, list[dict[str, Any] | None]]]:
    """The map x seed table of the submission's results: each map's label with its row of
    the course's seeds (None where not flown)."""
    cells = {(m["label"], m["seed"]): m[SUBMISSION] for m in content["missions"]}
    labels = dict.fromkeys(m["label"] for m in content["missions"])
    return [(label, [cells.get((label, seed)) for seed in content["course"]["seeds"]])
            for label in labels]


def _line(mission: dict[str, Any]) -> dict[str, Any]:
    """A mission's line: its result and why, its numbers beside the baseline's."""
    own, base = mission[SUBMISSION], mission[BASELINE]
    metrics = own["metrics"]
    base_metrics = None if base is None else base["metrics"]
    return {"label": mission["label"], "seed": mission["seed"], "own": own, "base": base,
            "time_to_goal": _beside(metrics, base_metrics, "time_to_goal_s"),
            "rms_tracking_error": _beside(metrics, base_metrics, "rms_tracking_error_m", 100),
            "margin": _number(metrics.get("flight_margin_m"), digits=3)}


def _failure(mission: dict[str, Any], folder: Path) -> dict[str, Any]:
    """A failed mission: its row, warnings and flight figure (None without one)."""
    own = mission[SUBMISSION]
    path = folder / own["figure"] if own["figure"] else None
    return {"map": mission["map"], "seed": mission["seed"], "own": own,
            "warnings": own.get("warnings", []),
            "figure": (figure(path.read_bytes(), CAPTIONS[path.name])
                       if path is not None and path.is_file() else None)}


def grade_html(content: dict[str, Any], folder: Path) -> str:
    """grade.html of ``content`` (:func:`grade_content`), its figures read from
    ``folder``."""
    graded = [m for m in content["missions"] if m[SUBMISSION] is not None]
    return render("grade.html", title=f"Grade of {Path(content['submission']).name}",
                  name=Path(content["submission"]).name, content=content,
                  seeds=content["course"]["seeds"], matrix=_matrix(content),
                  lines=[_line(m) for m in graded],
                  failures=[_failure(m, folder) for m in graded if not m[SUBMISSION]["passed"]])

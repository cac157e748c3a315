"""The grade a TA hands back: ``grade.json`` (everything), ``grade.csv`` (a line per
mission) and ``grade.html`` (the score, the pass rule, a map x seed table of what passed
and why not, links to each mission's run folder, the flight figure of each failed mission
embedded, and the submission beside quadnav's own parts on the same missions), written
from the rows of :func:`~quadnav.grading.grade_one.grade_mission`."""

from __future__ import annotations

import csv
import html
import io
import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from quadnav import __version__
from quadnav.files import atomic_output
from quadnav.grading.course import Course
from quadnav.grading.grade_one import BASELINE, OUTCOMES, SUBMISSION
from quadnav.report.html_report import CAPTIONS, figure_html, html_page, html_table

GRADE_JSON, GRADE_CSV, GRADE_HTML = "grade.json", "grade.csv", "grade.html"
#: Every file a grade writes into its folder, besides ``missions/``.
GRADE_FILES = (GRADE_JSON, GRADE_CSV, GRADE_HTML)
#: The columns of grade.csv: the mission, the submission's result, the baseline's.
CSV_COLUMNS = ("map", "seed", "passed", "outcome", "reason", "time_to_goal_s",
               "rms_tracking_error_m", "flight_margin_m", "baseline_passed",
               "baseline_time_to_goal_s", "baseline_rms_tracking_error_m", "folder")
STYLE = """<style>
td.pass { background: #e6f4ea; color: #1a7f37; font-weight: 600; }
td.fail { background: #fdecea; color: #c62828; font-weight: 600; }
td.missing { color: #888; }
td.why { overflow-wrap: anywhere; min-width: 18em; }
pre { background: #f6f6f6; padding: 0.6em; overflow-x: auto; font-size: 0.85em; }
.score { font-size: 1.4em; }
</style>"""


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
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(CSV_COLUMNS)
    for mission in content["missions"]:
        own, base = mission[SUBMISSION], mission[BASELINE] or {}
        if own is None:
            continue
        metrics, base_metrics = own["metrics"], base.get("metrics", {})
        writer.writerow([mission["map"], mission["seed"], own["passed"], own["outcome"],
                         own["reason"], metrics.get("time_to_goal_s"),
                         metrics.get("rms_tracking_error_m"), metrics.get("flight_margin_m"),
                         base.get("passed"), base_metrics.get("time_to_goal_s"),
                         base_metrics.get("rms_tracking_error_m"), own["folder"]])
    return out.getvalue()


# ------------------------------------------------------------------------------ the page
def _escape(value: Any) -> str:
    return html.escape(str(value))


def _number(value: float | None, scale: float = 1.0, digits: int = 2) -> str:
    return "&ndash;" if value is None else f"{scale * value:.{digits}f}"


def _result_cell(row: dict[str, Any] | None) -> str:
    if row is None:
        return '<td class="missing">not flown</td>'
    word, kind = ("pass", "pass") if row["passed"] else (row["outcome"], "fail")
    return f'<td class="{kind}">{_escape(word)}</td>'


def _matrix(content: dict[str, Any]) -> str:
    """The map x seed table of the submission's results."""
    seeds = content["course"]["seeds"]
    cells = {(m["label"], m["seed"]): m[SUBMISSION] for m in content["missions"]}
    labels = list(dict.fromkeys(m["label"] for m in content["missions"]))
    head = "".join(f"<th>seed {seed}</th>" for seed in seeds)
    body = "".join(
        f"<tr><th>{_escape(label)}</th>"
        + "".join(_result_cell(cells.get((label, seed))) for seed in seeds) + "</tr>"
        for label in labels)
    return f"<table><thead><tr><th>map</th>{head}</tr></thead><tbody>{body}</tbody></table>"


def _beside(metrics: dict[str, Any], base: dict[str, Any] | None, key: str,
            scale: float = 1.0) -> str:
    """The submission's value of ``key``, with the baseline's in brackets when flown."""
    ours = _number(metrics.get(key), scale)
    return ours if base is None else f"{ours} ({_number(base.get(key), scale)})"


def _mission_rows(content: dict[str, Any]) -> str:
    """A line per mission: its result and why, its numbers beside the baseline's, links."""
    header = ["map", "seed", "result", "why", "time to goal (s)", "RMS tracking error (cm)",
              "margin kept (m)", "baseline", "run folder"]
    lines = []
    for mission in content["missions"]:
        own, base = mission[SUBMISSION], mission[BASELINE]
        if own is None:
            continue
        metrics = own["metrics"]
        base_metrics = None if base is None else base["metrics"]
        links = [f'<a href="{_escape(own["folder"])}/">folder</a>']
        if own["report"]:
            links.append(f'<a href="{_escape(own["report"])}">report</a>')
        lines.append("<tr>" + "".join([
            f"<td>{_escape(mission['label'])}</td>", f"<td>{mission['seed']}</td>",
            _result_cell(own), f'<td class="why">{_escape(own["reason"])}</td>',
            f"<td>{_beside(metrics, base_metrics, 'time_to_goal_s')}</td>",
            f"<td>{_beside(metrics, base_metrics, 'rms_tracking_error_m', 100)}</td>",
            f"<td>{_number(metrics.get('flight_margin_m'), digits=3)}</td>",
            _result_cell(base), f"<td>{' '.join(links)}</td>"]) + "</tr>")
    head = "".join(f"<th>{_escape(cell)}</th>" for cell in header)
    return f"<table><thead><tr>{head}</tr></thead><tbody>{''.join(lines)}</tbody></table>"


def _failure(mission: dict[str, Any], folder: Path) -> str:
    """A failed mission's section: why, the part's traceback, its flight figure."""
    own = mission[SUBMISSION]
    parts = [f"<h3>{_escape(mission['map'])}, seed {mission['seed']}: "
             f"{_escape(own['outcome'])}</h3>",
             f'<p class="failure">{_escape(own["reason"])}</p>']
    if own["traceback"]:
        parts.append(f"<pre>{_escape(own['traceback'])}</pre>")
    for warning in own.get("warnings", []):
        parts.append(f'<p class="muted">warning: {_escape(warning)}</p>')
    figure = folder / own["figure"] if own["figure"] else None
    if figure is not None and figure.is_file():
        parts.append(figure_html(figure.read_bytes(), CAPTIONS[figure.name]))
    parts.append(f'<p class="muted">run folder: <a href="{_escape(own["folder"])}/">'
                 f'{_escape(own["folder"])}</a></p>')
    return "".join(parts)


def grade_html(content: dict[str, Any], folder: Path) -> str:
    """grade.html of ``content`` (:func:`grade_content`), its figures read from
    ``folder``."""
    score, base = content["score"], content["baseline"]
    state = ("" if content["complete"] else
             " The grade was stopped before every mission flew; grading again into the "
             "same folder finishes it.")
    parts = html_table(["part", "the submission's"],
                       [[_escape(key), _escape(spec)] for key, spec in content["parts"].items()],
                       1)
    body = [STYLE, f"<h1>Grade of {_escape(Path(content['submission']).name)}</h1>",
            f'<p class="muted">submission {_escape(content["submission"])}; graded by quadnav '
            f"{_escape(content['quadnav'])}.{_escape(state)}</p>",
            f'<p class="score"><b>{score["passed"]} of {score["total"]}</b> missions '
            "passed</p>", f"<p>{_escape(content['rule'])}</p>",
            "<h2>Parts graded</h2>", parts,
            "<p>Every other part is quadnav's own. The baseline flies quadnav's own parts on "
            "the same missions.</p>"]
    if base is not None:
        body.append(f"<p>Baseline: {base['passed']} of {base['total']} missions passed.</p>")
    compared = content["comparison"]
    if compared is not None:
        body.append(
            f"<p>On the {compared['missions']} missions both passed: time to goal "
            f"{compared['submission_time_to_goal_s']:.2f} s against "
            f"{compared['baseline_time_to_goal_s']:.2f} s on average, RMS tracking "
            f"error {100 * compared['submission_rms_tracking_error_m']:.2f} cm against "
            f"{100 * compared['baseline_rms_tracking_error_m']:.2f} cm.</p>")
    body += ["<h2>Missions</h2>", _matrix(content),
             "<p>The time to goal (when the flight came within the goal tolerance to stay) "
             "and the RMS tracking error of each mission, with the baseline's in brackets; "
             "the least margin the flight kept off the legs.</p>",
             _mission_rows(content)]
    failed = [m for m in content["missions"] if m[SUBMISSION] and not m[SUBMISSION]["passed"]]
    if failed:
        body += ["<h2>Failed missions</h2>", *(_failure(m, folder) for m in failed)]
    outcomes = html_table(["outcome", "meaning"],
                          [[_escape(key), _escape(text)] for key, text in
                           content["outcomes"].items()], 0)
    body += ["<h2>Outcomes</h2>", outcomes]
    return html_page(f"Grade of {Path(content['submission']).name}", "".join(body))

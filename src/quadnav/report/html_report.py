"""A run report to hand in: one self-contained HTML file over one or more run folders.

Each run gets a section: the map (or, for ``quadnav track``, the reference) and outcome,
the figures of the run (the explored tree with the path in red, desired against actual
position, velocity and acceleration, the tracking error, the attitude and motor
commands), the metrics (metrics.json) and every parameter used (parameters.json, flattened
to dotted names). Images are embedded as base64 PNG and the style is inline, so the file
opens anywhere, offline, on its own. Figures are the PNG files of the folder when it has
them, else drawn from the folder read back, by the same functions.
"""

from __future__ import annotations

import io
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from matplotlib.figure import Figure

from quadnav import __version__
from quadnav.errors import QuadnavError
from quadnav.files import atomic_output
from quadnav.pages import figure, render
from quadnav.runs import DRIFT_FIGURE, Run, run_outcome
from quadnav.tracking import step_summary
from quadnav.viz.figures import write_png
from quadnav.viz.flight_figures import figure_makers
from quadnav.world.placement import format_estimate, format_point

#: File name endings accepted for a report.
SUFFIXES = (".html", ".htm")
CM_PER_M = 100.0
#: Units of metrics.json values by key ending, longest first.
UNITS = (("_m_s", "m/s"), ("_s", "s"), ("_m", "m"))
#: What each figure shows, by its file name in the run folder.
CAPTIONS = {
    "flight_3d.png": "The map with the explored tree (blue), the path (red, dashed), the "
                     "trajectory (orange) and the flown track (black; a Tello's: its "
                     "dead-reckoned estimate, and in purple its true track when known), "
                     "seen obliquely and from above.",
    "flight_states.png": "Desired (dashed) against actual (solid) position, velocity and "
                         "acceleration per axis against time (for a step: the 2 % band, "
                         "the peak and the settling time).",
    "tracking_error.png": "Distance from the reference position against time, with its RMS "
                          "(dashed) and the largest recorded error.",
    "attitude_motors.png": "Roll, pitch and yaw (the yaw reference dashed) and the four "
                           "motor commands against time.",
    DRIFT_FIGURE: "The drift of the dead-reckoned estimate: its horizontal distance from "
                  "the true track (the emulator's) against time, with the 1-sigma "
                  "uncertainty stated for the landing (dashed).",
}


def check_report_path(path: str | Path) -> Path:
    """``path`` as a Path; QuadnavError unless it ends in .html (or .htm) in a folder
    that exists."""
    path = Path(path)
    if path.suffix.lower() not in SUFFIXES:
        raise QuadnavError(f"{path}: expected a file name ending in .html")
    if not path.parent.is_dir():
        raise QuadnavError(f"{path}: folder {str(path.parent)!r} does not exist")
    return path


def format_value(value: object) -> str:
    """A JSON value as text: numbers to 6 significant digits, lists in brackets, null as
    a dash."""
    if value is None:
        return "—"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float):
        return f"{value:.6g}"
    if isinstance(value, list):
        return "[" + ", ".join(format_value(item) for item in value) + "]"
    return str(value)


def flatten(value: object, prefix: str = "") -> list[tuple[str, object]]:
    """Nested dictionaries as (dotted name, leaf value) rows, in file order."""
    if not isinstance(value, dict):
        return [(prefix, value)]
    rows: list[tuple[str, object]] = []
    for key, item in value.items():
        rows += flatten(item, f"{prefix}.{key}" if prefix else str(key))
    return rows


def unit_of(key: str) -> str:
    """The unit a metrics.json key ends in (``_m``, ``_s``, ``_m_s``), or ''."""
    return next((unit for ending, unit in UNITS if key.endswith(ending)), "")


def _png(run: Run, name: str, make: Callable[[Run], Figure]) -> bytes:
    """The figure ``name`` of ``run``: the folder's PNG file, or drawn by ``make``."""
    path = run.folder / name
    if path.is_file():
        return path.read_bytes()
    return png_bytes(make(run))


def png_bytes(fig: Figure) -> bytes:
    """``fig`` as PNG bytes (:func:`~quadnav.viz.figures.write_png`)."""
    buffer = io.BytesIO()
    write_png(fig, buffer)
    return buffer.getvalue()


def _summary(run: Run) -> str:
    """The headline numbers of a run, one line of text."""
    m = run.metrics
    if run.is_track:
        parts = [f"vehicle {m['vehicle']}", f"reference {m['reference_duration_s']:.2f} s"]
    else:
        parts = [f"{m['planner']} seed {m['seed']}", f"vehicle {m['vehicle']}",
                 f"top speed {m['speed_m_s']:g} m/s"]
    if run.flight is not None:
        clearance = m["min_clearance_m"]
        parts += [] if run.is_track else [f"path {m['path_length_m']:.2f} m"]
        parts += [f"flight {m['flight_time_s']:.2f} s",
                  f"tracking error RMS {CM_PER_M * m['rms_tracking_error_m']:.2f} cm, max "
                  f"{CM_PER_M * m['max_tracking_error_m']:.2f} cm"]
        parts += (_landing(m) if run.is_hardware
                  else [f"final error {CM_PER_M * m['final_error_m']:.2f} cm"])
        if not run.is_track:
            parts.append("min clearance " + ("none" if clearance is None
                                             else f"{clearance:.3f} m"))
        if "overshoot_percent" in m:
            parts.append(step_summary(m))
    return ", ".join(parts)


def _landing(metrics: dict) -> list[str]:
    """A real drone's landing: where its dead reckoning put it, with the stated 1-sigma
    (as ``quadnav tello fly`` printed it), and where it truly landed and the estimate's
    drift from the truth, when known."""
    m = metrics
    if m.get("landing_m") is None:
        return ["landing not confirmed"]
    parts = [f"landed at {format_estimate(m['landing_m'], m['landing_sigma_m'])} (dead "
             f"reckoning), {m['final_error_m']:.2f} m from the goal (tolerance "
             f"{m['goal_tolerance_m']:g} m)"]
    if m.get("true_landing_m") is not None:
        parts.append(f"truly at {format_point(m['true_landing_m'])}, "
                     f"{m['true_final_error_m']:.2f} m from the goal: drift "
                     f"{CM_PER_M * m['landing_drift_m']:.2f} cm at the landing, RMS "
                     f"{CM_PER_M * m['rms_drift_m']:.2f} cm, max "
                     f"{CM_PER_M * m['max_drift_m']:.2f} cm")
    return parts


def _section(run: Run, number: int, folder: Path) -> dict[str, Any]:
    """What the report shows of one run (anchor ``run-NUMBER``), naming ``folder`` as its
    folder."""
    m = run.metrics
    return {"number": number, "title": run.title, "folder": str(folder),
            "track": run.is_track, "size": " x ".join(f"{extent:g}" for extent in run.world.extent),
            "blocks": len(run.world.blocks), "start": format_value(m["start"]),
            "goal": format_value(m["goal"]), "margin": m.get("margin_m"),
            "status": "success" if m["success"] else "failure", "outcome": run_outcome(m),
            "summary": _summary(run),
            "figures": [figure(_png(run, name, make), CAPTIONS[name])
                        for name, make in figure_makers(run).items()],
            "metrics": [(key, format_value(value), unit_of(key)) for key, value in m.items()],
            "parameters": [(key, format_value(value)) for key, value in flatten(run.parameters)]}


def _overview_row(number: int, run: Run) -> tuple[object, ...]:
    """A run's line in the overview: its number, title, outcome, path length (m), flight
    time (s), RMS and largest tracking error (cm)."""

    def shown(value: float | None, scale: float = 1.0) -> str:
        return "—" if value is None else f"{scale * value:.2f}"

    m = run.metrics
    return (number, run.title, run_outcome(m), shown(m.get("path_length_m")),
            shown(m.get("flight_time_s")), shown(m.get("rms_tracking_error_m"), CM_PER_M),
            shown(m.get("max_tracking_error_m"), CM_PER_M))


def report_html(runs: Sequence[Run], shown: Sequence[Path] | None = None) -> str:
    """The whole report over ``runs`` (at least one) as one HTML document; ``shown``: the
    folder to name for each run (default: where each was read from)."""
    title = ("quadnav flight report" if len(runs) > 1
             else f"quadnav flight report: {runs[0].title}")
    folders = shown or [run.folder for run in runs]
    return render("report.html", title=title, version=__version__,
                  overview=[_overview_row(k, run) for k, run in enumerate(runs, start=1)],
                  runs=[_section(run, k, folder)
                        for k, (run, folder) in enumerate(zip(runs, folders, strict=True), 1)])


def write_report(runs: Sequence[Run], path: str | Path,
                 shown: Sequence[Path] | None = None) -> Path:
    """Write :func:`report_html` of ``runs`` (folders named as ``shown``) to ``path``
    (.html), whole or not at all; returns the path. QuadnavError for a bad path."""
    path = check_report_path(path)
    text = report_html(runs, shown)
    with atomic_output(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return path

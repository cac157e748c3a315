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

import base64
import html
import io
import struct
from collections.abc import Callable, Sequence
from pathlib import Path

from matplotlib.figure import Figure

from quadnav import __version__
from quadnav.errors import QuadnavError
from quadnav.files import atomic_output
from quadnav.runs import DRIFT_FIGURE, Run, run_outcome
from quadnav.tracking import step_summary
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
STYLE = """
body { font-family: system-ui, -apple-system, "Segoe UI", Helvetica, Arial, sans-serif;
       color: #222; margin: 0; background: #fff; line-height: 1.45; }
main { max-width: 1120px; margin: 0 auto; padding: 1.5em; }
h1 { font-size: 1.6em; margin-bottom: 0.2em; }
h2 { font-size: 1.3em; border-bottom: 2px solid #ccc; padding-bottom: 0.2em;
     margin-top: 2.2em; overflow-wrap: anywhere; }
h3 { font-size: 1.05em; margin-top: 1.6em; }
.outcome { font-weight: 600; }
.success { color: #1a7f37; }
.failure { color: #c62828; }
figure { margin: 1em 0; }
figure img { max-width: 100%; height: auto; border: 1px solid #e4e4e4; }
.tooltips { position: relative; width: fit-content; max-width: 100%; }
.tooltips img { display: block; }
.tooltips .tooltip { position: absolute; }
figcaption { font-size: 0.9em; color: #555; }
table { border-collapse: collapse; font-size: 0.9em; margin: 0.5em 0; }
th, td { border: 1px solid #ddd; padding: 0.25em 0.6em; text-align: left;
         vertical-align: top; }
th { background: #f3f3f3; }
td.value { font-family: ui-monospace, Menlo, Consolas, monospace; overflow-wrap: anywhere; }
code { font-family: ui-monospace, Menlo, Consolas, monospace; font-size: 0.95em; }
.muted { color: #666; font-size: 0.9em; overflow-wrap: anywhere; }
@media print { section + section { break-before: page; } main { max-width: none; } }
"""


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


def html_table(header: Sequence[str], rows: Sequence[Sequence[str]], value_column: int) -> str:
    """An HTML table of already escaped cells; the ``value_column`` is set monospace."""
    head = "".join(f"<th>{cell}</th>" for cell in header)
    body = "".join(
        "<tr>" + "".join(f'<td class="value">{cell}</td>' if column == value_column
                         else f"<td>{cell}</td>" for column, cell in enumerate(row)) + "</tr>"
        for row in rows)
    return f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


def _png(run: Run, name: str, make: Callable[[Run], Figure]) -> bytes:
    """The figure ``name`` of ``run``: the folder's PNG file, or drawn by ``make``."""
    path = run.folder / name
    if path.is_file():
        return path.read_bytes()
    return png_bytes(make(run))


def png_bytes(fig: Figure) -> bytes:
    """``fig`` as PNG bytes."""
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png")
    return buffer.getvalue()


def figure_html(png: bytes, caption: str,
                tooltips: Sequence[tuple[tuple[float, float, float, float], str]] = ()) -> str:
    """A ``<figure>`` with the PNG embedded (base64) and its caption; each of ``tooltips``,
    ``((left, top, width, height), text)`` with the box in fractions of the image from its
    top left corner, shows ``text`` when the pointer rests on that part of the image (a
    shortened label's full wording), at any size the image is shown."""
    width, height = struct.unpack(">II", png[16:24])  # from the PNG's IHDR chunk
    data = base64.b64encode(png).decode("ascii")
    image = (f'<img src="data:image/png;base64,{data}" width="{width}" '
             f'height="{height}" alt="{html.escape(caption)}">')
    if tooltips:
        spots = "".join(
            f'<span class="tooltip" title="{html.escape(text)}" style="left: {100 * left:.3f}%; '
            f'top: {100 * top:.3f}%; width: {100 * wide:.3f}%; height: {100 * high:.3f}%">'
            "</span>" for (left, top, wide, high), text in tooltips)
        image = f'<div class="tooltips">{image}{spots}</div>'
    return f"<figure>{image}<figcaption>{html.escape(caption)}</figcaption></figure>"


def html_page(title: str, body: str) -> str:
    """A whole HTML document: ``title`` (text) and ``body`` (HTML) in the report's style."""
    return (f'<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
            f'<meta name="viewport" content="width=device-width, initial-scale=1">'
            f"<title>{html.escape(title)}</title><style>{STYLE}</style></head>"
            f"<body><main>{body}</main></body></html>\n")


def _summary(run: Run) -> str:
    """The outcome and the headline numbers of a run, one line of HTML."""
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
    status = "success" if m["success"] else "failure"
    return (f'<p><span class="outcome {status}">{html.escape(run_outcome(m))}</span> — '
            f"{html.escape(', '.join(parts))}</p>")


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


def run_section(run: Run, number: int, folder: Path) -> str:
    """The report section of one run (anchor ``run-NUMBER``), naming ``folder`` as its
    folder."""
    m = run.metrics
    world = run.world
    size = " x ".join(f"{extent:g}" for extent in world.extent)
    figures = "".join(figure_html(_png(run, name, make), CAPTIONS[name])
                      for name, make in figure_makers(run).items())
    metrics = html_table(("metrics.json key", "value", "unit"),
                     [(f"<code>{html.escape(key)}</code>", html.escape(format_value(value)),
                       unit_of(key)) for key, value in m.items()], 1)
    parameters = html_table(("parameter", "value"),
                        [(f"<code>{html.escape(key)}</code>", html.escape(format_value(value)))
                         for key, value in flatten(run.parameters)], 1)
    where = (f"flown in an empty box of {size} m" if run.is_track
             else f"map {size} m with {len(world.blocks)} blocks")
    margin = "" if run.is_track else f", margin {m['margin_m']:g} m"
    return (f'<section id="run-{number}"><h2>Run {number}: {html.escape(run.title)}</h2>'
            f'<p class="muted">folder {html.escape(str(folder))}; {where}, start '
            f"{html.escape(format_value(m['start']))} m, "
            f"{'end' if run.is_track else 'goal'} {html.escape(format_value(m['goal']))} m"
            f"{margin}</p>{_summary(run)}"
            f"<h3>Figures</h3>{figures}"
            f"<h3>Metrics</h3>{metrics}"
            f"<h3>Parameters</h3>{parameters}</section>")


def _overview(runs: Sequence[Run]) -> str:
    """A table of every run's outcome and headline numbers, linking to its section."""

    def number(value: float | None, scale: float = 1.0) -> str:
        return "—" if value is None else f"{scale * value:.2f}"

    rows = [(f'<a href="#run-{k}">{k}</a>', html.escape(run.title),
             html.escape(run_outcome(run.metrics)), number(run.metrics.get("path_length_m")),
             number(run.metrics.get("flight_time_s")),
             number(run.metrics.get("rms_tracking_error_m"), CM_PER_M),
             number(run.metrics.get("max_tracking_error_m"), CM_PER_M))
            for k, run in enumerate(runs, start=1)]
    return "<h2>Overview</h2>" + html_table(
        ("run", "map or reference", "outcome", "path (m)", "flight (s)", "RMS error (cm)",
         "max error (cm)"), rows, 1)


def report_html(runs: Sequence[Run], shown: Sequence[Path] | None = None) -> str:
    """The whole report over ``runs`` (at least one) as one HTML document; ``shown``: the
    folder to name for each run (default: where each was read from)."""
    title = ("quadnav flight report" if len(runs) > 1
             else f"quadnav flight report: {runs[0].title}")
    folders = shown or [run.folder for run in runs]
    sections = "".join(run_section(run, k, folder)
                       for k, (run, folder) in enumerate(zip(runs, folders, strict=True), 1))
    overview = _overview(runs) if len(runs) > 1 else ""
    return html_page(title, f"<h1>quadnav flight report</h1>"
                     f'<p class="muted">{len(runs)} run{"s" if len(runs) > 1 else ""}, '
                     f"written by quadnav {__version__} from the files of each run folder. "
                     "Units are SI (metres, seconds) unless a column says otherwise.</p>"
                     f"{overview}{sections}")


def write_report(runs: Sequence[Run], path: str | Path,
                 shown: Sequence[Path] | None = None) -> Path:
    """Write :func:`report_html` of ``runs`` (folders named as ``shown``) to ``path``
    (.html), whole or not at all; returns the path. QuadnavError for a bad path."""
    path = check_report_path(path)
    text = report_html(runs, shown)
    with atomic_output(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return path

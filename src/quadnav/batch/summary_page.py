"""``summary.html``: one self-contained page over a batch's results, readable offline.

* the success rate per map and speed as a heat map, one panel per combination of the
  other grid values (wind, gusts, spread, planner, gains, controller, trajectory method or
  class), each cell with its Wilson 95 %
  interval;
* box plots of the RMS tracking error, the least clearance and the trajectory duration
  of each group's flown missions;
* the table of the groups (``summary.json``).

The figures name each map by a short label (the end of its path that tells it apart, cut in
the middle when long); resting the pointer on a label shows the map's full name, which the
table gives too. Images are embedded PNGs and the style inline (the report's: the page
extends :mod:`quadnav.pages`' ``base.html``, in ``templates/summary.html``).
"""

from __future__ import annotations

import inspect
import math
import re
import textwrap
from collections.abc import Sequence
from pathlib import Path, PurePath
from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.text import Text

from quadnav import __version__
from quadnav.batch.compare import short_spec
from quadnav.batch.summary import GROUP_COLUMNS, MEDIAN_COLUMNS, group_values, percent_text
from quadnav.files import atomic_output
from quadnav.pages import figure, render
from quadnav.report.html_report import png_bytes
from quadnav.viz.flight_figures import SMALL_FONT, TITLE_FONT
from quadnav.world.builtin import is_builtin_spec
from quadnav.world.courses import is_course_name

SUMMARY_HTML = "summary.html"
#: Figure resolution, dots per inch, and the widths of the figures, inches (shown about
#: 1100 pixels wide, the report's width).
DPI = 120
WIDTH = 9.0
#: Distributions drawn: column, axis label, scale to the unit shown.
DISTRIBUTIONS = (("rms_tracking_error_m", "RMS tracking\nerror (cm)", 100.0),
                 ("min_clearance_m", "least clearance\nfrom a block (m)", 1.0),
                 ("trajectory_duration_s", "trajectory\nduration (s)", 1.0))
#: Characters per line of a group's label beside the box plots.
LABEL_WIDTH = 42
#: Most characters of a map's label in the figures (the page shows its full name on hover).
MAP_LABEL_WIDTH = 32
#: Inches a row label of the heat map takes per character, and beyond its characters.
LABEL_INCHES_PER_CHARACTER = 0.075
LABEL_INCHES = 0.3
#: Inches of one speed's column of a heat map at least (room for its two lines of text at
#: SMALL_FONT), and of the gap after a panel.
CELL_INCHES = 0.9
PANEL_GAP_INCHES = 0.3
#: Inches of the colour bar beside the heat maps, with its labels.
COLORBAR_INCHES = 1.0
#: Inches a character of a panel's title takes, about (wider than most).
TITLE_INCHES_PER_CHARACTER = 0.65 * TITLE_FONT / 72
#: Inches of one row of a heat map, and of a line of panels beyond its rows (title, ticks).
ROW_INCHES = 0.42
PANEL_INCHES = 0.8


#: Matplotlib's way to lay box plots on their side (``vert`` before 3.10).
HORIZONTAL = ({"orientation": "horizontal"}
              if "orientation" in inspect.signature(Axes.boxplot).parameters else {"vert": False})


def short_maps(names: Sequence[str]) -> dict[str, str]:
    """Short labels of map names, at most :data:`MAP_LABEL_WIDTH` characters: built-in world
    specs and course maps as they are, files by the fewest trailing parts of their path that
    no other name ends with (the file name when that is enough); cut in the middle when
    longer; numbered when two would read the same."""
    parts = {name: (name,) if _is_named(name) else PurePath(name).parts or (name,)
             for name in dict.fromkeys(names)}

    def tail(name: str) -> str:
        own = parts[name]
        others = [other for key, other in parts.items() if key != name]
        count = next((k for k in range(1, len(own)) if all(other[-k:] != own[-k:]
                                                            for other in others)), len(own))
        return str(PurePath(*own[-count:]))

    labels = {name: _cut(tail(name), MAP_LABEL_WIDTH) for name in parts}
    if len(set(labels.values())) < len(labels):
        labels = {name: _cut(f"{k}. {tail(name)}", MAP_LABEL_WIDTH)
                  for k, name in enumerate(parts, 1)}
    return labels


def _cut(text: str, width: int) -> str:
    """``text``, or when longer than ``width`` characters its start and (longer) end with
    an ellipsis between, ``width`` characters in all."""
    if len(text) <= width:
        return text
    head = (width - 1) // 3
    return text[:head] + "\u2026" + text[len(text) - (width - 1 - head):]


def _is_named(name: str) -> bool:
    """Whether a map name is a built-in world spec or a course map, not a file."""
    return is_builtin_spec(name) or is_course_name(name)


def _speed(value: float | None) -> str:
    return "max" if value is None else f"{value:g} m/s"


def _percent(value: float | None) -> str:
    return percent_text(value, digits=0)


class _Groups:
    """The groups of a summary with the labels the page shows for them: short ones in the
    figures, the maps' full names in the table and on hover."""

    def __init__(self, summary_groups: list[dict[str, Any]]) -> None:
        self.groups = summary_groups
        self.maps = short_maps([g["map"] for g in summary_groups])
        self.varying = [name for name in (*GROUP_COLUMNS, "start", "goal")
                        if len({json_key(g[name]) for g in summary_groups}) > 1]

    def row_label(self, group: dict[str, Any], full: bool = False) -> str:
        """Map (and its query when the map is flown with several), by its short label or
        by its ``full`` name."""
        label = group["map"] if full else self.maps[group["map"]]
        same_map = [g for g in self.groups if g["map"] == group["map"]]
        queries = {json_key([g[n] for n in ("start", "goal", "margin_m")]) for g in same_map}
        if len(queries) > 1:
            label += " " + _query(group)
        return label

    def panel_label(self, group: dict[str, Any]) -> str:
        """The panel's grid values, those that vary."""
        parts = []
        if any(n in self.varying for n in ("wind_x", "wind_y", "wind_z")):
            parts.append(f"wind ({group['wind_x']:g}, {group['wind_y']:g}, "
                         f"{group['wind_z']:g}) N")
        if "gusts" in self.varying:
            parts.append(f"gusts {group['gusts']:g} N")
        if "spread" in self.varying:
            parts.append(f"spread {group['spread']}")
        if "planner" in self.varying:
            parts.append(short_spec(group["planner"]))
        if "gains" in self.varying:
            parts.append(f"gains {Path(group['gains']).name}")
        parts += [short_spec(group[name] or "") for name in (
            "wind_model", "controller", "method", "reference") if name in self.varying]
        return ", ".join(part for part in parts if part)

    def label(self, group: dict[str, Any], full: bool = False) -> str:
        """Everything that tells the group apart from the others, the map by its short
        label or by its ``full`` name."""
        parts = [self.row_label(group, full)]
        if "speed" in self.varying:
            parts.append(_speed(group["speed"]))
        panel = self.panel_label(group)
        return ", ".join(parts + ([panel] if panel else []))


def wrapped(text: str, width: int) -> str:
    """``text`` in lines of at most ``width`` characters where it can be, each broken only
    after a space, ``,``, ``/``, ``:`` or ``(`` (a word or a number is never cut)."""
    lines = [""]
    for piece in re.split(r"(?<=[ ,/:(])", text):
        if lines[-1] and len(lines[-1]) + len(piece.rstrip()) > width:
            lines[-1] = lines[-1].rstrip()
            lines.append("")
        lines[-1] += piece
    return "\n".join(line.rstrip() for line in lines)


def json_key(value: Any) -> str:
    """A hashable text of a JSON value."""
    return repr(value)


def _query(group: dict[str, Any]) -> str:
    if group["start"] == "drawn":
        return f"(drawn start, goal; margin {group['margin_m']:g} m)"
    start, goal = (", ".join(f"{v:g}" for v in group[end]) for end in ("start", "goal"))
    return f"({start} to {goal}; margin {group['margin_m']:g} m)"


def heat_map(labels: _Groups) -> tuple[Figure, dict[Text, str]]:
    """Success rate per map (rows) and speed (columns), one panel per combination of the
    other grid values; each cell shows the rate and its 95 % interval in percent. The rows
    are labelled on the left of each line of panels only, so no label reaches into another
    panel, and the figure grows with the rows. Returns the figure and the row labels drawn,
    each with its full wording."""
    panels: dict[str, list[dict[str, Any]]] = {}
    for group in labels.groups:
        panels.setdefault(labels.panel_label(group), []).append(group)
    full = {labels.row_label(g): labels.row_label(g, full=True) for g in labels.groups}
    rows = list(full)
    speeds = sorted({g["speed"] for g in labels.groups},
                    key=lambda v: math.inf if v is None else v)
    label_width = LABEL_INCHES_PER_CHARACTER * max(len(r) for r in rows) + LABEL_INCHES
    panel_width = CELL_INCHES * len(speeds) + PANEL_GAP_INCHES
    width = max(WIDTH, label_width + panel_width + COLORBAR_INCHES)  # wider for many speeds
    columns = max(1, min(len(panels), int((width - label_width - COLORBAR_INCHES)
                                          // panel_width)))
    title_width = int(((width - label_width - COLORBAR_INCHES) / columns - PANEL_GAP_INCHES)
                      / TITLE_INCHES_PER_CHARACTER)
    lines = math.ceil(len(panels) / columns)
    fig = Figure(figsize=(width, lines * (PANEL_INCHES + ROW_INCHES * len(rows)) + 0.6),
                 dpi=DPI, layout="constrained")
    axes = np.atleast_1d(fig.subplots(lines, columns, squeeze=False)).ravel()
    image = None
    drawn: dict[Text, str] = {}
    for k, (ax, (title, groups)) in enumerate(zip(axes, panels.items(), strict=False)):
        rates = np.full((len(rows), len(speeds)), np.nan)
        for group in groups:
            i, j = rows.index(labels.row_label(group)), speeds.index(group["speed"])
            rates[i, j] = group["success_rate"]
            text = (f"{_percent(group['success_rate'])} %\n[{_percent(group['ci_low'])}, "
                    f"{_percent(group['ci_high'])}]")
            ax.text(j, i, text, ha="center", va="center", fontsize=SMALL_FONT,
                    color="black" if 0.25 < group["success_rate"] < 0.95 else "white")
        image = ax.imshow(rates, cmap="RdYlGn", vmin=0.0, vmax=1.0, aspect="auto")
        ax.set_xticks(range(len(speeds)), [_speed(v) for v in speeds], fontsize=SMALL_FONT)
        first = k % columns == 0
        ax.set_yticks(range(len(rows)), rows if first else [], fontsize=SMALL_FONT)
        if first:
            drawn |= {text: full[text.get_text()] for text in ax.get_yticklabels()}
        ax.tick_params(length=0)
        if title:
            ax.set_title(wrapped(title, title_width), fontsize=TITLE_FONT)
    for ax in axes[len(panels):]:
        ax.set_visible(False)
    bar = fig.colorbar(image, ax=axes[:len(panels)].tolist(), shrink=0.8, pad=0.02)
    bar.set_label("success rate", fontsize=SMALL_FONT)
    bar.ax.tick_params(labelsize=SMALL_FONT)
    return fig, drawn


def distributions(labels: _Groups, rows: Sequence[dict[str, Any]]
                  ) -> tuple[Figure, dict[Text, str]]:
    """Box plots, one per group, of the RMS tracking error, the least clearance and the
    trajectory duration of its flown missions. Returns the figure and the group labels
    drawn, each with its full wording."""
    members: dict[str, list[dict[str, Any]]] = {}
    for row in rows:
        members.setdefault(json_key(group_values(row)), []).append(row)
    names = [textwrap.fill(labels.label(g), LABEL_WIDTH) for g in labels.groups]
    keys = list(members)
    lines = max(name.count("\n") + 1 for name in names)
    fig = Figure(figsize=(WIDTH, 1.0 + (0.12 + 0.16 * lines) * len(names)), dpi=DPI,
                 layout="constrained")
    axes = fig.subplots(1, len(DISTRIBUTIONS), sharey=True)
    positions = np.arange(len(names))[::-1]
    for ax, (column, title, scale) in zip(axes, DISTRIBUTIONS, strict=True):
        data = [[scale * row[column] for row in members[key]
                 if row[column] is not None and math.isfinite(row[column])] for key in keys]
        filled = [k for k, values in enumerate(data) if values]
        if filled:
            ax.boxplot([data[k] for k in filled], positions=positions[filled], widths=0.6,
                       flierprops={"markersize": 3}, **HORIZONTAL)
        ax.set_xlabel(title, fontsize=SMALL_FONT)
        ax.tick_params(labelsize=SMALL_FONT)
        ax.grid(axis="x", alpha=0.3)
    axes[0].set_yticks(positions, names)
    axes[0].set_ylim(-0.7, len(names) - 0.3)
    full = [labels.label(g, full=True) for g in labels.groups]
    return fig, dict(zip(axes[0].get_yticklabels(), full, strict=True))


def tooltip_boxes(fig: Figure, texts: dict[Text, str]
                  ) -> list[tuple[tuple[float, float, float, float], str]]:
    """Where each of ``texts`` is drawn in ``fig`` as (left, top, width, height) in fractions
    of the figure from its top left corner, with its full wording: the figure is laid out
    as it will be saved."""
    fig.draw_without_rendering()
    width, height = fig.bbox.width, fig.bbox.height
    boxes = []
    for text, wording in texts.items():
        box = text.get_window_extent()
        boxes.append(((box.x0 / width, 1.0 - box.y1 / height, box.width / width,
                       box.height / height), wording))
    return boxes


def _figure_with_tooltips(drawn: tuple[Figure, dict[Text, str]], caption: str
                          ) -> dict[str, Any]:
    """The page's figure (:func:`quadnav.pages.figure`) of a figure and its labels' full
    wording (on hover)."""
    fig, texts = drawn
    tooltips = tooltip_boxes(fig, texts)
    return figure(png_bytes(fig), caption, tooltips)


def _cell(value: Any) -> str:
    if value is None:
        return "—"
    if isinstance(value, float):
        return f"{value:.3g}"
    return str(value)


def groups_table(labels: _Groups) -> list[tuple[str, ...]]:
    """The rows of the groups' table: what tells them apart, n, successes, the rate and its
    interval (percent), refused missions, flights short of the margin and the medians."""
    return [(labels.label(g, full=True), str(g["n"]), str(g["successes"]),
             _percent(g["success_rate"]), f"{_percent(g['ci_low'])}\u2013{_percent(g['ci_high'])}",
             str(g["errors"]), str(g["short_of_margin"]),
             *(_cell(g[f"median_{name}"]) for name in MEDIAN_COLUMNS))
            for g in labels.groups]


def summary_html(summary: dict[str, Any], rows: Sequence[dict[str, Any]], folder: Path) -> str:
    """The page over ``summary`` (:func:`~quadnav.batch.summary.summary`) and the ``rows``
    it summarises, naming ``folder`` as the batch's."""
    labels = _Groups(summary["groups"])
    figures = {}
    if labels.groups:
        figures = {
            "heat_map": _figure_with_tooltips(
                heat_map(labels), "Share of missions that reached the goal, per map and "
                "speed, in percent, with its 95 % interval in brackets. A map's full name "
                "shows on its label."),
            "distributions": _figure_with_tooltips(
                distributions(labels, rows), "Per group, over its flown missions: the RMS "
                "tracking error, the least clearance of the vehicle's centre from a block, "
                "and the trajectory's duration (box: quartiles; whiskers: 1.5 times the box; "
                "dots: beyond).")}
    return render("summary.html", title="quadnav batch summary", folder=str(folder),
                  version=__version__, summary=summary, rate=_percent(summary["success_rate"]),
                  ci_low=_percent(summary["ci_low"]), ci_high=_percent(summary["ci_high"]),
                  groups=groups_table(labels),
                  medians=[f"median {name}" for name in MEDIAN_COLUMNS], **figures)


def write_summary_page(summary: dict[str, Any], rows: Sequence[dict[str, Any]],
                       folder: Path) -> None:
    """Write ``folder``/summary.html, atomically."""
    text = summary_html(summary, rows, folder)
    with atomic_output(folder / SUMMARY_HTML) as tmp:
        tmp.write_text(text, encoding="utf-8")

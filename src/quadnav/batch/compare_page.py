"""``compare.png`` and ``compare.html``: the leaderboard of a batch
(:func:`~quadnav.batch.compare.compare`) drawn and written as one offline page.

The figure has one panel per measure: the success rate with its Wilson 95 % interval, then
the median of each :data:`~quadnav.batch.compare.METRICS` with its quartiles, one bar per
contender, best first from the top. The page shows it with the leaderboard and every
comparison of two contenders, its tests and whether the difference is significant.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from quadnav import __version__
from quadnav.batch.compare import ALPHA, METRIC_NOTES, METRICS
from quadnav.batch.summary import percent_text
from quadnav.batch.summary_page import wrapped
from quadnav.files import atomic_output
from quadnav.pages import figure, render
from quadnav.report.html_report import png_bytes
from quadnav.viz.flight_figures import SMALL_FONT, TITLE_FONT

COMPARE_HTML, COMPARE_PNG = "compare.html", "compare.png"
#: Figure resolution, dots per inch, its width, inches, and the panels in a line.
DPI = 120
WIDTH = 9.0
COLUMNS = 3
#: Characters per line of a contender's label, and inches per bar.
LABEL_WIDTH = 24
BAR_INCHES = 0.3


def leaderboard_figure(result: dict[str, Any]) -> Figure:
    """The bars of every contender (best at the top) with their whiskers: success rate in
    percent with its interval, each metric's median with its quartiles."""
    contenders = result["contenders"]
    labels = [wrapped(c["contender"], LABEL_WIDTH) for c in contenders]
    lines = sum(label.count("\n") + 1 for label in labels) / len(labels)
    panels = 1 + len(METRICS)
    rows = math.ceil(panels / COLUMNS)
    height = rows * (0.9 + BAR_INCHES * max(lines, 1.0) * len(contenders))
    fig = Figure(figsize=(WIDTH, height), dpi=DPI, layout="constrained")
    axes = fig.subplots(rows, COLUMNS, squeeze=False).ravel()
    positions = np.arange(len(contenders))[::-1]
    success = [(100 * c["success_rate"], 100 * c["ci_low"], 100 * c["ci_high"])
               for c in contenders]
    _bars(axes[0], positions, success, "success rate (%)", "tab:green")
    axes[0].set_xlim(0, 105)
    for ax, metric in zip(axes[1:], METRICS, strict=False):
        values = [(c[metric.name]["median"], c[metric.name]["q1"], c[metric.name]["q3"])
                  for c in contenders]
        better = "lower" if metric.lower_is_better else "higher"
        _bars(ax, positions, values, f"{metric.title} ({metric.unit}),\n{better} is better",
              "tab:blue")
    for k, ax in enumerate(axes[:panels]):
        ax.set_yticks(positions, labels if k % COLUMNS == 0 else [], fontsize=SMALL_FONT)
        ax.set_ylim(-0.7, len(contenders) - 0.3)
    for ax in axes[panels:]:
        ax.set_visible(False)
    fig.suptitle(f"{len(contenders)} contenders by {', '.join(result['by'])}",
                 fontsize=TITLE_FONT)
    return fig


def _bars(ax: Any, positions: np.ndarray, values: list[tuple[Any, Any, Any]], title: str,
          colour: str) -> None:
    """Horizontal bars of the centres of ``values`` (centre, low, high) with whiskers from
    low to high; a contender without a value has no bar."""
    for y, (centre, low, high) in zip(positions, values, strict=True):
        if centre is None:
            continue
        ax.barh(y, centre, height=0.6, color=colour, alpha=0.6)
        ax.errorbar(centre, y, xerr=[[centre - low], [high - centre]], fmt="none",
                    ecolor="black", capsize=3, linewidth=1)
    ax.set_xlabel(title, fontsize=SMALL_FONT)
    ax.tick_params(labelsize=SMALL_FONT)
    ax.grid(axis="x", alpha=0.3)


def _number(value: float | None) -> str:
    return "—" if value is None else f"{value:.3g}"


def median_text(spread: dict[str, Any]) -> str:
    """A metric's median and quartiles as shown: ``median [q1, q3]``."""
    if spread["median"] is None:
        return "—"
    return f"{_number(spread['median'])} [{_number(spread['q1'])}, {_number(spread['q3'])}]"


def leaderboard_rows(result: dict[str, Any]) -> tuple[list[str], list[list[str]]]:
    """The leaderboard as text cells: its header and one row per contender."""
    header = ["rank", "contender", "success", "95 % interval (%)",
              *(f"{m.title} ({m.unit})" for m in METRICS)]
    rows = [[str(c["rank"]), c["contender"],
             f"{c['successes']}/{c['n']} = {percent_text(c['success_rate'])} %",
             f"{percent_text(c['ci_low'])} to {percent_text(c['ci_high'])}",
             *(median_text(c[m.name]) for m in METRICS)] for c in result["contenders"]]
    return header, rows


def comparison_text(comparison: dict[str, Any]) -> str:
    """What a comparison found, in words (without its p-values)."""
    if comparison["metric"] == "success":
        found = (f"success: {comparison['a_only']} pairs only {comparison['a']} reached the "
                 f"goal, {comparison['b_only']} only {comparison['b']}")
    else:
        metric = next(m for m in METRICS if m.name == comparison["metric"])
        found = (f"{metric.title}: median paired difference "
                 f"{_number(comparison['median_difference'])} {metric.unit} over "
                 f"{comparison['pairs']} pairs")
    if comparison["better"]:
        found += f"; {comparison['better']} better"
    return found


def untimed_text(result: dict[str, Any]) -> str:
    """A line saying how many missions reached the goal without a time to goal (rows of a
    table written before flights measured it), or "" when none did."""
    if not result["untimed"]:
        return ""
    return (f"time to goal: {result['untimed']} missions reached the goal in rows written "
            "before quadnav measured it and have none; the time to goal is over the others")


def compare_html(result: dict[str, Any], folder: Path, png: bytes) -> str:
    """The page of the leaderboard ``result`` of the batch in ``folder``, with its figure
    ``png``."""
    header, rows = leaderboard_rows(result)
    comparisons = sorted(result["comparisons"], key=lambda c: (not c["significant"], c["p_holm"]))
    return render(
        "compare.html", title="quadnav compare", folder=str(folder), version=__version__,
        result=result, metric_notes=METRIC_NOTES, alpha=ALPHA, untimed=untimed_text(result),
        leaderboard=figure(png, "Per contender, best at the top: the success rate with its "
                                "95 % interval, and the median of each measure with its "
                                "quartiles."),
        header=header, rows=rows,
        significant=sum(c["significant"] for c in comparisons),
        comparisons=[(f"{c['a']} vs {c['b']}", comparison_text(c), f"{c['p']:.3g}",
                      f"{c['p_holm']:.3g}", "yes" if c["significant"] else "no")
                     for c in comparisons])


def write_compare_page(result: dict[str, Any], folder: Path) -> list[str]:
    """Write ``folder``/compare.png and compare.html, atomically; returns their names."""
    png = png_bytes(leaderboard_figure(result))
    with atomic_output(folder / COMPARE_PNG) as tmp:
        tmp.write_bytes(png)
    with atomic_output(folder / COMPARE_HTML) as tmp:
        tmp.write_text(compare_html(result, folder, png), encoding="utf-8")
    return [COMPARE_HTML, COMPARE_PNG]

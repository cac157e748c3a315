"""The summary of a batch: success rates per group of grid values with Wilson intervals,
and ``summary.json``.

A group is every distinct combination of the grid values but the seed: map, speed, wind
(force or class), gusts, spread, planner, gains, controller and trajectory method or class,
and the start, goal and margin when they were given
(not drawn from each seed). Success is the mission's own: the goal reached within the
tolerance with no contact and the body inside the map; a refused mission counts as a failure.
Apart from it, each rate counts the flights that kept less margin than asked off the legs
(``margin_shortfall_m`` above 0, by any amount), successes or not.
"""

from __future__ import annotations

import json
import math
import statistics
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from scipy.stats import binomtest

from quadnav.batch.table import AXES
from quadnav.files import atomic_output

#: Columns whose value names a group (the start and goal only when given).
GROUP_COLUMNS = ("map", "speed", "wind_x", "wind_y", "wind_z", "wind_model", "gusts", "spread",
                 "planner", "gains", "controller", "method", "reference", "margin_m")
QUERY_COLUMNS = tuple(f"{end}_{a}" for end in ("start", "goal") for a in AXES)
#: Columns whose medians each group reports.
MEDIAN_COLUMNS = ("rms_tracking_error_m", "min_clearance_m", "trajectory_duration_s")
SUMMARY_JSON = "summary.json"


def wilson_interval(successes: int, n: int) -> tuple[float, float]:
    """The Wilson score 95 % interval of a success rate, ``successes`` of ``n`` (n > 0),
    without continuity correction (scipy's ``binomtest(...).proportion_ci``): exactly 0
    below with no success and 1 above with no failure."""
    interval = binomtest(successes, n).proportion_ci(confidence_level=0.95, method="wilson")
    return float(interval.low), float(interval.high)


def percent_text(fraction: float | None, digits: int = 1) -> str:
    """``fraction`` in percent with ``digits`` decimals, and more (up to 4) where rounding
    would make a share that is not 0 or 1 read as 0 or 100 (the interval of 10,000
    successes in 10,000 missions starts at 99.96 %, not 100.0 %); a dash for None."""
    if fraction is None:
        return "\u2014"
    for places in range(digits, max(digits, 4) + 1):
        text = f"{100 * fraction:.{places}f}"
        if fraction in (0.0, 1.0) or float(text) not in (0.0, 100.0):
            break
    return text


def group_values(row: dict[str, Any]) -> dict[str, Any]:
    """The values naming the group of ``row``: :data:`GROUP_COLUMNS`, and the start and
    goal unless they were drawn."""
    values = {name: row[name] for name in GROUP_COLUMNS}
    if not row["start_goal_drawn"]:
        values |= {name: row[name] for name in QUERY_COLUMNS}
    return values


def rate(rows: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """``n``, ``successes``, ``success_rate`` and its Wilson 95 % ``ci_low``, ``ci_high``,
    ``errors`` (refused missions) and ``short_of_margin`` (flights that kept less margin
    than asked off the legs) of ``rows``."""
    n = len(rows)
    successes = sum(bool(row["success"]) for row in rows)
    low, high = wilson_interval(successes, n) if n else (None, None)
    return {"n": n, "successes": successes, "success_rate": successes / n if n else None,
            "ci_low": low, "ci_high": high,
            "errors": sum(row["error"] is not None for row in rows),
            "short_of_margin": sum(bool(row["margin_shortfall_m"]) for row in rows)}


def _median(rows: Sequence[dict[str, Any]], name: str) -> float | None:
    values = [row[name] for row in rows if row[name] is not None and math.isfinite(row[name])]
    return statistics.median(values) if values else None


def groups(rows: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """One entry per group, in the order of the rows: its values (:data:`GROUP_COLUMNS`,
    and the ``start`` and ``goal``, each [x, y, z] m or ``drawn``), :func:`rate` and the
    medians of
    :data:`MEDIAN_COLUMNS` (``median_`` before each name)."""
    members: dict[str, list[dict[str, Any]]] = {}
    for row in rows:
        members.setdefault(json.dumps(group_values(row)), []).append(row)
    summary = []
    for group in members.values():
        first = group[0]
        values = {name: first[name] for name in GROUP_COLUMNS} | {
            end: "drawn" if first["start_goal_drawn"] else
            [first[f"{end}_{a}"] for a in AXES] for end in ("start", "goal")}
        summary.append(values | rate(group)
                       | {f"median_{name}": _median(group, name) for name in MEDIAN_COLUMNS})
    return summary


def summary(rows: Sequence[dict[str, Any]], expected: int,
            ran_on: dict[str, int] | None = None, retried: int | None = None
            ) -> dict[str, Any]:
    """The whole summary: the overall rate over ``rows``, how many of the ``expected``
    missions they are, where this run flew its missions (``ran_on``: ``workers`` and the
    ``numba_threads`` of each; None when it flew none), how many of them it flew again
    because the worker process flying them died (``retried``; None when it flew none) and
    :func:`groups`."""
    return {"missions": expected, "finished": len(rows), "complete": len(rows) == expected,
            **rate(rows), "ran_on": ran_on, "retried": retried, "groups": groups(rows)}


def write_summary(content: dict[str, Any], path: Path) -> None:
    """Write :func:`summary`'s ``content`` as JSON, atomically."""
    with atomic_output(path) as tmp:
        tmp.write_text(json.dumps(content, indent=2, allow_nan=False) + "\n", encoding="utf-8")

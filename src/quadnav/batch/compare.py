"""The leaderboard of a batch: its contenders (the controllers, planners, trajectories, winds
... it flew) side by side, and which of their differences are significant.

A contender is a value of one axis of the grid (:data:`AXES`), or a combination of values
of several. Its missions are paired with another's: two missions pair when every other grid
value (map and query, seed, speed, the other axes) is the same, so each pair differs only in
the contender. Per contender: the success rate with its Wilson 95 % interval, and the median
and quartiles of each :data:`METRICS` over the missions that have a value (the time to goal:
those that reached the goal). Per pair of
contenders: McNemar's exact test on the paired successes (a two-sided binomial test of the
pairs where one succeeded and the other failed) and Wilcoxon's signed-rank test on each
metric's paired values (the pairs where both have one), every p-value then corrected by
Holm's method over all the comparisons that have a pair to test; a difference is significant
when its corrected p-value is below :data:`ALPHA`. A comparison without a pair (a metric that
rows written before its column have none of) tests nothing: it stays out of the correction,
which it would only make stricter, with p-values of 1 (no pair has two times to goal when
one contender never reached the goal).
"""

from __future__ import annotations

import json
import math
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path, PurePath
from typing import Any

import numpy as np
from scipy.stats import binomtest, wilcoxon

from quadnav.batch.summary import group_values, rate
from quadnav.batch.table import AXES as XYZ
from quadnav.errors import QuadnavError
from quadnav.files import atomic_output, csv_text

#: Significance level of every comparison, after Holm's correction.
ALPHA = 0.05
#: The axes a batch may compare, each by the columns of its value. ``method`` and
#: ``reference`` are one axis (what makes the reference: a method, or a class of your own).
AXES: dict[str, tuple[str, ...]] = {
    "controller": ("controller",), "planner": ("planner",),
    "method": ("method", "reference"), "reference": ("method", "reference"),
    "wind": ("wind_x", "wind_y", "wind_z", "wind_model"), "gains": ("gains",),
    "speed": ("speed",), "gusts": ("gusts",), "spread": ("spread",),
}
#: The axes looked at, in order, when none is asked for.
CONTENDER_AXES = ("controller", "planner", "method", "reference", "wind", "gains")
COMPARE_CSV, COMPARE_JSON = "compare.csv", "compare.json"


@dataclass(frozen=True)
class Metric:
    """A measure of each mission compared between contenders.

    Attributes:
        name: its key in compare.json and compare.csv.
        title: its words in the tables and figure.
        unit: the unit it is shown in.
        scale: from the table's unit to the one shown.
        columns: the row's columns summed to it (None when the first is None).
        lower_is_better: whether less is better (else more).
    """

    name: str
    title: str
    unit: str
    scale: float
    columns: tuple[str, ...]
    lower_is_better: bool = True

    def value(self, row: dict[str, Any]) -> float | None:
        """The metric of ``row`` in the unit shown, or None."""
        values = [row[name] for name in self.columns]
        if values[0] is None:
            return None
        total = self.scale * sum(v for v in values if v is not None)
        return total if math.isfinite(total) else None


#: The metrics compared besides success.
METRICS = (
    Metric("time_to_goal", "time to goal", "s", 1.0, ("time_to_goal_s",)),
    Metric("tracking_error", "RMS tracking error", "cm", 100.0, ("rms_tracking_error_m",)),
    Metric("margin_kept", "margin kept", "m", 1.0, ("flight_margin_m",), lower_is_better=False),
    Metric("energy", "rotor energy", "J", 1.0, ("rotor_energy_j",)),
    Metric("compute_time", "compute time", "s", 1.0,
           ("planning_time_s", "trajectory_time_s", "sim_wall_time_s")),
)
METRIC_NOTES = ("time to goal: when the flight came within the goal tolerance to stay, so "
                "over the missions that reached the goal; margin kept: the least margin the "
                "flight kept off the legs; compute time: planning, trajectory and simulation "
                "wall time (machine-dependent)")


def untimed(rows: Sequence[dict[str, Any]]) -> int:
    """How many of ``rows`` reached the goal but have no time to goal: rows of a table
    written before flights measured it (:data:`~quadnav.batch.table.ARRIVAL_COLUMNS`), as
    a flight that ends within the goal tolerance always has one."""
    return sum(bool(row["reached_goal"]) and row["time_to_goal_s"] is None for row in rows)


def short_spec(text: str) -> str:
    """A plug-in's spec or a file's path as shown: a file by its name
    (``/a/b/my.py:Ctl(k=1)`` -> ``my.py:Ctl(k=1)``), anything else as it is."""
    where, colon, rest = text.partition(":")
    if colon and where.endswith(".py"):
        return f"{PurePath(where).name}:{rest}"
    if where.endswith(".toml"):
        return PurePath(text).name
    return text


def _value_label(axis: str, row: dict[str, Any], short: bool = True) -> str:
    """The value of ``axis`` in ``row`` as shown: a plug-in file or gains file by its name
    (``short``) or in full."""
    shown = short_spec if short else str
    if axis in ("method", "reference"):
        return shown(row["reference"]) if row["reference"] else row["method"]
    if axis == "wind":
        if row["wind_model"]:
            return shown(row["wind_model"])
        return "wind (" + ", ".join(f"{row[f'wind_{a}']:g}" for a in XYZ) + ") N"
    if axis == "speed":
        return "max speed" if row["speed"] is None else f"{row['speed']:g} m/s"
    if axis == "gusts":
        return f"gusts {row['gusts']:g} N"
    if axis == "spread":
        return f"spread {row['spread']}"
    return shown(str(row[axis]))


def varying_axes(rows: Sequence[dict[str, Any]], axes: Sequence[str] = CONTENDER_AXES
                 ) -> list[str]:
    """The ``axes`` whose value differs between ``rows``, each set of columns once
    (``reference`` rather than ``method`` when a trajectory class is among them)."""
    found: list[str] = []
    for axis in axes:
        columns = AXES[axis]
        if any(AXES[other] == columns for other in found):
            continue
        if len({tuple(row[c] for c in columns) for row in rows}) > 1:
            if columns == AXES["reference"]:
                axis = "reference" if any(row["reference"] for row in rows) else "method"
            found.append(axis)
    return found


def contender_of(row: dict[str, Any], by: Sequence[str], short: bool = True) -> str:
    """The contender flying ``row``: its values of the axes ``by``, joined (files by their
    names when ``short``)."""
    return ", ".join(dict.fromkeys(_value_label(axis, row, short) for axis in by))


def contender_rows(rows: Sequence[dict[str, Any]], by: Sequence[str]
                   ) -> dict[str, list[dict[str, Any]]]:
    """``rows`` by the contender flying each, in their order, each named by
    :func:`contender_of`: files by their names, or by their whole paths when two
    contenders' files have the same name."""
    found: dict[tuple, list[dict[str, Any]]] = {}
    for row in rows:
        found.setdefault(tuple(row[c] for axis in by for c in AXES[axis]), []).append(row)
    names = [contender_of(group[0], by) for group in found.values()]
    if len(set(names)) < len(names):
        names = [contender_of(group[0], by, short=False) for group in found.values()]
    return dict(zip(names, found.values(), strict=True))


def _pair_key(row: dict[str, Any], by: Sequence[str]) -> str:
    """What a mission shares with its pair: every grid value but those of ``by``, and the
    seeds (the simulation's empty in a table written before it had its own)."""
    skip = {column for axis in by for column in AXES[axis]}
    values = {k: v for k, v in group_values(row).items() if k not in skip}
    return json.dumps([values, row["seed"], row["sim_seed"]], sort_keys=True)


#: What :func:`_spread` gives of a metric's values.
SPREAD_PARTS = ("n", "median", "q1", "q3")


def _spread(values: list[float]) -> dict[str, Any]:
    """``n``, ``median`` and the quartiles ``q1``, ``q3`` of ``values`` (None when empty)."""
    if not values:
        return {"n": 0, "median": None, "q1": None, "q3": None}
    q1, median, q3 = (float(v) for v in np.percentile(values, [25, 50, 75]))
    return {"n": len(values), "median": median, "q1": q1, "q3": q3}


def holm(p_values: Sequence[float]) -> list[float]:
    """Holm's step-down adjustment of ``p_values``: the k-th smallest of m is multiplied
    by m - k + 1 (k from 1), made non-decreasing in that order and capped at 1."""
    m = len(p_values)
    adjusted = [0.0] * m
    running = 0.0
    for k, i in enumerate(sorted(range(m), key=lambda i: p_values[i])):
        running = max(running, min(1.0, (m - k) * p_values[i]))
        adjusted[i] = running
    return adjusted


def mcnemar(a: Sequence[bool], b: Sequence[bool]) -> dict[str, Any]:
    """McNemar's exact test of paired successes ``a``, ``b``: ``a_only`` (pairs where only a
    succeeded), ``b_only``, and the two-sided binomial p-value of ``a_only`` of the
    discordant pairs at one half (1 with none)."""
    a_only = sum(x and not y for x, y in zip(a, b, strict=True))
    b_only = sum(y and not x for x, y in zip(a, b, strict=True))
    discordant = a_only + b_only
    p = binomtest(a_only, discordant, 0.5).pvalue if discordant else 1.0
    return {"a_only": a_only, "b_only": b_only, "p": float(p)}


def signed_rank(a: Sequence[float], b: Sequence[float]) -> float:
    """Wilcoxon's signed-rank p-value (two-sided) of the paired values ``a``, ``b``; pairs
    that are equal are dropped, and with none left the p-value is 1."""
    differences = np.asarray(a, dtype=float) - np.asarray(b, dtype=float)
    if not np.any(differences != 0.0):
        return 1.0
    with warnings.catch_warnings():  # scipy says when ties make it use the normal approximation
        warnings.simplefilter("ignore", UserWarning)
        return float(wilcoxon(differences, zero_method="wilcox").pvalue)


def _pairs(by_key: dict[str, dict[str, Any]], other: dict[str, dict[str, Any]],
           value: Callable[[dict[str, Any]], Any]) -> tuple[list, list]:
    """The paired values of two contenders' rows (by pair key) where both have one."""
    a, b = [], []
    for key in sorted(by_key.keys() & other.keys()):
        x, y = value(by_key[key]), value(other[key])
        if x is not None and y is not None:
            a.append(x)
            b.append(y)
    return a, b


def compare(rows: Sequence[dict[str, Any]], by: Sequence[str]) -> dict[str, Any]:
    """The leaderboard of ``rows`` by the axes ``by`` (at least two contenders): the
    contenders, best first (by success rate, then the low end of its interval, then name),
    and every comparison of two of them (see the module's docstring)."""
    grouped = contender_rows(rows, by)
    members = {name: {_pair_key(row, by): row for row in group}
               for name, group in grouped.items()}
    contenders = []
    for name, group in grouped.items():
        values = {column: group[0][column] for axis in by for column in AXES[axis]}
        contenders.append({"contender": name, "values": values, **rate(group)} | {
            metric.name: _spread([v for r in group if (v := metric.value(r)) is not None])
            for metric in METRICS})
    contenders.sort(key=lambda c: (-c["success_rate"], -c["ci_low"], c["contender"]))
    for rank, entry in enumerate(contenders, start=1):
        entry["rank"] = rank
    comparisons = []
    names = [c["contender"] for c in contenders]
    for i, first in enumerate(names):
        for second in names[i + 1:]:
            a, b = members[first], members[second]
            wins = mcnemar(*_pairs(a, b, lambda r: bool(r["success"])))
            comparisons.append({"a": first, "b": second, "metric": "success",
                                "pairs": len(a.keys() & b.keys()), **wins})
            for metric in METRICS:
                x, y = _pairs(a, b, metric.value)
                comparisons.append({
                    "a": first, "b": second, "metric": metric.name, "pairs": len(x),
                    "median_difference": float(np.median(np.subtract(x, y))) if x else None,
                    "p": signed_rank(x, y)})
    tested = [c for c in comparisons if c["pairs"]]
    for comparison in comparisons:
        comparison["p_holm"] = 1.0
    for comparison, adjusted in zip(tested, holm([c["p"] for c in tested]), strict=True):
        comparison["p_holm"] = adjusted
    for comparison in comparisons:
        comparison["significant"] = comparison["p_holm"] < ALPHA
        comparison["better"] = _better(comparison) if comparison["significant"] else None
    return {"by": list(by), "alpha": ALPHA, "correction": "holm", "missions": len(rows),
            "untimed": untimed(rows), "contenders": contenders, "comparisons": comparisons}


def _better(comparison: dict[str, Any]) -> str | None:
    """Which contender of a significant ``comparison`` did better."""
    if comparison["metric"] == "success":
        ahead = comparison["a_only"] - comparison["b_only"]
    else:
        metric = next(m for m in METRICS if m.name == comparison["metric"])
        difference = comparison["median_difference"] or 0.0
        ahead = -difference if metric.lower_is_better else difference
    if ahead == 0:
        return None
    return comparison["a"] if ahead > 0 else comparison["b"]


def choose_axes(rows: Sequence[dict[str, Any]], asked: Sequence[str] | None,
                folder: Path) -> list[str]:
    """The axes to compare by: those ``asked`` (each must vary), else every contender axis
    that varies; QuadnavError when there are no two contenders."""
    varying = varying_axes(rows, tuple(AXES))
    if asked:
        for axis in asked:
            if not varying_axes(rows, (axis,)):
                shown = ", ".join(sorted({_value_label(axis, r) for r in rows}))
                raise QuadnavError(
                    f"--by {axis}: every mission of {folder} flies {shown}; expected an axis "
                    "that varies" + (f": {', '.join(varying)}" if varying else ""))
        return list(asked)
    chosen = varying_axes(rows)
    if not chosen:
        raise QuadnavError(
            f"{folder}: the batch has a single contender (its {', '.join(CONTENDER_AXES)} "
            "do not vary); expected a batch over two or more of them"
            + (f", or --by one of {', '.join(varying)}" if varying else ""))
    return chosen


def write_tables(result: dict[str, Any], folder: Path) -> list[str]:
    """Write ``folder``/compare.json (all of ``result``) and compare.csv (the leaderboard),
    each atomically; returns the names written."""
    with atomic_output(folder / COMPARE_JSON) as tmp:
        tmp.write_text(json.dumps(result, indent=2, allow_nan=False) + "\n", encoding="utf-8")
    header = ["rank", "contender", "n", "successes", "success_rate", "ci_low", "ci_high",
              *(f"{m.name}_{part}" for m in METRICS for part in SPREAD_PARTS)]
    rows = ([entry["rank"], entry["contender"], entry["n"], entry["successes"],
             entry["success_rate"], entry["ci_low"], entry["ci_high"],
             *(entry[m.name][part] for m in METRICS for part in SPREAD_PARTS)]
            for entry in result["contenders"])
    with atomic_output(folder / COMPARE_CSV) as tmp:
        tmp.write_text(csv_text(header, rows), encoding="utf-8")
    return [COMPARE_CSV, COMPARE_JSON]

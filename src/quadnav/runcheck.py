"""A run folder read back is untrusted input: its JSON files and tables are checked for what
``report``, ``view``, ``animate`` and ``blender`` rely on, each fault one
:class:`~quadnav.errors.QuadnavError` naming the file (and line) and what was expected.

A folder quadnav wrote passes every check: its JSON holds no NaN (non-finite numbers are
written as null), its tables have their header, finite numbers and times that never go back.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from quadnav.errors import QuadnavError
from quadnav.limits import is_number
from quadnav.sim.flight import Ending

#: Key endings of metrics.json that hold a number (or null, or a list of numbers): metres,
#: seconds, m/s, joules, percent, factors.
NUMBER_SUFFIXES = ("_m", "_s", "_m_s", "_j", "_percent", "_factor", "_saturation")
#: Keys of metrics.json that hold true or false.
FLAGS = ("success", "collision", "reached_goal", "path_found")
#: Keys of metrics.json that hold text.
TEXTS = ("map", "reference", "ending", "planner", "vehicle", "source")


def read_json_object(path: Path) -> dict:
    """The JSON object in the file at ``path``: UTF-8 text, standard JSON (no NaN or
    Infinity, which JSON does not have), an object at the top level."""
    try:
        text = path.read_bytes().decode("utf-8")
    except OSError as error:
        raise QuadnavError(f"{path}: cannot read: {error.strerror}") from None
    except UnicodeDecodeError as error:
        raise QuadnavError(f"{path}: not UTF-8 text (bad byte at offset {error.start})"
                           ) from None
    try:
        value = json.loads(text, parse_constant=_refuse_constant)
    except json.JSONDecodeError as error:
        raise QuadnavError(f"{path}:{error.lineno}: not valid JSON: {error.msg}") from None
    except ValueError as error:
        raise QuadnavError(f"{path}: not valid JSON: {error}") from None
    if not isinstance(value, dict):
        raise QuadnavError(f"{path}: expected a JSON object at the top level, got "
                           f"{_kind(value)}")
    return value


def _refuse_constant(name: str) -> Any:
    raise ValueError(f"{name} is not a number JSON has: expected finite numbers or null")


def _kind(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    return {dict: "an object", list: "a list", str: "a string", type(None): "null"}.get(
        type(value), "a number")


def _numeric(value: Any) -> bool:
    """A number, null, or a list of numbers (a per-axis margin)."""
    return (value is None or is_number(value)
            or (isinstance(value, list) and all(map(is_number, value))))


def check_metrics(metrics: dict, path: Path, flown: bool, track: bool) -> None:
    """QuadnavError naming ``path`` (metrics.json) and the key for the first value that is
    not what a run's pictures and report read: ``flown`` (the folder has a flight) and
    ``track`` (``quadnav track`` wrote it) decide which keys must be there."""
    def fail(key: str, expected: str) -> QuadnavError:
        shown = "missing" if key not in metrics else f"got {json.dumps(metrics[key])[:60]}"
        return QuadnavError(f"{path}: {key}: expected {expected}, {shown}")

    def need(key: str, is_valid: Callable[[Any], bool], expected: str) -> None:
        if key not in metrics or not is_valid(metrics[key]):
            raise fail(key, expected)

    for key, value in metrics.items():
        if key in FLAGS and not isinstance(value, bool):
            raise fail(key, "true or false")
        if key in TEXTS and not isinstance(value, str):
            raise fail(key, "a string")
        if key.endswith(NUMBER_SUFFIXES) and not _numeric(value):
            raise fail(key, "a number or null")
    need("success", lambda v: isinstance(v, bool), "true or false")
    need("reference" if track else "map", lambda v: isinstance(v, str), "a string")
    if not flown:
        return
    need("ending", lambda v: isinstance(v, str), "a string")
    need("rms_tracking_error_m", is_number, "a number")
    if not track:
        need("speed_m_s", is_number, "a number")
    if metrics.get("source") == "tello":
        need("margin_m", is_number, "a number")
    _check_outcome(metrics, need)


def _check_outcome(metrics: dict, need: Callable[[str, Callable[[Any], bool], str], None
                                                  ]) -> None:
    """The keys that say how the flight ended (:func:`quadnav.runs.run_outcome`) and, for a
    step response, what the step was."""
    if metrics["success"] and metrics.get("margin_shortfall_m"):
        need("flight_margin_m", is_number, "a number")
    if not metrics["success"] and metrics["ending"] == Ending.COMPLETED.value:
        if metrics.get("body_outside_m"):
            need("body_outside_since_s", is_number, "a number")
        else:
            need("final_error_m", is_number, "a number")
    if not metrics["success"] and metrics["ending"] != Ending.COMPLETED.value:
        need("contact_time_s", is_number, "a number")
    if "overshoot_percent" in metrics:
        need("step_axis", lambda v: v in ("x", "y", "z"), "x, y or z")
        need("goal", lambda v: isinstance(v, list) and len(v) == 3
             and all(map(is_number, v)), "a list of 3 numbers")
        for key in ("step_size_m", "step_time_s", "steady_state_error_m", "overshoot_percent"):
            need(key, is_number, "a number")


def check_rows(rows: np.ndarray, path: Path, least: int = 0, times: bool = False,
               unknown: tuple[int, ...] = ()) -> None:
    """QuadnavError naming ``path`` for a table (rows under a header line) with fewer than
    ``least`` rows or a number that is not finite (but in the ``unknown`` columns, which
    may be NaN: a real drone's motor commands); with ``times``, its first column (time, s)
    must never go back."""
    if len(rows) < least:
        raise QuadnavError(f"{path}: {len(rows)} rows: expected at least {least}")
    known = np.delete(rows, list(unknown), axis=1)
    bad = np.flatnonzero(~np.isfinite(known).all(axis=1))
    if len(bad):
        raise QuadnavError(f"{path}:{bad[0] + 2}: expected finite numbers, got "
                           f"{known[bad[0]][~np.isfinite(known[bad[0]])][0]}")
    if times and len(rows) > 1:
        back = np.flatnonzero(np.diff(rows[:, 0]) < 0)
        if len(back):
            raise QuadnavError(f"{path}:{back[0] + 3}: the time goes back (from "
                               f"{rows[back[0], 0]:g} to {rows[back[0] + 1, 0]:g} s): "
                               "expected times that never decrease")


def check_parents(parents: np.ndarray, path: Path) -> np.ndarray:
    """The tree's parent column as integers: each -1 (a root) or a row of the tree (a
    rewired vertex's parent may come after it); QuadnavError naming ``path`` and the line
    of the first that is not."""
    bad = np.flatnonzero((parents != np.round(parents)) | (parents < -1)
                         | (parents >= len(parents)))
    if len(bad):
        raise QuadnavError(f"{path}:{bad[0] + 2}: parent {parents[bad[0]]:g}: expected -1 "
                           f"(a root) or a row of the tree (0 to {len(parents) - 1})")
    return parents.astype(np.int64)

"""The results table of a batch: its fixed schema, the row of a mission, the journal that
keeps every finished row, and the Parquet and CSV files.

One row per mission: its key, its grid values, the factors of its flown vehicle, where
its start and goal came from, every key of :meth:`~quadnav.mission.Mission.metrics`
(the points ``start``, ``goal`` and ``goal_asked`` as ``start_x`` ... ``goal_asked_z``),
what ended the search, the key of the plan it flew (``plan_key``, shared by the missions
that flew one plan: :mod:`~quadnav.batch.stages`), and
``error``: why a mission was refused (None when it flew or found no path). The schema
(:data:`COLUMNS`) is explicit, so the Parquet and CSV files have the same columns and types
whatever rows failed.

The journal is ``DIR/results.csv`` itself: each finished row is appended and flushed at
once, so a run stopped by any means, SIGKILL included, keeps every finished row (a last
line cut short by a kill is dropped when the journal is read back). At the end (or on a
stop) ``results.csv`` is rewritten whole in the grid's order, a line at a time, and
``results.parquet`` written in row groups of :data:`ROW_GROUP_ROWS` rows, a group at a
time, both atomically.
"""

from __future__ import annotations

import csv
import io
import math
import os
import sys
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any

import numpy as np

from quadnav.errors import QuadnavError
from quadnav.files import atomic_output, csv_text
from quadnav.limits import MAX_SPEED
from quadnav.profiling import staged

if TYPE_CHECKING:
    from quadnav.batch.grid import MissionSpec
    from quadnav.mission import Mission

STR, FLOAT, INT, BOOL = "string", "float64", "int64", "bool"
AXES = ("x", "y", "z")
#: The points of ``metrics.json``, each three columns ``NAME_x`` ... ``NAME_z``.
POINTS = ("start", "goal", "goal_asked")

#: The grid values of a mission and its flown vehicle's factors.
GRID_COLUMNS: tuple[tuple[str, str], ...] = (
    ("mission_key", STR), ("map", STR), ("seed", INT), ("sim_seed", INT), ("speed", FLOAT),
    ("wind_x", FLOAT), ("wind_y", FLOAT), ("wind_z", FLOAT), ("wind_model", STR),
    ("gusts", FLOAT),
    ("spread", STR), ("spread_mass", FLOAT), ("spread_thrust", FLOAT), ("spread_drag", FLOAT),
    ("mass_factor", FLOAT), ("thrust_factor", FLOAT), ("drag_factor", FLOAT),
    ("planner", STR), ("gains", STR), ("controller", STR), ("method", STR), ("reference", STR),
    ("start_goal_drawn", BOOL),
)
#: The columns of the grid values added when controllers, methods, references and wind
#: classes became values of the grid: a table written before has none of them.
ADDED_COLUMNS = ("wind_model", "controller", "method", "reference")
#: The columns added when the simulation got seeds of its own and missions shared plans:
#: a table written before has none of them.
PLAN_COLUMNS = ("sim_seed", "plan_key")
#: The columns added when flights measured when they reached the goal: a table written
#: before has none of them, and its rows keep none (empty) when read.
ARRIVAL_COLUMNS = ("time_to_goal_s",)
#: The keys of ``metrics.json`` besides those of the grid (map, seed, planner).
METRIC_COLUMNS: tuple[tuple[str, str], ...] = (
    ("success", BOOL), *((f"{point}_{a}", FLOAT) for point in POINTS for a in AXES),
    ("margin_m", FLOAT), ("start_leg_m", FLOAT),
    ("goal_leg_m", FLOAT), ("vehicle", STR), ("speed_m_s", FLOAT), ("path_found", BOOL),
    ("path_length_m", FLOAT), ("path_vertices", INT), ("planning_time_s", FLOAT),
    ("trajectory_time_s", FLOAT), ("trajectory_duration_s", FLOAT),
    ("trajectory_margin_m", FLOAT), ("trajectory_leg_margin_m", FLOAT),
    ("flight_margin_m", FLOAT), ("flight_leg_margin_m", FLOAT), ("margin_shortfall_m", FLOAT),
    ("flight_margin_time_s", FLOAT), ("collision", BOOL),
    ("reached_goal", BOOL), ("ending", STR), ("contact_time_s", FLOAT), ("contact_block", INT),
    ("floor_touch_speed_m_s", FLOAT),
    ("body_outside_m", FLOAT), ("body_outside_time_s", FLOAT), ("body_outside_since_s", FLOAT),
    ("final_error_m", FLOAT), ("goal_tolerance_m", FLOAT), ("time_to_goal_s", FLOAT),
    ("flight_time_s", FLOAT),
    ("rms_tracking_error_m", FLOAT), ("max_tracking_error_m", FLOAT),
    ("max_velocity_error_m_s", FLOAT), ("min_clearance_m", FLOAT), ("mixer_saturation", FLOAT),
    ("rotor_energy_j", FLOAT),
    ("sim_load_time_s", FLOAT), ("sim_wall_time_s", FLOAT), ("real_time_factor", FLOAT),
)
#: Every column, in order, with its type.
COLUMNS = (*GRID_COLUMNS, *METRIC_COLUMNS, ("search_stopped_by", STR), ("plan_key", STR),
           ("error", STR))
NAMES = tuple(name for name, _ in COLUMNS)
TYPES = dict(COLUMNS)
#: The columns of a table written before :data:`ARRIVAL_COLUMNS` were added.
UNTIMED_NAMES = tuple(name for name in NAMES if name not in ARRIVAL_COLUMNS)
#: The columns of a table written before :data:`PLAN_COLUMNS` were added.
PREVIOUS_NAMES = tuple(name for name in UNTIMED_NAMES if name not in PLAN_COLUMNS)
#: The columns of a table written before :data:`ADDED_COLUMNS` were added.
EARLIER_NAMES = tuple(name for name in PREVIOUS_NAMES if name not in ADDED_COLUMNS)
#: Columns of wall time, which differ between runs of the same mission.
WALL_TIME_COLUMNS = ("planning_time_s", "trajectory_time_s", "sim_load_time_s",
                     "sim_wall_time_s", "real_time_factor")
RESULTS_CSV = "results.csv"
RESULTS_PARQUET = "results.parquet"


@staged("row")
def mission_row(mission: MissionSpec, factors: tuple[float, float, float], drawn: bool,
                flown: Mission | None, error: str | None = None,
                start: np.ndarray | None = None, goal: np.ndarray | None = None,
                margin: float | None = None, plan_key: str | None = None) -> dict[str, Any]:
    """The row of ``mission``: its grid values, the spread ``factors`` (mass, thrust,
    drag) and whether its start and goal were ``drawn``; then the metrics of the mission
    ``flown`` and the key of its plan, or for a refused mission (``flown`` None) the
    ``error`` and what is known of its query (``start``, ``goal`` (3,) m or None,
    ``margin`` m)."""
    row: dict[str, Any] = dict.fromkeys(NAMES) | mission_columns(mission)
    row["start_goal_drawn"] = drawn
    row["plan_key"] = plan_key
    row |= dict(zip(("mass_factor", "thrust_factor", "drag_factor"), factors, strict=True))
    if flown is None:
        row |= {"success": False, "path_found": False, "collision": False,
                "reached_goal": False, "margin_m": margin,
                "error": None if error is None else one_line(error)}
        row |= _point_columns("start", start) | _point_columns("goal", goal)
        return row
    metrics = flown.metrics()
    unknown = set(metrics) - set(NAMES) - set(POINTS)
    if unknown:
        raise RuntimeError(f"metrics missing from the batch table schema: {sorted(unknown)}")
    row |= {key: value for key, value in metrics.items()
            if key not in (*POINTS, "map", "seed", "planner")}
    for name in POINTS:
        row |= _point_columns(name, metrics[name])
    return row


def compact_row(row: dict[str, Any]) -> dict[str, Any]:
    """``row`` keyed by the names of :data:`NAMES` themselves, its texts interned: a row
    unpickled from a worker has a copy of its own of every column name and text, about
    5 of its 7 KB, which a batch that keeps every row would keep for each."""
    return {name: sys.intern(value) if isinstance(value, str) else value
            for name, value in zip(NAMES, map(row.__getitem__, NAMES), strict=True)}


def mission_columns(mission: MissionSpec) -> dict[str, Any]:
    """The columns of ``mission``'s grid values: its key, map, seed and the simulation's
    (:attr:`~quadnav.batch.grid.MissionSpec.flight_seed`), speed (None: max),
    wind (a force's ``wind_x`` ... ``wind_z``, or 0 and its class's spec as
    ``wind_model``), gusts, spread, planner, gains, controller, and method or reference."""
    spread, wind = mission.spread, mission.wind
    model = wind if isinstance(wind, str) else None
    force = (0.0, 0.0, 0.0) if isinstance(wind, str) else wind
    return {
        "mission_key": mission.key, "map": mission.map.map, "seed": mission.seed,
        "sim_seed": mission.flight_seed,
        "speed": None if mission.speed == MAX_SPEED else mission.speed,  # empty: max
        "wind_model": model, "gusts": mission.gusts, "spread": spread.label,
        "spread_mass": spread.mass, "spread_thrust": spread.thrust,
        "spread_drag": spread.drag, "planner": mission.planner, "gains": mission.gains,
        "controller": mission.controller, "method": mission.method,
        "reference": mission.reference,
    } | {f"wind_{a}": w for a, w in zip(AXES, force, strict=True)}


def _point_columns(name: str, point: Sequence[float] | np.ndarray | None) -> dict[str, Any]:
    values = [None] * 3 if point is None else [float(v) for v in point]
    return {f"{name}_{a}": v for a, v in zip(AXES, values, strict=True)}


# ------------------------------------------------------------------------------ CSV text
def _text(value: Any) -> str:
    """A value as CSV text: empty for None, ``true``/``false``, floats exactly (repr)."""
    if value is None:
        return ""
    if isinstance(value, bool | np.bool_):
        return "true" if value else "false"
    if isinstance(value, float | np.floating):
        return repr(float(value))
    return one_line(str(value))


def one_line(text: str) -> str:
    """``text`` with line breaks turned into spaces: a row is one line of the journal."""
    return text.replace("\r", " ").replace("\n", " ")


#: The Python type of each column type.
PYTHON_TYPES = {STR: str, FLOAT: float, INT: int, BOOL: bool}


def _parse(text: str, kind: str) -> Any:
    """A value of type ``kind`` from its CSV text (:func:`_text`)."""
    if text == "":
        return None
    if kind == BOOL and text not in ("true", "false"):
        raise ValueError(f"expected true or false, got {text!r}")
    return text == "true" if kind == BOOL else PYTHON_TYPES[kind](text)


def csv_line(row: dict[str, Any]) -> str:
    """One row as a line of CSV (with its newline)."""
    return csv_text(None, [[_text(row[name]) for name in NAMES]])


HEADER = ",".join(NAMES) + "\n"
#: The columns of a table written before today's, most recent first.
OLDER_NAMES = (UNTIMED_NAMES, PREVIOUS_NAMES, EARLIER_NAMES)


def read_rows(path: Path, missions: Sequence[MissionSpec] = ()) -> list[dict[str, Any]]:
    """The rows of a results.csv (or journal); a last line without its newline (cut short
    by a kill) is dropped. A table written before :data:`ARRIVAL_COLUMNS` (or also
    :data:`PLAN_COLUMNS`, or also :data:`ADDED_COLUMNS`) were added is read too, each row
    completed from its mission among ``missions`` (found by its key, or its
    :attr:`~quadnav.batch.grid.MissionSpec.earlier_key` in a table without
    :data:`ADDED_COLUMNS`; the row takes the mission's key; ``plan_key`` and
    ``time_to_goal_s`` stay empty).
    QuadnavError naming the file and line if it is not a table.
    """
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as error:
        raise QuadnavError(f"{path}: cannot read: {error.strerror}") from None
    names = next((names for names in (NAMES, *OLDER_NAMES)
                  if text.startswith(",".join(names) + "\n")), None)
    if names is None:
        raise QuadnavError(f"{path}:1: expected the header of a quadnav batch table "
                           f"({len(NAMES)} columns, from {NAMES[0]} to {NAMES[-1]})")
    body = text[len(",".join(names)) + 1:]
    body = body[:body.rfind("\n") + 1]
    rows = []
    for number, fields in enumerate(csv.reader(io.StringIO(body)), start=2):
        try:
            if len(fields) != len(names):
                raise ValueError(f"expected {len(names)} fields, got {len(fields)}")
            rows.append(dict.fromkeys(NAMES) | {
                name: _parse(field, TYPES[name])
                for name, field in zip(names, fields, strict=True)})
        except ValueError as error:
            raise QuadnavError(f"{path}:{number}: {error}") from None
    if names != NAMES:
        earlier = names == EARLIER_NAMES
        by_key = {mission.earlier_key if earlier else mission.key: mission
                  for mission in missions}
        missing = {"mission_key", *(name for name in NAMES if name not in names)}
        rows = [row | {name: value for name, value in mission_columns(mission).items()
                       if name in missing}
                if (mission := by_key.get(row["mission_key"])) is not None else row
                for row in rows]
    return rows


class Journal:
    """``results.csv`` open for appending: :meth:`append` writes and flushes a row."""

    def __init__(self, path: Path) -> None:
        self.path = path
        if not path.exists():
            with atomic_output(path) as tmp:
                tmp.write_text(HEADER, encoding="utf-8")
        else:  # drop a line cut short by a kill, so that the next row starts a line
            with path.open("r+b") as file:
                data = file.read()
                file.truncate(data.rfind(b"\n") + 1)
        self._file: IO[str] | None = path.open("a", encoding="utf-8")

    def append(self, row: dict[str, Any]) -> None:
        """Write ``row`` and flush it to the operating system."""
        assert self._file is not None
        self._file.write(csv_line(row))
        self._file.flush()

    def close(self) -> None:
        """Close the file (and sync it to disk)."""
        if self._file is not None:
            self._file.flush()
            os.fsync(self._file.fileno())
            self._file.close()
            self._file = None


def write_tables(rows: Sequence[dict[str, Any]], folder: Path,
                 group_rows: int | None = None) -> list[str]:
    """Write ``rows`` to ``folder``/results.csv and results.parquet, each atomically, the
    Parquet file in row groups of ``group_rows`` (default :data:`ROW_GROUP_ROWS`);
    returns the names written."""
    write_csv(rows, folder / RESULTS_CSV)
    write_parquet(rows, folder / RESULTS_PARQUET, group_rows or ROW_GROUP_ROWS)
    return [RESULTS_PARQUET, RESULTS_CSV]


def write_csv(rows: Iterable[dict[str, Any]], path: Path) -> None:
    """The rows as a results.csv, atomically, a line at a time."""
    with atomic_output(path) as tmp, tmp.open("w", encoding="utf-8") as file:
        file.write(HEADER)
        file.writelines(csv_line(row) for row in rows)


#: Rows of each row group of results.parquet: the file is written a group at a time, so
#: writing it holds one group's columns beside the rows, not a copy of the whole table.
ROW_GROUP_ROWS = 4096


def write_parquet(rows: Sequence[dict[str, Any]], path: Path,
                  group_rows: int = ROW_GROUP_ROWS) -> None:
    """The rows as a Parquet file with the schema :data:`COLUMNS`, atomically, in row
    groups of ``group_rows`` rows."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    schema = pa.schema([(name, pa.from_numpy_dtype(np.dtype(kind)) if kind != STR
                         else pa.string()) for name, kind in COLUMNS])
    with atomic_output(path) as tmp, pq.ParquetWriter(tmp, schema) as writer:
        for first in range(0, len(rows), group_rows):
            group = rows[first:first + group_rows]
            columns = {name: [_plain(row[name], TYPES[name]) for row in group]
                       for name in NAMES}
            writer.write_table(pa.Table.from_pydict(columns, schema=schema),
                               row_group_size=group_rows)


def _plain(value: Any, kind: str) -> Any:
    """``value`` as the plain Python type of its column (numpy scalars converted)."""
    return None if value is None else PYTHON_TYPES[kind](value)


def same_row(a: dict[str, Any], b: dict[str, Any], ignore: Sequence[str] = WALL_TIME_COLUMNS
             ) -> bool:
    """Whether two rows agree on every column but ``ignore`` (NaN equals NaN)."""
    for name in NAMES:
        if name in ignore:
            continue
        x, y = a[name], b[name]
        if isinstance(x, float) and isinstance(y, float) and math.isnan(x) and math.isnan(y):
            continue
        if x != y:
            return False
    return True

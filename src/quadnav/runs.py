"""A run folder: what ``quadnav fly`` and ``quadnav track`` write, and :func:`read_run` to
read it back. This module draws nothing: :func:`quadnav.report.run_writer.write_run` writes
a whole folder with its figures and pages.

Files (every number SI, world frame z up):

================== ============================================================
``metrics.json``   outcome and figures of merit (:meth:`Mission.metrics`,
                   :meth:`Tracking.metrics`)
``parameters.json`` every setting used (``parameters()`` of either)
``mission.toml``   the mission flown, as a mission file (fly, refly: ``quadnav fly
                   --mission`` and ``quadnav refly`` fly it again;
                   :meth:`MissionConfig.flown`)
``map.json``       the map, with the start, goal and margin flown (JSON map format);
                   for a track, the empty world it was flown in
``tree.csv``       the explored tree: ``x,y,z,parent`` per vertex (parent -1: a root;
                   fly only)
``path.csv``       the refined path, ``x,y,z`` per vertex (fly, only with a path)
``trajectory.csv`` the reference every 10 ms (only with a flight)
``flight.csv``     the flight record (only with a flight)
``truth.csv``      the true track, ``t,x,y,z`` in flight.csv's time (a Tello flight
                   whose true track was known: against the emulator)
``*.png``          figures (unless skipped; only the 3D view without a flight)
``report.html``    the run report (:mod:`quadnav.report.html_report`, unless skipped)
================== ============================================================

The figures, the viewer, the animation, the Blender scene and the report all start
from :func:`read_run`, so they work on any folder a run left, long after the run.
"""

from __future__ import annotations

import io
import json
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from quadnav.arrays import FloatArray
from quadnav.errors import QuadnavError
from quadnav.mission import Mission
from quadnav.missionconfig import MISSION_FILE, MissionConfig
from quadnav.planning.report import path_csv
from quadnav.planning.result import IntArray, tree_edges
from quadnav.runcheck import check_metrics, check_parents, check_rows, read_json_object
from quadnav.sim.export import FLIGHT_HEADER, flight_csv
from quadnav.sim.flight import Ending, Flight
from quadnav.tracking import Tracking
from quadnav.trajectory.references.contract import Reference, Samples
from quadnav.trajectory.references.export import CSV_HEADER, csv_table, trajectory_csv
from quadnav.world import World, read_map
from quadnav.world.mapfile import format_map

#: Sample interval of trajectory.csv, s.
TRAJECTORY_DT = 0.01
#: Figures a run writes, in the order the report shows them.
FIGURES = ("flight_3d.png", "flight_states.png", "tracking_error.png", "attitude_motors.png")
#: The figure of a real drone's run with a true track: the estimate's drift from it.
DRIFT_FIGURE = "drift.png"
#: The HTML report written with the figures (:mod:`.html_report`).
REPORT = "report.html"
#: The interactive page written on request (:mod:`quadnav.viz.html_viewer`).
VIEW_PAGE = "view.html"
#: Files written only when there was a flight (path.csv: by fly only; truth.csv: by a
#: Tello flight whose true track was known).
FLIGHT_FILES = ("path.csv", "trajectory.csv", "flight.csv", "truth.csv")
#: Every file a run folder can hold.
RUN_FILES = ("metrics.json", "parameters.json", MISSION_FILE, "map.json", "tree.csv", *FLIGHT_FILES,
             *FIGURES, DRIFT_FIGURE, REPORT, VIEW_PAGE)
TREE_HEADER = "x,y,z,parent"
#: The comment at the top of a run folder's mission.toml.
MISSION_COMMENT = ("The mission flown into this folder: quadnav fly --mission FILE flies it "
                   "again\n(quadnav refly DIR too), and another key or flag changes it.")
#: truth.csv: flight.csv's time, s, and the true position, m.
TRUTH_HEADER = "t,x,y,z"


@dataclass(frozen=True, eq=False)
class FlightTable:
    """flight.csv as arrays: t (N,) s, position, velocity (N, 3), attitude (N, 4)
    quaternions (w, x, y, z), commands (N, 4) in [0, 1], reference (N, 3) m."""

    t: FloatArray
    position: FloatArray
    velocity: FloatArray
    attitude: FloatArray
    commands: FloatArray
    reference: FloatArray

    def csv(self) -> str:
        """The table as flight.csv (:data:`~quadnav.sim.export.FLIGHT_HEADER`)."""
        return csv_table(np.column_stack([self.t, self.position, self.velocity, self.attitude,
                                          self.commands, self.reference]), FLIGHT_HEADER)


@dataclass(frozen=True, eq=False)
class RunContent:
    """What a run folder holds, whatever made it (:func:`run_content`).

    Attributes:
        world: the map, with the start, goal and margin flown.
        metrics: for metrics.json.
        parameters: for parameters.json.
        tree: the explored tree's vertices (N, 3) m and parent rows (N,), or None.
        path: (M, 3) the refined path, m, or None.
        reference: what was flown, or None without a flight.
        flight: the flight (simulated, or a real one's :class:`FlightTable`), or None.
        truth: (K, 4) the true track of a real one's flight (t s as the flight's, x, y,
            z m), or None when not known.
        mission: the text of mission.toml, or None when the run is not a mission's.
    """

    world: World
    metrics: dict
    parameters: dict
    tree: tuple[FloatArray, IntArray] | None
    path: FloatArray | None
    reference: Reference | None
    flight: Flight | FlightTable | None
    truth: FloatArray | None = None
    mission: str | None = None


def run_content(run: Mission | Tracking, config: MissionConfig | None = None) -> RunContent:
    """The content of the run folder of a mission (``quadnav fly``) or a tracking
    (``quadnav track``: no tree, no path); with the ``config`` the mission was built from,
    its mission.toml (:meth:`MissionConfig.flown`)."""
    if isinstance(run, Tracking):
        return RunContent(run.world, run.metrics(), run.parameters(), None, None,
                          run.reference, run.flight)
    problem, plan = run.problem, run.plan
    flown = run.flight is not None
    return RunContent(
        problem.world.replace(start=problem.start, goal=problem.goal, margin=problem.margin),
        run.metrics(), run.parameters(), (plan.tree_nodes, plan.tree_parents),
        plan.path if flown else None, run.trajectory if flown else None, run.flight,
        mission=None if config is None else config.flown(run).toml(MISSION_COMMENT))


def write_run_files(content: RunContent, folder: Path) -> list[str]:
    """Write the text files of ``content`` (every file of the run folder but the figures
    and pages) into ``folder``; returns their names."""
    texts = {
        "metrics.json": _json(content.metrics),
        "parameters.json": _json(content.parameters),
        MISSION_FILE: content.mission,
        "map.json": format_map(content.world, "map.json"),
    }
    texts = {name: text for name, text in texts.items() if text is not None}
    if content.tree is not None:
        texts["tree.csv"] = csv_table(np.column_stack(content.tree), TREE_HEADER)
    if content.path is not None:
        texts["path.csv"] = path_csv(content.path)
    if content.reference is not None and content.flight is not None:
        texts["trajectory.csv"] = trajectory_csv(content.reference, TRAJECTORY_DT)
        flight = content.flight
        texts["flight.csv"] = (flight_csv(flight) if isinstance(flight, Flight)
                               else flight.csv())
        if content.truth is not None:
            texts["truth.csv"] = csv_table(content.truth, TRUTH_HEADER)
    for name, text in texts.items():
        (folder / name).write_text(text, encoding="utf-8")
    return list(texts)


def _json(value) -> str:
    return json.dumps(_finite(value), indent=2) + "\n"


def _finite(value):
    """JSON has no infinity or NaN: such numbers become null."""
    if isinstance(value, dict):
        return {key: _finite(item) for key, item in value.items()}
    if isinstance(value, list | tuple):
        return [_finite(item) for item in value]
    if isinstance(value, float) and not np.isfinite(value):
        return None
    return value


@dataclass(frozen=True, eq=False)
class Run:
    """A run folder read back.

    Attributes:
        folder: where it was read from.
        world: the map with the start, goal and margin flown.
        metrics: metrics.json.
        parameters: parameters.json.
        tree_nodes: (N, 3) explored tree vertices, m (none for a track).
        tree_parents: (N,) parent row of each vertex, -1 for a root.
        path: (M, 3) refined path, or None without a path (and for a track).
        trajectory: the reference, or None.
        flight: the flight record, or None.
        truth: (K, 4) the true track (t s, x, y, z m; see :class:`RunContent`), or None.
    """

    folder: Path
    world: World
    metrics: dict
    parameters: dict
    tree_nodes: FloatArray
    tree_parents: np.ndarray
    path: FloatArray | None
    trajectory: Samples | None
    flight: FlightTable | None
    truth: FloatArray | None = None

    def tree_edges(self) -> FloatArray:
        """(E, 2, 3) segments from each non-root vertex to its parent."""
        return tree_edges(self.tree_nodes, self.tree_parents)

    @property
    def is_track(self) -> bool:
        """Whether ``quadnav track`` wrote the folder (a reference flown, no planning)."""
        return "reference" in self.metrics

    @property
    def is_hardware(self) -> bool:
        """Whether a real (or emulated) drone flew it (``quadnav tello fly``): its flight
        is a tracked position, with no motor commands and no timed reference."""
        return self.metrics.get("source") == "tello"

    @property
    def title(self) -> str:
        """What the run flew: the reference of a track, else the map."""
        return self.metrics["reference"] if self.is_track else self.metrics["map"]


def run_outcome(metrics: dict) -> str:
    """``success`` (saying so when the flight kept less margin than asked), or why the run
    failed (from metrics.json): no path, the flight's ending and when, the body leaving the
    map, or the goal (a track: the reference's end) missed."""
    if not metrics.get("path_found", True):
        return "no path found"
    if metrics["success"] and metrics.get("margin_shortfall_m"):
        return (f"success, but kept only {metrics['flight_margin_m']:.3f} m of the "
                f"{metrics['margin_m']:g} m margin")
    if metrics["success"]:
        return "success"
    if metrics["ending"] == Ending.COMPLETED.value and metrics.get("body_outside_m"):
        return (f"the body left the map by {100 * metrics['body_outside_m']:.1f} cm at "
                f"{metrics['body_outside_since_s']:.2f} s")
    if metrics["ending"] == Ending.COMPLETED.value:
        return f"goal missed by {metrics['final_error_m']:.2f} m"
    return f"{metrics['ending']} at {metrics['contact_time_s']:.2f} s"


#: The columns of flight.csv holding the motor commands: unknown (NaN) for a real drone.
MOTOR_COLUMNS = (11, 12, 13, 14)


def read_table(path: Path, header: str, text: str | None = None, least: int = 0,
               times: bool = False, unknown: tuple[int, ...] = ()) -> np.ndarray:
    """The numbers of the CSV file ``path`` (or of its ``text``, already read) whose first
    line must be ``header``, at least ``least`` rows of them, finite (but in the ``unknown``
    columns), with ``times`` a first column that never goes back (see
    :func:`~quadnav.runcheck.check_rows`); QuadnavError naming the file if not."""
    try:
        with io.StringIO(text) if text is not None else path.open(encoding="utf-8") as file:
            first = file.readline().strip()
            if first != header:
                raise QuadnavError(f"{path}:1: expected the header {header!r}, got {first!r}")
            with warnings.catch_warnings():  # no rows: said below, with the file's name
                warnings.filterwarnings("ignore", "loadtxt: input contained no data")
                rows = np.loadtxt(file, delimiter=",", ndmin=2)
    except OSError as error:
        raise QuadnavError(f"{path}: cannot read: {error.strerror}") from None
    except (ValueError, UnicodeDecodeError) as error:
        raise QuadnavError(f"{path}: expected rows of numbers: {error}") from None
    width = header.count(",") + 1
    if rows.size and rows.shape[1] != width:
        raise QuadnavError(f"{path}: expected {width} columns, got {rows.shape[1]}")
    rows = rows.reshape(-1, width)
    check_rows(rows, path, least, times, unknown)
    return rows


def read_run(folder: str | Path) -> Run:
    """The run folder at ``folder`` (of ``quadnav fly`` or ``quadnav track``: a folder
    without tree.csv has an empty tree, one without path.csv no path); QuadnavError naming
    the file if one is missing or bad."""
    folder = Path(folder)
    if not (folder / "metrics.json").is_file():
        raise QuadnavError(f"{folder}: not a quadnav fly or track output folder (no "
                           "metrics.json); run quadnav fly -o DIR or quadnav track REF -o DIR "
                           "first")
    flown = (folder / "flight.csv").is_file()
    metrics = read_json_object(folder / "metrics.json")
    check_metrics(metrics, folder / "metrics.json", flown, "reference" in metrics)
    parameters = read_json_object(folder / "parameters.json")
    tree = (read_table(folder / "tree.csv", TREE_HEADER) if (folder / "tree.csv").is_file()
            else np.zeros((0, 4)))
    parents = check_parents(tree[:, 3], folder / "tree.csv")
    path = (read_table(folder / "path.csv", "x,y,z", least=2)
            if (folder / "path.csv").is_file() else None)
    trajectory = flight = truth = None
    if flown:
        t = read_table(folder / "trajectory.csv", CSV_HEADER, least=1, times=True)
        trajectory = Samples(t[:, 0], t[:, 1:4], t[:, 4:7], t[:, 7:10], t[:, 10])
        f = read_table(folder / "flight.csv", FLIGHT_HEADER, least=1, times=True,
                       unknown=MOTOR_COLUMNS)
        flight = FlightTable(f[:, 0], f[:, 1:4], f[:, 4:7], f[:, 7:11], f[:, list(MOTOR_COLUMNS)],
                             f[:, 15:18])
        if (folder / "truth.csv").is_file():
            truth = read_table(folder / "truth.csv", TRUTH_HEADER, least=1, times=True)
    return Run(folder, read_map(folder / "map.json"), metrics, parameters, tree[:, 0:3],
               parents, path, trajectory, flight, truth)


def drift(flight: FlightTable, truth: FloatArray) -> FloatArray:
    """(N,) the horizontal distance, m, from the flown position at each row of ``flight``
    (a real drone's: its estimate) to the true one, ``truth`` (K, 4: t s, x, y, z m)
    interpolated at the row's time (held at its ends)."""
    true = np.column_stack([np.interp(flight.t, truth[:, 0], truth[:, axis]) for axis in (1, 2)])
    return np.linalg.norm(flight.position[:, :2] - true, axis=1)

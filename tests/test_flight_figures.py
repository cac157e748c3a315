"""Flight figures drawn from real run folders read back: what each one shows, that it
agrees with the mission that wrote the folder, and what write_run saves."""

from __future__ import annotations

import dataclasses
import gc
import struct

import numpy as np
import pytest
from figurecheck import (
    DrawCounter,
    assert_labels_apart,
    assert_legends_outside,
    assert_outlined,
)
from mpl_toolkits.mplot3d import Axes3D

from quadnav.mission import Mission, MissionSettings, fly_mission
from quadnav.planning import PlannerSettings
from quadnav.report.run_writer import write_run
from quadnav.runs import FIGURES, REPORT, Run, read_run
from quadnav.sim.flight import Ending
from quadnav.sim.simulate import simulate
from quadnav.trajectory.generate import make_trajectory
from quadnav.vehicle.quaternion import euler_angles
from quadnav.viz.flight_figures import (
    MIN_SPAN,
    actual_acceleration,
    attitude_motors_figure,
    desired_acceleration,
    desired_velocity,
    figure_makers,
    flight_3d_figure,
    flight_states_figure,
    tracking_error_figure,
)
from quadnav.viz.plan_figure import MAX_TREE_EDGES
from quadnav.viz.style import TREE_COLOR
from quadnav.world import load_world

SETTINGS = MissionSettings(planning=PlannerSettings(seed=0, max_iterations=3000, time_limit=30))
WORLD = "forest:size=12x12x4,seed=1"


@pytest.fixture(scope="module")
def mission() -> Mission:
    flown = fly_mission(load_world(WORLD), settings=SETTINGS)
    assert flown.success
    return flown


def folder_of(mission: Mission, tmp_path_factory, name: str) -> Run:
    """``mission`` written to a fresh folder (text files only) and read back."""
    folder = tmp_path_factory.mktemp(name)
    write_run(mission, folder, figures=False)
    return read_run(folder)


@pytest.fixture(scope="module")
def run(mission, tmp_path_factory) -> Run:
    return folder_of(mission, tmp_path_factory, "run")


@pytest.fixture(scope="module")
def crashed_mission(mission) -> Mission:
    """The mission with its flight replaced by a straight one along x through block 0."""
    world = mission.problem.world
    block = world.blocks[0]
    y = (block[1] + block[4]) / 2
    trajectory = make_trajectory(np.array([[block[0] - 2, y, 1.0], [block[3] + 2, y, 1.0]]))
    flight = simulate(trajectory, world=world)
    assert flight.ending is Ending.COLLISION and flight.contact_block == 0
    return dataclasses.replace(mission, trajectory=trajectory, flight=flight)


@pytest.fixture(scope="module")
def crashed(crashed_mission, tmp_path_factory) -> Run:
    return folder_of(crashed_mission, tmp_path_factory, "crashed")


@pytest.fixture(scope="module")
def pathless(tmp_path_factory) -> Run:
    """A run whose search stopped after one sample, without a path."""
    settings = MissionSettings(planning=PlannerSettings(seed=0, max_iterations=1))
    mission = fly_mission(load_world(WORLD), settings=settings)
    assert mission.flight is None
    return folder_of(mission, tmp_path_factory, "pathless")


def png_size(path) -> tuple[int, int]:
    """Width and height of a PNG file, pixels, after checking its signature."""
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and data[12:16] == b"IHDR"
    assert len(data) > 20_000  # a drawn figure, not a blank canvas
    return struct.unpack(">II", data[16:24])


def legend_texts(fig) -> list[str]:
    """The entries of the figure's one legend."""
    (legend,) = fig.legends
    return [text.get_text() for text in legend.get_texts()]


def line(ax, prefix: str):
    """The one line on ``ax`` whose label starts with ``prefix``."""
    (found,) = [ln for ln in ax.get_lines() if ln.get_label().startswith(prefix)]
    return found


def points(ax, prefix: str) -> np.ndarray:
    """(N, 3) points of the line ``prefix`` on a 3D axes, (N, 2) on a 2D one."""
    drawn = line(ax, prefix)
    return np.array(drawn.get_data_3d()).T if isinstance(ax, Axes3D) else drawn.get_xydata()


def test_write_run_draws_the_figures_from_the_folder_and_clears_stale_ones(mission, run,
                                                                           tmp_path):
    written = write_run(mission, tmp_path)
    assert written[-len(FIGURES) - 1:] == [*FIGURES, REPORT]
    assert (tmp_path / REPORT).stat().st_size > 0
    assert [name for name in written if not name.endswith((".png", ".html"))] == [
        "metrics.json", "parameters.json", "map.json", "tree.csv", "path.csv",
        "trajectory.csv", "flight.csv"]
    for name, make in figure_makers(run).items():
        fig = make(run)
        expected = tuple(round(v) for v in fig.get_size_inches() * fig.dpi)
        assert fig.dpi == 120
        assert png_size(tmp_path / name) == expected
    (tmp_path / REPORT).write_text("an earlier run's report")
    assert write_run(mission, tmp_path, figures=False) == written[:-len(FIGURES) - 1]
    assert not any((tmp_path / name).exists() for name in (*FIGURES, REPORT))


def test_write_run_draws_each_figure_once_and_spares_the_collector(mission, tmp_path,
                                                                   monkeypatch):
    """What ``quadnav fly`` spends most of its figures' time on is drawing: each figure is
    laid out without drawing it and drawn once, when it is saved (it was drawn 16 times
    for 4 figures: each layout round and saving drew it, saving twice). And the objects
    alive before the figures are drawn are kept out of the garbage collector's
    collections while they are (each full collection would walk them all again), and
    handed back to it afterwards, so nothing stays out of its reach."""
    counter = DrawCounter(monkeypatch)
    frozen: list[int] = []

    def watch(phase: str, info: dict) -> None:
        if phase == "start":
            frozen.append(gc.get_freeze_count())

    gc.callbacks.append(watch)
    try:
        write_run(mission, tmp_path)
    finally:
        gc.callbacks.remove(watch)
    assert counter.of_figures() == [1] * len(FIGURES)
    assert max(frozen) > 0
    assert gc.get_freeze_count() == 0


def test_3d_figure_shows_an_oblique_3d_view_and_a_2d_top_view(run):
    fig = flight_3d_figure(run)
    flight = run.flight
    oblique, top = fig.axes
    assert isinstance(oblique, Axes3D) and (oblique.elev, oblique.azim) == (30, -60)
    assert not isinstance(top, Axes3D) and top.get_aspect() == 1.0  # to scale, in 2D
    texts = legend_texts(fig)  # one legend, below both views
    for prefix in ("start", "goal", "tree (", "path (", "trajectory (", "flown ("):
        assert sum(t.startswith(prefix) for t in texts) == 1, (prefix, texts)
    assert oblique.get_legend() is None and top.get_legend() is None
    assert not any(t.startswith(("collision", "not to scale")) for t in texts)
    for ax, columns in ((oblique, 3), (top, 2)):
        assert np.array_equal(points(ax, "flown"), flight.position[:, :columns])
        assert np.array_equal(points(ax, "trajectory"), run.trajectory.position[:, :columns])
        assert np.array_equal(points(ax, "path"), run.path[:, :columns])
        assert line(ax, "path").get_color() == "red"
        assert_outlined(line(ax, "path"))
        assert len(ax.collections) >= 1  # the blocks
        tree = [drawn for drawn in ax.get_lines() if drawn.get_color() == TREE_COLOR]
        assert len(tree) == 1  # one line, pen lifted between edges (NaN rows)
        xs = tree[0].get_data_3d()[0] if columns == 3 else tree[0].get_xdata()
        assert np.isnan(xs).sum() == min(len(run.tree_edges()), MAX_TREE_EDGES) - 1
        assert ax.get_xlabel() == "x (m)" and ax.get_ylabel() == "y (m)"
    aspect = oblique.get_box_aspect()  # a metre is as long along every axis
    assert np.allclose(aspect / aspect[0], run.world.extent / run.world.extent[0])
    assert oblique.get_zlabel() == "z (m)"
    title = fig._suptitle.get_text()
    assert run.metrics["map"] in title and "success" in title
    assert f"RMS tracking error {100 * run.metrics['rms_tracking_error_m']:.2f} cm" in title
    assert "2 m/s" in title
    assert_legends_outside(fig)
    assert_labels_apart(fig)


def test_collision_is_marked_where_the_flight_stopped(crashed, crashed_mission):
    fig = flight_3d_figure(crashed)
    flight = crashed_mission.flight
    assert any(t.startswith("collision (block 0") for t in legend_texts(fig))
    for ax in fig.axes:
        assert line(ax, "collision").get_marker() == "X"
        marked = points(ax, "collision")  # x, y, z in 3D; x, y from above
        assert np.allclose(marked, flight.position[-1:, :marked.shape[1]], atol=1e-6)
    assert f"collision at {flight.contact_time:.2f} s" in fig._suptitle.get_text()


def test_a_run_without_a_path_shows_the_map_and_the_tree(pathless):
    assert list(figure_makers(pathless)) == [FIGURES[0]]
    fig = flight_3d_figure(pathless)
    texts = legend_texts(fig)
    assert any(t.startswith("tree (") for t in texts)
    assert not any(t.startswith(("path", "trajectory", "flown")) for t in texts)
    assert fig._suptitle.get_text().endswith("\nno path found")


@pytest.mark.parametrize("which", ["run", "crashed"])
def test_states_figure_plots_desired_and_actual_per_axis(which, request):
    run = request.getfixturevalue(which)
    original = request.getfixturevalue("mission" if which == "run" else "crashed_mission")
    flight = run.flight
    fig = flight_states_figure(run)
    assert len(fig.axes) == 9
    axes = np.array(fig.axes).reshape(3, 3)
    wanted_velocity = desired_velocity(run)
    # The velocity read back from trajectory.csv is the one the controller was given (a
    # crash ends between two 10 ms rows, where interpolating is off by jerk dt^2 / 8).
    assert np.allclose(wanted_velocity, original.flight.reference[:, 3:6], atol=1e-4)
    wanted_acceleration = desired_acceleration(run)
    assert np.allclose(wanted_acceleration, original.flight.reference[:, 6:9], atol=2e-3)
    # The flown acceleration: the velocity's finite differences, close to the reference's
    # where the flight tracks it well.
    flown_acceleration = actual_acceleration(flight)
    if which == "run":
        assert np.sqrt(np.mean((flown_acceleration - wanted_acceleration) ** 2)) < 0.5
    columns = ((flight.reference, flight.position, "m)"),
               (wanted_velocity, flight.velocity, "m/s)"),
               (wanted_acceleration, flown_acceleration, "m/s²)"))
    for column, (desired, actual, unit) in enumerate(columns):
        for axis in range(3):
            ax = axes[axis, column]
            assert len(ax.get_lines()) == 2
            assert ax.get_ylabel().endswith(unit) and "xyz"[axis] in ax.get_ylabel()
            wanted, flown = line(ax, "desired"), line(ax, "actual")
            assert wanted.get_linestyle() == "--" and flown.get_linestyle() == "-"
            assert np.array_equal(wanted.get_xdata(), flight.t)
            assert np.array_equal(wanted.get_ydata(), desired[:, axis])
            assert np.array_equal(flown.get_ydata(), actual[:, axis])
            low, high = ax.get_ylim()  # a still axis (the crash flies along x) stays flat
            assert high - low >= MIN_SPAN - 1e-12 and low <= actual[:, axis].min()
            assert high >= actual[:, axis].max()
    assert [axes[-1, k].get_xlabel() for k in range(3)] == ["time (s)"] * 3
    assert [axes[0, k].get_title() for k in range(3)] == ["position", "velocity",
                                                          "acceleration"]
    assert legend_texts(fig) == ["desired", "actual x", "actual y", "actual z"]
    assert_legends_outside(fig)
    assert_labels_apart(fig)


@pytest.mark.parametrize("which", ["run", "crashed"])
def test_attitude_figure_shows_roll_pitch_yaw_and_the_motor_commands(which, request):
    run = request.getfixturevalue(which)
    flight = run.flight
    fig = attitude_motors_figure(run)
    roll, pitch, yaw, motors = fig.axes
    angles = np.degrees(euler_angles(flight.attitude))
    for ax, column, name in ((roll, 0, "roll"), (pitch, 1, "pitch"), (yaw, 2, "yaw")):
        assert ax.get_ylabel() == f"{name} (deg)"
        drawn = line(ax, f"actual {name}")
        assert np.array_equal(drawn.get_xdata(), flight.t)
        assert np.allclose(drawn.get_ydata(), angles[:, column])
    assert np.abs(angles[:, :2]).max() > 1.0  # the flight banks
    reference = line(yaw, "yaw reference")
    assert reference.get_linestyle() == "--"
    assert np.allclose(reference.get_ydata(), np.degrees(run.trajectory.yaw[0]))  # constant
    assert motors.get_ylabel() == "motor command" and motors.get_xlabel() == "time (s)"
    for k in range(4):
        assert np.array_equal(line(motors, f"motor {k + 1}").get_ydata(), flight.commands[:, k])
    assert len({line(motors, f"motor {k + 1}").get_linestyle() for k in range(4)}) == 4
    assert legend_texts(fig) == ["actual roll", "actual pitch", "actual yaw", "yaw reference",
                                 "motor 1", "motor 2", "motor 3", "motor 4"]
    assert_legends_outside(fig)
    assert_labels_apart(fig)


@pytest.mark.parametrize("which", ["run", "crashed"])
def test_error_figure_shows_error_rms_and_max(which, request):
    run = request.getfixturevalue(which)
    original = request.getfixturevalue("mission" if which == "run" else "crashed_mission")
    flight, metrics = run.flight, run.metrics
    fig = tracking_error_figure(run)
    (ax,) = fig.axes
    error = line(ax, "tracking error")
    assert np.array_equal(error.get_xdata(), flight.t)
    # From the files, the same error as the flight in memory had (to the CSV's digits).
    assert np.allclose(error.get_ydata(), 100 * original.flight.tracking_error, atol=1e-5)
    assert np.allclose(line(ax, "RMS").get_ydata(), 100 * metrics["rms_tracking_error_m"])
    recorded = 100 * np.linalg.norm(flight.position - flight.reference, axis=1)
    peak = int(np.argmax(recorded))
    (note,) = ax.texts
    assert note.get_text() == f"max {recorded[peak]:.2f} cm at {flight.t[peak]:.2f} s"
    assert note.xy == (flight.t[peak], recorded[peak])
    assert f"max {100 * metrics['max_tracking_error_m']:.2f} cm" in ax.get_title()
    assert ax.get_ylabel() == "position error (cm)" and ax.get_xlabel() == "time (s)"
    assert [text.get_text() for text in ax.get_legend().get_texts()] == [
        "tracking error", f"RMS {100 * metrics['rms_tracking_error_m']:.2f} cm"]
    assert_legends_outside(fig)
    assert_labels_apart(fig)

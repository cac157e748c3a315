"""Flight figures drawn from real missions: what each one shows, and that it saves."""

from __future__ import annotations

import dataclasses
import struct

import numpy as np
import pytest

from quadnav.mission import Mission, MissionSettings, fly_mission
from quadnav.planning import PlannerSettings
from quadnav.sim.flight import Ending
from quadnav.sim.simulate import simulate
from quadnav.trajectory.generate import make_trajectory
from quadnav.viz.figures import save_figure
from quadnav.viz.flight_figures import (
    MIN_SPAN,
    flight_3d_figure,
    flight_states_figure,
    tracking_error_figure,
)
from quadnav.world import load_world

SETTINGS = MissionSettings(planning=PlannerSettings(seed=0, max_iterations=3000, time_limit=30))


@pytest.fixture(scope="module")
def mission() -> Mission:
    world = load_world("forest:size=12x12x4,seed=1")
    flown = fly_mission(world, settings=SETTINGS)
    assert flown.success
    return flown


@pytest.fixture(scope="module")
def crashed(mission) -> Mission:
    """The mission with its flight replaced by a straight one along x through block 0."""
    world = mission.problem.world
    block = world.blocks[0]
    y = (block[1] + block[4]) / 2
    trajectory = make_trajectory(np.array([[block[0] - 2, y, 1.0], [block[3] + 2, y, 1.0]]))
    flight = simulate(trajectory, world=world)
    assert flight.ending is Ending.COLLISION and flight.contact_block == 0
    return dataclasses.replace(mission, trajectory=trajectory, flight=flight)


def png_size(path) -> tuple[int, int]:
    """Width and height of a PNG file, pixels, after checking its signature."""
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and data[12:16] == b"IHDR"
    assert len(data) > 20_000  # a drawn figure, not a blank canvas
    return struct.unpack(">II", data[16:24])


def legend_texts(ax) -> list[str]:
    return [text.get_text() for text in ax.get_legend().get_texts()]


def line(ax, prefix: str):
    """The one line on ``ax`` whose label starts with ``prefix``."""
    (found,) = [ln for ln in ax.get_lines() if ln.get_label().startswith(prefix)]
    return found


def test_three_figures_save_as_pngs_of_their_size(mission, tmp_path):
    for name, fig in (("flight", flight_3d_figure(mission)),
                      ("states", flight_states_figure(mission.flight)),
                      ("error", tracking_error_figure(mission.flight))):
        expected = tuple(round(v) for v in fig.get_size_inches() * fig.dpi)
        assert fig.dpi == 120
        save_figure(fig, tmp_path / f"{name}.png")
        assert png_size(tmp_path / f"{name}.png") == expected


def test_3d_figure_shows_both_views_with_path_trajectory_and_flight(mission):
    fig = flight_3d_figure(mission)
    flight = mission.flight
    assert len(fig.axes) == 2 and all(ax.name == "3d" for ax in fig.axes)
    assert [(ax.elev, ax.azim) for ax in fig.axes] == [(30, -60), (90, -90)]
    texts = legend_texts(fig.axes[0])
    for prefix in ("start", "goal", "tree (", "path (", "trajectory (", "flown ("):
        assert sum(t.startswith(prefix) for t in texts) == 1, (prefix, texts)
    assert fig.axes[1].get_legend() is None
    assert not any(t.startswith("collision") for t in texts)
    samples = mission.trajectory.sample(0.02).position
    for ax in fig.axes:
        assert np.array_equal(np.array(line(ax, "flown").get_data_3d()).T, flight.position)
        assert np.array_equal(np.array(line(ax, "trajectory").get_data_3d()).T, samples)
        assert np.array_equal(np.array(line(ax, "path").get_data_3d()).T, mission.plan.path)
        assert line(ax, "path").get_color() == "red"
        assert len(ax.collections) > 3  # blocks, boundary, spheres and the tree
    title = fig._suptitle.get_text()
    assert mission.problem.world.name in title and "success" in title
    assert f"RMS tracking error {100 * flight.rms_tracking_error:.2f} cm" in title
    assert "2 m/s" in title


def test_collision_is_marked_where_the_flight_stopped(crashed, tmp_path):
    fig = flight_3d_figure(crashed)
    flight = crashed.flight
    assert any(t.startswith("collision (block 0") for t in legend_texts(fig.axes[0]))
    for ax in fig.axes:
        marker = line(ax, "collision")
        assert marker.get_marker() == "X"
        assert np.array_equal(np.array(marker.get_data_3d()).T, flight.position[-1:])
    assert f"collision at {flight.contact_time:.2f} s" in fig._suptitle.get_text()
    save_figure(fig, tmp_path / "crash.png")
    png_size(tmp_path / "crash.png")


@pytest.mark.parametrize("which", ["mission", "crashed"])
def test_states_figure_plots_desired_and_actual_per_axis(which, request):
    flight = request.getfixturevalue(which).flight
    fig = flight_states_figure(flight)
    assert len(fig.axes) == 6
    axes = np.array(fig.axes).reshape(3, 2)
    columns = ((flight.reference[:, 0:3], flight.position, "m)"),
               (flight.reference[:, 3:6], flight.velocity, "m/s)"))
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
    assert axes[-1, 0].get_xlabel() == axes[-1, 1].get_xlabel() == "time (s)"


@pytest.mark.parametrize("which", ["mission", "crashed"])
def test_error_figure_shows_error_rms_and_max(which, request):
    flight = request.getfixturevalue(which).flight
    fig = tracking_error_figure(flight)
    (ax,) = fig.axes
    error = line(ax, "tracking error")
    assert np.array_equal(error.get_xdata(), flight.t)
    assert np.allclose(error.get_ydata(), 100 * flight.tracking_error, rtol=1e-12, atol=0)
    rms = line(ax, "RMS")
    assert np.allclose(rms.get_ydata(), 100 * flight.rms_tracking_error)
    peak = int(np.argmax(flight.tracking_error))
    (note,) = ax.texts
    assert note.get_text() == (f"max {100 * flight.tracking_error[peak]:.2f} cm at "
                               f"{flight.t[peak]:.2f} s")
    assert note.xy == (flight.t[peak], 100 * flight.tracking_error[peak])
    assert ax.get_ylabel() == "position error (cm)"

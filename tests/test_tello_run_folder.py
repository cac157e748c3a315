"""A Tello flight leaves a run folder that every viewer reads: a whole emulated mission
(``go`` waypoints and ``rc`` sticks) through the bridge, then ``report``, ``view``,
``animate`` and ``blender`` on its folder, planned against flown."""

from __future__ import annotations

import contextlib
import io
import json

import numpy as np
import pytest
from tellotools import emulated_flight, needs_netns, planned_room

from quadnav.cli.main import main
from quadnav.hardware.bridge import BridgeSettings
from quadnav.hardware.run_record import planned_route, tello_run_content
from quadnav.planning.result import nearest_on_polyline
from quadnav.report.run_writer import write_run
from quadnav.runs import read_run


def quadnav(*args) -> tuple[int, str]:
    """``quadnav ARGS`` in this process: exit code and standard error (output dropped)."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main([str(arg) for arg in args])
    return code, err.getvalue()


@pytest.fixture(scope="module", params=["waypoints", "rc"])
def tello_run(request, client_ns, tmp_path_factory):
    """An emulated mission along the room, written as a run folder: (folder, the
    emulator's true track (N, 3))."""
    mode = request.param
    plan = planned_room()
    folder = tmp_path_factory.mktemp(f"tello_{mode}")
    outcome, track, drone = emulated_flight(plan, client_ns, folder, mode)
    content = tello_run_content(plan, BridgeSettings(mode=mode, time_scale=10.0), outcome,
                                track, drone.host)
    write_run(content, folder)
    return folder, drone.track()[1]


def test_nearest_on_polyline_is_the_foot_of_the_perpendicular_or_an_end():
    line = np.array([[0.0, 0, 0], [2, 0, 0], [2, 2, 0]])
    points = np.array([[1.0, 1, 0], [-1, 0, 0], [3, 1, 5], [2.5, 3, 0]])
    assert np.allclose(nearest_on_polyline(points, line),
                       [[1, 0, 0], [0, 0, 0], [2, 1, 0], [2, 2, 0]])


@needs_netns
def test_the_folder_holds_planned_and_flown_and_the_metrics_measure_the_flight(tello_run):
    folder, truth = tello_run
    run = read_run(folder)
    m = run.metrics
    plan = planned_room()
    assert run.is_hardware and m["success"] and m["ending"] == "landed"
    assert np.allclose(run.path, planned_route(plan))
    assert run.trajectory is not None and len(run.tree_nodes) > 0
    flown = run.flight.position
    assert len(flown) == m["state_packets"] > 5
    # the dead-reckoned track follows the true one within a few centimetres ...
    assert np.abs(flown[-1, :2] - truth[-1, :2]).max() < 0.15
    # ... and the metrics are measured on it: the error is the distance to the route
    error = np.linalg.norm(flown - nearest_on_polyline(flown, run.path), axis=1)
    assert m["max_tracking_error_m"] == pytest.approx(error.max(), abs=1e-5)  # CSV digits
    assert 0 < m["rms_tracking_error_m"] <= m["max_tracking_error_m"] < 0.2
    assert m["final_error_m"] < 0.15
    # the room has no blocks: the clearance is to its walls and ceiling (not the floor)
    low, high = run.world.lower, run.world.upper
    walls = np.minimum(np.minimum(flown[:, :2] - low[:2], high[:2] - flown[:, :2]).min(axis=1),
                       high[2] - flown[:, 2])
    assert m["min_clearance_m"] == pytest.approx(walls.min(), abs=1e-5)
    assert m["min_clearance_m"] > 0 and not m["collision"]
    assert np.isnan(run.flight.commands).all()  # a Tello does not report its motors
    assert sorted(p.name for p in folder.glob("*.png")) == [
        "flight_3d.png", "tello_track.png", "tracking_error.png"]


@needs_netns
def test_report_view_and_animate_accept_the_folder(tello_run, tmp_path):
    folder, _ = tello_run
    code, err = quadnav("report", folder, "-o", tmp_path / "report.html")
    assert (code, err) == (0, "")
    page = (tmp_path / "report.html").read_text()
    assert "landed" in page and "tracking error RMS" in page
    code, err = quadnav("view", folder, "-o", tmp_path / "view.html")
    assert (code, err) == (0, "")
    assert "http://" not in (tmp_path / "view.html").read_text().replace(
        "http://www.w3.org", "")
    code, err = quadnav("animate", folder, "-o", tmp_path / "flight.gif",
                             "--max-frames", "10", "--quiet")
    assert (code, err) == (0, ""), err
    assert (tmp_path / "flight.gif").stat().st_size > 0


@needs_netns
def test_blender_accepts_the_folder(tello_run, tmp_path):
    pytest.importorskip("bpy", reason="Blender's bpy is not installed")
    folder, _ = tello_run
    code, err = quadnav("blender", folder, "-o", tmp_path / "scene.blend")
    assert code == 0, err
    assert (tmp_path / "scene.blend").stat().st_size > 0


def test_a_dry_run_writes_the_plan_as_a_run_folder_without_a_flight(tmp_path):
    code, err = quadnav("tello", "fly", "forest", "--dry-run", "--quiet", "-o", tmp_path)
    assert code == 0, err
    run = read_run(tmp_path)
    assert run.flight is None and run.path is not None
    assert json.loads((tmp_path / "parameters.json").read_text())["dry_run"] is True
    code, err = quadnav("report", tmp_path, "-o", tmp_path / "again.html")
    assert (code, err) == (0, "")

"""A Tello flight leaves a run folder that every viewer reads: a whole emulated mission
(``go`` waypoints and ``rc`` sticks) through the bridge, then ``report``, ``view``,
``animate`` and ``blender`` on its folder, planned against flown, and the estimate
against the emulator's true track; ``quadnav tello fly`` prints the one landing place and
verdict that its metrics and report give."""

from __future__ import annotations

import contextlib
import html
import io
import json
import re
import subprocess

import numpy as np
import pytest
from clitools import QUADNAV, assert_user_error, run_here
from tellotools import (
    ROOM,
    ROOM_GOAL,
    ROOM_START,
    emulated_flight,
    needs_netns,
    planned_room,
)

from quadnav.cli.main import main
from quadnav.hardware.bridge.flight import BridgeSettings
from quadnav.hardware.bridge.run_record import planned_route, tello_run_content
from quadnav.hardware.emulator.netns import NetNamespace
from quadnav.hardware.emulator.server import TelloEmulator
from quadnav.planning.result import nearest_on_polyline
from quadnav.report.html_report import CAPTIONS
from quadnav.report.run_writer import write_run
from quadnav.runs import DRIFT_FIGURE, drift, read_run
from quadnav.viz.html_viewer import viewer_data
from quadnav.world.placement import format_estimate, format_point

#: One worker flies this module's shared flights (each once, not once per worker).
pytestmark = pytest.mark.xdist_group("tello-run-folder")


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
    flown, drone = emulated_flight(plan, client_ns, folder, mode)
    content = tello_run_content(plan, BridgeSettings(mode=mode, time_scale=10.0), flown,
                                drone.host)
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
    assert m["rms_tracking_error_m"] == pytest.approx(np.sqrt(np.mean(error ** 2)), abs=1e-5)
    # (0 when every packet came at a move's end, on the route: as on a loaded machine)
    assert 0 <= m["rms_tracking_error_m"] <= m["max_tracking_error_m"] < 0.2
    assert m["final_error_m"] < 0.15
    # the room has no blocks: the clearance is to its walls and ceiling (not the floor)
    low, high = run.world.lower, run.world.upper
    walls = np.minimum(np.minimum(flown[:, :2] - low[:2], high[:2] - flown[:, :2]).min(axis=1),
                       high[2] - flown[:, 2])
    assert m["min_clearance_m"] == pytest.approx(walls.min(), abs=1e-5)
    assert m["min_clearance_m"] > 0 and not m["collision"]
    assert np.isnan(run.flight.commands).all()  # a Tello does not report its motors
    assert sorted(p.name for p in folder.glob("*.png")) == [
        "drift.png", "flight_3d.png", "tello_track.png", "tracking_error.png"]


@needs_netns
def test_the_folder_records_the_true_track_and_the_estimates_drift_from_it(tello_run):
    folder, emulated = tello_run
    run = read_run(folder)
    m, truth, flight = run.metrics, run.truth, run.flight
    # truth.csv: the emulator's own samples from the flight's start on, in flight.csv's time
    assert truth is not None and truth[0, 0] >= 0 and np.all(np.diff(truth[:, 0]) > 0)
    up, emulated_up = np.argmax(truth[:, 3] > 0.05), np.argmax(emulated[:, 2] > 0.05)
    assert np.allclose(truth[up:, 1:], emulated[emulated_up:emulated_up + len(truth) - up],
                       atol=1e-6)
    # the same clock: the drone truly left the floor before a state packet said so
    assert 0 < truth[up, 0] <= flight.t[np.argmax(flight.position[:, 2] > 0.05)]
    # where it truly landed (a few mm up as the landing was answered), and the estimate's
    # drift from the truth
    assert m["true_landing_m"] == pytest.approx(truth[-1, 1:].tolist())
    assert m["true_landing_m"] == pytest.approx(emulated[-1].tolist(), abs=0.01)
    assert m["true_final_error_m"] == pytest.approx(  # truth.csv's digits: micrometres
        np.linalg.norm(emulated[-1, :2] - np.asarray(ROOM_GOAL[:2])), abs=1e-5)
    assert m["landing_drift_m"] == pytest.approx(
        np.linalg.norm(np.subtract(m["landing_m"], m["true_landing_m"])[:2]), abs=1e-9)
    drifts = drift(flight, truth)
    assert m["rms_drift_m"] == pytest.approx(np.sqrt(np.mean(drifts ** 2)), abs=1e-5)
    assert m["max_drift_m"] == pytest.approx(drifts.max(), abs=1e-5)
    # the landing the bridge reported lies within its stated uncertainty of the truth
    assert m["landing_drift_m"] < m["landing_sigma_m"]


@needs_netns
def test_report_view_and_animate_accept_the_folder(tello_run, tmp_path):
    folder, _ = tello_run
    code, err = quadnav("report", folder, "-o", tmp_path / "report.html")
    assert (code, err) == (0, "")
    page = html.unescape((tmp_path / "report.html").read_text())
    assert "landed" in page and "tracking error RMS" in page
    # the landing as tello fly printed it, the true one, and the drift figure
    m = read_run(folder).metrics
    assert (f"landed at {format_estimate(m['landing_m'], m['landing_sigma_m'])} (dead "
            f"reckoning), {m['final_error_m']:.2f} m from the goal") in page
    assert (f"truly at {format_point(m['true_landing_m'])}, {m['true_final_error_m']:.2f} m "
            f"from the goal: drift {100 * m['landing_drift_m']:.2f} cm at the landing") in page
    assert CAPTIONS[DRIFT_FIGURE] in page and page.count("<img ") == 3
    code, err = quadnav("view", folder, "-o", tmp_path / "view.html")
    assert (code, err) == (0, "")
    view = (tmp_path / "view.html").read_text()
    assert "http://" not in view.replace("http://www.w3.org", "")
    data = json.loads(re.search(r'<script id="run-data" type="application/json">(.*?)'
                                r"</script>", view, re.S)[1])
    assert data == viewer_data(read_run(folder))
    assert np.allclose(np.reshape(data["truth"], (-1, 3)), read_run(folder).truth[:, 1:],
                       atol=1e-3)  # the true track, to the millimetre
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


@needs_netns
def test_tello_fly_prints_records_and_reports_one_landing_place_and_verdict(tmp_path):
    """Against an emulator writing its true track: the line printed, metrics.json and the
    report give one landing place (the dead-reckoned estimate with its 1-sigma) and one
    verdict; the truth reaches the run folder through the emulator's file."""
    room, truth, out = tmp_path / "room.txt", tmp_path / "emulator_truth.csv", tmp_path / "run"
    room.write_text(ROOM)
    host = "198.18.70.1"
    with NetNamespace.create() as namespace, TelloEmulator(
            host=host, start=(*ROOM_START[:2], 0.0), time_scale=10.0, client_netns=namespace,
            truth=truth) as drone:
        result = namespace.call(lambda: subprocess.run(
            [*QUADNAV, "tello", "fly", str(room), "--start", *map(str, ROOM_START), "--goal",
             *map(str, ROOM_GOAL), "--iterations", "300", "--host", host, "--time-scale", "10",
             "--truth", str(truth), "--quiet", "-o", str(out)],
            capture_output=True, text=True, timeout=120))
    assert (result.returncode, result.stderr) == (0, "")
    line = result.stdout.splitlines()[0]
    printed = re.fullmatch(r"quadnav: tello: landed: (landed at (\(.*\) \+- [\d.]+ m), "
                           r"([\d.]+) m from the goal, after \d+ go moves)", line)
    assert printed, line
    m = json.loads((out / "metrics.json").read_text())
    assert (m["ending"], m["message"], m["success"]) == ("landed", printed[1], True)
    assert printed[2] == format_estimate(m["landing_m"], m["landing_sigma_m"])
    assert float(printed[3]) == pytest.approx(m["final_error_m"], abs=0.005)
    assert m["final_error_m"] <= m["goal_tolerance_m"]
    report = html.unescape((out / "report.html").read_text())
    assert f"{printed[2]} (dead reckoning), {printed[3]} m from the goal" in report
    _, positions = drone.track()
    assert read_run(out).truth is not None
    assert m["true_landing_m"] == pytest.approx(positions[-1].tolist(), abs=0.01)
    assert m["landing_drift_m"] < m["landing_sigma_m"]


def test_a_true_track_that_cannot_be_read_is_bad_input(tmp_path):
    out = tmp_path / "out"
    assert_user_error(run_here("tello", "fly", "forest", "--dry-run", "--quiet", "--truth",
                               tmp_path / "none.csv", "-o", out),
                      f"{tmp_path / 'none.csv'}: cannot read the true track")
    wrong = tmp_path / "wrong.csv"
    wrong.write_text("t,x,y,z\n0,1,2,3\n")
    assert_user_error(run_here("tello", "fly", "forest", "--dry-run", "--quiet", "--truth",
                               wrong, "-o", out),
                      f"{wrong}:1: expected the header 'unix_time_s,x,y,z'")
    assert not out.exists()

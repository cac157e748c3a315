"""``quadnav track``: hover, step and helix on the tello preset with their metrics, an MP.csv
written by ``quadnav traj`` flown back exactly, failures and bad input, and the folder
read by ``quadnav report`` and ``quadnav view``."""

from __future__ import annotations

import json

import numpy as np
import pytest
from clitools import assert_user_error, run, run_here
from figurecheck import assert_labels_apart, assert_legends_outside

from quadnav.runs import FIGURES, REPORT, read_run
from quadnav.viz.flight_figures import flight_states_figure

RUN_FILES = ["metrics.json", "parameters.json", "map.json", "trajectory.csv", "flight.csv"]


def _track(folder, *args: str, here: bool = True) -> dict:
    """Fly ``quadnav track args`` into ``folder``; its metrics.json, after checking that it
    succeeded and wrote the run's files (no tree.csv, no path.csv)."""
    result = (run_here if here else run)("track", *args, "--quiet", "-o", folder)
    assert result.returncode == 0, result.stderr
    assert "success" in result.stdout
    for name in RUN_FILES:
        assert (folder / name).is_file()
    assert not (folder / "tree.csv").exists() and not (folder / "path.csv").exists()
    return json.loads((folder / "metrics.json").read_text())


#: The tests of :func:`step`'s folder, on one xdist worker: the step is tracked once.
STEP = pytest.mark.xdist_group("track-step")


@pytest.fixture(scope="module")
def step(tmp_path_factory):
    """A 1 m step along x on the tello, with its figures and report."""
    folder = tmp_path_factory.mktemp("step")
    return folder, _track(folder, "step")


def test_hover_holds_still(tmp_path):
    metrics = _track(tmp_path, "hover:height=1.5,duration=3", "--no-figures")
    assert metrics["reference"] == "hover:height=1.5,duration=3"
    assert metrics["success"] and metrics["ending"] == "completed"
    assert metrics["rms_tracking_error_m"] < 0.01 and metrics["final_error_m"] < 0.01
    assert metrics["flight_time_s"] == pytest.approx(5.0, abs=0.002)  # 3 s, 2 s settling
    assert "overshoot_percent" not in metrics
    world = json.loads((tmp_path / "map.json").read_text())  # 1 m round it, floor at z = 0
    assert world["bounds"]["extents"] == [-1, 1, -1, 1, 0, 2.5] and world["blocks"] == []


@STEP
def test_a_step_settles_with_the_stated_metrics(step):
    folder, metrics = step
    assert metrics["success"] and metrics["reference"] == (
        "step:axis=x,size=1,height=1,at=1,duration=6")
    assert (metrics["step_axis"], metrics["step_size_m"], metrics["step_time_s"]) == ("x", 1, 1)
    # As tests/test_control.py measures a 1 m step: under 5 % overshoot, settled in 2 s.
    assert 0 <= metrics["overshoot_percent"] < 5
    assert 0.5 < metrics["settling_time_s"] < 2.0
    assert 0.2 < metrics["rise_time_s"] < metrics["settling_time_s"]
    assert metrics["steady_state_error_m"] < 0.01
    assert metrics["max_tracking_error_m"] == pytest.approx(1.0, abs=1e-6)  # the jump itself
    # Recorded at the control rate, so the times are to the millisecond.
    t = np.loadtxt(folder / "flight.csv", delimiter=",", skiprows=1)[:, 0]
    assert np.allclose(np.diff(t), 0.001)
    for name in (*FIGURES, REPORT):
        assert (folder / name).stat().st_size > 10_000
    report = (folder / REPORT).read_text()
    assert "step 1 m along x: overshoot" in report and "flown in an empty box" in report


def test_a_helix_is_tracked_within_centimetres(tmp_path):
    metrics = _track(tmp_path, "helix", "--no-figures", here=False)  # a new process, as a user
    assert metrics["success"] and metrics["reference_duration_s"] == pytest.approx(13.72, abs=0.01)
    assert metrics["rms_tracking_error_m"] < 0.02 and metrics["max_tracking_error_m"] < 0.05
    assert metrics["final_error_m"] < 0.005 and metrics["mixer_saturation"] == 0
    parameters = json.loads((tmp_path / "parameters.json").read_text())
    assert parameters["vehicle"]["name"] == "tello" and parameters["gains"]["position"]["kp"]
    assert parameters["boundary"] == pytest.approx([-2, -1, 0, 2, 3, 3.5], abs=1e-3)


def test_an_mp_csv_written_by_traj_is_flown_as_written(tmp_path):
    path = tmp_path / "path.csv"
    path.write_text("x,y,z\n1,1,1\n4,2,1.5\n7,6,2\n")
    written = run_here("traj", "empty", "--path", path, "--dt", "0.01", "-o", tmp_path / "traj")
    assert written.returncode == 0, written.stderr
    out = tmp_path / "track"
    # traj writes MP.csv at the course's 0.05 s and track reads it at that rate by default.
    result = run_here("track", tmp_path / "traj" / "MP.csv", "--no-figures", "--quiet",
                      "-o", out)
    assert result.returncode == 0, result.stderr
    columns = np.loadtxt(tmp_path / "traj" / "MP.csv", delimiter=",").shape[1]
    first = result.stdout.splitlines()[0]
    assert first == (f"{tmp_path / 'traj' / 'MP.csv'}: {columns:,} samples read as every "
                     f"0.05 s (--rate 20 Hz): a {(columns - 1) * 0.05:.2f} s reference")
    # The reference flown (trajectory.csv of the track, every 10 ms) is the one traj wrote
    # (every 10 ms too) at every MP.csv sample: position, velocity and acceleration, to the
    # 9 digits written.
    original = np.loadtxt(tmp_path / "traj" / "trajectory.csv", delimiter=",", skiprows=1)
    flown = np.loadtxt(out / "trajectory.csv", delimiter=",", skiprows=1)
    common = min(len(flown), len(original)) - 1  # traj's last row is at the end time
    np.testing.assert_allclose(flown[:common:5, :10], original[:common:5, :10], rtol=1e-8,
                               atol=1e-8)
    parameters = json.loads((out / "parameters.json").read_text())
    assert parameters["reference_info"] == {"format": "MP.csv", "samples": columns,
                                            "sample_interval_s": 0.05, "rate_hz": 20}


def test_a_flight_blown_away_exits_1_and_still_reports(tmp_path):
    result = run_here("track", "hover", "--wind", "2", "0", "0", "--no-figures", "--quiet",
                      "-o", tmp_path)
    assert result.returncode == 1
    assert "quadnav: flight failed: left boundary at t = " in result.stderr
    metrics = json.loads((tmp_path / "metrics.json").read_text())
    assert not metrics["success"] and metrics["ending"] == "left boundary"


def test_bad_input_is_one_line_exit_2_and_writes_nothing(tmp_path):
    bad = tmp_path / "MP.csv"
    bad.write_text("0,1\n" * 8)
    out = tmp_path / "out"
    cases = [
        (("spiral",), "spiral: no such file, not a built-in reference (built-in: hover"),
        (("step:size=0",), "step:size=0: size: expected a step other than 0 m"),
        (("helix:radius=-1",), "radius: expected from 0.01 to 1,000 m, got -1"),
        ((bad,), "MP.csv: expected 9 rows (x, y, z, vx, vy, vz, ax, ay, az"),
        (("hover", "--rate", "20"), "--rate: applies only to an MP.csv file"),
        (("hover", "--rate", "0"), "argument --rate: expected from 0.1 to 100,000 Hz"),
        (("hover", "--gusts", "-1"), "argument --gusts: expected from 0 to 100 N"),
        (("hover", "--params", "nothing"), "nothing"),
    ]
    for args, fragment in cases:
        assert_user_error(run_here("track", *args, "-o", out), fragment)
    assert not out.exists()


@STEP
def test_report_view_and_animate_accept_a_track_folder(step, tmp_path):
    folder, _ = step
    run = read_run(folder)
    assert run.is_track and run.title.startswith("step:") and run.path is None
    assert len(run.tree_nodes) == 0 and run.flight is not None
    result = run_here("report", folder, "-o", tmp_path / "again.html")
    assert result.returncode == 0, result.stderr
    text = (tmp_path / "again.html").read_text()
    assert "Run 1: step:axis=x,size=1,height=1,at=1,duration=6" in text
    assert text.count("<img src=") == len(FIGURES)
    result = run_here("view", folder, "-o", tmp_path / "view.html")
    assert result.returncode == 0, result.stderr
    assert "step:axis=x" in (tmp_path / "view.html").read_text()
    result = run_here("animate", folder, "-o", tmp_path / "step.gif", "--max-frames", "2",
                      "--quiet")
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "step.gif").read_bytes()[:6] == b"GIF89a"


@STEP
def test_the_states_figure_marks_the_step_response(step):
    folder, metrics = step
    run = read_run(folder)
    fig = flight_states_figure(run)
    x = fig.axes[0]
    (band,) = x.patches
    extent = x.transData.inverted().transform(band.get_extents())  # in data units
    low, high = extent[:, 1]
    assert (low, high) == pytest.approx((0.98, 1.02))  # 2 % of the 1 m step about x = 1
    settled = metrics["step_time_s"] + metrics["settling_time_s"]
    (vertical,) = [ln for ln in x.get_lines() if ln.get_linestyle() == ":"]
    assert vertical.get_xdata()[0] == pytest.approx(settled)
    (peak,) = [ln for ln in x.get_lines() if ln.get_marker() == "o"]
    assert peak.get_ydata()[0] == pytest.approx(1 + metrics["overshoot_percent"] / 100,
                                                abs=1e-6)
    texts = [text.get_text() for text in fig.legends[0].get_texts()]
    assert texts[4:7] == ["2 % band about the target",
                          f"peak: overshoot {metrics['overshoot_percent']:.2f} %",
                          f"settled at {settled:.2f} s ({metrics['settling_time_s']:.2f} s "
                          "after the step)"]
    assert_legends_outside(fig)
    assert_labels_apart(fig)

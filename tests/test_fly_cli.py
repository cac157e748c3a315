"""``quadnav fly``: outputs, exit codes, bad input, seeds."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest
from clitools import assert_user_error, run, run_here

REQUIRED_METRICS = ("success", "collision", "reached_goal", "final_error_m", "path_length_m",
                    "trajectory_duration_s", "rms_tracking_error_m", "max_tracking_error_m",
                    "min_clearance_m", "planning_time_s", "sim_wall_time_s")
FLIGHT_COLUMNS = ["t", "x", "y", "z", "vx", "vy", "vz", "qw", "qx", "qy", "qz",
                  "u1", "u2", "u3", "u4", "x_ref", "y_ref", "z_ref"]
OUTPUTS = ("metrics.json", "path.csv", "trajectory.csv", "flight.csv", "flight_3d.png",
           "flight_states.png", "tracking_error.png")
SMALL = "forest:size=12x12x4,seed=2"


@pytest.fixture(scope="module")
def small_run(tmp_path_factory):
    """``fly SMALL --strict`` (seed 0, no figures): its folder and result, for the tests that
    read a plain run of it (--strict changes only the exit code of a flight short of the
    margin, which this one is not)."""
    folder = tmp_path_factory.mktemp("small") / "out"
    return folder, run_here("fly", SMALL, "-o", folder, "--quiet", "--no-figures", "--strict")


#: The tests that read ``small_run``: on one worker, which flies it once.
SMALL_RUN = pytest.mark.xdist_group("fly-cli-small-run")


def test_fly_on_the_default_world_writes_every_output(tmp_path):
    result = run("fly", "-o", tmp_path / "out", "--quiet")
    assert result.returncode == 0, result.stderr
    assert "success" in result.stdout
    out = tmp_path / "out"
    for name in OUTPUTS:
        assert (out / name).stat().st_size > 0, name
    metrics = json.loads((out / "metrics.json").read_text())
    for key in REQUIRED_METRICS:
        assert key in metrics, key
    assert metrics["success"] and not metrics["collision"] and metrics["reached_goal"]
    assert metrics["map"].startswith("forest")
    assert metrics["vehicle"] == "tello" and metrics["speed_m_s"] == 2.0
    with (out / "flight.csv").open() as file:
        rows = list(csv.reader(file))
    assert rows[0] == FLIGHT_COLUMNS
    table = np.array(rows[1:], dtype=float)
    assert table[-1, 0] == pytest.approx(metrics["flight_time_s"], abs=1e-6)
    final = table[-1, 1:4]
    assert np.linalg.norm(final - metrics["goal"]) == pytest.approx(metrics["final_error_m"],
                                                                     abs=1e-6)
    assert np.all((table[:, 11:15] >= 0) & (table[:, 11:15] <= 1))
    path = np.loadtxt(out / "path.csv", delimiter=",", skiprows=1)
    assert np.allclose(path[0], metrics["start"]) and np.allclose(path[-1], metrics["goal"])


def test_the_same_seed_flies_the_same_flight(tmp_path):
    for name in ("a", "b"):
        assert run_here("fly", SMALL, "--seed", "5", "-o", tmp_path / name, "--quiet",
                   "--no-figures").returncode == 0
    assert (tmp_path / "a/flight.csv").read_text() == (tmp_path / "b/flight.csv").read_text()
    assert run_here("fly", SMALL, "--seed", "6", "-o", tmp_path / "c", "--quiet",
               "--no-figures").returncode == 0
    assert not (tmp_path / "c/flight_3d.png").exists()
    assert (tmp_path / "a/path.csv").read_text() != (tmp_path / "c/path.csv").read_text()


def test_the_rbe595_vehicle_and_a_gains_file(tmp_path):
    gains = tmp_path / "gains.toml"
    gains.write_text("[position]\nkp = [0.6, 0.6, 2.0]\n")
    # Soft position gains lag: a gentle acceleration limit lets them settle on the goal.
    result = run_here("fly", SMALL, "--params", "rbe595", "--gains", gains, "--speed", "1",
                 "--accel", "1",
                 "-o", tmp_path / "out", "--quiet", "--no-figures")
    assert result.returncode == 0, result.stdout + result.stderr
    assert json.loads((tmp_path / "out/metrics.json").read_text())["vehicle"] == "rbe595"


def test_a_missed_goal_exits_1_and_still_reports(tmp_path):
    # A wind of 1.5 N on an 80 g drone needs more tilt than the controller allows.
    result = run_here("fly", SMALL, "--wind", "1.5", "0", "0", "--settle", "0", "-o",
                 tmp_path / "out", "--quiet", "--no-figures")
    assert result.returncode == 1, result.stdout + result.stderr
    assert "quadnav: flight failed:" in result.stderr
    metrics = json.loads((tmp_path / "out/metrics.json").read_text())
    assert not metrics["success"] and not metrics["reached_goal"]
    assert metrics["time_to_goal_s"] is None  # it ended outside the goal tolerance
    assert (tmp_path / "out/flight.csv").exists()


def test_no_path_exits_1_with_metrics_only(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "flight.csv").write_text("stale")
    (out / "view.html").write_text("stale")
    result = run_here("fly", SMALL, "--iterations", "1", "-o", out, "--quiet")
    assert result.returncode == 1
    assert "no path" in result.stderr
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["path_found"] is False and metrics["success"] is False
    assert not (out / "flight.csv").exists()
    assert not (out / "view.html").exists()


@pytest.mark.parametrize(("args", "fragments"), [
    (["--params", "boeing"], ["boeing", "expected a vehicle preset"]),
    (["--speed", "-2"], ["--speed", "expected from 0.01 to 100 m/s or max"]),
    (["--speed", "fastest"], ["--speed", "or max, got 'fastest'"]),
    (["--method", "spline"], ["--method", "invalid choice: 'spline'"]),
    (["--timing", "snap-time", "--method", "cubic"], ["snap-time timing need method minsnap"]),
    (["--physics-rate", "1500"], ["whole multiple of the control rate"]),
    (["--settle", "-1"], ["--settle", "expected from 0 to 60 s"]),
    (["--gains", "/nonexistent/gains.toml"], ["/nonexistent/gains.toml", "cannot read"]),
    (["--start", "100", "0", "1"], ["start", "outside"]),
    (["--goal", "6", "6", "-1"], ["goal", "outside"]),
])
def test_bad_input_is_one_line_exit_2_and_writes_nothing(tmp_path, args, fragments):
    out = tmp_path / "out"
    assert_user_error(run_here("fly", SMALL, *args, "-o", out), *fragments)
    assert not out.exists()


def test_a_bad_gains_file_is_named(tmp_path):
    gains = tmp_path / "gains.toml"
    gains.write_text("[rate]\nkp = [1, 2]\n")
    out = tmp_path / "out"
    assert_user_error(run_here("fly", SMALL, "--gains", gains, "-o", out), str(gains), "kp")
    assert not out.exists()


def test_an_unreachable_goal_is_a_user_error(tmp_path, shared_maps):
    out = tmp_path / "out"
    result = run_here("fly", shared_maps / "meam620/test_impossible.json", "-o", out)
    assert_user_error(result, "disconnected")
    assert not out.exists()


def test_a_start_inside_a_block_is_a_user_error(tmp_path, shared_maps):
    out = tmp_path / "out"
    result = run_here("fly", shared_maps / "rbe595/map1.txt", "--start", "5", "2.25", "1",
                 "--goal", "8", "18", "3", "-o", out)
    assert_user_error(result, "start (5, 2.25, 1)", "inside block")
    assert not out.exists()


@SMALL_RUN
def test_a_run_folder_reads_back(small_run):
    from quadnav.runs import read_run

    out, result = small_run
    assert result.returncode == 0, result.stderr
    record = read_run(out)
    metrics = json.loads((out / "metrics.json").read_text())
    assert record.metrics == metrics
    assert record.parameters["vehicle"]["name"] == "tello"
    assert record.parameters["simulation"]["control_rate"] == 1000.0
    assert np.allclose(record.world.start, metrics["start"])
    assert np.allclose(record.world.goal, metrics["goal"])
    assert record.world.margin == metrics["margin_m"]
    assert len(record.world.blocks) > 0
    assert record.tree_parents[0] == -1 and len(record.tree_edges()) == len(record.tree_nodes) - 1
    assert np.allclose(record.path[[0, -1]], [metrics["start"], metrics["goal"]])
    assert record.flight.t[-1] == pytest.approx(metrics["flight_time_s"], abs=1e-6)
    assert record.trajectory.t[-1] == pytest.approx(metrics["trajectory_duration_s"], abs=1e-6)


@SMALL_RUN
def test_the_time_to_goal_is_when_the_flown_records_came_within_the_tolerance_to_stay(
        small_run):
    out, result = small_run
    assert result.returncode == 0, result.stderr
    metrics = json.loads((out / "metrics.json").read_text())
    flight = np.loadtxt(out / "flight.csv", delimiter=",", skiprows=1)
    close = np.linalg.norm(flight[:, 1:4] - metrics["goal"], axis=1) <= metrics["goal_tolerance_m"]
    arrived = len(close) - np.argmin(close[::-1])  # the first record of the last close run
    assert close[arrived:].all() and not close[arrived - 1]

    assert metrics["time_to_goal_s"] == pytest.approx(flight[arrived, 0], abs=1e-9)
    # flown, not the reference's duration: it reached the goal before its 2 s of settling
    assert metrics["time_to_goal_s"] != metrics["trajectory_duration_s"]
    assert 0 < metrics["time_to_goal_s"] < metrics["flight_time_s"] - 1.0


def test_reading_a_folder_that_is_not_a_run_is_a_user_error(tmp_path):
    from quadnav.errors import QuadnavError
    from quadnav.runs import read_run

    with pytest.raises(QuadnavError, match="not a quadnav fly or track output folder"):
        read_run(tmp_path)


@SMALL_RUN
def test_wind_and_gusts_disturb_the_flight_but_it_still_arrives(small_run, tmp_path):
    calm, result = small_run
    assert result.returncode == 0, result.stderr
    results = {"calm": json.loads((calm / "metrics.json").read_text())}
    out = tmp_path / "windy"
    assert run_here("fly", SMALL, "--wind", "0.03", "0", "0", "--gusts", "0.01", "-o", out,
                    "--quiet", "--no-figures").returncode == 0
    results["windy"] = json.loads((out / "metrics.json").read_text())
    assert results["windy"]["success"]
    # A 0.03 N wind and 0.01 N gusts add a centimetre or so of tracking error.
    assert results["windy"]["rms_tracking_error_m"] > results["calm"]["rms_tracking_error_m"] + 0.005
    parameters = json.loads((tmp_path / "windy/parameters.json").read_text())
    assert parameters["simulation"]["wind"] == [0.03, 0.0, 0.0]
    assert parameters["simulation"]["gust_std"] == 0.01


# ------------------------------------------------------------------- the margin kept
#: A flight that keeps clearly less than the 0.2 m margin asked (0.186 m, 14 mm short),
#: and SMALL, which keeps clearly more (0.230 m).
SHORT_OF_MARGIN = "window:seed=17"


def test_a_flight_short_of_the_margin_says_so_in_a_warning_and_strict_fails_it(tmp_path):
    result = run_here("fly", SHORT_OF_MARGIN, "-o", tmp_path / "out", "--quiet",
                      "--no-figures")
    assert result.returncode == 0, result.stderr
    metrics = json.loads((tmp_path / "out/metrics.json").read_text())
    kept, asked = metrics["flight_margin_m"], metrics["margin_m"]
    assert metrics["success"] and kept < asked - 0.01
    assert metrics["margin_shortfall_m"] == pytest.approx(asked - kept)
    # the place named is the flight's record at the time it kept the least
    when = metrics["flight_margin_time_s"]
    flight = np.loadtxt(tmp_path / "out/flight.csv", delimiter=",", skiprows=1)
    place = flight[np.argmin(np.abs(flight[:, 0] - when)), 1:4]
    assert [line for line in result.stderr.splitlines() if "margin asked" in line] == [
        f"quadnav: warning: the flight kept only {kept:.3f} m of the 0.2 m margin asked off "
        f"the legs ({asked - kept:.3g} m short), least at t = {when:.2f} s near "
        f"({', '.join(f'{v:.2f}' for v in place)})"]

    strict = run_here("fly", SHORT_OF_MARGIN, "-o", tmp_path / "strict", "--quiet",
                      "--no-figures", "--strict")
    assert strict.returncode == 1
    assert strict.stderr.splitlines()[-1] == (
        "quadnav: flight failed: it kept less margin than asked (--strict)")


@SMALL_RUN
def test_a_flight_that_keeps_the_margin_gives_no_warning_even_when_strict(small_run):
    out, result = small_run
    assert result.returncode == 0, result.stderr
    assert "margin asked" not in result.stderr
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["flight_margin_m"] > metrics["margin_m"] + 0.01
    assert metrics["margin_shortfall_m"] == 0.0


def test_any_shortfall_counts_however_small():
    from quadnav.mission import margin_shortfall

    assert margin_shortfall(0.2, 0.2 - 1e-9) > 0.0
    assert margin_shortfall(0.2, 0.2) == margin_shortfall(0.2, 0.25) == 0.0
    assert margin_shortfall(0.12, 0.083) == pytest.approx(0.037)


# ------------------------------------------------------------------------- the floor
def _p2b(shared_maps) -> list:
    """The real Tello lab map with its start and goal on the floor (z = 0)."""
    return [shared_maps / "rbe595/p2b_map1.txt", "--start-goal",
            shared_maps / "rbe595/p2b_startandgoal_map1.txt"]


@pytest.mark.parametrize("controller", [[], ["--controller", "se3", "--control-rate", "100"]])
def test_a_take_off_and_a_landing_on_the_floor_where_the_plan_has_them_are_no_crash(
        tmp_path, shared_maps, controller):
    result = run_here("fly", *_p2b(shared_maps), *controller, "-o", tmp_path / "out",
                      "--quiet", "--no-figures")
    assert result.returncode == 0, result.stderr
    metrics = json.loads((tmp_path / "out/metrics.json").read_text())
    assert metrics["success"] and metrics["ending"] == "completed"
    # the start and goal on the floor are flown from and to where the body fits, just above
    # it (docs/maps.md): if the vehicle meets the floor at all, it is gently
    touch = metrics["floor_touch_speed_m_s"]
    assert touch is None or touch < 0.2
    assert metrics["goal"][2] > 0.0 == metrics["goal_asked"][2]


def test_a_gust_that_slams_the_vehicle_into_the_floor_is_a_crash(tmp_path, shared_maps):
    # 0.2 N gusts (a quarter of the Tello's weight): this seed pushes it into the floor at
    # 0.95 m/s as it descends to the goal; before floor contact counted, it flew on and
    # ended 3.4 cm from the goal, a success (along the path of the fixed search budget it
    # was found with, --stall 0)
    result = run_here("fly", *_p2b(shared_maps), "--gusts", "0.2", "--seed", "6", "--stall", "0",
                      "-o", tmp_path / "out", "--quiet", "--no-figures")
    metrics = json.loads((tmp_path / "out/metrics.json").read_text())
    assert result.returncode == 1
    assert not metrics["success"] and metrics["ending"] == "hit the floor"
    assert metrics["floor_touch_speed_m_s"] > 0.85 and not metrics["collision"]
    assert result.stderr.splitlines()[-1] == (
        f"quadnav: flight failed: hit the floor at {metrics['floor_touch_speed_m_s']:.2f} m/s "
        f"at t = {metrics['contact_time_s']:.2f} s")

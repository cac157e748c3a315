"""``quadnav kino diffdrive|quadrotor``: the files they write, exit codes, one-line errors."""

from __future__ import annotations

import json

import numpy as np
import pytest
from clitools import assert_user_error, run_here

from quadnav.kinodynamic.diffdrive import DiffDrive, propagate
from quadnav.kinodynamic.pointmass import SampledQuadrotor
from quadnav.world import load_world

PNG = b"\x89PNG\r\n\x1a\n"
DIFFDRIVE = ("kino", "diffdrive", "forest", "--height", "1", "--start", "1", "1", "0.785",
             "--goal", "19", "19", "--iterations", "3000", "--time", "60")


def read_csv(path) -> tuple[list[str], np.ndarray]:
    lines = path.read_text().splitlines()
    return lines[0].split(","), np.loadtxt(lines[1:], delimiter=",", ndmin=2)


def assert_pngs(folder, *names):
    for name in names:
        assert (folder / name).read_bytes()[:8] == PNG, name


def test_help_names_both_vehicles_and_the_default_height():
    result = run_here("kino", "--help")
    assert result.returncode == 0 and "diffdrive" in result.stdout and "quadrotor" in result.stdout
    result = run_here("kino", "diffdrive", "--help")
    assert result.returncode == 0 and "half way up its z range" in " ".join(result.stdout.split())


def test_diffdrive_writes_plan_tracks_stats_and_figures(tmp_path):
    out = tmp_path / "out"
    result = run_here(*DIFFDRIVE, "--compare", "--quiet", "-o", out)
    assert result.returncode == 0, result.stderr
    model = DiffDrive()

    header, states = read_csv(out / "states.csv")
    assert header == ["t", "x", "y", "theta"]
    assert np.allclose(states[0, 1:], [1, 1, 0.785])
    assert np.hypot(*(states[-1, 1:3] - 19)) <= 0.5
    header, controls = read_csv(out / "controls.csv")
    assert header == ["t_start", "duration", "v", "omega", "left_speed", "right_speed"]
    assert np.array_equal(controls[:, 0], states[:-1, 0])
    assert np.allclose(controls[:, 0] + controls[:, 1], states[1:, 0])
    v, omega = controls[:, 2], controls[:, 3]
    assert np.all((model.v_min <= v) & (v <= model.v_max) & (np.abs(omega) <= model.omega_max))
    assert np.allclose(controls[:, 4:], np.column_stack(model.wheel_speeds(controls[:, 2:4])))
    # The controls, integrated from each state, reproduce the next one.
    assert np.allclose(propagate(states[:-1, 1:], controls[:, 2:4], controls[:, 1]), states[1:, 1:])

    header, tracks = read_csv(out / "tracks.csv")
    assert header == ["t", "x", "y", "left_x", "left_y", "right_x", "right_y"]
    assert np.allclose(tracks[[0, -1], 1:3], states[[0, -1], 1:3])
    assert np.allclose(np.hypot(*(tracks[:, 3:5] - tracks[:, 5:7]).T), model.wheel_base)

    summary = json.loads((out / "kino.json").read_text())
    assert summary["vehicle"] == "diffdrive" and summary["solved"] and summary["height"] == 1
    assert summary["duration"] == pytest.approx(states[-1, 0])
    assert summary["nodes"] <= summary["iterations"] + 1
    assert 0 < summary["time_to_goal"] <= summary["seconds"]
    assert summary["settings"]["biased"] and summary["settings"]["max_iterations"] == 3000
    assert summary["model"]["wheel_base"] == model.wheel_base
    assert set(summary["compare"]) == {"biased", "unbiased"}
    assert summary["compare"]["biased"]["iterations"] == summary["iterations"]
    assert_pngs(out, "kino.png", "controls.png", "biased_vs_unbiased.png")
    assert "biased sampling" in result.stdout and "unbiased sampling" in result.stdout


def test_diffdrive_on_a_2d_map_file_and_no_plan_in_one_iteration(tmp_path):
    map2d = tmp_path / "room.map2d"
    map2d.write_text("# a wall with a gap at the top\nboundary 0 0 10 6\nrect 4 0 5 4\n")
    args = ("kino", "diffdrive", map2d, "--start", "1", "1", "0", "--goal", "8", "1",
            "--quiet", "-o", tmp_path)
    assert run_here(*args).returncode == 0
    summary = json.loads((tmp_path / "kino.json").read_text())
    assert summary["solved"] and summary["height"] is None and summary["map"] == str(map2d)
    states = read_csv(tmp_path / "states.csv")[1]
    assert states[:, 2].max() > 4  # around the wall, not through it

    result = run_here(*args, "--iterations", "1")
    assert result.returncode == 1
    assert "goal region not reached" in result.stderr
    assert json.loads((tmp_path / "kino.json").read_text())["solved"] is False
    for stale in ("states.csv", "controls.csv", "tracks.csv"):
        assert not (tmp_path / stale).exists()
    assert_pngs(tmp_path, "kino.png", "controls.png")


def test_quadrotor_writes_states_controls_replay_and_figures(tmp_path):
    result = run_here("kino", "quadrotor", "forest", "--seed", "1", "--quiet", "-o", tmp_path)
    assert result.returncode == 0, result.stderr
    world, model = load_world("forest"), SampledQuadrotor()
    header, states = read_csv(tmp_path / "states.csv")
    assert header == ["t", "x", "y", "z", "vx", "vy", "vz"]
    assert np.array_equal(states[0, 1:], [*world.start, 0, 0, 0])
    assert np.linalg.norm(states[-1, 1:4] - world.goal) <= 0.5
    header, controls = read_csv(tmp_path / "controls.csv")
    assert header == ["t_start", "duration", "phi", "theta", "thrust"]
    assert np.all((model.control_lower <= controls[:, 2:]) & (controls[:, 2:] <= model.control_upper))
    assert np.allclose(model.propagate(states[:-1, 1:], controls[:, 2:], controls[:, 1]),
                       states[1:, 1:])
    summary = json.loads((tmp_path / "kino.json").read_text())
    assert summary["vehicle"] == "quadrotor" and summary["solved"] and summary["margin"] == 0.2
    assert summary["start"] == world.start.tolist() and summary["goal"] == world.goal.tolist()
    assert summary["replay"]["max_position_error"] <= summary["replay"]["tolerance"]
    assert summary["model"]["mass"] == model.mass
    assert_pngs(tmp_path, "kino.png", "controls.png")


def test_quadrotor_in_one_iteration_exits_1(tmp_path):
    result = run_here("kino", "quadrotor", "forest", "--iterations", "1", "--quiet", "-o", tmp_path)
    assert result.returncode == 1
    assert "goal region not reached" in result.stderr
    assert not (tmp_path / "states.csv").exists() and not (tmp_path / "controls.csv").exists()
    assert json.loads((tmp_path / "kino.json").read_text())["iterations"] == 1


def assert_user_errors(folder, cases) -> None:
    """Each case (args, *fragments) exits 2 with one line holding the fragments, and
    nothing is written."""
    for args, *fragments in cases:
        assert_user_error(run_here("kino", *args, "-o", folder), *fragments)
    assert not folder.exists()


TRUNK = load_world("forest").blocks[0]
IN_TRUNK = [str(v) for v in (TRUNK[:3] + TRUNK[3:]) / 2]
DIFFDRIVE_FOREST = ("diffdrive", "forest", "--start", "1", "1", "0", "--goal", "19", "19")


def test_diffdrive_bad_input_is_one_line_exit_2_and_writes_nothing(tmp_path):
    malformed = tmp_path / "bad.map2d"
    malformed.write_text("boundary 0 0 10 10\nrect 1 2 3\n")
    assert_user_errors(tmp_path / "out", [
        (("diffdrive", "forest", "--start", *IN_TRUNK[:2], "0", "--goal", "19", "19"),
         "start (11.4, 6.525) is within 0.21 m (robot radius 0.2 m + tolerance 0.01 m)",
         "of rect 0"),
        (("diffdrive", malformed, "--start", "1", "1", "0", "--goal", "9", "9"),
         "bad.map2d:2: rect: expected 4 numbers"),
        ((*DIFFDRIVE_FOREST, "--height", "9"), "slice height 9 m is outside"),
        ((*DIFFDRIVE_FOREST, "--goal-radius", "-1"), "expected from 0.001 to 10,000 m"),
        ((*DIFFDRIVE_FOREST, "--bogus"), "unrecognized arguments: --bogus"),
        (("diffdrive", "forest", "--start", "1", "1", "0"), "required: --goal"),
    ])


def test_quadrotor_bad_input_is_one_line_exit_2_and_writes_nothing(tmp_path):
    assert_user_errors(tmp_path / "out", [
        (("quadrotor", "forest", "--start", *IN_TRUNK), "inside block 0"),
        (("quadrotor", "forest", "--goal", "30", "1", "1"), "outside the boundary"),
        (("quadrotor", "forest", "--iterations", "0"),
         "--iterations: expected a whole number from 1 to 1,000,000"),
    ])
    (tmp_path / "file").write_text("")
    assert_user_error(run_here("kino", *DIFFDRIVE_FOREST, "-o", tmp_path / "file"),
                      "expected a folder")

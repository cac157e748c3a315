"""The contenders of a batch: controllers, planners, trajectory methods, references and winds
as lists of the grid (names or plug-in specs), in a TOML spec and as ``quadnav batch``
flags; bad entries refused up front; a batch folder written before they existed resumes."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from clitools import assert_user_error, run_here

from quadnav.batch.fly_one import mission_config
from quadnav.batch.grid import spec_from_table
from quadnav.batch.table import EARLIER_NAMES, NAMES, read_rows, same_row
from quadnav.cli.batch_command import batch_spec
from quadnav.cli.main import build_parser

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"
EARLIER_BATCH = Path(__file__).parent / "data" / "earlier_batch"
WINDOW = "window:size=4x6x3,walls=1"


def _contenders_spec(folder: Path) -> dict:
    """A grid of every kind of contender, plug-ins named by paths relative to ``folder``."""
    return {"maps": [WINDOW], "seeds": 2, "speeds": [2.0],
            "controllers": ["cascade", "se3", "plain_controller.py:PDAttitude"],
            "planners": ["rrtstar", "plain_planner.py:graph_search(resolution=0.5)"],
            "methods": ["minsnap", "quintic"],
            "references": ["none", "plain_trajectory.py:StopAndGo(speed=1.5)"],
            "winds": [[0, 0, 0], "plain_wind.py:GustFront(speed=2.0)"]}


def test_a_spec_lists_every_kind_of_contender_and_each_mission_flies_its_own():
    spec = spec_from_table(_contenders_spec(EXAMPLES), EXAMPLES)

    assert spec.controllers == ("cascade", "se3", f"{EXAMPLES}/plain_controller.py:PDAttitude")
    assert spec.planners[1] == f"{EXAMPLES}/plain_planner.py:graph_search(resolution=0.5)"
    assert spec.winds == ((0.0, 0.0, 0.0), f"{EXAMPLES}/plain_wind.py:GustFront(speed=2.0)")
    # "none" flies each method; a trajectory class replaces the methods
    assert spec.trajectories == [("minsnap", None), ("quintic", None),
                                 (None, f"{EXAMPLES}/plain_trajectory.py:StopAndGo(speed=1.5)")]
    missions = spec.missions()
    assert len(missions) == spec.size == 2 * 3 * 2 * 3 * 2
    assert len({m.key for m in missions}) == len(missions)
    assert spec_from_table(spec.table(), "/elsewhere") == spec  # batch.json reads back the same
    last = missions[-1]
    config = mission_config(spec.fixed, last).table()
    assert config["controller"] == {"name": spec.controllers[-1]}
    assert config["planner"]["name"] == spec.planners[-1]
    assert config["trajectory"]["reference"] == spec.references[-1]
    assert config["disturbances"]["wind_model"] == spec.winds[-1]
    assert config["disturbances"]["wind"] == [0.0, 0.0, 0.0]


def test_a_mission_of_four_plugins_flies_in_a_worker_and_refly_flies_it_again(tmp_path):
    # a plain-Python controller, planner, trajectory class and wind in one mission, flown by
    # a spawned worker that loads each from the spec's text; the batch.json of a grid
    # without the methods (its references all classes) reads back, so refly flies the row
    spec = {"maps": [WINDOW], "seeds": 1, "speeds": [2.0], "control_rate": 200.0,
            "controllers": ["plain_controller.py:PDAttitude"],
            "planners": ["plain_planner.py:graph_search(resolution=0.5)"],
            "references": ["plain_trajectory.py:StopAndGo(speed=1.5)"],
            "winds": ["plain_wind.py:GustFront(speed=1.0)"]}
    parsed = spec_from_table(spec, EXAMPLES)
    assert spec_from_table(parsed.table(), "/elsewhere") == parsed
    lines = [f"{key} = {json.dumps(value)}" for key, value in spec.items()]
    (tmp_path / "spec.toml").write_text("\n".join(lines) + "\n")
    for name in ("plain_controller.py", "plain_planner.py", "plain_trajectory.py",
                 "plain_wind.py"):
        shutil.copy(EXAMPLES / name, tmp_path)

    result = run_here("batch", tmp_path / "spec.toml", "--workers", "1", "--quiet",
                      "-o", tmp_path / "out")

    assert result.returncode == 0, result.stderr
    row, = read_rows(tmp_path / "out" / "results.csv")
    assert row["success"] and row["error"] is None
    assert (row["controller"], row["planner"], row["method"], row["reference"],
            row["wind_model"]) == (
        f"{tmp_path}/plain_controller.py:PDAttitude",
        f"{tmp_path}/plain_planner.py:graph_search(resolution=0.5)", None,
        f"{tmp_path}/plain_trajectory.py:StopAndGo(speed=1.5)",
        f"{tmp_path}/plain_wind.py:GustFront(speed=1.0)")
    again = run_here("refly", tmp_path / "out", "1", "--no-figures", "-o", tmp_path / "again")
    assert again.returncode == 0, again.stderr
    metrics = json.loads((tmp_path / "again" / "metrics.json").read_text())
    for key in ("rms_tracking_error_m", "flight_margin_m", "rotor_energy_j", "path_length_m"):
        assert metrics[key] == row[key], key


def test_the_default_contenders_keep_the_mission_keys_of_earlier_batch_folders():
    plain = spec_from_table({"maps": ["forest"], "seeds": [3], "speeds": ["max"]}, ".")
    named = spec_from_table({"maps": ["forest"], "seeds": [3], "speeds": ["max"],
                             "controllers": ["cascade", "se3"], "method": "minsnap"}, ".")
    assert plain.missions()[0].key == named.missions()[0].key == "ab5f7820b3a2679d"
    assert named.missions()[1].key != "ab5f7820b3a2679d"


def _parsed(*argv: str) -> dict:
    args = build_parser(["batch", *argv]).parse_args(["batch", *argv])
    return batch_spec(args).table()


def test_flags_give_the_grid_a_spec_gives(monkeypatch):
    monkeypatch.chdir(EXAMPLES)
    table = _parsed(WINDOW, "--seeds", "2", "--controller", "cascade", "se3",
                    "plain_controller.py:PDAttitude", "--planner", "rrtstar",
                    "plain_planner.py:graph_search(resolution=0.5)", "--method", "minsnap",
                    "quintic", "--reference", "none",
                    "plain_trajectory.py:StopAndGo(speed=1.5)", "--wind", "0", "0", "0",
                    "--wind", "plain_wind.py:GustFront(speed=2.0)", "--speeds", "2")

    assert table == spec_from_table(_contenders_spec(EXAMPLES), EXAMPLES).table()
    # one wind per --wind, a negative force read as a number
    assert _parsed(WINDOW, "--wind", "-0.01", "0", "0", "--wind", "0", "0.02", "0"
                   )["winds"] == [[-0.01, 0.0, 0.0], [0.0, 0.02, 0.0]]


BAD_CONTROLLER = "class NoUpdate:\n    def __init__(self, quad_params):\n        pass\n"
BROKEN = "import nothing_of_that_name\n"


@pytest.mark.parametrize(("text", "message"), [
    ("controllers = ['cascade', 'pid']\n", "spec.toml:4: controllers: unknown controller 'pid'; expected one of cascade, se3"),
    ("controllers = ['bad.py:NoUpdate']\n", "spec.toml:4: controllers: | NoUpdate | update"),
    ("controllers = [3]\n", "spec.toml:4: controllers: expected a name or module:NAME or file.py:NAME, got 3"),
    ("planners = ['rrtstar', 'nowhere.py:plan']\n", "spec.toml:4: planners: | nowhere.py"),
    ("methods = ['minsnap', 'spline']\n", "spec.toml:4: methods: expected one of minsnap, quintic"),
    ("method = 'minsnap'\nmethods = ['quintic']\n", "spec.toml:4: method: give methods (a list) or method (one), not both"),
    ("references = ['nowhere.py:Traj']\n", "spec.toml:4: references: | nowhere.py"),
    ("references = ['plain_trajectory.py:StopAndGo']\nmethods = ['quintic']\n", "spec.toml:5: methods: no mission flies a method"),
    ("winds = [[0, 0, 0], 'plain_wind.py:NoSuchWind']\n", "spec.toml:4: winds: | NoSuchWind"),
    ("winds = [[0, 0]]\n", "spec.toml:4: winds: expected [fx, fy, fz] forces | or a wind class"),
])
def test_a_bad_contender_is_one_line_naming_the_spec_line_before_any_mission_flies(
        tmp_path, text, message):
    for name in ("plain_trajectory.py", "plain_wind.py"):
        shutil.copy(EXAMPLES / name, tmp_path)
    (tmp_path / "bad.py").write_text(BAD_CONTROLLER)
    (tmp_path / "spec.toml").write_text(f"seeds = 1\nspeeds = [1]\nmaps = ['{WINDOW}']\n{text}")

    result = run_here("batch", tmp_path / "spec.toml", "-o", tmp_path / "out")

    assert_user_error(result, *message.split(" | "))
    assert not (tmp_path / "out").exists()


def test_a_contender_that_raises_while_loading_shows_its_traceback_once(tmp_path):
    (tmp_path / "broken.py").write_text(BROKEN)
    (tmp_path / "spec.toml").write_text(f"seeds = 1\nspeeds = [1]\nmaps = ['{WINDOW}']\n"
                                        "controllers = ['cascade', 'broken.py:Ctl']\n")

    result = run_here("batch", tmp_path / "spec.toml", "-o", tmp_path / "out")

    assert result.returncode == 2
    lines = result.stderr.strip().splitlines()
    assert lines[-1].startswith(f"quadnav: error: {tmp_path / 'spec.toml'}:4: controllers: ")
    assert result.stderr.count("Traceback") == 1 and "nothing_of_that_name" in result.stderr
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(("args", "message"), [
    (["--controller", "cascade", "pid"], "the command line: controllers: unknown controller 'pid'"),
    (["--wind", "1", "2"], "--wind: expected three forces FX FY FZ (N) or one wind model's spec, got 1 2"),
    (["--wind", "0", "0", "0", "nope.py:Wind"], "--wind: expected three forces FX FY FZ"),
    (["--reference", "nowhere.py:Traj"], "the command line: references: | nowhere.py"),
    (["--planner", "rrtstar", "--compare"], "--compare: the batch has a single contender (one controller, planner, method or reference, wind and gains)"),
])
def test_bad_contender_flags_are_one_line_and_nothing_is_written(tmp_path, args, message):
    result = run_here("batch", WINDOW, *args, "-o", tmp_path / "out", cwd=tmp_path)

    assert_user_error(result, *message.split(" | "))
    assert not (tmp_path / "out").exists()


def test_a_batch_folder_written_before_the_contender_columns_resumes_and_refies(tmp_path):
    # written by the batch command of quadnav before controllers were values of the grid,
    # stopped after 2 of its 3 missions
    folder = tmp_path / "earlier"
    shutil.copytree(EARLIER_BATCH, folder)
    spec = folder / "spec.toml"
    earlier = read_rows(folder / "results.csv")
    assert json.loads((folder / "batch.json").read_text())["columns"] == list(EARLIER_NAMES)

    again = run_here("refly", folder, "2", "-o", tmp_path / "row2", "--no-figures")
    assert again.returncode == 0, again.stderr
    metrics = json.loads((tmp_path / "row2" / "metrics.json").read_text())
    # the same mission flown again: the row's error, to the last digits another CPU's
    # arithmetic changes (the folder was written on another machine)
    assert metrics["rms_tracking_error_m"] == pytest.approx(earlier[1]["rms_tracking_error_m"],
                                                            rel=1e-6)

    # it searched before the stall rule: its spec now means another batch, refused ...
    refused = run_here("batch", spec, "--quiet", "-o", folder)
    assert_user_error(refused, f"{folder}: holds another batch (its stall differs)")
    # ... and, with the fixed budget it flew with, the same one
    spec.write_text(spec.read_text() + "stall = 0\n")
    result = run_here("batch", spec, "--quiet", "-o", folder)

    assert result.returncode == 0, result.stderr
    assert f"3 missions, 2 already in {folder}; flying 1 on" in result.stdout
    assert json.loads((folder / "batch.json").read_text())["columns"] == list(NAMES)
    rows = read_rows(folder / "results.csv")
    assert len(rows) == 3 and (folder / "results.csv").read_text().startswith(",".join(NAMES))
    for old, new in zip(earlier, rows, strict=False):
        assert new["mission_key"] == old["mission_key"]
        assert (new["controller"], new["method"], new["reference"]) == ("cascade", "minsnap",
                                                                          None)
        assert same_row(new, old | {"controller": "cascade", "method": "minsnap",
                                    "sim_seed": old["seed"]}, ignore=())
    # and it is the same batch for good: a third run has nothing left to fly
    last = run_here("batch", spec, "--quiet", "-o", folder)
    assert "3 missions, all already in" in last.stdout

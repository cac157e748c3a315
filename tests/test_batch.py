"""``quadnav batch`` and ``quadnav refly``: the spec, the rows against missions flown one by
one, the tables, the summary and its page, re-flying a row, the vehicle spread, bad input."""

from __future__ import annotations

import json
import operator

import pyarrow.parquet as pq
import pytest
from batchtools import MISSIONS, write_spec
from clitools import assert_user_error, run_here

from quadnav.batch.executor import LocalExecutor
from quadnav.batch.fly_one import fly_row, load_context
from quadnav.batch.grid import MissionSpec, Spread, read_spec, spec_from_table
from quadnav.batch.run import BatchRun
from quadnav.batch.summary import percent_text, wilson_interval
from quadnav.batch.table import NAMES, POINTS, WALL_TIME_COLUMNS, read_rows, same_row
from quadnav.mission import Mission, MissionSettings, fly_mission
from quadnav.planning import PlannerSettings
from quadnav.sim.settings import SimSettings
from quadnav.trajectory.generate import TrajectorySettings
from quadnav.world import load_world

#: One worker for the module, so that its module-scoped fixtures are built once under
#: --dist loadgroup (each test apart would build them on each worker).
pytestmark = pytest.mark.xdist_group("batch")


@pytest.fixture(scope="module")
def batch(tmp_path_factory):
    """The test batch run once into a folder, on a local worker."""
    folder = tmp_path_factory.mktemp("batch")
    spec_path = write_spec(folder / "spec")
    run = BatchRun(read_spec(spec_path), folder / "out")
    written = run.run(workers=1)
    return spec_path, folder / "out", run, written


# ------------------------------------------------------------------------------- the spec
def test_a_spec_sets_every_grid_value_and_resolves_paths_against_its_folder(tmp_path):
    (tmp_path / "maps").mkdir()
    (tmp_path / "maps" / "m.txt").write_text("boundary 0 0 0 5 5 3\n")
    (tmp_path / "g.toml").write_text("[position]\nkp = [2.0, 2.0, 3.0]\n")
    (tmp_path / "sg.txt").write_text("start: (1, 1, 1)\ngoal: (4, 4, 2)\n")
    path = tmp_path / "spec.toml"
    path.write_text("""
seeds = [0, 5]
speeds = [1.0, "max"]
accel = 2.5
winds = [[0, 0, 0], [0.02, 0, 0]]
gusts = [0.0, 0.01]
spreads = [0.0, {mass = 0.1, drag = 0.2}]
planners = ["rrtstar"]
gains = ["default", "g.toml"]
maps = ["forest:seed=1", {map = "maps/m.txt", start_goal = "sg.txt", margin = 0.1}]
""")
    spec = read_spec(path)

    assert spec.seeds == (0, 5) and spec.speeds == (1.0, "max")
    assert spec.fixed.accel == 2.5 and spec.fixed.improve == 50_000
    assert spec.spreads[1] == Spread(mass=0.1, thrust=0.0, drag=0.2)
    assert spec.spreads[1].label == "mass=0.1,thrust=0,drag=0.2"
    assert spec.gains == ("default", str(tmp_path / "g.toml"))
    entry = spec.maps[1]
    assert (entry.map, entry.start, entry.goal, entry.margin) == (
        str(tmp_path / "maps" / "m.txt"), (1.0, 1.0, 1.0), (4.0, 4.0, 2.0), 0.1)
    missions = spec.missions()
    assert len(missions) == spec.size == 2 * 2 * 2 * 2 * 2 * 2 * 2
    assert [m.seed for m in missions[:3]] == [0, 5, 0]  # the seed varies fastest
    assert len({m.key for m in missions}) == len(missions)
    assert spec_from_table(spec.table(), "/elsewhere") == spec  # batch.json reads back the same


def test_mission_keys_stay_those_of_earlier_batch_folders():
    # a batch folder written before speeds became one type ("max") resumes: same keys
    spec = spec_from_table({"maps": ["forest"], "seeds": [3], "speeds": ["max", 2.0]}, ".")
    assert [(m.speed, m.key) for m in spec.missions()] == [
        ("max", "ab5f7820b3a2679d"), (2.0, "d82baf8f1adb65ac")]


@pytest.mark.parametrize(("text", "message"), [
    ("seeds = 3\nspeeds = [1]\nmaps = ['forest']\nsped = 2\n", "spec.toml:4: sped: unknown key"),
    ("seeds = 3\nspeeds = [0]\nmaps = ['forest']\n", "spec.toml:2: speeds: expected from 0.01 to 100 m/s or \"max\", got 0"),
    ("seeds = 0\nspeeds = [1]\nmaps = ['forest']\n", "spec.toml:1: seeds: expected a whole number from 1"),
    ("seeds = 3\nspeeds = [1]\nmaps = ['nowhere.txt']\n", "spec.toml:3: maps: expected a map file, a built-in world spec or a course map (course:NAME), got 'nowhere.txt'"),
    ("seeds = 3\nspeeds = [1]\nmaps = ['course:rbe595/map9']\n", "spec.toml:3: maps: course:rbe595/map9: no such course map; known: meam620/grid_forest, "),
    ("seeds = 3\nspeeds = [1]\nmaps = [{map = 'forest', start_goal = 'course:rotorpy/pillar'}]\n", "spec.toml:3: start_goal: course:rotorpy/pillar: a map, not a start/goal file: pass it as the map"),
    ("seeds = 3\nspeeds = [1]\nmaps = [{map = 'forest', strat = [0, 0, 0]}]\n", "spec.toml:3: strat: unknown key in a map entry"),
    ("seeds = 3\nspeeds = [1]\nmaps = ['forest']\nspreads = [0.95]\n", "spec.toml:4: spreads: expected from 0 to 0.9"),
    ("seeds = 3\nspeeds = [1]\nmaps = ['forest']\nwinds = [[0, 0]]\n", "spec.toml:4: winds: expected [fx, fy, fz]"),
    ("seeds = 3\nspeeds = [1, 1]\nmaps = ['forest']\n", "spec.toml:2: speeds: a value is listed twice"),
    ("seeds = 3\nspeeds = [1]\nmaps = ['forest']\nplanners = ['rrt']\n", "spec.toml:4: planners: unknown planner 'rrt'"),
    ("seeds = 3\nspeeds = [1]\n", "spec.toml: missing key 'maps'"),
    ("seeds = 3\nspeeds = [1]\nmaps = ['forest']\nvehicle = 'jet'\n", "spec.toml:4: vehicle: expected a vehicle preset"),
    ("seeds = 3\nspeeds = [1\n", "spec.toml: not valid TOML"),
])
def test_a_bad_spec_is_one_line_naming_the_line_and_nothing_is_written(tmp_path, text, message):
    (tmp_path / "spec.toml").write_text(text)

    result = run_here("batch", tmp_path / "spec.toml", "-o", tmp_path / "out")

    assert_user_error(result, message)
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(("args", "message"), [
    (["forest", "--seeds", "0"], "argument --seeds: expected a whole number from 1"),
    (["forest", "--speeds", "fast"], "argument --speeds: expected from 0.01 to 100 m/s or max"),
    (["forest", "--workers", "0"], "argument --workers: expected a whole number from 1"),
    (["spec.toml", "--seeds", "3"], "--seeds: set it in the spec | spec.toml instead"),
    (["forest", "--start", "1", "1", "1", "--gains", "missing.toml"], "gains: expected 'default', a course gain table (p2a-22by7-raikar, "),
    (["forest", "--start", "1e5", "1", "1"], "argument --start: expected from -10,000 to 10,000 m"),
    (["forest", "--ray", "localhost:1", "--seeds", "1", "--params", "nope"], "vehicle: expected a vehicle preset"),
])
def test_bad_flags_are_one_line_and_nothing_is_written(tmp_path, args, message):
    write_spec(tmp_path)
    args = [tmp_path / a if a == "spec.toml" else a for a in args]

    result = run_here("batch", *args, "-o", tmp_path / "out", cwd=tmp_path)

    assert_user_error(result, *message.split(" | "))
    assert not (tmp_path / "out").exists()


def test_wilson_interval_matches_known_values():
    low, high = wilson_interval(8, 10)  # the textbook example: 8 successes in 10
    assert (round(low, 4), round(high, 4)) == (0.4902, 0.9433)
    assert wilson_interval(0, 10)[0] == 0.0 and wilson_interval(0, 10)[1] == pytest.approx(
        0.27753, abs=1e-5)
    assert wilson_interval(50, 50) == (pytest.approx(0.92865, abs=1e-5), 1.0)
    assert wilson_interval(10, 10)[1] == 1.0  # not 0.9999999999999999


# ------------------------------------------------------------------------ a whole batch
def _flown_alone(row: dict) -> Mission:
    """The mission of ``row`` flown with fly_mission and settings built here, not by the
    batch (the test spec's: improve 2000, 60 s cap, 3 m/s^2, the row's seed and speed)."""
    world = load_world(row["map"])
    seed = row["seed"]
    settings = MissionSettings(
        planning=PlannerSettings(time_limit=60.0, improve_iterations=2000, seed=seed),
        trajectory=TrajectorySettings(v_max=row["speed"], a_max=3.0),
        sim=SimSettings(seed=seed))
    start = [row[f"start_{a}"] for a in "xyz"]
    goal = [row[f"goal_{a}"] for a in "xyz"]
    return fly_mission(world, start, goal, row["margin_m"], settings)


def _short_of_margin(mission: Mission) -> bool:
    """Whether the flight kept less than the asked margin off the legs."""
    return mission.metrics()["flight_margin_m"] < mission.problem.margin


def test_a_batch_gives_the_rows_rates_tables_and_page_of_its_missions_flown_one_by_one(batch):
    _, out, run, written = batch
    rows = read_rows(out / "results.csv")
    assert len(rows) == MISSIONS == len(run.missions)
    alone = [_flown_alone(row) for row in rows]

    for row, mission in zip(rows, alone, strict=True):
        metrics = mission.metrics()
        for key, value in metrics.items():
            if key == "map" or key in POINTS or key in WALL_TIME_COLUMNS:
                continue
            assert row[key] == value, (key, row, metrics)
        for name in POINTS:
            assert [row[f"{name}_{a}"] for a in "xyz"] == metrics[name]
        assert row["error"] is None and row["search_stopped_by"] in ("improvement", "direct")
    summary = json.loads((out / "summary.json").read_text())
    assert summary["n"] == MISSIONS and summary["complete"]
    assert summary["successes"] == sum(m.success for m in alone)
    assert len(summary["groups"]) == 2  # one per map
    for group in summary["groups"]:
        members = [m for row, m in zip(rows, alone, strict=True) if row["map"] == group["map"]]
        assert group["n"] == len(members) == 3
        assert group["successes"] == sum(m.success for m in members)
        assert group["short_of_margin"] == sum(_short_of_margin(m) for m in members)
        assert (group["ci_low"], group["ci_high"]) == wilson_interval(group["successes"], 3)
    # flights that kept less margin than asked, counted apart from success: the test batch
    # has both kinds, each with a margin of a millimetre or more
    short = [m for m in alone if _short_of_margin(m)]
    assert 0 < len(short) < MISSIONS and summary["short_of_margin"] == len(short)
    assert all(abs(row["flight_margin_m"] - row["margin_m"]) > 0.001 for row in rows)
    # the map without a start and goal: each seed drew its own, recorded in the row
    drawn = [row for row in rows if row["start_goal_drawn"]]
    assert [row["map"].endswith("pillar.txt") for row in drawn] == [True] * 3
    assert len({(row["start_x"], row["start_y"], row["goal_x"]) for row in drawn}) == 3
    assert summary["groups"][1]["start"] == summary["groups"][1]["goal"] == "drawn"
    assert summary["groups"][0]["start"] == [1.0, 1.0, 1.0]
    # Parquet and CSV: the same table with a fixed schema
    assert written == ["results.parquet", "results.csv", "summary.json", "summary.html"]
    table = pq.read_table(out / "results.parquet")
    assert table.column_names == list(NAMES)
    assert str(table.schema.field("seed").type) == "int64"
    assert str(table.schema.field("contact_block").type) == "int64"  # all null here
    assert str(table.schema.field("success").type) == "bool"
    assert table.to_pylist() == rows
    # the summary page: one offline file with the heat map and the distributions
    page = (out / "summary.html").read_text()
    assert "http://" not in page and "https://" not in page
    assert page.count('src="data:image/png;base64,') == 2
    assert "Success rate" in page and "Distributions" in page and "pillar.txt" in page
    assert f"{len(short)} kept less margin than asked off the legs" in page


def test_a_rerun_skips_every_finished_mission_and_another_batch_is_refused(batch, tmp_path):
    spec_path, out, _, _ = batch
    before = (out / "results.csv").read_text()
    again = BatchRun(read_spec(spec_path), out)
    assert again.todo == [] and len(again.rows) == MISSIONS
    again.run()
    assert (out / "results.csv").read_text() == before

    other = spec_path.with_name("other.toml")
    other.write_text(spec_path.read_text().replace("seeds = 3", "seeds = 4"))
    result = run_here("batch", other, "-o", out)
    assert_user_error(result, f"{out}: holds another batch (its seeds differ)", "--restart")


def test_refly_flies_a_row_again_with_figures_and_the_same_metrics(batch, tmp_path):
    _, out, _, _ = batch
    rows = read_rows(out / "results.csv")
    number = next(k for k, row in enumerate(rows, 1) if row["start_goal_drawn"])
    row = rows[number - 1]

    result = run_here("refly", out, number, "-o", tmp_path / "again")

    assert result.returncode == 0, result.stderr
    assert (tmp_path / "again" / "flight_3d.png").is_file()
    assert (tmp_path / "again" / "report.html").is_file()
    metrics = json.loads((tmp_path / "again" / "metrics.json").read_text())
    assert [metrics[name] for name in POINTS] == [
        [row[f"{name}_{a}"] for a in "xyz"] for name in POINTS]
    for key, value in metrics.items():
        if key not in POINTS and key not in WALL_TIME_COLUMNS:
            assert row[key] == value, key
    by_key = run_here("refly", out, row["mission_key"], "-o", tmp_path / "by-key",
                      "--no-figures")
    assert by_key.returncode == 0
    assert_user_error(run_here("refly", out, "99", "-o", tmp_path / "x"),
                      "99: expected a row number", "from 1 to 6")


# ------------------------------------------------------------------------ vehicle spread
def test_a_spread_vehicle_flies_the_nominal_trajectory_with_the_nominal_controller(tmp_path):
    spec = spec_from_table({"maps": ["window:size=4x6x3,walls=1"], "seeds": [4], "speeds": [3.0],
                            "spreads": [0.0, 0.3], "improve": 2000}, tmp_path)
    context = load_context(spec)
    nominal, spread = (fly_row(context, mission) for mission in spec.missions())

    assert (nominal["mass_factor"], nominal["thrust_factor"], nominal["drag_factor"]) == (
        1.0, 1.0, 1.0)
    factors = [spread[f"{part}_factor"] for part in ("mass", "thrust", "drag")]
    assert all(0.7 <= f <= 1.3 for f in factors) and len(set(factors)) == 3
    assert spread["spread"] == "0.3"
    # the same path and trajectory (made for the nominal vehicle), another flight
    for key in ("path_length_m", "trajectory_duration_s", "trajectory_margin_m"):
        assert spread[key] == nominal[key], key
    assert spread["rms_tracking_error_m"] != nominal["rms_tracking_error_m"]
    assert spread["success"] and nominal["success"]
    heavy = MissionSpec(spec.maps[0], 4, 3.0, (0.0, 0.0, 0.0), 0.0, Spread(mass=0.3, thrust=0.3, drag=0.3),
                        "rrtstar", "default")
    assert same_row(fly_row(context, heavy), spread)  # the same factors from the seed


def test_a_drawn_start_and_goal_depend_on_the_seed_alone(tmp_path):
    write_spec(tmp_path)
    spec = spec_from_table({"maps": ["pillar.txt"], "seeds": [7], "speeds": [1.0, 3.0],
                            "improve": 500}, tmp_path)
    context = load_context(spec)
    slow, fast = (fly_row(context, mission) for mission in spec.missions())
    assert slow["start_goal_drawn"] and slow["success"] and fast["success"]
    for name in ("start_x", "start_y", "start_z", "goal_x", "goal_y", "goal_z"):
        assert slow[name] == fast[name], name
    assert slow["trajectory_duration_s"] > fast["trajectory_duration_s"]


def test_the_local_executor_runs_any_module_level_function_with_its_shared_data():
    with LocalExecutor(shared=10, workers=2) as executor:
        results = dict(executor.map_unordered(operator.mul, [1, 2, 3]))
    assert results == {0: 10, 1: 20, 2: 30}


def test_a_refused_mission_is_a_row_with_its_error(tmp_path):
    spec = spec_from_table({"maps": [{"map": "window:size=4x6x3,walls=1", "start": [1, 3, 1],
                                      "goal": [2, 5, 1]}],
                            "seeds": 1, "speeds": [1.0]}, tmp_path)
    context = load_context(spec)
    row = fly_row(context, spec.missions()[0])
    assert row["success"] is False and row["path_found"] is False
    assert "inside" in row["error"] and row["start_x"] == 1.0 and row["margin_m"] == 0.2
    assert row["rms_tracking_error_m"] is None and row["seed"] == 0


def test_a_rate_or_bound_short_of_all_or_none_never_reads_as_100_or_0_percent():
    low, high = wilson_interval(10_000, 10_000)
    assert (percent_text(low), percent_text(high)) == ("99.96", "100.0")
    low, high = wilson_interval(0, 10_000)
    assert (percent_text(low), percent_text(high)) == ("0.0", "0.04")
    assert percent_text(9_999 / 10_000) == "99.99"
    assert percent_text(0.5, digits=0) == "50" and percent_text(None) == "\u2014"

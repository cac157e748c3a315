"""Plans and trajectories made once per distinct input (quadnav.batch.stages): a batch with
separate planner and simulation seeds plans once per planner seed, gives the rows its
missions give flown alone, keeps its plans in DIR/plans for a resumed run, and never
trusts a plan file it cannot check."""

from __future__ import annotations

import json
import pickle
import shutil
import tomllib
from pathlib import Path

import numpy as np
import pytest
from clitools import assert_user_error, run_here

from quadnav.batch.fly_one import (
    flown_row,
    fly_mission_spec,
    load_context,
    mission_problem,
    mission_settings,
)
from quadnav.batch.folder import PLANS, batch_record, begin
from quadnav.batch.grid import read_spec, spec_from_table
from quadnav.batch.stages import StageCache
from quadnav.batch.table import NAMES, PREVIOUS_NAMES, UNTIMED_NAMES, read_rows, same_row
from quadnav.control.registry import controller_gains
from quadnav.planning.legs import leg_world
from quadnav.sim.collision import body_grid
from quadnav.trajectory.clearance.space import (
    SafeSpace,
    reference_margins,
    trajectory_margins,
)
from quadnav.tune.sets import read_set, set_items
from quadnav.vehicle.params import load_params
from quadnav.world import load_world
from quadnav.world.connectivity import disconnected, unblocked_components

PREVIOUS_BATCH = Path(__file__).parent / "data" / "previous_batch"
UNTIMED_BATCH = Path(__file__).parent / "data" / "untimed_batch"
WINDOW = "window:size=4x6x3,walls=1"
SPEC = f"""\
seeds = {{plan = 2, sim = 3}}
speeds = [2.0]
gusts = [0.02]
improve = 500
maps = ["{WINDOW}"]
"""


def _alone(spec_path: Path) -> list[dict]:
    """The spec's rows, each mission flown alone without a cache."""
    spec = read_spec(spec_path)
    context = load_context(spec)
    return [flown_row(context, mission) for mission in spec.missions()]


@pytest.fixture(scope="module")
def spec_path(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("spec") / "spec.toml"
    path.write_text(SPEC)
    return path


@pytest.fixture(scope="module")
def alone(spec_path) -> list[dict]:
    return _alone(spec_path)


@pytest.fixture(scope="module")
def kept_plans(spec_path, tmp_path_factory) -> Path:
    """A folder of the spec's plans, as its missions flown with a cache left it."""
    spec = read_spec(spec_path)
    context = load_context(spec)
    folder = tmp_path_factory.mktemp("kept") / PLANS
    cache = StageCache(folder)
    for mission in spec.missions():
        flown_row(context, mission, cache)
    return folder


def test_a_seeds_table_flies_every_planner_seed_with_every_simulation_seed(tmp_path):
    spec = spec_from_table(tomllib.loads(SPEC.replace("sim = 3", "sim = [5, 7, 9]")), tmp_path)

    assert [(m.seed, m.sim_seed) for m in spec.missions()] == [
        (0, 5), (0, 7), (0, 9), (1, 5), (1, 7), (1, 9)]
    assert spec.size == 6 and spec.table()["seeds"] == {"plan": [0, 1], "sim": [5, 7, 9]}
    assert spec_from_table(spec.table(), tmp_path) == spec
    # one seed for both keeps today's missions, their keys and their settings
    plain = spec_from_table({"maps": [WINDOW], "seeds": 2, "speeds": [2.0]}, tmp_path)
    assert [(m.seed, m.sim_seed, m.flight_seed) for m in plain.missions()] == [
        (0, None, 0), (1, None, 1)]
    assert plain.table()["seeds"] == [0, 1]
    assert plain.missions()[1].key == plain.missions()[1].earlier_key
    assert spec.missions()[0].key != plain.missions()[0].key


@pytest.mark.parametrize(("seeds", "message"), [
    ("{plan = 2}", "seeds: a seeds table needs plan and sim, each a count or a list; sim is missing"),
    ("{plan = 2, sim = 3, gust = 1}", "seeds: unknown key 'gust' in a seeds table; expected plan and sim"),
    ("{plan = 0, sim = 3}", "seeds: plan: expected a whole number from 1 to 1,000,000, got 0"),
    ("{plan = 2, sim = [1, 1]}", "seeds: sim: a value is listed twice"),
    ("{plan = 2, sim = []}", "seeds: sim: expected at least one value, got an empty list"),
    ("{plan = 2, sim = [-1]}", "seeds: sim: expected a whole number from 0 to"),
    ("{plan = 2, sim = 'x'}", "seeds: sim: expected a whole number from 1 to 1,000,000, got 'x'"),
])
def test_bad_seeds_are_one_line_naming_the_spec_line_and_nothing_is_written(tmp_path, seeds,
                                                                            message):
    spec = tmp_path / "spec.toml"
    spec.write_text(f"speeds = [1]\nseeds = {seeds}\nmaps = ['{WINDOW}']\n")

    result = run_here("batch", spec, "-o", tmp_path / "out")

    assert_user_error(result, f"{spec}:2: {message}")
    assert not (tmp_path / "out").exists()


def test_missions_that_share_a_plan_plan_once_and_give_the_rows_they_give_alone(
        spec_path, alone, tmp_path):
    spec = read_spec(spec_path)
    context = load_context(spec)
    cache = StageCache(tmp_path / PLANS)

    rows = [flown_row(context, mission, cache) for mission in spec.missions()]

    assert all(same_row(a, b) for a, b in zip(rows, alone, strict=True))
    assert (cache.made["plan"], cache.made["reference"], cache.read) == (2, 2, 0)
    keys = {seed: {r["plan_key"] for r in rows if r["seed"] == seed} for seed in (0, 1)}
    assert all(len(shared) == 1 for shared in keys.values()) and keys[0] != keys[1]
    assert sorted(p.stem for p in (tmp_path / PLANS).iterdir()) == sorted(
        key for shared in keys.values() for key in shared)
    # the simulation's seed alone differs among the missions of a plan: their gusts do
    assert [r["sim_seed"] for r in rows] == [0, 1, 2, 0, 1, 2]
    assert len({r["rms_tracking_error_m"] for r in rows[:3]}) == 3
    # a worker of a resumed batch reads the plans instead of planning again
    again = StageCache(tmp_path / PLANS)
    assert all(same_row(a, b) for a, b in zip(
        [flown_row(context, m, again) for m in spec.missions()], alone, strict=True))
    assert (again.made["plan"], again.read) == (0, 2)


def _straight_through(plan_file: Path, problem) -> None:
    """Rewrite ``plan_file``'s path as the straight line from the search's start to its
    goal (through the map's wall), keeping its key."""
    with np.load(plan_file) as data:
        kept = {name: data[name] for name in data.files}
    assert not problem.free_world.segment_free(problem.search_start, problem.search_goal)
    kept["path"] = problem.full_path([problem.search_start, problem.search_goal])
    with plan_file.open("wb") as file:
        np.savez(file, **kept)


@pytest.mark.parametrize("fault", ["garbage", "truncated", "another plan", "pickled",
                                   "through a wall"])
def test_a_plan_file_that_is_not_a_sound_plan_of_its_key_is_made_again(
        spec_path, alone, kept_plans, tmp_path, fault):
    spec = read_spec(spec_path)
    context = load_context(spec)
    folder = tmp_path / PLANS
    shutil.copytree(kept_plans, folder)
    target, other = sorted(folder.iterdir(), key=lambda p: p.stem != alone[0]["plan_key"])
    mission = spec.missions()[0]
    problem = mission_problem(context, mission, mission_settings(context, mission).body)
    if fault == "garbage":
        target.write_bytes(b"not a plan")
    elif fault == "truncated":
        target.write_bytes(target.read_bytes()[:200])
    elif fault == "another plan":
        shutil.copy(other, target)
    elif fault == "pickled":
        target.write_bytes(pickle.dumps({"path": np.zeros((2, 3))}))
    else:
        _straight_through(target, problem)

    cache = StageCache(folder)
    rows = [flown_row(context, m, cache) for m in spec.missions()]

    assert (cache.made["plan"], cache.read) == (1, 1)
    assert all(same_row(a, b) for a, b in zip(rows, alone, strict=True))
    assert StageCache(folder).plan(context.world_hashes[WINDOW], problem,
                                   mission_settings(context, mission))[0] == target.stem


def test_a_plan_that_cannot_be_kept_on_disk_is_kept_in_memory(spec_path, alone, tmp_path):
    spec = read_spec(spec_path)
    context = load_context(spec)
    (tmp_path / PLANS).write_text("a file where the folder would be")
    cache = StageCache(tmp_path / PLANS)

    rows = [flown_row(context, mission, cache) for mission in spec.missions()]

    assert all(same_row(a, b) for a, b in zip(rows, alone, strict=True))
    assert cache.made["plan"] == 2 and (tmp_path / PLANS).is_file()


def test_a_batch_keeps_its_plans_and_a_resumed_batch_plans_none_again(spec_path, alone,
                                                                      tmp_path):
    out = tmp_path / "out"

    result = run_here("batch", spec_path, "--workers", "1", "--quiet", "-o", out)

    assert result.returncode == 0, result.stderr
    rows = read_rows(out / "results.csv")
    assert all(same_row(a, b) for a, b in zip(rows, alone, strict=True))
    plans = {path: path.stat() for path in (out / PLANS).iterdir()}
    assert sorted(p.stem for p in plans) == sorted({r["plan_key"] for r in rows})
    # stopped after two missions: the rest fly again, on the plans kept
    lines = (out / "results.csv").read_text().splitlines(keepends=True)
    (out / "results.csv").write_text("".join(lines[:3]))

    again = run_here("batch", spec_path, "--workers", "1", "--quiet", "-o", out)

    assert again.returncode == 0, again.stderr
    assert f"6 missions, 2 already in {out}; flying 4 on" in again.stdout
    assert all(same_row(a, b) for a, b in zip(read_rows(out / "results.csv"), alone,
                                              strict=True))
    for path, stat in plans.items():  # read, not written again
        assert (path.stat().st_ino, path.stat().st_mtime_ns) == (stat.st_ino,
                                                                  stat.st_mtime_ns)
    assert sorted((out / PLANS).iterdir()) == sorted(plans)
    # a row flies again alone, its simulation seed in its mission file
    refly = run_here("refly", out, "6", "-o", tmp_path / "row6", "--no-figures")
    assert refly.returncode == 0, refly.stderr
    metrics = json.loads((tmp_path / "row6" / "metrics.json").read_text())
    assert metrics["rms_tracking_error_m"] == alone[5]["rms_tracking_error_m"]
    mission = tomllib.loads((tmp_path / "row6" / "mission.toml").read_text())
    assert (mission["seed"], mission["simulation"]["seed"]) == (1, 2)


def test_a_restarted_batch_forgets_the_plans_of_the_batch_it_replaces(spec_path, tmp_path):
    spec = read_spec(spec_path)
    record = batch_record(spec, load_context(spec))
    (tmp_path / PLANS).mkdir()
    (tmp_path / PLANS / "0123.npz").write_bytes(b"a plan of another batch")

    begin(tmp_path, record, restart=False, rows=[])
    assert (tmp_path / PLANS / "0123.npz").is_file()
    begin(tmp_path, record, restart=True, rows=[])

    assert not (tmp_path / PLANS).exists()
    assert json.loads((tmp_path / "batch.json").read_text()) == record


def test_a_batch_folder_written_before_the_simulation_seeds_resumes(tmp_path):
    # written by the batch command of quadnav before the simulation had seeds of its own
    # and rows said which plan they flew, stopped after 2 of its 3 missions
    folder = tmp_path / "previous"
    shutil.copytree(PREVIOUS_BATCH, folder)
    previous = read_rows(folder / "results.csv")
    assert json.loads((folder / "batch.json").read_text())["columns"] == list(PREVIOUS_NAMES)
    # and before the stall rule: its searches ran their whole improve budget
    spec = folder / "spec.toml"
    spec.write_text(spec.read_text() + "stall = 0\n")

    result = run_here("batch", spec, "--workers", "1", "--quiet", "-o", folder)

    assert result.returncode == 0, result.stderr
    assert f"3 missions, 2 already in {folder}; flying 1 on" in result.stdout
    assert json.loads((folder / "batch.json").read_text())["columns"] == list(NAMES)
    rows = read_rows(folder / "results.csv")
    assert (folder / "results.csv").read_text().startswith(",".join(NAMES))
    assert [r["sim_seed"] for r in rows] == [0, 1, 2]
    assert [r["plan_key"] is None for r in rows] == [True, True, False]
    for old, new in zip(previous, rows, strict=False):
        assert same_row(new, old | {"sim_seed": old["seed"]}, ignore=())
    assert same_row(rows[2], _alone(folder / "spec.toml")[2])
    last = run_here("batch", folder / "spec.toml", "--quiet", "-o", folder)
    assert "3 missions, all already in" in last.stdout


def test_a_batch_folder_written_before_the_time_to_goal_resumes(tmp_path):
    # written by the batch command of quadnav before rows had the flown time to goal,
    # stopped after 2 of its 3 missions
    folder = tmp_path / "untimed"
    shutil.copytree(UNTIMED_BATCH, folder)
    untimed = read_rows(folder / "results.csv")
    assert json.loads((folder / "batch.json").read_text())["columns"] == list(UNTIMED_NAMES)
    assert [(r["reached_goal"], r["time_to_goal_s"]) for r in untimed] == [(True, None)] * 2

    result = run_here("batch", folder / "spec.toml", "--workers", "1", "--quiet", "-o",
                      folder)

    assert result.returncode == 0, result.stderr
    assert f"3 missions, 2 already in {folder}; flying 1 on" in result.stdout
    assert json.loads((folder / "batch.json").read_text())["columns"] == list(NAMES)
    rows = read_rows(folder / "results.csv")
    assert (folder / "results.csv").read_text().startswith(",".join(NAMES))
    for old, new in zip(untimed, rows, strict=False):  # kept as flown: no time to goal
        assert same_row(new, old, ignore=())
    spec = read_spec(folder / "spec.toml")
    assert same_row(rows[2], flown_row(load_context(spec), spec.missions()[2]))
    assert rows[2]["reached_goal"] and 0 < rows[2]["time_to_goal_s"] < rows[2]["flight_time_s"]
    last = run_here("batch", folder / "spec.toml", "--quiet", "-o", folder)
    assert "3 missions, all already in" in last.stdout


def test_tune_plans_its_missions_that_share_a_plan_once(tmp_path):
    path = tmp_path / "set.toml"
    path.write_text(f"maps = ['{WINDOW}']\nseeds = [0]\nspeeds = [1.0]\ngusts = [0.0, 0.02]\n"
                    "improve = 500\nspreads = [0.0, 0.1]\n")
    cache = StageCache()

    vehicle = load_params("tello")
    items = set_items(read_set(path, "tello"), vehicle, controller_gains("cascade", vehicle), cache)

    assert len(items) == 4 and (cache.made["plan"], cache.made["reference"]) == (1, 1)
    assert len({id(item.reference) for item in items}) == 1
    assert [item.settings.gust_std for item in items] == [0.0, 0.0, 0.02, 0.02]
    assert [item.plant is None for item in items] == [True, False, True, False]


def test_a_world_inflates_and_labels_its_free_space_once_per_margin():
    world = load_world(WINDOW)
    inflated = world.inflate(0.2)

    assert world.inflate(0.2) is inflated and world.inflate(0.3) is not inflated
    assert np.array_equal(inflated.blocks, world.blocks + np.r_[[-0.2] * 3, [0.2] * 3])
    labels, _ = unblocked_components(inflated, 1000)
    assert unblocked_components(inflated, 1000)[0] is labels
    fresh = pickle.loads(pickle.dumps(inflated))  # a worker's copy carries none of them
    assert "_inflated" not in pickle.loads(pickle.dumps(world)).__dict__
    assert np.array_equal(unblocked_components(fresh, 1000)[0], labels)
    assert not disconnected(inflated, world.start, world.goal, 1000)


def test_a_map_grows_its_blocks_for_a_body_and_for_legs_once():
    world = load_world(WINDOW)
    half = np.array([0.1, 0.1, 0.05])
    grid = body_grid(world, half)
    legs = SafeSpace(world, 0.2).legs_world

    assert body_grid(world, half.copy()) is grid and body_grid(world, 2 * half) is not grid
    assert np.array_equal(grid[0], body_grid(load_world(WINDOW), half)[0])
    assert SafeSpace(world, 0.3).legs_world is legs
    assert np.array_equal(legs.blocks, leg_world(world).blocks)
    assert np.array_equal(legs.boundary, leg_world(world).boundary)


def test_missions_that_fly_one_trajectory_measure_its_margins_once(spec_path):
    spec = read_spec(spec_path)
    context = load_context(spec)
    cache = StageCache()
    first, second = (fly_mission_spec(context, m, cache) for m in spec.missions()[:2])
    world = context.worlds[WINDOW]

    assert second.trajectory is first.trajectory
    assert reference_margins(first.trajectory, world) is reference_margins(
        second.trajectory, world)
    assert reference_margins(first.trajectory, world) == trajectory_margins(first.trajectory,
                                                                            world)
    assert first.metrics()["trajectory_margin_m"] == second.metrics()["trajectory_margin_m"]

"""The planning bench's compiled OMPL driver (bench/ompl_rrtstar.cpp) plans real paths,
and our planner reports its set-up apart from the search, as the driver does."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

from quadnav.planning import PlannerSettings, make_problem, plan
from quadnav.world import load_world

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "bench"))
from compiled_ompl import compiled_ompl, run_compiled, write_problem


@pytest.fixture(scope="module")
def driver() -> Path:
    binary, why_not = compiled_ompl()
    if binary is None:
        pytest.skip(f"compiled OMPL: {why_not}")
    return binary


def test_compiled_ompl_finds_the_forest_path_and_repeats_it_for_a_seed(driver, tmp_path):
    world = load_world("forest")
    problem = make_problem(world, world.start, world.goal, world.margin)
    problem_file = tmp_path / "problem.txt"
    write_problem(problem, PlannerSettings(), problem_file)

    first = run_compiled(driver, problem_file, problem, seed=4, limit=5.0)
    again = run_compiled(driver, problem_file, problem, seed=4, limit=5.0)

    straight = float(np.linalg.norm(world.goal - world.start))
    assert 0 < first.first < 5.0 and first.setup > 0
    assert straight <= first.length < 2 * straight
    assert again.length == first.length


def test_compiled_ompl_reports_no_path_through_a_closed_wall(driver, tmp_path):
    world = load_world("forest")
    problem = make_problem(world, world.start, world.goal, world.margin)
    problem_file = tmp_path / "problem.txt"
    write_problem(problem, PlannerSettings(), problem_file)
    header = problem_file.read_text().splitlines()[0].split()
    header[-1] = "1"  # one block: a wall across the whole map halfway from start to goal
    lower, upper = problem.free_world.lower, problem.free_world.upper
    wall = [9.0, lower[1] - 1, lower[2] - 1, 11.0, upper[1] + 1, upper[2] + 1]
    problem_file.write_text(" ".join(header) + "\n" + " ".join(f"{v:g}" for v in wall) + "\n")

    run = run_compiled(driver, problem_file, problem, seed=0, limit=0.3)

    assert math.isinf(run.first) and math.isinf(run.length)


def test_our_first_solution_is_timed_after_the_set_up():
    world = load_world("forest")
    problem = make_problem(world, world.start, world.goal, world.margin)

    stats = plan(problem, PlannerSettings(seed=2, stop_at_first=True), "rrtstar").stats

    assert stats.setup_seconds > 0
    assert 0 < stats.time_to_first <= stats.seconds

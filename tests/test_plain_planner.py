"""Plain-Python planners, ``function(world, start, goal, margin) -> path (N, 3)``, named
``file.py:function`` or ``module:function`` beside the registered planners: what they
return is checked exactly and a path at fault is reported, segment and place, never
flown; an exception in them shows its own traceback once."""

from __future__ import annotations

import json
import pickle
from pathlib import Path

import numpy as np
import pytest
from clitools import assert_user_error, run, run_here

from quadnav.errors import QuadnavError
from quadnav.mission import MissionSettings, fly_mission
from quadnav.planning import PlannerSettings, get_planner, make_problem, plan
from quadnav.plugins import PluginError
from quadnav.world import World, load_world

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "plain_planner.py"
GRID_FOREST = ("course:meam620/grid_forest", "--start", "1.25", "1.25", "1",
               "--goal", "3.25", "5.25", "1.5")

PLANNERS = '''
import numpy as np

def straight(world, start, goal, margin):
    return np.stack([start, goal])

def via(world, start, goal, margin, y=1.0, z=None):
    """Across to ``y`` (and up or down to ``z``), along, and back to the goal."""
    return [start, [start[0], y, start[2] if z is None else z],
            [goal[0], y, goal[2] if z is None else z], goal]

def given(world, start, goal, margin, points=()):
    return points

def seeded(world, start, goal, margin, seed=None):
    rng = np.random.default_rng(seed)
    middle = (start + goal) / 2 + [0.0, rng.uniform(0.6, 1.0), 0.0]  # beside the pillar
    return [start, middle, goal]

def nothing(world, start, goal, margin):
    return None

def helper(x):
    return x / 0

def broken(world, start, goal, margin):
    return helper(margin)
'''


@pytest.fixture
def planners(tmp_path) -> Path:
    path = tmp_path / "my_planners.py"
    path.write_text(PLANNERS)
    return path


@pytest.fixture
def pillar():
    """The pillar in rotorpy's world, [-1, -0.75] x [-0.125, 0.125] x [-0.5, 3], between a
    start and a goal 7 m apart; the 0.2 m margin."""
    return make_problem(load_world("course:rotorpy/pillar"), (-4, 0, 1.5), (3, 0, 1.5), 0.2)


def test_a_plain_function_plans_and_its_path_runs_from_the_start_to_the_goal(planners, pillar):
    result = plan(pillar, PlannerSettings(seed=4), f"{planners}:seeded")
    assert result.solved and result.planner == f"{planners}:seeded" and result.seed == 4
    assert result.path[0].tolist() == [-4, 0, 1.5] and result.path[-1].tolist() == [3, 0, 1.5]
    aside = result.path[1, 1]
    assert 0.6 <= aside <= 1.0  # the seed reached the function: the same seed, the same path
    assert plan(pillar, PlannerSettings(seed=4), f"{planners}:seeded").path[1, 1] == aside
    assert plan(pillar, PlannerSettings(seed=5), f"{planners}:seeded").path[1, 1] != aside


def test_a_plain_function_is_called_even_when_the_goal_is_in_sight(planners):
    world = World(np.array([0, 0, 0, 10, 10, 5.0]))
    problem = make_problem(world, (1, 1, 1), (9, 1, 1), 0.2)
    assert plan(problem, planner="rrtstar").stats.stopped_by == "direct"
    result = plan(problem, planner=f"{planners}:via(y=2)")
    assert result.solved and len(result.path) == 4 and result.path[1].tolist() == [1, 2, 1]


@pytest.mark.parametrize(("spec", "fault"), [
    ("straight", "returned a path whose segment 0 from (-4, 0, 1.5) to (3, 0, 1.5) passes "
                 "through block 0 [-1, -0.75] x [-0.125, 0.125] x [-0.5, 3], entering it at "
                 "(-1, 0, 1.5)"),
    ("via(y=0, z=2.9)", "returned a path whose segment 0 from (-4, 0, 1.5) to (-4, 0, 2.9) "
                         "comes within the 0.2 m margin of the boundary at (-4, 0, 2.8), "
                         "keeping 0.1 m"),
    ("via(y=0, z=3.5)", "returned a path whose segment 0 from (-4, 0, 1.5) to (-4, 0, 3.5) "
                         "leaves the map [-10, 10] x [-10, 10] x [-0.5, 3] at (-4, 0, 3)"),
    ("given(points=[[-4, 0, 1.5], [-1.1, 0.3, 1.5], [3, 0, 1.5]])",
     "returned a path whose segment 0 from (-4, 0, 1.5) to (-1.1, 0.3, 1.5) comes within the "
     "0.2 m margin of block 0 [-1, -0.75] x [-0.125, 0.125] x [-0.5, 3] at (-1.2, 0.2897, "
     "1.5), keeping 0.168 m"),
    ("given(points=[[-4, 0, 1.6], [-4, 3, 1.5], [3, 3, 1.5], [3, 0, 1.5]])",
     "returned a path that starts at (-4, 0, 1.6), not at the start of the search "
     "(-4, 0, 1.5) (within 1 um)"),
    ("given(points=[[-4, 0, 1.5], [-4, 3, 1.5], [3, 3, 1.5]])",
     "returned a path that ends at (3, 3, 1.5), not at the goal of the search (3, 0, 1.5) "
     "(within 1 um)"),
    ("given(points=[-4, 0, 1.5])", "returned an array of shape (3,): expected a path (N, 3), "
                                   "2 <= N <= 100,000"),
    ("given(points=[[-4, 0, 1.5], [0, 0, None], [3, 0, 1.5]])",
     "returned point 1 (0, 0, nan): expected finite numbers"),
    ("given(points='north')", "returned str 'north': expected a path, an array (N, 3) of "
                              "numbers"),
    ("given(points=[[-4, 0, 1.5], [3, 0]])", "returned list '[[-4, 0, 1.5], [3, 0]]': expected "
                                            "a path, an array (N, 3) of numbers"),
    ("nothing", "found no path (it returned None)"),
    ("given(points=[])", "found no path (it returned an empty path)"),
])
def test_what_a_plain_function_returns_is_checked_exactly(planners, pillar, spec, fault):
    result = plan(pillar, planner=f"{planners}:{spec}")
    assert not result.solved and len(result.path) == 0
    assert result.message == f"planner {planners}:{spec} {fault}"


def test_a_path_within_a_micrometre_of_the_ends_is_moved_onto_them(planners, pillar):
    near = "[[-4, 0, 1.5000004], [-4, 3, 1.5], [3, 3, 1.5], [3.0000005, 0, 1.5]]"
    result = plan(pillar, planner=f"{planners}:given(points={near})")
    assert result.solved and result.path[0].tolist() == [-4, 0, 1.5]
    assert result.path[-1].tolist() == [3, 0, 1.5]


@pytest.mark.filterwarnings("ignore:start .* is inside the 0.2 m safety margin")
def test_legs_out_of_the_margin_are_added_around_a_plain_path(planners):
    world = load_world("course:rotorpy/pillar")
    problem = make_problem(world, (-9.9, 0, 1.5), (3, 0, 1.5), 0.2)  # 0.1 m from the wall
    result = plan(problem, planner=f"{planners}:via(y=1)")
    assert result.solved and result.path[0].tolist() == [-9.9, 0, 1.5]
    assert np.array_equal(result.path[1], problem.search_start)
    assert result.path[2].tolist() == [problem.search_start[0], 1, 1.5]


def test_a_plain_planner_in_a_mission_flies_and_its_settings_pickle(planners):
    settings = MissionSettings(planner=f"{planners}:via(y=1)")
    mission = fly_mission(load_world("course:rotorpy/pillar"), (-4, 0, 1.5), (3, 0, 1.5),
                          settings=pickle.loads(pickle.dumps(settings)))
    metrics = mission.metrics()
    assert metrics["success"] and metrics["planner"] == f"{planners}:via(y=1)"
    assert metrics["flight_margin_m"] > 0.15


def test_names_and_arguments_that_cannot_be_used_are_refused(planners):
    with pytest.raises(QuadnavError, match=r"has no 'astar' \(it defines broken, given"):
        get_planner(f"{planners}:astar")
    with pytest.raises(QuadnavError, match=r": cannot be called as via\(world, start, goal, "
                                           r"margin, x=\.\.\.\): got an unexpected "
                                           "keyword argument 'x'"):
        get_planner(f"{planners}:via(x=2)")
    with pytest.raises(QuadnavError, match=r"unknown planner 'astar'; expected one of rrtstar"
                                           r".*, or module:FUNCTION or path/to/file.py:"):
        get_planner("astar")


def test_an_exception_in_a_plain_planner_fails_the_plan_with_its_own_traceback(planners,
                                                                              pillar):
    with pytest.raises(PluginError) as caught:
        plan(pillar, planner=f"{planners}:broken")
    error = caught.value
    assert str(error) == f"planner {planners}:broken raised ZeroDivisionError: float division by zero"
    assert error.exit_code == 1
    assert error.details.splitlines()[0] == "Traceback (most recent call last):"
    assert "return helper(margin)" in error.details and "return x / 0" in error.details
    assert "quadnav" not in error.details.replace(str(planners.parent), "")


def test_fly_and_plan_report_a_path_at_fault_in_one_line_and_never_fly_it(planners, tmp_path):
    spec = f"{planners}:via(y=0, z=2.7)"
    where = ("course:rotorpy/pillar", "--start", "-4", "0", "1.5", "--goal", "3", "0", "1.5")
    fault = (f"planner {spec} returned a path whose segment 1 from (-4, 0, 2.7) to (3, 0, 2.7) "
             "passes through block 0 [-1, -0.75] x [-0.125, 0.125] x [-0.5, 3], entering it at "
             "(-1, 0, 2.7)")
    flown = run_here("fly", *where, "--planner", spec, "--no-figures", "--quiet",
                     "-o", tmp_path / "fly")
    assert flown.returncode == 1
    assert flown.stderr.strip() == f"quadnav: flight failed: no path: {fault}"
    assert not (tmp_path / "fly" / "flight.csv").exists()
    assert json.loads((tmp_path / "fly" / "metrics.json").read_text())["path_found"] is False
    planned = run_here("plan", *where, "--planner", spec, "--no-figures", "--quiet",
                       "-o", tmp_path / "plan")
    assert planned.returncode == 1 and planned.stderr.strip() == f"quadnav: no path: {fault}"


def test_the_command_line_shows_a_plain_planners_traceback_once_and_refuses_bad_names(
        planners, tmp_path):
    where = ("course:rotorpy/pillar", "--start", "-4", "0", "1.5", "--goal", "3", "0", "1.5")
    broken = run("plan", *where, "--planner", f"{planners}:broken", "--no-figures",
                 "--quiet", "-o", tmp_path / "broken")
    assert broken.returncode == 1, broken
    lines = broken.stderr.strip().splitlines()
    assert lines[0] == "Traceback (most recent call last):" and broken.stderr.count(
        "Traceback") == 1
    assert lines[-1] == (f"quadnav: error: planner {planners}:broken raised "
                         "ZeroDivisionError: float division by zero")
    assert_user_error(run_here("fly", *where, "--planner", f"{planners}:astar", "-o",
                               tmp_path / "no"), f"{planners}:astar: ", "has no 'astar'")
    assert not (tmp_path / "no").exists()


def test_the_example_graph_search_flies_a_course_map_from_the_command_line(tmp_path):
    spec = f"{EXAMPLE}:graph_search(resolution=0.25)"
    result = run("fly", *GRID_FOREST, "--planner", spec, "--no-figures", "--quiet",
                 "-o", tmp_path / "fly")
    assert result.returncode == 0, result.stderr
    metrics = json.loads((tmp_path / "fly" / "metrics.json").read_text())
    assert metrics["success"] and metrics["planner"] == spec
    assert metrics["flight_margin_m"] >= 0.19 and metrics["collision"] is False

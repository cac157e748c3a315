"""A quadrotor kinodynamic plan flown closed loop (quadnav.kinoflight, kino quadrotor --fly):
the trajectory is the plan itself, the flight is measured as a fly run is, and the run
folder is one every viewer reads."""

from __future__ import annotations

import json

import numpy as np
import pytest

from quadnav.cli.main import main
from quadnav.errors import PlanningWarning, QuadnavError
from quadnav.kinodynamic.pointmass import SampledQuadrotor
from quadnav.kinodynamic.quadrotor import plan_quadrotor
from quadnav.kinodynamic.result import KinoResult
from quadnav.kinodynamic.settings import KinoSettings
from quadnav.kinoflight import fly_kino_plan, plan_trajectory
from quadnav.runs import read_run
from quadnav.sim.settings import SimSettings
from quadnav.world import World, load_world

MODEL = SampledQuadrotor()


def _plan(world_spec: str, seed: int, start=None, **budget):
    world = load_world(world_spec)
    start = world.start if start is None else np.array(start, dtype=np.float64)
    settings = KinoSettings(seed=seed, **budget)
    result = plan_quadrotor(world, start, world.goal, settings, MODEL, 0.2)
    assert result.solved, result.message
    return world.replace(start=start, margin=0.2), result, settings


def test_the_trajectory_is_the_plan_ending_at_rest_at_the_goal():
    world, result, _ = _plan("forest", 3)
    trajectory = plan_trajectory(result, MODEL)
    times = np.concatenate([[0.0], np.cumsum(result.durations)])
    assert np.allclose(trajectory.breaks, times, atol=1e-12)
    assert np.abs(trajectory.position(times) - result.states[:, :3]).max() < 1e-9
    assert np.abs(trajectory.velocity(times) - result.states[:, 3:]).max() < 1e-9
    middles = times[:-1] + 0.5 * result.durations  # each control's own acceleration
    planned = np.array([MODEL.acceleration(control) for control in result.controls])
    assert np.abs(trajectory.acceleration(middles) - planned).max() < 1e-9
    # The last two controls are the closing stop: from the goal region to rest at the goal.
    assert np.linalg.norm(result.states[-3, 3:]) > 0.1  # the tree reaches it moving ...
    assert np.allclose(trajectory.position(trajectory.duration), world.goal, rtol=0,
                       atol=1e-12)  # ... and the trajectory stops exactly on the goal
    assert np.allclose(trajectory.velocity(trajectory.duration), 0.0, atol=1e-12)
    assert trajectory.info["stop_s"] == pytest.approx(result.durations[-2:].sum())


def test_the_leg_out_of_the_margin_is_the_trajectorys_start_leg():
    world, result, _ = _plan("forest", 0, start=[0.1, 0.1, 1.0])  # 0.1 m from two walls
    assert result.leg_controls >= 2
    trajectory = plan_trajectory(result, MODEL)
    assert trajectory.leg_segments == (result.leg_controls, 0)
    flown = fly_kino_plan(world, result, MODEL, KinoSettings(seed=0))
    metrics = flown.metrics()
    assert metrics["success"]
    assert metrics["trajectory_leg_margin_m"] < 0.2 <= metrics["trajectory_margin_m"] + 1e-9


def test_a_goal_in_the_margin_is_reached_by_its_leg_after_the_closing_stop():
    world = load_world("forest")
    goal = np.array([19.9, 19.9, 3.0])  # 0.1 m from two walls
    with pytest.warns(PlanningWarning, match=r"goal \(19.9, 19.9, 3\) is inside the 0.22 m"):
        result = plan_quadrotor(world, world.start, goal, KinoSettings(), MODEL, 0.2)
    assert result.solved and result.closing_controls == 2 and result.goal_leg_controls >= 2
    assert np.array_equal(result.states[-1], [*goal, 0, 0, 0])
    trajectory = plan_trajectory(result, MODEL)
    assert trajectory.leg_segments == (0, result.goal_leg_controls)
    flown = fly_kino_plan(world.replace(goal=goal, margin=0.2), result, MODEL, KinoSettings())
    metrics = flown.metrics()
    assert metrics["success"] and metrics["reached_goal"]
    assert np.linalg.norm(flown.flight.position[-1] - goal) < 0.1  # radius 0.5 m
    assert metrics["trajectory_leg_margin_m"] < 0.2 <= metrics["trajectory_margin_m"] + 1e-9


def test_a_plan_that_does_not_end_at_rest_at_the_goal_is_not_flown():
    """The planner ends every plan at rest on the goal; a plan from elsewhere that does not
    is refused, not flown to wherever it stops."""
    world = World(np.array([0.0, 0, 0, 10, 10, 5]), np.zeros((0, 6)), start=[1.0, 5, 2],
                  goal=[3.0, 5, 2], margin=0.1)
    moving = np.array([[1.0, 5, 2, 0, 0, 0], [2.0, 5, 2, 2, 0, 0]])  # 1 m at 2 m/s^2
    result = KinoResult("quadrotor", True, moving, [MODEL.control_for([2.0, 0, 0])], [1.0],
                        moving, [-1, 0], np.zeros((2, 3)), [0.0, 1.0], 1, 0.0, 0.0, 0)
    with pytest.raises(QuadnavError, match=r"the plan ends at \(2, 5, 2\) moving at "
                                           r"2.00 m/s; a plan to fly must end at rest"):
        fly_kino_plan(world, result, MODEL, KinoSettings())
    resting = np.array([[1.0, 5, 2, 0, 0, 0], [1.25, 5, 2, 1, 0, 0], [1.5, 5, 2, 0, 0, 0]])
    controls = [MODEL.control_for([2.0, 0, 0]), MODEL.control_for([-2.0, 0, 0])]
    result = KinoResult("quadrotor", True, resting, controls, [0.5, 0.5], resting,
                        [-1, 0, 1], np.zeros((3, 3)), [0.0, 0.5, 0.5], 1, 0.0, 0.0, 0)
    with pytest.raises(QuadnavError, match=r"the plan ends at \(1.5, 5, 2\), not at the "
                                           r"goal \(3, 5, 2\)"):
        fly_kino_plan(world, result, MODEL, KinoSettings())
    assert fly_kino_plan(world.replace(goal=[1.5, 5, 2]), result, MODEL,
                         KinoSettings()).success


def test_a_flight_that_ends_outside_the_goal_tolerance_is_not_reached():
    """Judged against the goal asked for: with a 1 mm tolerance the flight, which ends a
    few millimetres from the goal, has not reached it, and says so."""
    world, result, settings = _plan("forest", 0)
    flown = fly_kino_plan(world, result, MODEL, settings, settings=SimSettings(
        goal_tolerance=0.001))
    metrics = flown.metrics()
    distance = float(np.linalg.norm(flown.flight.position[-1] - world.goal))
    assert 0.002 < distance < 0.05
    assert metrics["final_error_m"] == pytest.approx(distance, abs=1e-9)
    assert metrics["ending"] == "completed"
    assert not metrics["reached_goal"] and not metrics["success"] and not flown.success
    assert metrics["goal_tolerance_m"] == 0.001


@pytest.mark.parametrize("world_spec", ["empty", "forest"])
def test_plans_on_the_built_in_worlds_fly_closed_loop_over_ten_seeds(world_spec):
    """Every seed 0-9 (the window and the maze, whose plans take seconds to tens of seconds
    each, are flown over the same seeds by bench/kino_fly.py)."""
    for seed in range(10):
        world, result, settings = _plan(world_spec, seed, max_iterations=100_000)
        flown = fly_kino_plan(world, result, MODEL, settings)
        metrics = flown.metrics()
        assert metrics["success"], (seed, metrics["ending"], metrics["final_error_m"])
        # Judged against the goal asked for, with the goal radius, and well inside it.
        assert metrics["goal_tolerance_m"] == settings.goal_radius == 0.5
        distance = float(np.linalg.norm(flown.flight.position[-1] - world.goal))
        assert metrics["reached_goal"] and distance < 0.05
        assert metrics["final_error_m"] == pytest.approx(distance, abs=1e-9)
        assert not metrics["collision"]
        assert metrics["min_clearance_m"] is None or metrics["min_clearance_m"] > 0.05
        assert 0.01 < metrics["rms_tracking_error_m"] < 0.08
        assert metrics["trajectory_margin_m"] >= 0.2 - 1e-9 or world_spec == "empty"
        assert metrics["rotor_energy_j"] > 0


def test_kino_fly_writes_the_run_folder_fly_writes(tmp_path, capsys):
    out = tmp_path / "kino"
    code = main(["kino", "quadrotor", "forest:seed=1", "--fly", "--controller", "se3",
                 "--quiet", "-o", str(out)])
    printed = capsys.readouterr().out
    assert code == 0, printed
    assert "flown closed loop by the se3 controller on the tello vehicle: success" in printed
    kino = json.loads((out / "kino.json").read_text())
    assert kino["flight"]["success"] and kino["flight"]["rotor_energy_j"] > 0
    run = read_run(out / "flight")
    assert run.metrics["controller"] == "se3"
    assert run.metrics["rms_tracking_error_m"] == kino["flight"]["rms_tracking_error_m"]
    assert run.trajectory is not None and run.flight is not None
    assert np.allclose(run.path, np.loadtxt(out / "states.csv", delimiter=",", skiprows=1)[:, 1:4])
    assert len(run.tree_nodes) == kino["nodes"]
    for name in ("flight_3d.png", "tracking_error.png", "report.html"):
        assert (out / "flight" / name).stat().st_size > 1000


def test_kino_fly_without_figures_writes_the_rest_and_no_earlier_figures_stay(tmp_path, capsys):
    out = tmp_path / "kino"
    (out / "flight").mkdir(parents=True)
    for name in ("kino.png", "controls.png", "flight/flight_3d.png", "flight/report.html"):
        (out / name).write_text("an earlier run's")
    assert main(["kino", "quadrotor", "forest:size=8x8x3,seed=1", "--fly", "--no-figures",
                 "--quiet", "-o", str(out)]) == 0
    printed = capsys.readouterr().out.splitlines()
    assert printed[-1].startswith(f"wrote {out / 'flight' / 'metrics.json'}, ")
    assert sorted(path.name for path in out.iterdir()) == [
        "controls.csv", "flight", "kino.json", "states.csv"]
    assert not [path.name for path in (out / "flight").iterdir() if path.suffix in (".png", ".html")]
    assert read_run(out / "flight").flight is not None


@pytest.mark.parametrize("which", ["forest", "test_window"])
def test_kino_fly_ends_within_the_goal_radius_of_the_goal_asked_for(which, tmp_path, capsys,
                                                                     request):
    """The flights a user found stopping 0.58 m (forest) and 0.81 m (test_window) from the
    goal, reported as reaching it: the closing stop now ends on the goal, and the verdict
    is the distance from it."""
    spec = ("forest" if which == "forest" else
            str(request.getfixturevalue("shared_maps") / "meam620" / "test_window.json"))
    goal = load_world(spec).goal
    out = tmp_path / "kino"
    code = main(["kino", "quadrotor", spec, "--fly", "--no-figures", "--quiet", "-o", str(out)])
    printed = capsys.readouterr().out
    assert code == 0, printed
    run = read_run(out / "flight")
    distance = float(np.linalg.norm(run.flight.position[-1] - goal))
    assert distance < 0.05  # the goal radius is 0.5 m
    assert "success" in printed and "s stop at the goal)" in printed
    metrics = run.metrics
    assert metrics["goal"] == goal.tolist() and metrics["goal_tolerance_m"] == 0.5
    assert metrics["reached_goal"] and metrics["success"]
    assert metrics["final_error_m"] == pytest.approx(distance, abs=1e-6)
    assert metrics["goal_distance_m"] == pytest.approx(distance, abs=1e-6)
    assert json.loads((out / "kino.json").read_text())["flight"]["reached_goal"]


def test_a_kino_flight_short_of_the_margin_says_so_and_strict_fails_it(tmp_path, capsys):
    # window (seed 0): the flight keeps 0.168 m of the 0.2 m margin, 32 mm short
    code = main(["kino", "quadrotor", "window", "--fly", "--no-figures", "--quiet", "--strict",
                 "-o", str(tmp_path / "kino")])
    err = capsys.readouterr().err.splitlines()
    metrics = json.loads((tmp_path / "kino" / "flight" / "metrics.json").read_text())
    assert metrics["margin_shortfall_m"] > 0.02
    assert code == 1
    assert err[-2].startswith(f"quadnav: warning: the flight kept only "
                              f"{metrics['flight_margin_m']:.3f} m of the 0.2 m margin asked")
    assert err[-1] == "quadnav: flight failed: it kept less margin than asked (--strict)"


def test_a_bad_vehicle_file_is_refused_before_planning(tmp_path, capsys):
    out = tmp_path / "kino"
    code = main(["kino", "quadrotor", "forest", "--fly", "--params", str(tmp_path / "no.toml"),
                 "-o", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and "no.toml" in err and len(err.strip().splitlines()) == 1
    assert not out.exists()

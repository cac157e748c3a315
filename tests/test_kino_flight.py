"""A quadrotor kinodynamic plan flown closed loop (quadnav.kinoflight, kino quadrotor --fly):
the trajectory is the plan itself, the flight is measured as a fly run is, and the run
folder is one every viewer reads."""

from __future__ import annotations

import json

import numpy as np
import pytest

from quadnav.cli.main import main
from quadnav.errors import QuadnavError
from quadnav.kinodynamic.pointmass import SampledQuadrotor
from quadnav.kinodynamic.quadrotor import plan_quadrotor
from quadnav.kinodynamic.result import KinoResult
from quadnav.kinodynamic.settings import KinoSettings
from quadnav.kinoflight import STOP_ACCELERATION, fly_kino_plan, plan_trajectory
from quadnav.runs import read_run
from quadnav.world import World, load_world

MODEL = SampledQuadrotor()


def _plan(world_spec: str, seed: int, start=None, **budget):
    world = load_world(world_spec)
    start = world.start if start is None else np.array(start, dtype=np.float64)
    settings = KinoSettings(seed=seed, **budget)
    result = plan_quadrotor(world, start, world.goal, settings, MODEL, 0.2)
    assert result.solved, result.message
    return world.replace(start=start, margin=0.2), result, settings


def test_the_trajectory_is_the_plan_then_a_straight_stop():
    _, result, _ = _plan("forest", 3)
    trajectory = plan_trajectory(result, MODEL)
    times = np.concatenate([[0.0], np.cumsum(result.durations)])
    assert np.allclose(trajectory.breaks[:-1], times, atol=1e-12)
    assert np.abs(trajectory.position(times) - result.states[:, :3]).max() < 1e-9
    assert np.abs(trajectory.velocity(times[:-1]) - result.states[:-1, 3:]).max() < 1e-9
    middles = times[:-1] + 0.5 * result.durations  # each control's own acceleration
    planned = np.array([MODEL.acceleration(control) for control in result.controls])
    assert np.abs(trajectory.acceleration(middles) - planned).max() < 1e-9
    end_velocity = result.states[-1, 3:]
    speed = np.linalg.norm(end_velocity)
    assert speed > 0.1  # the plan ends moving ...
    stop_time = trajectory.duration - times[-1]
    braking = trajectory.acceleration(times[-1] + 0.5 * stop_time)
    assert np.allclose(np.cross(braking, end_velocity), 0.0, atol=1e-9)
    assert braking @ end_velocity < 0 and np.linalg.norm(braking) <= STOP_ACCELERATION
    assert MODEL.control_for(braking) is not None
    assert stop_time == pytest.approx(speed / np.linalg.norm(braking))
    assert np.allclose(trajectory.velocity(trajectory.duration - 1e-9), 0.0, atol=1e-6)
    stopped = trajectory.position(trajectory.duration)  # ... and stops straight ahead
    assert np.allclose(stopped - result.states[-1, :3], 0.5 * end_velocity * stop_time)


def test_the_leg_out_of_the_margin_is_the_trajectorys_start_leg():
    world, result, _ = _plan("forest", 0, start=[0.1, 0.1, 1.0])  # 0.1 m from two walls
    assert result.leg_controls >= 2
    trajectory = plan_trajectory(result, MODEL)
    assert trajectory.leg_segments == (result.leg_controls, 0)
    flown = fly_kino_plan(world, result, MODEL, KinoSettings(seed=0))
    metrics = flown.metrics()
    assert metrics["success"]
    assert metrics["trajectory_leg_margin_m"] < 0.2 <= metrics["trajectory_margin_m"] + 1e-9


def test_a_plan_whose_stop_would_reach_a_block_is_refused():
    """A plan that ends moving at 2 m/s towards a wall 0.5 m ahead: the stop needs 0.67 m."""
    world = World(np.array([0.0, 0, 0, 10, 10, 5]), np.array([[2.5, 0, 0, 4, 10, 5]]),
                  margin=0.1)
    states = np.array([[1.0, 5, 2, 0, 0, 0], [2.0, 5, 2, 2, 0, 0]])  # 1 m at 2 m/s^2
    result = KinoResult("quadrotor", True, states, [MODEL.control_for([2.0, 0, 0])], [1.0],
                        states, [-1, 0], np.zeros((2, 3)), [0.0, 1.0], 1, 0.0, 0.0, 0)
    with pytest.raises(QuadnavError, match=r"ends at \(2, 5, 2\) moving at 2.00 m/s, and "
                                           r"the 0.67 m it needs to stop do not keep the "
                                           r"0.1 m margin"):
        plan_trajectory(result, MODEL, world)
    assert plan_trajectory(result, MODEL, world.replace(blocks=np.zeros((0, 6)), colors=None)).duration > 1


@pytest.mark.parametrize("world_spec", ["empty", "forest"])
def test_plans_on_the_built_in_worlds_fly_closed_loop_over_ten_seeds(world_spec):
    """Every seed 0-9 (the window and the maze, whose plans take seconds to tens of seconds
    each, are flown over the same seeds by bench/kino_fly.py)."""
    for seed in range(10):
        world, result, settings = _plan(world_spec, seed, max_iterations=100_000)
        flown = fly_kino_plan(world, result, MODEL, settings)
        metrics = flown.metrics()
        assert metrics["success"], (seed, metrics["ending"], metrics["final_error_m"])
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


def test_a_kino_flight_short_of_the_margin_says_so_and_strict_fails_it(tmp_path, capsys):
    # window (seed 0): the flight keeps 0.168 m of the 0.2 m margin, 32 mm short
    code = main(["kino", "quadrotor", "window", "--fly", "--quiet", "--strict",
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

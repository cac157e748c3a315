"""Plain-Python trajectories in rotorpy's shape, ``update(t) -> flat outputs``, named
``module:Class`` or ``file.py:Class``: flown by ``fly`` instead of quadnav's trajectory
stage (built from the planned path) and by ``track``; sampled at the control rate exactly
as ``update`` returns them; the margin they keep measured against the real blocks; a class
that returns what cannot be flown, or raises, is one line (and its own traceback), exit 1;
a name that cannot be used, exit 2. rotorpy's own MinSnap and ThreeDCircularTraj fly
unchanged."""

from __future__ import annotations

import json
import pickle
from pathlib import Path

import numpy as np
import pytest
from clitools import assert_user_error, run, run_here

from quadnav.errors import QuadnavError
from quadnav.mission import MissionSettings, fly_mission
from quadnav.plugins import PluginError, literal_arrays
from quadnav.sim.simulate import reference_table
from quadnav.trajectory.references.builtin import load_reference
from quadnav.trajectory.references.plain import FlatOutputReference
from quadnav.vehicle.quaternion import euler_angles
from quadnav.world import load_world
from quadnav.world.margins import point_margins

minsnap = pytest.importorskip("rotorpy.trajectories.minsnap")

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "plain_trajectory.py"
MINSNAP = "rotorpy.trajectories.minsnap:MinSnap(v_avg=1.5, verbose=False)"
PILLAR = ("course:rotorpy/pillar", "--start", "-4", "0", "1.5", "--goal", "3", "0", "1.5")
CIRCLE = ("rotorpy.trajectories.circular_traj:ThreeDCircularTraj(center=[0, 0, 1.5], "
          "radius=[1, 1, 0], freq=[0.2, 0.2, 0.2], yaw_bool=True)")

CLASSES = '''
import numpy as np


def helper(t):
    return 1.0 / (t - t)


class Spiral:
    """Up a spiral for ``duration`` s, turning at ``turn`` rad/s."""

    def __init__(self, duration=3.0, turn=0.5):
        self.duration, self.turn = duration, turn

    def update(self, t):
        c, s = np.cos(t), np.sin(t)
        return {"x": np.array([c, s, 1 + 0.1 * t]), "x_dot": np.array([-s, c, 0.1]),
                "x_ddot": np.array([-c, -s, 0.0]), "x_dddot": np.zeros(3),
                "yaw": self.turn * t, "yaw_dot": self.turn}


class Forever(Spiral):
    def __init__(self):
        self.turn = 0.5


class NoUpdate:
    duration = 1.0


class Missing(Spiral):
    def update(self, t):
        flat = super().update(t)
        return {"x": flat["x"], "x_dot": flat["x_dot"], "yaw": 0.0}


class Flat(Spiral):
    def update(self, t):
        return super().update(t) | {"x_dot": np.zeros(2)}


class Listed(Spiral):
    def update(self, t):
        return list(super().update(t).values())


class Diverging(Spiral):
    def update(self, t):
        flat = super().update(t)
        if t >= 1.5:
            flat["x_ddot"] = np.array([np.nan, 0.0, 0.0])
        return flat


class Raising(Spiral):
    def update(self, t):
        return helper(t) if t >= 0.5 else super().update(t)


class Unbuilt(Spiral):
    def __init__(self):
        raise RuntimeError("no spiral today")


class WorldTraj:
    """MEAM620's shape: plans for itself from the map, the start and the goal, past the
    pillar when the straight line is blocked, and flies rotorpy's MinSnap through it."""

    def __init__(self, world, start, goal):
        from rotorpy.trajectories.minsnap import MinSnap

        blocked = not world.segments_free(np.array([[start, goal]]))[0]
        self.points = np.array([start, *([[-0.875, 1.0, 1.5]] if blocked else []), goal])
        self.trajectory = MinSnap(self.points, v_avg=1.0, verbose=False)
        self.t_keyframes = self.trajectory.t_keyframes

    def update(self, t):
        return self.trajectory.update(t)


class Elsewhere:
    """Stays 1 m above where a path starts."""

    def __init__(self, points):
        self.start = np.asarray(points[0]) + [0.0, 0.0, 1.0]
        self.duration = 1.0

    def update(self, t):
        zero = np.zeros(3)
        return {"x": self.start, "x_dot": zero, "x_ddot": zero, "yaw": 0.0, "yaw_dot": 0.0}
'''


@pytest.fixture
def classes(tmp_path) -> Path:
    path = tmp_path / "my_trajectories.py"
    path.write_text(CLASSES)
    return path


def test_a_class_is_flown_exactly_as_its_update_returns_at_the_control_rate(classes):
    dt = 0.002
    reference = load_reference(f"{classes}:Spiral(turn=0.25)", dt=dt)
    assert isinstance(reference, FlatOutputReference) and reference.duration == 3.0
    assert reference.info == {"format": "update(t)", "samples": 1501, "sample_interval_s": dt,
                              "duration_s": 3.0, "duration_from": "duration"}
    steps = 1600  # past the end, where it holds still
    table = reference_table(reference, dt, steps)
    t = np.arange(steps) * dt
    flown = t <= 3.0
    c, s = np.cos(t[flown]), np.sin(t[flown])
    expected = np.column_stack([c, s, 1 + 0.1 * t[flown], -s, c, np.full(c.shape, 0.1), -c, -s,
                                np.zeros(c.shape), 0.25 * t[flown], np.full(c.shape, 0.25)])
    assert np.abs(table[flown] - expected).max() < 1e-7  # the yaw rate flown: yaw_dot
    held = table[~flown]
    assert np.array_equal(held[:, 0:3], np.tile(table[flown][-1, 0:3], (len(held), 1)))
    assert not held[:, 3:9].any() and not held[:, 10].any()
    assert load_reference(f"{classes}:Spiral", dt=dt, duration=1.0).duration == 1.0


def test_rotorpys_minsnap_flies_through_a_planned_path_with_its_margin_measured(tmp_path):
    # along the path of the fixed search budget (--stall 0) its tolerances were set on
    result = run_here("fly", *PILLAR, "--reference", MINSNAP, "--stall", "0", "--no-figures",
                      "--quiet", "-o", tmp_path)
    assert result.returncode == 0, result.stderr
    assert result.stdout.startswith(f"course:rotorpy/pillar: success, rrtstar seed 0, vehicle "
                                    f"tello, reference {MINSNAP}\n")
    metrics = json.loads((tmp_path / "metrics.json").read_text())
    parameters = json.loads((tmp_path / "parameters.json").read_text())
    path = np.loadtxt(tmp_path / "path.csv", delimiter=",", skiprows=1)
    rotorpys = minsnap.MinSnap(path, v_avg=1.5, verbose=False)
    assert parameters["reference"] == MINSNAP
    assert parameters["reference_info"]["duration_from"] == "t_keyframes"
    assert metrics["trajectory_duration_s"] == pytest.approx(rotorpys.t_keyframes[-1], abs=1e-12)
    assert metrics["success"] and metrics["collision"] is False
    # The reference written is rotorpy's own, sample for sample, to the accuracy of its QP
    # solver: cvxopt meets its constraints to about 1e-7 of their scale, so the same QP
    # solved in the command and here gave end accelerations 1.4e-7 m/s^2 apart on one CPU.
    table = np.loadtxt(tmp_path / "trajectory.csv", delimiter=",", skiprows=1)
    own = [rotorpys.update(t) for t in table[:, 0]]
    for columns, key in ((slice(1, 4), "x"), (slice(4, 7), "x_dot"), (slice(7, 10), "x_ddot")):
        assert np.abs(table[:, columns] - [flat[key] for flat in own]).max() < 1e-5, key
    # The margin it keeps, from its samples flown straight between: a lower bound of the
    # margin of rotorpy's curve itself, sampled 5 times finer, within a millimetre of it.
    # The curve is sampled finely within a step of the table (10 ms) of every sample that
    # keeps less than 3 cm more than the least: elsewhere the curve, within its speed
    # (< 5 m/s) x 5 ms of a sample, keeps more than the least, a margin changing no more
    # than the distance moved.
    world = load_world("course:rotorpy/pillar")
    step = np.diff(table[:, 0]).max()
    assert np.linalg.norm(table[:, 4:7], axis=1).max() * step / 2 < 0.025
    coarse = point_margins(world, table[:, 1:4])
    near = table[coarse < coarse.min() + 0.03, 0]
    fine = np.unique(np.round(np.concatenate([np.arange(t - step, t + step, 2e-4)
                                              for t in near]) / 2e-4) * 2e-4)
    fine = fine[(fine >= 0.0) & (fine <= rotorpys.t_keyframes[-1])]
    curve = point_margins(world, [rotorpys.update(t)["x"] for t in fine]).min()
    assert curve - 1e-3 <= metrics["trajectory_margin_m"] <= curve
    assert metrics["trajectory_leg_margin_m"] is None


@pytest.mark.filterwarnings("ignore:start .* is inside the 0.2 m safety margin")
def test_a_class_from_a_start_in_the_margin_keeps_it_off_the_legs():
    settings = MissionSettings(reference=f"{EXAMPLE}:StopAndGo(speed=1.5)")
    mission = fly_mission(load_world("course:rotorpy/pillar"), (-9.9, 0, 1.5), (-5, 2, 1.5),
                          settings=pickle.loads(pickle.dumps(settings)))
    metrics = mission.metrics()
    assert metrics["success"], metrics
    begin, end = mission.trajectory.main_window
    assert 0 < begin < 0.5 and end == mission.trajectory.duration
    # On its leg it keeps what its start keeps; off it, the margin its path keeps (it flies
    # the path's straight segments).
    assert metrics["trajectory_leg_margin_m"] == pytest.approx(0.1, abs=1e-6)
    assert 0.2 - 2e-3 <= metrics["trajectory_margin_m"] < 0.21


def test_a_class_that_plans_for_itself_is_given_the_map_start_and_goal(classes):
    mission = fly_mission(load_world("course:rotorpy/pillar"), (-4, 0, 1.5), (3, 0, 1.5),
                          settings=MissionSettings(reference=f"{classes}:WorldTraj"))
    assert mission.success, mission.metrics()
    flown = mission.trajectory.samples.position  # through its own waypoint past the pillar
    assert np.linalg.norm(flown - [-0.875, 1.0, 1.5], axis=1).min() < 2e-3


def test_rotorpys_circle_is_tracked_with_its_yaw(tmp_path):
    result = run_here("track", CIRCLE, "--duration", "5", "--no-figures", "--quiet",
                      "-o", tmp_path)
    assert result.returncode == 0, result.stderr
    assert result.stdout.startswith(
        f"{CIRCLE}: update(t) sampled 5,001 times, every 0.001 s (the control rate): a 5.00 s "
        "reference (--duration)\n")
    metrics = json.loads((tmp_path / "metrics.json").read_text())
    assert metrics["success"] and metrics["reference_duration_s"] == 5.0
    flight = np.loadtxt(tmp_path / "flight.csv", delimiter=",", skiprows=1)
    t, yaw = flight[:, 0], euler_angles(flight[:, 7:11])[:, 2]
    asked = 0.8 * np.pi / 2 * np.sin(2.5 * np.minimum(t, 5.0))
    late = (t > 1.0) & (t < 5.0)
    assert np.abs(yaw - asked)[late].max() < 0.15  # rad, of 1.26: the yaw and its rate flown


@pytest.mark.parametrize(("spec", "line"), [
    ("Missing", "update(0) returned no x_ddot, yaw_dot (it gave x, x_dot, yaw): expected a "
                "dict of flat outputs: x, x_dot, x_ddot (3,) and yaw, yaw_dot"),
    ("Flat", "update(0) returned x_dot of shape (2,): expected (3,)"),
    ("Listed", "update(0) returned list: expected a dict of flat outputs: x, x_dot, x_ddot "
               "(3,) and yaw, yaw_dot"),
    ("Diverging", "update(1.5) returned x_ddot (nan, 0, 0): expected finite numbers"),
])
def test_a_class_that_returns_what_cannot_be_flown_fails_the_flight_in_one_line(
        classes, tmp_path, spec, line):
    result = run_here("track", f"{classes}:{spec}", "--quiet", "-o", tmp_path / "out")
    assert result.returncode == 1
    assert result.stderr.strip().splitlines() == [
        f"quadnav: error: reference {classes}:{spec}: {line}"]
    assert not (tmp_path / "out").exists()


def test_an_exception_in_a_class_shows_its_own_traceback_once(classes, tmp_path):
    with pytest.raises(PluginError) as caught:
        load_reference(f"{classes}:Raising", dt=0.001)
    assert caught.value.exit_code == 1
    assert str(caught.value) == (f"reference {classes}:Raising: update(0.5) raised "
                                 "ZeroDivisionError: float division by zero")
    assert "return helper(t)" in caught.value.details and "1.0 / (t - t)" in caught.value.details
    result = run("track", f"{classes}:Unbuilt", "--quiet", "-o", tmp_path / "out")
    assert result.returncode == 1
    lines = result.stderr.strip().splitlines()
    assert lines[0] == "Traceback (most recent call last):" and result.stderr.count(
        "Traceback") == 1 and 'raise RuntimeError("no spiral today")' in result.stderr
    assert lines[-1] == (f"quadnav: error: reference {classes}:Unbuilt: building it raised "
                         "RuntimeError: no spiral today")
    assert not (tmp_path / "out").exists()


def test_a_class_that_cannot_be_used_is_bad_input(classes, tmp_path):
    out = tmp_path / "out"
    cases = [
        ((f"{classes}:NoUpdate",), "NoUpdate has no update(t) method"),
        ((f"{classes}:Forever",), "Forever does not say how long it lasts (no duration or "
                                  "t_keyframes attribute): give --duration S"),
        ((f"{classes}:Spiral(spin=1)",), "cannot be called as Spiral(spin=...): got an "
                                         "unexpected keyword argument 'spin'"),
        ((f"{classes}:Helix",), "has no 'Helix' (it defines Diverging, Elsewhere, Flat"),
        (("rotorpy.trajectories.minsnap:MinSnap",), "cannot be called as MinSnap(): missing "
                                                    "a required argument: 'points'"),
        (("hover", "--duration", "3"), "--duration: applies only to a trajectory class of "
                                       "your own (module:Class or path/to/file.py:Class), "
                                       "not to hover"),
        ((f"{classes}:Spiral", "--duration", "0"), "argument --duration: expected from 0.1"),
    ]
    for args, fragment in cases:
        assert_user_error(run_here("track", *args, "-o", out), fragment)
        assert not out.exists()
    assert_user_error(run_here("fly", *PILLAR, "--reference", f"{classes}:NoUpdate", "-o", out),
                      "NoUpdate has no update(t) method")
    assert_user_error(run_here("fly", *PILLAR, "--duration", "3", "-o", out),
                      "--duration: applies only to a trajectory class of your own "
                      "(--reference, a mission file's trajectory.reference)")
    with pytest.raises(QuadnavError, match="give its arguments by keyword"):
        MissionSettings(reference="my.py:Spiral(3)")


def test_a_missions_class_must_fly_from_its_start_to_its_goal(classes, tmp_path):
    result = run_here("fly", *PILLAR, "--reference", f"{classes}:Elsewhere", "--quiet",
                      "-o", tmp_path / "out")
    assert result.returncode == 1
    assert result.stderr.strip() == (
        f"quadnav: error: reference {classes}:Elsewhere starts at (-4, 0, 2.5), 1 m from the "
        "start (-4, 0, 1.5) (the goal tolerance is 0.1 m): a mission's reference flies from "
        "its start to its goal")


def test_a_list_of_numbers_in_a_spec_arrives_as_an_array():
    given = literal_arrays({"freq": [0.2, 0.2, 0], "points": [[0, 0, 1], [2, 0, 1.5]],
                            "ragged": [[1, 2], [3]], "flags": [True, False], "names": ["a"],
                            "empty": [], "speed": 1.5, "label": "x"})
    assert given["freq"].dtype == np.float64 and given["freq"].tolist() == [0.2, 0.2, 0.0]
    assert given["points"].shape == (2, 3)
    assert {key: given[key] for key in ("ragged", "flags", "names", "empty", "speed", "label")
            } == {"ragged": [[1, 2], [3]], "flags": [True, False], "names": ["a"], "empty": [],
                  "speed": 1.5, "label": "x"}

"""Plain-Python controllers in rotorpy's shape fly through the compiled closed loop: rotorpy's
own SE3Control, unchanged, agrees with quadnav's SE(3) controller on the same vehicle; every
control abstraction goes through quadnav's inner loops; a controller is named, registered
and reported as a compiled one is."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import warnings

import numpy as np
import pytest
from clitools import assert_user_error, run_here
from publicmaps import course_query

from quadnav.control.registry import CONTROLLERS, make_controller
from quadnav.control.se3 import SE3Gains, se3_controller
from quadnav.errors import PlanningWarning, QuadnavError
from quadnav.mission import MissionSettings, fly_mission
from quadnav.sim.settings import SimSettings
from quadnav.sim.simulate import simulate
from quadnav.tracking import track_reference
from quadnav.trajectory.references.builtin import load_reference
from quadnav.vehicle.params import VehicleParams, load_params
from quadnav.world import load_world

pytest.importorskip("rotorpy", reason="rotorpy (quadnav[test]) is not installed")

SE3CONTROL = "rotorpy.controllers.quadrotor_control:SE3Control"
#: The Tello without drag (rotorpy's SE3Control knows none) and rotorpy's Crazyflie
#: (rotorpy/vehicles/crazyflie_params.py, without its rotor drag).
TELLO = load_params("tello").replace(name="tello without drag", drag=np.zeros(3))
CRAZYFLIE = VehicleParams(name="crazyflie", mass=0.03, inertia=np.array([1.43e-5, 1.43e-5,
                                                                          2.89e-5]),
                          arm_length=0.043, thrust_coefficient=2.3e-8,
                          torque_coefficient=7.8e-10, rotor_speed_max=2500.0,
                          motor_time_constant=0.072, drag=np.zeros(3),
                          body_size=np.array([0.09, 0.09, 0.03]))
#: quadnav's SE(3) controller with rotorpy's attitude gains (kp_att 310, kd_att 57, on every
#: axis): the position gains are rotorpy's already.
ROTORPY_GAINS = SE3Gains(kr=(310.0,) * 3, kw=(57.0,) * 3)
#: How closely the two must agree, m: the same law, computed by numpy and by numba.
AGREEMENT = 1e-6
#: The control rate of these flights: a Python controller costs Python time at every control
#: step, so a quarter of the default rate's steps (the physics stays at 1 kHz); they agree,
#: and track, as at 1 kHz.
PYTHON_RATE = SimSettings(control_rate=250.0)

CONTROLLERS_FILE = '''
import numpy as np
from rotorpy.controllers.quadrotor_control import SE3Control


class RateCommands(SE3Control):
    """SE3Control's thrust, with body rates from its attitude error (2 kq q_err)."""

    control_abstraction = "cmd_ctbr"

    def __init__(self, quad_params, kq=10.0):
        super().__init__(quad_params)
        self.kq = kq

    def update(self, t, state, flat_output):
        out = super().update(t, state, flat_output)
        wanted, q = out["cmd_q"], state["q"]  # (i, j, k, w)
        # q_err = q^-1 wanted, its vector part in the body frame
        w1, v1 = q[3], -q[:3]
        w2, v2 = wanted[3], wanted[:3]
        error = w1 * v2 + w2 * v1 + np.cross(v1, v2)
        sign = 1.0 if w1 * w2 - v1 @ v2 >= 0 else -1.0
        return {"cmd_thrust": out["cmd_thrust"], "cmd_w": 2 * self.kq * sign * error}


class VelocityCommands:
    """The reference velocity plus kp times the position error."""

    def __init__(self, quad_params, kp=2.0):
        self.kp = kp

    def update(self, t, state, flat_output):
        return {"cmd_v": flat_output["x_dot"] + self.kp * (flat_output["x"] - state["x"])}


class Seen:
    """Hovers by motor speeds and keeps what it was given."""

    def __init__(self, quad_params):
        self.speed = np.sqrt(quad_params["mass"] * 9.81 / 4 / quad_params["k_eta"])
        self.params, self.calls = quad_params, []

    def update(self, t, state, flat_output):
        self.calls.append((t, state, flat_output))
        return {"cmd_motor_speeds": np.full(4, self.speed)}
'''


@pytest.fixture
def controllers(tmp_path):
    path = tmp_path / "my_controllers.py"
    path.write_text(CONTROLLERS_FILE)
    return path


def _course_flight(world, start, goal, margin, vehicle):
    settings = MissionSettings(vehicle=vehicle, controller=SE3CONTROL, sim=PYTHON_RATE)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PlanningWarning)  # starts inside the margin
        return fly_mission(world, start, goal, margin, settings)


@pytest.mark.parametrize("vehicle", [TELLO, CRAZYFLIE], ids=["tello", "crazyflie"])
def test_rotorpys_se3control_flies_a_course_map_as_quadnavs_se3_with_its_gains(vehicle):
    world = load_world("course:rotorpy/double_pillar")  # shipped with quadnav
    mission = _course_flight(world, [0, -4, 1], [0, 4, 1], None, vehicle)
    assert mission.success and mission.flight.mixer_saturation == 0.0
    assert mission.parameters()["controller"] == SE3CONTROL
    ours = simulate(mission.trajectory, vehicle, world=world, settings=mission.settings.sim,
                    controller=se3_controller(ROTORPY_GAINS))
    apart = np.linalg.norm(ours.states[:, 0:7] - mission.flight.states[:, 0:7], axis=1)
    assert len(ours.t) == len(mission.flight.t) and apart.max() < AGREEMENT
    assert ours.rms_tracking_error == pytest.approx(mission.flight.rms_tracking_error,
                                                    abs=AGREEMENT)


def test_rotorpys_se3control_agrees_with_quadnavs_se3_on_a_public_course_map(shared_maps):
    world, start, goal, margin = course_query(shared_maps, "rbe595/map1.txt")
    mission = _course_flight(world, start, goal, margin, TELLO)
    assert mission.success and mission.flight.rms_tracking_error < 0.1
    ours = simulate(mission.trajectory, TELLO, world=world, settings=mission.settings.sim,
                    controller=se3_controller(ROTORPY_GAINS))
    assert np.abs(ours.position - mission.flight.position).max() < AGREEMENT


def test_speeds_thrusts_and_moments_of_one_controller_fly_one_flight():
    """rotorpy's SE3Control by motor speeds, rotor thrusts and thrust with moments: three
    forms of the same commands, one flight (quadnav's mixer meets the wrench exactly): half
    a lap of the helix, climbing and turning about every axis as the whole one does."""
    helix = load_reference("helix:radius=1,speed=1,laps=0.5")
    flights = [simulate(helix, TELLO, settings=PYTHON_RATE, controller=make_controller(
        f"{SE3CONTROL}(control_abstraction={name!r})", TELLO))
        for name in ("cmd_motor_speeds", "cmd_motor_thrusts", "cmd_ctbm")]
    for flight in flights[1:]:
        assert np.abs(flight.states[:, 0:13] - flights[0].states[:, 0:13]).max() < 1e-9


@pytest.mark.parametrize(("spec", "rms"), [
    (f"{SE3CONTROL}(control_abstraction='cmd_ctatt')", 0.02),  # the cascade's attitude loop
    ("{file}:RateCommands", 0.03),  # the cascade's rate loop
    ("{file}:VelocityCommands(kp=2.0)", 0.15),  # the cascade's velocity loop
])
def test_attitude_rate_and_velocity_commands_fly_through_quadnavs_inner_loops(
        controllers, spec, rms):
    tracking = track_reference(load_reference("helix:radius=1,speed=1"), TELLO,
                               settings=PYTHON_RATE, controller=spec.format(file=controllers))
    assert tracking.success and tracking.flight.rms_tracking_error < rms


def test_a_controller_sees_rotorpys_state_and_flat_outputs(controllers):
    controller = make_controller(f"{controllers}:Seen", TELLO)
    helix = load_reference("helix:radius=1,speed=1")
    flight = simulate(helix, TELLO, settings=SimSettings(control_rate=500.0),
                      controller=controller)
    seen = controller.python.controller
    assert seen.params["mass"] == TELLO.mass and seen.params["rotor_pos"]["r1"][0] > 0
    t, state, flat = seen.calls[1500]
    assert t == pytest.approx(1500 / 500.0)
    k = 1500 // 5  # the record keeps every fifth step at 100 Hz
    assert np.allclose(state["x"], flight.position[k]) and state["wind"].tolist() == [0] * 3
    q = flight.attitude[k]
    assert np.allclose(state["q"], [q[1], q[2], q[3], q[0]])  # (i, j, k, w)
    assert set(state) == {"x", "v", "q", "w", "wind", "rotor_speeds"}
    assert set(flat) == {"x", "x_dot", "x_ddot", "x_dddot", "x_ddddot", "yaw", "yaw_dot"}
    assert np.allclose(flat["x"], helix.position(t)) and np.allclose(flat["x_ddot"],
                                                                      helix.acceleration(t))
    # a helix has no jerk of its own: finite differences of its acceleration stand in
    h = 1e-4
    jerk = (helix.acceleration(t + h) - helix.acceleration(t - h)) / (2 * h)
    assert np.linalg.norm(jerk) > 0.1 and np.allclose(flat["x_dddot"], jerk, rtol=1e-3)


def test_a_controller_registered_by_name_or_declared_by_a_package_flies(controllers, tmp_path):
    from quadnav.plugins import load_target

    CONTROLLERS.register("velocity_test", load_target(f"{controllers}:VelocityCommands"))
    try:
        tracking = track_reference(load_reference("hover"), TELLO, controller="velocity_test")
    finally:
        CONTROLLERS.unregister("velocity_test")
    assert tracking.success and tracking.parameters()["controller"] == "velocity_test"
    info = tmp_path / "my_controllers-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: my-controllers\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text(
        "[quadnav.controllers]\nvelocity = my_controllers:VelocityCommands\n")
    result = subprocess.run(
        [sys.executable, "-m", "quadnav", "track", "hover", "--controller", "velocity",
         "--control-rate", "200", "--no-figures", "--quiet", "-o", str(tmp_path / "out")],
        env={**os.environ, "PYTHONPATH": os.pathsep.join([str(tmp_path), *sys.path])},
        capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    assert '"controller": "velocity"' in (tmp_path / "out" / "parameters.json").read_text()


def test_fly_names_a_controller_by_its_file_and_reports_it_as_named(controllers, tmp_path):
    spec = f"{controllers}:VelocityCommands(kp=2.0)"
    result = run_here("fly", "course:rotorpy/double_pillar", "--start", "0", "-4", "1",
                      "--goal", "0", "4", "1", "--controller", spec, "--control-rate", "250",
                      "--no-figures", "--quiet", "-o", tmp_path / "out")
    assert result.returncode == 0, result.stderr
    assert f"controller {spec}, top speed" in result.stdout.splitlines()[0]


@pytest.mark.parametrize(("text", "words"), [
    (f"{SE3CONTROL}(control_abstraction='cmd_acc')", "control_abstraction must be one of "
     "cmd_motor_speeds, cmd_motor_thrusts, cmd_ctbm, cmd_ctatt, cmd_ctbr, cmd_vel, got "
     "'cmd_acc'"),
    ("quadnav.control.gains:Gains", "Gains has no method update(t, state, flat_output)"),
    ("numpy:array", "expected a class with update(t, state, flat_output), or a function of "
     "the vehicle and gains returning a quadnav.control.contract.Controller; it returned "
     "ndarray"),
])
def test_what_is_not_a_controller_is_refused_before_it_flies(text, words):
    with pytest.raises(QuadnavError) as caught:
        MissionSettings(controller=text)
    assert str(caught.value) == f"controller {text}: {words}"


def test_gains_tune_the_inner_loops_a_python_controller_flies_through(controllers, tmp_path):
    """--gains reaches the cascade's rate loop that RateCommands' body rates go through."""
    def flown(*flags: str) -> dict:
        result = run_here("track", "helix:radius=1,speed=1", "--controller",
                          f"{controllers}:RateCommands", "--control-rate", "250", *flags,
                          "--no-figures", "--quiet", "-o", tmp_path / "out")
        assert result.returncode == 0, result.stderr
        return {name: json.loads((tmp_path / "out" / name).read_text())
                for name in ("metrics.json", "parameters.json")}

    slow = tmp_path / "slow_rates.toml"
    slow.write_text("[rate]\nkp = [15.0, 15.0, 15.0]\n")  # the tello's: 40, 40, 15
    tuned, default = flown("--gains", str(slow)), flown()
    assert tuned["parameters.json"]["gains"]["rate"]["kp"] == [15.0, 15.0, 15.0]
    error = [run["metrics.json"]["rms_tracking_error_m"] for run in (tuned, default)]
    assert abs(error[0] - error[1]) > 1e-4
    result = run_here("track", "hover", "--controller", "se3", "--gains", str(slow),
                      "-o", tmp_path / "se3")  # the cascade's keys are not SE(3)'s
    assert_user_error(result, f"{slow}: unknown key 'rate'; expected one of kx, kv, kr, kw")

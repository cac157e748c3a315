"""The cascaded controller on the simulated vehicle: hover, steps, saturation, gain files."""

from __future__ import annotations

import numpy as np
import pytest

from quadnav.control.gains import Gains, Saturations, course_gain_names
from quadnav.control.registry import controller_gains, gain_set_names
from quadnav.errors import QuadnavError
from quadnav.sim.flight import Ending
from quadnav.sim.settings import SimSettings
from quadnav.sim.simulate import simulate
from quadnav.sim.step_response import step_response
from quadnav.trajectory.model import hold_trajectory
from quadnav.vehicle.dynamics import hover_state
from quadnav.vehicle.params import load_params

TELLO = load_params("tello")
RBE595 = load_params("rbe595")
HOME = np.array([1.0, 2.0, 1.5])
#: Every control step recorded.
FULL_RECORD = SimSettings(record_rate=1000.0)


def test_hover_holds_within_a_centimetre_with_sensor_noise_and_gusts():
    settings = SimSettings(record_rate=1000.0, gust_std=0.005, position_noise=0.001,
                           velocity_noise=0.005, attitude_noise=0.002, gyro_noise=0.005,
                           seed=7)
    flight = simulate(hold_trajectory(HOME, 20.0), TELLO, world=None, settings=settings)
    deviation = np.linalg.norm(flight.position - HOME, axis=1)
    print(f"hover with noise and gusts: max {100 * deviation.max():.2f} cm, "
          f"RMS {100 * np.sqrt(np.mean(deviation ** 2)):.2f} cm")
    assert flight.ending is Ending.COMPLETED
    assert deviation.max() < 0.01


@pytest.mark.parametrize("params", [TELLO, RBE595], ids=["tello", "rbe595"])
def test_hover_without_disturbance_does_not_move(params):
    flight = simulate(hold_trajectory(HOME, 5.0), params, controller_gains("cascade", params),
                      settings=FULL_RECORD)
    assert flight.max_tracking_error < 1e-9


def _step(params, axis: int, size: float, gains: Gains | None = None, seconds: float = 8.0):
    start = hover_state(params, HOME - size * np.eye(3)[axis])
    flight = simulate(hold_trajectory(HOME, seconds), params,
                      gains or controller_gains("cascade", params), settings=FULL_RECORD,
                      initial_state=start)
    response = step_response(flight.t, flight.position, start[0:3], HOME, 0.0)
    return flight, response.overshoot, response.settling_time


#: (vehicle, axis, step m, largest overshoot as a fraction, largest 2 % settling time s)
STEPS = [(TELLO, 0, 1.0, 0.05, 2.0), (TELLO, 1, 1.0, 0.05, 2.0), (TELLO, 2, 0.5, 0.05, 1.5),
         (RBE595, 0, 1.0, 0.05, 4.0), (RBE595, 2, 0.5, 0.05, 2.0)]


@pytest.mark.parametrize(("params", "axis", "size", "max_overshoot", "max_settling"), STEPS,
                         ids=["tello-x", "tello-y", "tello-z", "rbe595-x", "rbe595-z"])
def test_a_step_settles_without_overshoot_beyond_five_percent(params, axis, size,
                                                              max_overshoot, max_settling):
    flight, overshoot, settling = _step(params, axis, size)
    print(f"{params.name} step {size} m along {'xyz'[axis]}: overshoot {100 * overshoot:.2f} %, "
          f"2 % settling {settling:.2f} s")
    assert flight.ending is Ending.COMPLETED
    assert overshoot < max_overshoot
    assert settling < max_settling
    assert flight.final_error < 0.005


def test_a_long_step_under_the_speed_limit_does_not_wind_up():
    gains = Gains(limits=Saturations(speed_xy=1.5))
    flight, overshoot, settling = _step(TELLO, 0, 8.0, gains, seconds=12.0)
    speed = np.hypot(flight.velocity[:, 0], flight.velocity[:, 1])
    print(f"8 m step at 1.5 m/s: top speed {speed.max():.3f} m/s, overshoot "
          f"{100 * overshoot:.2f} %, settling {settling:.2f} s")
    assert speed.max() < 1.5 * 1.05
    assert overshoot < 0.01
    assert settling < 8.0


def test_a_steady_wind_is_integrated_away():
    settings = SimSettings(record_rate=1000.0, wind=[0.03, -0.02, 0.0])  # ~4 % of the weight
    flight = simulate(hold_trajectory(HOME, 15.0), TELLO, settings=settings)
    assert flight.ending is Ending.COMPLETED
    assert flight.final_error < 0.005
    assert flight.max_tracking_error < 0.05


def test_a_gains_file_sets_only_its_keys(tmp_path):
    path = tmp_path / "gains.toml"
    path.write_text("attitude_kp = [8.0, 8.0, 4.0]\n[velocity]\nki = [0.5, 0.5, 1.0]\n"
                    "[limits]\ntilt_max_deg = 30.0\n")
    gains = controller_gains("cascade", TELLO, path)
    default = Gains()
    assert np.array_equal(gains.attitude_kp, [8.0, 8.0, 4.0])
    assert np.array_equal(gains.velocity.ki, [0.5, 0.5, 1.0])
    assert np.array_equal(gains.velocity.kp, default.velocity.kp)
    assert gains.limits.tilt_max_deg == 30.0
    assert gains.limits.speed_xy == default.limits.speed_xy
    assert gains.as_dict()["velocity"]["ki"] == [0.5, 0.5, 1.0]


@pytest.mark.parametrize(("text", "message"), [
    ("[velocity]\nkq = [1, 1, 1]\n", r"\[velocity\]: unknown key 'kq'"),
    ("[velocity]\nkp = [1, 1]\n", "kp: expected a list of 3 numbers"),
    ("[position]\nki = [-1, 0, 0]\n", r"ki: expected each value from 0 to 10,000, got \[-1, 0, 0\]"),
    # a gain that would fly and diverge (before: exit 1, a failed flight, not bad input)
    ("[position]\nkp = [1e300, 1, 1]\n", r"kp: expected each value from 0 to 10,000, got \[1e\+300, 1, 1\]"),
    ("attitude_kp = [12, 12, 10000.5]\n", r"attitude_kp: expected each value from 0 to 10,000, got \[12, 12, 10000.5\]"),
    ("[limits]\nspeed_xy = 1e300\n", r"speed_xy: expected from 0.01 to 100 m/s, got 1e\+300"),
    ("[limits]\nrate_max_deg = [360, 360, 1e9]\n", r"rate_max_deg: expected each value above 0, at most 3,600 deg/s"),
    ("[limits]\ntilt_max_deg = 95\n", "tilt_max_deg must be in"),
    ("velocity = 3\n", "velocity must be a table"),
])
def test_a_bad_gains_file_names_the_file_and_key(tmp_path, text, message):
    path = tmp_path / "gains.toml"
    path.write_text(text)
    with pytest.raises(QuadnavError, match=message) as error:
        controller_gains("cascade", TELLO, path)
    assert str(path) in str(error.value)


def test_vehicle_presets_name_their_gain_sets():
    assert gain_set_names() == ["rbe595", "tello"]
    assert TELLO.gains == "tello" and RBE595.gains == "rbe595"
    assert controller_gains("cascade", RBE595).rate.kp[0] < Gains().rate.kp[0]
    with pytest.raises(QuadnavError, match="the tello vehicle names the gain set 'nope'; "
                                           "expected one of rbe595, tello"):
        controller_gains("cascade", TELLO.replace(gains="nope"))


def test_course_gain_tables_set_the_18_outer_gains_on_the_vehicles_own():
    names = course_gain_names()
    assert "p2a-starter" in names and len(names) >= 6
    for vehicle in (TELLO, RBE595):
        own = controller_gains("cascade", vehicle)
        for name in names:
            table = controller_gains("cascade", vehicle, name)
            assert np.array_equal(table.rate.kp, own.rate.kp)  # inner loops kept
            assert np.array_equal(table.attitude_kp, own.attitude_kp)
            assert not np.array_equal(table.velocity.kp, own.velocity.kp)
    starter = controller_gains("cascade", TELLO, "p2a-starter")
    assert starter.position.kp.tolist() == [20.0, 20.0, 0.1]
    assert starter.velocity.kd.tolist() == [5.0, 5.0, 0.5534]
    with pytest.raises(QuadnavError, match="p2a-nope"):
        controller_gains("cascade", TELLO, "p2a-nope")

"""A control rate too slow for the controller's gains is refused, one that leaves them little
margin warned about (quadnav.control.sampling): the criterion against the simulated loop, the
defaults, the measured SE(3) case and the command line."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from clitools import assert_user_error, run_here
from scipy.linalg import expm

from quadnav.control.gains import course_gain_names
from quadnav.control.registry import (
    CONTROLLERS,
    check_controller_rate,
    controller_gains,
    make_controller,
)
from quadnav.control.sampling import (
    GAIN_MARGIN,
    axis_loops,
    check_control_rate,
    lowest_rate,
    rate_verdict,
    sampled_plant,
)
from quadnav.errors import ControlWarning, QuadnavError
from quadnav.mission import MissionSettings
from quadnav.sim import loop
from quadnav.sim.settings import SimSettings
from quadnav.tracking import track_reference
from quadnav.trajectory.references.builtin import load_reference
from quadnav.vehicle import quaternion
from quadnav.vehicle.dynamics import hover_state, vehicle_arrays
from quadnav.vehicle.params import load_params, preset_names

TELLO = load_params("tello")
TILT = 0.02  # rad: the roll the hover starts with in the loop below


def _loops(name: str, gains=None, vehicle=TELLO):
    return axis_loops(make_controller(name, vehicle, gains))


def _roll_growth(name: str, rate: float, seconds: float = 4.0) -> float:
    """The real compiled loop (not simulate, which would not fly it), hovering at ``rate``
    Hz from a roll of TILT: its largest roll over the last second, in units of TILT."""
    controller = make_controller(name, TELLO)
    vehicle = vehicle_arrays(TELLO)
    steps = round(seconds * rate)
    state = hover_state(TELLO, [0.0, 0.0, 1.0])
    state[6:10] = quaternion.from_rotation_vector(np.array([TILT, 0.0, 0.0]))
    references = np.zeros((steps, 11))
    references[:, 2] = 1.0
    record = loop.new_record(steps)
    code, done = loop.run_steps(controller, state, controller.new_memory(), 0, steps,
                                references, vehicle, vehicle, round(1000 / rate), 1.0 / rate,
                                loop.scene(None, vehicle.half_size), loop.still_air(steps),
                                record)
    assert code == loop.RUNNING and done == steps
    roll = 2.0 * np.arcsin(np.abs(record.states[-round(rate):, 7]))
    return float(roll.max() / TILT)


def test_the_sampled_plant_is_the_exact_solution():
    for lag, period in ((0.02, 0.001), (0.02, 0.04), (0.005, 1e-5), (0.1, 0.1)):
        generator = np.zeros((4, 4))
        generator[0, 1] = generator[1, 2] = 1.0
        generator[2, 2], generator[2, 3] = -1.0 / lag, 1.0 / lag
        exact = expm(generator * period)
        step, hold = sampled_plant(lag, period)
        assert np.allclose(step, exact[:3, :3], rtol=1e-12, atol=1e-15)
        assert np.allclose(hold, exact[:3, 3], rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize("name", ["se3", "cascade"])
def test_the_lowest_stable_rate_is_where_the_simulated_loop_turns_unstable(name):
    # the linearised, sampled loop turns unstable at 28.0 Hz (SE(3)) and 20.2 Hz (cascade)
    # on the Tello; the real loop, nonlinear, with RK4 physics, at about 27 and 19.5 Hz
    lowest = lowest_rate(_loops(name), TELLO.motor_time_constant, 1.0)
    assert 15.0 < lowest < 35.0
    assert _roll_growth(name, 0.85 * lowest) > 5.0  # the roll grows
    assert _roll_growth(name, 1.2 * lowest) < 0.1  # the roll dies out


def test_every_shipped_gain_set_keeps_a_wide_margin_at_the_default_rate():
    for vehicle in map(load_params, preset_names()):
        for name in CONTROLLERS.names():
            tables = course_gain_names() if name == "cascade" else []  # the cascade's tables
            for table in (None, *tables):
                gains = controller_gains(name, vehicle, table)
                verdict = rate_verdict(_loops(name, gains, vehicle), vehicle.motor_time_constant,
                                       1000.0)
                assert verdict.gain_margin > 15 * GAIN_MARGIN, (vehicle.name, table, name)
    # the defaults: 62 (cascade) and 33 (SE(3)) on the Tello
    assert rate_verdict(_loops("cascade"), 0.02, 1000.0).gain_margin > 60.0
    assert rate_verdict(_loops("se3"), 0.02, 1000.0).gain_margin > 30.0


def test_se3_at_100_hz_keeps_enough_margin_and_flies_unwarned():
    # the case: rotorpy runs these gains at 100 Hz; the sampled loop keeps 3.4
    verdict = rate_verdict(_loops("se3"), TELLO.motor_time_constant, 100.0)
    assert verdict.axis == "roll" and 3.0 < verdict.gain_margin < 4.0
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_control_rate(make_controller("se3", TELLO), TELLO, 100.0)


def test_a_rate_the_gains_are_unstable_at_is_refused_before_planning(tmp_path):
    out = tmp_path / "out"
    result = run_here("fly", "--controller", "se3", "--control-rate", "25", "-o", out)
    assert_user_error(
        result, "quadnav: error: control rate 25 Hz: the se3 controller's roll loop on the "
        "tello vehicle, sampled at that rate behind its rotors' 0.02 s lag, is unstable "
        "(stable from 29 Hz, a gain margin of 2 from 58 Hz); raise --control-rate")
    assert result.stdout == "" and not out.exists()
    track = run_here("track", "hover", "--control-rate", "10", "-o", out)
    assert_user_error(track, "control rate 10 Hz: the cascade controller's roll loop",
                      "stable from 21 Hz")
    assert not out.exists()


def test_a_rate_that_leaves_little_margin_is_warned_about_and_flown(tmp_path):
    result = run_here("track", "hover", "--controller", "se3", "--control-rate", "40",
                      "--no-figures", "--quiet", "-o", tmp_path / "out")
    assert result.returncode == 0, result.stderr
    assert result.stderr.splitlines() == [
        "quadnav: warning: control rate 40 Hz: the se3 controller's roll loop on the tello "
        "vehicle keeps a gain margin of only 1.42, under 2: poorly damped (stable from 29 Hz, "
        "a gain margin of 2 from 58 Hz)"]
    assert "success" in result.stdout


def test_gains_unstable_at_any_rate_are_refused(tmp_path):
    gains = tmp_path / "gains.toml"  # a rate loop with a big integral and a small P
    gains.write_text("attitude_kp = [40.0, 40.0, 5.0]\n[rate]\nkp = [3.0, 3.0, 15.0]\n"
                     "ki = [40.0, 40.0, 5.0]\nkd = [0.0, 0.0, 0.0]\n")
    with pytest.raises(QuadnavError, match="roll loop on the tello vehicle is unstable at any "
                                           "control rate: its gains cannot fly"):
        check_control_rate(make_controller("cascade", TELLO, controller_gains(
            "cascade", TELLO, gains)), TELLO, 1000.0)


def test_another_controller_is_not_checked():
    from quadnav.control.contract import Controller

    other = Controller("mine", make_controller("se3", TELLO).step, (1.0,), 1)
    assert axis_loops(other) is None
    with warnings.catch_warnings():
        warnings.simplefilter("error", ControlWarning)
        check_control_rate(other, TELLO, 10.0)


#: Plain-Python controllers holding a hover, one per kind of command: an attitude (the
#: cascade's attitude and rate loops fly it), body rates (its rate loop alone), motor speeds
#: (no loop of quadnav's) and one that leaves its abstraction to its first update.
PLAIN = '''
import numpy as np


class Attitude:
    control_abstraction = "cmd_ctatt"

    def __init__(self, quad_params):
        self.weight = quad_params["mass"] * 9.81
        self.hover = np.sqrt(self.weight / 4 / quad_params["k_eta"])

    def update(self, t, state, flat_output):
        return {"cmd_thrust": self.weight, "cmd_q": [0.0, 0.0, 0.0, 1.0],
                "cmd_w": [0.0, 0.0, 0.0], "cmd_motor_speeds": [self.hover] * 4}


class Rates(Attitude):
    control_abstraction = "cmd_ctbr"


class Motors(Attitude):
    control_abstraction = "cmd_motor_speeds"


class Undeclared(Attitude):
    control_abstraction = None
'''


def test_one_control_rate_rule_for_every_controller(tmp_path):
    """The control rate is checked against the loops that run at it, by every flight: under a
    plain-Python controller the cascade's loops that its commands fly through (on main, a
    plain-Python controller was never checked: fly, track and kino --fly passed it)."""
    (tmp_path / "plain.py").write_text(PLAIN)
    spec = {name: f"{tmp_path / 'plain.py'}:{name}"
            for name in ("Attitude", "Rates", "Motors", "Undeclared")}
    slow = SimSettings(control_rate=16.0, physics_rate=960.0, record_rate=16.0)
    unstable = (f"control rate 16 Hz: the {spec['Attitude']} controller's roll loop (the "
                "cascade's, flying its cmd_ctatt commands) on the tello vehicle, sampled at that "
                "rate behind its rotors' 0.02 s lag, is unstable (stable from 21 Hz, a gain "
                "margin of 2 from 41 Hz); raise --control-rate")
    with pytest.raises(QuadnavError) as refused:
        check_controller_rate(spec["Attitude"], TELLO, None, 16.0)
    assert str(refused.value) == unstable
    for fly in (lambda: MissionSettings(controller=spec["Attitude"], sim=slow),
                lambda: track_reference(load_reference("hover:duration=0.5"), TELLO,
                                        settings=slow, controller=spec["Attitude"])):
        with pytest.raises(QuadnavError, match=r"cmd_ctatt commands.*is unstable"):
            fly()
    # body rates fly through the rate loop alone, which keeps some margin at 16 Hz
    with pytest.warns(ControlWarning) as warned:
        check_controller_rate(spec["Rates"], TELLO, None, 16.0)
    assert [str(w.message) for w in warned] == [
        f"control rate 16 Hz: the {spec['Rates']} controller's roll loop (the cascade's, "
        "flying its cmd_ctbr commands) on the tello vehicle keeps a gain margin of only 1.41, "
        "under 2: poorly damped (stable from 13 Hz, a gain margin of 2 from 31 Hz)"]
    # a controller commanding its rotors, or choosing its commands in flight, has none here
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for name in ("Motors", "Undeclared"):
            check_controller_rate(spec[name], TELLO, None, 10.0)
            MissionSettings(controller=spec[name], sim=slow)
    # the command line: refused before planning, by fly and track alike
    out = tmp_path / "out"
    for command in (("fly",), ("track", "hover")):
        result = run_here(*command, "--controller", spec["Attitude"], "--control-rate", "16",
                          "--physics-rate", "960", "-o", out)
        assert_user_error(result, f"quadnav: error: {unstable}")
        assert not out.exists()

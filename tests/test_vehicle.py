"""The vehicle: parameters and presets, the mixer, and the 6-DOF dynamics."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from quadnav.errors import QuadnavError
from quadnav.vehicle import quaternion
from quadnav.vehicle.dynamics import (
    STATE_SIZE,
    derivative,
    hover_state,
    rk4_step,
    rk4_workspace,
    rotor_speed_commands,
    vehicle_arrays,
)
from quadnav.vehicle.params import VehicleParams, load_params, preset_names
from quadnav.vehicle.rotors import (
    allocation_matrix,
    mix,
    roll_pitch_acceleration_max,
    rotor_positions,
)

TELLO = load_params("tello")
RBE595 = load_params("rbe595")


def test_presets_are_shipped_and_the_dataclass_defaults_are_the_tello():
    assert preset_names() == ["rbe595", "tello"]
    default = VehicleParams()
    for key in ("mass", "arm_length", "thrust_coefficient", "torque_coefficient",
                "rotor_speed_max", "motor_time_constant"):
        assert getattr(default, key) == getattr(TELLO, key)
    for key in ("inertia", "drag", "body_size"):
        assert np.array_equal(getattr(default, key), getattr(TELLO, key))


def test_rbe595_preset_has_the_course_numbers():
    assert RBE595.mass == 0.08
    assert np.allclose(RBE595.inertia, [0.0097, 0.0097, 0.017])
    assert RBE595.arm_length == 0.06
    # per-rotor thrust U * m * g * 2 / 4 for U in [0, 1]
    assert RBE595.max_rotor_thrust == pytest.approx(0.08 * 9.81 * 2 / 4, rel=1e-12)
    assert RBE595.hover_command == pytest.approx(0.5, rel=1e-12)
    assert RBE595.torque_per_thrust == pytest.approx(0.08, rel=1e-12)


def test_tello_preset_is_physically_plausible():
    assert TELLO.mass == 0.08
    assert 1.5 < TELLO.max_total_thrust / TELLO.weight < 3.0
    assert 0.005 < TELLO.motor_time_constant < 0.1
    assert np.array_equal(TELLO.body_size, [0.10, 0.10, 0.05])


def test_a_params_file_overrides_its_preset(tmp_path):
    path = tmp_path / "heavy.toml"
    path.write_text('based_on = "rbe595"\nmass = 0.1\ndrag = [0.1, 0.1, 0.2]\n')
    params = load_params(path)
    assert params.name == "heavy"
    assert params.mass == 0.1
    assert np.array_equal(params.drag, [0.1, 0.1, 0.2])
    assert np.array_equal(params.inertia, RBE595.inertia)


def test_a_params_file_sets_rotorpys_aerodynamics_which_the_presets_leave_out(tmp_path):
    path = tmp_path / "aero.toml"
    path.write_text("rotor_drag = [1e-6, 1e-6, 7e-7]\nparasitic_drag = [0.01, 0.01, 0.02]\n"
                    "translational_lift = 1e-3\nflapping = 1e-6\n")
    params = load_params(path)
    assert np.array_equal(params.rotor_drag, [1e-6, 1e-6, 7e-7])
    assert np.array_equal(params.parasitic_drag, [0.01, 0.01, 0.02])
    assert (params.translational_lift, params.flapping) == (1e-3, 1e-6)
    assert vehicle_arrays(params).aerodynamics.modelled
    for preset in (TELLO, RBE595):
        assert not vehicle_arrays(preset).aerodynamics.modelled
        assert np.array_equal(preset.hover_drag, preset.drag)


@pytest.mark.parametrize(("text", "message"), [
    ("mass = -1\n", "mass must be > 0"),
    ("masss = 1\n", "unknown key 'masss'"),
    ("drag = [1, 2]\n", "drag: expected a list of 3 numbers"),
    ("mass = 'heavy'\n", "mass: expected a number"),
    ('based_on = "boeing"\n', "based_on must name a preset"),
    ("mass = 2.0\n", "not more than the weight"),
    ("rotor_drag = [1e-6, 1e-6, -1e-6]\n", "rotor_drag must be >= 0"),
    ("flapping = -1e-6\n", "flapping must be >= 0"),
    ("mass = [\n", "not valid TOML"),
    ("mass = " + "9" * 5000 + "\n", "not valid TOML: a number with too many digits"),
])
def test_a_bad_params_file_names_the_file_and_the_problem(tmp_path, text, message):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(QuadnavError, match=message) as error:
        load_params(path)
    assert str(path) in str(error.value) or "must be" in str(error.value)


def test_an_unknown_preset_is_a_user_error():
    with pytest.raises(QuadnavError, match="expected a vehicle preset"):
        load_params("no-such-preset")


# ------------------------------------------------------------------------------- mixer
@pytest.mark.parametrize("params", [TELLO, RBE595], ids=["tello", "rbe595"])
@given(st.lists(st.floats(0.0, 1.0), min_size=4, max_size=4))
@settings(deadline=None)  # the first call compiles the mixer
def test_the_mixer_inverts_the_allocation_exactly(params, fractions):
    thrusts = np.array(fractions) * params.max_rotor_thrust
    wrench = allocation_matrix(params) @ thrusts
    v = vehicle_arrays(params)
    mixed, changed = mix(wrench, v.mixer, v.max_rotor_thrust)
    assert np.allclose(mixed, thrusts, rtol=0, atol=1e-12 * params.max_rotor_thrust)
    assert np.allclose(allocation_matrix(params) @ mixed, wrench, rtol=1e-12, atol=1e-15)
    assert not changed


def test_an_impossible_wrench_keeps_roll_and_pitch_before_yaw():
    v = vehicle_arrays(TELLO)
    hover = TELLO.weight
    wrench = np.array([hover, 0.002, 0.0, 0.01])  # far more yaw than the rotors give
    mixed, changed = mix(wrench, v.mixer, v.max_rotor_thrust)
    achieved = v.allocation @ mixed
    assert changed
    assert np.all((mixed >= 0) & (mixed <= v.max_rotor_thrust))
    assert achieved[1] == pytest.approx(0.002, rel=1e-9)  # roll torque kept
    assert 0 < achieved[3] < 0.01  # yaw cut back
    too_much = np.array([hover, 1.0, 1.0, 0.0])  # roll and pitch beyond the rotors
    mixed, changed = mix(too_much, v.mixer, v.max_rotor_thrust)
    achieved = v.allocation @ mixed
    assert changed and np.all((mixed >= 0) & (mixed <= v.max_rotor_thrust + 1e-15))
    assert achieved[1] == pytest.approx(achieved[2], rel=1e-9)  # direction kept


def test_rotor_geometry_signs():
    a = allocation_matrix(TELLO)
    # rotor 1 front-right, 2 back-left, 3 front-left, 4 back-right (PX4 quad X)
    assert np.allclose(a[0], 1.0)
    assert a[1, 0] < 0 and a[1, 2] > 0  # right rotors roll left-wing-up negative
    assert a[2, 0] < 0 and a[2, 1] > 0  # front rotors pitch nose up negative
    assert a[3, 0] < 0 and a[3, 2] > 0  # counter-clockwise rotors twist the body clockwise


# ---------------------------------------------------------------------------- dynamics
def _fly(params, state, commands, seconds, dt=0.001, floor_z=-math.inf, force=(0, 0, 0),
         wind=(0, 0, 0)):
    v = vehicle_arrays(params)
    x = np.array(state, dtype=float)
    work = rk4_workspace()
    for _ in range(round(seconds / dt)):
        rk4_step(x, np.asarray(commands, dtype=float), v, np.asarray(force, float),
                 np.asarray(wind, float), dt, floor_z, work)
    return x


@pytest.mark.parametrize("params", [TELLO, RBE595], ids=["tello", "rbe595"])
def test_hover_commands_hold_a_hover_state(params):
    state = hover_state(params, [1.0, 2.0, 3.0], yaw=0.7)
    end = _fly(params, state, [params.hover_command] * 4, 5.0)
    assert np.allclose(end, state, atol=1e-9)


def test_free_fall_follows_gravity_and_the_floor_stops_it():
    params = TELLO.replace(drag=np.zeros(3))
    state = np.zeros(STATE_SIZE)
    state[2] = 10.0
    state[6] = 1.0
    end = _fly(params, state, [0.0] * 4, 1.0)
    assert end[2] == pytest.approx(10.0 - 0.5 * params.gravity, abs=1e-9)
    assert end[5] == pytest.approx(-params.gravity, abs=1e-9)
    landed = _fly(params, state, [0.0] * 4, 2.0, floor_z=0.0)
    assert landed[2] == 0.0 and np.all(landed[3:6] == 0.0)


def test_motors_lag_their_command_with_the_stated_time_constant():
    state = hover_state(TELLO, [0, 0, 5])
    state[13:17] = 0.0
    tau = TELLO.motor_time_constant
    end = _fly(TELLO, state, [1.0] * 4, tau)
    assert end[13] == pytest.approx(TELLO.rotor_speed_max * (1 - math.exp(-1)), rel=1e-6)
    speeds = np.empty(4)
    rotor_speed_commands(np.array([0.25, 1.0, -1.0, 2.0]), vehicle_arrays(TELLO), speeds)
    assert np.allclose(speeds, TELLO.rotor_speed_max * np.array([0.5, 1.0, 0.0, 1.0]))


def test_more_thrust_on_the_clockwise_rotors_yaws_counter_clockwise():
    state = hover_state(TELLO, [0, 0, 5])
    h = TELLO.hover_command
    end = _fly(TELLO, state, [h * 0.9, h * 0.9, h * 1.1, h * 1.1], 0.2)
    assert end[12] > 0.1  # body yaw rate, rad/s, about +z
    assert abs(end[10]) < 1e-9 and abs(end[11]) < 1e-9


def test_drag_gives_the_terminal_speed_of_a_constant_push():
    params = TELLO.replace(drag=np.array([0.05, 0.05, 0.05]))
    state = hover_state(params, [0, 0, 5])
    end = _fly(params, state, [params.hover_command] * 4, 10.0, force=(0.05, 0, 0))
    # v(t) = (push / drag) (1 - exp(-drag t / m))
    assert end[3] == pytest.approx(1.0 - math.exp(-0.05 * 10.0 / params.mass), rel=1e-9)


def test_rotor_drag_near_the_hover_is_the_hover_drag_and_the_parasitic_drag_is_quadratic():
    """A level vehicle, its rotors at the hover speed, flying at ``v`` along body x meets
    ``-hover_drag v`` from its rotors' drag (``4 w_hover k_d v``) and ``-c_D v^2`` from its
    frame, and neither lifts nor turns it."""
    params = TELLO.replace(drag=np.zeros(3), rotor_drag=np.array([2e-6, 2e-6, 1e-6]),
                           parasitic_drag=np.array([0.01, 0.01, 0.02]))
    assert params.hover_drag[0] == pytest.approx(4 * params.hover_rotor_speed * 2e-6)
    for speed in (0.5, 2.0):
        state = hover_state(params, [0, 0, 5])
        state[3] = speed
        out = np.empty(STATE_SIZE)
        derivative(state, state[13:17].copy(), vehicle_arrays(params), np.zeros(3),
                   np.zeros(3), out)
        drag = params.hover_drag[0] * speed + 0.01 * speed ** 2
        assert out[3] == pytest.approx(-drag / params.mass, rel=1e-12)
        assert abs(out[5]) < 1e-12 and np.allclose(out[10:13], 0.0, atol=1e-9)


def test_a_wind_drags_the_vehicle_along_on_its_airspeed_to_the_winds_own_speed():
    params = TELLO.replace(drag=np.array([0.05, 0.05, 0.05]))
    state = hover_state(params, [0, 0, 5])
    end = _fly(params, state, [params.hover_command] * 4, 10.0, wind=(2.0, -1.0, 0))
    # at rest in a 2 m/s wind the drag pushes as in still air at -2 m/s; the vehicle
    # speeds up to the wind's velocity: v(t) = wind (1 - exp(-drag t / m))
    approach = 1.0 - math.exp(-0.05 * 10.0 / params.mass)
    assert end[3:5] == pytest.approx(np.array([2.0, -1.0]) * approach, rel=1e-9)
    # moving with the wind, there is no drag at all
    state[3:6] = [2.0, -1.0, 0.0]
    end = _fly(params, state, [params.hover_command] * 4, 1.0, wind=(2.0, -1.0, 0))
    assert end[3:6] == pytest.approx([2.0, -1.0, 0.0], abs=1e-12)


def test_quaternion_round_trips_through_a_matrix():
    rng = np.random.default_rng(0)
    for q in rng.normal(size=(50, 4)):
        q /= np.linalg.norm(q)
        q *= np.sign(q[0])
        r = quaternion.to_matrix(q)
        assert np.allclose(r @ r.T, np.eye(3), atol=1e-12)
        assert np.allclose(quaternion.from_matrix(r), q, atol=1e-12)


@pytest.mark.parametrize("params", [TELLO, RBE595], ids=["tello", "rbe595"])
@pytest.mark.parametrize("axis", [0, 1], ids=["roll", "pitch"])
def test_the_roll_pitch_acceleration_bound_is_what_the_rotors_give_about_the_hover(params,
                                                                                   axis):
    # The rotors on one side at the hover's thrust plus the most they can add, on the
    # other minus as much: the dynamics turn the body at the bound, hold the height and
    # make no yaw.
    hover = params.weight / 4
    change = min(hover, params.max_rotor_thrust - hover)
    lever = rotor_positions(params)[:, 1 - axis] * (1 if axis == 0 else -1)
    commands = np.where(lever > 0, hover + change, hover - change) / params.max_rotor_thrust
    state = hover_state(params, [0.0, 0.0, 5.0])
    state[13:17] = params.rotor_speed_max * np.sqrt(commands)  # no motor lag to wait for
    dt = 1e-5
    end = _fly(params, state, commands, dt, dt=dt)
    rates = end[10:13] / dt  # body rates gained over dt, rad/s^2
    assert rates[axis] == pytest.approx(roll_pitch_acceleration_max(params), rel=1e-6)
    assert abs(rates[1 - axis]) < 1e-9 and abs(rates[2]) < 1e-9
    assert abs(end[5]) < 1e-12  # the collective still holds the weight
    assert roll_pitch_acceleration_max(RBE595) == pytest.approx(3.4326, rel=1e-4)

"""A quadnav vehicle as rotorpy's parameter dict: rotorpy's own model of the vehicle, built
from the dict, pushes and turns it as quadnav's dynamics do."""

from __future__ import annotations

import numpy as np
import pytest

from quadnav.vehicle.dynamics import STATE_SIZE, derivative, vehicle_arrays
from quadnav.vehicle.params import load_params
from quadnav.vehicle.rotorpy_params import rotorpy_params

multirotor = pytest.importorskip("rotorpy.vehicles.multirotor",
                                 reason="rotorpy (quadnav[test]) is not installed")

TELLO = load_params("tello")


def rotorpy_derivative(params: dict, x: np.ndarray, target: np.ndarray, wind: np.ndarray,
                       aero: bool) -> np.ndarray:
    """d state / dt (17,) in quadnav's layout by rotorpy's Multirotor built from ``params``:
    state ``x`` (17,), rotor speed targets (4,) rad/s, wind velocity (3,) m/s."""
    vehicle = multirotor.Multirotor(params, aero=aero)
    q = x[6:10]
    s = np.concatenate([x[0:6], [q[1], q[2], q[3], q[0]], x[10:13], wind, x[13:17]])
    d = vehicle._s_dot_fn(0.0, s, target)
    return np.concatenate([d[0:6], [d[9], d[6], d[7], d[8]], d[10:13], d[16:20]])


def quadnav_derivative(vehicle, x, target, wind):
    out = np.empty(STATE_SIZE)
    derivative(x, target, vehicle_arrays(vehicle), np.zeros(3), wind, out)
    return out


def random_state(rng, vehicle, rotor_speeds):
    x = np.empty(STATE_SIZE)
    x[0:6] = rng.normal(size=6)
    q = rng.normal(size=4)
    x[6:10] = q / np.linalg.norm(q)
    x[10:13] = rng.normal(size=3) * 3.0
    x[13:17] = rotor_speeds
    return x


@pytest.mark.parametrize("preset", ["tello", "rbe595"])
def test_rotorpy_pushes_and_turns_a_vehicle_without_drag_as_quadnav_does(preset):
    vehicle = load_params(preset).replace(drag=np.zeros(3))
    params = rotorpy_params(vehicle)
    rng = np.random.default_rng(3)
    for _ in range(20):  # any attitude, body rates and rotor speeds: every rotor's place,
        # spin, thrust and yaw torque, the inertia and the motor lag
        x = random_state(rng, vehicle, rng.uniform(0.2, 1.0, 4) * vehicle.rotor_speed_max)
        target = rng.uniform(0.0, 1.0, 4) * vehicle.rotor_speed_max
        wind = rng.normal(size=3)
        ours = quadnav_derivative(vehicle, x, target, wind)
        theirs = rotorpy_derivative(params, x, target, wind, aero=False)
        assert theirs == pytest.approx(ours, rel=1e-9, abs=1e-9 * np.max(np.abs(ours)))


def test_quadnavs_drag_is_rotorpys_rotor_drag_at_the_hover_speed_on_the_airspeed():
    params = rotorpy_params(TELLO)
    hover = TELLO.rotor_speed_max * np.sqrt(TELLO.hover_command)
    assert params["c_Dx"] == params["c_Dy"] == params["c_Dz"] == 0.0
    assert params["k_d"] == pytest.approx(0.04 / (4 * hover), rel=1e-12)
    assert params["k_z"] == pytest.approx(0.06 / (4 * hover), rel=1e-12)
    rng = np.random.default_rng(4)
    for _ in range(20):  # rotors at hover, no body rates: the rotor drags sum to a linear drag
        x = random_state(rng, TELLO, np.full(4, hover))
        x[10:13] = 0.0
        wind = rng.normal(size=3) * 2.0
        ours = quadnav_derivative(TELLO, x, x[13:17], wind)
        theirs = rotorpy_derivative(params, x, x[13:17], wind, aero=True)
        assert theirs[3:6] == pytest.approx(ours[3:6], rel=1e-9, abs=1e-12)
        assert theirs[10:13] == pytest.approx(ours[10:13], abs=1e-9)


def test_the_dict_has_rotorpys_keys_and_quadnavs_rotor_order():
    params = rotorpy_params(TELLO)
    from rotorpy.vehicles.crazyflie_params import quad_params

    inner_loops = {"k_w", "k_v", "kp_att", "kd_att"}  # rotorpy's own inner loops' gains
    assert set(params) == set(quad_params) - inner_loops
    assert list(params["rotor_pos"]) == ["r1", "r2", "r3", "r4"]
    front_right, back_left, front_left, back_right = params["rotor_pos"].values()
    assert front_right[0] > 0 > front_right[1] and back_left[0] < 0 < back_left[1]
    assert front_left[0] > 0 and front_left[1] > 0 and back_right[0] < 0 and back_right[1] < 0
    assert np.linalg.norm(front_right) == pytest.approx(TELLO.arm_length)
    assert params["mass"] == TELLO.mass and params["k_eta"] == TELLO.thrust_coefficient

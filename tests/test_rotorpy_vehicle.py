"""A rotorpy parameter dict as a quadnav vehicle (``--params module:NAME`` or
``file.py:NAME``): what maps onto what, the layouts and values refused, and flying one."""

from __future__ import annotations

import math

import numpy as np
import pytest
from clitools import assert_user_error, run_here

from quadnav.batch.fly_one import load_context, mission_settings
from quadnav.batch.grid import read_spec, spec_from_table
from quadnav.control.gains import Gains
from quadnav.errors import QuadnavError
from quadnav.missionconfig import spread_factors
from quadnav.trajectory.envelope import vehicle_limits
from quadnav.vehicle.params import load_params
from quadnav.vehicle.rotorpy_params import body_box, rotor_layout, vehicle_from_rotorpy

pytest.importorskip("rotorpy", reason="rotorpy (quadnav[test]) is not installed")
from rotorpy.vehicles import crazyflie_params, hummingbird_params, px4_sihsim_quadx_params

CRAZYFLIE = "rotorpy.vehicles.crazyflie_params:quad_params"
SMALL = "forest:size=12x12x4,seed=2"
#: A user's own vehicle file: rotorpy's keys, plain Python (no rotorpy import), two dicts.
MY_PARAMS = """\
import numpy as np

d = 0.1
quad_params = {
    "mass": 0.25, "Ixx": 4e-4, "Iyy": 5e-4, "Izz": 8e-4, "Ixy": 0.0, "Ixz": 0.0, "Iyz": 0.0,
    "num_rotors": 4,
    "rotor_pos": {"front_right": d * np.array([1, -1, 0]) / np.sqrt(2),
                  "back_left": d * np.array([-1, 1, 0]) / np.sqrt(2),
                  "front_left": d * np.array([1, 1, 0]) / np.sqrt(2),
                  "back_right": d * np.array([-1, -1, 0]) / np.sqrt(2)},
    "rotor_directions": np.array([-1, -1, 1, 1]),
    "k_eta": 2e-7, "k_m": 4e-9, "tau_m": 0.03, "rotor_speed_min": 0, "rotor_speed_max": 2500,
    "k_d": 2e-6, "k_z": 1e-6, "c_Dx": 0.01, "c_Dy": 0.01, "c_Dz": 0.02,
    "k_w": 1, "k_v": 10, "kp_att": 544, "kd_att": 46.64, "rI": np.zeros(3),
}
small = {**quad_params, "mass": 0.2}
"""


@pytest.fixture
def my_params(tmp_path):
    path = tmp_path / "my_params.py"
    path.write_text(MY_PARAMS)
    return path


def test_the_crazyflie_maps_key_by_key():
    vehicle = load_params(CRAZYFLIE)
    assert vehicle.name == "crazyflie_params"
    assert vehicle.mass == 0.03
    assert np.array_equal(vehicle.inertia, [1.43e-5, 1.43e-5, 2.89e-5])
    assert vehicle.arm_length == pytest.approx(0.043, rel=1e-9)
    assert (vehicle.thrust_coefficient, vehicle.torque_coefficient) == (2.3e-08, 7.8e-10)
    assert (vehicle.motor_time_constant, vehicle.rotor_speed_max) == (0.072, 2500.0)
    assert np.array_equal(vehicle.rotor_drag, [10.2506e-07, 10.2506e-07, 7.553e-07])
    assert np.array_equal(vehicle.parasitic_drag, [0, 0, 0]) and np.array_equal(vehicle.drag,
                                                                                 [0, 0, 0])
    assert vehicle.translational_lift == 0 and vehicle.flapping == 0
    # the box: hubs 0.0304 m each side of the centre, and a propeller of as much beyond
    hub = 0.043 / math.sqrt(2)
    assert np.allclose(vehicle.body_size, [4 * hub, 4 * hub, 2 * hub], rtol=1e-9)


def test_a_dict_with_a_rotor_radius_and_every_aerodynamic_term():
    params = hummingbird_params.quad_params
    vehicle = vehicle_from_rotorpy(params, "hummingbird")
    assert np.array_equal(vehicle.rotor_drag, [1.19e-04, 1.19e-04, 2.32e-04])
    assert np.array_equal(vehicle.parasitic_drag, [0.5e-2, 0.5e-2, 1e-2])
    assert vehicle.translational_lift == 3.39e-3
    assert np.allclose(vehicle.body_size, body_box(0.17, 0.10))
    assert vehicle.body_size[0] == pytest.approx(2 * (0.17 / math.sqrt(2) + 0.10))


def test_each_of_rotorpys_rotors_is_one_of_quadnavs():
    """rotorpy's crazyflie numbers its rotors front left, front right, back right, back left;
    quadnav (PX4) front right, back left, front left, back right. The PX4 SIH dict numbers
    them as quadnav does, its arms along (1, 1) d, so 0.24 m long."""
    assert rotor_layout(crazyflie_params.quad_params, "crazyflie")[1] == [2, 0, 3, 1]
    arm, corners = rotor_layout(px4_sihsim_quadx_params.quad_params, "px4")
    assert corners == [0, 1, 2, 3] and arm == pytest.approx(0.17 * math.sqrt(2))


def test_a_users_file_names_its_vehicle_and_keywords_replace_its_keys(my_params):
    vehicle = load_params(f"{my_params}:quad_params")
    assert vehicle.name == "my_params" and vehicle.mass == 0.25
    assert vehicle.arm_length == pytest.approx(0.1)
    assert np.array_equal(vehicle.parasitic_drag, [0.01, 0.01, 0.02])
    assert load_params(f"{my_params}:small").name == "my_params.small"
    plain = load_params(f"{my_params}:quad_params(k_d=0, k_z=0.0, mass=0.3)")
    assert np.array_equal(plain.rotor_drag, [0, 0, 0]) and plain.mass == 0.3


def test_the_envelope_counts_the_rotor_drag_near_the_hover():
    vehicle = load_params(CRAZYFLIE)
    hover = vehicle.rotor_speed_max * math.sqrt(vehicle.hover_command)
    drag = 4 * hover * np.array([10.2506e-07, 10.2506e-07, 7.553e-07]) / vehicle.mass
    assert np.allclose(vehicle_limits(vehicle, Gains()).drag, drag, rtol=1e-12)


PLUS = "{'a': [0.1, 0, 0], 'b': [0, 0.1, 0], 'c': [-0.1, 0, 0], 'd': [0, -0.1, 0]}"
RAISED = ("{'a': [0.0707, -0.0707, 0.02], 'b': [-0.0707, 0.0707, 0], 'c': [0.0707, 0.0707, 0], "
          "'d': [-0.0707, -0.0707, 0]}")


@pytest.mark.parametrize(("keywords", "message"), [
    ("Ixy=1e-6", "Ixy must be 0, got 1e-06 kg m^2 (quadnav's inertia is diagonal"),
    ("rotor_speed_min=100", "rotor_speed_min must be 0, got 100 rad/s"),
    ("num_rotors=6", "num_rotors and rotor_pos must give 4 rotors"),
    (f"rotor_pos={PLUS}", "rotor a at (0.1, 0, 0) m: quadnav flies the X layout"),
    (f"rotor_pos={RAISED}", "rotor a at (0.0707, -0.0707, 0.02) m: quadnav flies the X layout"),
    ("rotor_directions=[1, 1, -1, -1]", "rotor front_right at (0.07071, -0.07071, 0) m has "
     "direction 1; quadnav's rotors turn counter-clockwise (rotorpy's direction -1) at the "
     "front right"),
    ("rotor_directions=[1, 1]", "rotor_directions must be 4 finite numbers"),
    ("mass='heavy'", "mass must be a number, got 'heavy'"),
    ("k_eta=float('nan')", "not a literal"),
    ("mass=1.0", "the rotors lift 5 N in all, not more than the weight 9.81 N"),
    ("k_d=-1e-6", "rotor_drag must be >= 0"),
    ("kd=0", "unknown key 'kd'"),
])
def test_a_dict_quadnav_cannot_fly_is_one_line_naming_it(my_params, keywords, message):
    spec = f"{my_params}:quad_params({keywords})"
    with pytest.raises(QuadnavError) as error:
        load_params(spec)
    assert message in str(error.value) and "\n" not in str(error.value)
    assert str(my_params) in str(error.value)


def test_what_is_not_a_rotorpy_dict_is_named(my_params):
    with pytest.raises(QuadnavError, match="expected a rotorpy parameter dict, got float"):
        load_params(f"{my_params}:d")
    with pytest.raises(QuadnavError, match="missing k_eta, tau_m"):
        vehicle_from_rotorpy({"mass": 1.0, "Ixx": 1, "Iyy": 1, "Izz": 1, "k_m": 1,
                              "rotor_speed_max": 1, "num_rotors": 4, "rotor_pos": {},
                              "rotor_directions": []}, "bare")
    with pytest.raises(QuadnavError, match="no module named 'no_such_vehicles'"):
        load_params("no_such_vehicles:quad_params")


def test_fly_a_rotorpy_vehicle_and_refuse_a_bad_one(tmp_path, my_params):
    result = run_here("fly", SMALL, "--params", CRAZYFLIE, "--no-figures", "-o", tmp_path / "a")
    assert result.returncode == 0, result.stderr
    assert "success" in result.stdout and "vehicle crazyflie_params" in result.stdout
    out = tmp_path / "b"
    assert_user_error(run_here("fly", SMALL, "--params", f"{my_params}:quad_params(Ixy=1e-6)",
                               "-o", out), "Ixy must be 0")
    assert not out.exists()


def test_a_batch_names_a_rotorpy_vehicle_by_a_file_beside_its_spec(my_params):
    spec = my_params.parent / "spec.toml"
    spec.write_text("seeds = 1\nspeeds = [1]\nmaps = ['forest']\n"
                    "vehicle = 'my_params.py:quad_params(k_d=0)'\n")
    assert read_spec(spec).fixed.vehicle == f"{my_params}:quad_params(k_d=0)"
    spec.write_text(spec.read_text().replace("k_d=0", "Ixy=1e-6"))
    with pytest.raises(QuadnavError, match=r"spec.toml:4: vehicle: vehicle .* Ixy must be 0"):
        read_spec(spec)


def test_a_batch_spread_scales_the_rotor_and_parasitic_drag_with_the_linear(my_params):
    spec = spec_from_table({"maps": ["forest"], "seeds": [4], "speeds": [1.0], "spreads": [0.3],
                            "vehicle": "my_params.py:quad_params"}, my_params.parent)
    context = load_context(spec)
    mission = spec.missions()[0]
    plant = mission_settings(context, mission).plant
    drag = spread_factors(mission.spread, mission.seed)[2]
    assert drag != 1.0 and plant is not None
    for key in ("rotor_drag", "parasitic_drag"):
        assert np.allclose(getattr(plant, key), getattr(context.vehicle, key) * drag, rtol=1e-15)

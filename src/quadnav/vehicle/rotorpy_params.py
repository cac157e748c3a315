"""A quadnav vehicle as rotorpy's parameter dict: :func:`rotorpy_params`.

rotorpy (the UPenn simulator) builds a controller with a dict of the vehicle's parameters,
keyed as in ``rotorpy/vehicles/crazyflie_params.py``; quadnav hands such a dict to a
plain-Python controller (:mod:`quadnav.control.plain`), so that a controller
written for rotorpy runs unchanged. The rotors are listed in quadnav's order
(:mod:`quadnav.vehicle.rotors`: 1 front-right, 2 back-left, 3 front-left, 4 back-right), so
the per-rotor commands such a controller returns are in quadnav's order too.
"""

from __future__ import annotations

import math

import numpy as np

from quadnav.vehicle.params import VehicleParams
from quadnav.vehicle.rotors import SPIN, rotor_positions


def rotorpy_params(vehicle: VehicleParams) -> dict:
    """``vehicle`` as rotorpy's parameter dict (``quad_params``).

    Keys and how each is read from ``vehicle``:

    - ``mass`` kg; ``Ixx``, ``Iyy``, ``Izz`` kg m^2 (``inertia``), ``Ixy``, ``Iyz``,
      ``Ixz`` = 0 (principal axes).
    - ``num_rotors`` = 4; ``rotor_pos``: ``{"r1": (3,), ... "r4": (3,)}`` m, body frame,
      quadnav's rotor order (:func:`~quadnav.vehicle.rotors.rotor_positions`);
      ``rotor_directions`` (4,): rotorpy's sign of each rotor's yaw torque
      (``rotor_dir k_m w^2``), so ``-SPIN`` (quadnav twists the body by ``-s k_m w^2``);
      ``rI`` = 0 (the IMU at the centre of mass).
    - ``k_eta`` N/(rad/s)^2 (``thrust_coefficient``), ``k_m`` N m/(rad/s)^2
      (``torque_coefficient``), ``tau_m`` s (``motor_time_constant``),
      ``rotor_speed_min`` = 0 and ``rotor_speed_max`` rad/s, ``motor_noise_std`` = 0.
    - Drag: quadnav's is linear in the body-frame velocity, ``drag`` (3,) N/(m/s);
      rotorpy's parasitic drag ``c_Dx``, ``c_Dy``, ``c_Dz`` is quadratic, so it is 0, and
      its rotor drag (``k_d`` along body x and y, ``k_z`` along z, per rotor and per rad/s
      of rotor speed) carries quadnav's drag at the hover rotor speed ``w_h``:
      ``k_d = (drag_x + drag_y) / 2 / (4 w_h)``, ``k_z = drag_z / (4 w_h)`` (the four
      rotors at ``w_h`` then drag as quadnav's vehicle does). ``k_h`` and ``k_flap`` = 0.

    rotorpy's keys for its own inner loops (``k_w``, ``k_v``, ``kp_att``, ``kd_att``) are
    left out: quadnav's inner loops are its own (a controller that reads them with
    ``dict.get`` takes its default, as rotorpy's ``SE3Control`` does: 310 and 57).
    """
    hover_speed = vehicle.rotor_speed_max * math.sqrt(vehicle.hover_command)
    per_rotor = 4.0 * hover_speed
    inertia = [float(value) for value in vehicle.inertia]
    return {
        "mass": float(vehicle.mass),
        "Ixx": inertia[0], "Iyy": inertia[1], "Izz": inertia[2],
        "Ixy": 0.0, "Iyz": 0.0, "Ixz": 0.0,
        "num_rotors": 4,
        "rotor_pos": {f"r{i + 1}": position
                      for i, position in enumerate(rotor_positions(vehicle))},
        "rotor_directions": -SPIN.copy(),
        "rI": np.zeros(3),
        "c_Dx": 0.0, "c_Dy": 0.0, "c_Dz": 0.0,
        "k_eta": float(vehicle.thrust_coefficient),
        "k_m": float(vehicle.torque_coefficient),
        "k_d": float(vehicle.drag[0] + vehicle.drag[1]) / 2.0 / per_rotor,
        "k_z": float(vehicle.drag[2]) / per_rotor,
        "k_h": 0.0,
        "k_flap": 0.0,
        "tau_m": float(vehicle.motor_time_constant),
        "rotor_speed_min": 0.0,
        "rotor_speed_max": float(vehicle.rotor_speed_max),
        "motor_noise_std": 0.0,
    }

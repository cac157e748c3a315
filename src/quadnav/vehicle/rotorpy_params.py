"""quadnav's vehicles and rotorpy's parameter dicts (the ``quad_params`` of
``rotorpy/vehicles/*_params.py``).

:func:`vehicle_from_rotorpy` reads a rotorpy dict as a :class:`VehicleParams`, key by key:

================================  ==========================================================
rotorpy                           quadnav
================================  ==========================================================
``mass``                          ``mass``
``Ixx``, ``Iyy``, ``Izz``         ``inertia``; ``Ixy``, ``Ixz``, ``Iyz`` must be 0 (quadnav's
                                  inertia is diagonal)
``num_rotors``, ``rotor_pos``,    ``arm_length``: four rotors in the X layout of
``rotor_directions``              :mod:`quadnav.vehicle.rotors`, in any order and under any
                                  names, spinning as quadnav's do (direction -1, a rotor
                                  turning counter-clockwise, at the front right and the back
                                  left)
``k_eta``, ``k_m``                ``thrust_coefficient``, ``torque_coefficient``
``tau_m``                         ``motor_time_constant``
``rotor_speed_max``               ``rotor_speed_max``; ``rotor_speed_min`` must be 0
``k_d``, ``k_z``                  ``rotor_drag`` = ``(k_d, k_d, k_z)``
``c_Dx``, ``c_Dy``, ``c_Dz``      ``parasitic_drag``
``k_h``, ``k_flap``               ``translational_lift``, ``flapping``
(none)                            ``drag`` (linear) 0; ``body_size``: :func:`body_box`
================================  ==========================================================

The aerodynamic keys that are missing count as 0, as rotorpy reads them. Ignored: ``rI``
(quadnav measures at the centre), ``motor_noise_std`` (quadnav's sensor noise is its own,
``--noise``), ``ground_friction_beta`` (quadnav's floor is its own), and rotorpy's
inner-loop gains ``k_w``, ``k_v``, ``kp_att``, ``kd_att``, which belong to the controllers
that use them, not to the vehicle. ``rotor_radius``, when given, sizes the body box.

:func:`rotorpy_params` goes the other way, for a plain-Python controller written for rotorpy
(:mod:`quadnav.control.plain`), which is built with such a dict: the rotors in quadnav's
order (1 front-right, 2 back-left, 3 front-left, 4 back-right), so the per-rotor commands it
returns are in quadnav's order too.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from quadnav.arrays import FloatArray
from quadnav.config import frozen_vector
from quadnav.errors import QuadnavError
from quadnav.vehicle.params import VehicleParams
from quadnav.vehicle.rotors import ROTOR_DIRECTIONS, SPIN

#: Relative tolerance of the rotor layout: rotorpy's dicts write 1/sqrt(2) to 11 digits.
_LAYOUT_TOLERANCE = 1e-6
#: Products of inertia up to this share of the largest moment count as 0 (round-off).
_PRODUCT_TOLERANCE = 1e-9
#: Keys quadnav reads besides the required ones, with rotorpy's defaults.
_OPTIONAL = {"Ixy": 0.0, "Ixz": 0.0, "Iyz": 0.0, "rotor_speed_min": 0.0,
             "c_Dx": 0.0, "c_Dy": 0.0, "c_Dz": 0.0, "k_d": 0.0, "k_z": 0.0, "k_h": 0.0,
             "k_flap": 0.0}
#: The numbers quadnav must have, and the rotor layout.
_NUMBERS = ("mass", "Ixx", "Iyy", "Izz", "k_eta", "k_m", "tau_m", "rotor_speed_max")
_REQUIRED = (*_NUMBERS, "num_rotors", "rotor_pos", "rotor_directions")
#: Every key :func:`vehicle_from_rotorpy` reads.
ROTORPY_KEYS = frozenset((*_REQUIRED, *_OPTIONAL, "rotor_radius"))


def vehicle_from_rotorpy(params: Mapping[str, Any], name: str,
                         where: str | None = None) -> VehicleParams:
    """The quadnav vehicle a rotorpy parameter dict describes (see the module docstring
    for what maps onto what).

    Args:
        params: rotorpy's parameter dict, e.g. ``rotorpy.vehicles.crazyflie_params.quad_params``.
        name: the vehicle's name, for reports.
        where: what messages name (default ``rotorpy vehicle NAME``).

    Raises:
        QuadnavError: a missing key, a value that is not a finite number (or a vector of
            them), products of inertia, a layout other than quadnav's X with its spins,
            a minimum rotor speed, or a vehicle its rotors cannot lift.
    """
    where = where or f"rotorpy vehicle {name}"
    missing = [key for key in _REQUIRED if key not in params]
    if missing:
        raise QuadnavError(f"{where}: missing {', '.join(missing)} (expected rotorpy's "
                           "keys, as in rotorpy/vehicles/crazyflie_params.py)")
    number = {key: _number(params.get(key, _OPTIONAL.get(key)), key, where)
              for key in (*_NUMBERS, *_OPTIONAL)}
    inertia = np.array([number["Ixx"], number["Iyy"], number["Izz"]])
    for key in ("Ixy", "Ixz", "Iyz"):
        if abs(number[key]) > _PRODUCT_TOLERANCE * np.max(np.abs(inertia)):
            raise QuadnavError(f"{where}: {key} must be 0, got {number[key]:g} kg m^2 "
                               "(quadnav's inertia is diagonal: principal axes along the "
                               "body's)")
    if number["rotor_speed_min"] != 0:
        raise QuadnavError(f"{where}: rotor_speed_min must be 0, got "
                           f"{number['rotor_speed_min']:g} rad/s (quadnav's rotors slow "
                           "down to a stop)")
    arm, _ = rotor_layout(params, where)
    radius = params.get("rotor_radius")
    try:
        return VehicleParams(
            name=name, mass=number["mass"], inertia=frozen_vector(inertia, 3),
            arm_length=arm, thrust_coefficient=number["k_eta"],
            torque_coefficient=number["k_m"], rotor_speed_max=number["rotor_speed_max"],
            motor_time_constant=number["tau_m"], drag=frozen_vector((0.0, 0.0, 0.0), 3),
            rotor_drag=frozen_vector((number["k_d"], number["k_d"], number["k_z"]), 3),
            parasitic_drag=frozen_vector([number[f"c_D{a}"] for a in "xyz"], 3),
            translational_lift=number["k_h"], flapping=number["k_flap"],
            body_size=body_box(arm, None if radius is None
                               else _number(radius, "rotor_radius", where)))
    except QuadnavError as error:
        raise QuadnavError(f"{where}: {error}") from None


def rotorpy_params(vehicle: VehicleParams) -> dict:
    """``vehicle`` as rotorpy's parameter dict (``quad_params``), the keys of the module
    docstring's table read the other way: ``rotor_pos`` (``r1`` to ``r4``, m) in quadnav's
    rotor order with ``rotor_directions`` = ``-SPIN``, ``Ixy`` = ``Iyz`` = ``Ixz`` = 0,
    ``rotor_speed_min`` = 0, ``rI`` = 0, ``motor_noise_std`` = 0, and rotorpy's aerodynamic
    keys from the vehicle's. quadnav's linear ``drag`` (3,) N/(m/s) has no rotorpy key: it
    joins the rotor drag as the four rotors would make it at the hover speed ``w_h``, so
    ``k_d`` and ``k_z`` are :attr:`~quadnav.vehicle.params.VehicleParams.hover_drag` over
    ``4 w_h`` (x and y averaged). rotorpy's inner-loop gains (``k_w``, ``k_v``, ``kp_att``,
    ``kd_att``) are left out: a controller that reads them with ``dict.get`` takes its
    default, as rotorpy's ``SE3Control`` does (310 and 57)."""
    drag = vehicle.hover_drag / (4.0 * vehicle.hover_rotor_speed)  # per rotor, per rad/s
    inertia = [float(value) for value in vehicle.inertia]
    return {
        "mass": float(vehicle.mass),
        "Ixx": inertia[0], "Iyy": inertia[1], "Izz": inertia[2],
        "Ixy": 0.0, "Iyz": 0.0, "Ixz": 0.0,
        "num_rotors": 4,
        "rotor_pos": {f"r{i + 1}": np.append(vehicle.arm_length * direction, 0.0)
                      for i, direction in enumerate(ROTOR_DIRECTIONS)},
        "rotor_directions": -SPIN.copy(),
        "rI": np.zeros(3),
        "c_Dx": float(vehicle.parasitic_drag[0]), "c_Dy": float(vehicle.parasitic_drag[1]),
        "c_Dz": float(vehicle.parasitic_drag[2]),
        "k_eta": float(vehicle.thrust_coefficient),
        "k_m": float(vehicle.torque_coefficient),
        "k_d": float(drag[0] + drag[1]) / 2.0,
        "k_z": float(drag[2]),
        "k_h": float(vehicle.translational_lift),
        "k_flap": float(vehicle.flapping),
        "tau_m": float(vehicle.motor_time_constant),
        "rotor_speed_min": 0.0,
        "rotor_speed_max": float(vehicle.rotor_speed_max),
        "motor_noise_std": 0.0,
    }


def rotor_layout(params: Mapping[str, Any], where: str) -> tuple[float, list[int]]:
    """The distance, m, from the centre to each rotor of rotorpy's ``rotor_pos`` and
    ``rotor_directions``, and which of quadnav's rotors (0-3, :mod:`quadnav.vehicle.rotors`)
    each of rotorpy's is, in ``rotor_pos``'s order. QuadnavError unless they are quadnav's
    X layout: four rotors in the body's x-y plane on the diagonals at one distance, one
    per corner, spinning as :data:`quadnav.vehicle.rotors.SPIN` (rotorpy's direction is
    the sign of the rotor's yaw torque on the body, the opposite of quadnav's spin)."""
    count, positions, directions = (params["num_rotors"], params["rotor_pos"],
                                    params["rotor_directions"])
    if not (isinstance(positions, Mapping) and count == 4 and len(positions) == 4):
        raise QuadnavError(f"{where}: num_rotors and rotor_pos must give 4 rotors (quadnav "
                           f"flies quadrotors), got {count!r} and {_count(positions)}")
    spins = _vector(directions, 4, "rotor_directions", where)
    names = list(positions)
    hubs = np.array([_vector(positions[key], 3, f"rotor_pos[{key!r}]", where)
                     for key in names])
    arm = float(np.mean(np.hypot(hubs[:, 0], hubs[:, 1])))
    layout = ("quadnav flies the X layout: four rotors at one distance from the centre, "
              "one on each diagonal, in the body's x-y plane")
    corners: list[int] = []
    for key, hub, spin in zip(names, hubs, spins, strict=True):
        corner = int(np.argmax(ROTOR_DIRECTIONS @ hub[:2]))
        if (arm <= 0 or np.max(np.abs(hub - np.append(arm * ROTOR_DIRECTIONS[corner], 0.0)))
                > _LAYOUT_TOLERANCE * arm or corner in corners):
            raise QuadnavError(f"{where}: rotor {key} at {_point(hub)} m: {layout}")
        if spin != -SPIN[corner]:
            raise QuadnavError(
                f"{where}: rotor {key} at {_point(hub)} m has direction {spin:g}; quadnav's "
                "rotors turn counter-clockwise (rotorpy's direction -1) at the front right "
                "and the back left, clockwise (+1) at the front left and the back right")
        corners.append(corner)
    return arm, corners


def body_box(arm: float, rotor_radius: float | None = None) -> FloatArray:
    """The collision box (3,), m, of a rotorpy vehicle (rotorpy has none): across x and y,
    the rotor hubs (``arm / sqrt(2)`` each side of the centre) and a propeller beyond them
    (``rotor_radius``, or when rotorpy's dict has none the largest that fits: half the
    distance between neighbouring hubs, also ``arm / sqrt(2)``); half as tall as it is
    wide, the proportions of the ``tello`` preset's box."""
    hub = arm / math.sqrt(2.0)
    half_width = hub + (hub if rotor_radius is None else rotor_radius)
    return frozen_vector((2.0 * half_width, 2.0 * half_width, half_width), 3)


def _number(value: Any, key: str, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise QuadnavError(f"{where}: {key} must be a number, got {value!r}")
    if not math.isfinite(value):
        raise QuadnavError(f"{where}: {key} must be finite, got {value!r}")
    return float(value)


def _vector(value: Any, length: int, key: str, where: str) -> FloatArray:
    try:
        array = np.array(value, dtype=np.float64)
    except (TypeError, ValueError):
        array = np.empty(0)
    if array.shape != (length,) or not np.all(np.isfinite(array)):
        raise QuadnavError(f"{where}: {key} must be {length} finite numbers, got {value!r}")
    return array


def _count(positions: Any) -> str:
    return f"{len(positions)} positions" if isinstance(positions, Mapping) else repr(positions)


def _point(hub: FloatArray) -> str:
    return "(" + ", ".join(f"{c:.4g}" for c in hub) + ")"

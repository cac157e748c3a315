"""Can this vehicle, with this controller, fly this trajectory? Checked before flying.

The vehicle's rotors and the controller's saturations bound what a trajectory may ask:
the collective thrust (within the rotors' range, as the controller clips it), the tilt,
the roll and pitch rates and the (horizontal) speed. A trajectory may use :data:`HEADROOM` of each,
so the feedback that corrects tracking errors keeps the rest. :func:`check_flyable`
refuses a trajectory that asks for more, with the limit it breaks and the fastest
``--speed``/``--accel`` that would fly the same path within every limit.
"""

from __future__ import annotations

import math

import numpy as np

from quadnav.control.gains import Gains
from quadnav.errors import QuadnavError
from quadnav.trajectory.feasibility import (
    GRAVITY,
    FeasibilityReport,
    Limits,
    feasibility,
    slowest_feasible_scale,
)
from quadnav.trajectory.model import Trajectory
from quadnav.vehicle.params import VehicleParams

#: Fraction of each limit a trajectory may use; feedback keeps the rest.
HEADROOM = 0.9


def vehicle_limits(vehicle: VehicleParams, gains: Gains) -> Limits:
    """What a trajectory may ask of ``vehicle`` flown with ``gains``, with
    :data:`HEADROOM` (see the module docstring)."""
    limits = gains.limits
    weight_ratio = vehicle.max_total_thrust / (vehicle.mass * GRAVITY)
    return Limits(
        v_max=HEADROOM * limits.speed_xy,
        a_max=HEADROOM * limits.acceleration_xy,
        thrust_to_weight_max=HEADROOM * limits.thrust_max * weight_ratio,
        thrust_to_weight_min=limits.thrust_min * weight_ratio / HEADROOM,
        tilt_max=HEADROOM * math.radians(limits.tilt_max_deg),
        body_rate_max=HEADROOM * math.radians(float(np.min(limits.rate_max_deg[:2]))),
        drag=tuple(float(d) for d in vehicle.drag / vehicle.mass),
    )


def check_flyable(trajectory: Trajectory, vehicle: VehicleParams, gains: Gains,
                  speed: float, acceleration: float) -> FeasibilityReport:
    """The feasibility report of ``trajectory`` against :func:`vehicle_limits`;
    QuadnavError naming the broken limit and the fastest settings that would work when
    it is not flyable.

    Args:
        trajectory: the reference to fly.
        vehicle: the simulated quadrotor.
        gains: the controller, whose saturations count as limits.
        speed: the top speed the trajectory was made with, m/s (for the advice).
        acceleration: its acceleration limit, m/s^2 (for the advice).
    """
    limits = vehicle_limits(vehicle, gains)
    report = feasibility(trajectory, None, limits)
    if report.ok:
        return report
    scale = slowest_feasible_scale(trajectory, limits)
    advice = ("no slower flight of it would either" if scale is None else
              f"the same path flies within every limit at --speed {speed / scale:.3g} "
              f"--accel {acceleration / scale**2:.3g} or less")
    raise QuadnavError(f"the {vehicle.name} vehicle cannot fly this trajectory: "
                       f"{report.violations[0]} (with {1 - HEADROOM:.0%} kept for control); "
                       f"{advice}")

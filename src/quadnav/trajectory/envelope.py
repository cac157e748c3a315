"""Can this vehicle, with this controller, fly this trajectory? Checked before flying.

The vehicle's rotors and the controller's saturations bound what a trajectory may ask:
the collective thrust (within the rotors' range, as the controller clips it), the tilt,
the roll and pitch rates, the roll and pitch angular acceleration (the torque the rotors
give about the hover, :func:`~quadnav.vehicle.rotors.roll_pitch_acceleration_max`) and
the (horizontal) speed. A trajectory may use :data:`HEADROOM` of each (of the torque,
:data:`TORQUE_HEADROOM`), so the feedback that corrects tracking errors keeps the rest.
:func:`flyable_trajectory` makes the trajectory, and refuses one that asks for more with
the limit it breaks and the fastest ``--speed``/``--accel`` that flies the same path
within every limit — or, for ``--speed max``, flies that one. What the controller's
gains make of it is not bounded here: a vehicle that turns slowly may still track a
trajectory within every limit poorly at its top speed.
"""

from __future__ import annotations

import math

import numpy as np

from quadnav.arrays import FloatArray
from quadnav.control.gains import Gains
from quadnav.errors import QuadnavError
from quadnav.limits import ACCELERATION, SPEED
from quadnav.trajectory.clearance.space import SafeSpace
from quadnav.trajectory.feasibility import (
    GRAVITY,
    FeasibilityReport,
    Limits,
    feasibility,
    slowest_feasible_scale,
)
from quadnav.trajectory.generate import TrajectorySettings, make_trajectory
from quadnav.trajectory.model import Trajectory
from quadnav.vehicle.params import VehicleParams
from quadnav.vehicle.rotors import roll_pitch_acceleration_max

#: Fraction of each limit a trajectory may use; feedback keeps the rest.
HEADROOM = 0.9
#: Fraction of the rotors' roll and pitch torque a trajectory may use. The feedback keeps
#: half, as it corrects every attitude error with torque alone: on the slow-turning
#: ``rbe595`` preset, trajectories that asked for 90 % of it failed on two of the three
#: built-in worlds at 1 m/s; for the Tello the bound is far above what any course
#: trajectory asks.
TORQUE_HEADROOM = 0.5
#: Rounds of slowing a trajectory down (remaking it each time) until the vehicle flies it.
SLOWING_ROUNDS = 4
#: How much slower than the least slowing that would do the advice flies: the advice
#: must fly on any machine, so it keeps a margin to the limit it would otherwise meet
#: to the last digits (4 % of a roll/pitch acceleration, which goes as its 4th power).
ADVICE_SLACK = 1.01


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
        angular_acceleration_max=TORQUE_HEADROOM * roll_pitch_acceleration_max(vehicle),
        drag=tuple(float(d) for d in vehicle.hover_drag / vehicle.mass),
    )


def flyable_trajectory(path: FloatArray, settings: TrajectorySettings, space: SafeSpace,
                       vehicle: VehicleParams, gains: Gains, fastest: bool = False
                       ) -> tuple[Trajectory, TrajectorySettings]:
    """The trajectory through ``path`` (N, 3) that ``vehicle`` flies, and the settings
    that made it: ``settings``, told the vehicle's :func:`vehicle_limits` (so the timing
    slows where the roll/pitch rate would exceed them) — or, with ``fastest``, the
    vehicle's own top speed and acceleration, slowed as a whole until every limit holds.

    Raises:
        QuadnavError: the trajectory breaks a limit (not ``fastest``): the line names the
            limit and the fastest ``--speed``/``--accel`` at which the same path flies
            within every limit, found by making and checking that trajectory.
    """
    limits = vehicle_limits(vehicle, gains)
    chosen = settings.replace(vehicle=limits)
    if fastest:
        chosen = chosen.replace(v_max=min(limits.v_max, SPEED.high),
                                a_max=min(limits.a_max, ACCELERATION.high))
    trajectory = make_trajectory(path, chosen, space)
    report = feasibility(trajectory, None, limits)
    if report.ok:
        return trajectory, chosen
    slower = _slowed(path, chosen, space, trajectory, report, limits)
    if slower is not None and fastest:
        return slower
    advice = ("no slower flight of it would either" if slower is None else
              f"the same path flies within every limit at --speed "
              f"{_down(slower[1].v_max):g} --accel {_down(slower[1].a_max):g} or less")
    kept = (f"{1 - TORQUE_HEADROOM:.0%} of the torque"
            if report.broken[0] == "angular_acceleration_max" else f"{1 - HEADROOM:.0%}")
    raise QuadnavError(f"the {vehicle.name} vehicle cannot fly this trajectory: "
                       f"{report.violations[0]} (with {kept} kept for control); "
                       f"{advice}")


def _slowed(path: FloatArray, settings: TrajectorySettings, space: SafeSpace,
            trajectory: Trajectory, report: FeasibilityReport, limits: Limits
            ) -> tuple[Trajectory, TrajectorySettings] | None:
    """A slower trajectory through ``path`` within ``limits`` and its settings: the
    acceleration limit (and the top speed too, if the speed is what breaks a limit)
    lowered by the factor that would slow ``trajectory`` (whose feasibility is
    ``report``) into the limits, and :data:`ADVICE_SLACK` more, for up to
    :data:`SLOWING_ROUNDS` rounds; None if none is within."""
    for _ in range(SLOWING_ROUNDS):
        scale = slowest_feasible_scale(trajectory, limits)
        if scale is None:
            return None
        scale *= ADVICE_SLACK
        too_fast = report.max_speed.value > limits.v_max
        settings = settings.replace(
            v_max=_down(settings.v_max / scale) if too_fast else settings.v_max,
            a_max=_down(settings.a_max / scale**2))
        trajectory = make_trajectory(path, settings, space)
        report = feasibility(trajectory, None, limits)
        if report.ok:
            return trajectory, settings
    return None


def _down(value: float) -> float:
    """``value`` > 0 rounded down to 3 significant digits (advice that stays within)."""
    step = 10.0 ** (math.floor(math.log10(value)) - 2)
    return round(math.floor(value / step + 1e-9) * step, 12)

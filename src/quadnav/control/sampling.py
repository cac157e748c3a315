"""Whether a control rate is fast enough for a controller's gains: :func:`check_control_rate`.

The fastest loops of both built-in controllers are the attitude and body-rate loops of each
body axis, which command an angular acceleration (the gains are normalised by the inertia):

* the cascade: ``alpha = kp (ka (angle_sp - angle) - rate) + ki * integral - kd * d(rate)/dt``
  (the attitude P ``ka`` = ``attitude_kp``, the rate PID, its derivative of the measured rate
  low-pass filtered at ``derivative_cutoff_hz``);
* SE(3): ``alpha = -kR angle_error - kw rate_error``, the same with ``ka = kR / kw``,
  ``kp = kw`` and no I or D.

Linearised about the hover, one axis is a double integrator (angle, rate) behind the rotors'
first-order lag (``motor_time_constant``: the angular acceleration follows the command with
that lag), and the controller's command is held over each control period, as the closed
loop holds it. :func:`transition` is that sampled loop's exact transition over one period
(the plant's solution over a period in closed form, the controller's own states, integral and
derivative filter, as :mod:`quadnav.control.cascade` updates them). The loop is stable at a
control rate when every eigenvalue of the transition lies inside the unit circle.

**The criterion.** :func:`gain_margin` is the factor by which the controller's output (all its
rate-loop gains at once: the rotors giving that many times the torque the controller expects)
could grow before the sampled loop turns unstable; sampling slower shrinks it. A rate at which
some axis's loop is unstable (a gain margin of at most 1) is refused; one that leaves less than
the textbook's 2 (6 dB, :data:`GAIN_MARGIN`) is warned about. What the default gains keep,
and the lowest rates they are stable at, are in docs/flying.md (*Control rate*);
``tests/test_control_rate.py`` checks them, and the lowest stable rates against the rates at
which the simulated loop turns unstable. Under a plain-Python controller the loops checked are
the cascade's that its commands fly through (its rate loop alone for body-rate commands:
:func:`~quadnav.control.registry.check_controller_rate`); a controller of another kind is not
checked.
"""

from __future__ import annotations

import math
import warnings
from typing import NamedTuple

import numpy as np

from quadnav.control.cascade import GainArrays
from quadnav.control.contract import Controller
from quadnav.control.se3 import SE3GainArrays
from quadnav.errors import ControlWarning, QuadnavError
from quadnav.limits import RATE
from quadnav.vehicle.params import VehicleParams

#: The least gain margin a control rate should leave (6 dB), below which it is warned about.
GAIN_MARGIN = 2.0
#: Body axes, as messages name them.
AXES = ("roll", "pitch", "yaw")
#: Bisection steps of :func:`gain_margin` and :func:`lowest_rate` (relative precision 2^-40).
BISECTIONS = 40
#: Largest gain margin looked for: beyond it a loop counts as stable at any gain.
MARGIN_CAP = 1e6


class AxisLoop(NamedTuple):
    """One body axis's attitude and rate loops, linearised (see the module docstring)."""

    attitude: float  # ka: rate setpoint per radian of attitude error, 1/s
    rate_p: float  # kp: angular acceleration per rad/s of rate error, 1/s
    rate_i: float  # ki: of the rate error's integral, 1/s^2
    rate_d: float  # kd: of the filtered derivative of the measured rate, dimensionless
    derivative_cutoff: float  # cut-off of that derivative's filter, Hz


def axis_loops(controller: Controller) -> list[AxisLoop] | None:
    """The three body axes' loops of a built-in controller (cascade or SE(3), known by the
    type of its gains), or None for any other (a plain-Python controller too: which of the
    cascade's loops it flies through is its control abstraction's,
    :func:`~quadnav.control.registry.check_controller_rate`)."""
    if controller.python is not None:
        return None
    return gain_loops(controller.gains)


def gain_loops(g: object, attitude: bool = True) -> list[AxisLoop] | None:
    """The three body axes' loops of the compiled gains ``g`` (the cascade's
    :class:`~quadnav.control.cascade.GainArrays` or SE(3)'s
    :class:`~quadnav.control.se3.SE3GainArrays`; None for any other); without ``attitude``
    the cascade's rate loop alone (``ka`` = 0: body-rate commands, no attitude loop)."""
    if isinstance(g, GainArrays):
        return [AxisLoop(float(g.attitude_kp[b]) if attitude else 0.0,
                         *(float(g.rate[k, b]) for k in range(3)),
                         float(g.derivative_cutoff)) for b in range(3)]
    if isinstance(g, SE3GainArrays):
        return [AxisLoop(float(g.kr[b] / g.kw[b]), float(g.kw[b]), 0.0, 0.0, math.inf)
                for b in range(3)]
    return None


def sampled_plant(lag: float, period: float) -> tuple[np.ndarray, np.ndarray]:
    """One axis's plant (angle rad, rate rad/s, angular acceleration rad/s^2; the last
    following its command with the first-order ``lag`` s) over one control ``period`` s with
    the command held: ``(A (3, 3), b (3,))``, state' = A state + b command, exactly (the
    solution in closed form)."""
    rise = -math.expm1(-period / lag)  # how far the acceleration moves to its command
    gained = period - lag * rise  # the command's share of the rate's change, per unit
    step = np.array([[1.0, period, lag * gained],
                     [0.0, 1.0, lag * rise],
                     [0.0, 0.0, 1.0 - rise]])
    hold = np.array([0.5 * period ** 2 - lag * gained, gained, rise])
    return step, hold


def transition(loop: AxisLoop, plant: tuple[np.ndarray, np.ndarray], period: float,
               scale: float = 1.0) -> np.ndarray:
    """The sampled closed loop's transition over one control ``period`` s: a square matrix
    on (angle, rate, angular acceleration, then the rate integral if ``ki`` > 0, then the
    derivative filter and the last measured rate if ``kd`` > 0), with the controller's
    rate-loop gains multiplied by ``scale``; ``plant`` is :func:`sampled_plant`."""
    plant_step, hold = plant
    integral, derivative = loop.rate_i > 0.0, loop.rate_d > 0.0
    size = 3 + integral + 2 * derivative
    error = np.zeros(size)  # the rate error, -ka angle - rate (a zero setpoint)
    error[0], error[1] = -loop.attitude, -1.0
    command = scale * loop.rate_p * error
    step = np.zeros((size, size))
    if integral:
        at = 3
        command[at] = 1.0
        step[at] = scale * loop.rate_i * period * error
        step[at, at] += 1.0
    if derivative:
        at = size - 2
        alpha = period / (period + 1.0 / (2.0 * math.pi * loop.derivative_cutoff))
        filtered = np.zeros(size)  # the filter's new value, of the last one and the rates
        filtered[at] = 1.0 - alpha
        filtered[1], filtered[at + 1] = alpha / period, -alpha / period
        command -= scale * loop.rate_d * filtered
        step[at] = filtered
        step[at + 1, 1] = 1.0
    step[:3, :3] = plant_step
    step[:3] += np.outer(hold, command)
    return step


def _stable(loop: AxisLoop, plant: tuple[np.ndarray, np.ndarray], period: float,
            scale: float) -> bool:
    step = transition(loop, plant, period, scale)
    if loop.attitude == 0.0:  # a rate loop alone: the angle, fed back nowhere, is left out
        step = step[1:, 1:]
    return float(np.max(np.abs(np.linalg.eigvals(step)))) < 1.0


def gain_margin(loop: AxisLoop, lag: float, control_rate: float) -> float:
    """The factor by which ``loop``'s output could be multiplied before it turns unstable,
    sampled at ``control_rate`` Hz behind the rotors' ``lag`` s (inf: stable up to
    :data:`MARGIN_CAP`); below 1 when it is unstable as it is."""
    period = 1.0 / control_rate
    plant = sampled_plant(lag, period)
    low, high = 0.0, 1.0
    if _stable(loop, plant, period, 1.0):
        low, high = 1.0, 2.0
        while _stable(loop, plant, period, high):
            if high >= MARGIN_CAP:
                return math.inf
            low, high = high, 2.0 * high
    for _ in range(BISECTIONS):
        middle = 0.5 * (low + high)
        low, high = (middle, high) if _stable(loop, plant, period, middle) else (low, middle)
    return low


class RateVerdict(NamedTuple):
    """The worst axis of a controller at a control rate (:func:`rate_verdict`)."""

    axis: str  # roll, pitch or yaw
    gain_margin: float  # of that axis's sampled loop


def rate_verdict(loops: list[AxisLoop], lag: float, control_rate: float) -> RateVerdict:
    """The axis whose sampled loop keeps the least gain margin at ``control_rate`` Hz."""
    margins = [gain_margin(loop, lag, control_rate) for loop in loops]
    worst = int(np.argmin(margins))
    return RateVerdict(AXES[worst], margins[worst])


def keeps_margin(loops: list[AxisLoop], lag: float, control_rate: float,
                 margin: float) -> bool:
    """Whether every axis's loop, sampled at ``control_rate`` Hz behind the rotors' ``lag``
    s, keeps a gain margin above ``margin``: stays stable with its output multiplied by it
    (with ``margin`` 1: is stable as it is)."""
    period = 1.0 / control_rate
    plant = sampled_plant(lag, period)
    return all(_stable(loop, plant, period, margin) for loop in loops)


def lowest_rate(loops: list[AxisLoop], lag: float, margin: float) -> float:
    """The lowest control rate, Hz, at which :func:`keeps_margin` holds (the margin grows
    with the rate), within :data:`~quadnav.limits.RATE`."""
    low, high = RATE.low, RATE.high
    if keeps_margin(loops, lag, low, margin):
        return low
    for _ in range(BISECTIONS):
        middle = math.sqrt(low * high)
        low, high = (low, middle) if keeps_margin(loops, lag, middle, margin) else (middle, high)
    return high


def check_control_rate(controller: Controller, vehicle: VehicleParams,
                       control_rate: float) -> None:
    """Refuse a ``control_rate`` Hz at which a built-in controller's loop on ``vehicle``
    (behind its rotors' lag) is unstable, and warn of one that leaves it a gain margin under
    :data:`GAIN_MARGIN` (:func:`check_loops`); other controllers pass unchecked.

    Raises:
        QuadnavError: some axis's sampled loop is unstable at that rate (or at any).
    """
    check_loops(axis_loops(controller), f"the {controller.name} controller's", vehicle,
                control_rate)


def check_loops(loops: list[AxisLoop] | None, owner: str, vehicle: VehicleParams,
                control_rate: float, note: str = "") -> None:
    """Refuse a ``control_rate`` Hz at which one of ``loops`` (None: nothing to check) on
    ``vehicle`` (behind its rotors' lag) is unstable, and warn of one that leaves a gain
    margin under :data:`GAIN_MARGIN` (see the module docstring). Messages name the loop
    ``{owner} {axis} loop{note}``.

    Raises:
        QuadnavError: some axis's sampled loop is unstable at that rate (or at any).
    """
    if loops is None:
        return
    lag = vehicle.motor_time_constant
    if keeps_margin(loops, lag, control_rate, GAIN_MARGIN):
        return
    verdict = rate_verdict(loops, lag, control_rate)
    loop = f"{owner} {verdict.axis} loop{note} on the {vehicle.name} vehicle"
    if not keeps_margin(loops, lag, RATE.high, 1.0):
        raise QuadnavError(f"{loop} is unstable at any control rate: its gains cannot fly")
    rates = (f"stable from {math.ceil(lowest_rate(loops, lag, 1.0))} Hz, a gain margin of "
             f"{GAIN_MARGIN:g} from {math.ceil(lowest_rate(loops, lag, GAIN_MARGIN))} Hz")
    if not keeps_margin(loops, lag, control_rate, 1.0):
        raise QuadnavError(
            f"control rate {control_rate:g} Hz: {loop}, sampled at that rate behind its "
            f"rotors' {lag:g} s lag, is unstable ({rates}); raise --control-rate")
    warnings.warn(
        f"control rate {control_rate:g} Hz: {loop} keeps a gain margin of only "
        f"{verdict.gain_margin:.2f}, under {GAIN_MARGIN:g}: poorly damped ({rates})",
        ControlWarning, stacklevel=1)

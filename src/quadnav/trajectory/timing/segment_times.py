"""Segment times: a trapezoidal speed profile per segment, and optimising times for a cost.

:func:`trapezoidal_times` gives each segment the time a rest-to-rest move along it takes
(:func:`rest_to_rest_duration`; :func:`rest_to_rest_distance` is where that move is)
with a speed and an acceleration limit; :func:`optimize_times` re-allocates the times to
minimise a trajectory cost (e.g. the snap cost) plus a weight times the total time.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike
from scipy.optimize import minimize

from quadnav.arrays import FloatArray
from quadnav.errors import QuadnavError
from quadnav.trajectory.polynomials.basis import check_waypoints_and_times

#: Default top speed, m/s, of every trajectory (``fly``, ``traj`` and the library): an
#: indoor cruise speed for a Tello-class (80 g) drone, within what it can fly.
DEFAULT_V_MAX = 2.0
#: Default acceleration limit (size of the vector), m/s^2: a tilt of about 17 degrees,
#: leaving thrust to reject disturbances.
DEFAULT_A_MAX = 3.0
#: Step of the forward-difference gradient in log-time (a relative time change).
_GRADIENT_STEP = 1e-6


def _positive(value: float, what: str) -> float:
    """``value`` as a float; QuadnavError unless it is finite and > 0."""
    if not (math.isfinite(value) and value > 0):
        raise QuadnavError(f"{what} must be a finite number > 0, got {value}")
    return float(value)


def segment_lengths(waypoints: ArrayLike) -> FloatArray:
    """Lengths (N - 1,), metres, of the straight segments between ``waypoints`` (N, 3).

    Raises QuadnavError unless there are at least 2 finite waypoints and no two
    consecutive ones coincide (a zero-length segment has no direction and no time; drop
    repeated waypoints first, as :func:`quadnav.trajectory.generate.make_trajectory` does).
    """
    points = np.asarray(waypoints, dtype=np.float64)
    unit_times = np.ones(max(len(np.atleast_1d(points)) - 1, 0))  # only the points matter here
    points, _ = check_waypoints_and_times(points, unit_times)
    lengths = np.linalg.norm(np.diff(points, axis=0), axis=1)
    if np.any(lengths == 0):
        i = int(np.flatnonzero(lengths == 0)[0])
        raise QuadnavError(f"waypoints {i} and {i + 1} are the same point "
                           f"{points[i].tolist()}; expected distinct consecutive waypoints")
    return lengths


def trapezoidal_times(waypoints: ArrayLike, v_max: float = DEFAULT_V_MAX,
                      a_max: float = DEFAULT_A_MAX, scale: float = 1.0) -> FloatArray:
    """Segment durations (N - 1,), s, for ``waypoints`` (N, 3), metres.

    Each segment of length ``L`` gets the time of a rest-to-rest move along it that
    accelerates at ``a_max`` m/s^2, cruises at ``v_max`` m/s and brakes at ``a_max``:
    ``L / v_max + v_max / a_max`` when ``L >= v_max^2 / a_max`` (trapezoidal profile),
    else ``2 sqrt(L / a_max)`` (triangular: it never reaches ``v_max``). The times are
    then multiplied by ``scale`` (> 0). Raises QuadnavError for bad input (see
    :func:`segment_lengths`).
    """
    v = _positive(v_max, "v_max (m/s)")
    a = _positive(a_max, "a_max (m/s^2)")
    factor = _positive(scale, "time scale")
    return factor * rest_to_rest_duration(segment_lengths(waypoints), v, a)


def rest_to_rest_duration(length: ArrayLike, v_max: float, a_max: float) -> FloatArray:
    """Durations, s, of the fastest rest-to-rest moves over ``length`` m (a number or an
    array, elementwise) with speed at most ``v_max`` m/s and acceleration at most
    ``a_max`` m/s^2: ``L / v + v / a`` when it reaches ``v`` (``L >= v^2 / a``,
    trapezoidal), else ``2 sqrt(L / a)`` (triangular)."""
    lengths = np.asarray(length, dtype=np.float64)
    reaches_cruise = lengths >= v_max * v_max / a_max
    return np.where(reaches_cruise, lengths / v_max + v_max / a_max,
                    2.0 * np.sqrt(lengths / a_max))


def rest_to_rest_distance(length: float, v_max: float, a_max: float, t: FloatArray
                          ) -> FloatArray:
    """Distance (K,), m, covered at times ``t`` (K,) s, within its duration
    (:func:`rest_to_rest_duration`), by the fastest rest-to-rest move over ``length`` m
    with speed at most ``v_max`` m/s and acceleration ``a_max`` m/s^2."""
    top = min(v_max, math.sqrt(a_max * length))
    ramp = top / a_max
    duration = float(rest_to_rest_duration(length, v_max, a_max))
    return np.where(t < ramp, 0.5 * a_max * t**2,
                    np.where(t > duration - ramp, length - 0.5 * a_max * (duration - t)**2,
                             0.5 * a_max * ramp**2 + top * (t - ramp)))


def average_times(waypoints: ArrayLike, speed: float) -> FloatArray:
    """Segment durations (N - 1,), s: each segment's length over ``speed`` m/s (the
    "average velocity" timing of the course reports), for ``waypoints`` (N, 3), metres."""
    return segment_lengths(waypoints) / _positive(speed, "speed (m/s)")


def optimize_times(times0: ArrayLike, cost: Callable[[FloatArray], float],
                   time_weight: float, min_time: float = 0.05,
                   max_iterations: int = 100) -> FloatArray:
    """Segment durations (S,), s, that minimise ``cost(T) + time_weight * sum(T)``.

    The search runs over the log-times ``log T`` (so every segment is scaled alike,
    whatever its length) with L-BFGS-B, the bound ``T >= min_time`` and forward-difference
    gradients; the objective is divided by its value at the start so the tolerances are
    relative. It is deterministic: the same inputs give the same times.

    Args:
        times0: (S,) starting durations, s, each > 0 (raised to ``min_time`` if below).
        cost: the trajectory cost of durations (S,) s, e.g. the snap cost in m^2/s^7; it
            should be finite for every durations >= ``min_time``.
        time_weight: weight of the total time, cost units per second, > 0.
        min_time: the shortest duration allowed, s, > 0.
        max_iterations: L-BFGS-B iterations at most (each costs about S + 1 cost calls).

    Returns:
        The best durations found (S,), s, each >= ``min_time``.
    """
    start = np.array(times0, dtype=np.float64)
    if start.ndim != 1 or len(start) < 1 or not np.all(np.isfinite(start) & (start > 0)):
        raise QuadnavError(f"starting times must be (S,) finite durations > 0 s, S >= 1, "
                           f"got {start.tolist()}")
    weight = _positive(time_weight, "time weight")
    floor = _positive(min_time, "minimum segment time (s)")
    if max_iterations < 1:
        raise QuadnavError(f"max iterations must be >= 1, got {max_iterations}")

    def total(log_times: FloatArray) -> float:
        durations = np.exp(log_times)
        return float(cost(durations)) + weight * float(np.sum(durations))

    u0 = np.log(np.maximum(start, floor))
    f0 = total(u0)
    if not math.isfinite(f0):
        raise QuadnavError(f"the cost of the starting times is {f0}; expected a finite number")
    unit = abs(f0) or 1.0
    result = minimize(lambda u: total(u) / unit, u0, method="L-BFGS-B",
                      bounds=[(math.log(floor), None)] * len(u0),
                      options={"maxiter": max_iterations, "ftol": 1e-12, "gtol": 1e-8,
                               "eps": _GRADIENT_STEP})
    return np.maximum(np.exp(result.x), floor)

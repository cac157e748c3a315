"""Quintic segments between waypoints, each fixed by position, velocity and acceleration at
both ends (quintic Hermite interpolation).

* :func:`quintic_segments` — the course reports' method: at rest at the first and last
  waypoint; at interior waypoints a velocity along the path and zero acceleration (C1).
* :func:`quintic_average` — another report's method: at each interior waypoint the
  average of the two segments' average velocities (length over time, along the segment),
  zero acceleration; at rest at both ends.
* :func:`quintic_c2` — interior velocities and accelerations such that jerk and snap are
  continuous too: the minimum-jerk spline (C4), which
  :func:`~quadnav.trajectory.polynomials.minsnap.minimum_derivative` solves with ``derivative=3``.

The Hermite pieces are written here rather than by scipy's ``BPoly.from_derivatives``:
that one agrees to 1e-12 but not exactly at the waypoints (its Bernstein coefficients
differ by round-off there), and a ``trajectory.csv`` or ``MP.csv`` read back must give
the written samples exactly.

Segment ``i`` of ``T_i`` s is written in the normalised time ``tau = (t - t_i) / T_i``;
a velocity enters its end conditions times ``T_i`` and an acceleration times ``T_i^2``.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from quadnav.arrays import FloatArray
from quadnav.errors import QuadnavError
from quadnav.trajectory.model import Trajectory
from quadnav.trajectory.polynomials.basis import (
    check_waypoints_and_times,
    derivative_rows,
    trajectory_from_tau,
)
from quadnav.trajectory.polynomials.minsnap import minimum_derivative
from quadnav.trajectory.timing.segment_times import segment_lengths

#: Coefficients in tau (6,) from the end conditions ``[p0, v0, a0, p1, v1, a1]`` (tau units).
_HERMITE = np.linalg.inv(np.vstack([derivative_rows(6, order, tau)
                                    for tau in (0.0, 1.0) for order in range(3)]))


def hermite_trajectory(states: FloatArray, durations: FloatArray, method: str, info: dict
                       ) -> Trajectory:
    """The trajectory whose segment ``i`` joins ``states[i]`` to ``states[i + 1]``: the
    quintic Hermite interpolation of the states, exact at the waypoints.

    ``states`` (N, 3, 3) holds position, velocity and acceleration (m, m/s, m/s^2) at each
    waypoint; ``durations`` (N - 1,) s, each > 0.
    """
    powers = durations[:, None] ** np.arange(3)  # (segments, 3): 1, T, T^2
    ends = np.concatenate([states[:-1] * powers[:, :, None], states[1:] * powers[:, :, None]],
                          axis=1)  # (segments, 6, 3)
    coefficients = np.einsum("kj,sja->ska", _HERMITE, ends)
    return trajectory_from_tau(coefficients, states[:, 0], durations, method, info)


def quintic_segments(waypoints: ArrayLike, times: ArrayLike, cruise_speed: float) -> Trajectory:
    """Quintic segments through ``waypoints``, C1, at rest at both ends.

    At the first and last waypoint the velocity and acceleration are zero. At an interior
    waypoint ``i`` the acceleration is zero and the velocity is
    ``s * (u_in + u_out) / 2``, with ``u_in`` and ``u_out`` the unit directions of the
    segments arriving and leaving and
    ``s = min(cruise_speed, 2 / (T_in / L_in + T_out / L_out))`` (the cruise speed, capped
    by the harmonic mean of the two segments' mean speeds: a waypoint where the flight
    speeds up or slows down is passed at a speed in between, and one beside a short, slow
    segment slowly enough that the segment does not overshoot and back up). It points
    along the normalised sum of the two directions (the bisector of the turn) and its
    magnitude is ``s cos(turn / 2)``: full speed on a straight line, slower in turns, zero
    where the path doubles back.

    Args:
        waypoints: (N, 3) points, metres, N >= 2, no two consecutive ones equal.
        times: (N - 1,) segment durations, s, each finite and > 0.
        cruise_speed: the speed at interior waypoints before the caps, m/s, > 0.

    Returns:
        A :class:`Trajectory`, method ``"quintic"``; ``info["cruise_speed"]`` in m/s.

    Raises:
        QuadnavError: bad shapes, non-finite values, times or speed not > 0, or a repeated
            waypoint.
    """
    if not (math.isfinite(cruise_speed) and cruise_speed > 0):
        raise QuadnavError(f"cruise speed must be a finite number > 0 m/s, got {cruise_speed}")
    points, durations = check_waypoints_and_times(waypoints, times)
    lengths = segment_lengths(points)
    directions = np.diff(points, axis=0) / lengths[:, None]
    mean_speeds = lengths / durations
    speeds = np.minimum(cruise_speed, 2.0 / (1.0 / mean_speeds[:-1] + 1.0 / mean_speeds[1:]))
    states = np.zeros((len(points), 3, 3))
    states[:, 0] = points
    states[1:-1, 1] = speeds[:, None] * (directions[:-1] + directions[1:]) / 2
    return hermite_trajectory(states, durations, "quintic", {"cruise_speed": float(cruise_speed)})


def quintic_average(waypoints: ArrayLike, times: ArrayLike) -> Trajectory:
    """Quintic segments through ``waypoints``, C1, at rest at both ends, with the "average
    velocity" end conditions: at an interior waypoint the velocity is the mean of the
    average velocities ``(p_{i+1} - p_i) / T_i`` of the segments arriving and leaving,
    and the acceleration is zero. With segment times length / v (see
    :func:`~quadnav.trajectory.timing.segment_times.average_times`) that is speed v along a straight
    line and less in turns.

    Args:
        waypoints: (N, 3) points, metres, N >= 2, no two consecutive ones equal.
        times: (N - 1,) segment durations, s, each finite and > 0.

    Returns:
        A :class:`Trajectory`, method ``"quintic-average"``.
    """
    points, durations = check_waypoints_and_times(waypoints, times)
    segment_lengths(points)
    average = np.diff(points, axis=0) / durations[:, None]
    states = np.zeros((len(points), 3, 3))
    states[:, 0] = points
    states[1:-1, 1] = (average[:-1] + average[1:]) / 2
    return hermite_trajectory(states, durations, "quintic-average", {})


def quintic_c2(waypoints: ArrayLike, times: ArrayLike) -> Trajectory:
    """Quintic segments through ``waypoints`` with continuous velocity, acceleration, jerk
    and snap: the minimum-jerk spline, at rest (zero velocity and acceleration) at both ends
    (:func:`~quadnav.trajectory.polynomials.minsnap.minimum_derivative` with ``derivative=3``).

    Args:
        waypoints: (N, 3) points, metres, N >= 2, no two consecutive ones equal.
        times: (N - 1,) segment durations, s, each finite and > 0.

    Returns:
        A :class:`Trajectory`, method ``"quintic-c2"``.

    Raises:
        QuadnavError: bad shapes, non-finite values, times not > 0, or a repeated waypoint.
    """
    points, durations = check_waypoints_and_times(waypoints, times)
    segment_lengths(points)
    return minimum_derivative(points, durations, 3).replace(method="quintic-c2", info={})

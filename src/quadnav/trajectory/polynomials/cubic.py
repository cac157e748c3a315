"""The clamped cubic spline through waypoints: C2, at rest at both ends."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike
from scipy.interpolate import CubicSpline, PPoly

from quadnav.trajectory.model import Trajectory
from quadnav.trajectory.polynomials.basis import check_waypoints_and_times
from quadnav.trajectory.timing.segment_times import segment_lengths


def cubic_spline(waypoints: ArrayLike, times: ArrayLike) -> Trajectory:
    """The cubic spline through ``waypoints`` with zero velocity at both ends.

    Args:
        waypoints: (N, 3) points, metres, N >= 2, no two consecutive ones equal (drop
            repeats first); waypoint ``i`` is passed at ``sum(times[:i])`` s.
        times: (N - 1,) segment durations, s, each finite and > 0.

    Returns:
        A :class:`Trajectory`, method ``"cubic"``: scipy's
        :class:`~scipy.interpolate.CubicSpline` with ``bc_type="clamped"`` per axis,
        continuous in position, velocity and acceleration; the acceleration at the ends is
        not zero and the jerk jumps at every waypoint.

    Raises:
        QuadnavError: bad shapes, non-finite values, times not > 0, or a repeated waypoint.
    """
    points, durations = check_waypoints_and_times(waypoints, times)
    segment_lengths(points)
    breaks = np.concatenate([[0.0], np.cumsum(durations)])
    spline = CubicSpline(breaks, points, axis=0, bc_type="clamped")
    return Trajectory(PPoly(spline.c, spline.x), points, "cubic")

"""Near time-optimal segment times: cruise at the top speed, slow only where needed.

A smooth trajectory through a few far-apart waypoints brakes towards each of them if each
segment gets the time of a rest-to-rest move. Here instead (the approach TOPP-RA takes,
with the exact acceleration bound of :mod:`quadnav.trajectory.timing.speed_profile`):

1. :func:`knots` adds waypoints on the path's straight segments, about
   :data:`KNOT_INTERVAL` seconds of flight apart (closer where the flight speeds up from
   and slows down to rest), so a polynomial per segment can follow any speed profile.
   They lie on the path's segments, which are free, so the collision refinement still
   applies.
2. :func:`fastest_times` builds the trajectory, finds the fastest speed along its own
   curve within the limits (:func:`~quadnav.trajectory.timing.speed_profile.fastest_speeds`),
   and gives each segment the time that speed takes over it; the new times change the
   curve a little, so this repeats :data:`PROFILE_ROUNDS` times. The profile lets the
   acceleration grow from rest over :data:`RAMP_TIME` (a minimum-snap trajectory starts
   and stops with zero acceleration and jerk, so it cannot jump to the limit).
3. :func:`stretch_where_fast` stretches the times of the segments whose speed or
   acceleration still exceeds a limit (a polynomial rounds off the profile's corners
   and overshoots a little) — and, given the vehicle's :class:`Limits`, whose roll and
   pitch rate or angular acceleration does (quick turns at speed ask for fast rotations,
   sudden ones for strong torques) — and finally all of
   them alike if a few local rounds were not enough, so the result is always within the
   speed and acceleration limits.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from quadnav.arrays import FloatArray
from quadnav.profiling import staged
from quadnav.trajectory.feasibility import Limits, quantities
from quadnav.trajectory.model import Trajectory
from quadnav.trajectory.timing.segment_times import rest_to_rest_distance, rest_to_rest_duration
from quadnav.trajectory.timing.speed_profile import fastest_speeds, travel_times

#: ``build(waypoints (N, 3), segment times (N - 1,) s) -> Trajectory``.
Build = Callable[[FloatArray, FloatArray], Trajectory]
#: Flight time between added waypoints, s: long enough for a round curve through a
#: corner, short enough for the polynomials to follow the speed profile.
KNOT_INTERVAL = 0.4
#: Added waypoints within this fraction of an interval of a path vertex (in the time of
#: the rest-to-rest move along the path) are dropped: a very short segment beside a
#: corner only sharpens it.
VERTEX_CLEARANCE = 0.3
#: Samples of the rest-to-rest move's clock, to find when it passes each vertex.
_CLOCK_SAMPLES = 2001
#: Time, s, in which the speed profile's acceleration may grow from rest to the limit.
RAMP_TIME = 0.2
#: Rounds of "build the curve, time it along its own fastest speed".
PROFILE_ROUNDS = 3
#: Fraction of the acceleration limit the speed profile plans with: the polynomials
#: overshoot the profile's sudden changes of acceleration a little.
PROFILE_ACCELERATION_SHARE = 0.9
#: Samples per segment along which the speed profile and the peaks are measured.
SAMPLES_PER_SEGMENT = 24
#: Rounds of stretching only the segments that exceed a limit, before stretching all.
LOCAL_STRETCH_ROUNDS = 8
#: Extra stretch, relative, beyond what the sampled peaks ask for (peaks between samples).
STRETCH_ALLOWANCE = 1e-2


def knots(points: FloatArray, v_max: float, a_max: float,
          interval: float = KNOT_INTERVAL) -> FloatArray:
    """The path ``points`` (N, 3) with points added on its segments (M, 3), M >= N.

    They sit where a rest-to-rest move along the whole path (its corners ignored) with
    ``v_max`` m/s and ``a_max`` m/s^2 would be every ``interval`` s — closer together
    where it speeds up and slows down — every vertex kept, and none within
    :data:`VERTEX_CLEARANCE` of an interval of a vertex in that move's time.
    """
    cumulative = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(points, axis=0),
                                                                 axis=1))])
    length = float(cumulative[-1])
    duration = float(rest_to_rest_duration(length, v_max, a_max))
    count = max(1, math.ceil(duration / interval))
    times = np.linspace(0.0, duration, count + 1)[1:-1]
    clock = np.linspace(0.0, duration, _CLOCK_SAMPLES)
    vertex_times = np.interp(cumulative, rest_to_rest_distance(length, v_max, a_max, clock),
                             clock)
    gap = np.abs(times[:, None] - vertex_times[None, :]).min(axis=1, initial=np.inf)
    added = rest_to_rest_distance(length, v_max, a_max,
                                  times[gap > VERTEX_CLEARANCE * interval])
    along = np.concatenate([cumulative, added])
    order = np.argsort(along, kind="stable")
    is_vertex = order < len(points)
    segment = np.clip(np.searchsorted(cumulative, along[order], side="right") - 1, 0,
                      len(points) - 2)
    fraction = (along[order] - cumulative[segment]) / (cumulative[segment + 1]
                                                       - cumulative[segment])
    inserted = points[segment] + fraction[:, None] * (points[segment + 1] - points[segment])
    return np.where(is_vertex[:, None], points[np.minimum(order, len(points) - 1)], inserted)


def _sample_times(trajectory: Trajectory) -> FloatArray:
    """Times (K,) s, :data:`SAMPLES_PER_SEGMENT` evenly spread over each segment, with
    every break at index ``SAMPLES_PER_SEGMENT * i``."""
    breaks = trajectory.breaks
    local = np.arange(SAMPLES_PER_SEGMENT) / SAMPLES_PER_SEGMENT
    return np.append((breaks[:-1, None] + np.diff(breaks)[:, None] * local).ravel(),
                     breaks[-1])


def _curve_samples(trajectory: Trajectory) -> tuple[FloatArray, FloatArray]:
    """The arc length (K,) m and the curvature (K,) 1/m (0 where the trajectory stops)
    at :func:`_sample_times`."""
    t = _sample_times(trajectory)
    positions = trajectory.position(t)
    velocity = trajectory.velocity(t)
    speed = np.linalg.norm(velocity, axis=1)
    turning = np.linalg.norm(np.cross(velocity, trajectory.acceleration(t)), axis=1)
    moving = speed > 1e-9 * max(float(speed.max()), 1e-300)
    curvature = np.zeros_like(speed)
    curvature[moving] = turning[moving] / speed[moving] ** 3
    steps = np.linalg.norm(np.diff(positions, axis=0), axis=1)
    # A step the curve barely moves along still needs a little length (and time).
    arc = np.concatenate([[0.0], np.cumsum(np.maximum(steps, 1e-9))])
    return arc, curvature


def profile_times(trajectory: Trajectory, v_max: float, a_max: float) -> FloatArray:
    """Segment times (S,), s: how long the fastest flight along ``trajectory``'s curve,
    within ``v_max`` m/s and ``a_max`` m/s^2, from rest to rest, takes over each of its
    segments — shortened where a segment's curve is longer than its chord."""
    arc, curvature = _curve_samples(trajectory)
    passing = travel_times(arc, fastest_speeds(arc, curvature, v_max, a_max,
                                               a_max / RAMP_TIME))
    # A segment whose curve is longer than its chord (a wiggle) is not given the time to
    # fly the wiggle, or the next curve would wiggle more: its time shrinks by the ratio.
    chords = np.linalg.norm(np.diff(trajectory.waypoints, axis=0), axis=1)
    stretches = np.diff(arc[::SAMPLES_PER_SEGMENT])
    return np.diff(passing[::SAMPLES_PER_SEGMENT]) * np.minimum(1.0, chords / stretches)


@staged("fastest timing")
def fastest_times(points: FloatArray, times: FloatArray, build: Build, v_max: float,
                  a_max: float) -> FloatArray:
    """Segment times (N - 1,), s, for ``points`` (N, 3) that fly ``build``'s curve as fast
    as ``v_max`` m/s and :data:`PROFILE_ACCELERATION_SHARE` of ``a_max`` m/s^2 allow,
    starting from the guess ``times`` (N - 1,) s (see the module docstring)."""
    for _ in range(PROFILE_ROUNDS):
        times = profile_times(build(points, times), v_max,
                              PROFILE_ACCELERATION_SHARE * a_max)
    return times


def segment_excess(trajectory: Trajectory, v_max: float, a_max: float,
                   vehicle: Limits | None = None) -> FloatArray:
    """Per segment (S,), the factor by which its times must stretch to bring its sampled
    peak speed within ``v_max`` m/s, acceleration within ``a_max`` m/s^2 and, given
    ``vehicle``, roll/pitch rate within its ``body_rate_max`` and roll/pitch angular
    acceleration within its ``angular_acceleration_max`` (stretching by k divides speeds
    by k, accelerations by k^2 and, about, the rate by k^3 and the angular acceleration by
    k^4); <= 1 where within."""
    t = _sample_times(trajectory)
    velocity, acceleration = trajectory.velocity(t), trajectory.acceleration(t)
    excess = np.maximum(np.linalg.norm(velocity, axis=1) / v_max,
                        np.sqrt(np.linalg.norm(acceleration, axis=1) / a_max))
    # Each vehicle limit: the quantity, the limit and the root that undoes a stretch.
    bounds = [] if vehicle is None else [
        (name, limit, root) for name, limit, root in (
            ("max_body_rate", vehicle.body_rate_max, np.cbrt),
            ("max_angular_acceleration", vehicle.angular_acceleration_max,
             lambda ratio: np.sqrt(np.sqrt(ratio))))
        if limit is not None]
    if bounds:
        series = quantities(velocity, acceleration, trajectory.jerk(t), trajectory.snap(t),
                            vehicle)
        for name, limit, root in bounds:
            excess = np.maximum(excess, root(series[name] / limit))
    per_segment = excess[:-1].reshape(-1, SAMPLES_PER_SEGMENT).max(axis=1)
    ends = excess[SAMPLES_PER_SEGMENT::SAMPLES_PER_SEGMENT]  # the break ending each segment
    return np.maximum(per_segment, ends)


@staged("fastest timing")
def stretch_where_fast(trajectory: Trajectory, build: Build, v_max: float, a_max: float,
                       vehicle: Limits | None = None) -> Trajectory:
    """``trajectory`` rebuilt with longer times where it exceeds a limit (see
    :func:`segment_excess`): each offending segment and, half as much, its neighbours,
    for up to :data:`LOCAL_STRETCH_ROUNDS` rounds, then every segment alike;
    ``info["time_stretch"]`` is the final duration over the first."""
    first = trajectory.duration
    for _ in range(LOCAL_STRETCH_ROUNDS):
        excess = segment_excess(trajectory, v_max, a_max, vehicle)
        if excess.max() <= 1.0:
            break
        trajectory = build(trajectory.waypoints,
                           trajectory.segment_times * _local_stretch(excess))
    else:
        excess = segment_excess(trajectory, v_max, a_max, vehicle)
        if excess.max() > 1.0:
            factor = float(excess.max()) * (1.0 + STRETCH_ALLOWANCE)
            trajectory = build(trajectory.waypoints, trajectory.segment_times * factor)
    return trajectory.replace(info={**trajectory.info,
                                    "time_stretch": trajectory.duration / first})


def _local_stretch(excess: NDArray[np.float64]) -> FloatArray:
    """Stretch factors (S,) >= 1 for segments with ``excess`` (S,): the excess (plus
    :data:`STRETCH_ALLOWANCE`) where above 1, and its square root on the neighbours."""
    own = np.where(excess > 1.0, excess * (1.0 + STRETCH_ALLOWANCE), 1.0)
    beside = np.sqrt(np.maximum(np.r_[own[1:], 1.0], np.r_[1.0, own[:-1]]))
    return np.maximum(own, beside)

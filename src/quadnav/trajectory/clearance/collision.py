"""Collision checks of trajectories against free space, and refinement until free.

A trajectory is checked densely and exactly: it is sampled so that consecutive positions
are at most ``spacing`` metres apart, and the polyline through the samples is tested
segment by segment with the exact :meth:`~quadnav.world.model.World.segments_free`.

Sampling is adaptive: each waypoint interval starts with :data:`INITIAL_SAMPLES` evenly
timed samples (the breaks among them; enough to resolve the shape of the polynomials of
degree <= 7 used here), then every pair of consecutive samples is cut into equal time
steps until, for every pair, (1) the positions are at most ``spacing`` apart — a
guarantee on the samples themselves, not on an estimated speed bound — and (2) the curve
strays from the chord between them by at most ``spacing * CHORD_TOLERANCE`` (1 mm at
the default 2 cm). The stray over a step of ``dt`` seconds is at most
``max |acceleration| * dt**2 / 8``; the larger of the accelerations at the pair's ends
stands in for the maximum. So the exact polyline check is the check of the curve up to
about a millimetre.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from quadnav.arrays import FloatArray
from quadnav.errors import QuadnavError
from quadnav.trajectory.model import Trajectory
from quadnav.world.model import World
from quadnav.world.placement import format_point

#: Evenly timed samples per waypoint interval before adaptive refinement.
INITIAL_SAMPLES = 16
#: Largest stray of the curve from a checked chord, as a fraction of the spacing.
CHORD_TOLERANCE = 0.05
#: Most samples a check may take; a wilder trajectory is an error, not an endless check.
MAX_SAMPLES = 20_000_000


@dataclass(frozen=True, eq=False)
class Collision:
    """Where a trajectory first leaves free space.

    Attributes:
        t: time of the first contact, s from the start.
        point: (3,) position of the trajectory at ``t``, metres.
        segment: index of the waypoint interval (trajectory segment) holding ``t``.
    """

    t: float
    point: FloatArray
    segment: int


def checked_waypoints(waypoints: ArrayLike) -> FloatArray:
    """``waypoints`` as a float64 (N, 3) array, metres; QuadnavError unless it is at least
    2 finite points."""
    points = np.asarray(waypoints, dtype=np.float64)
    if points.ndim != 2 or points.shape[1] != 3 or len(points) < 2:
        raise QuadnavError(f"waypoints must be an (N, 3) array with N >= 2, got shape "
                           f"{points.shape}")
    if not np.all(np.isfinite(points)):
        row = int(np.argmax(~np.all(np.isfinite(points), axis=1)))
        raise QuadnavError(f"waypoint {row} is {points[row].tolist()}; expected finite numbers")
    return points


def require_free_polyline(free_world: World, waypoints: FloatArray) -> None:
    """QuadnavError naming the first segment of ``waypoints`` (N, 3) that is not wholly in
    the free space of ``free_world``."""
    blocked = ~free_world.segments_free(np.stack([waypoints[:-1], waypoints[1:]], axis=1))
    if blocked.any():
        bad = int(np.argmax(blocked))
        raise QuadnavError(
            f"waypoint segment {bad} from {format_point(waypoints[bad])} to "
            f"{format_point(waypoints[bad + 1])} is not in free space of {free_world.name} "
            "(it touches an inflated block or the boundary)")


def check_samples(trajectory: Trajectory, spacing: float) -> tuple[FloatArray, FloatArray]:
    """Times (K,) s and positions (K, 3) m, consecutive positions at most ``spacing`` m
    apart and their chords close to the curve, the breaks among the times (see the module
    docstring)."""
    if not (math.isfinite(spacing) and spacing > 0):
        raise QuadnavError(f"check spacing must be a positive distance in m, got {spacing}")
    if not np.all(np.isfinite(trajectory.poly.c)):
        raise QuadnavError("the trajectory has non-finite coefficients")
    breaks = trajectory.breaks
    local = np.arange(INITIAL_SAMPLES) / INITIAL_SAMPLES
    t = np.append((breaks[:-1, None] + np.diff(breaks)[:, None] * local).ravel(), breaks[-1])
    while True:
        positions = trajectory.position(t)
        gaps = np.linalg.norm(np.diff(positions, axis=0), axis=1)
        acceleration = np.linalg.norm(trajectory.acceleration(t), axis=1)
        stray = np.maximum(acceleration[:-1], acceleration[1:]) * np.diff(t) ** 2 / 8
        # Cutting a step into k shortens the gap k-fold and the stray k^2-fold.
        parts = np.maximum.reduce([np.ceil(gaps / spacing),
                                   np.ceil(np.sqrt(stray / (spacing * CHORD_TOLERANCE))),
                                   np.ones_like(gaps)])
        if np.all(parts == 1.0):
            return t, positions
        if parts.sum() > MAX_SAMPLES:
            raise QuadnavError(f"the trajectory is too long to check every {spacing:g} m "
                               f"(more than {MAX_SAMPLES} samples)")
        counts = parts.astype(np.int64)
        interval = np.repeat(np.arange(len(counts)), counts)
        step = np.arange(len(interval)) - np.repeat(np.cumsum(counts) - counts, counts)
        t = np.append(t[interval] + np.diff(t)[interval] * step / parts[interval], t[-1])


def _offending(trajectory: Trajectory, free_world: World, spacing: float
               ) -> tuple[FloatArray, FloatArray, NDArray[np.int64]]:
    """Sample times (K,), positions (K, 3) and the indices (J,) of the sample pairs whose
    straight segment is not in free space, in time order."""
    t, positions = check_samples(trajectory, spacing)
    free = free_world.segments_free(np.stack([positions[:-1], positions[1:]], axis=1))
    return t, positions, np.flatnonzero(~free)


def _segment_of(trajectory: Trajectory, times: FloatArray) -> NDArray[np.int64]:
    """Index of the waypoint interval [break i, break i + 1) holding each time (the last
    interval holds the end)."""
    index = np.searchsorted(trajectory.breaks, times, side="right") - 1
    return np.clip(index, 0, len(trajectory.breaks) - 2)


def _segments_of_pairs(trajectory: Trajectory, t: FloatArray, pairs: NDArray[np.int64]
                       ) -> NDArray[np.int64]:
    """The waypoint intervals (J,), ascending and unique, holding the sample pairs
    ``pairs`` of the sample times ``t`` (K,)."""
    return np.unique(_segment_of(trajectory, t[pairs]))


def _first(trajectory: Trajectory, free_world: World, t: FloatArray, positions: FloatArray,
           pair: int) -> Collision:
    """The collision at the first contact along sample pair ``pair``."""
    fraction, _ = free_world.first_hits(positions[None, pair:pair + 2])
    time = float(t[pair] + fraction[0] * (t[pair + 1] - t[pair]))
    segment = int(_segment_of(trajectory, t[pair:pair + 1])[0])
    return Collision(time, trajectory.position(time), segment)


def first_collision(trajectory: Trajectory, free_world: World, spacing: float = 0.02
                    ) -> Collision | None:
    """The first time ``trajectory`` leaves the free space of ``free_world``, or ``None``.

    Args:
        trajectory: the trajectory to check.
        free_world: the map inflated by the safety margin.
        spacing: largest distance between checked positions, metres (module docstring).

    The time is where the exact check first meets an obstacle along the chord between
    two samples, interpolated linearly in time between them.
    """
    t, positions, bad = _offending(trajectory, free_world, spacing)
    return _first(trajectory, free_world, t, positions, int(bad[0])) if bad.size else None


def collisions(trajectory: Trajectory, free_world: World, spacing: float = 0.02
               ) -> NDArray[np.int64]:
    """Indices (J,), ascending, of every waypoint interval in which ``trajectory`` leaves
    the free space of ``free_world`` (see :func:`first_collision`)."""
    t, _, bad = _offending(trajectory, free_world, spacing)
    return _segments_of_pairs(trajectory, t, bad)


def refine_until_free(free_world: World, waypoints: ArrayLike, times: ArrayLike,
                      build: Callable[[FloatArray, FloatArray], Trajectory], *,
                      max_rounds: int = 10, spacing: float = 0.02) -> Trajectory:
    """Build a trajectory, adding waypoints until it stays in free space.

    Each round builds a trajectory with ``build(waypoints (N, 3), times (N - 1,))`` and
    checks it (:func:`collisions`); every waypoint interval it leaves free space in gets
    the midpoint of its straight segment as a new waypoint, and each half of the interval
    half its time, so the original waypoints keep their times. The midpoint of a free
    segment is free and pulls the curve towards the segment.

    Args:
        free_world: the map inflated by the safety margin; every waypoint segment must be
            free in it.
        waypoints: (N, 3) points the trajectory passes, metres.
        times: (N - 1,) positive segment durations, s.
        build: the generator, e.g. minimum snap.
        max_rounds: most rounds of adding waypoints.
        spacing: largest distance between checked positions, metres.

    Returns:
        The first free trajectory; its ``info`` gains ``refine_rounds`` (rounds of adding
        waypoints) and ``inserted_waypoints`` (how many were added).

    Raises:
        QuadnavError: bad input, a waypoint segment that is not free, or a trajectory still
            leaving free space after ``max_rounds`` rounds.
    """
    points = checked_waypoints(waypoints)
    durations = np.asarray(times, dtype=np.float64)
    if durations.shape != (len(points) - 1,):
        raise QuadnavError(f"expected {len(points) - 1} segment times for {len(points)} "
                           f"waypoints, got shape {durations.shape}")
    if not np.all(np.isfinite(durations) & (durations > 0)):
        raise QuadnavError(f"segment times must be positive finite seconds, got "
                           f"{durations.tolist()}")
    if max_rounds < 0:
        raise QuadnavError(f"max rounds must be >= 0, got {max_rounds}")
    require_free_polyline(free_world, points)
    inserted = rounds = 0
    while True:
        trajectory = build(points, durations)
        t, positions, bad = _offending(trajectory, free_world, spacing)
        if not bad.size:
            return trajectory.replace(info={**trajectory.info, "refine_rounds": rounds,
                                            "inserted_waypoints": inserted})
        if rounds == max_rounds:
            hit = _first(trajectory, free_world, t, positions, int(bad[0]))
            raise QuadnavError(
                f"trajectory still leaves free space at {format_point(hit.point)} at "
                f"t = {hit.t:.3f} s after {max_rounds} refinement"
                f"{'' if max_rounds == 1 else 's'}; lower the speed or add waypoints")
        segments = _segments_of_pairs(trajectory, t, bad)
        points, durations = _split(points, durations, segments)
        inserted += len(segments)
        rounds += 1


def insert_points(points: FloatArray, segments: NDArray[np.int64],
                  fractions: ArrayLike = 0.5) -> FloatArray:
    """The path ``points`` (N, 3) with a point inserted on each segment listed in
    ``segments`` (J,) (indices, ascending and unique), at ``fractions`` (J,) or scalar,
    in (0, 1), of the way along it (default: the midpoints) -> (N + J, 3)."""
    count = np.ones(len(points) - 1, dtype=np.int64)
    count[segments] = 2
    starts = np.repeat(points[:-1], count, axis=0)
    along = np.reshape(fractions, (-1, 1))
    starts[(np.cumsum(count) - 1)[segments]] = (points[segments] + along * (
        points[segments + 1] - points[segments]))
    return np.concatenate([starts, points[-1:]])


def _split(points: FloatArray, durations: FloatArray, segments: NDArray[np.int64]
           ) -> tuple[FloatArray, FloatArray]:
    """Waypoints (N + J, 3) and segment times (N - 1 + J,) with the midpoint of each
    segment in ``segments`` (J,) added and its time shared equally by the halves."""
    count = np.ones(len(durations), dtype=np.int64)
    count[segments] = 2
    return insert_points(points, segments), np.repeat(durations / count, count)
